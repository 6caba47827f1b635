//! Study (b1), collocation meshes (paper Sect. 4.3, objective of eq. 60): cold solves of
//! `periodic-qc` on Legendre–Gauss meshes of increasing point count and on Radau meshes of
//! increasing element count; error of the objective J against a converged reference, versus
//! solve time. The reference is a cold Radau solve refined by the hp rule of
//! [`crate::pipeline::refine`] until the largest element error estimate is below
//! `MeshLadder`'s tolerance (1e-8; 1e-6 quick); its own error is estimated by the largest
//! change of J over the last three refinement rounds and stated with it. A cold solve that lands on another local optimum than the reference's is
//! re-solved on the same mesh warm-started from the reference solution, which gives the mesh's
//! discretisation error at the reference's optimum.
//!
//! The cold solves find a local optimum (J ≈ 0.56 on the full ladder) several times worse than
//! the one the report presents (the default search's, J ≈ 0.09); the discretisation error a
//! reader wants is at the latter. Given that optimum (`measure`'s `presented`), every mesh is
//! also solved warm-started from it, against a reference refined from it the same way as the
//! cold one ([`PresentedReference`]); the table and `sa_mesh` show both, labelled.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, anyhow};
use bf_optim::ocp::problem::Scheme;
use bf_plot::paper::WorkPrecisionSet;
use bf_problem::OcpSolution;
use bf_problem::{Problem, ProblemSettings};
use indicatif::ProgressBar;

use super::{Solved, max_iter, solve_qc, wp_figure};
use crate::pipeline::refine::{RefineSettings, refine_solution};

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
    /// Whether the solution is on the reference's local optimum (period and phase durations
    /// within 10 %, see `same_branch`).
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
    /// |J − J_ref,p| / |J_ref,p| of a solve on this mesh warm-started from the presented
    /// optimum, J_ref,p its refined reference ([`PresentedReference`]); NaN when no optimum
    /// was presented, the solve failed or left that optimum (period or a phase duration off by
    /// more than 10 %).
    pub presented_rel_error: f64,
    /// Objective of that solve (NaN if none).
    pub presented_objective: f64,
    /// Wall time of that solve (s; NaN if none).
    pub presented_seconds: f64,
}

/// The reference at the optimum the report presents: that solution refined like the cold
/// reference (warm-started from it on the reference's starting mesh).
#[derive(Debug, Clone, PartialEq)]
pub struct PresentedReference {
    /// How it was obtained, with its error estimates.
    pub description: String,
    /// J_ref,p: its objective on the refined mesh.
    pub objective: f64,
    /// The presented solution's own objective (on the mesh it was found on).
    pub presented_objective: f64,
    /// Period of the presented solution (s).
    pub presented_period: f64,
    /// Wall time of the refinement (s).
    pub seconds: f64,
    /// Whether the presented solution is on the cold reference's optimum (period and phase
    /// durations within 10 %, as the warm solves are judged).
    pub same_as_cold: bool,
    /// Whether its stick phase lies on the problem's lower bound
    /// ([`bf_problem::catalogue::MIN_STICK`]), as `active bounds` judges it.
    pub stick_on_bound: bool,
}

/// The meshes of the study.
pub(super) struct MeshLadder {
    /// LG points per phase.
    lg: &'static [usize],
    /// Radau elements per phase.
    radau: &'static [usize],
    /// Starting mesh of the reference: (Radau elements, points per element).
    reference: (usize, usize),
    /// Refinement tolerance of the reference (largest element error estimate).
    reference_tol: f64,
}

impl MeshLadder {
    /// The quick or the full ladder.
    pub(super) fn new(quick: bool) -> Self {
        if quick {
            MeshLadder {
                lg: &[10, 20],
                radau: &[2, 3],
                reference: (6, 5),
                reference_tol: 1e-6,
            }
        } else {
            MeshLadder {
                lg: &[10, 20, 30, 40],
                radau: &[2, 3, 5, 8],
                reference: (10, 6),
                reference_tol: 1e-8,
            }
        }
    }

    /// Number of cold solves (reference included).
    pub(super) fn solves(&self) -> usize {
        1 + self.lg.len() + self.radau.len()
    }
}

/// Points per element of the Radau meshes of the ladder.
const RADAU_POINTS_PER_ELEMENT: usize = 5;

/// The reference (description, objective, seconds), the reference at the presented optimum
/// (if one was given) and the rows of the ladder.
pub(super) type MeshRows = ((String, f64, f64), Option<PresentedReference>, Vec<MeshRow>);

/// Solves the reference and every mesh of `ladder` (interior-point cap `iters`), and where
/// `presented` is given (the optimum the report presents), its reference and every mesh
/// warm-started from it.
pub(super) fn measure(
    ladder: &MeshLadder,
    iters: usize,
    pb: &ProgressBar,
    presented: Option<&OcpSolution>,
) -> Result<MeshRows> {
    let (ref_el, ref_pe) = ladder.reference;
    pb.set_message("reference mesh");
    let r = solve_qc(
        ref_el * ref_pe,
        Scheme::Radau { elements: ref_el },
        None,
        None,
        1500,
    )?;
    let start_sol = r
        .sol
        .ok_or_else(|| anyhow!("the reference mesh of periodic-qc did not solve"))?;
    pb.set_message("refining the reference mesh");
    let t0 = std::time::Instant::now();
    let (ref_sol, ref_desc) = converged_reference(ladder, start_sol, false)?;
    let ref_seconds = r.seconds + t0.elapsed().as_secs_f64();
    pb.inc(1);
    let presented_ref = match presented {
        Some(p) => {
            pb.set_message("refining the presented optimum");
            let t0 = std::time::Instant::now();
            let (sol, description) = converged_reference(ladder, p.clone(), true)?;
            Some(PresentedReference {
                description,
                objective: sol.objective,
                presented_objective: p.objective,
                presented_period: p.period,
                seconds: t0.elapsed().as_secs_f64(),
                same_as_cold: same_branch(p, &ref_sol),
                stick_on_bound: p.stick_duration().is_some_and(|d| {
                    crate::pipeline::bounds::on_bound(d, bf_problem::catalogue::MIN_STICK)
                }),
            })
        }
        None => None,
    };
    let at_presented = |points: usize, scheme: Scheme| -> (f64, f64, f64) {
        let (Some(p), Some(r)) = (presented, &presented_ref) else {
            return (f64::NAN, f64::NAN, f64::NAN);
        };
        match solve_qc(points, scheme, None, Some(p), iters) {
            Ok(Solved {
                sol: Some(w),
                seconds,
            }) if same_branch(&w, p) => (
                (w.objective - r.objective).abs() / r.objective.abs(),
                w.objective,
                seconds,
            ),
            _ => (f64::NAN, f64::NAN, f64::NAN),
        }
    };
    let mut mesh = Vec::new();
    for &n in ladder.lg {
        pb.set_message(format!("LG {n}"));
        let s = solve_qc(n, Scheme::Lg, None, None, iters)?;
        let mut row = mesh_row("LG", n, 1, s, &ref_sol, iters);
        (
            row.presented_rel_error,
            row.presented_objective,
            row.presented_seconds,
        ) = at_presented(n, Scheme::Lg);
        mesh.push(row);
        pb.inc(1);
    }
    for &e in ladder.radau {
        let n = e * RADAU_POINTS_PER_ELEMENT;
        pb.set_message(format!("Radau {e} elements"));
        let s = solve_qc(n, Scheme::Radau { elements: e }, None, None, iters)?;
        let mut row = mesh_row("Radau", n, e, s, &ref_sol, iters);
        (
            row.presented_rel_error,
            row.presented_objective,
            row.presented_seconds,
        ) = at_presented(n, Scheme::Radau { elements: e });
        mesh.push(row);
        pb.inc(1);
    }
    Ok((
        (ref_desc, ref_sol.objective, ref_seconds),
        presented_ref,
        mesh,
    ))
}

/// Refines `start` by hp refinement from `ladder.reference` until the largest element error
/// estimate is at most `ladder.reference_tol`: the cold reference solve (on that mesh), or
/// (`presented`) the presented optimum, interpolated onto it. Returns the refined solution and
/// its description with the error estimates. A refinement that fails or does not reach the
/// tolerance is stated as such (the reference is then the best mesh reached).
fn converged_reference(
    ladder: &MeshLadder,
    start: OcpSolution,
    presented: bool,
) -> Result<(OcpSolution, String)> {
    let (el, pe) = ladder.reference;
    let (j_start, period_start) = (start.objective, start.period);
    let settings = ProblemSettings {
        points: el * pe,
        scheme: Scheme::Radau { elements: el },
        max_iter: 1500,
        ..ProblemSettings::default()
    };
    // From Radau 10 × 6, periodic-qc needs about 14 rounds to reach 1e-8.
    let opts = RefineSettings {
        tol: ladder.reference_tol,
        max_rounds: 16,
        ..RefineSettings::default()
    };
    let (sol, desc) = match refine_solution(
        Problem::PeriodicQc,
        &settings,
        start.clone(),
        &opts,
        None,
        None,
    ) {
        Ok((_, sol)) => {
            let desc = match &sol.refinement {
                Some(rr) => {
                    let points: usize = rr
                        .mesh
                        .iter()
                        .map(|m| m.degrees.iter().sum::<usize>())
                        .sum();
                    let elements: usize = rr.mesh.iter().map(|m| m.degrees.len()).sum();
                    let est = rr.errors.iter().flatten().copied().fold(0.0, f64::max);
                    let ok: Vec<f64> = rr
                        .history
                        .iter()
                        .filter(|h| h.status.is_success())
                        .map(|h| h.objective)
                        .collect();
                    // The largest change of J over the last three rounds: J creeps by
                    // ~1e-8 per round near the tolerance, so one round can understate it.
                    let dj = match ok.last() {
                        Some(last) if ok.len() >= 2 => {
                            let d = ok[ok.len().saturating_sub(4)..]
                                .windows(2)
                                .map(|w| (w[1] - w[0]).abs())
                                .fold(0.0, f64::max);
                            format!("{:.1e}", d / last.abs())
                        }
                        _ => "not available (one round)".to_string(),
                    };
                    let origin = if presented {
                        format!(
                            "the presented optimum (J = {j_start:.8} on its own mesh) \
                                 warm-started on "
                        )
                    } else {
                        String::new()
                    };
                    let unrefined = if presented {
                        String::new()
                    } else {
                        format!(
                            "the unrefined {el} × {pe} mesh gives J = {j_start:.8} with \
                             period {period_start:.4} s; refined, "
                        )
                    };
                    format!(
                        "{origin}Radau {el} × {pe} refined by hp rounds to {elements} elements, \
                         {points} points over the phases ({}; largest element error \
                         estimate {est:.1e}, tolerance {:.0e}; largest relative change of J \
                         in the last rounds {dj}, the estimated error of J_ref; \
                         {unrefined}period {:.4} s)",
                        if rr.converged {
                            "converged"
                        } else {
                            "NOT converged"
                        },
                        ladder.reference_tol,
                        sol.period
                    )
                }
                None => format!("Radau {el} × {pe} (no refinement record)"),
            };
            (sol, desc)
        }
        Err(e) => {
            let desc = format!(
                "Radau {el} × {pe}, NOT refined (refinement failed: {e}; period {:.4} s)",
                start.period
            );
            (start, desc)
        }
    };
    Ok((sol, desc))
}

/// Whether `sol` is on the local optimum of `reference`: the period within 10 % and every phase
/// duration within 10 % of its own value plus 1 % of the period. The period alone does not tell
/// neighbouring optima apart: the presented periodic-qc optimum (stick phase 26 ms, period
/// 0.620 s) and its neighbour with the stick phase on its 0.01 s bound (period 0.604 s) differ
/// by 2.5 % in the period but by 60 % in the stick phase.
fn same_branch(sol: &OcpSolution, reference: &OcpSolution) -> bool {
    let close = |a: f64, b: f64, slack: f64| (a - b).abs() <= 0.1 * b.abs() + slack;
    close(sol.period, reference.period, 0.0)
        && sol.phase_durations.len() == reference.phase_durations.len()
        && sol
            .phase_durations
            .iter()
            .zip(&reference.phase_durations)
            .all(|(&d, &d_ref)| close(d, d_ref, 0.01 * reference.period.abs()))
}

/// The row of cold solve `s` on a mesh, with the warm re-solve from `reference` when the cold
/// one is on another local optimum.
fn mesh_row(
    scheme: &str,
    points: usize,
    elements: usize,
    s: Solved,
    reference: &OcpSolution,
    iters: usize,
) -> MeshRow {
    let j_ref = reference.objective;
    let nlp_scheme = if scheme == "LG" {
        Scheme::Lg
    } else {
        Scheme::Radau { elements }
    };
    let (solved, objective, period, iterations) = match &s.sol {
        Some(sol) => (true, sol.objective, sol.period, sol.iterations),
        None => (false, f64::NAN, f64::NAN, 0),
    };
    let branch = s
        .sol
        .as_ref()
        .is_some_and(|sol| same_branch(sol, reference));
    let (warm_rel_error, warm_seconds) = if branch {
        (f64::NAN, f64::NAN)
    } else {
        match solve_qc(points, nlp_scheme, None, Some(reference), iters) {
            Ok(Solved {
                sol: Some(w),
                seconds,
            }) if same_branch(&w, reference) => {
                ((w.objective - j_ref).abs() / j_ref.abs(), seconds)
            }
            _ => (f64::NAN, f64::NAN),
        }
    };
    MeshRow {
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
        presented_rel_error: f64::NAN,
        presented_objective: f64::NAN,
        presented_seconds: f64::NAN,
    }
}

/// The Markdown of study (b1) and its figure `sa_mesh`.
pub(super) fn section(
    reference: &(String, f64, f64),
    presented: Option<&PresentedReference>,
    rows: &[MeshRow],
    quick: bool,
    fig_dir: &Path,
) -> Result<String> {
    let mut md = String::new();
    let (ref_name, ref_j, ref_s) = reference;
    // The periods the cold solves ended at, once each within 5 %: the local optima they found.
    let mut periods: Vec<f64> = Vec::new();
    for r in rows.iter().filter(|r| r.solved && r.period.is_finite()) {
        if !periods.iter().any(|p| (p - r.period).abs() <= 0.05 * p) {
            periods.push(r.period);
        }
    }
    let periods: Vec<String> = periods.iter().map(|p| format!("{p:.2} s")).collect();
    let _ = writeln!(
        md,
        "### (b) Optimisation: mesh and smoothing\n\n\
         `periodic-qc` (Sect. 6.1), cold solves (default guess strategy, iteration cap {} \
         per stage). Objective error against the reference: {ref_name}: J_ref = \
         {ref_j:.8}, solved and refined in {ref_s:.2} s. The problem has several local optima \
         and a cold start lands on one depending on the mesh (the cold solves below end at \
         periods of {}); a cold solution on another optimum than the reference's (another \
         period or phase durations, by more than 10 %) is re-solved on the same mesh \
         warm-started from the reference solution, which gives the mesh's discretisation \
         error at the reference's optimum (column \"warm\"). Neighbouring optima of nearly \
         the same shape pass that test, so an error far above its neighbours' may be the gap \
         to such an optimum rather than the mesh's.\n",
        max_iter(quick),
        periods.join(", ")
    );
    match presented {
        Some(p) => {
            // `--quick` presents its own cold solve, the full run the default search's optimum.
            let origin = if quick {
                "the cold solve of section 4 (`--quick`)"
            } else {
                "the default search's `periodic-qc` optimum"
            };
            let which = if p.same_as_cold {
                format!("The optimum this report presents, {origin}, is the cold reference's")
            } else {
                format!("The cold optimum is not the one this report presents: {origin}")
            };
            let _ = write!(
                md,
                "{which} (J = {:.8}, period {:.4} s). Columns \"presented\" measure the \
                 discretisation error there: every mesh solved warm-started from it, against its \
                 own reference: {}: J_ref,p = {:.8}, refined in {:.2} s. A warm solve that leaves \
                 that optimum (its period or a phase duration off by more than 10 %) shows \
                 \"—\".",
                p.presented_objective, p.presented_period, p.description, p.objective, p.seconds
            );
            if p.stick_on_bound {
                md.push_str(
                    " Its stick phase sits on its lower bound, and errors of some 1e-7 are its \
                     floor: warm solves on meshes finer than J_ref,p's differ from it by 2e-8 to \
                     1e-6 without falling as the mesh grows, so the column does not rank meshes \
                     below that, whatever the refinement's own estimate says.",
                );
            }
            md.push_str("\n\n");
        }
        None => md.push_str(
            "No presented optimum was given to this run (`report speed-accuracy` measures the \
             cold optimum only; `paper` adds the optimum its scenarios present).\n\n",
        ),
    }
    md.push_str(&table(rows, presented.is_some()));
    // One set per scheme and measurement: (solve time, error) of the rows that have it. Meshes
    // of one scheme are separate solves that may land on different local optima: labelled
    // markers, not a line.
    let set = |scheme: &str, name: String, pick: &dyn Fn(&MeshRow) -> Option<(f64, f64)>| {
        let kept: Vec<(&MeshRow, (f64, f64))> = rows
            .iter()
            .filter(|r| r.scheme == scheme)
            .filter_map(|r| pick(r).map(|v| (r, v)))
            .collect();
        WorkPrecisionSet {
            name,
            time_s: kept.iter().map(|(_, v)| v.0).collect(),
            error: kept.iter().map(|(_, v)| v.1).collect(),
            labels: kept
                .iter()
                .map(|(r, _)| format!("{}×{}", r.points, r.elements))
                .collect(),
            joined: false,
        }
    };
    let mut methods: Vec<WorkPrecisionSet> = Vec::new();
    for s in ["LG", "Radau"] {
        methods.push(set(s, format!("{s}, cold"), &|r| {
            r.same_branch.then_some((r.seconds, r.rel_error))
        }));
        methods.push(set(s, format!("{s}, warm from the cold reference"), &|r| {
            r.warm_rel_error
                .is_finite()
                .then_some((r.warm_seconds, r.warm_rel_error))
        }));
        if presented.is_some() {
            methods.push(set(
                s,
                format!("{s}, at the presented optimum (vs J_ref,p)"),
                &|r| {
                    r.presented_rel_error
                        .is_finite()
                        .then_some((r.presented_seconds, r.presented_rel_error))
                },
            ));
        }
    }
    if methods.iter().any(|m| !m.error.is_empty()) {
        let fig = wp_figure(
            if presented.is_some() {
                "periodic-qc: objective error vs solve time (cold and presented optima)"
            } else {
                "periodic-qc: objective error vs solve time (cold optima)"
            },
            "|J − J_ref| / |J_ref|",
            &methods,
        )?;
        bf_plot::render(&fig, fig_dir.join("sa_mesh"))?;
        md.push_str("\n![objective error vs solve time](figures/sa_mesh.svg)\n\n");
    } else {
        md.push_str("\nNo mesh solved on the reference's optimum: no figure.\n\n");
    }
    Ok(md)
}

/// The mesh table; the three columns at the presented optimum only where one was given
/// (`presented`): without it they would hold nothing but "—".
fn table(rows: &[MeshRow], presented: bool) -> String {
    let mut md = String::from(
        "| scheme | points/phase | elements | status | cold: J | cold: period (s) | cold: rel. error of J (vs J_ref) | cold: solve (s) | iterations | warm from the cold reference: rel. error of J | warm: solve (s) |",
    );
    if presented {
        md.push_str(
            " presented: J | presented: rel. error of J (vs J_ref,p) | presented: solve (s) |",
        );
    }
    md.push_str(if presented {
        "\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    } else {
        "\n|---|---|---|---|---|---|---|---|---|---|---|\n"
    });
    for r in rows {
        let _ = write!(
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
            finite_or_dash(r.warm_seconds, 2),
        );
        if presented {
            let _ = write!(
                md,
                " {} | {} | {} |",
                finite_or_dash(r.presented_objective, 8),
                if r.presented_rel_error.is_finite() {
                    format!("{:.2e}", r.presented_rel_error)
                } else {
                    "—".into()
                },
                finite_or_dash(r.presented_seconds, 2),
            );
        }
        md.push('\n');
    }
    md
}

/// `v` with `digits` decimals, or "—" when it is not finite (no such solve).
fn finite_or_dash(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "—".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(presented: f64) -> MeshRow {
        MeshRow {
            scheme: "Radau".into(),
            points: 10,
            elements: 2,
            solved: true,
            objective: 0.5,
            period: 2.5,
            same_branch: true,
            rel_error: 1e-3,
            seconds: 0.1,
            iterations: 90,
            warm_rel_error: f64::NAN,
            warm_seconds: f64::NAN,
            presented_rel_error: presented,
            presented_objective: 0.0876,
            presented_seconds: 0.02,
        }
    }

    /// Without a presented optimum the table has no presented columns (they would be all
    /// "—"); with one, every row has them.
    #[test]
    fn the_presented_columns_appear_only_with_a_presented_optimum() {
        let cells = |md: &str| -> Vec<usize> {
            md.lines()
                .filter(|l| l.starts_with('|'))
                .map(|l| l.matches('|').count() - 1)
                .collect()
        };
        let alone = table(&[row(f64::NAN)], false);
        assert!(!alone.contains("presented"), "{alone}");
        assert!(cells(&alone).iter().all(|&n| n == 11), "{alone}");
        let with = table(&[row(1.3e-6)], true);
        assert!(with.contains("presented: rel. error of J"), "{with}");
        assert!(cells(&with).iter().all(|&n| n == 14), "{with}");
        assert!(with.contains("| 0.08760000 | 1.30e-6 | 0.02 |"), "{with}");
    }
}
