//! Speed–accuracy report (issue 7 item 4): error against a more accurate computation versus
//! computing time, for the three places where users choose between them. All numbers come
//! from one run on the current machine.
//!
//! | part | knob | error measured against | paper |
//! |---|---|---|---|
//! | (a) simulation | DOPRI5 rtol, RK4 step | DOPRI5 rtol 1e-13 run: ‖x(T) − x_ref(T)‖∞ and event times | Sect. 3, Fig. 3 |
//! | (b) optimisation | LG points, Radau elements | objective J of a finer Radau mesh | Sect. 4.3, eq. 60 |
//! | (b) optimisation | smoothing ε | exact p_c (eq. 3) vs smooth p_c (eq. 58–59) along the solution | eq. 58–59 |
//! | (c) kernels | baked/runtime constants, Lagrangian/Newton–Euler, f32/f64, FMA | double-double evaluation of the same graph | eq. 22a, 76–79 |
//!
//! [`SpeedAccuracy::measure`] runs everything and keeps the rows (tests check them),
//! [`SpeedAccuracy::write`] renders tables and figures; [`speed_accuracy`] does both.
//! Timing is in-process (`Instant`, `black_box`, median of batches): good for ratios within
//! one run; the criterion bench `benches/kernel_variants.rs` is the reference for BENCHMARKS.md.

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use crate::study as problems;
use anyhow::{Context, Result, anyhow};
use bf_codegen::dd::Dd;
use bf_codegen::{Model as GraphModel, Scene, interp, kernels};
use bf_generated::{paper, paper_f32, paper_fma, paper_runtime};
use bf_model::{ImpactLaw, Mode as SimMode, State, Vec3, fixtures};
use bf_optim::ocp::problem::Scheme;
use bf_plot::paper::{WorkPrecision, fig_work_precision};
use bf_problem::{Mode, Problem, ProblemSettings};
use bf_sim::ball_finger::{BallFinger, BallFingerOptions};
use bf_sim::work_precision::{WorkPrecisionRow, ladder, work_precision};
use bf_sim::{Method, PdController, SimSettings};
use indicatif::{ProgressBar, ProgressStyle};

/// Kernels compared in part (c) (the variant modules of `bf_generated` emit exactly these).
pub const VARIANT_KERNELS: [&str; 4] = ["mass_matrix", "cqd_g", "cqd_g_rnea", "mass_cqd_g"];

/// Kernel variants of part (c), in table order.
pub const VARIANTS: [&str; 4] = ["f64 baked", "f64 runtime params", "f64 FMA", "f32 baked"];

/// One collocation solve of part (b).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshRow {
    /// `LG` or `Radau`.
    pub scheme: String,
    /// Collocation points per phase.
    pub points: usize,
    /// Radau elements per phase (1 for LG).
    pub elements: usize,
    /// Whether the solver converged.
    pub solved: bool,
    /// Objective J (eq. 60).
    pub objective: f64,
    /// Period of the solution (s).
    pub period: f64,
    /// Whether the solution is on the reference's local optimum (period within 10 %).
    pub same_branch: bool,
    /// |J − J_ref| / |J_ref| against the reference mesh (NaN if not solved or on another
    /// local optimum).
    pub rel_error: f64,
    /// Wall time of the solve (s).
    pub seconds: f64,
    /// Interior-point iterations.
    pub iterations: usize,
    /// When the cold solve is not on the reference's optimum: |J − J_ref| / |J_ref| of a solve
    /// on the same mesh warm-started from the reference solution (NaN otherwise or if it
    /// failed), i.e. the discretisation error of this mesh at the reference's optimum.
    pub warm_rel_error: f64,
    /// Wall time of that warm-started solve (s; NaN if none).
    pub warm_seconds: f64,
}

/// One smoothing-ε solve of part (b).
#[derive(Debug, Clone, PartialEq)]
pub struct EpsRow {
    /// ε of eq. 59 (m).
    pub eps: f64,
    /// Whether the solver converged.
    pub solved: bool,
    /// Objective J.
    pub objective: f64,
    /// Period of the solution (s).
    pub period: f64,
    /// max over contact nodes of ‖p_c,smooth(q) − p_c,exact(q)‖∞ (m).
    pub contact_point_error: f64,
    /// Wall time of the solve (s).
    pub seconds: f64,
    /// Interior-point iterations.
    pub iterations: usize,
}

/// One kernel variant of part (c).
#[derive(Debug, Clone, PartialEq)]
pub struct KernelRow {
    /// Kernel name.
    pub kernel: &'static str,
    /// Variant (one of [`VARIANTS`]).
    pub variant: &'static str,
    /// Median time per call (ns).
    pub ns_per_call: f64,
    /// Largest normwise relative error over the sampled states,
    /// ‖y − y_dd‖∞ / ‖y_dd‖∞, against double-double evaluation of the kernel's graph.
    pub max_rel_error: f64,
    /// Median of the same error over the states.
    pub median_rel_error: f64,
}

/// All measurements of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedAccuracy {
    /// Whether the quick ladders were used.
    pub quick: bool,
    /// Simulated time span of part (a) (s).
    pub sim_t_end: f64,
    /// Part (a): one row per integrator setting.
    pub sim: Vec<WorkPrecisionRow>,
    /// Part (b): reference mesh (description, objective, seconds).
    pub mesh_reference: (String, f64, f64),
    /// Part (b): LG and Radau meshes.
    pub mesh: Vec<MeshRow>,
    /// Part (b): smoothing ε ladder.
    pub eps: Vec<EpsRow>,
    /// Part (c): kernel variants.
    pub kernels: Vec<KernelRow>,
    /// Wall time of measuring parts (a), (b), (c) (s).
    pub part_seconds: [f64; 3],
}

/// [`fig_work_precision`] of the points a log–log plot can show: non-finite and non-positive
/// points are dropped, and so are series left without points (instead of failing the figure).
fn wp_figure(
    title: &str,
    error_label: &str,
    methods: &[WorkPrecision],
) -> Result<bf_plot::figure::LineFigure> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let kept: Vec<WorkPrecision> = methods
        .iter()
        .filter_map(|m| {
            let (t, e): (Vec<f64>, Vec<f64>) = m
                .time_s
                .iter()
                .copied()
                .zip(m.error.iter().copied())
                .filter(|&(t, e)| ok(t) && ok(e))
                .unzip();
            (!t.is_empty()).then(|| WorkPrecision {
                name: m.name.clone(),
                time_s: t,
                error: e,
            })
        })
        .collect();
    Ok(fig_work_precision(title, error_label, &kept)?)
}

/// Runs the whole report: measures, writes `out_dir/figures/*.svg|png`, returns the Markdown
/// section (image links relative to `out_dir`).
pub fn speed_accuracy(out_dir: &Path, quick: bool) -> Result<String> {
    let r = SpeedAccuracy::measure(quick)?;
    r.write(out_dir)
}

fn bar(len: usize, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template("{prefix:>28} [{bar:30}] {pos}/{len} {msg}") {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_prefix(what.to_string());
    pb
}

impl SpeedAccuracy {
    /// Measures parts (a)–(c); `quick` uses short ladders (< 20 s in release).
    pub fn measure(quick: bool) -> Result<Self> {
        let t = Instant::now();
        let (sim_t_end, sim) = measure_sim(quick)?;
        let ta = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (mesh_reference, mesh, eps) = measure_optim(quick)?;
        let tb = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let kernels = measure_kernels(quick)?;
        let tc = t.elapsed().as_secs_f64();
        Ok(SpeedAccuracy {
            quick,
            sim_t_end,
            sim,
            mesh_reference,
            mesh,
            eps,
            kernels,
            part_seconds: [ta, tb, tc],
        })
    }

    /// Writes the figures into `out_dir/figures` and returns the Markdown section.
    pub fn write(&self, out_dir: &Path) -> Result<String> {
        let fig_dir = out_dir.join("figures");
        std::fs::create_dir_all(&fig_dir)
            .with_context(|| format!("creating {}", fig_dir.display()))?;
        let mut md = String::new();
        let _ = writeln!(md, "## Speed versus accuracy\n");
        let _ = writeln!(
            md,
            "All numbers from one run on this machine{}; times are wall-clock medians or best \
             of repeats, comparable within the run only.\n",
            if self.quick {
                " (quick mode: short ladders)"
            } else {
                ""
            }
        );
        let [ta, tb, tc] = self.part_seconds;
        let _ = writeln!(
            md,
            "Measuring took {ta:.1} s (simulation), {tb:.1} s (optimisation), {tc:.1} s (kernels).\n"
        );
        md.push_str(&self.write_sim(&fig_dir)?);
        md.push_str(&self.write_optim(&fig_dir)?);
        md.push_str(&self.write_kernels(&fig_dir)?);
        Ok(md)
    }

    fn write_sim(&self, fig_dir: &Path) -> Result<String> {
        let mut md = String::new();
        let _ = writeln!(
            md,
            "### (a) Simulation: integrator work-precision\n\n\
             Paper scene, finger dropped from q = (0.1, 0.5, 0.5) onto the ball (τ = 0, Newton \
             impact): impact, slip, stick and lift-off events over {} s. Error of x(T) and of the \
             event times against a DOPRI5 run at rtol = 1e-13, atol = 1e-15 (Sect. 3, Fig. 3).\n",
            self.sim_t_end
        );
        md.push_str(
            "| method | rtol / h (s) | error ‖x(T) − x_ref(T)‖∞ | max event-time error (s) | CPU (ms) | steps | f evals |\n\
             |---|---|---|---|---|---|---|\n",
        );
        for r in &self.sim {
            let ev = if r.same_events {
                format!("{:.2e}", r.event_time_error)
            } else {
                "event sequence differs".into()
            };
            let err = match &r.failure {
                Some(m) => format!("failed: {m}"),
                None => format!("{:.2e}", r.error),
            };
            let _ = writeln!(
                md,
                "| {} | {:.0e} | {} | {} | {:.3} | {} | {} |",
                r.method,
                r.parameter,
                err,
                ev,
                1e3 * r.cpu_seconds,
                r.steps,
                r.rhs_evals
            );
        }
        let series = |f: &dyn Fn(&WorkPrecisionRow) -> f64| -> Vec<WorkPrecision> {
            ["dopri5", "rk4"]
                .iter()
                .map(|m| {
                    let rows: Vec<&WorkPrecisionRow> = self
                        .sim
                        .iter()
                        .filter(|r| r.method == *m && r.failure.is_none())
                        .collect();
                    WorkPrecision {
                        name: m.to_string(),
                        time_s: rows.iter().map(|r| r.cpu_seconds).collect(),
                        error: rows.iter().map(|r| f(r)).collect(),
                    }
                })
                .collect()
        };
        let fig = wp_figure(
            "Simulation: state error vs CPU time",
            "‖x(T) − x_ref(T)‖∞",
            &series(&|r| r.error),
        )?;
        bf_plot::render(&fig, fig_dir.join("sa_sim_state"))?;
        let fig = wp_figure(
            "Simulation: event-time error vs CPU time",
            "max |t_event − t_event,ref| [s]",
            &series(&|r| {
                if r.same_events {
                    r.event_time_error
                } else {
                    f64::NAN
                }
            }),
        )?;
        bf_plot::render(&fig, fig_dir.join("sa_sim_events"))?;
        md.push_str(
            "\n![state error vs time](figures/sa_sim_state.svg)\n\
             ![event-time error vs time](figures/sa_sim_events.svg)\n\n",
        );
        Ok(md)
    }

    fn write_optim(&self, fig_dir: &Path) -> Result<String> {
        let mut md = String::new();
        let (ref_name, ref_j, ref_s) = &self.mesh_reference;
        let _ = writeln!(
            md,
            "### (b) Optimisation: mesh and smoothing\n\n\
             `periodic-qc` (Sect. 6.1), cold solves (default guess strategy, iteration cap {} \
             per stage). Objective error against the reference mesh {ref_name}: J_ref = \
             {ref_j:.8}, solved in {ref_s:.2} s. The problem has several local optima (periods \
             ≈ 2.6 s and ≈ 0.95 s) and a cold start lands on one depending on the mesh; a \
             cold solution on another optimum than the reference's is re-solved on the same mesh \
             warm-started from the reference solution, which gives the mesh's discretisation \
             error at the reference's optimum (column \"warm\").\n",
            max_iter(self.quick)
        );
        md.push_str(
            "| scheme | points/phase | elements | status | J | period (s) | rel. error of J | solve (s) | iterations | warm: rel. error of J | warm: solve (s) |\n\
             |---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.mesh {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.8} | {:.4} | {} | {:.2} | {} | {} | {} |",
                r.scheme,
                r.points,
                r.elements,
                if r.solved { "solved" } else { "not solved" },
                r.objective,
                r.period,
                if r.same_branch {
                    format!("{:.2e}", r.rel_error)
                } else if r.solved {
                    "other local optimum".into()
                } else {
                    "—".into()
                },
                r.seconds,
                r.iterations,
                if r.warm_rel_error.is_finite() {
                    format!("{:.2e}", r.warm_rel_error)
                } else {
                    "—".into()
                },
                if r.warm_seconds.is_finite() {
                    format!("{:.2}", r.warm_seconds)
                } else {
                    "—".into()
                }
            );
        }
        let mut methods: Vec<WorkPrecision> = Vec::new();
        for s in ["LG", "Radau"] {
            let cold: Vec<&MeshRow> = self
                .mesh
                .iter()
                .filter(|r| r.scheme == s && r.same_branch)
                .collect();
            methods.push(WorkPrecision {
                name: format!("{s}, cold"),
                time_s: cold.iter().map(|r| r.seconds).collect(),
                error: cold.iter().map(|r| r.rel_error).collect(),
            });
            let warm: Vec<&MeshRow> = self
                .mesh
                .iter()
                .filter(|r| r.scheme == s && r.warm_rel_error.is_finite())
                .collect();
            methods.push(WorkPrecision {
                name: format!("{s}, warm from the reference"),
                time_s: warm.iter().map(|r| r.warm_seconds).collect(),
                error: warm.iter().map(|r| r.warm_rel_error).collect(),
            });
        }
        if methods.iter().any(|m| !m.error.is_empty()) {
            let fig = wp_figure(
                "periodic-qc: objective error vs solve time",
                "|J − J_ref| / |J_ref|",
                &methods,
            )?;
            bf_plot::render(&fig, fig_dir.join("sa_mesh"))?;
            md.push_str("\n![objective error vs solve time](figures/sa_mesh.svg)\n\n");
        } else {
            md.push_str("\nNo mesh solved on the reference's optimum: no figure.\n\n");
        }

        md.push_str(
            "Smoothing ε of |x| ≈ √(x² + ε²) (eq. 58–59), default mesh (Radau, cold solves): error of the \
             smooth contact point against the exact one (eq. 3) at the solution's contact \
             nodes, and the change of J.\n\n\
             | ε (m) | status | J | period (s) | contact-point error (m) | solve (s) | iterations |\n\
             |---|---|---|---|---|---|---|\n",
        );
        for r in &self.eps {
            let _ = writeln!(
                md,
                "| {:.0e} | {} | {:.8} | {:.4} | {:.2e} | {:.2} | {} |",
                r.eps,
                if r.solved { "solved" } else { "not solved" },
                r.objective,
                r.period,
                r.contact_point_error,
                r.seconds,
                r.iterations
            );
        }
        let rows: Vec<&EpsRow> = self.eps.iter().filter(|r| r.solved).collect();
        let fig = wp_figure(
            "periodic-qc: contact-point error vs solve time (ε ladder)",
            "max ‖p_c,smooth − p_c‖∞ [m]",
            &[WorkPrecision {
                name: "smooth sat, ε ladder".into(),
                time_s: rows.iter().map(|r| r.seconds).collect(),
                error: rows.iter().map(|r| r.contact_point_error).collect(),
            }],
        )?;
        bf_plot::render(&fig, fig_dir.join("sa_eps"))?;
        md.push_str("\n![contact-point error vs solve time](figures/sa_eps.svg)\n\n");
        Ok(md)
    }

    fn write_kernels(&self, fig_dir: &Path) -> Result<String> {
        let mut md = String::new();
        md.push_str(
            "### (c) Generated kernels: variants\n\n\
             Paper scene. Error: ‖y − y_dd‖∞ / ‖y_dd‖∞ against a double-double evaluation of the \
             same expression graph (the runtime-parameter variant against its own graph), over \
             random states q ∈ [−π, π]³, q̇ ∈ [−3, 3]³. `cqd_g` is the Lagrangian (Christoffel) \
             path, `cqd_g_rnea` symbolic Newton–Euler; `mass_cqd_g` returns M and C q̇ + g. FMA: \
             every a·b ± c as `mul_add` (without `-C target-feature=+fma` this is a libm call). \
             f32: arguments, constants and arithmetic in single precision (the error includes \
             rounding the state to f32).\n\n\
             | kernel | variant | ns/call | max rel. error | median rel. error |\n\
             |---|---|---|---|---|\n",
        );
        for r in &self.kernels {
            let _ = writeln!(
                md,
                "| {} | {} | {:.1} | {:.2e} | {:.2e} |",
                r.kernel, r.variant, r.ns_per_call, r.max_rel_error, r.median_rel_error
            );
        }
        let methods: Vec<WorkPrecision> = VARIANTS
            .iter()
            .map(|v| {
                let rows: Vec<&KernelRow> =
                    self.kernels.iter().filter(|r| r.variant == *v).collect();
                WorkPrecision {
                    name: v.to_string(),
                    time_s: rows.iter().map(|r| 1e-9 * r.ns_per_call).collect(),
                    // A result equal to the double-double one to the last bit has error 0,
                    // which a log axis cannot show: clamp to half an ulp.
                    error: rows
                        .iter()
                        .map(|r| r.max_rel_error.max(f64::EPSILON / 2.0))
                        .collect(),
                }
            })
            .collect();
        let fig = wp_figure(
            "Kernels (mass_matrix, cqd_g, cqd_g_rnea, mass_cqd_g): error vs time per call",
            "max ‖y − y_dd‖∞ / ‖y_dd‖∞",
            &methods,
        )?;
        bf_plot::render(&fig, fig_dir.join("sa_kernels"))?;
        md.push_str("\n![kernel error vs time per call](figures/sa_kernels.svg)\n\n");
        Ok(md)
    }
}

// ---------------------------------------------------------------------------------------------
// (a) simulation
// ---------------------------------------------------------------------------------------------

fn sim_settings(method: Method, rtol: f64) -> SimSettings {
    SimSettings {
        method,
        rtol,
        atol: 1e-2 * rtol,
        h_max: 0.05,
        ..SimSettings::default()
    }
}

fn measure_sim(quick: bool) -> Result<(f64, Vec<WorkPrecisionRow>)> {
    let t_end = if quick { 3.0 } else { 10.0 };
    let sys = BallFinger::new(
        fixtures::paper_scene().map_err(|e| anyhow!("paper scene: {e}"))?,
        PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3])
            .map_err(|e| anyhow!("zero input: {e}"))?,
        BallFingerOptions {
            impact_law: ImpactLaw::Newton,
            ..BallFingerOptions::default()
        },
    )
    .map_err(|e| anyhow!("ball-finger system: {e}"))?;
    let x0 = State::new(Vec3::new(0.1, 0.5, 0.5), Vec3::zeros(), Vec3::zeros()).to_array();
    let reference = SimSettings {
        rtol: 1e-13,
        atol: 1e-15,
        ..sim_settings(Method::Dopri5, 1e-13)
    };
    let (rtols, steps, repeats): (&[f64], &[f64], usize) = if quick {
        (&[1e-3, 1e-5, 1e-7, 1e-9], &[1e-2, 1e-3], 1)
    } else {
        (
            &[
                1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
            ],
            &[1e-2, 3e-3, 1e-3, 3e-4, 1e-4],
            3,
        )
    };
    let configs = ladder(&sim_settings(Method::Dopri5, 1e-8), rtols, 1e-2, steps);
    let pb = bar(configs.len(), "(a) simulation");
    let mut rows = Vec::with_capacity(configs.len());
    // One configuration at a time so the bar moves; the reference is cheap (< 0.1 s).
    for c in &configs {
        pb.set_message(format!("{:?}", c.method));
        let mut r = work_precision(
            &sys,
            SimMode::Free,
            0.0,
            &x0,
            t_end,
            &reference,
            std::slice::from_ref(c),
            repeats,
        )
        .map_err(|e| anyhow!("reference simulation failed: {e}"))?;
        rows.append(&mut r);
        pb.inc(1);
    }
    pb.finish_and_clear();
    Ok((t_end, rows))
}

// ---------------------------------------------------------------------------------------------
// (b) optimisation
// ---------------------------------------------------------------------------------------------

struct Solved {
    sol: Option<problems::OcpSolution>,
    seconds: f64,
}

/// Interior-point iteration cap of the report's solves: a mesh that needs more is reported as
/// not solved instead of stalling the report (cold LG at 30 points runs 3000 iterations).
fn max_iter(quick: bool) -> usize {
    if quick { 150 } else { 400 }
}

fn solve_qc(
    points: usize,
    scheme: Scheme,
    epsilon: Option<f64>,
    warm: Option<&problems::OcpSolution>,
    max_iter: usize,
) -> Result<Solved> {
    let settings = ProblemSettings {
        points,
        scheme,
        epsilon,
        warm_start: warm.cloned(),
        max_iter,
        ..ProblemSettings::default()
    };
    let start = Instant::now();
    let p = problems::build(Problem::PeriodicQc, &settings)
        .map_err(|e| anyhow!("building periodic-qc: {e}"))?;
    let sol = problems::solve(&p, None).map_err(|e| anyhow!("solving periodic-qc: {e}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let ok = sol.status.is_success() && sol.objective.is_finite();
    Ok(Solved {
        sol: ok.then_some(sol),
        seconds,
    })
}

/// Largest ‖p_c,smooth − p_c,exact‖∞ over the nodes of contact phases of `sol`.
fn contact_point_error(sol: &problems::OcpSolution, eps: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for (i, q) in sol.nodes.q.iter().enumerate() {
        let phase = sol.nodes.phase.get(i).copied().unwrap_or(0);
        if sol.modes.get(phase) == Some(&Mode::Free) || q.len() != paper::NQ {
            continue;
        }
        let q = [q[0], q[1], q[2]];
        let z = [0.0; 3];
        let mut exact = paper::Contact::default();
        let mut smooth = paper::Contact::default();
        paper::contact(&q, &z, &z, &paper::PARAM_DEFAULTS, &mut exact);
        paper::contact_smooth(&q, &z, &z, eps, &paper::PARAM_DEFAULTS, &mut smooth);
        for k in 0..3 {
            worst = worst.max((exact.p_c[k] - smooth.p_c[k]).abs());
        }
    }
    worst
}

type OptimRows = ((String, f64, f64), Vec<MeshRow>, Vec<EpsRow>);

/// Whether two periods belong to the same local optimum (the optima found differ by > 2×).
fn same_branch(period: f64, reference: f64) -> bool {
    (period - reference).abs() <= 0.1 * reference.abs()
}

fn measure_optim(quick: bool) -> Result<OptimRows> {
    let (lg, radau, reference, eps_ladder): (&[usize], &[usize], (usize, usize), &[f64]) = if quick
    {
        (&[10, 20], &[2, 3], (6, 5), &[0.1, 0.01, 1e-3])
    } else {
        (
            &[10, 20, 30, 40],
            &[2, 3, 5, 8],
            (10, 6),
            &[0.1, 0.03, 0.01, 1e-3, 1e-4],
        )
    };
    const RADAU_POINTS_PER_ELEMENT: usize = 5;
    let iters = max_iter(quick);
    let pb = bar(
        1 + lg.len() + radau.len() + eps_ladder.len(),
        "(b) optimisation",
    );
    let (ref_el, ref_pe) = reference;
    pb.set_message("reference mesh");
    let r = solve_qc(
        ref_el * ref_pe,
        Scheme::Radau { elements: ref_el },
        None,
        None,
        1500,
    )?;
    let ref_sol = r
        .sol
        .ok_or_else(|| anyhow!("the reference mesh of periodic-qc did not solve"))?;
    let (j_ref, t_ref) = (ref_sol.objective, ref_sol.period);
    let ref_desc = format!("Radau, {ref_el} elements × {ref_pe} points (period {t_ref:.4} s)");
    pb.inc(1);
    let mut mesh = Vec::new();
    let mut push = |scheme: &str, points: usize, elements: usize, s: Solved| {
        let nlp_scheme = if scheme == "LG" {
            Scheme::Lg
        } else {
            Scheme::Radau { elements }
        };
        let (solved, objective, period, iterations) = match &s.sol {
            Some(sol) => (true, sol.objective, sol.period, sol.iterations),
            None => (false, f64::NAN, f64::NAN, 0),
        };
        let branch = solved && same_branch(period, t_ref);
        let (warm_rel_error, warm_seconds) = if branch {
            (f64::NAN, f64::NAN)
        } else {
            match solve_qc(points, nlp_scheme, None, Some(&ref_sol), iters) {
                Ok(Solved {
                    sol: Some(w),
                    seconds,
                }) if same_branch(w.period, t_ref) => {
                    ((w.objective - j_ref).abs() / j_ref.abs(), seconds)
                }
                _ => (f64::NAN, f64::NAN),
            }
        };
        mesh.push(MeshRow {
            scheme: scheme.into(),
            points,
            elements,
            solved,
            objective,
            period,
            same_branch: branch,
            rel_error: if branch {
                (objective - j_ref).abs() / j_ref.abs()
            } else {
                f64::NAN
            },
            seconds: s.seconds,
            iterations,
            warm_rel_error,
            warm_seconds,
        });
    };
    for &n in lg {
        pb.set_message(format!("LG {n}"));
        push("LG", n, 1, solve_qc(n, Scheme::Lg, None, None, iters)?);
        pb.inc(1);
    }
    for &e in radau {
        let n = e * RADAU_POINTS_PER_ELEMENT;
        pb.set_message(format!("Radau {e} elements"));
        let s = solve_qc(n, Scheme::Radau { elements: e }, None, None, iters)?;
        push("Radau", n, e, s);
        pb.inc(1);
    }
    let defaults = ProblemSettings::default();
    let mut eps_rows = Vec::new();
    for &eps in eps_ladder {
        pb.set_message(format!("eps {eps:.0e}"));
        let s = solve_qc(defaults.points, defaults.scheme, Some(eps), None, iters)?;
        let row = match &s.sol {
            Some(sol) => EpsRow {
                eps,
                solved: true,
                objective: sol.objective,
                period: sol.period,
                contact_point_error: contact_point_error(sol, eps),
                seconds: s.seconds,
                iterations: sol.iterations,
            },
            None => EpsRow {
                eps,
                solved: false,
                objective: f64::NAN,
                period: f64::NAN,
                contact_point_error: f64::NAN,
                seconds: s.seconds,
                iterations: 0,
            },
        };
        eps_rows.push(row);
        pb.inc(1);
    }
    pb.finish_and_clear();
    Ok(((ref_desc, j_ref, r.seconds), mesh, eps_rows))
}

// ---------------------------------------------------------------------------------------------
// (c) kernels
// ---------------------------------------------------------------------------------------------

/// Deterministic uniform numbers in [0, 1) (splitmix64): the report needs no RNG crate.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

type Q = [f64; paper::NQ];

fn states(n: usize) -> Vec<(Q, Q)> {
    let mut rng = SplitMix(0x5eed_2026);
    (0..n)
        .map(|_| {
            let mut q = [0.0; 3];
            let mut qd = [0.0; 3];
            for v in &mut q {
                *v = std::f64::consts::PI * (2.0 * rng.next_f64() - 1.0);
            }
            for v in &mut qd {
                *v = 3.0 * (2.0 * rng.next_f64() - 1.0);
            }
            (q, qd)
        })
        .collect()
}

/// Double-double values of kernel `name` of `model` at every state.
fn dd_reference(model: &mut GraphModel, name: &str, states: &[(Q, Q)]) -> Result<Vec<Vec<Dd>>> {
    let def = kernels::build_kernel(model, name).map_err(|e| anyhow!("kernel {name}: {e}"))?;
    let ids: Vec<_> = def
        .outputs
        .iter()
        .flat_map(|o| o.ids.iter().copied())
        .collect();
    let layout = model.layout;
    let n = layout.nq;
    let mut vars = vec![Dd::new(0.0); layout.n_vars()];
    for (i, p) in model.params.iter().enumerate() {
        vars[layout.param(i) as usize] = Dd::new(p.1);
    }
    Ok(states
        .iter()
        .map(|(q, qd)| {
            for i in 0..n {
                vars[i] = Dd::new(q[i]);
                vars[n + i] = Dd::new(qd[i]);
            }
            interp::eval::<Dd>(&model.g, &ids, &vars)
        })
        .collect())
}

/// (max, median) over states of ‖y − y_dd‖∞ / ‖y_dd‖∞.
fn rel_errors(values: &[Vec<f64>], reference: &[Vec<Dd>]) -> Result<(f64, f64)> {
    let mut errs = Vec::with_capacity(values.len());
    for (y, r) in values.iter().zip(reference) {
        if y.len() != r.len() {
            return Err(anyhow!(
                "kernel output length {} differs from its graph's {}",
                y.len(),
                r.len()
            ));
        }
        let scale = r.iter().map(|v| v.to_f64().abs()).fold(0.0, f64::max);
        let err = y
            .iter()
            .zip(r)
            .map(|(a, b)| (Dd::new(*a) - *b).to_f64().abs())
            .fold(0.0, f64::max);
        errs.push(if scale > 0.0 { err / scale } else { err });
    }
    errs.sort_by(f64::total_cmp);
    let max = errs.last().copied().unwrap_or(f64::NAN);
    let median = errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN);
    Ok((max, median))
}

/// Median over `batches` of the time per call of `f(i)` (i cycling over the states), in ns.
fn time_ns(calls: usize, batches: usize, n_states: usize, mut f: impl FnMut(usize)) -> f64 {
    for i in 0..calls.min(1000) {
        f(i % n_states);
    }
    let mut t: Vec<f64> = (0..batches)
        .map(|_| {
            let start = Instant::now();
            for i in 0..calls {
                f(black_box(i % n_states));
            }
            start.elapsed().as_secs_f64() * 1e9 / calls as f64
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn to32(v: &[f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

/// Flattened outputs of kernel `name` of every variant at `(q, qd)`, in [`VARIANTS`] order.
fn eval_variants(name: &str, q: &Q, qd: &Q) -> Result<[Vec<f64>; 4]> {
    let z = [0.0; 3];
    let missing = || anyhow!("kernel {name} missing in a variant module");
    let base =
        paper::eval_flat(name, q, qd, &z, 0.0, &paper::PARAM_DEFAULTS).ok_or_else(missing)?;
    let rt = paper_runtime::eval_flat(name, q, qd, &z, 0.0, &paper_runtime::PARAM_DEFAULTS)
        .ok_or_else(missing)?;
    let fma = paper_fma::eval_flat(name, q, qd, &z, 0.0, &paper_fma::PARAM_DEFAULTS)
        .ok_or_else(missing)?;
    let f32v = paper_f32::eval_flat(
        name,
        &to32(q),
        &to32(qd),
        &[0.0; 3],
        0.0,
        &paper_f32::PARAM_DEFAULTS,
    )
    .ok_or_else(missing)?
    .into_iter()
    .map(f64::from)
    .collect();
    Ok([base, rt, fma, f32v])
}

/// Time per call of kernel `name` in variant `v` (index into [`VARIANTS`]).
fn time_variant(name: &str, v: usize, states: &[(Q, Q)], calls: usize, batches: usize) -> f64 {
    let n = states.len();
    let s32: Vec<([f32; 3], [f32; 3])> = states.iter().map(|(q, qd)| (to32(q), to32(qd))).collect();
    macro_rules! time_f64 {
        ($m:ident) => {{
            let p = &$m::PARAM_DEFAULTS;
            match name {
                "mass_matrix" => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0; 3]; 3];
                    $m::mass_matrix(black_box(&states[i].0), p, &mut m);
                    black_box(&m);
                }),
                "cqd_g" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0; 3];
                    $m::cqd_g(black_box(&states[i].0), black_box(&states[i].1), p, &mut o);
                    black_box(&o);
                }),
                "cqd_g_rnea" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0; 3];
                    $m::cqd_g_rnea(black_box(&states[i].0), black_box(&states[i].1), p, &mut o);
                    black_box(&o);
                }),
                _ => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0; 3]; 3];
                    let mut o = [0.0; 3];
                    $m::mass_cqd_g(
                        black_box(&states[i].0),
                        black_box(&states[i].1),
                        p,
                        &mut m,
                        &mut o,
                    );
                    black_box((&m, &o));
                }),
            }
        }};
    }
    match v {
        0 => time_f64!(paper),
        1 => time_f64!(paper_runtime),
        2 => time_f64!(paper_fma),
        _ => {
            let p = &paper_f32::PARAM_DEFAULTS;
            match name {
                "mass_matrix" => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0f32; 3]; 3];
                    paper_f32::mass_matrix(black_box(&s32[i].0), p, &mut m);
                    black_box(&m);
                }),
                "cqd_g" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0f32; 3];
                    paper_f32::cqd_g(black_box(&s32[i].0), black_box(&s32[i].1), p, &mut o);
                    black_box(&o);
                }),
                "cqd_g_rnea" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0f32; 3];
                    paper_f32::cqd_g_rnea(black_box(&s32[i].0), black_box(&s32[i].1), p, &mut o);
                    black_box(&o);
                }),
                _ => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0f32; 3]; 3];
                    let mut o = [0.0f32; 3];
                    paper_f32::mass_cqd_g(
                        black_box(&s32[i].0),
                        black_box(&s32[i].1),
                        p,
                        &mut m,
                        &mut o,
                    );
                    black_box((&m, &o));
                }),
            }
        }
    }
}

fn measure_kernels(quick: bool) -> Result<Vec<KernelRow>> {
    let (n_states, calls, batches) = if quick {
        (100, 4_000, 5)
    } else {
        (1000, 40_000, 9)
    };
    let scene = Scene::from_toml_str(paper::SCENE_TOML, "scenes/paper.toml")
        .map_err(|e| anyhow!("paper scene: {e}"))?;
    let mut baked = GraphModel::new(&scene).map_err(|e| anyhow!("paper graph: {e}"))?;
    let all_runtime = Scene {
        runtime_parameters: scene.constants().into_iter().map(|c| c.0).collect(),
        ..scene.clone()
    };
    let mut runtime =
        GraphModel::new(&all_runtime).map_err(|e| anyhow!("runtime-parameter graph: {e}"))?;
    let same_params = runtime.params.len() == paper_runtime::NP
        && runtime
            .params
            .iter()
            .zip(
                paper_runtime::PARAM_NAMES
                    .iter()
                    .zip(&paper_runtime::PARAM_DEFAULTS),
            )
            .all(|(a, (n, v))| a.0 == *n && a.1 == *v);
    if !same_params {
        return Err(anyhow!(
            "bf_generated::paper_runtime was generated with other parameters than the report's graph"
        ));
    }
    let st = states(n_states);
    let pb = bar(VARIANT_KERNELS.len() * VARIANTS.len(), "(c) kernels");
    let mut rows = Vec::new();
    for name in VARIANT_KERNELS {
        pb.set_message(name);
        let ref_baked = dd_reference(&mut baked, name, &st)?;
        let ref_runtime = dd_reference(&mut runtime, name, &st)?;
        let mut values: [Vec<Vec<f64>>; 4] = Default::default();
        for (q, qd) in &st {
            let ys = eval_variants(name, q, qd)?;
            for (v, y) in values.iter_mut().zip(ys) {
                v.push(y);
            }
        }
        for (v, variant) in VARIANTS.iter().enumerate() {
            let reference = if v == 1 { &ref_runtime } else { &ref_baked };
            let (max_rel_error, median_rel_error) = rel_errors(&values[v], reference)?;
            let ns_per_call = time_variant(name, v, &st, calls, batches);
            rows.push(KernelRow {
                kernel: name,
                variant,
                ns_per_call,
                max_rel_error,
                median_rel_error,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    Ok(rows)
}
