//! Speed versus accuracy: error against a more accurate computation versus computing time,
//! for the places where users choose between them. One file per study:
//!
//! | study | file | knob | error measured against | paper |
//! |---|---|---|---|---|
//! | (a) simulation | [`integrators`] | DOPRI5 rtol, RK4 step | DOPRI5 rtol 1e-13 run: ‖x(T) − x_ref(T)‖∞ and event times | Sect. 3, Fig. 3 |
//! | (b) optimisation | [`meshes`] | LG points, Radau elements | objective J of an hp-refined Radau reference (element error estimate ≤ 1e-8, its J error stated) | Sect. 4.3, eq. 60 |
//! | (b) optimisation | [`smoothing`] | smoothing ε | exact p_c (eq. 3) vs smooth p_c (eq. 58–59) along the solution | eq. 58–59 |
//! | (c) kernels | [`kernel_variants`] | baked/runtime constants, Lagrangian/Newton–Euler, f32/f64, FMA | double-double evaluation of the same graph | eq. 22a, 76–79 |
//!
//! [`SpeedAccuracy::measure`] runs every study and keeps the rows (tests check them),
//! [`SpeedAccuracy::write`] renders tables and figures; [`speed_accuracy`] does both. All
//! numbers come from one run on the current machine. Timing is in-process (`Instant`,
//! `black_box`, median of batches): good for ratios within one run; the criterion bench
//! `benches/kernel_variants.rs` is the reference for BENCHMARKS.md.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use crate::pipeline as problems;
use anyhow::{Context, Result};
use bf_optim::ocp::problem::Scheme;
use bf_plot::paper::{WorkPrecisionSet, fig_work_precision_sets};
use bf_problem::{Problem, ProblemSettings};
use bf_sim::work_precision::WorkPrecisionRow;
use indicatif::{ProgressBar, ProgressStyle};

pub mod integrators;
pub mod kernel_variants;
pub mod meshes;
pub mod smoothing;

pub use kernel_variants::{KernelRow, VARIANT_KERNELS, VARIANTS};
pub use meshes::{MeshRow, PresentedReference};
pub use smoothing::EpsRow;

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
    /// Part (b): the reference at the optimum the report presents (`None` when none was
    /// given, [`SpeedAccuracy::measure_at`]).
    pub mesh_presented: Option<PresentedReference>,
    /// Part (b): LG and Radau meshes.
    pub mesh: Vec<MeshRow>,
    /// Part (b): smoothing ε ladder.
    pub eps: Vec<EpsRow>,
    /// Part (c): kernel variants.
    pub kernels: Vec<KernelRow>,
    /// Wall time of measuring studies (a), (b), (c) (s).
    pub part_seconds: [f64; 3],
}

/// [`fig_work_precision_sets`] of the points a log–log plot can show: non-finite and
/// non-positive points are dropped together with their labels, and so are sets left without
/// points (instead of failing the figure).
fn wp_figure(
    title: &str,
    error_label: &str,
    sets: &[WorkPrecisionSet],
) -> Result<bf_plot::figure::LineFigure> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let kept: Vec<WorkPrecisionSet> = sets
        .iter()
        .filter_map(|m| {
            let keep: Vec<usize> = (0..m.time_s.len().min(m.error.len()))
                .filter(|&i| ok(m.time_s[i]) && ok(m.error[i]))
                .collect();
            (!keep.is_empty()).then(|| WorkPrecisionSet {
                name: m.name.clone(),
                time_s: keep.iter().map(|&i| m.time_s[i]).collect(),
                error: keep.iter().map(|&i| m.error[i]).collect(),
                labels: if m.labels.is_empty() {
                    Vec::new()
                } else {
                    keep.iter().map(|&i| m.labels[i].clone()).collect()
                },
                joined: m.joined,
            })
        })
        .collect();
    Ok(fig_work_precision_sets(title, error_label, &kept)?)
}

/// Runs the whole report: measures (the mesh study also at `presented`, the `periodic-qc`
/// optimum the calling report presents, if given), writes `out_dir/figures/*.svg|png`, returns
/// the Markdown section (image links relative to `out_dir`).
pub fn speed_accuracy(
    out_dir: &Path,
    quick: bool,
    presented: Option<&problems::OcpSolution>,
) -> Result<String> {
    let r = SpeedAccuracy::measure_at(quick, presented)?;
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
    /// Measures studies (a)–(c); `quick` uses short ladders (< 20 s in release).
    pub fn measure(quick: bool) -> Result<Self> {
        Self::measure_at(quick, None)
    }

    /// [`SpeedAccuracy::measure`], the mesh study also at `presented` (a `periodic-qc`
    /// optimum: [`meshes`]).
    pub fn measure_at(quick: bool, presented: Option<&problems::OcpSolution>) -> Result<Self> {
        let t = Instant::now();
        let (sim_t_end, sim) = integrators::measure(quick)?;
        let ta = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (mesh_reference, mesh_presented, mesh, eps) = measure_optim(quick, presented)?;
        let tb = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let kernels = kernel_variants::measure(quick)?;
        let tc = t.elapsed().as_secs_f64();
        Ok(SpeedAccuracy {
            quick,
            sim_t_end,
            sim,
            mesh_reference,
            mesh_presented,
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
        md.push_str(&integrators::section(self.sim_t_end, &self.sim, &fig_dir)?);
        md.push_str(&meshes::section(
            &self.mesh_reference,
            self.mesh_presented.as_ref(),
            &self.mesh,
            self.quick,
            &fig_dir,
        )?);
        md.push_str(&smoothing::section(&self.eps, &fig_dir)?);
        md.push_str(&kernel_variants::section(&self.kernels, &fig_dir)?);
        Ok(md)
    }
}

// ---------------------------------------------------------------------------------------------
// Collocation solves shared by studies (b1) and (b2)
// ---------------------------------------------------------------------------------------------

type OptimRows = (
    (String, f64, f64),
    Option<PresentedReference>,
    Vec<MeshRow>,
    Vec<EpsRow>,
);

/// Studies (b1) (also at `presented`) and (b2) under one progress bar, in that order.
fn measure_optim(quick: bool, presented: Option<&problems::OcpSolution>) -> Result<OptimRows> {
    let mesh_ladder = meshes::MeshLadder::new(quick);
    let eps_ladder = smoothing::ladder(quick);
    let iters = max_iter(quick);
    let pb = bar(mesh_ladder.solves() + eps_ladder.len(), "(b) optimisation");
    let (reference, presented_ref, mesh) = meshes::measure(&mesh_ladder, iters, &pb, presented)?;
    let eps = smoothing::measure(eps_ladder, iters, &pb)?;
    pb.finish_and_clear();
    Ok((reference, presented_ref, mesh, eps))
}

/// A solve of `periodic-qc`: the solution if it succeeded, and the wall time either way.
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
    let p = problems::build(Problem::PeriodicQc, &settings).context("building periodic-qc")?;
    let sol = problems::solve(&p, None).context("solving periodic-qc")?;
    let seconds = start.elapsed().as_secs_f64();
    let ok = sol.status.is_success() && sol.objective.is_finite();
    Ok(Solved {
        sol: ok.then_some(sol),
        seconds,
    })
}
