//! The impulse friction cone at the impact (eq. 66, the paper's Sect. 7), for the paper report.
//!
//! The sticking impact law (eq. 40) gives the finger whatever impulse ι stops the contact
//! point, and the paper's problems of Sect. 6.1 do not ask whether static friction can hold
//! it: ‖ι_∥‖ ≤ μ_s ι·n (eq. 66) is an option the paper discusses in Sect. 7 ("In our example
//! with the quadratic objective function … adding this constraint did not have a significant
//! effect on the solution. For the COT objective function, the velocity of the finger normal to
//! the ball was prior to the collision increased to ensure enough friction while the rest of
//! the variables were similar"). The section shows, for every optimum the report presents, the
//! planned impulse against the cone (the verification's [`ImpactCone`] records), and compares
//! the COT optimum with the one found with the cone imposed (`optimize --impulse-cone`),
//! choosing each sentence by the numbers:
//!
//! * [`cone_table`]: ι·n, ‖ι_∥‖, the friction ‖ι_∥‖ / ι·n the impulse needs, and the impact
//!   speed −n·v_c⁻ (eq. 36) per optimum; a row that needs more than μ_s is flagged;
//! * [`comparison`]: the two COT optima side by side, and whether the impact speed rose;
//! * [`qc_sentence`]: whether the QC optimum already meets the cone (then the constraint is
//!   inactive there, and the optimum is also one of the problem with the cone).

use std::fmt::Write as _;

use bf_problem::OcpSolution;
use bf_problem::solution::records::ImpactCone;

use crate::pipeline::verify::outside_impulse_cone;

/// Output subdirectory (of the report) of the COT run with the cone imposed.
pub const CONE_DIR: &str = "impulse-cone";

/// The first impact's cone record of `sol`'s verification, if it has one.
pub fn first_impact(sol: &OcpSolution) -> Option<&ImpactCone> {
    sol.verification.as_ref()?.impacts.first()
}

/// The friction an impulse needs, as a table cell.
fn friction_cell(c: &ImpactCone) -> String {
    let mu = c.friction_needed();
    if mu.is_finite() {
        format!("{mu:.3}")
    } else {
        "∞ (ι·n ≤ 0)".into()
    }
}

/// The table of the planned impulses of `rows` (label, solution) against the cone of `mu_s`;
/// a row whose impulse needs more friction than μ_s is marked ⚑ where its problem did not
/// impose the cone (the run's summary counts these through
/// [`crate::pipeline::verify::impulse_cone_warning`]) and **no** where it did.
pub fn cone_table(rows: &[(String, &OcpSolution)], mu_s: f64) -> String {
    let mut s = format!(
        "| optimum | impact law | cone imposed | impact speed −n·v_c⁻ (m/s) | ι·n (N s) | ‖ι_∥‖ (N s) | friction needed ‖ι_∥‖ / ι·n | within μ_s = {mu_s} |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for (label, sol) in rows {
        let Some(c) = first_impact(sol) else {
            let _ = writeln!(
                s,
                "| {label} | {} | {} | — | — | — | — | not re-integrated |",
                sol.impact_law.name(),
                yes_no(sol.impulse_cone)
            );
            continue;
        };
        let within = if !outside_impulse_cone(mu_s, c) {
            "yes"
        } else if c.imposed {
            "**no**"
        } else {
            "no ⚑"
        };
        let _ = writeln!(
            s,
            "| {label} | {} | {} | {:.4} | {:.3e} | {:.3e} | {} | {within} |",
            sol.impact_law.name(),
            yes_no(c.imposed),
            c.impact_speed,
            c.normal,
            c.tangential,
            friction_cell(c),
        );
    }
    s
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

/// What the comparison needs of one COT optimum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CotFacts {
    /// φ (eq. 61).
    pub objective: f64,
    /// Period (s).
    pub period: f64,
    /// Duration of the stick phase (s).
    pub stick: f64,
    /// ‖ω̄‖ over the period (rad/s).
    pub mean_omega: f64,
    /// The impact's record.
    pub impact: ImpactCone,
}

impl CotFacts {
    /// The facts of `sol`, `None` without a re-integrated impact.
    pub fn of(sol: &OcpSolution) -> Option<Self> {
        Some(CotFacts {
            objective: sol.objective,
            period: sol.period,
            stick: sol.stick_duration().unwrap_or(f64::NAN),
            mean_omega: sol.mean_omega.iter().map(|w| w * w).sum::<f64>().sqrt(),
            impact: *first_impact(sol)?,
        })
    }
}

/// Relative change from `a` to `b` in percent.
fn change(a: f64, b: f64) -> f64 {
    100.0 * (b - a) / a.abs()
}

/// The paragraph comparing the COT optimum without the cone (`free`) and with it (`imposed`),
/// each sentence chosen by their numbers: the change of φ, whether the free optimum already
/// met the cone, whether the impact speed rose (the paper's observation) and how much the other
/// variables moved.
pub fn comparison(free: &CotFacts, imposed: &CotFacts, mu_s: f64) -> String {
    let mut s = format!(
        "With the cone imposed, φ changes by {:+.1} % ({:.4e} against {:.4e}).",
        change(free.objective, imposed.objective),
        imposed.objective,
        free.objective
    );
    if !outside_impulse_cone(mu_s, &free.impact) {
        s += &format!(
            " The optimum without it already needs only μ = {} ≤ μ_s = {mu_s}: the cone \
             does not bind there, so it is also an optimum with the cone, and a different one \
             is another local optimum; the paper's remark on the impact speed is not tested \
             by this pair.",
            friction_cell(&free.impact)
        );
        return s;
    } else {
        s += &format!(
            " Without it, the impact needs μ = {} against μ_s = {mu_s}; with it, {}{}.",
            friction_cell(&free.impact),
            friction_cell(&imposed.impact),
            if (imposed.impact.friction_needed() - mu_s).abs() <= 1e-3 * mu_s {
                ", on the cone's boundary"
            } else {
                ""
            }
        );
    }
    let rose = imposed.impact.impact_speed > free.impact.impact_speed;
    s += &format!(
        " The contact point reaches the ball at {:.4} m/s instead of {:.4} m/s ({:+.0} %): {}",
        imposed.impact.impact_speed,
        free.impact.impact_speed,
        change(free.impact.impact_speed, imposed.impact.impact_speed),
        if rose {
            "the normal velocity before the collision increased, as the paper's Sect. 7 reports."
        } else {
            "the normal velocity before the collision did not increase, unlike what the paper's \
             Sect. 7 reports."
        }
    );
    s += &format!(
        " The period changes by {:+.1} % ({:.3} s against {:.3} s), the stick phase from \
         {:.1} ms to {:.1} ms, ‖ω̄‖ by {:+.1} %.",
        change(free.period, imposed.period),
        imposed.period,
        free.period,
        1e3 * free.stick,
        1e3 * imposed.stick,
        change(free.mean_omega, imposed.mean_omega)
    );
    s
}

/// The sentence on the QC optimum: within the cone (inactive there, so the QC optimum is also
/// a local optimum of QC with the cone, as the paper's "no significant effect") or not.
pub fn qc_sentence(qc: &ImpactCone, mu_s: f64) -> String {
    if outside_impulse_cone(mu_s, qc) {
        format!(
            "The QC optimum's impact needs μ = {} > μ_s = {mu_s}: imposing the cone would change \
             it, unlike the paper's QC example.",
            friction_cell(qc)
        )
    } else {
        format!(
            "The QC optimum's impact needs μ = {} ≤ μ_s = {mu_s}: the cone is inactive there, so \
             the optimum is also a local optimum of QC with the cone imposed, as the paper's \
             Sect. 7 found (\"did not have a significant effect\").",
            friction_cell(qc)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cone(normal: f64, tangential: f64, speed: f64, imposed: bool) -> ImpactCone {
        ImpactCone {
            phase: 0,
            impulse: [normal, tangential, 0.0],
            normal,
            tangential,
            margin: 0.8 * normal - tangential,
            impact_speed: speed,
            imposed,
        }
    }

    fn facts(objective: f64, impact: ImpactCone) -> CotFacts {
        CotFacts {
            objective,
            period: 4.0,
            stick: 0.01,
            mean_omega: 0.5,
            impact,
        }
    }

    /// The paragraph follows the numbers: an impulse that needs μ = 3 moved onto the cone by a
    /// faster impact is what the paper reports; a slower impact is said not to be; an optimum
    /// already inside the cone is said to be unbound by it.
    #[test]
    fn the_comparison_follows_the_optima() {
        let free = facts(8.0e-5, cone(1e-3, 3e-3, 0.1, false));
        let imposed = facts(8.8e-5, cone(5e-3, 4e-3, 0.2, true));
        let s = comparison(&free, &imposed, 0.8);
        assert!(
            s.starts_with("With the cone imposed, φ changes by +10.0 %"),
            "{s}"
        );
        assert!(
            s.contains("needs μ = 3.000 against μ_s = 0.8; with it, 0.800, on the cone's boundary"),
            "{s}"
        );
        assert!(
            s.contains("(+100 %): the normal velocity before the collision increased"),
            "{s}"
        );
        let slower = facts(8.8e-5, cone(5e-3, 2e-3, 0.05, true));
        let s = comparison(&free, &slower, 0.8);
        assert!(s.contains("did not increase"), "{s}");
        assert!(!s.contains("boundary"), "{s}");
        let inside = facts(8.0e-5, cone(1e-2, 1e-3, 0.1, false));
        let s = comparison(&inside, &imposed, 0.8);
        assert!(s.contains("does not bind there"), "{s}");
        assert!(!s.contains("as the paper's Sect. 7 reports"), "{s}");
    }

    /// A row outside the cone is flagged where its problem did not impose it and failed where it
    /// did; a row whose impulse does not push needs infinite friction.
    #[test]
    fn the_table_flags_the_impulses_outside_the_cone() {
        let mut a = crate::paper::stored::sticking_optimum(bf_problem::Problem::PeriodicCot)
            .unwrap()
            .solution()
            .unwrap();
        a.verification.as_mut().unwrap().impacts = vec![cone(1e-3, 3e-3, 0.1, false)];
        let mut b = a.clone();
        b.verification.as_mut().unwrap().impacts = vec![cone(5e-3, 4e-3, 0.2, true)];
        let mut c = a.clone();
        c.verification.as_mut().unwrap().impacts = vec![cone(-1e-9, 3e-3, 0.0, false)];
        let md = cone_table(&[("a".into(), &a), ("b".into(), &b), ("c".into(), &c)], 0.8);
        assert!(
            md.contains("| a | stick | no | 0.1000 | 1.000e-3 | 3.000e-3 | 3.000 | no ⚑ |"),
            "{md}"
        );
        assert!(
            md.contains("| b | stick | yes | 0.2000 | 5.000e-3 | 4.000e-3 | 0.800 | yes |"),
            "{md}"
        );
        assert!(
            md.contains("| c | stick | no | 0.0000 | -1.000e-9 | 3.000e-3 | ∞ (ι·n ≤ 0) | no ⚑ |"),
            "{md}"
        );
        let mut d = b.clone();
        d.verification.as_mut().unwrap().impacts = vec![cone(5e-3, 4.5e-3, 0.2, true)];
        let md = cone_table(&[("d".into(), &d)], 0.8);
        assert!(md.contains("| **no** |"), "{md}");
    }
}
