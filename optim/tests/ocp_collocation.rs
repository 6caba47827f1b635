//! Collocation layer on problems with closed-form optima: double integrator (fixed and free
//! final time, one and two phases), ratio objective, derivative checks, convergence in N.

use bf_codegen::graph::Graph;
use bf_optim::ipm::TerminationSettings;
use bf_optim::ipm::{Settings, Status, check_derivatives};
use bf_optim::ocp::toys::{self, double_integrator_phase, rest_to_rest};
use bf_optim::ocp::{
    NodeFunction, Objective, Ocp, Phase, PhaseGuess, PointFunction, Scheme, Transcription, VarRef,
    solve_nlp,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const INF: f64 = 1e20;

fn quiet() -> Settings {
    Settings {
        termination: TerminationSettings {
            tol: 1e-10,
            ..Default::default()
        },
        ..Settings::default()
    }
}

#[test]
fn rest_to_rest_min_energy_matches_closed_form() {
    // u* = 6 − 12 t on [0, 1], ∫u² = 12; the polynomial optimum is exact for N ≥ 2.
    for scheme in [Scheme::Lg, Scheme::Radau { elements: 3 }] {
        let ocp = Ocp {
            phases: vec![double_integrator_phase(8, false, (1.0, 1.0), 1.0)],
            n_costs: 2,
            params: vec![],
            points: rest_to_rest(1),
            cost_bounds: vec![],
            objective: Objective::Cost(0),
            scheme,
        };
        let tr = Transcription::new(&ocp).unwrap();
        let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
        assert_eq!(sol.status, Status::Solved, "{scheme:?}");
        assert!(
            (sol.objective - 12.0).abs() < 1e-7,
            "{scheme:?}: {}",
            sol.objective
        );
        let traj = bf_optim::ocp::extract(&tr, &sol.x);
        for (k, &tau) in traj[0].node_tau.iter().enumerate() {
            let t = traj[0].time(tau);
            assert!((traj[0].u[k][0] - (6.0 - 12.0 * t)).abs() < 1e-6);
        }
        // Dense interpolation of the state: p(t) = 3t² − 2t³.
        for t in [0.1, 0.37, 0.8] {
            let x = traj[0].x_at(2.0 * t - 1.0);
            assert!(
                (x[0] - (3.0 * t * t - 2.0 * t * t * t)).abs() < 1e-7,
                "{scheme:?} t={t}"
            );
        }
    }
}

/// `Transcription::set_block_bounds` moves a fixed end state without transcribing again: the
/// rest-to-rest double integrator's target position moved from 1 to d gives the closed-form
/// ∫u² = 12 d²; a block that does not exist, a wrong length and a reversed bound are refused.
#[test]
fn moved_end_state_matches_closed_form() {
    let ocp = Ocp {
        phases: vec![double_integrator_phase(8, false, (1.0, 1.0), 1.0)],
        n_costs: 2,
        params: vec![],
        points: rest_to_rest(1),
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme: Scheme::Radau { elements: 3 },
    };
    let mut tr = Transcription::new(&ocp).unwrap();
    for d in [2.0, -0.5] {
        // Rows of the block: x0(0), x1(0), x0(T), x1(T).
        let b = [(0.0, 0.0), (0.0, 0.0), (d, d), (0.0, 0.0)];
        tr.set_block_bounds("boundary", &b).unwrap();
        let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
        assert_eq!(sol.status, Status::Solved);
        assert!(
            (sol.objective - 12.0 * d * d).abs() < 1e-7 * (1.0 + d * d),
            "d = {d}: {}",
            sol.objective
        );
        let traj = bf_optim::ocp::extract(&tr, &sol.x);
        assert!((traj[0].x.last().unwrap()[0] - d).abs() < 1e-8);
    }
    assert!(tr.set_block_bounds("no such block", &[(0.0, 0.0)]).is_err());
    assert!(tr.set_block_bounds("boundary", &[(0.0, 0.0)]).is_err());
    let reversed = [(0.0, 0.0), (0.0, 0.0), (1.0, 0.5), (0.0, 0.0)];
    assert!(tr.set_block_bounds("boundary", &reversed).is_err());
}

#[test]
fn free_final_time_two_phases() {
    // J = ∫(1 + u²) dt over two linked phases, distance 1: J(T) = T + 12/T³, T* = 36^{1/4}.
    let t_star = libm::pow(36f64, 0.25);
    let j_star = t_star + 12.0 / t_star.powi(3);
    for scheme in [Scheme::Lg, Scheme::Radau { elements: 2 }] {
        let ocp = Ocp {
            phases: vec![
                double_integrator_phase(6, false, (0.05, 10.0), 1.0),
                double_integrator_phase(6, false, (0.05, 10.0), 1.0),
            ],
            n_costs: 2,
            params: vec![],
            points: rest_to_rest(2),
            cost_bounds: vec![],
            objective: Objective::Cost(1),
            scheme,
        };
        // Cost 1 = ∫1 and cost 0 = ∫u²: add them by using a third combined integrand is not
        // needed — minimise c_1 + c_0 via a custom phase instead.
        let mut ocp = ocp;
        for ph in &mut ocp.phases {
            let g = &mut ph.node.graph;
            let one = g.one();
            let s = g.add(one, ph.node.costs[0]);
            ph.node.costs[1] = s;
        }
        let tr = Transcription::new(&ocp).unwrap();
        let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
        assert_eq!(sol.status, Status::Solved);
        assert!(
            (sol.objective - j_star).abs() < 1e-6,
            "{scheme:?}: {} vs {j_star}",
            sol.objective
        );
        let total = sol.x[tr.phases[0].t] + sol.x[tr.phases[1].t];
        assert!((total - t_star).abs() < 1e-5, "{total} vs {t_star}");
    }
}

#[test]
fn ratio_objective_hits_duration_bound() {
    // c0/c1 = 12/T⁴ decreasing in T: optimum at the bound T = 2 with value 0.75.
    let ocp = Ocp {
        phases: vec![double_integrator_phase(6, false, (0.5, 2.0), 1.0)],
        n_costs: 2,
        params: vec![],
        points: rest_to_rest(1),
        cost_bounds: vec![],
        objective: Objective::Ratio(0, 1),
        scheme: Scheme::Lg,
    };
    let tr = Transcription::new(&ocp).unwrap();
    let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
    assert!(sol.status.is_success());
    assert!((sol.objective - 0.75).abs() < 1e-6, "{}", sol.objective);
}

/// Nonlinear test problem for the derivative check: pendulum-like ẋ = v, v̇ = −sin x + u·x,
/// costs with cross terms, and a nonlinear point function.
#[test]
fn assembled_derivatives_match_finite_differences() {
    let mut g = Graph::new();
    let (x, v, a, u) = (g.var(0), g.var(1), g.var(2), g.var(3));
    let s = g.sin(x);
    let ux = g.mul(u, x);
    let vd = g.sub(ux, s);
    let path = g.sub(a, vd); // algebraic a = v̇, imposed as path equality
    let c0 = {
        let u2 = g.square(u);
        let xv = g.mul(x, v);
        g.add(u2, xv)
    };
    let c1 = {
        let one = g.one();
        let c = g.cos(v);
        g.add(one, c)
    };
    let node = NodeFunction {
        graph: g,
        x: vec![0, 1],
        a: vec![2],
        u: vec![3],
        duration: 4,
        fixed: vec![],
        xdot: vec![v, a],
        path: vec![path],
        path_bounds: vec![(0.0, 0.0)],
        costs: vec![c0, c1],
    };
    let mut pg = Graph::new();
    let (p, q, t) = (pg.var(0), pg.var(1), pg.var(2));
    let e1 = pg.mul(p, q);
    let e2 = {
        let st = pg.sin(t);
        pg.mul(st, p)
    };
    let pf = PointFunction {
        name: "nl".into(),
        graph: pg,
        vars: vec![
            (0, VarRef::Initial { phase: 0, i: 0 }),
            (1, VarRef::Final { phase: 1, i: 1 }),
            (2, VarRef::Duration(1)),
        ],
        fixed: vec![],
        outputs: vec![e1, e2],
        bounds: vec![(0.0, 1.0), (-1.0, 1.0)],
        row_names: Vec::new(),
    };
    for scheme in [Scheme::Lg, Scheme::Radau { elements: 2 }] {
        let phase = Phase {
            name: "p".into(),
            node: node.clone(),
            x_bounds: vec![(-INF, INF); 2],
            a_bounds: vec![(-INF, INF)],
            u_bounds: vec![(-1.0, 1.0)],
            duration_bounds: (0.1, 5.0),
            points: 5,
            guess: PhaseGuess::constant(vec![0.1, 0.2], vec![0.0], vec![0.3], 1.0),
            end_ramp: None,
        };
        let ocp = Ocp {
            phases: vec![phase.clone(), phase],
            n_costs: 2,
            params: vec![],
            points: vec![pf.clone()],
            cost_bounds: vec![],
            objective: Objective::Ratio(0, 1),
            scheme,
        };
        let tr = Transcription::new(&ocp).unwrap();
        let n = bf_optim::ipm::Nlp::num_variables(&tr);
        let m = bf_optim::ipm::Nlp::num_constraints(&tr);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..3 {
            let mut x: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            for l in &tr.phases {
                x[l.t] = rng.random_range(0.5..2.0);
            }
            // Keep the denominator cost state away from 0.
            x[tr.c0 + 1] = rng.random_range(1.0..2.0);
            let lam: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
            let rep = check_derivatives(&tr, &x, 0.7, &lam, 1e-6);
            assert!(rep.max_error() < 1e-6, "{scheme:?}: {rep:?}");
        }
    }
}

#[test]
fn brachistochrone_minimum_time() {
    brachistochrone(Scheme::Lg, &[3, 4, 6, 20]);
    brachistochrone(Scheme::Radau { elements: 1 }, &[3, 4, 6, 20]);
}

/// Minimum-time brachistochrone to (1, 0.6) against the cycloid; the error must shrink with N
/// (spectral convergence) and be below 1e-6 at the finest mesh.
fn brachistochrone(scheme: Scheme, meshes: &[usize]) {
    let mut errs = Vec::new();
    for &n in meshes {
        errs.push(brachistochrone_error(scheme, n));
    }
    println!("{scheme:?} brachistochrone errors {errs:?}");
    assert!(
        errs.windows(2).all(|w| w[1] < w[0] || w[1] < 1e-9),
        "{scheme:?}: {errs:?}"
    );
    assert!(*errs.last().unwrap() < 1e-6, "{scheme:?}: {errs:?}");
}

fn brachistochrone_error(scheme: Scheme, points: usize) -> f64 {
    let tr = Transcription::new(&toys::brachistochrone(false, scheme, points)).unwrap();
    let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
    assert!(sol.status.is_success(), "{:?}", sol.status);
    (sol.objective - toys::cycloid_time()).abs()
}

/// The single integrator ẋ = u from x(0) = 1 to x(1) = 0 minimising ∫u² dt, with the path
/// output x ≥ 0 and an end ramp of clearance 0.5 over the last 20 % of the phase: x ≥ 0.5
/// until s = 0.8, then x ≥ 2.5 (1 − s). The optimum is the taut string through (0.8, 0.5),
/// ∫u² = 0.5²/0.8 + 0.5²/0.2 = 1.5625, which lies in the collocation space when 0.8 is an
/// element break (Radau, 5 equal elements); without the ramp it is the straight line, ∫u² = 1.
#[test]
fn an_end_ramp_bounds_the_path_away_from_the_phase_end_only() {
    use bf_optim::ocp::EndRamp;
    let mut g = Graph::new();
    let (x, u) = (g.var(0), g.var(1));
    let u2 = g.square(u);
    let node = NodeFunction {
        graph: g,
        x: vec![0],
        a: vec![],
        u: vec![1],
        duration: 2,
        fixed: vec![],
        xdot: vec![u],
        path: vec![x],
        path_bounds: vec![(0.0, INF)],
        costs: vec![u2],
    };
    let ramp = EndRamp {
        index: 0,
        clearance: 0.5,
        ramp: 0.2,
    };
    let ocp = |end_ramp: Option<EndRamp>, points: Vec<PointFunction>| Ocp {
        phases: vec![Phase {
            name: "string".into(),
            node: node.clone(),
            x_bounds: vec![(-INF, INF)],
            a_bounds: vec![],
            u_bounds: vec![(-INF, INF)],
            duration_bounds: (1.0, 1.0),
            points: 4,
            guess: PhaseGuess::constant(vec![0.5], vec![], vec![0.0], 1.0),
            end_ramp,
        }],
        n_costs: 1,
        params: vec![],
        points,
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme: Scheme::Radau { elements: 5 },
    };
    let solve = |end_ramp: Option<EndRamp>| {
        let ocp = ocp(
            end_ramp,
            vec![toys::fixed_ends(0, &[(0, 1.0)], 0, &[(0, 0.0)])],
        );
        let tr = Transcription::new(&ocp).unwrap();
        let sol = solve_nlp(&tr, &quiet(), None, None).unwrap();
        assert_eq!(sol.status, Status::Solved);
        (sol.objective, bf_optim::ocp::extract(&tr, &sol.x))
    };
    let (plain, _) = solve(None);
    assert!((plain - 1.0).abs() < 1e-7, "{plain}");
    let (j, traj) = solve(Some(ramp));
    assert!((j - 1.5625).abs() < 1e-6, "{j}");
    // Every collocation node meets its own bound, and the string touches it at s = 0.8.
    for (k, &tau) in traj[0].node_tau.iter().enumerate() {
        let s = 0.5 * (tau + 1.0);
        let xk = traj[0].x[traj[0].node_state[k]][0];
        assert!(xk >= ramp.extra(s) - 1e-8, "s = {s}: x = {xk}");
    }
    let at = traj[0].x_at(2.0 * 0.8 - 1.0)[0];
    assert!((at - 0.5).abs() < 1e-6, "{at}");
    // A ramp outside its ranges is refused by name.
    for bad in [
        EndRamp { ramp: 0.0, ..ramp },
        EndRamp {
            clearance: -1.0,
            ..ramp
        },
        EndRamp { index: 1, ..ramp },
    ] {
        let ocp = ocp(Some(bad), vec![]);
        let Err(err) = Transcription::new(&ocp) else {
            panic!("{bad:?} accepted");
        };
        let err = err.to_string();
        assert!(err.contains("end ramp"), "{err}");
    }
}
