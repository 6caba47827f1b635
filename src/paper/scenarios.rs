//! The three optimal-control scenarios of the paper's Sect. 6.1 — `periodic-cot` (robotic
//! finger, COT objective eq. 61–63), `periodic-cot-human` (q₂, q₃ ≥ 0) and `periodic-qc`
//! (quadratic objective eq. 64–65) — solved, written to disk, plotted (counterparts of
//! Fig. 5–16) and checked against the paper's qualitative claims. A figure with a paper
//! counterpart says so in its title ("Fig. N counterpart") and its file name (`figN_…`, see
//! [`figure_stem`]); Fig. 11 compares two scenarios ([`fig11_compare_paths`]).
//!
//! Contact location is reported with the exact saturation (eq. 3) evaluated on the optimal
//! joint trajectory; the optimiser itself uses the smooth one (eq. 58–59), whose difference is
//! at most ε/2.

use crate::paper::claims::Facts;
use crate::pipeline::solution_io::write_solution;
use crate::pipeline::strategy::Strategy;
use anyhow::{Context, Result, anyhow};
use bf_codegen::spec::SceneId;
use bf_plot::paper::{Phases, TimeSeries};
use bf_plot::scene3d::{FingerPaths, NamedPath, View};
use bf_problem::solution::records::{StageRow, stage_table};
use bf_problem::{BuiltProblem, OcpSolution, Problem, ProblemSettings, QC_OMEGA_REF, Samples};
use std::fmt::Write as _;
use std::path::Path;

/// The scenarios of Sect. 6.1, in the paper's order: (problem name, short description).
pub const SCENARIOS: [(&str, &str); 3] = [
    ("periodic-cot", "COT, robotic finger (no joint limits)"),
    ("periodic-cot-human", "COT, human finger (q2, q3 ≥ 0)"),
    ("periodic-qc", "QC, ω_ref = (0, 0, 2.2) rad/s"),
];

/// The per-scenario figures, in report order: (file suffix, caption).
const SCENARIO_FIGURES: [(&str, &str); 5] = [
    ("paths", "finger path"),
    ("omega", "ball angular velocity"),
    ("distance", "distance h and contact point"),
    ("torques", "joint torques"),
    ("forces", "contact force"),
];

/// The paper figure a scenario figure corresponds to (Sect. 6.1): Fig. 5–9 for the robotic
/// COT solution, Fig. 10 for the human finger's path, Fig. 12–16 for the QC solution.
pub fn paper_figure(scenario: &str, fig: &str) -> Option<u32> {
    let k = SCENARIO_FIGURES.iter().position(|(f, _)| *f == fig)? as u32;
    match scenario {
        "periodic-cot" => Some(5 + k),
        "periodic-cot-human" if fig == "paths" => Some(10),
        "periodic-qc" => Some(12 + k),
        _ => None,
    }
}

/// File stem (under `figures/`) of a scenario figure: `fig<N>_<scenario>_<fig>` when it has a
/// paper counterpart, `<scenario>_<fig>` otherwise.
pub fn figure_stem(scenario: &str, fig: &str) -> String {
    match paper_figure(scenario, fig) {
        Some(n) => format!("fig{n}_{scenario}_{fig}"),
        None => format!("{scenario}_{fig}"),
    }
}

/// Title of a scenario figure, starting with "Fig. N counterpart" when it has one; `variant`
/// (see [`variant_note`]) follows the scenario's name.
fn figure_title(scenario: &str, variant: &str, fig: &str, caption: &str) -> String {
    match paper_figure(scenario, fig) {
        Some(n) => format!("Fig. {n} counterpart: {scenario}{variant}: {caption}"),
        None => format!("{scenario}{variant}: {caption}"),
    }
}

/// What sets a variant of a scenario apart from the scenario as the report presents it (its
/// figures would otherwise carry the same titles): the impulse cone imposed, or another
/// minimum stick duration; empty for the scenario itself.
fn variant_note(settings: &ProblemSettings) -> String {
    let plain = ProblemSettings::default();
    let mut parts = Vec::new();
    if settings.impulse_cone && !plain.impulse_cone {
        parts.push("impulse cone imposed".to_string());
    }
    if settings.min_stick != plain.min_stick {
        parts.push(format!("stick ≥ {} s", settings.min_stick));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join(", "))
    }
}

/// Per-scenario figures of merit (the results table of the report).
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// Problem name.
    pub name: String,
    /// The solution.
    pub solution: OcpSolution,
    /// max |τ_i| over the collocation nodes and the dense samples (N m).
    pub max_tau: f64,
    /// Distance of the exact contact point from the fingertip during contact, |sat(α)| (m):
    /// (min, mean, max).
    pub contact_from_tip: (f64, f64, f64),
    /// Share of the contact (stick) samples with ‖λ_∥‖ ≥ 0.99 μ_s λ_n (on the friction-cone
    /// boundary).
    pub cone_share: f64,
    /// The bounds of the problem the solution sits on ([`crate::pipeline::bounds::active_bounds`]).
    pub active: Vec<crate::pipeline::bounds::ActiveBound>,
}

/// Samples of the collocation polynomials per period for the path figures (Fig. 5, 10, 11, 12):
/// with the 100 dense samples per phase of [`Samples`], a 9.6 s COT period was drawn from
/// samples 0.1 s apart in its long free phases, visibly jagged.
pub const PATH_SAMPLES_PER_PERIOD: usize = 1200;

/// Least samples of one phase in the path figures (a 0.01 s stick phase still gets a smooth
/// contact path).
pub const PATH_SAMPLES_PER_PHASE: usize = 60;

/// Normalised times τ ∈ [−1, 1] at which to evaluate each phase's collocation polynomials for
/// the path figures: equally spaced, [`PATH_SAMPLES_PER_PERIOD`] over the period shared out by
/// duration, at least [`PATH_SAMPLES_PER_PHASE`] per phase, both ends included.
pub fn path_taus(durations: &[f64]) -> Vec<Vec<f64>> {
    let period: f64 = durations.iter().filter(|d| d.is_finite()).sum();
    durations
        .iter()
        .map(|&d| {
            let share = if period > 0.0 && d.is_finite() {
                // Intervals, not samples: steps of at most period / PATH_SAMPLES_PER_PERIOD.
                (PATH_SAMPLES_PER_PERIOD as f64 * d / period).ceil() as usize + 1
            } else {
                0
            };
            let n = share.max(PATH_SAMPLES_PER_PHASE);
            (0..n)
                .map(|k| -1.0 + 2.0 * k as f64 / (n - 1) as f64)
                .collect()
        })
        .collect()
}

/// One state on the collocation polynomials: (phase, q, q̇, ω).
type PathState = (usize, Vec<f64>, Vec<f64>, Vec<f64>);

/// The states of `sol` at [`path_taus`], from its per-phase collocation data (`raw`); empty
/// when the solution carries none (then the callers fall back to the dense samples).
fn path_states(sol: &OcpSolution) -> Vec<PathState> {
    let nq = sol.dense.q.first().map_or(0, |q| q.len());
    let durations: Vec<f64> = sol.raw.iter().map(|tr| tr.duration).collect();
    let mut out = Vec::new();
    for ((pi, tr), taus) in sol.raw.iter().enumerate().zip(path_taus(&durations)) {
        for tau in taus {
            let x = tr.x_at(tau);
            if x.len() < 2 * nq + 3 {
                return Vec::new();
            }
            out.push((
                pi,
                x[..nq].to_vec(),
                x[nq..2 * nq].to_vec(),
                x[2 * nq..2 * nq + 3].to_vec(),
            ));
        }
    }
    out
}

/// The path-figure states of `sol`: [`path_states`], or its dense samples when it has no
/// collocation data.
fn path_states_or_dense(sol: &OcpSolution) -> Vec<PathState> {
    let s = path_states(sol);
    if !s.is_empty() {
        return s;
    }
    let d = &sol.dense;
    (0..d.t.len())
        .map(|i| {
            (
                d.phase.get(i).copied().unwrap_or(0),
                d.q[i].clone(),
                d.qd[i].clone(),
                d.omega[i].clone(),
            )
        })
        .collect()
}

fn phase_is_stick(sol: &OcpSolution, phase: usize) -> bool {
    sol.modes
        .get(phase)
        .is_some_and(|m| *m == bf_problem::node::PhaseMode::Stick)
}

/// Geometry evaluated by the compiled kernels of the problem's scene at one sample.
struct Geometry {
    frames: Vec<[f64; 3]>,
    p_c: [f64; 3],
    n: [f64; 3],
    h: f64,
    sat_alpha: f64,
}

macro_rules! geometry_of {
    ($m:ident, $q:expr, $qd:expr, $omega:expr) => {{
        use bf_generated::$m as k;
        let p = &k::PARAM_DEFAULTS;
        let q: [f64; 3] = [$q[0], $q[1], $q[2]];
        let qd: [f64; 3] = [$qd[0], $qd[1], $qd[2]];
        let omega: [f64; 3] = [$omega[0], $omega[1], $omega[2]];
        let mut pos = [[0.0; 3]; 3];
        let mut rot = [[[0.0; 3]; 3]; 3];
        k::frames(&q, p, &mut pos, &mut rot);
        let mut c = k::Contact::default();
        k::contact(&q, &qd, &omega, p, &mut c);
        (pos, c.p_c, c.n, c.h, c.sat_alpha)
    }};
}

fn geometry(scene: &SceneId, base: [f64; 3], q: &[f64], qd: &[f64], omega: &[f64]) -> Geometry {
    let (pos, p_c, n, h, sat_alpha) = if *scene == SceneId::HUMAN {
        geometry_of!(human, q, qd, omega)
    } else {
        geometry_of!(paper, q, qd, omega)
    };
    let mut frames = vec![base];
    frames.extend_from_slice(&pos);
    Geometry {
        frames,
        p_c,
        n,
        h,
        sat_alpha,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn components(rows: &[Vec<f64>], names: &[&str], t: &[f64]) -> TimeSeries {
    TimeSeries {
        t: t.to_vec(),
        values: (0..names.len())
            .map(|k| {
                rows.iter()
                    .map(|r| r.get(k).copied().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect(),
        names: names.iter().map(|s| s.to_string()).collect(),
    }
}

/// Phase switching markers and the contact interval of a free–stick–free solution.
pub fn phases_of(sol: &OcpSolution) -> Phases {
    let mut t = 0.0;
    let mut switches = Vec::new();
    let mut contact = Vec::new();
    for (i, d) in sol.phase_durations.iter().enumerate() {
        let start = t;
        t += d;
        if i + 1 < sol.phase_durations.len() {
            let label = match (sol.modes.get(i), sol.modes.get(i + 1)) {
                (Some(a), Some(b))
                    if *a == bf_problem::node::PhaseMode::Free
                        && *b == bf_problem::node::PhaseMode::Stick =>
                {
                    "impact"
                }
                (Some(a), _) if *a == bf_problem::node::PhaseMode::Stick => "lift-off",
                _ => "switch",
            };
            switches.push((t, label.to_string()));
        }
        if sol
            .modes
            .get(i)
            .is_some_and(|m| *m == bf_problem::node::PhaseMode::Stick)
        {
            contact.push((start, t));
        }
    }
    Phases { switches, contact }
}

fn is_stick(sol: &OcpSolution, samples: &Samples, i: usize) -> bool {
    samples
        .phase
        .get(i)
        .and_then(|&p| sol.modes.get(p))
        .is_some_and(|m| *m == bf_problem::node::PhaseMode::Stick)
}

/// How a scenario is solved: the problem, its settings and the strategy give the built problem
/// and its solution (the CLI passes a solve behind a progress spinner).
pub type Solver<'a> =
    &'a dyn Fn(Problem, ProblemSettings, Strategy) -> Result<(BuiltProblem, OcpSolution)>;

/// Solve one scenario, write `dir/<name>/{solution.json, torques.csv}` and its figures into
/// `dir/figures`, and compute the figures of merit.
pub fn run_scenario(
    name: &str,
    settings: ProblemSettings,
    strategy: Strategy,
    dir: &Path,
    mu_s: f64,
    solve: Solver<'_>,
) -> Result<ScenarioResult> {
    let problem: Problem = name.parse().map_err(|e| anyhow!("{e}"))?;
    let variant = variant_note(&settings);
    let (problem, mut sol) = solve(problem, settings, strategy)?;
    // Re-integration of every phase with the optimal torques: stored in solution.json and
    // shown in the results table; an optimum that fails it (or cannot be re-integrated) does
    // not stop the run here, but marks the whole set FAILED at its end (`commands::paper`).
    sol.verification = crate::pipeline::verify::verify(&problem, &sol, 1e-10).ok();
    let active = crate::pipeline::bounds::active_bounds(&problem.ocp, &sol);
    sol.active_bounds = Some(active.clone());
    write_solution(&sol, &dir.join(name))?;
    let scene = problem.problem.scene();
    let base = problem.scene.base_translation();
    let d = &sol.dense;
    let phases = phases_of(&sol);
    let figs = dir.join("figures");
    let stem = |s: &str| figs.join(figure_stem(name, s));
    let title = |s: &str| {
        let caption = SCENARIO_FIGURES
            .iter()
            .find(|(f, _)| *f == s)
            .map_or(s, |(_, c)| *c);
        figure_title(name, &variant, s, caption)
    };

    // Geometry along the dense samples.
    let geo: Vec<Geometry> = (0..d.t.len())
        .map(|i| geometry(&scene, base, &d.q[i], &d.qd[i], &d.omega[i]))
        .collect();
    let mut lambda_n = Vec::new();
    let mut lambda_t = Vec::new();
    let mut from_tip = Vec::new();
    let mut cone = (0usize, 0usize);
    let mut loc = (f64::INFINITY, 0.0, 0.0f64, 0usize);
    for (i, g) in geo.iter().enumerate() {
        let lam = &d.lambda[i];
        let ln = dot(lam, &g.n);
        let lt = (dot(lam, lam) - ln * ln).max(0.0).sqrt();
        lambda_n.push(ln);
        lambda_t.push(lt);
        let dist = g.sat_alpha.abs();
        from_tip.push(dist);
        if is_stick(&sol, d, i) {
            cone.1 += 1;
            if lt >= 0.99 * mu_s * ln && ln > 0.0 {
                cone.0 += 1;
            }
            loc = (loc.0.min(dist), loc.1 + dist, loc.2.max(dist), loc.3 + 1);
        }
        let _ = g.h;
    }
    let max_tau = max_abs_tau(&sol);

    let omega = components(&d.omega, &["ω_x", "ω_y", "ω_z"], &d.t);
    let omega_fig = if name == "periodic-qc" {
        bf_plot::paper::fig_ball_omega_ref(
            &title("omega"),
            &omega,
            &phases,
            &[("ω_ref,z".into(), QC_OMEGA_REF[2])],
        )?
    } else {
        bf_plot::paper::fig_ball_omega(&title("omega"), &omega, &phases)?
    };
    bf_plot::render(&omega_fig, stem("omega"))?;
    bf_plot::render_panels(
        &bf_plot::paper::fig_distance(&title("distance"), &d.t, &d.h, &from_tip, &phases)?,
        stem("distance"),
    )?;
    let tau = components(&d.tau, &["τ1", "τ2", "τ3"], &d.t);
    // Forces only where the samples are in a stick phase: the free phase's sample at the
    // impact or lift-off time has λ = 0 and would draw a drop to zero at the window's edges.
    let any_stick = (0..d.t.len()).any(|i| is_stick(&sol, d, i));
    let in_stick = |v: &[f64]| -> Vec<f64> {
        if !any_stick {
            return v.to_vec();
        }
        v.iter()
            .enumerate()
            .map(|(i, x)| if is_stick(&sol, d, i) { *x } else { f64::NAN })
            .collect()
    };
    bf_plot::render_panels(
        &bf_plot::paper::fig_torques(&title("torques"), &tau, Some(1.0), &phases)?,
        stem("torques"),
    )?;
    bf_plot::render(
        &bf_plot::paper::fig_contact_forces(
            &title("forces"),
            &d.t,
            &in_stick(&lambda_n),
            &in_stick(&lambda_t),
            mu_s,
            &phases,
        )?,
        stem("forces"),
    )?;
    let snaps = 6usize;
    // The paths from the collocation polynomials, finely sampled (PATH_SAMPLES_PER_PERIOD).
    let path: Vec<(bool, Geometry)> = path_states_or_dense(&sol)
        .iter()
        .map(|(p, q, qd, w)| (phase_is_stick(&sol, *p), geometry(&scene, base, q, qd, w)))
        .collect();
    let paths = FingerPaths {
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        snapshots: (0..snaps)
            .map(|k| geo[k * (geo.len() - 1) / (snaps - 1)].frames.clone())
            .collect(),
        tip_path: path.iter().map(|(_, g)| g.frames[3]).collect(),
        contact_path: path
            .iter()
            .map(|(stick, g)| if *stick { g.p_c } else { [f64::NAN; 3] })
            .collect(),
    };
    bf_plot::render_panels(
        &bf_plot::scene3d::fig_finger_paths(
            &title("paths"),
            &paths,
            &[View::FrontXZ, View::SideYZ, View::Iso],
        )?,
        stem("paths"),
    )?;
    animation_from(name, &sol, &geo, dir)?;
    let mean = if loc.3 > 0 {
        loc.1 / loc.3 as f64
    } else {
        f64::NAN
    };
    Ok(ScenarioResult {
        name: name.to_string(),
        active,
        max_tau,
        contact_from_tip: (loc.0, mean, loc.2),
        cone_share: if cone.1 > 0 {
            cone.0 as f64 / cone.1 as f64
        } else {
            f64::NAN
        },
        solution: sol,
    })
}

/// Writes `dir/animation_<name>.html` of `sol` from its geometry `geo` at the dense samples.
fn animation_from(name: &str, sol: &OcpSolution, geo: &[Geometry], dir: &Path) -> Result<()> {
    let frames = animation_frames(sol, &sol.dense, geo);
    bf_plot::anim::write_animation_html(
        &bf_plot::anim::Animation {
            title: format!("{name}: one period"),
            ball_center: [0.0; 3],
            ball_radius: 1.0,
            frames,
        },
        dir.join(format!("animation_{name}.html")),
    )?;
    Ok(())
}

/// Writes `dir/animation_<name>.html`, the self-contained 3-D animation of one period of
/// `sol`, a solution of `built` (a scenario's figures write theirs in [`run_scenario`]; the
/// plans for the plant use this).
pub fn write_animation(
    name: &str,
    built: &BuiltProblem,
    sol: &OcpSolution,
    dir: &Path,
) -> Result<()> {
    let scene = built.problem.scene();
    let base = built.scene.base_translation();
    let d = &sol.dense;
    let geo: Vec<Geometry> = (0..d.t.len())
        .map(|i| geometry(&scene, base, &d.q[i], &d.qd[i], &d.omega[i]))
        .collect();
    animation_from(name, sol, &geo, dir)
}

/// Base translation of a compiled-in scene (from bf-generated's registry).
fn scene_base(scene: &SceneId) -> Result<[f64; 3]> {
    let text = bf_generated::scene_toml(scene.as_str())
        .ok_or_else(|| anyhow!("scene `{scene}` is not compiled in"))?;
    Ok(bf_codegen::Scene::from_toml_str(text, scene.as_str())?.base_translation())
}

/// Path of the finger's closest point to the ball, p_c (eq. 3 with the exact saturation), over
/// one period of a solution, on its collocation polynomials ([`path_taus`]).
fn closest_point_path(name: &str, sol: &OcpSolution) -> Result<Vec<[f64; 3]>> {
    let problem: Problem = name.parse().map_err(|e| anyhow!("{e}"))?;
    let scene = problem.scene();
    let base = scene_base(&scene)?;
    Ok(path_states_or_dense(sol)
        .iter()
        .map(|(_, q, qd, w)| geometry(&scene, base, q, qd, w).p_c)
        .collect())
}

/// Fig. 11 counterpart: the closest-point paths of the robotic (`periodic-cot`) and the human
/// (`periodic-cot-human`) finger around the ball, written to `dir/figures/fig11_compare_paths`.
/// Returns the report paragraph, or `None` when either scenario has no solution.
pub fn fig11_compare_paths(dir: &Path, results: &[ScenarioResult]) -> Result<Option<String>> {
    let get = |n: &str| results.iter().find(|r| r.name == n);
    let (Some(robot), Some(human)) = (get("periodic-cot"), get("periodic-cot-human")) else {
        return Ok(None);
    };
    let paths = [
        NamedPath {
            name: "robotic finger (periodic-cot): closest point".into(),
            points: closest_point_path(&robot.name, &robot.solution)?,
        },
        NamedPath {
            name: "human finger (periodic-cot-human): closest point".into(),
            points: closest_point_path(&human.name, &human.solution)?,
        },
    ];
    let fig = bf_plot::scene3d::fig_compare_paths(
        "Fig. 11 counterpart: closest-point paths of the robotic and the human finger (COT)",
        [0.0; 3],
        1.0,
        &paths,
        &[View::FrontXZ, View::SideYZ, View::Iso],
    )?;
    bf_plot::render_panels(&fig, dir.join("figures").join("fig11_compare_paths"))?;
    Ok(Some(
        "### Robotic vs human finger (Fig. 11)\n\n\
         ![Fig. 11 counterpart: closest-point paths](figures/fig11_compare_paths.svg)\n"
            .to_string(),
    ))
}

/// Rotation matrix exp(S(w)) (Rodrigues), for integrating the ball orientation Ṙ = S(ω) R.
pub fn rodrigues(w: [f64; 3]) -> [[f64; 3]; 3] {
    let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let (a, b) = if th < 1e-8 {
        (1.0 - th * th / 6.0, 0.5 - th * th / 24.0)
    } else {
        (libm::sin(th) / th, (1.0 - libm::cos(th)) / (th * th))
    };
    let k = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let k2: f64 = (0..3).map(|l| k[i][l] * k[l][j]).sum();
            r[i][j] = if i == j { 1.0 } else { 0.0 } + a * k[i][j] + b * k2;
        }
    }
    r
}

fn matmul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|l| a[i][l] * b[l][j]).sum();
        }
    }
    c
}

/// Animation frames over one period: finger frame origins, the ball orientation integrated
/// from ω with the midpoint rule, and the contact point during contact.
fn animation_frames(
    sol: &OcpSolution,
    d: &Samples,
    geo: &[Geometry],
) -> Vec<bf_plot::anim::AnimFrame> {
    let mut rot = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut out = Vec::with_capacity(d.t.len());
    for i in 0..d.t.len() {
        if i > 0 {
            let dt = d.t[i] - d.t[i - 1];
            let w: [f64; 3] =
                std::array::from_fn(|k| 0.5 * (d.omega[i][k] + d.omega[i - 1][k]) * dt);
            rot = matmul(&rodrigues(w), &rot);
        }
        out.push(bf_plot::anim::AnimFrame {
            t: d.t[i],
            joints: geo[i].frames.clone(),
            ball_rotation: rot,
            contact: is_stick(sol, d, i).then_some(geo[i].p_c),
        });
    }
    out
}

/// The results table and the per-claim comparison with Sect. 6.1, as markdown.
pub fn results_markdown(results: &[ScenarioResult]) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "| scenario | status | objective φ | period (s) | phase durations (s) | mean ω (rad/s) | max abs τ (N m) | contact distance from tip, min/mean/max (m) | contact on the friction-cone boundary | re-integration defect | verified | mesh: points (elements) per phase | strategy | iterations | solve time (s) |"
    )?;
    writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )?;
    for r in results {
        let o = &r.solution;
        writeln!(
            s,
            "| {} | {} | {:.5e} | {:.4} | {} | ({:.3}, {:.3}, {:.3}) | {:.3} | {:.3} / {:.3} / {:.3} | {:.0} % | {} | {} | {} | {} | {} | {:.2} |",
            r.name,
            crate::names::name(&o.status),
            o.objective,
            o.period,
            o.phase_durations
                .iter()
                .map(|d| format!("{d:.3}"))
                .collect::<Vec<_>>()
                .join(", "),
            o.mean_omega[0],
            o.mean_omega[1],
            o.mean_omega[2],
            r.max_tau,
            r.contact_from_tip.0,
            r.contact_from_tip.1,
            r.contact_from_tip.2,
            100.0 * r.cone_share,
            o.verification
                .as_ref()
                .map_or("not verified".into(), |v| format!("{:.1e}", v.max_defect)),
            if crate::pipeline::verify::is_verified(o) {
                "yes"
            } else {
                "**no**"
            },
            mesh_cell(o),
            o.strategy
                .as_ref()
                .map_or("direct".into(), |st| st.strategy.to_string()),
            o.iterations,
            o.solve_seconds
        )?;
    }
    writeln!(s, "\n{}", active_bounds_markdown(results))?;
    writeln!(s, "{}", tolerances_markdown(results))?;
    let facts: Vec<Facts> = results.iter().map(facts_of).collect();
    writeln!(s, "### Claims of Sect. 6.1\n")?;
    writeln!(
        s,
        "{}",
        crate::paper::claims::markdown(&crate::paper::claims::claims(&facts, QC_OMEGA_REF[2]))
    )?;
    Ok(s)
}

/// The mesh an optimum was solved on: the refined mesh of its hp refinement where it has one
/// (the problem's mesh otherwise), as collocation points (elements) per phase.
pub fn mesh_cell(o: &bf_problem::OcpSolution) -> String {
    let per_phase: Vec<String> = match &o.refinement {
        Some(r) if !r.mesh.is_empty() => r
            .mesh
            .iter()
            .map(|m| format!("{} ({})", m.degrees.iter().sum::<usize>(), m.degrees.len()))
            .collect(),
        _ => {
            // The problem's own mesh, as the transcription builds it from `--points` (a
            // Radau element count that does not divide the points rounds each element up);
            // Legendre–Gauss: one element of `points`.
            let (points, elements) = match bf_optim::ocp::MeshSpec::from_scheme(o.scheme, o.points)
            {
                Ok(spec) => (spec.degrees.iter().sum(), spec.degrees.len()),
                Err(_) => (o.points, 1),
            };
            vec![format!("{points} ({elements})"); o.phase_durations.len()]
        }
    };
    per_phase.join(", ")
}

/// What the claims need of a scenario result.
fn facts_of(r: &ScenarioResult) -> Facts {
    Facts {
        name: r.name.clone(),
        verified: crate::pipeline::verify::is_verified(&r.solution),
        objective: r.solution.objective,
        period: r.solution.period,
        mean_omega_z: r.solution.mean_omega[2],
        cone_share: r.cone_share,
        stick_duration: r.solution.stick_duration().unwrap_or(f64::NAN),
        from_tip: r.contact_from_tip,
        active: r.active.clone(),
    }
}

/// The bounds each reported optimum sits on, one list per scenario.
pub fn active_bounds_markdown(results: &[ScenarioResult]) -> String {
    let mut s = String::from(
        "Active bounds (phase durations, the period, torque and joint limits at the collocation \
         nodes; a value within 1e-5 + 1e-4·|bound| of its bound):\n\n",
    );
    for r in results {
        let list = if r.active.is_empty() {
            "none".to_string()
        } else {
            r.active
                .iter()
                .map(|a| a.describe())
                .collect::<Vec<_>>()
                .join("; ")
        };
        s.push_str(&format!("- `{}`: {list}\n", r.name));
    }
    s
}

/// Penetration and friction-cone margins of each verified re-integration against their
/// allowances, as the verification's verdict judges them: the "within" cells are
/// [`crate::pipeline::verify::penetration_failure`] and the worst stick phase of
/// [`crate::pipeline::verify::worst_cone_margin`] (whose allowance uses the max λ_n and μ_s of
/// the record), so the table and the `verified` column cannot disagree.
pub fn tolerances_markdown(results: &[ScenarioResult]) -> String {
    use crate::pipeline::verify::{
        CONE_ROUNDING, CONE_TOLERANCE, NEAR_BALL, PENETRATION_TOLERANCE, VERIFIED_DEFECT,
        penetration_failure, worst_cone_margin,
    };
    let mut s = format!(
        "Tolerances of \"verified\": re-integration defect ≤ {VERIFIED_DEFECT:e}; along the \
         re-integrated free phases, penetration min h ≥ −{PENETRATION_TOLERANCE:e} r, r the \
         ball's radius (the problem's own allowance at touch-down and release), and within \
         {NEAR_BALL:e} r of the ball the exact contact distance (the plant's) within the same \
         allowance of the smoothed one (the smoothing column, decision record 0089); along the re-integrated stick \
         phases, friction-cone margin min σ ≥ −({CONE_TOLERANCE} μ_s + {CONE_ROUNDING:e}) max λ_n of the phase \
         (σ = μ_s λ_n − ‖λ_∥‖, eq. 18; the optimum satisfies σ ≥ 0 at its collocation nodes \
         only). All of them decide the verdict; the first \"within\" covers min h and the \
         smoothing, the cone columns show the stick phase with the lowest margin relative to \
         its allowance.\n\n\
         | scenario | min h (m) | smoothing (m) | within | phase | min σ (N) | −({CONE_TOLERANCE} μ_s + {CONE_ROUNDING:e}) max λ_n (N) | within |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for r in results {
        let Some(v) = &r.solution.verification else {
            s.push_str(&format!("| {} | not verified | | | | | | |\n", r.name));
            continue;
        };
        let h = v
            .phases
            .iter()
            .filter_map(|p| p.min_h)
            .fold(f64::INFINITY, f64::min);
        let smoothing = v
            .phases
            .iter()
            .filter_map(|p| p.smoothing_error)
            .fold(f64::NEG_INFINITY, f64::max);
        let yes = |ok: bool| if ok { "yes" } else { "**no**" };
        let smoothing = if smoothing.is_finite() {
            format!("{smoothing:.2e}")
        } else {
            "—".to_string()
        };
        let h_cells = if h.is_finite() {
            format!(
                "{h:.2e} | {smoothing} | {}",
                yes(penetration_failure(v).is_none())
            )
        } else {
            format!("— | {smoothing} | —")
        };
        let cone_cells = match worst_cone_margin(v) {
            Some(m) => format!(
                "{} | {:.2e} | {:.2e} | {}",
                m.phase + 1,
                m.min_sigma,
                -m.allowance,
                yes(m.within())
            ),
            None => "— | — | — | —".to_string(),
        };
        s.push_str(&format!("| {} | {h_cells} | {cone_cells} |\n", r.name));
    }
    s
}

/// The solve stages of `sol` as the report shows them: the strategy's summary, the stages
/// of its kept chain and the verification refinements of that chain
/// (`StrategyReport::kept_rows`), then the rounds of the hp refinement of its mesh
/// (`solution.json`'s `refinement.history`: indented where they are one of those
/// refinements, whose line counts their iterations (`RefineReport::stage` names it); marked
/// as the origin's where the winner inherited the mesh from another candidate), and last the
/// optimum the results
/// table reports: where `resolved`, the
/// solve of the stored optimum from its own point in this run, otherwise a line of its own
/// only where it differs from the line before. `None` for a solution without a strategy
/// record.
pub fn solve_stages(sol: &OcpSolution, resolved: bool) -> Option<String> {
    let st = sol.strategy.as_ref()?;
    let mut rows = st.kept_rows();
    let chain = st.chosen;
    let mut last = rows.last().map(|r| r.objective);
    // Under a refinement's own line its rounds are its parts, indented so that no one sums
    // them twice. A winner that a hop or the polish found on the mesh of its origin carries
    // the rounds of the origin's refinement, which no line of its own chain counts; rounds
    // of a refinement the strategy did not record (`optimize --refine`) are no line's parts.
    let source = sol
        .refinement
        .as_ref()
        .and_then(|r| r.stage.as_deref())
        .and_then(|stage| st.refinements.iter().rev().find(|r| r.stage == stage));
    let own = source.is_some_and(|r| Some(r.chain) == chain);
    let indent = if own { "  " } else { "" };
    let origin = if source.is_some() && !own {
        "the mesh's origin's "
    } else {
        ""
    };
    let row = |stage: String, status, objective, period, iterations, seconds| StageRow {
        kept: true,
        chain,
        stage,
        status,
        objective,
        period,
        iterations,
        seconds,
    };
    if let Some(refinement) = &sol.refinement {
        let what = match refinement.criterion {
            bf_problem::solution::records::RefineCriterion::Estimate => "error estimate",
            bf_problem::solution::records::RefineCriterion::Reintegration { .. } => "defect",
        };
        for r in &refinement.history {
            let points: Vec<String> = r.points.iter().map(usize::to_string).collect();
            rows.push(row(
                format!(
                    "{indent}{origin}hp round {}: {} points, {what} {:.1e}",
                    r.round,
                    points.join("/"),
                    r.max_error
                ),
                r.status,
                r.objective,
                None,
                r.iterations,
                r.seconds,
            ));
            last = Some(r.objective);
        }
    }
    if resolved || last.is_none_or(|o| o.to_bits() != sol.objective.to_bits()) {
        let stage = if resolved {
            "stored optimum solved again here from its own point"
        } else {
            "reported optimum"
        };
        rows.push(row(
            stage.to_string(),
            sol.status,
            sol.objective,
            Some(sol.period),
            sol.iterations,
            sol.solve_seconds,
        ));
    }
    Some(format!("{}\n{}", st.summary(), stage_table(&rows)))
}

/// Figures of one scenario as markdown image links (relative to the report).
pub fn figures_markdown(name: &str) -> String {
    let mut s: String = SCENARIO_FIGURES
        .iter()
        .map(|(f, caption)| {
            let alt = match paper_figure(name, f) {
                Some(n) => format!("Fig. {n} counterpart: {name} {caption}"),
                None => format!("{name} {caption}"),
            };
            format!("![{alt}](figures/{}.svg)\n\n", figure_stem(name, f))
        })
        .collect();
    s.push_str(&format!(
        "Animation of one period (self-contained HTML): [animation_{name}.html](animation_{name}.html)\n"
    ));
    s
}

/// Run every scenario; one that fails does not stop the others: it is returned as a line
/// "`name` failed: why" beside the results.
pub fn run_all(
    dir: &Path,
    quick: bool,
    mu_s: f64,
    solve: Solver<'_>,
) -> Result<(Vec<ScenarioResult>, Vec<String>)> {
    let mut results = Vec::new();
    let mut failures = Vec::new();
    for (name, _) in SCENARIOS {
        let settings = ProblemSettings {
            points: if quick { 20 } else { 30 },
            ..ProblemSettings::default()
        };
        // `--quick` is a smoke run of the pipeline: one cold solve per problem. Otherwise
        // `optimize`'s default search, which `solve` runs or whose stored optimum it presents.
        let strategy = match name.parse::<Problem>() {
            _ if quick => Strategy::Direct,
            Ok(p) => crate::pipeline::strategy::default_strategy(p, settings.scheme),
            Err(_) => Strategy::default(),
        };
        match run_scenario(name, settings, strategy, dir, mu_s, solve)
            .with_context(|| format!("scenario {name}"))
        {
            Ok(r) => results.push(r),
            Err(e) => failures.push(format!("`{name}` failed: {}", crate::errors::render(&e))),
        }
    }
    Ok((results, failures))
}

/// max |τ_i| over the collocation nodes and the dense samples of `sol` (N m). The nodes too:
/// the dense grid of a long phase (a COT optimum's 10 s approach, 100 samples) can fall between
/// the collocation points where the torque peaks.
fn max_abs_tau(sol: &OcpSolution) -> f64 {
    (sol.dense.tau.iter().chain(&sol.nodes.tau))
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The report's max |τ| sees a peak at a collocation node that the dense grid misses.
    #[test]
    fn the_torque_peak_at_a_node_is_reported() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/fragile-cot-plan/solution.json"
        );
        use crate::pipeline::SolutionIo as _;
        let mut sol = OcpSolution::read_json(std::path::Path::new(path)).unwrap();
        let dense = sol
            .dense
            .tau
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert_eq!(max_abs_tau(&sol), dense);
        let last = sol.nodes.tau.len() / 2;
        sol.nodes.tau[last][2] = -1.5 * dense;
        assert_eq!(max_abs_tau(&sol), 1.5 * dense);
    }

    /// A variant's figures say what makes them one; the scenario's own titles are unchanged.
    #[test]
    fn a_variants_figure_titles_say_what_it_is() {
        let plain = ProblemSettings::default();
        assert_eq!(variant_note(&plain), "");
        assert_eq!(
            figure_title(
                "periodic-cot",
                &variant_note(&plain),
                "paths",
                "finger path"
            ),
            "Fig. 5 counterpart: periodic-cot: finger path"
        );
        let coned = ProblemSettings {
            impulse_cone: true,
            ..ProblemSettings::default()
        };
        assert_eq!(
            figure_title(
                "periodic-cot",
                &variant_note(&coned),
                "paths",
                "finger path"
            ),
            "Fig. 5 counterpart: periodic-cot (impulse cone imposed): finger path"
        );
        let long = ProblemSettings {
            min_stick: 0.1,
            ..ProblemSettings::default()
        };
        assert_eq!(variant_note(&long), " (stick ≥ 0.1 s)");
    }

    #[test]
    fn path_taus_sample_every_period_finely_and_every_phase() {
        // A COT-like period: 9.59 s free, 0.01 s stick, 0.4 s free.
        let d = [9.59, 0.01, 0.4];
        let taus = path_taus(&d);
        let total: usize = taus.iter().map(|t| t.len()).sum();
        assert!(total >= PATH_SAMPLES_PER_PERIOD, "{total}");
        for (p, t) in taus.iter().enumerate() {
            assert!(t.len() >= PATH_SAMPLES_PER_PHASE);
            assert_eq!((t[0], *t.last().unwrap()), (-1.0, 1.0));
            // Time steps at most period / PATH_SAMPLES_PER_PERIOD (up to rounding the share up).
            let dt = 0.5 * (t[1] - t[0]) * d[p];
            assert!(
                dt <= 10.0 / PATH_SAMPLES_PER_PERIOD as f64 + 1e-12,
                "phase {p}: {dt}"
            );
            assert!(t.windows(2).all(|w| w[1] > w[0]));
        }
        // Degenerate durations still give the minimum per phase, no panic.
        let t = path_taus(&[0.0, f64::NAN]);
        assert!(t.iter().all(|t| t.len() == PATH_SAMPLES_PER_PHASE));
    }

    /// The stages end at the optimum the table reports: the kept chain, then every round of
    /// the hp refinement, then the solve of the stored optimum in this run, or a line of its
    /// own for an optimum that differs from the last round.
    #[test]
    fn solve_stages_end_with_the_reported_optimum() {
        let stored = crate::paper::stored::sticking_optimum(Problem::PeriodicCotHuman).unwrap();
        let sol = stored.solution().unwrap();
        let history = &sol.refinement.as_ref().unwrap().history;
        assert!(history.len() > 1, "the stored optimum was refined");
        let last_round = history.last().unwrap();
        let text = solve_stages(&sol, false).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for r in history {
            assert!(
                lines
                    .iter()
                    .any(|l| l.contains(&format!("hp round {}: ", r.round))),
                "round {} missing:\n{text}",
                r.round
            );
        }
        let tail = *lines.last().unwrap();
        assert!(
            tail.contains(&format!("hp round {}", last_round.round)),
            "{text}"
        );
        assert!(
            tail.contains(&format!("{:.6e}", last_round.objective)),
            "{text}"
        );
        assert_eq!(last_round.objective.to_bits(), sol.objective.to_bits());

        // Without a refinement the cell is the problem's mesh as the transcription built it:
        // 10 points in 3 Radau elements are 3 elements of 4 (its nodes per phase, 12).
        let mut plain = sol.clone();
        plain.refinement = None;
        plain.scheme = bf_optim::ocp::Scheme::Radau { elements: 3 };
        plain.points = 10;
        assert_eq!(mesh_cell(&plain), ["12 (3)"; 3].join(", "));
        plain.scheme = bf_optim::ocp::Scheme::Lg;
        plain.points = 30;
        assert_eq!(mesh_cell(&plain), ["30 (1)"; 3].join(", "));

        let mut moved = sol.clone();
        moved.objective *= 1.001;
        let text = solve_stages(&moved, false).unwrap();
        let tail = text.lines().last().unwrap();
        assert!(tail.contains("reported optimum"), "{text}");
        assert!(tail.contains(&format!("{:.6e}", moved.objective)), "{text}");

        let text = solve_stages(&sol, true).unwrap();
        let tail = text.lines().last().unwrap();
        assert!(tail.contains("solved again here"), "{text}");
        assert!(tail.contains(&format!("{:.6e}", sol.objective)), "{text}");
    }

    /// The hp rounds are indented under the line of the kept chain's refinement that sums
    /// them, marked as the origin's where the refinement was another chain's (a hop solved on
    /// its mesh), and neither where no line of the strategy sums them, whatever the
    /// iteration counts: the link is the record's stage, not a count that may coincide.
    #[test]
    fn hp_rounds_follow_the_refinement_that_made_them() {
        use bf_problem::solution::records::StageRecord;
        let stored = crate::paper::stored::sticking_optimum(Problem::PeriodicCotHuman).unwrap();
        let mut sol = stored.solution().unwrap();
        let rounds: usize = sol
            .refinement
            .as_ref()
            .unwrap()
            .history
            .iter()
            .map(|h| h.iterations)
            .sum();
        let record = |chain: usize, iterations: usize| StageRecord {
            chain,
            stage: format!("refine start {chain} to 1e-4 (defect 1.0e-6)"),
            status: bf_optim::ipm::Status::Solved,
            objective: sol.objective,
            period: sol.period,
            iterations,
            seconds: 1.0,
        };
        let st = sol.strategy.as_mut().unwrap();
        let kept = st.chosen.unwrap();
        let other = kept + 1;
        // The other chain's count equals the rounds' sum and the kept chain's does not: a
        // comparison of counts would take the rounds for the wrong chain's.
        st.refinements = vec![record(kept, rounds + 7), record(other, rounds)];
        let round_lines = |sol: &OcpSolution| -> Vec<String> {
            solve_stages(sol, false)
                .unwrap()
                .lines()
                .filter(|l| l.contains("hp round"))
                .map(str::to_string)
                .collect()
        };
        let own_stage = record(kept, 0).stage;
        let origin_stage = record(other, 0).stage;
        for (stage, indented, origin) in [
            (Some(own_stage), true, false),
            (Some(origin_stage), false, true),
            (None, false, false),
        ] {
            sol.refinement.as_mut().unwrap().stage = stage.clone();
            let lines = round_lines(&sol);
            assert!(!lines.is_empty());
            for l in &lines {
                assert_eq!(l.contains("    hp round"), indented, "{stage:?}: {l}");
                assert_eq!(l.contains("the mesh's origin's"), origin, "{stage:?}: {l}");
            }
        }
    }

    /// Text for readers counts phases from 1, as the active bounds do: the stick phase of
    /// free, stick, free (index 1 in the file) is phase 2 in the tolerance table and in the
    /// verification summary, and so are the verdict's sentences.
    #[test]
    fn phases_are_numbered_from_one_in_every_text() {
        let stored = crate::paper::stored::sticking_optimum(Problem::PeriodicQc).unwrap();
        let sol = stored.solution().unwrap();
        let v = sol.verification.clone().unwrap();
        assert_eq!(v.phases[1].phase, 1, "the file's index is 0-based");
        let r = ScenarioResult {
            name: "periodic-qc".into(),
            solution: sol,
            max_tau: 0.0,
            contact_from_tip: (0.0, 0.0, 0.0),
            cone_share: 1.0,
            active: vec![],
        };
        let md = tolerances_markdown(&[r]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| periodic-qc |"))
            .unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[5], "2", "{row}");
        let summary = v.summary();
        assert!(
            summary.lines().any(|l| l.starts_with("    2 stick")),
            "{summary}"
        );
        assert!(
            !summary.lines().any(|l| l.starts_with("    0 ")),
            "{summary}"
        );
        let mut slipping = v.clone();
        slipping.phases[1].min_sigma = Some(-1.0);
        let why = crate::pipeline::verify::cone_failure(&slipping).unwrap();
        assert!(why.starts_with("phase 2 (stick)"), "{why}");
        let mut sagging = v;
        sagging.phases[0].min_h = Some(-1.0);
        let why = crate::pipeline::verify::penetration_failure(&sagging).unwrap();
        assert!(why.starts_with("phase 1 (free)"), "{why}");
    }

    /// The plans for the plant get their animation like the scenarios: the human finger's
    /// plan on its own scene, written under the plan's name.
    #[test]
    fn a_plan_gets_its_animation() {
        let stored = crate::paper::stored::plan_for_the_plant(Problem::PeriodicCotHuman).unwrap();
        let sol = stored.solution().unwrap();
        let (built, _) = crate::pipeline::solve::own_problem(&sol).unwrap();
        let dir = std::env::temp_dir().join(format!("bf-plan-animation-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        write_animation("periodic-cot-human-newton", &built, &sol, &dir).unwrap();
        let html =
            std::fs::read_to_string(dir.join("animation_periodic-cot-human-newton.html")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert!(
            html.contains("periodic-cot-human-newton: one period"),
            "title"
        );
    }

    #[test]
    fn rodrigues_is_a_rotation_about_the_given_axis() {
        let w = [0.3, -0.4, 1.2];
        let r = rodrigues(w);
        // Orthonormal with det +1.
        for i in 0..3 {
            for j in 0..3 {
                let d: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
            - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        assert!((det - 1.0).abs() < 1e-14);
        // The axis is fixed; the angle is |w| (trace = 1 + 2 cos θ).
        let rw: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|k| r[i][k] * w[k]).sum())
            .collect();
        for i in 0..3 {
            assert!((rw[i] - w[i]).abs() < 1e-14);
        }
        let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        assert!((r[0][0] + r[1][1] + r[2][2] - (1.0 + 2.0 * libm::cos(th))).abs() < 1e-14);
        // Small-angle branch agrees with the closed form near the switch.
        let a = rodrigues([1e-9, 0.0, 0.0]);
        assert!((a[1][2] + 1e-9).abs() < 1e-20 && (a[2][1] - 1e-9).abs() < 1e-20);
    }
}
