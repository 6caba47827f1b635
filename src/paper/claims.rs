//! The claims of the paper's Sect. 6.1 checked against this run's optima, each with a verdict
//! and, where it differs, a paragraph saying why (which optimum, which bound, which modelling
//! choice) and what would change it. The bounds each optimum sits on come from
//! [`active_bounds`](crate::pipeline::bounds::active_bounds).
//!
//! | item | paper |
//! |---|---|
//! | [`claims`]: QC mean ω vs ω_ref, QC on the friction-cone boundary (eq. 18), QC fingertip contact (eq. 3), QC vs COT period, COT contact on the link side, human fingertip contact, robotic vs human COT | Sect. 6.1, Fig. 5–16 |

use std::fmt::Write as _;

use crate::pipeline::bounds::ActiveBound;

/// The longer minimum stick duration of the `--min-stick` comparison (s): defined here, where
/// claim 2's explanation points to it, so that the comparison (`report::min_stick`, which
/// reads the scenarios, which read these claims) can use it without a cycle.
pub const LONG_MIN_STICK: f64 = 0.1;

/// What the claims need to know of one scenario's optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct Facts {
    /// Problem name (`periodic-cot`, `periodic-cot-human`, `periodic-qc`).
    pub name: String,
    /// Whether the optimum passed its re-integration check.
    pub verified: bool,
    /// Objective φ.
    pub objective: f64,
    /// Period (s).
    pub period: f64,
    /// Mean ω_z over the period (rad/s).
    pub mean_omega_z: f64,
    /// Share of contact samples on the friction-cone boundary.
    pub cone_share: f64,
    /// Duration of the stick phase (s; NaN without one).
    pub stick_duration: f64,
    /// Contact point's distance from the fingertip during contact (m): min, mean, max.
    pub from_tip: (f64, f64, f64),
    /// The bounds the optimum sits on.
    pub active: Vec<ActiveBound>,
}

/// One claim of the paper with its verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    /// The claim, as the paper makes it.
    pub claim: String,
    /// What this reproduction finds.
    pub here: String,
    /// Whether it agrees.
    pub agrees: bool,
    /// Scenarios it rests on that failed their re-integration check.
    pub unverified: Vec<String>,
    /// Where it differs: why (which optimum, bound, modelling choice) and what would change
    /// it. Empty where it agrees.
    pub why: String,
}

/// Contact at most this far from the fingertip (m) counts as fingertip contact (2 % of the
/// 1 m ball radius; the smooth saturation's ε = 0.01 moves the contact point by ≤ ε/2).
pub const TIP_CONTACT: f64 = 0.02;

/// Share of contact samples on the friction-cone boundary above which the cone counts as
/// "always active".
pub const ALWAYS_ON_CONE: f64 = 0.9;

/// The QC mean ω_z agrees with ω_ref when within this fraction of it.
pub const OMEGA_REF_MATCH: f64 = 0.1;

fn active_list(f: &Facts) -> String {
    if f.active.is_empty() {
        format!("the {} optimum sits on none of its bounds", f.name)
    } else {
        format!(
            "the {} optimum sits on: {}",
            f.name,
            f.active
                .iter()
                .map(ActiveBound::describe)
                .collect::<Vec<_>>()
                .join("; ")
        )
    }
}

/// The lower bound of the stick phase's duration (s) when the optimum sits on it.
fn stick_minimum(f: &Facts) -> Option<f64> {
    f.active
        .iter()
        .find(|a| a.lower && a.what.contains("(stick) duration"))
        .map(|a| a.bound)
}

fn claim(claim: &str, here: String, agrees: bool, on: &[&Facts], why: String) -> Claim {
    Claim {
        claim: claim.into(),
        here,
        agrees,
        unverified: on
            .iter()
            .filter(|f| !f.verified)
            .map(|f| f.name.clone())
            .collect(),
        why: if agrees { String::new() } else { why },
    }
}

/// The claims of Sect. 6.1 that `facts` (one per solved scenario) can decide, in the paper's
/// order; `omega_ref_z` is QC's reference ω_z (rad/s).
pub fn claims(facts: &[Facts], omega_ref_z: f64) -> Vec<Claim> {
    let get = |n: &str| facts.iter().find(|f| f.name == n);
    let mut out = Vec::new();
    let search = "The problems have many local optima (section 4): this is the optimum this \
                  run's search reached, not necessarily the one the paper shows";
    if let Some(qc) = get("periodic-qc") {
        let wz = qc.mean_omega_z;
        let rel = (wz - omega_ref_z) / omega_ref_z;
        out.push(claim(
            &format!("QC: the average angular velocity matches ω_ref = (0, 0, {omega_ref_z})"),
            format!(
                "mean ω_z = {wz:.3} rad/s ({:+.1} %; a match: within ±{:.0} %)",
                100.0 * rel,
                100.0 * OMEGA_REF_MATCH
            ),
            rel.abs() < OMEGA_REF_MATCH,
            &[qc],
            format!(
                "The QC objective (eq. 64–65) weighs the deviation from ω_ref against the torque \
                 effort, so its optimum trades one for the other: the mean ω_z is {:+.1} % off \
                 ω_ref. {search}; {}. A heavier weight on the ω term (smaller \
                 `--effort-scale`) or an equality on the mean ω would pull it to ω_ref.",
                100.0 * rel,
                active_list(qc)
            ),
        ));
        // What the stick phase is, and whether the longer bound compared in the report could
        // change it, from this optimum's numbers: a sentence that holds for each.
        let stick = match stick_minimum(qc) {
            Some(b) if b < LONG_MIN_STICK => format!(
                "Its stick phase sits on its lower bound ({b} s), the shortest contact the \
                 problem allows; whether a longer one pushes against the cone is what the run \
                 with `--min-stick {LONG_MIN_STICK}` below measures."
            ),
            Some(b) => format!(
                "Its stick phase sits on its lower bound ({b} s), and the tangential force \
                 stays inside the cone for part of it."
            ),
            None => format!(
                "Its stick phase ({:.3} s) is longer than its lower bound, and the tangential \
                 force stays inside the cone for part of it.",
                qc.stick_duration
            ),
        };
        out.push(claim(
            "QC: the friction-cone constraint is always active during contact",
            format!(
                "{:.0} % of the contact samples on the boundary (always: > {:.0} %)",
                100.0 * qc.cone_share,
                100.0 * ALWAYS_ON_CONE
            ),
            qc.cone_share > ALWAYS_ON_CONE,
            &[qc],
            format!(
                "Only {:.0} % of the contact samples of the QC optimum lie on the cone boundary \
                 (‖λ_∥‖ ≥ 0.99 μ_s λ_n). {stick} {search}; {}.",
                100.0 * qc.cone_share,
                active_list(qc)
            ),
        ));
        out.push(claim(
            "QC: only the fingertip is used",
            format!(
                "contact point at most {:.3} m from the tip (tip: ≤ {TIP_CONTACT} m)",
                qc.from_tip.2
            ),
            qc.from_tip.2 < TIP_CONTACT,
            &[qc],
            format!(
                "The QC optimum touches the ball up to {:.3} m from the fingertip (tip contact: \
                 ≤ {TIP_CONTACT} m). The contact point is free along the last link (eq. 3, \
                 smooth saturation eq. 58–59), and this optimum rolls the link over the ball. \
                 {search}; {}. Bounding the contact parameter α to the tip would exclude it; \
                 whether φ then rises decides which is the better optimum.",
                qc.from_tip.2,
                active_list(qc)
            ),
        ));
        if let Some(cot) = get("periodic-cot") {
            out.push(claim(
                "QC period shorter than the COT period",
                format!("{:.3} s vs {:.3} s", qc.period, cot.period),
                qc.period < cot.period,
                &[qc, cot],
                format!(
                    "The QC period ({:.3} s) is not shorter than the COT period ({:.3} s). COT \
                     lets the finger rest at no cost, so its period grows to its bound when \
                     resting is cheap; QC pays for effort per unit time. {search}; {}; {}. \
                     A different COT period bound (here 10 s) or another QC optimum would \
                     change the order.",
                    qc.period,
                    cot.period,
                    active_list(qc),
                    active_list(cot)
                ),
            ));
        }
    }
    if let Some(cot) = get("periodic-cot") {
        out.push(claim(
            "COT, robotic finger: the contact point lies on the side of the link",
            format!(
                "contact point {:.3}–{:.3} m from the tip, mean {:.3} m (side: mean > \
                 {TIP_CONTACT} m)",
                cot.from_tip.0, cot.from_tip.2, cot.from_tip.1
            ),
            cot.from_tip.1 > TIP_CONTACT,
            &[cot],
            format!(
                "The robotic-finger COT optimum touches the ball at the fingertip (mean {:.3} m \
                 from it, side contact: > {TIP_CONTACT} m), where the paper's touches with the \
                 side of the last link. Nothing in the model prefers the tip: the contact point \
                 is free along the link (eq. 3, 58–59), and both kinds of contact are feasible; \
                 they are different local optima of a nonconvex problem. {search}; {}. A \
                 search started from a side-contact guess (contact parameter α away from the \
                 tip) would find a side-contact optimum, and its φ compared with this one's \
                 ({:.4e}) decides which the global optimum is.",
                cot.from_tip.1,
                active_list(cot),
                cot.objective
            ),
        ));
    }
    if let Some(h) = get("periodic-cot-human") {
        out.push(claim(
            "COT, human finger: touches with the fingertip only",
            format!(
                "contact point at most {:.3} m from the tip (tip: ≤ {TIP_CONTACT} m)",
                h.from_tip.2
            ),
            h.from_tip.2 < TIP_CONTACT,
            &[h],
            format!(
                "The human-finger COT optimum touches the ball up to {:.3} m from the tip (tip \
                 contact: ≤ {TIP_CONTACT} m). The joint limits q2, q3 ≥ 0 keep the finger from \
                 folding back but do not pin the contact point to the tip. {search}; {}. A \
                 search from a tip-contact guess would show whether a tip optimum with lower \
                 φ exists.",
                h.from_tip.2,
                active_list(h)
            ),
        ));
        if let Some(cot) = get("periodic-cot") {
            out.push(claim(
                "the robotic finger rotates the ball more efficiently (lower COT)",
                format!(
                    "φ = {:.4e} (robotic) vs {:.4e} (human)",
                    cot.objective, h.objective
                ),
                cot.objective < h.objective,
                &[cot, h],
                format!(
                    "The human finger is the robotic one with the joint limits q2, q3 ≥ 0 \
                     (scenes/human.toml), so every human-finger motion is feasible for the \
                     robotic finger too and the robotic global optimum cannot be worse. Here \
                     the robotic φ = {:.4e} is not below the human φ = {:.4e}: the robotic \
                     search ended in a worse local optimum. {}; {}. Starting the robotic \
                     search from the human optimum (`optimize --warm-start`) gives a robotic φ \
                     at most the human one.",
                    cot.objective,
                    h.objective,
                    active_list(cot),
                    active_list(h)
                ),
            ));
        }
    }
    out
}

/// The claims as a table (claim, this reproduction, verdict) followed by one paragraph per
/// claim that differs, numbered like the table rows.
pub fn markdown(claims: &[Claim]) -> String {
    let mut s =
        String::from("| # | claim (paper) | this reproduction | verdict |\n|---|---|---|---|\n");
    for (i, c) in claims.iter().enumerate() {
        let v = if c.agrees { "agrees" } else { "differs" };
        let v = if c.unverified.is_empty() {
            v.to_string()
        } else {
            format!("{v} (**unverified**: {})", c.unverified.join(", "))
        };
        let _ = writeln!(s, "| {} | {} | {} | {v} |", i + 1, c.claim, c.here);
    }
    let differs: Vec<(usize, &Claim)> = claims
        .iter()
        .enumerate()
        .filter(|(_, c)| !c.agrees)
        .collect();
    if !differs.is_empty() {
        s.push_str("\nWhere it differs, why, and what would change it:\n\n");
        for (i, c) in differs {
            let _ = writeln!(s, "- **Claim {}** ({}): {}\n", i + 1, c.claim, c.why);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(name: &str, objective: f64, period: f64, tip: f64, stick_min: bool) -> Facts {
        Facts {
            name: name.into(),
            verified: true,
            objective,
            period,
            mean_omega_z: 1.0,
            cone_share: 0.2,
            stick_duration: if stick_min { 0.01 } else { 0.3 },
            from_tip: (0.0, tip, tip),
            active: if stick_min {
                vec![ActiveBound {
                    what: "phase 2 (stick) duration (s)".into(),
                    value: 0.01,
                    bound: 0.01,
                    lower: true,
                    hits: 1,
                    of: 1,
                }]
            } else {
                vec![]
            },
        }
    }

    /// Every claim differs (QC off ω_ref, off the cone, side contact, longer period; COT tip
    /// contact; human side contact; robotic worse): each gets a paragraph in the markdown that
    /// names the optimum's active bounds, and none where the claim agrees.
    #[test]
    fn every_differing_claim_has_its_paragraph() {
        let all = [
            facts("periodic-qc", 1.0, 20.0, 0.5, true),
            facts("periodic-cot", 2.0, 10.0, 0.0, false),
            facts("periodic-cot-human", 1.0, 10.0, 0.5, false),
        ];
        let c = claims(&all, 2.2);
        assert_eq!(c.len(), 7);
        assert!(c.iter().all(|c| !c.agrees && !c.why.is_empty()));
        let md = markdown(&c);
        for (i, cl) in c.iter().enumerate() {
            let row = md
                .lines()
                .find(|l| l.starts_with(&format!("| {} |", i + 1)))
                .unwrap();
            assert!(row.contains("differs"), "{row}");
            let para = md
                .lines()
                .find(|l| l.starts_with(&format!("- **Claim {}**", i + 1)))
                .unwrap_or_else(|| panic!("claim {} has no paragraph:\n{md}", i + 1));
            assert!(para.contains(&cl.why));
        }
        // The QC paragraphs name the stick phase on its minimum.
        assert!(
            c[0].why
                .contains("phase 2 (stick) duration (s) = 0.010000 on its minimum")
        );
        assert!(c[1].why.contains("sits on its lower bound (0.01 s)"));
        assert!(c[1].why.contains("`--min-stick 0.1` below measures"));
        // Agreeing claims: no paragraph at all.
        let good = [
            Facts {
                mean_omega_z: 2.2,
                cone_share: 1.0,
                ..facts("periodic-qc", 1.0, 1.0, 0.0, false)
            },
            facts("periodic-cot", 1.0, 10.0, 0.5, false),
            facts("periodic-cot-human", 2.0, 10.0, 0.0, false),
        ];
        let c = claims(&good, 2.2);
        assert!(c.iter().all(|c| c.agrees && c.why.is_empty()), "{c:?}");
        assert!(!markdown(&c).contains("- **Claim"));
    }

    /// The verdict's thresholds are stated beside the numbers, and claim 2's explanation
    /// follows the optimum's stick phase: the comparison with the longer bound is pointed to
    /// only where the stick phase sits on a shorter bound, never for a stick phase that is
    /// already longer, nor for the run with the longer bound itself.
    #[test]
    fn the_text_follows_the_numbers() {
        let mut qc = facts("periodic-qc", 1.0, 2.6, 0.0, false);
        qc.mean_omega_z = 2.2 * (1.0 - 0.07);
        qc.stick_duration = 1.426;
        let c = claims(std::slice::from_ref(&qc), 2.2);
        assert!(c[0].agrees);
        assert!(
            c[0].here.contains("(-7.0 %; a match: within ±10 %)"),
            "{}",
            c[0].here
        );
        assert!(c[1].here.contains("(always: > 90 %)"), "{}", c[1].here);
        assert!(c[2].here.contains("(tip: ≤ 0.02 m)"), "{}", c[2].here);
        assert!(
            c[1].why
                .contains("Its stick phase (1.426 s) is longer than its lower bound")
        );
        assert!(!c[1].why.contains("--min-stick"), "{}", c[1].why);
        let mut long = facts("periodic-qc", 1.0, 0.65, 0.0, true);
        long.active[0].bound = LONG_MIN_STICK;
        long.active[0].value = LONG_MIN_STICK;
        let c = claims(&[long], 2.2);
        assert!(
            c[1].why.contains("sits on its lower bound (0.1 s)"),
            "{}",
            c[1].why
        );
        assert!(!c[1].why.contains("below measures"), "{}", c[1].why);
    }
}
