//! Extrapolation of a full step along negative curvature
//! (`Settings::max_curvature_extrapolation`; decision record 0010). At a saddle
//! the inertia correction keeps δ_w just above the most negative curvature, so the step along
//! that direction is ‖∇L‖ / (δ_w − |λ|) and grows by a bounded factor per iteration; doubling α
//! while the acceptance test holds and φ_μ decreases leaves the saddle in fewer iterations and
//! reaches the same minimizer, on every barrier problem or only on those whose μ is at most
//! the tolerance (`Settings::extrapolation_scope`). The second test checks that neither scope
//! changes a result of the Hock–Schittkowski suite (objective as given and × 1e8, × 1e12).

mod hs;

use bf_optim::ipm::{
    BarrierSettings, ExperimentalSettings, ExtrapolationScope, LineSearchSettings, Settings,
    Status, solve,
};
use hs::Hs;
use hs::dual::D;

/// Curvature along x₁ at the saddle: −2 EPS.
const EPS: f64 = 1e-3;
/// Quartic coefficient that bounds the objective along x₁.
const QUARTIC: f64 = 1e-5;

/// `f = −EPS x₁² + QUARTIC x₁⁴ + (x₂ − 1)²`, no bounds, started next to the saddle at
/// x₁ = 0: minima at x₁ = ±√(EPS / (2 QUARTIC)) = ±√50, f* = −EPS² / (4 QUARTIC).
fn saddle() -> Hs {
    fn f(x: &[D]) -> D {
        let x2 = x[0] * x[0];
        -EPS * x2 + QUARTIC * x2 * x2 + (x[1] - 1.0) * (x[1] - 1.0)
    }
    fn none(_: &[D]) -> Vec<D> {
        Vec::new()
    }
    Hs {
        name: "saddle",
        tags: "",
        x0: vec![1e-4, 0.0],
        xl: vec![f64::NEG_INFINITY; 2],
        xu: vec![f64::INFINITY; 2],
        neq: 0,
        m: 0,
        f,
        g: none,
        fstar: FSTAR,
        xstar: Some(vec![XSTAR, 1.0]),
    }
}

const FSTAR: f64 = -EPS * EPS / (4.0 * QUARTIC);
const XSTAR: f64 = 7.0710678118654755;

/// No extrapolation (cap 1).
fn without() -> Settings {
    Settings {
        line_search: LineSearchSettings {
            max_curvature_extrapolation: 1.0,
            ..Default::default()
        },
        ..Settings::default()
    }
}

/// Extrapolation up to α = 16 on the barrier problems of `scope`; with those whose μ is at
/// most the tolerance (`Answers`), the default.
fn with(scope: ExtrapolationScope) -> Settings {
    let default = Settings::default();
    assert_eq!(default.line_search.max_curvature_extrapolation, 16.0);
    assert_eq!(
        default.experimental.extrapolation_scope,
        ExtrapolationScope::Answers
    );
    Settings {
        experimental: ExperimentalSettings {
            extrapolation_scope: scope,
            ..default.experimental
        },
        ..default
    }
}

const SCOPES: [ExtrapolationScope; 2] = [
    ExtrapolationScope::Answers,
    ExtrapolationScope::EveryBarrier,
];

#[test]
fn a_saddle_is_left_in_fewer_iterations_for_the_same_minimum() {
    let off = solve(&saddle(), &without()).unwrap();
    assert_eq!(off.counters.extrapolations, 0);
    let every = solve(&saddle(), &with(ExtrapolationScope::EveryBarrier)).unwrap();
    // A barrier problem that is an answer from the start (μ₀ = tol): the scope that waits
    // for one then acts at the saddle too.
    let at_floor = |s: Settings| Settings {
        barrier: BarrierSettings {
            mu_init: s.termination.tol,
            ..s.barrier
        },
        ..s
    };
    let off_floor = solve(&saddle(), &at_floor(without())).unwrap();
    let fin_floor = solve(&saddle(), &at_floor(with(ExtrapolationScope::Answers))).unwrap();
    for (label, sol) in [
        ("without", &off),
        ("every barrier", &every),
        ("without, μ₀ = tol", &off_floor),
        ("answers only, μ₀ = tol", &fin_floor),
    ] {
        assert_eq!(sol.status, Status::Solved, "{label}: {sol:?}");
        assert!((sol.x[0] - XSTAR).abs() < 1e-6, "{label}: x = {:?}", sol.x);
        assert!((sol.x[1] - 1.0).abs() < 1e-6, "{label}: x = {:?}", sol.x);
        assert!((sol.objective - FSTAR).abs() < 1e-12, "{label}: {sol:?}");
        println!("{label}: {} iterations", sol.iterations);
    }
    // Here the unextrapolated step already grows geometrically (nothing but δ_w limits it),
    // so the saving is a few iterations (11 against 16); where the constraints' curvature
    // limits each step, as on `periodic-cot` Radau 3 × 48, it is the difference between a
    // crawl to the iteration limit and Solved (tests/kkt_ordering.rs).
    for (on, base) in [(&every, &off), (&fin_floor, &off_floor)] {
        assert!(on.counters.extrapolations > 0, "{:?}", on.counters);
        assert!(
            on.iterations < base.iterations,
            "{} vs {}",
            on.iterations,
            base.iterations
        );
    }
    // From μ₀ = 0.1 this unconstrained solve (no bound, so μ falls at every iteration) reaches
    // μ ≤ tol before it leaves the saddle: the default scope leaves it as early as every
    // barrier problem in scope, for the same minimum.
    let fin = solve(&saddle(), &with(ExtrapolationScope::Answers)).unwrap();
    println!(
        "answers only, μ₀ = 0.1: {} iterations, {} extrapolated steps (every barrier: {})",
        fin.iterations, fin.counters.extrapolations, every.counters.extrapolations
    );
    assert_eq!(fin.status, Status::Solved);
    assert!((fin.objective - FSTAR).abs() < 1e-12, "{fin:?}");
    assert!(fin.counters.extrapolations > 0);
    assert!(fin.iterations < off.iterations);
}

#[test]
fn extrapolation_keeps_every_hock_schittkowski_result() {
    let off = hs::sweep_scaled_objectives(&without());
    for scope in SCOPES {
        let on = hs::sweep_scaled_objectives(&with(scope));
        // HS013's Acceptable ends (about 1 % from f* = 1) may move by a hair: with
        // extrapolation at most 1 % farther from the published optimum.
        hs::assert_same_optima(&off, &on, &format!("with extrapolation ({scope:?})"), 1.01);
        let n: usize = on.iter().map(|(_, _, s)| s.counters.extrapolations).sum();
        let changed = off
            .iter()
            .zip(&on)
            .filter(|((_, _, a), (_, _, b))| a.iterations != b.iterations)
            .count();
        println!(
            "{scope:?}: {n} extrapolated steps over the suite; {changed} solves with other \
             iteration counts"
        );
        // With every barrier problem in scope the comparison covers solves that extrapolation
        // changes; near the minimizers of this suite the barrier problems with μ ≤ tol have
        // no negative curvature, so the default scope changes none of them.
        match scope {
            ExtrapolationScope::EveryBarrier => assert!(
                n > 0 && changed > 0,
                "{scope:?}: {n} extrapolations, {changed} changed solves"
            ),
            ExtrapolationScope::Answers => assert_eq!((n, changed), (0, 0)),
        }
        for ((name, obj, a), (_, _, b)) in off.iter().zip(&on) {
            if a.iterations != b.iterations || a.status != Status::Solved {
                println!(
                    "  {name} × {obj:e}: {:?} {} it. {} without, {:?} {} it. {} with",
                    a.status, a.iterations, a.objective, b.status, b.iterations, b.objective
                );
            }
        }
    }
}

#[test]
fn invalid_extrapolation_caps_are_rejected() {
    for bad in [0.5, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        let s = {
            let base = with(ExtrapolationScope::Answers);
            Settings {
                line_search: LineSearchSettings {
                    max_curvature_extrapolation: bad,
                    ..base.line_search
                },
                ..base
            }
        };
        let err = solve(&saddle(), &s).unwrap_err().to_string();
        assert!(err.contains("max_curvature_extrapolation"), "{bad}: {err}");
    }
}
