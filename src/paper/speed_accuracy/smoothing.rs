//! Study (b2), the smoothing ε of |x| ≈ √(x² + ε²) (eq. 58–59): cold solves of `periodic-qc`
//! on the default mesh over an ε ladder; error of the smooth contact point against the exact
//! one (eq. 3) at the solution's contact nodes and the change of J, versus solve time.

use std::fmt::Write as _;
use std::path::Path;

use crate::pipeline as problems;
use anyhow::Result;
use bf_generated::paper;
use bf_plot::paper::WorkPrecisionSet;
use bf_problem::{PhaseMode, ProblemSettings};
use indicatif::ProgressBar;

use super::{solve_qc, wp_figure};

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

/// The ε ladder of the study (m).
pub(super) fn ladder(quick: bool) -> &'static [f64] {
    if quick {
        &[0.1, 0.01, 1e-3]
    } else {
        &[0.1, 0.03, 0.01, 1e-3, 1e-4]
    }
}

/// Largest ‖p_c,smooth − p_c,exact‖∞ over the nodes of contact phases of `sol`.
fn contact_point_error(sol: &problems::OcpSolution, eps: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for (i, q) in sol.nodes.q.iter().enumerate() {
        let phase = sol.nodes.phase.get(i).copied().unwrap_or(0);
        if sol.modes.get(phase) == Some(&PhaseMode::Free) || q.len() != paper::NQ {
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

/// Solves `periodic-qc` at every ε of `eps_ladder` (interior-point cap `iters`).
pub(super) fn measure(eps_ladder: &[f64], iters: usize, pb: &ProgressBar) -> Result<Vec<EpsRow>> {
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
    Ok(eps_rows)
}

/// The Markdown of study (b2) and its figure `sa_eps`.
pub(super) fn section(rows: &[EpsRow], fig_dir: &Path) -> Result<String> {
    let mut md = String::new();
    md.push_str(
        "Smoothing ε of |x| ≈ √(x² + ε²) (eq. 58–59), default mesh (Radau, cold solves): error of the \
         smooth contact point against the exact one (eq. 3) at the solution's contact \
         nodes, and the change of J. Each row is one cold solve, **not verified** by \
         re-integration: its J is the discretised problem's local optimum at that ε, and a \
         cold solve can miss the verification's tolerance (`report strategies` verifies the \
         cold solve at ε = 0.01); what a row measures is the smoothing's error in the contact \
         point.\n\n\
         | ε (m) | status | J | period (s) | contact-point error (m) | solve (s) | iterations |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in rows {
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
    let solved: Vec<&EpsRow> = rows.iter().filter(|r| r.solved).collect();
    let fig = wp_figure(
        "periodic-qc: contact-point error vs solve time (ε ladder)",
        "max ‖p_c,smooth − p_c‖∞ [m]",
        &[WorkPrecisionSet {
            name: "smooth sat, ε ladder".into(),
            time_s: solved.iter().map(|r| r.seconds).collect(),
            error: solved.iter().map(|r| r.contact_point_error).collect(),
            labels: solved
                .iter()
                .map(|r| format!("ε = {:.0e}", r.eps))
                .collect(),
            // Solve times of the ladder are not monotone in ε: no line between the runs.
            joined: false,
        }],
    )?;
    bf_plot::render(&fig, fig_dir.join("sa_eps"))?;
    md.push_str("\n![contact-point error vs solve time](figures/sa_eps.svg)\n\n");
    Ok(md)
}
