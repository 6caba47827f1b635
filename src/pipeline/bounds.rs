//! The bounds an optimum sits on, as `optimize` prints them and `solution.json` records them
//! (`active_bounds`): phase durations, the period row, torque limits |τ_i| ≤ τ_max and joint
//! limits (eq. 60–65 of the paper's Sect. 4), and the inequality rows of the point constraints
//! (eq. 57c–d: the touch and lift-off rows on h, the apex height, the impulse's normal part and
//! cone, eq. 66).

use bf_optim::ocp::Ocp;
use bf_optim::terms::VarRef;
use bf_problem::OcpSolution;

pub use bf_problem::solution::records::ActiveBound;

/// Whether `v` is on bound `b`: within 1e-5 + 1e-4·|b|. An interior-point optimum approaches an
/// active bound to within about its tolerance (1e-8) over the multiplier, an inactive one stays
/// farther off; 1e-4 relative also covers the clamp of interpolated torques.
pub fn on_bound(v: f64, b: f64) -> bool {
    b.is_finite() && v.is_finite() && (v - b).abs() <= 1e-5 + 1e-4 * b.abs()
}

/// Whether the value `v` of a point constraint's row is on its bound `b`: within
/// 1e-7 + 1e-4·|b|. The rows come in their own units, some of them small (the impulse cone of
/// eq. 66 in N² s², about 1e-5 on the paper's taps), so the slack of [`on_bound`] would call
/// inactive rows active; an interior-point optimum leaves an active row within about its
/// tolerance (1e-8) of the bound.
pub fn on_point_bound(v: f64, b: f64) -> bool {
    b.is_finite() && v.is_finite() && (v - b).abs() <= 1e-7 + 1e-4 * b.abs()
}

/// The bounds among `quantities` = (what, samples, (lower, upper)) that some sample sits on
/// ([`on_bound`]), one entry per side (value: the sample nearest to the bound).
pub fn bound_hits(quantities: &[(String, Vec<f64>, (f64, f64))]) -> Vec<ActiveBound> {
    hits_within(quantities, on_bound)
}

/// [`bound_hits`] with the test `on` of a sample against a bound.
fn hits_within(
    quantities: &[(String, Vec<f64>, (f64, f64))],
    on: fn(f64, f64) -> bool,
) -> Vec<ActiveBound> {
    let mut out = Vec::new();
    for (what, values, (lo, hi)) in quantities {
        for (bound, lower) in [(*lo, true), (*hi, false)] {
            let hits: Vec<f64> = values.iter().copied().filter(|&v| on(v, bound)).collect();
            if let Some(&value) = hits
                .iter()
                .min_by(|a, b| (*a - bound).abs().total_cmp(&(*b - bound).abs()))
            {
                out.push(ActiveBound {
                    what: what.clone(),
                    value,
                    bound,
                    lower,
                    hits: hits.len(),
                    of: values.len(),
                });
            }
        }
    }
    out
}

/// The constraint rows of `ocp` on phase durations alone (point functions of one bounded row
/// whose variables are all durations): the phases each one reads, and its bounds. The period
/// row of the periodic problems reads every phase.
pub fn duration_rows(ocp: &Ocp) -> Vec<(Vec<usize>, (f64, f64))> {
    ocp.points
        .iter()
        .filter_map(|pf| {
            let phases: Option<Vec<usize>> = pf
                .vars
                .iter()
                .map(|(_, v)| match v {
                    VarRef::Duration(i) => Some(*i),
                    _ => None,
                })
                .collect();
            match (phases, pf.bounds.as_slice()) {
                (Some(ph), [b]) => Some((ph, *b)),
                _ => None,
            }
        })
        .collect()
}

/// The period row's bounds of `ocp` (the [`duration_rows`] entry that reads every phase);
/// `None` if it has none (`periodic-qc` without `ProblemSettings::period_bounds`).
pub fn period_row(ocp: &Ocp) -> Option<(f64, f64)> {
    let n = ocp.phases.len();
    duration_rows(ocp).into_iter().find_map(|(mut ph, b)| {
        ph.sort_unstable();
        ph.dedup();
        (ph.len() == n).then_some(b)
    })
}

/// The bounds of `ocp` that `sol` sits on: each phase's duration bounds, every constraint row
/// on phase durations alone (the period), the control bounds (torque limits, at the
/// collocation nodes) and the state bounds (joint limits, at the state points). Constraints
/// on other functions of the state (h(0) ≥ 0.3 r, contact conditions) are not listed: they
/// are equalities or hold by construction of the phase sequence.
pub fn active_bounds(ocp: &Ocp, sol: &OcpSolution) -> Vec<ActiveBound> {
    let nq = sol.dense.q.first().map_or(0, |q| q.len());
    let mode = |p: usize| {
        sol.modes
            .get(p)
            .map_or("?".to_string(), |m| crate::names::name(m).to_lowercase())
    };
    let mut q: Vec<(String, Vec<f64>, (f64, f64))> = Vec::new();
    for (p, (ph, d)) in ocp.phases.iter().zip(&sol.phase_durations).enumerate() {
        q.push((
            format!("phase {} ({}) duration (s)", p + 1, mode(p)),
            vec![*d],
            ph.duration_bounds,
        ));
    }
    for (ph, b) in duration_rows(ocp) {
        let sum = ph
            .iter()
            .map(|&i| sol.phase_durations.get(i).copied().unwrap_or(f64::NAN))
            .sum::<f64>();
        let what = if ph.len() == sol.phase_durations.len() {
            "period (s)".to_string()
        } else {
            let phases: Vec<String> = ph.iter().map(|i| (i + 1).to_string()).collect();
            format!("sum of the durations of phases {} (s)", phases.join(", "))
        };
        q.push((what, vec![sum], b));
    }
    for (p, (ph, tr)) in ocp.phases.iter().zip(&sol.raw).enumerate() {
        for (i, b) in ph.u_bounds.iter().enumerate() {
            let v: Vec<f64> = tr.u.iter().filter_map(|u| u.get(i).copied()).collect();
            q.push((format!("τ{} in phase {} (N m)", i + 1, p + 1), v, *b));
        }
        for (i, b) in ph.x_bounds.iter().enumerate().take(nq) {
            let v: Vec<f64> = tr.x.iter().filter_map(|x| x.get(i).copied()).collect();
            q.push((format!("q{} in phase {} (rad)", i + 1, p + 1), v, *b));
        }
    }
    let mut out = bound_hits(&q);
    out.extend(hits_within(&point_rows(ocp, sol), on_point_bound));
    out
}

/// The inequality rows of `ocp`'s point constraints at `sol` (what, its value, its bounds): each
/// point function evaluated at the solution's phase end points, durations and parameters,
/// which do not depend on the mesh (so a candidate on a refined mesh of the problem is
/// evaluated alike). A row is named by its point function and its own name
/// (`PointFunction::row_names`), or its row counted from 1 where the function has several
/// and names none. Equality rows, and the duration rows that [`active_bounds`]
/// names as the period, are left out; so is a function that reads a value the solution does
/// not have.
fn point_rows(ocp: &Ocp, sol: &OcpSolution) -> Vec<(String, Vec<f64>, (f64, f64))> {
    let mut out = Vec::new();
    for pf in &ocp.points {
        let inequality = pf.bounds.iter().any(|(lo, hi)| lo < hi);
        let durations = pf
            .vars
            .iter()
            .all(|(_, v)| matches!(v, VarRef::Duration(_)));
        if !inequality || durations {
            continue;
        }
        let value = |v: &VarRef| -> Option<f64> {
            match *v {
                VarRef::Initial { phase, i } => sol.raw.get(phase)?.x.first()?.get(i).copied(),
                VarRef::Final { phase, i } => sol.raw.get(phase)?.x.last()?.get(i).copied(),
                VarRef::Duration(p) => sol.phase_durations.get(p).copied(),
                VarRef::Param(i) => sol.params.get(i).copied(),
            }
        };
        let len = pf
            .vars
            .iter()
            .map(|(k, _)| *k)
            .chain(pf.fixed.iter().map(|(k, _)| *k))
            .max()
            .map_or(0, |k| k as usize + 1);
        let mut vars = vec![0.0; len];
        let mut complete = true;
        for (k, v) in &pf.vars {
            match value(v) {
                Some(x) => vars[*k as usize] = x,
                None => complete = false,
            }
        }
        if !complete {
            continue;
        }
        for &(k, x) in &pf.fixed {
            vars[k as usize] = x;
        }
        let values = bf_codegen::interp::eval(&pf.graph, &pf.outputs, &vars);
        let rows = pf.bounds.len();
        for (r, (&v, &(lo, hi))) in values.iter().zip(&pf.bounds).enumerate() {
            if lo < hi {
                let what = match pf.row_names.get(r).filter(|n| !n.is_empty()) {
                    Some(row) => format!("{}: {row}", pf.name),
                    None if rows > 1 => format!("{}, row {}", pf.name, r + 1),
                    None => pf.name.clone(),
                };
                out.push((what, vec![v], (lo, hi)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bound_hits_find_the_sides_a_solution_sits_on() {
        let q = vec![
            ("stick".to_string(), vec![0.010_000_1], (0.01, 5.0)),
            ("free".to_string(), vec![1.3], (0.01, 5.0)),
            ("period".to_string(), vec![9.9999], (0.0, 10.0)),
            (
                "τ1".to_string(),
                vec![-1.0, 0.2, 0.99999, 1.0, 0.5],
                (-1.0, 1.0),
            ),
            ("q2".to_string(), vec![0.0, 0.3], (0.0, f64::INFINITY)),
        ];
        let a = bound_hits(&q);
        let d: Vec<(&str, bool, usize)> = a
            .iter()
            .map(|a| (a.what.as_str(), a.lower, a.hits))
            .collect();
        assert_eq!(
            d,
            vec![
                ("stick", true, 1),
                ("period", false, 1),
                ("τ1", true, 1),
                ("τ1", false, 2),
                ("q2", true, 1)
            ]
        );
        assert!(a[3].describe().contains("at 2 of 5 nodes"));
        // 1e-3 from a 10 s bound is off it; NaN is never on a bound.
        assert!(!on_bound(9.998, 10.0) && !on_bound(f64::NAN, 1.0));
    }
}
