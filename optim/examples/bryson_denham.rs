//! A small optimal-control problem through `bf_optim::ocp`: the Bryson–Denham problem, a
//! double integrator with a state inequality constraint and a closed-form optimum.
//!
//! ```text
//! min  ½ ∫₀¹ u² dt
//! s.t. ẋ = v,  v̇ = u,
//!      x(0) = 0, v(0) = 1,  x(1) = 0, v(1) = −1,
//!      x(t) ≤ ℓ
//! ```
//!
//! For ℓ ≤ 1/6 the constraint is active on [3ℓ, 1 − 3ℓ] and J* = 4 / (9ℓ) (Bryson & Ho,
//! *Applied Optimal Control*, Sect. 3.11); here ℓ = 1/9, so J* = 4. The optimal x is cubic
//! on the two unconstrained arcs and u is piecewise linear with kinks at t = 3ℓ and 1 − 3ℓ, so
//! a mesh whose element boundaries sit on those kinks is exact up to the solver tolerance.
//!
//! What a user writes:
//! * one [`Phase`] per arc of the trajectory: its dynamics, path constraints and running costs
//!   are expressions of an expression [`Graph`] (differentiated exactly by the transcription);
//!   variable bounds, the duration's bounds, the number of collocation points and a guess;
//! * [`PointFunction`]s for boundary and linkage conditions, reading states at the phase ends
//!   through [`VarRef`];
//! * the [`Ocp`] (phases, number of cost states, points, objective, scheme), transcribed once
//!   by [`Transcription::new`] and solved by [`solve_nlp`]; [`extract`] returns the
//!   trajectory per phase.
//!
//! Run it: `cargo run --release -p bf-optim --example bryson_denham`.

use bf_optim::OptimError;
use bf_optim::ipm::{Settings, Solution, Status, TerminationSettings};
use bf_optim::ocp::{
    Graph, NodeFunction, Objective, Ocp, Phase, PhaseGuess, PhaseTrajectory, PointFunction, Scheme,
    Transcription, VarRef, extract, solve_nlp,
};

/// The state bound ℓ.
pub const ELL: f64 = 1.0 / 9.0;

/// The closed-form optimum J* = 4 / (9ℓ).
pub fn exact_objective() -> f64 {
    4.0 / (9.0 * ELL)
}

/// "No bound" (the transcription treats |b| ≥ 1e19 as infinite).
const INF: f64 = 1e20;

/// The phase: graph variables 0 = x, 1 = v (states), 2 = u (control), 3 = T (duration);
/// ẋ = v, v̇ = u, one running cost ½u².
fn phase(points: usize, x0: f64, v0: f64) -> Phase {
    let mut g = Graph::new();
    let (v, u) = (g.var(1), g.var(2));
    let u2 = g.square(u);
    let half = g.constant(0.5);
    let cost = g.mul(half, u2);
    Phase {
        name: "arc".into(),
        node: NodeFunction {
            graph: g,
            x: vec![0, 1],
            a: vec![],
            u: vec![2],
            duration: 3,
            fixed: vec![],
            xdot: vec![v, u],
            path: vec![],
            path_bounds: vec![],
            costs: vec![cost],
        },
        x_bounds: vec![(-INF, ELL), (-INF, INF)],
        a_bounds: vec![],
        u_bounds: vec![(-INF, INF)],
        duration_bounds: (1.0, 1.0),
        points,
        guess: PhaseGuess::constant(vec![x0, v0], vec![], vec![0.0], 1.0),
        end_ramp: None,
    }
}

/// x(0) = 0, v(0) = 1, x(1) = 0, v(1) = −1, as one point function with four outputs.
fn boundary() -> PointFunction {
    let mut graph = Graph::new();
    let ends = [
        (VarRef::Initial { phase: 0, i: 0 }, 0.0),
        (VarRef::Initial { phase: 0, i: 1 }, 1.0),
        (VarRef::Final { phase: 0, i: 0 }, 0.0),
        (VarRef::Final { phase: 0, i: 1 }, -1.0),
    ];
    let (mut vars, mut outputs, mut bounds) = (Vec::new(), Vec::new(), Vec::new());
    for (k, (r, value)) in ends.into_iter().enumerate() {
        vars.push((k as u32, r));
        outputs.push(graph.var(k as u32));
        bounds.push((value, value));
    }
    PointFunction {
        name: "boundary".into(),
        graph,
        vars,
        fixed: vec![],
        outputs,
        bounds,
        row_names: Vec::new(),
    }
}

/// Solves the problem on `elements` equal Radau elements of 4 points each (the kinks at
/// 3ℓ = 1/3 and 2/3 are element boundaries when `elements` is a multiple of 3).
pub fn run(elements: usize) -> Result<(Solution, Vec<PhaseTrajectory>), OptimError> {
    let ocp = Ocp {
        phases: vec![phase(4 * elements, 0.0, 0.0)],
        n_costs: 1,
        params: vec![],
        points: vec![boundary()],
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme: Scheme::Radau { elements },
    };
    let tr = Transcription::new(&ocp)?;
    let settings = Settings {
        termination: TerminationSettings {
            tol: 1e-10,
            ..Default::default()
        },
        ..Settings::default()
    };
    let sol = solve_nlp(&tr, &settings, None, None)?;
    let traj = extract(&tr, &sol.x);
    Ok((sol, traj))
}

#[allow(dead_code)] // `main` is unused when a test includes this file as a module.
fn main() -> Result<(), OptimError> {
    let (sol, traj) = run(6)?;
    println!(
        "{:?} after {} iterations: J = {:.9} (closed form {:.9})",
        sol.status,
        sol.iterations,
        sol.objective,
        exact_objective()
    );
    let p = &traj[0];
    for t in [0.0, 0.2, 1.0 / 3.0, 0.5, 2.0 / 3.0, 0.8, 1.0] {
        let x = p.x_at(2.0 * t - 1.0);
        println!("t = {t:.3}: x = {:+.6}, v = {:+.6}", x[0], x[1]);
    }
    if sol.status != Status::Solved {
        std::process::exit(1);
    }
    Ok(())
}
