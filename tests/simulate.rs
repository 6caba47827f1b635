//! The hybrid ball-and-finger simulator on the compiled paper-scene kernels (paper Sect. 2.4–3,
//! Fig. 3), through the library (the `ball-finger simulate` command: `tests/simulate_cli.rs`).
//!
//! Physics that must hold:
//! * without Coulomb friction, torque or damping, E = T + U is conserved between events
//!   (free motion, eq. 26; frictionless slip, eq. 37 with μ_k = 0: λ ⟂ Δv) and never grows at
//!   events (inelastic impacts, eq. 40–43);
//! * with friction and damping, E never increases except by the torque work ∫ q̇ᵀτ dt
//!   (dE/dt = q̇ᵀτ − μ_v‖q̇‖² − D‖ω‖² − λ·Δv, model/src/energy.rs);
//! * no penetration beyond the documented tolerance (h ≥ −1e-9 m at every stored sample), and
//!   the contact drift stays bounded (and is removed by the projection);
//! * a scripted push gives Free → Stick → Slip → Free, with h ≈ 0 at the impact, σ ≈ 0 at
//!   stick → slip and λ_n ≈ 0 at lift-off (the Sect. 3.1 transition conditions).

use bf_model::{ImpactLaw, Mode, PaperKernels, State, Vec3, fixtures};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings, SampleInfo};
use bf_sim::{Input, PdController, SampleKind, SimOutput, SimSettings, simulate};

#[path = "common/sim.rs"]
mod sim_util;
use sim_util::{PENETRATION_TOL, scripted_push};

fn zero() -> PdController {
    PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]).unwrap()
}

fn tight() -> SimSettings {
    SimSettings {
        rtol: 1e-10,
        atol: 1e-12,
        h_max: 0.01,
        ..SimSettings::default()
    }
}

fn infos<I: Input>(sys: &BallFinger<PaperKernels, I>, out: &SimOutput<Mode>) -> Vec<SampleInfo> {
    let tr = &out.trajectory;
    (0..tr.len())
        .map(|i| sys.sample_info(tr.mode[i], tr.t[i], &tr.x[i]).unwrap())
        .collect()
}

/// Energy between events is constant to integrator tolerance; events never add energy.
/// Returns the largest drift inside a segment (J).
fn frictionless_energy_check(t_end: f64) -> f64 {
    let m = fixtures::paper_scene().unwrap();
    let p = m
        .params()
        .with_coulomb(0.0, 0.0)
        .unwrap()
        .with_viscous(0.0, 0.0)
        .unwrap();
    let m = m.with_params(p);
    let sys = BallFinger::new(
        m,
        zero(),
        BallFingerSettings {
            impact_law: ImpactLaw::NormalImpulse,
            ..BallFingerSettings::default()
        },
    )
    .unwrap();
    // Finger dropped from the paper's initial guess onto a spinning ball.
    let x0 = State::new(
        Vec3::new(0.1, 0.5, 0.5),
        Vec3::zeros(),
        Vec3::new(0.0, 0.0, 2.0),
    )
    .to_array();
    let out = match simulate(&sys, tight(), Mode::Free, 0.0, &x0, t_end) {
        Ok(o) => o,
        Err(f) => panic!("{f}"),
    };
    assert!(
        out.events.iter().any(|e| e.mode_before == Mode::Free),
        "the finger must hit the ball"
    );
    let tr = &out.trajectory;
    let info = infos(&sys, &out);
    let e0 = info[0].energy;
    let mut seg = e0;
    let mut worst: f64 = 0.0;
    for i in 0..tr.len() {
        assert!(info[i].h >= -PENETRATION_TOL, "penetration at {}", tr.t[i]);
        match tr.kind[i] {
            SampleKind::Initial | SampleKind::EventPost => {
                assert!(
                    info[i].energy <= seg + 1e-9,
                    "event added {:e} J at t = {}",
                    info[i].energy - seg,
                    tr.t[i]
                );
                seg = info[i].energy;
            }
            _ => worst = worst.max((info[i].energy - seg).abs()),
        }
    }
    let ev = out.events.len();
    eprintln!("frictionless {t_end} s: {ev} events, max in-segment energy drift {worst:e} J");
    worst
}

#[test]
fn frictionless_undamped_energy_conserved_between_events_10s() {
    // E ~ 0.8 J; rtol 1e-10 over 10 s: measured 2.0e-10 J.
    let worst = frictionless_energy_check(10.0);
    assert!(worst < 2e-9, "energy drift {worst:e} J");
}

/// 100 s takes ~0.2 s in release, so it is not ignored.
#[test]
fn frictionless_undamped_energy_conserved_between_events_100s() {
    // Measured 4.9e-10 J at rtol 1e-10 (E ~ 0.8 J).
    let worst = frictionless_energy_check(100.0);
    assert!(worst < 5e-9, "energy drift {worst:e} J");
}

#[test]
fn scripted_push_free_stick_slip_free_with_transition_conditions() {
    let (x0, series) = scripted_push();
    let sys = BallFinger::new(
        fixtures::paper_scene().unwrap(),
        series,
        BallFingerSettings {
            impact_law: ImpactLaw::Stick,
            ..BallFingerSettings::default()
        },
    )
    .unwrap();
    let out = simulate(&sys, tight(), Mode::Free, 0.0, &x0, 2.5).unwrap();
    let rep = sys.report(&out, 0.0, 1.0);
    let kinds: Vec<&str> = rep.events.iter().map(|e| e.kind).collect();
    assert_eq!(kinds, ["impact", "stick_to_slip", "lift_off"], "{kinds:?}");
    let modes: Vec<(Mode, Option<Mode>)> = rep
        .events
        .iter()
        .map(|e| (e.mode_before, e.mode_after))
        .collect();
    assert_eq!(
        modes,
        [
            (Mode::Free, Some(Mode::Stick)),
            (Mode::Stick, Some(Mode::Slip)),
            (Mode::Slip, Some(Mode::Free)),
        ]
    );
    let lam_scale = rep
        .samples
        .iter()
        .map(|s| s.lambda_n.abs())
        .fold(0.0, f64::max);
    assert!(lam_scale > 0.01, "contact force scale {lam_scale}");
    let [imp, s2s, off] = [&rep.events[0], &rep.events[1], &rep.events[2]];
    // Impact: h ≈ 0 and approaching; sticking impact leaves Δv⁺ = 0 and n·v_c⁺ = 0.
    assert!(imp.pre.h.abs() < 1e-9, "h at impact {:e}", imp.pre.h);
    assert!(imp.pre.normal_velocity < -1e-3);
    assert!(imp.post.slip_speed < 1e-12 && imp.post.normal_velocity.abs() < 1e-12);
    assert!(imp.post.lambda_n > 0.0 && imp.post.sigma > 0.0);
    // Stick → slip: σ ≈ 0 with λ_n > 0; afterwards ‖Δv‖ = slip_kick.
    assert!(
        s2s.pre.sigma.abs() < 1e-8 * lam_scale,
        "σ = {:e}",
        s2s.pre.sigma
    );
    assert!(s2s.pre.lambda_n > 0.0);
    assert!((s2s.post.slip_speed - 2e-6).abs() < 1e-9);
    // Lift-off: λ_n ≈ 0; the reset only puts q back on h = 0 (a drift-sized move) and adds
    // the separation speed n·v_c⁺ = 1e-8 m/s (ω unchanged: the normal impulse has no moment
    // about the centre).
    assert!(
        off.pre.lambda_n.abs() < 1e-8 * lam_scale,
        "λ_n = {:e}",
        off.pre.lambda_n
    );
    for j in 0..3 {
        assert!((off.x_pre[j] - off.x_post[j]).abs() < 1e-8);
    }
    assert!(
        off.post.h.abs() < 1e-14,
        "h after lift-off {:e}",
        off.post.h
    );
    assert_eq!(off.x_pre[6..9], off.x_post[6..9]);
    assert!(
        (off.post.normal_velocity - 1e-8).abs() < 1e-12,
        "{:e}",
        off.post.normal_velocity
    );
    assert!((off.post.energy - off.pre.energy).abs() < 1e-12);
    // λ_n > 0 and (in Stick) σ > 0 at every contact-mode step sample: the modes were valid.
    let tr = &out.trajectory;
    for i in 0..tr.len() {
        if tr.kind[i] == SampleKind::Step && tr.mode[i] != Mode::Free {
            assert!(rep.samples[i].lambda_n > 0.0, "λ_n ≤ 0 at {}", tr.t[i]);
            if tr.mode[i] == Mode::Stick {
                assert!(rep.samples[i].sigma > 0.0);
                assert!(rep.samples[i].slip_speed < 1e-9);
            }
        }
        assert!(rep.samples[i].h >= -PENETRATION_TOL);
    }
    assert!(rep.summary.max_drift < 1e-8, "{}", rep.summary.max_drift);
}

/// With friction, damping and torques: between consecutive samples of one mode the energy rises
/// by at most the torque work (trapezoid on q̇ᵀτ), and events never add energy.
#[test]
fn with_friction_energy_grows_only_by_torque_work() {
    let (x0, series) = scripted_push();
    for law in [
        ImpactLaw::Stick,
        ImpactLaw::MaxDissipation,
        ImpactLaw::MinRelativeVelocity,
    ] {
        let sys = BallFinger::new(
            fixtures::paper_scene().unwrap(),
            series.clone(),
            BallFingerSettings {
                impact_law: law,
                ..BallFingerSettings::default()
            },
        )
        .unwrap();
        let set = SimSettings {
            output_dt: Some(1e-3),
            h_max: 1e-3,
            ..tight()
        };
        let out = match simulate(&sys, set, Mode::Free, 0.0, &x0, 2.5) {
            Ok(o) => o,
            Err(f) => {
                for e in f.partial.events.iter().take(12) {
                    let pre = sys.sample_info_or_nan(e.mode_before, e.t, &e.x_pre);
                    let post = sys.sample_info_or_nan(e.mode_after.unwrap(), e.t, &e.x_post);
                    eprintln!(
                        "{:.12} {} {:?}->{:?} pre {:?}\n   post {:?}",
                        e.t, e.guard, e.mode_before, e.mode_after, pre, post
                    );
                }
                panic!("{law:?}: {}", f.error)
            }
        };
        let tr = &out.trajectory;
        let info = infos(&sys, &out);
        let power = |i: usize| {
            let qd = &tr.x[i][3..6];
            (0..3).map(|j| qd[j] * info[i].tau[j]).sum::<f64>()
        };
        // Time-ordered samples without the duplicated grid/step points.
        let mut idx: Vec<usize> = (0..tr.len()).collect();
        idx.sort_by(|&a, &b| tr.t[a].total_cmp(&tr.t[b]).then(a.cmp(&b)));
        let mut checked = 0;
        for w in idx.windows(2) {
            let (a, b) = (w[0], w[1]);
            let de = info[b].energy - info[a].energy;
            if tr.kind[b] == SampleKind::EventPost {
                assert!(de <= 1e-10, "{law:?}: event added {de:e} J at {}", tr.t[b]);
                continue;
            }
            if tr.mode[a] != tr.mode[b] || tr.kind[a] == SampleKind::EventPre {
                continue;
            }
            let work = 0.5 * (power(a) + power(b)) * (tr.t[b] - tr.t[a]);
            assert!(
                de <= work + 1e-9,
                "{law:?}: E rose by {de:e} J, torque work {work:e} J, t = {}",
                tr.t[b]
            );
            checked += 1;
        }
        assert!(checked > 1000);
        // Damping and friction dissipate: total change < total torque work.
        assert!(out.events.len() >= 2, "{law:?}");
    }
}

#[test]
fn projection_bounds_drift_and_without_it_drift_stays_within_tolerance() {
    let (x0, series) = scripted_push();
    let mut drift = Vec::new();
    for project in [true, false] {
        let sys = BallFinger::new(
            fixtures::paper_scene().unwrap(),
            series.clone(),
            BallFingerSettings {
                impact_law: ImpactLaw::Stick,
                project,
                ..BallFingerSettings::default()
            },
        )
        .unwrap();
        let set = SimSettings {
            rtol: 1e-5,
            atol: 1e-7,
            ..SimSettings::default()
        };
        let out = simulate(&sys, set, Mode::Free, 0.0, &x0, 1.4).unwrap();
        let rep = sys.report(&out, 0.0, 1.0);
        let tr = &out.trajectory;
        let gap = (0..tr.len())
            .filter(|&i| tr.kind[i] == SampleKind::Step && tr.mode[i] != Mode::Free)
            .map(|i| rep.samples[i].h.abs())
            .fold(0.0, f64::max);
        drift.push((rep.summary.max_drift, gap));
    }
    let ((d_proj, gap_proj), (d_none, gap_none)) = (drift[0], drift[1]);
    assert!(d_proj > 0.0, "projection must report the drift it removed");
    assert!(gap_proj < 1e-12, "after projection |h| = {gap_proj:e}");
    assert_eq!(d_none, 0.0, "no projection, no reported removal");
    assert!(gap_none > 100.0 * gap_proj.max(1e-15), "{gap_none:e}");
    assert!(
        gap_none < 1e-3,
        "unprojected drift {gap_none:e} beyond contact tolerance"
    );
}
