//! The filter of the line search (W&B Sect. 2.3 and 3.3): the set of (θ, φ_μ) pairs a trial
//! point must improve on (eq. (18)), its margins γ_θ, γ_φ (eq. (21)), the bounds θ_max (trial
//! points above it are rejected) and θ_min (below it the switching rule and the Armijo test
//! apply), and Ipopt's filter reset heuristic.

use crate::ipm::settings::Settings;

/// The filter and its reset bookkeeping, one per barrier run.
#[derive(Debug, Clone, Default)]
pub(super) struct Filter {
    /// Entries (θ, φ_μ), none dominating another.
    entries: Vec<(f64, f64)>,
    /// Trial points with θ above this are rejected (W&B Sect. 3.3: 1e4 max(1, θ₀)).
    pub theta_max: f64,
    /// Below this θ the switching rule and the Armijo test decide (1e-4 max(1, θ₀)).
    pub theta_min: f64,
    /// The last rejected trial point was blocked by the filter alone.
    blocked_last: bool,
    /// Consecutive accepted steps that followed such a rejection.
    blocked_run: usize,
    /// Resets so far in this solve.
    resets: usize,
}

impl Filter {
    /// θ_max and θ_min from the initial infeasibility θ₀ (W&B Sect. 3.3).
    pub fn set_bounds(&mut self, theta0: f64) {
        self.theta_max = 1e4 * theta0.max(1.0);
        self.theta_min = 1e-4 * theta0.max(1.0);
    }

    /// Whether (θ, φ) is acceptable to the filter: better in θ or in φ than every entry.
    pub fn acceptable(&self, theta: f64, phi: f64) -> bool {
        self.entries.iter().all(|&(ft, fp)| theta < ft || phi < fp)
    }

    /// Adds the point (θ, φ) with the margins of W&B eq. (21), removing entries it dominates.
    pub fn augment(&mut self, theta: f64, phi: f64, settings: &Settings) {
        let t = (1.0 - settings.line_search.gamma_theta) * theta;
        let p = phi - settings.line_search.gamma_phi * theta;
        self.entries.retain(|&(ft, fp)| !(ft >= t && fp >= p));
        self.entries.push((t, p));
    }

    /// Empties the filter (a new barrier problem, or a fallback of the μ rule).
    pub fn clear(&mut self) {
        self.entries.clear();
    }

    /// The entries (handed to the restoration phase, whose exit test uses them).
    pub fn entries(&self) -> &[(f64, f64)] {
        &self.entries
    }

    /// Records a rejected trial point: `by_filter_alone` when only the filter blocked it.
    pub fn note_rejection(&mut self, by_filter_alone: bool) {
        self.blocked_last = by_filter_alone;
    }

    /// Ipopt's filter reset heuristic, run on every accepted trial point before the filter is
    /// augmented: when the trial before it was blocked by the filter alone in
    /// `filter_reset_trigger` consecutive line searches, the filter is cleared (at most
    /// `max_filter_resets` times per solve). Entries from a distant part of the path (e.g. the
    /// first iterates of a warm start far from feasibility) can otherwise admit only steps
    /// that do not raise θ above them, which on curved constraints are ~1e-4 of the Newton
    /// step. Returns whether the filter was reset.
    pub fn note_accept(&mut self, settings: &Settings) -> bool {
        let mut reset = false;
        if self.resets < settings.line_search.max_filter_resets {
            if self.blocked_last {
                self.blocked_run += 1;
                if self.blocked_run >= settings.line_search.filter_reset_trigger {
                    self.entries.clear();
                    self.resets += 1;
                    self.blocked_run = 0;
                    reset = true;
                }
            } else {
                self.blocked_run = 0;
            }
        }
        self.blocked_last = false;
        reset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_dominate_with_margins_and_reset_after_the_trigger() {
        let settings = Settings::default();
        let mut f = Filter::default();
        f.set_bounds(0.5);
        assert_eq!((f.theta_max, f.theta_min), (1e4, 1e-4));
        f.augment(1.0, 2.0, &settings);
        // The entry sits at ((1 − γ_θ) θ, φ − γ_φ θ): the point itself is not acceptable,
        // one better in θ or φ beyond the margin is.
        assert!(!f.acceptable(1.0, 2.0));
        assert!(f.acceptable(0.99, 5.0) && f.acceptable(3.0, 1.9));
        // A new entry that dominates the old one replaces it.
        f.augment(0.5, 1.0, &settings);
        assert_eq!(f.entries().len(), 1);
        // Reset heuristic: `filter_reset_trigger` accepted steps, each after a rejection by
        // the filter alone, clear it; a plain rejection in between restarts the count.
        for k in 1..=settings.line_search.filter_reset_trigger {
            f.note_rejection(true);
            let reset = f.note_accept(&settings);
            assert_eq!(
                reset,
                k == settings.line_search.filter_reset_trigger,
                "step {k}"
            );
        }
        assert!(f.entries().is_empty());
        f.augment(0.5, 1.0, &settings);
        f.note_rejection(true);
        assert!(!f.note_accept(&settings));
        f.note_rejection(false);
        assert!(!f.note_accept(&settings));
        assert_eq!(f.entries().len(), 1);
    }
}
