//! Legendre–Gauss (LG) transcription of the ball-and-finger problems.
//!
//! With LG the stick phase imposes d(Δv)/dt = 0 at the Gauss nodes (`StickLevel::Acceleration`)
//! and Δv⁺ = 0 at the impact (eq. 40c), without an end-point Δv row, and the Gauss defects are
//! in integral form X_k − X₀ − (T/2) Σ_j A_kj f_j with A = D₁⁻¹ (`ocp::transcription`).
//! Checked here:
//! * the acceleration-level rows are the time derivative of Δv (eq. 13), against central
//!   differences of the independently compiled contact diagnostics;
//! * the integral-form defect rows are the differential collocation defects
//!   Σ_j D_kj X_j − (T/2) f_k (D from `ocp::nodes`, f = (q̇, q̈, ω̇)) multiplied by D₁⁻¹, and
//!   the quadrature end row is X_f − X₀ − (T/2) Σ w_k f_k;
//! * `periodic-qc` with LG-30 and LG-40 is Solved from the default guess without an extra
//!   period row, at the same local optimum as Radau 3 × 10 (objective, phase durations), with
//!   small KKT residuals; Δv = 0 at the stick phase's quadrature end point although it is not
//!   imposed there;
//! * `periodic-cot` and `periodic-cot-human` with LG-30 converge from the default guess (with
//!   the differential Gauss defects both ended at MaxIterations), with small KKT residuals,
//!   rotating the ball the desired way, within 10 % of the Radau 3 × 10 objective.
//! * an LG-30 optimum re-loaded without its NLP vector is interpolated onto the same mesh
//!   exactly (every Gauss node, the last included) and re-solved in at most 10 iterations.

#[path = "common/cli.rs"]
mod cli_util;

mod common;

use ball_finger::pipeline::{SolutionIo, build, solve};
use bf_codegen::Scene;
use bf_optim::ipm::{Nlp, Status};
use bf_optim::ocp::nodes::{differentiation_matrix, legendre_gauss};
use bf_optim::ocp::transcription::integration_matrix;
use bf_optim::ocp::{GraphFn, Scheme};
use bf_problem::node::{NodeSettings, node_function as node_function_with};
use bf_problem::points::Diagnostics;
use bf_problem::{
    BuiltProblem, CostKind, OcpSolution, PhaseMode, Problem, ProblemSettings, StickLevel,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn paper_scene() -> Scene {
    Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").unwrap()
}

#[test]
fn acceleration_level_stick_rows_are_the_time_derivative_of_delta_v() {
    let scene = paper_scene();
    let ph = bf_problem::node::physics(&scene).unwrap();
    let eps = 0.01;
    let opt = NodeSettings {
        mode: PhaseMode::Stick,
        cost: CostKind::Qc {
            w: 1.0,
            omega_ref: [0.0, 0.0, 2.2],
        },
        h_bounds: None,
        hdot_bounds: None,
        eps,
        cone_margin: 0.0,
    };
    let (nf, _) = node_function_with(&scene, &ph, &opt, StickLevel::Acceleration).unwrap();
    let (nv, _) = node_function_with(&scene, &ph, &opt, StickLevel::Velocity).unwrap();
    assert_eq!(nf.path_bounds, nv.path_bounds);
    let nq = ph.nq;
    let nx = bf_codegen::spec::state_len(nq);
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

fn solve_named(name: &str, scheme: Scheme, points: usize) -> (BuiltProblem, OcpSolution) {
    let s = ProblemSettings {
        points,
        scheme,
        max_iter: 600,
        ..ProblemSettings::default()
    };
    let p = build(name.parse().unwrap(), &s).unwrap();
    let sol = solve(&p, None).unwrap();
    (p, sol)
}

use common::kkt::{ocp_kkt_residual as kkt_residual, solved_or_degenerate};

/// |Δv| at the end point of the stick phase (phase 1) of `sol`.
fn stick_end_delta_v(sol: &OcpSolution, scene: &Scene) -> f64 {
    let diag = Diagnostics::new(scene, sol.epsilon).unwrap();
    let xf = sol.raw[1].x.last().unwrap();
    diag.eval(xf)
        .delta_v
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
}

#[test]
fn lg_defects_are_the_differential_defects_in_integral_form() {
    let n = 12;
    let s = ProblemSettings {
        points: n,
        scheme: Scheme::Lg,
        ..ProblemSettings::default()
    };
    // A single free phase: x = (q, q̇, ω), algebraic a = (q̈, ω̇), so f = (q̇, q̈, ω̇).
    let p = build(Problem::Reach, &s).unwrap();
    let l = &p.nlp.phases[0];
    let (nx, nq) = (l.nx, (l.nx - 3) / 2);
    assert_eq!(l.na, nq + 3);
    let (tau, w) = legendre_gauss(n);
    let mut support = vec![-1.0];
    support.extend(&tau);
    let d = differentiation_matrix(&support);
    // A = D₁⁻¹ with row sums 1 + τ_k (it integrates constants exactly) and bounded entries.
    let a = integration_matrix(&l.mesh).unwrap();
    for k in 0..n {
        for j in 0..n {
            let e: f64 = (0..n).map(|m| a[k][m] * d[m + 1][j + 1]).sum();
            let id = if k == j { 1.0 } else { 0.0 };
            assert!((e - id).abs() < 1e-10, "(A D1)[{k}][{j}] = {e}");
        }
        let sum: f64 = a[k].iter().sum();
        assert!((sum - (1.0 + tau[k])).abs() < 1e-12);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    let mut x = p.nlp.initial().to_vec();
    for v in x.iter_mut() {
        *v += rng.random_range(-1.0..1.0);
    }
    x[l.t] = 1.7;
    let mut g = vec![0.0; p.nlp.num_constraints()];
    p.nlp.constraints(&x, &mut g);
    let def0 = p
        .nlp
        .row_blocks
        .iter()
        .find(|b| b.0.contains("defects"))
        .unwrap()
        .1
        .start;
    let end0 = p
        .nlp
        .row_blocks
        .iter()
        .find(|b| b.0.contains("quadrature end"))
        .unwrap()
        .1
        .start;
    // f_i at node k from the node variables.
    let f = |k: usize, i: usize| -> f64 {
        if i < nq {
            x[l.x(k + 1, nq + i)]
        } else {
            x[l.a(k, i - nq)]
        }
    };
    let ht = 0.5 * x[l.t];
    for i in 0..nx {
        for k in 0..n {
            // Differential defect, and D₁ applied to the transcription's rows.
            let diff: f64 = (0..=n).map(|j| d[k + 1][j] * x[l.x(j, i)]).sum::<f64>() - ht * f(k, i);
            let mapped: f64 = (0..n).map(|j| d[k + 1][j + 1] * g[def0 + j * nx + i]).sum();
            assert!(
                (diff - mapped).abs() < 1e-9 * (1.0 + diff.abs()),
                "state {i}, node {k}: differential {diff} vs D1 * row {mapped}"
            );
        }
        let quad: f64 = (0..n).map(|k| w[k] * f(k, i)).sum();
        let end = x[l.x(n + 1, i)] - x[l.x(0, i)] - ht * quad;
        assert!((g[end0 + i] - end).abs() < 1e-12 * (1.0 + end.abs()));
    }
}

/// `periodic-qc` with Legendre–Gauss: LG-30 from the default guess reaches the local optimum
/// of the Radau 3 × 10 solve from that guess, and LG-40 warm-started from LG-30 stays there
/// (a cold start on another mesh may land on another of the problem's local optima, which says
/// nothing about the transcription); both Solved in one stage, the KKT conditions met, and the
/// stick phase's end point at rest relative to the ball to the quadrature error.
#[test]
fn lg_periodic_qc_is_solved_at_the_radau_optimum() {
    let scene = paper_scene();
    let (_, radau) = solve_named("periodic-qc", Scheme::Radau { elements: 3 }, 30);
    assert!(radau.status.is_success(), "{:?}", radau.status);
    let mut last_dv = f64::INFINITY;
    let mut prev: Option<OcpSolution> = None;
    for n in [30, 40] {
        let s = ProblemSettings {
            points: n,
            scheme: Scheme::Lg,
            max_iter: 600,
            warm_start: prev.take(),
            ..ProblemSettings::default()
        };
        let p = build("periodic-qc".parse().unwrap(), &s).unwrap();
        let lg = solve(&p, None).unwrap();
        // The plain problem: no period row (LG-30 with the differential Gauss defects only
        // converged with one).
        assert!(p.ocp.points.iter().all(|pf| pf.name != "period bounds"));
        assert_eq!(lg.status, Status::Solved, "LG-{n}: {:?}", lg.stages);
        assert!(
            lg.stages.len() == 1,
            "LG-{n} needed the fallback guess: {:?}",
            lg.stages
        );
        let (stat, viol) = kkt_residual(&p, &lg);
        assert!(viol < 1e-7 && stat < 1e-5, "LG-{n}: {viol} {stat}");
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
        let dv = stick_end_delta_v(&lg, &scene);
        assert!(
            dv < 1e-4 && dv < last_dv,
            "LG-{n}: |dv(tf)| = {dv} (previous N: {last_dv})"
        );
        last_dv = dv;
        prev = Some(lg);
    }
}

#[test]
fn lg_periodic_cot_problems_converge_from_the_default_guess() {
    for name in ["periodic-cot", "periodic-cot-human"] {
        // The Radau reference of the objective check below: a cold direct solve with the
        // relative-residual accuracy test alone. With the default backward-error test its
        // path on the human scene diverges after a few changed steps and reaches the
        // iteration limit; over 32 starts the two tests solve as many (decision record 0008),
        // so this pairing of two single cold solves is a property of their paths. Likewise
        // three refinement steps (decision record 0009): with ten this path also reaches the
        // iteration limit on the human scene.
        let reference = ProblemSettings {
            points: 30,
            scheme: Scheme::Radau { elements: 3 },
            max_iter: 600,
            ipm: Some(bf_optim::ipm::Settings {
                linear_solver: bf_optim::ipm::LinearSolverSettings {
                    backward_error_tol: 0.0,
                    max_refinement_steps: 3,
                    ..Default::default()
                },
                ..bf_optim::ipm::Settings::default()
            }),
            ..ProblemSettings::default()
        };
        let radau = solve(&build(name.parse().unwrap(), &reference).unwrap(), None).unwrap();
        assert!(radau.status.is_success(), "{name}: {:?}", radau.stages);
        let (p, lg) = solve_named(name, Scheme::Lg, 30);
        // Solved, not just Acceptable: with plain AMD and δ_c = 1e-9 the LDLᵀ growth of the
        // constraint rows eliminated first hid the curvature and the iterates crept to an
        // Acceptable exit (optim/README.md, KKT factorization).
        assert_eq!(lg.status, Status::Solved, "{name} LG-30: {:?}", lg.stages);
        // From the solver's δ_c = 1e-9, as Radau (no LG-only start value): 202 and 69
        // iterations measured (BENCHMARKS.md, mesh sweep); a crawl would take thousands.
        assert!(
            lg.iterations < 400,
            "{name} LG-30: {} iterations",
            lg.iterations
        );
        assert!(
            lg.stages.len() == 1,
            "{name} LG-30 needed the fallback guess: {:?}",
            lg.stages
        );
        let (stat, viol) = kkt_residual(&p, &lg);
        assert!(viol < 1e-6 && stat < 1e-5, "{name} LG-30: {viol} {stat}");
        assert!(lg.period <= bf_problem::COT_MAX_PERIOD + 1e-6);
        // Rotation in the desired direction (1, −1, 0)/√2.
        let along = (lg.mean_omega[0] - lg.mean_omega[1]) / 2f64.sqrt();
        assert!(along > 0.05, "{name}: {:?}", lg.mean_omega);
        if name == "periodic-cot-human" {
            for q in &lg.nodes.q {
                assert!(q[1] >= -1e-7 && q[2] >= -1e-7 && q[1] <= 90f64.to_radians() + 1e-7);
            }
        }
        // Near the Radau optimum: one degree-30 polynomial per phase resolves the long release
        // phase less well than three elements (module docs of `problems`).
        let rel = (lg.objective - radau.objective).abs() / radau.objective;
        assert!(
            rel < 0.1,
            "{name}: LG-30 J = {} vs Radau J = {}",
            lg.objective,
            radau.objective
        );
    }
}

/// The fixed-horizon spinning archetypes keep contact through the stick phase: |h| stays at
/// the contact tolerance at the collocation points with both schemes (without the stick-phase
/// h row, Δv = 0 alone let the contact point slide over the smoothed fingertip: rotate-fast
/// LG-30 reached J = −28 with h = −0.76 m, Radau −3.8 with h = −0.05 m). Two checks on the
/// objective: from the default guess LG ends no more than 10 % below the Radau optimum (a
/// sliding contact shows as a far lower J; the two cold solves may end on different local
/// optima), and LG warm-started from the Radau optimum reaches the same optimum to 1 % (5 %
/// for the bang-bang torques of rotate-fast, whose switches the two meshes resolve
/// differently).
#[test]
fn spinning_archetypes_keep_contact_in_the_stick_phase() {
    let scene = paper_scene();
    let diag = Diagnostics::new(&scene, 0.01).unwrap();
    let solved = |name: &str, scheme: Scheme, warm: Option<OcpSolution>| {
        let s = ProblemSettings {
            points: 30,
            scheme,
            max_iter: 1500,
            warm_start: warm,
            ..ProblemSettings::default()
        };
        let p = build(name.parse().unwrap(), &s).unwrap();
        let sol = solve(&p, None).unwrap();
        assert!(
            solved_or_degenerate(name, &sol),
            "{name} {scheme:?}: {:?}",
            sol.stages
        );
        let (stat, viol) = kkt_residual(&p, &sol);
        assert!(
            viol < 1e-7 && stat < 1e-5,
            "{name} {scheme:?}: {viol} {stat}"
        );
        // The state at every collocation node of the stick phase: |h| within the path bound
        // 1e-4, relaxed by the solver's bound relaxation (1e-8) and the reported violation.
        let stick = &sol.raw[1];
        assert_eq!(stick.node_state.len(), 30);
        let tol = 1e-4 + 1e-8 + sol.constraint_violation;
        for &k in &stick.node_state {
            let h = diag.eval(&stick.x[k]).h;
            assert!(h.abs() <= tol, "{name} {scheme:?}: h = {h}");
        }
        sol
    };
    for name in ["rotate-fast", "rotate-ref"] {
        let radau = solved(name, Scheme::Radau { elements: 3 }, None);
        let lg = solved(name, Scheme::Lg, None);
        let jr = radau.objective;
        assert!(
            lg.objective >= jr - 0.1 * jr.abs(),
            "{name}: LG J = {} far below Radau J = {jr}",
            lg.objective
        );
        let lg_warm = solved(name, Scheme::Lg, Some(radau));
        let rel = (lg_warm.objective - jr).abs() / jr.abs();
        // rotate-fast's torques are bang-bang: one degree-29 polynomial per phase and three
        // elements resolve their switches differently, and LG warm-started from the Radau
        // optimum (J −3.286) moves to a neighbouring one 4 % lower (−3.417).
        let same = if name == "rotate-fast" { 0.05 } else { 0.01 };
        assert!(
            rel < same,
            "{name}: Radau J = {jr} vs LG J = {} from the Radau optimum",
            lg_warm.objective
        );
    }
}

/// `reach` and `reorient` with Legendre–Gauss, 30 points per phase, from the default guess:
/// Solved, with the KKT conditions met and each problem's defining constraint held (the other
/// two archetypes: `spinning_archetypes_keep_contact_in_the_stick_phase`).
#[test]
fn lg_reach_and_reorient_are_solved() {
    for name in ["reach", "reorient"] {
        let (p, sol) = solve_named(name, Scheme::Lg, 30);
        assert_eq!(sol.status, Status::Solved, "{name}: {:?}", sol.stages);
        let (stat, viol) = kkt_residual(&p, &sol);
        assert!(viol < 1e-7 && stat < 1e-5, "{name}: {viol} {stat}");
        match name {
            // Touches the ball (0 ≤ h ≤ 1e-4 at the end) at rest.
            "reach" => {
                let x = sol.raw[0].x.last().unwrap();
                let h = Diagnostics::new(&paper_scene(), sol.epsilon)
                    .unwrap()
                    .eval(x)
                    .h;
                assert!((-1e-8..=1e-4 + 1e-8).contains(&h), "reach: h(tf) = {h}");
                assert!(x[3..6].iter().all(|v| v.abs() < 1e-7), "reach: {x:?}");
            }
            // The ball turned by π/2 about z.
            _ => assert!(
                (sol.c2 - std::f64::consts::FRAC_PI_2).abs() < 1e-7,
                "{}",
                sol.c2
            ),
        }
    }
}

/// An LG-30 optimum written to `solution.json`, with `nlp_warm` stripped from its internals
/// file, and re-loaded is interpolated onto the same mesh from the element polynomials: the
/// states at every support point and the controls and algebraic variables at every Gauss node,
/// the last one included. The interpolated start is the optimum's NLP vector; the warm solve
/// (which has no multipliers to start from) begins at the barrier level its constraint
/// violation implies, not at the default 1e-4, and ends Solved in at most 10 iterations at
/// the same objective (to 1e-7 relative: two points that pass the tolerance 1e-8 of the KKT
/// error each, measured 5e-8 apart).
#[test]
fn lg_warm_start_without_the_nlp_vector_restarts_at_the_optimum() {
    let (_, sol) = solve_named("periodic-qc", Scheme::Lg, 30);
    assert_eq!(sol.status, Status::Solved, "{:?}", sol.stages);
    let dir = cli_util::tmpdir("lg-warm");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("solution.json");
    sol.write_json(&path).unwrap();
    let internals = dir.join(ball_finger::pipeline::solution_io::INTERNALS_FILE);
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&internals).unwrap()).unwrap();
    assert!(v.as_object_mut().unwrap().remove("nlp_warm").is_some());
    std::fs::write(&internals, serde_json::to_string(&v).unwrap()).unwrap();
    let stripped = OcpSolution::read_json(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert!(stripped.nlp_warm.is_none());
    let s = ProblemSettings {
        points: 30,
        scheme: Scheme::Lg,
        max_iter: 600,
        warm_start: Some(stripped),
        ..ProblemSettings::default()
    };
    let p = build(Problem::PeriodicQc, &s).unwrap();
    let exact = &sol.nlp_warm.as_ref().unwrap().x;
    let worst = p
        .nlp
        .initial()
        .iter()
        .zip(exact)
        .map(|(a, b)| (a - b).abs() / (1.0 + b.abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "interpolated start off by {worst:e}");
    let warm = solve(&p, None).unwrap();
    assert_eq!(warm.status, Status::Solved, "{:?}", warm.stages);
    assert!(
        warm.stages[0].0.starts_with("interpolated warm start"),
        "{:?}",
        warm.stages
    );
    assert!(warm.iterations <= 10, "{:?}", warm.stages);
    let rel = (warm.objective - sol.objective).abs() / sol.objective.abs();
    assert!(
        rel <= 1e-7,
        "J = {} vs {} (rel {rel:e})",
        warm.objective,
        sol.objective
    );
}
