//! The solve policy of the solve pipeline: interior-point settings of a problem
//! ([`solver_settings`], [`warm_settings`], [`interpolated_warm_settings`]), a solve with its guess fallback ([`solve`]) and a
//! primal-dual warm-started solve ([`solve_warm`]).
//!
//! Both schemes use the solver's KKT settings: static dual regularization δ_c = 1e-9, which
//! the solver raises to 3e-8 within a solve where 2 × 2 (variable, constraint row) pivots show
//! plain AMD's bare −δ_c pivots to mislead the inertia test or a factor is inaccurate
//! (decision record 0002; the mesh sweep of every periodic problem in BENCHMARKS.md). A
//! failed solve is not repeated with other KKT settings.

use std::time::Instant;

use bf_optim::ipm::{
    BarrierSettings, ExperimentalSettings, ExtrapolationScope, IterationInfo, LineSearchSettings,
    LinearSolverSettings, Nlp, OutputSettings, Settings, Solution, Status, TerminationSettings,
    WarmStart,
};
use bf_optim::ocp::solve_nlp;
use bf_problem::{BuiltProblem, GuessKind, OcpSolution, ProblemSettings, solution_at};

use super::error::PipelineError;

/// Interior-point settings used by [`solve`].
pub fn solver_settings(s: &ProblemSettings) -> Settings {
    let base = s.ipm.clone().unwrap_or_else(|| Settings {
        termination: TerminationSettings {
            tol: 1e-8,
            ..Default::default()
        },
        ..Settings::default()
    });
    Settings {
        termination: TerminationSettings {
            max_iter: s.max_iter,
            ..base.termination
        },
        output: OutputSettings {
            print_level: s.print_level,
        },
        linear_solver: LinearSolverSettings {
            static_dual_regularization: s
                .dual_regularization
                .unwrap_or(base.linear_solver.static_dual_regularization),
            ..base.linear_solver
        },
        experimental: ExperimentalSettings {
            residual_ratio_with_solution: s.kkt_residual_ratio
                || base.experimental.residual_ratio_with_solution,
            extrapolation_scope: if s.extrapolate_every_barrier {
                ExtrapolationScope::EveryBarrier
            } else {
                base.experimental.extrapolation_scope
            },
            ..base.experimental
        },
        line_search: LineSearchSettings {
            max_curvature_extrapolation: s
                .curvature_extrapolation
                .unwrap_or(base.line_search.max_curvature_extrapolation),
            ..base.line_search
        },
        barrier: BarrierSettings {
            proximal_weight: s.proximal_weight.unwrap_or(base.barrier.proximal_weight),
            ..base.barrier
        },
        ..base
    }
}

type Callback<'a> = Option<&'a mut dyn FnMut(&IterationInfo) -> bool>;

fn reborrow<'a>(c: &'a mut Callback<'_>) -> Callback<'a> {
    match c {
        Some(f) => Some(&mut **f),
        None => None,
    }
}

/// Solves `p` directly. Initial point: an exact primal-dual warm start when `p.settings`
/// carries a warm-start solution of the same problem on the same mesh, else its interpolated
/// primal point (with [`interpolated_warm_settings`]) or the guess of
/// [`ProblemSettings::guess`]; with [`GuessKind::Auto`], a failed solve from the
/// docs/parameters.md guess is repeated from the geometric [`GuessKind::Contact`] guess.
/// `callback` sees every iteration (return `false` to stop). The library's default
/// [`Strategy`](crate::pipeline::strategy::Strategy) wraps this in a continuation.
pub fn solve(
    p: &BuiltProblem,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<OcpSolution, PipelineError> {
    solve_with_mu_max(p, INTERPOLATED_MU_INIT_MAX, callback)
}

/// [`solve`], with an interpolated warm start re-centred at μ₀ at most `mu_max` (instead of
/// [`INTERPOLATED_MU_INIT_MAX`]; the rule of [`interpolated_warm_settings`] otherwise).
pub fn solve_with_mu_max(
    p: &BuiltProblem,
    mu_max: f64,
    mut callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<OcpSolution, PipelineError> {
    let start = Instant::now();
    let mut stages = Vec::new();
    let mut iters = 0;
    let exact = p
        .settings
        .warm_start
        .as_ref()
        .and_then(|ws| exact_warm_start(p, ws));
    let settings = match (&p.settings.warm_start, exact) {
        (Some(_), Some(_)) => warm_settings(&p.settings),
        (Some(_), None) => {
            interpolated_warm_settings_below(&p.settings, start_violation(p), mu_max)
        }
        (None, _) => solver_settings(&p.settings),
    };
    let label = match warm_start_kind(p) {
        Some(kind) => kind.to_string(),
        None => format!("{} guess", crate::names::name(&p.settings.guess)),
    };
    let sol = solve_nlp(&p.nlp, &settings, exact, reborrow(&mut callback))?;
    iters += sol.iterations;
    stages.push((
        format!("{label}, eps {}", p.epsilon),
        sol.status,
        sol.iterations,
    ));
    let mut best = (sol, p);
    let fallback;
    if !best.0.status.is_success()
        && p.settings.warm_start.is_none()
        && p.settings.guess == GuessKind::Auto
    {
        let s1 = ProblemSettings {
            guess: GuessKind::Contact,
            ..p.settings.clone()
        };
        fallback = bf_problem::build(p.problem, &s1, &p.generated)?;
        let sol1 = solve_nlp(
            &fallback.nlp,
            &solver_settings(&p.settings),
            None,
            reborrow(&mut callback),
        )?;
        iters += sol1.iterations;
        stages.push((
            format!("Contact guess, eps {}", p.epsilon),
            sol1.status,
            sol1.iterations,
        ));
        best = (sol1, &fallback);
    }
    let (sol, pp) = best;
    let mut out = finish_solution(pp, &sol)?;
    out.iterations = iters;
    out.solve_seconds = start.elapsed().as_secs_f64();
    out.stages = stages;
    Ok(out)
}

/// Whether `a` is the better of two solves of one problem: successful with a finite objective
/// where `b` is not, or both so and `a` lower. The search keeps the better of a promotion's two
/// starts by it, and a refinement the better of a round and its solve again.
pub fn better_solve(a: &OcpSolution, b: &OcpSolution) -> bool {
    let ok = |s: &OcpSolution| s.status.is_success() && s.objective.is_finite();
    ok(a) && (!ok(b) || a.objective < b.objective)
}

/// Interior-point settings for a warm-started stage: a small initial μ and bound pushes, so
/// the iterates stay near the previous solution instead of re-centring (unless the caller set
/// its own [`ProblemSettings::ipm`]).
pub fn warm_settings(s: &ProblemSettings) -> Settings {
    let mut st = solver_settings(s);
    if s.ipm.is_none() {
        st.barrier.mu_init = 1e-4;
        st.barrier.warm_start_bound_push = 1e-6;
        st.barrier.warm_start_mult_bound_push = 1e-6;
    }
    st
}

/// Largest initial barrier parameter μ₀ of an interpolated (primal-only) warm start, the μ₀
/// of [`warm_settings`].
pub const INTERPOLATED_MU_INIT_MAX: f64 = 1e-4;

/// Interior-point settings for a warm start from an interpolated primal point only (no
/// multipliers: [`ProblemSettings::warm_start`] without a matching NLP vector, e.g. a
/// `solution.json` without its internal fields, or another mesh), given the largest
/// constraint violation `violation` of that point. Unless the caller set its own
/// [`ProblemSettings::ipm`]:
/// * μ₀ = clamp(`violation`, tol / 10, [`INTERPOLATED_MU_INIT_MAX`]): along the central path
///   the primal infeasibility and the barrier parameter fall together, so a start as feasible
///   as the end of a converged solve (the optimum itself re-loaded on its own mesh) begins
///   where that solve ended, instead of climbing back to μ = 1e-4 and descending again; a
///   start off by the change of mesh keeps the larger μ₀, which lets the iterates re-centre
///   (a small μ₀ there costs iterations);
/// * the primal point is pushed into its bounds by the warm-start push of [`warm_settings`]
///   rather than the cold 1e-2, which would move every active bound (a stick phase at its
///   minimum duration, a torque at its limit) off the optimum.
pub fn interpolated_warm_settings(s: &ProblemSettings, violation: f64) -> Settings {
    interpolated_warm_settings_below(s, violation, INTERPOLATED_MU_INIT_MAX)
}

/// [`interpolated_warm_settings`] with μ₀ at most `mu_max` instead of
/// [`INTERPOLATED_MU_INIT_MAX`] (and at least the floor tol / 10).
pub fn interpolated_warm_settings_below(
    s: &ProblemSettings,
    violation: f64,
    mu_max: f64,
) -> Settings {
    let mut st = warm_settings(s);
    if s.ipm.is_none() {
        let floor = 0.1 * st.termination.tol;
        let ceiling = mu_max.max(floor);
        st.barrier.mu_init = if violation.is_finite() {
            violation.clamp(floor, ceiling)
        } else {
            ceiling
        };
        st.barrier.bound_push = st.barrier.warm_start_bound_push;
        st.barrier.bound_frac = st.barrier.warm_start_bound_push;
    }
    st
}

/// The largest violation of the constraint bounds at the initial point of `p` (user units).
fn start_violation(p: &BuiltProblem) -> f64 {
    let n = Nlp::num_variables(&p.nlp);
    let m = Nlp::num_constraints(&p.nlp);
    let mut x = vec![0.0; n];
    Nlp::initial_point(&p.nlp, &mut x);
    let mut g = vec![0.0; m];
    Nlp::constraints(&p.nlp, &x, &mut g);
    let (mut lo, mut up) = (vec![0.0; m], vec![0.0; m]);
    Nlp::constraint_bounds(&p.nlp, &mut lo, &mut up);
    (0..m)
        .map(|i| (lo[i] - g[i]).max(g[i] - up[i]))
        .fold(
            0.0,
            |a: f64, v| if v.is_nan() { f64::NAN } else { a.max(v) },
        )
}

/// How [`solve`] starts `p` from its warm start, if it has one: `"exact warm start"` from
/// the file's primal–dual point ([`exact_warm_start`]), otherwise `"interpolated warm start"`
/// from its collocation data. The strategy table names a direct solve by it, so that a user
/// who edited the collocation data of a file that keeps its point sees they were not used.
pub(crate) fn warm_start_kind(p: &BuiltProblem) -> Option<&'static str> {
    let ws = p.settings.warm_start.as_ref()?;
    Some(if exact_warm_start(p, ws).is_some() {
        "exact warm start"
    } else {
        "interpolated warm start"
    })
}

/// The primal-dual point of `ws` if it belongs to the same problem on the same mesh (same
/// NLP layout), so that it can warm-start `p` exactly rather than by interpolation.
fn exact_warm_start<'a>(p: &BuiltProblem, ws: &'a OcpSolution) -> Option<&'a WarmStart> {
    let w = ws.nlp_warm.as_ref()?;
    let n = Nlp::num_variables(&p.nlp);
    let m = Nlp::num_constraints(&p.nlp);
    let same = ws.problem == p.name
        && ws.scheme == p.settings.scheme
        && ws.points == p.settings.points
        && ws.nlp_size == (n, m)
        && w.x.len() == n
        && w.lambda.len() == m
        && w.z_l.len() == n
        && w.z_u.len() == n
        && w.x.iter().all(|v| v.is_finite());
    same.then_some(w)
}

/// Largest number of Legendre–Gauss collocation points per phase (`optimize`'s module docs say
/// why).
pub const MAX_LG_POINTS: usize = 200;

/// Largest number of collocation points per phase with the Radau scheme (its elements' points
/// together): it bounds the memory of the NLP.
pub const MAX_RADAU_POINTS: usize = 5000;

/// Why a transcription of `points` collocation points per phase on `scheme` is not built: fewer
/// than 2 points, no Radau element, more than [`MAX_LG_POINTS`] Legendre–Gauss points, or more
/// than [`MAX_RADAU_POINTS`] Radau points per phase or `MAX_RADAU_DEGREE` per element. `None`
/// when it is built. The one rule for `optimize`'s options and for the mesh a solution file
/// records.
pub fn transcription_size_error(
    points: usize,
    scheme: bf_optim::ocp::problem::Scheme,
) -> Option<String> {
    use bf_optim::ocp::problem::Scheme;
    match scheme {
        _ if points < 2 => Some(format!(
            "{points} collocation points per phase; at least 2 are needed"
        )),
        Scheme::Lg if points > MAX_LG_POINTS => Some(format!(
            "at most {MAX_LG_POINTS} Legendre–Gauss points per phase are supported (the nodes' \
             interpolation weights overflow at about 900 points, and the dense differentiation \
             blocks grow as N²)"
        )),
        Scheme::Lg => None,
        Scheme::Radau { elements: 0 } => Some("Radau with 0 elements; at least 1 is needed".into()),
        Scheme::Radau { elements } => {
            let per_element = points.div_ceil(elements).max(2);
            let total = per_element.saturating_mul(elements);
            let max_degree = bf_optim::ocp::mesh::MAX_RADAU_DEGREE;
            (per_element > max_degree || total > MAX_RADAU_POINTS).then(|| {
                format!(
                    "{elements} Radau elements of {per_element} points are {total} points per \
                     phase; at most {MAX_RADAU_POINTS} per phase (and {max_degree} per element) \
                     are supported"
                )
            })
        }
    }
}

/// Errors naming the field unless the problem a solution records is one this program poses: a
/// catalogue `problem`, a mesh it builds (`points`, `scheme`: [`transcription_size_error`]), a
/// `scene_toml` that parses with its `scene_params`, and settings its problems accept (ε, the
/// cone and torque margins, the approach clearance, the stick-phase bound:
/// [`bf_problem::check_settings`]), and joint angles within the kernels' ±2²⁰ rad. Every reader
/// of a solution file applies it, so an edited
/// value is refused whether or not the command at hand uses it. A file that records no scene
/// text (written before it was recorded) is checked against its problem's built-in scene.
pub fn check_recorded_problem(sol: &OcpSolution) -> Result<(), String> {
    let problem: bf_problem::Problem = sol
        .problem
        .parse()
        .map_err(|e| format!("`problem` {:?}: {e}", sol.problem))?;
    if let Some(why) = transcription_size_error(sol.points, sol.scheme) {
        return Err(format!(
            "`points` {} on `scheme` {:?}: {why}",
            sol.points, sol.scheme
        ));
    }
    let (scene, _) = solution_scene(sol).map_err(|e| e.to_string())?;
    let settings = recorded_settings(sol, None);
    bf_problem::check_settings(problem, &settings, &scene).map_err(|e| e.to_string())?;
    // Every replay or warm start from a sample beyond the kernels' angle range would evaluate
    // NaN.
    for (table, samples) in [("nodes", &sol.nodes), ("dense", &sol.dense)] {
        for (k, q) in samples.q.iter().enumerate() {
            if let Some((i, v)) = scene.angle_beyond_range(q) {
                return Err(format!(
                    "`{table}.q{}` = {v:e} rad at sample {k} is beyond ±2²⁰ = ±{} rad, where \
                     the kernels' sine and cosine are not defined",
                    i + 1,
                    bf_codegen::spec::MAX_ANGLE
                ));
            }
        }
    }
    Ok(())
}

/// The optimum's scene parsed, with its name: the scene file's text the solution records
/// (`scene_toml`, with `scene_params`), or, in files that record none, the compiled scene it
/// names (`paper` for solutions that name none).
/// A solution on a scene of the user's own runs on interpreted kernels, like its `optimize`
/// and `simulate`.
pub fn solution_scene(sol: &OcpSolution) -> Result<(bf_codegen::Scene, String), PipelineError> {
    let name = if sol.scene.is_empty() {
        "paper"
    } else {
        &sol.scene
    };
    let fail = |why: String| PipelineError::Unrecomputable(why);
    if let Some(scene) =
        recorded_scene(sol).map_err(|e| fail(format!("the solution's scene `{name}`: {e}")))?
    {
        return Ok((scene, name.into()));
    }
    let text = bf_generated::scene_toml(name).ok_or_else(|| {
        fail(format!(
            "the solution records no scene text (`scene_toml`), and its scene `{name}` is not \
             a compiled scene"
        ))
    })?;
    let scene = bf_codegen::Scene::from_toml_str(text, name)
        .map_err(|e| fail(format!("the compiled scene `{name}`: {e}")))?;
    Ok((scene, name.into()))
}

/// The scene a solution file records: its `scene_toml` parsed, with its `scene_params` set;
/// `None` for a file that records no scene text (written before it was recorded). The error
/// names the field that does not parse or set.
pub fn recorded_scene(sol: &OcpSolution) -> Result<Option<bf_codegen::Scene>, PipelineError> {
    if sol.scene_toml.is_empty() {
        return Ok(None);
    }
    let fail = |why: String| PipelineError::Unrecomputable(why);
    let mut scene = bf_codegen::Scene::from_toml_str(&sol.scene_toml, &sol.scene)
        .map_err(|e| fail(format!("its `scene_toml`: {e}")))?;
    bf_model::registry::set_parameters(&mut scene, &sol.scene_params)
        .map_err(|e| fail(format!("its `scene_params`: {e}")))?;
    Ok(Some(scene))
}

/// The problem and settings a solution file records (problem, scene text and runtime
/// parameters, points, scheme, ε, the planned impact law, the cone and torque margins, the
/// approach clearance and the stick-phase bound; everything else the defaults, no mesh): its
/// scene is `None`
/// when the text and parameters are the problem's compiled scene's, so the problem is built
/// on the same kernels as a run without `--scene`. Errors when the file does not record them.
pub fn settings_of(
    sol: &OcpSolution,
) -> Result<(bf_problem::Problem, ProblemSettings), PipelineError> {
    let fail = |why: String| PipelineError::Unrecomputable(why);
    let problem: bf_problem::Problem = sol
        .problem
        .parse()
        .map_err(|e| fail(format!("problem {:?}: {e}", sol.problem)))?;
    if sol.scene_toml.is_empty() {
        return Err(fail("it records no scene text (`scene_toml`)".into()));
    }
    let compiled = sol.scene_params.is_empty()
        && bf_generated::scene_toml(problem.scene().as_str()) == Some(sol.scene_toml.as_str());
    let scene = if compiled { None } else { recorded_scene(sol)? };
    Ok((problem, recorded_settings(sol, scene)))
}

/// The settings `sol` records, on `scene` (`None`: the problem's compiled scene).
fn recorded_settings(sol: &OcpSolution, scene: Option<bf_codegen::Scene>) -> ProblemSettings {
    ProblemSettings {
        points: sol.points,
        scheme: sol.scheme,
        epsilon: Some(sol.epsilon),
        scene,
        impact_law: sol.impact_law,
        cone_margin: sol.cone_margin,
        impulse_cone: sol.impulse_cone,
        torque_margin: sol.torque_margin,
        approach_clearance: sol.approach_clearance,
        // The stick-phase bound is a bound of the problem (eq. 66), recorded with the
        // search's settings; a file without them was posed with the default.
        min_stick: sol
            .search_settings
            .as_ref()
            .map_or(ProblemSettings::default().min_stick, |s| s.min_stick),
        ..ProblemSettings::default()
    }
}

/// `sol`'s own problem rebuilt from what the solution records (problem, scene text and
/// runtime parameters, mesh, ε, the plan's law, margins and bounds, [`settings_of`]) and its
/// own primal-dual point ([`OcpSolution::nlp_warm`]) on it. Errors when the solution does not
/// record enough to rebuild its NLP or its point does not fit the rebuilt NLP.
pub fn own_problem(sol: &OcpSolution) -> Result<(BuiltProblem, &WarmStart), PipelineError> {
    let (problem, mut settings) = settings_of(sol)?;
    settings.mesh = sol.refinement.as_ref().map(|r| r.mesh.clone());
    let p = super::build(problem, &settings)?;
    let w = exact_warm_start(&p, sol).ok_or_else(|| {
        PipelineError::Unrecomputable(format!(
            "its primal-dual point (`nlp_warm` of the internals, {} variables) does not fit its \
             problem rebuilt on its mesh ({} variables)",
            sol.nlp_warm.as_ref().map_or(0, |w| w.x.len()),
            Nlp::num_variables(&p.nlp)
        ))
    })?;
    Ok((p, w))
}

/// `sol` recomputed at its own primal point on its own problem ([`own_problem`]): objective,
/// cost states and durations as that NLP gives them, whatever numbers the file states.
pub fn recompute_at_own_point(sol: &OcpSolution) -> Result<OcpSolution, PipelineError> {
    let (p, w) = own_problem(sol)?;
    Ok(solution_at(&p, &w.x, sol.status)?)
}

/// The largest constraint violation (in the NLP's own units, as [`recompute_at_own_point`]
/// gives it) of a point at which the solver with the settings of `s` ends with `status`: its
/// termination tests admit no point beyond it. `None` for a status that claims no feasible
/// point. A file whose success its own point exceeds was edited, or is another run's.
pub fn violation_allowed(s: &ProblemSettings, status: Status) -> Option<f64> {
    let t = solver_settings(s).termination;
    match status {
        Status::Solved => Some(t.constr_viol_tol),
        Status::Acceptable => Some(t.acceptable_constr_viol_tol),
        _ => None,
    }
}

/// `sol` solved again on its own problem, warm from its own primal-dual point
/// ([`own_problem`]): the optimum a solution file records, recomputed by this program in a few
/// iterations (a stored optimum presented without its search). The result keeps the file's
/// records of how it was found (strategy, search settings, scene, refinement); its
/// verification is the caller's.
pub fn resolve_at_own_point(
    sol: &OcpSolution,
) -> Result<(BuiltProblem, OcpSolution), PipelineError> {
    let (p, w) = own_problem(sol)?;
    let mut out = solve_warm(&p, w, None)?;
    out.strategy.clone_from(&sol.strategy);
    out.search_settings.clone_from(&sol.search_settings);
    out.scene_toml.clone_from(&sol.scene_toml);
    out.scene_params.clone_from(&sol.scene_params);
    out.refinement.clone_from(&sol.refinement);
    Ok((p, out))
}

/// Solves `p` from the primal-dual point `warm` (same NLP layout) with [`warm_settings`].
pub fn solve_warm(
    p: &BuiltProblem,
    warm: &WarmStart,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<OcpSolution, PipelineError> {
    let start = Instant::now();
    let sol = solve_nlp(&p.nlp, &warm_settings(&p.settings), Some(warm), callback)?;
    let mut out = finish_solution(p, &sol)?;
    out.iterations = sol.iterations;
    out.solve_seconds = start.elapsed().as_secs_f64();
    out.stages = vec![(
        format!("warm start, eps {}", p.epsilon),
        sol.status,
        sol.iterations,
    )];
    Ok(out)
}

/// Solves `p` from the primal-dual point `warm` (same NLP layout) re-centred at the barrier
/// parameter `mu_init`, with bound pushes of the same size (unless the caller set its own
/// [`ProblemSettings::ipm`]): a basin hop of the global search ([`super::global`]) starts
/// from a perturbed optimum, and a re-solve from a larger μ than [`warm_settings`]' 1e-4
/// lets the iterates leave the old optimum's active set (e.g. reach a neighbouring optimum
/// with a phase on its bound).
pub fn solve_recentred(
    p: &BuiltProblem,
    warm: &WarmStart,
    mu_init: f64,
) -> Result<OcpSolution, PipelineError> {
    let start = Instant::now();
    let mut st = warm_settings(&p.settings);
    if p.settings.ipm.is_none() {
        st.barrier.mu_init = mu_init;
        st.barrier.warm_start_bound_push = mu_init;
        st.barrier.warm_start_mult_bound_push = mu_init;
    }
    let sol = solve_nlp(&p.nlp, &st, Some(warm), None)?;
    let mut out = finish_solution(p, &sol)?;
    out.iterations = sol.iterations;
    out.solve_seconds = start.elapsed().as_secs_f64();
    out.stages = vec![(
        format!("re-centred warm start (mu {mu_init:e}), eps {}", p.epsilon),
        sol.status,
        sol.iterations,
    )];
    Ok(out)
}

/// The [`OcpSolution`] of an interior-point result, with its statistics and warm-start data.
fn finish_solution(p: &BuiltProblem, sol: &Solution) -> Result<OcpSolution, PipelineError> {
    let mut out = solution_at(p, &sol.x, sol.status)?;
    out.iterations = sol.iterations;
    out.constraint_violation = sol.constraint_violation;
    out.dual_infeasibility = sol.dual_infeasibility;
    out.timing = sol.timing;
    out.counters = sol.counters;
    out.nlp_warm = Some(WarmStart::from(sol));
    Ok(out)
}
