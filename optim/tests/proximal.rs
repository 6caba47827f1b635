//! The proximal term δ_w ≥ κ_p μ on stalled barrier problems above the tolerance
//! (`Settings::proximal_weight`, `Settings::proximal_after`; decision record 0011). It
//! regularizes the Newton steps of barrier problems that are stations on the way, never of
//! those whose μ is at most the tolerance, so it may change a solve's path but not the
//! optimum it converges to: the tests check that on the Hock–Schittkowski suite (objective as
//! given, × 1e8, × 1e12) with the term on every barrier problem above the tolerance (where it
//! acts on every solve) and with the default stall count, that a solve whose barrier problems
//! are all answers is bit for bit the same with and without it, and that invalid weights are
//! refused by name.

mod hs;

use bf_optim::ipm::{BarrierSettings, Settings, Status, solve};

/// The term off.
fn off() -> Settings {
    Settings {
        barrier: BarrierSettings {
            proximal_weight: 0.0,
            ..Default::default()
        },
        ..Settings::default()
    }
}

#[test]
fn the_proximal_term_keeps_every_hock_schittkowski_result() {
    let default = Settings::default();
    assert_eq!(
        (
            default.barrier.proximal_weight,
            default.barrier.proximal_after
        ),
        (0.1, 60)
    );
    let without = hs::sweep_scaled_objectives(&off());
    let always = Settings {
        barrier: BarrierSettings {
            proximal_after: 0,
            ..Default::default()
        },
        ..Settings::default()
    };
    for (label, settings) in [
        ("the default (after 60 iterations)", default),
        ("on every barrier problem above tol", always),
    ] {
        let with = hs::sweep_scaled_objectives(&settings);
        // HS013's Acceptable ends (about 1 % from f* = 1, not a KKT point) may move by a hair.
        hs::assert_same_optima(&without, &with, label, 1.01);
        let n: usize = with
            .iter()
            .map(|(_, _, s)| s.counters.proximal_iterations)
            .sum();
        let changed = without
            .iter()
            .zip(&with)
            .filter(|((_, _, a), (_, _, b))| a.iterations != b.iterations)
            .count();
        println!("{label}: {n} proximal iterations, {changed} solves with other iteration counts");
        if settings.barrier.proximal_after == 0 {
            // Every solve that starts above the tolerance carries it: the comparison covers
            // solves that it changes.
            assert!(n > 0 && changed > 0, "{label}: {n}, {changed}");
        }
        for (_, _, s) in &without {
            assert_eq!(s.counters.proximal_iterations, 0);
        }
    }
}

#[test]
fn barrier_problems_that_are_answers_never_carry_it() {
    // μ₀ = tol: every barrier problem of these solves is an answer, so the term must not act
    // even on the first iteration of a stall count of 0.
    for p in hs::all().into_iter().take(12) {
        let at_tol = |s: Settings| Settings {
            barrier: BarrierSettings {
                mu_init: s.termination.tol,
                proximal_after: 0,
                ..s.barrier
            },
            ..s
        };
        let a = solve(&p, &at_tol(off())).unwrap();
        let b = solve(&p, &at_tol(Settings::default())).unwrap();
        assert_eq!(b.counters.proximal_iterations, 0, "{}", p.name);
        assert_eq!(
            (a.status, a.iterations, a.x.clone()),
            (b.status, b.iterations, b.x.clone()),
            "{}",
            p.name
        );
    }
}

#[test]
fn invalid_proximal_weights_are_rejected() {
    let p = hs::all().into_iter().next().unwrap();
    for bad in [-0.1, f64::NAN, f64::INFINITY] {
        let s = Settings {
            barrier: BarrierSettings {
                proximal_weight: bad,
                ..Default::default()
            },
            ..Settings::default()
        };
        let err = solve(&p, &s).unwrap_err().to_string();
        assert!(err.contains("proximal_weight"), "{bad}: {err}");
    }
    // 0 is the documented way to turn the term off, not an invalid weight.
    assert_eq!(solve(&p, &off()).unwrap().status, Status::Solved);
}
