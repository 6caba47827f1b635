//! Block on a Coulomb-friction plane pushed by a tent force: Stick → SlipPos → Stick → SlipNeg.
//!
//! This is the 1-D analogue of the paper's Stick/Slip modes (Sect. 3.1): stick → slip when the
//! required static force exceeds μ_s m g (σ ≤ 0), slip → stick when the relative velocity returns
//! to zero. Between events the velocity is piecewise quadratic, so the event times and positions
//! have closed forms (`FrictionBlock::reference`). A wrong reset, a missed guard that starts at
//! zero (v = 0 right after breakaway) or a broken chain (slip → stick landing where |F| > μ_s m g
//! must immediately go on to SlipNeg) changes the mode sequence or the times.

use bf_sim::toys::{BlockMode, FrictionBlock};
use bf_sim::{SimSettings, simulate};

fn block(b: f64) -> FrictionBlock {
    FrictionBlock {
        m: 1.0,
        g: 9.81,
        mu_s: 0.5,
        mu_k: 0.3,
        a: 10.0,
        t_peak: 1.0,
        b,
    }
}

fn tight() -> SimSettings {
    SimSettings {
        rtol: 1e-12,
        atol: 1e-12,
        ..SimSettings::default()
    }
}

#[test]
fn stick_slip_stick_slip_times_match_closed_form() {
    let blk = block(2.0);
    let r = blk.reference();
    assert!(!r.chained_at_t2);
    let out = simulate(
        &blk,
        tight(),
        BlockMode::Stick,
        0.0,
        &[0.0, 0.0],
        r.t3 + 1.0,
    )
    .unwrap();
    let seq: Vec<_> = out
        .events
        .iter()
        .map(|e| (e.mode_before, e.mode_after.unwrap()))
        .collect();
    assert_eq!(
        seq,
        vec![
            (BlockMode::Stick, BlockMode::SlipPos),
            (BlockMode::SlipPos, BlockMode::Stick),
            (BlockMode::Stick, BlockMode::SlipNeg),
        ]
    );
    let e = &out.events;
    assert!((e[0].t - r.t1).abs() < 1e-10, "t1 {} vs {}", e[0].t, r.t1);
    assert!((e[1].t - r.t2).abs() < 1e-8, "t2 {} vs {}", e[1].t, r.t2);
    assert!(
        (e[1].x_post[0] - r.x2).abs() < 1e-8,
        "x2 {} vs {}",
        e[1].x_post[0],
        r.x2
    );
    assert_eq!(e[1].x_post[1], 0.0);
    assert!((e[2].t - r.t3).abs() < 1e-10, "t3 {} vs {}", e[2].t, r.t3);
    // Position is frozen while sticking.
    assert_eq!(e[2].x_pre[0], e[1].x_post[0]);
    assert!(e.iter().all(|ev| !ev.chained));
    assert_eq!(out.mode_final, BlockMode::SlipNeg);
    assert!(out.trajectory.x.last().unwrap()[1] < 0.0);
}

#[test]
fn chained_transition_when_stick_cannot_hold() {
    let blk = block(5.0);
    let r = blk.reference();
    assert!(r.chained_at_t2);
    let out = simulate(
        &blk,
        tight(),
        BlockMode::Stick,
        0.0,
        &[0.0, 0.0],
        r.t2 + 1.0,
    )
    .unwrap();
    let e = &out.events;
    assert_eq!(e.len(), 3);
    assert_eq!(e[1].mode_after, Some(BlockMode::Stick));
    assert_eq!(e[2].mode_before, BlockMode::Stick);
    assert_eq!(e[2].mode_after, Some(BlockMode::SlipNeg));
    assert!(e[2].chained && !e[1].chained);
    assert_eq!(e[2].t, e[1].t);
    assert!((e[1].t - r.t2).abs() < 1e-8);
    assert!((e[1].x_post[0] - r.x2).abs() < 1e-8);
}

#[test]
fn starting_in_stick_beyond_breakaway_slips_immediately() {
    // Start at t0 = 0.8 with F = 8 N > μ_s m g: the breakaway guard is already past its zero.
    let blk = block(2.0);
    let out = simulate(&blk, tight(), BlockMode::Stick, 0.8, &[0.0, 0.0], 0.9).unwrap();
    assert_eq!(out.events[0].t, 0.8);
    assert_eq!(out.events[0].mode_after, Some(BlockMode::SlipPos));
    // Then slip: v(0.9) = ∫_{0.8}^{0.9} (10 t − μ_k g) dt.
    let v = 10.0 * (0.81 - 0.64) / 2.0 - 0.3 * 9.81 * 0.1;
    assert!((out.trajectory.x.last().unwrap()[1] - v).abs() < 1e-10);
}
