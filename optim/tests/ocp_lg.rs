//! Legendre–Gauss (LG) transcription of the ball-and-finger problems (issue 6).
//!
//! With LG the stick phase imposes d(Δv)/dt = 0 at the Gauss nodes (`StickLevel::Acceleration`)
//! and Δv⁺ = 0 at the impact (eq. 40c), without an end-point Δv row. Checked here:
//! * the acceleration-level rows are the time derivative of Δv (eq. 13), against central
//!   differences of the independently compiled contact diagnostics;
//! * `periodic-qc` with LG-20 and LG-30 converges from the default guess to the same local
//!   optimum as Radau 3 × 10 (objective, phase durations), with small KKT residuals;
//! * Δv = 0 at the stick phase's quadrature end point although it is not imposed there.

use bf_codegen::Scene;
use bf_optim::ocp::{GraphFn, Scheme};
use bf_optim::problems::bf::{
    CostKind, Diagnostics, Mode, NodeOptions, Physics, StickLevel, node_function_with,
};
use bf_optim::problems::{OcpSolution, ProblemSettings, build, solve};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn paper_scene() -> Scene {
    Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").unwrap()
}

#[test]
fn acceleration_level_stick_rows_are_the_time_derivative_of_delta_v() {
    let scene = paper_scene();
    let ph = Physics::new(&scene).unwrap();
    let eps = 0.01;
    let opt = NodeOptions {
        mode: Mode::Stick,
        cost: CostKind::Qc {
            w: 1.0,
            omega_ref: [0.0, 0.0, 2.2],
        },
        h_bounds: None,
        hdot_bounds: None,
        eps,
    };
    let (nf, _) = node_function_with(&scene, &ph, &opt, StickLevel::Acceleration).unwrap();
    let (nv, _) = node_function_with(&scene, &ph, &opt, StickLevel::Velocity).unwrap();
    assert_eq!(nf.path_bounds, nv.path_bounds);
    let nq = ph.nq;
    let nx = 2 * nq + 3;
    let diag = Diagnostics::new(&scene, eps).unwrap();
    let build_fn = |n: &bf_optim::ocp::NodeFunction| {
        let mut g = n.graph.clone();
        let mut locals = n.x.clone();
        locals.extend(&n.a);
        locals.extend(&n.u);
        locals.push(n.duration);
        GraphFn::new(&mut g, &n.path, &locals, &n.fixed)
    };
    let (fa, fv) = (build_fn(&nf), build_fn(&nv));
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    for _ in 0..20 {
        // Random state (q near the contact region), rates, λ, τ and duration.
        let mut x: Vec<f64> = (0..nx).map(|_| rng.random_range(-1.0..1.0)).collect();
        for (i, q) in [0.1, 0.9, 1.2].iter().enumerate() {
            x[i] += q;
        }
        let qdd: Vec<f64> = (0..nq).map(|_| rng.random_range(-2.0..2.0)).collect();
        let wd: Vec<f64> = (0..3).map(|_| rng.random_range(-2.0..2.0)).collect();
        let mut local = x.clone();
        local.extend(&qdd);
        local.extend(&wd);
        local.extend((0..3 + nq).map(|_| rng.random_range(-1.0..1.0)));
        local.push(1.0);
        let ya = fa.eval(&local);
        let yv = fv.eval(&local);
        // Direction of motion d/dt (q, q̇, ω) = (q̇, q̈, ω̇).
        let mut dir = x[nq..2 * nq].to_vec();
        dir.extend(&qdd);
        dir.extend(&wd);
        let h = 1e-6;
        let at = |s: f64| {
            let xs: Vec<f64> = x.iter().zip(&dir).map(|(a, d)| a + s * d).collect();
            diag.eval(&xs).delta_v
        };
        let (p, m) = (at(h), at(-h));
        let dv0 = diag.eval(&x).delta_v;
        for r in 0..3 {
            let fd = (p[r] - m[r]) / (2.0 * h);
            let row = nq + 3 + r;
            assert!(
                (ya[row] - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                "d(dv)/dt[{r}]: {} vs FD {fd}",
                ya[row]
            );
            // The velocity-level rows are Δv itself; all other rows are identical.
            assert!((yv[row] - dv0[r]).abs() <= 1e-12 * (1.0 + dv0[r].abs()));
        }
        for (row, (a, v)) in ya.iter().zip(&yv).enumerate() {
            if !(nq + 3..nq + 6).contains(&row) {
                assert_eq!(a.to_bits(), v.to_bits(), "row {row}");
            }
        }
    }
}

fn solve_qc(scheme: Scheme, points: usize) -> OcpSolution {
    let s = ProblemSettings {
        points,
        scheme,
        max_iter: 300,
        ..ProblemSettings::default()
    };
    let p = build("periodic-qc", &s).unwrap();
    solve(&p, None).unwrap()
}

/// |Δv| at the end point of the stick phase (phase 1) of `sol`.
fn stick_end_delta_v(sol: &OcpSolution) -> f64 {
    let diag = Diagnostics::new(&paper_scene(), sol.epsilon).unwrap();
    let xf = sol.raw[1].x.last().unwrap();
    diag.eval(xf)
        .delta_v
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
}

#[test]
fn lg_periodic_qc_converges_to_the_radau_optimum() {
    let radau = solve_qc(Scheme::Radau { elements: 3 }, 30);
    assert!(radau.status.is_success(), "{:?}", radau.status);
    let mut last_dv = f64::INFINITY;
    for n in [20, 30] {
        let lg = solve_qc(Scheme::Lg, n);
        assert!(lg.status.is_success(), "LG-{n}: {:?}", lg.status);
        assert!(
            lg.stages.len() == 1,
            "LG-{n} needed the fallback guess: {:?}",
            lg.stages
        );
        assert!(lg.constraint_violation < 1e-6, "LG-{n}");
        assert!(lg.dual_infeasibility < 1e-5, "LG-{n}");
        // The same local optimum as Radau: objective and the phase structure.
        let rel = (lg.objective - radau.objective).abs() / radau.objective;
        assert!(
            rel < 2e-3,
            "LG-{n} J = {} vs Radau J = {}",
            lg.objective,
            radau.objective
        );
        for (a, b) in lg.phase_durations.iter().zip(&radau.phase_durations) {
            assert!(
                (a - b).abs() < 0.02,
                "LG-{n} durations {:?} vs {:?}",
                lg.phase_durations,
                radau.phase_durations
            );
        }
        // Δv = 0 at the quadrature end point is not imposed with LG: it must follow from
        // d(Δv)/dt = 0 at the nodes and Δv⁺ = 0 (eq. 40c), up to the quadrature error.
        // It must stay well inside the contact tolerance 1e-4 of Sect. 7 and shrink with N.
        let dv = stick_end_delta_v(&lg);
        assert!(
            dv < 1e-4 && dv < last_dv,
            "LG-{n}: |dv(tf)| = {dv} (previous N: {last_dv})"
        );
        last_dv = dv;
    }
}
