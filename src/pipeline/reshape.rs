//! The reshaping moves of the global search ([`super::global::Landscape::reshape`]) on the
//! periodic problems (free–stick–free, eq. 60–66): each move holds the phase durations of a
//! local optimum away from their values by bounds on the duration variables (the stick phase
//! longer or shorter, the period shorter or longer, time moved from one free phase to the
//! other), so that the solve from that optimum must leave its basin in that direction; the
//! search then releases the bounds ([`super::search`]).
//!
//! Why bounds and not perturbations: on `periodic-qc` a random scaling of the durations
//! re-solved from the optimum falls back into the optimum's basin, while the one transition
//! between basins that the searches had seen was the stick continuation (stick phase bounded
//! to ≥ 0.1 s, then released; BENCHMARKS.md, "Global search on a coarse mesh"). A bound is
//! that transition made systematic: every optimum is pushed in every direction of its shape.
//!
//! * [`MOVES`]: the moves, [`Move::bounds`] their duration bounds for an optimum's durations;
//! * [`with_duration_bounds`]: a built problem transcribed again with other duration bounds
//!   (the same NLP layout, so primal-dual warm starts carry over).

use bf_optim::ocp::{KernelUse, Transcription};
use bf_problem::{BuiltProblem, PhaseMode};

use super::error::PipelineError;

/// One reshaping move: the bounds it puts on the phase durations of a free–stick–free
/// optimum with durations (d₀, d_s, d₂).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Move {
    /// The stick phase at least max(`abs`, `factor`·d_s) long.
    StickAtLeast {
        /// Lower bound (s) at least.
        abs: f64,
        /// Multiple of the optimum's stick duration at least.
        factor: f64,
    },
    /// The stick phase at most d_s / `factor` long (a "tap" where the impact does the work).
    StickAtMost {
        /// Divisor of the optimum's stick duration.
        factor: f64,
    },
    /// Every phase at most d / `factor` long (`factor` > 1: a shorter period) or at least
    /// d / `factor` (`factor` < 1: a longer one).
    Period {
        /// Divisor of every duration.
        factor: f64,
    },
    /// The elbow flip: the last joint angle reflected, q'ₙ = −qₙ, and the one before it
    /// turned by it, q'ₙ₋₁ = qₙ₋₁ + qₙ (velocities alike), at every state point, the
    /// durations unbounded. For two parallel joints of equal length (the paper's finger) this
    /// is the other inverse-kinematics branch of the same fingertip path: the contact and
    /// periodicity rows stay satisfied and the solve starts from the other posture, which a
    /// time-scale perturbation never reaches (the `periodic-qc` optima below J 0.11 have
    /// q₃ < 0, those of the 0.155–0.177 basins q₃ > 0). On other chains it is an
    /// approximate flip that the solve repairs.
    ElbowFlip,
    /// The first free phase at least `factor`·d₀ and the second at most d₂ / `factor` long
    /// (time moved into the first free phase), or the reverse for `factor` < 1.
    Shift {
        /// Multiple of the first free phase's duration.
        factor: f64,
    },
}

/// The moves tried from every reshaped optimum, in this order (the move number is its index).
pub const MOVES: [Move; 10] = [
    Move::ElbowFlip,
    Move::StickAtLeast {
        abs: 0.05,
        factor: 2.0,
    },
    Move::StickAtLeast {
        abs: 0.15,
        factor: 4.0,
    },
    Move::StickAtMost { factor: 3.0 },
    Move::Period { factor: 1.25 },
    Move::Period { factor: 0.8 },
    Move::Period { factor: 1.6 },
    Move::Period { factor: 2.5 },
    Move::Shift { factor: 1.5 },
    Move::Shift { factor: 1.0 / 1.5 },
];

impl Move {
    /// The duration bounds of the move for an optimum with durations `d` in a problem with
    /// the duration bounds `within` and the phase modes `modes`, each bound kept inside
    /// `within`; `None` where the move does not apply (not a free–stick–free problem, or the
    /// bound would not move the optimum: e.g. a stick phase already on its lower bound
    /// cannot be shortened).
    pub fn bounds(
        &self,
        d: &[f64],
        within: &[(f64, f64)],
        modes: &[PhaseMode],
    ) -> Option<Vec<(f64, f64)>> {
        if modes != [PhaseMode::Free, PhaseMode::Stick, PhaseMode::Free]
            || d.len() != 3
            || within.len() != 3
            || d.iter().any(|x| !(x.is_finite() && *x > 0.0))
        {
            return None;
        }
        let mut b = within.to_vec();
        let at_least = |b: &mut Vec<(f64, f64)>, i: usize, v: f64| {
            b[i].0 = v.clamp(within[i].0, within[i].1);
        };
        let at_most = |b: &mut Vec<(f64, f64)>, i: usize, v: f64| {
            b[i].1 = v.clamp(within[i].0, within[i].1);
        };
        match *self {
            // The posture moves, not the durations.
            Move::ElbowFlip => return Some(b),
            Move::StickAtLeast { abs, factor } => at_least(&mut b, 1, abs.max(factor * d[1])),
            Move::StickAtMost { factor } => at_most(&mut b, 1, d[1] / factor),
            Move::Period { factor } if factor > 1.0 => {
                (0..3).for_each(|i| at_most(&mut b, i, d[i] / factor));
            }
            Move::Period { factor } => (0..3).for_each(|i| at_least(&mut b, i, d[i] / factor)),
            Move::Shift { factor } if factor > 1.0 => {
                at_least(&mut b, 0, factor * d[0]);
                at_most(&mut b, 2, d[2] / factor);
            }
            Move::Shift { factor } => {
                at_most(&mut b, 0, factor * d[0]);
                at_least(&mut b, 2, d[2] / factor);
            }
        }
        // A move that leaves every bound where it was, or leaves the optimum inside the new
        // bounds, would re-solve the optimum itself.
        let moves = d
            .iter()
            .zip(&b)
            .any(|(x, (lo, hi))| *x < lo * (1.0 - 1e-9) || *x > hi * (1.0 + 1e-9));
        moves.then_some(b)
    }

    /// A short description for the search's records.
    pub fn describe(&self) -> String {
        match *self {
            Move::ElbowFlip => "elbow flip".to_string(),
            Move::StickAtLeast { abs, factor } => format!("stick >= max({abs}, {factor} x)"),
            Move::StickAtMost { factor } => format!("stick <= 1/{factor} x"),
            Move::Period { factor } if factor > 1.0 => format!("phases <= 1/{factor} x"),
            Move::Period { factor } => format!("phases >= 1/{factor} x"),
            Move::Shift { factor } if factor > 1.0 => {
                format!("free 1 >= {factor} x, free 2 <= 1/{factor} x")
            }
            Move::Shift { factor } => {
                format!("free 1 <= {factor:.3} x, free 2 >= {:.3} x", 1.0 / factor)
            }
        }
    }
}

/// The elbow flip ([`Move::ElbowFlip`]) of the primal point `x` of `p` (`nq` joints, states
/// [q, q̇, …] at every state point), each angle kept inside its variable bounds. Nothing for
/// fewer than two joints.
pub fn flip_elbow(p: &BuiltProblem, nq: usize, x: &mut [f64], lo: &[f64], up: &[f64]) {
    if nq < 2 {
        return;
    }
    let (a, b) = (nq - 2, nq - 1);
    for l in &p.nlp.phases {
        if l.nx < 2 * nq {
            continue;
        }
        for pt in 0..l.mesh.state_tau.len() {
            for (i, j) in [(a, b), (nq + a, nq + b)] {
                let (ki, kj) = (l.x(pt, i), l.x(pt, j));
                let (qi, qj) = (x[ki], x[kj]);
                x[ki] = (qi + qj).clamp(lo[ki], up[ki]);
                x[kj] = (-qj).clamp(lo[kj], up[kj]);
            }
        }
    }
}

/// `p` transcribed again with the phase duration bounds `bounds` (one per phase), on the same
/// meshes and node kernels: the NLP layout is `p`'s, so a primal-dual point of `p` warm-starts
/// it and one of it warm-starts `p`.
pub fn with_duration_bounds(
    p: &BuiltProblem,
    bounds: &[(f64, f64)],
) -> Result<BuiltProblem, PipelineError> {
    if bounds.len() != p.ocp.phases.len() {
        return Err(PipelineError::Internal(
            "duration bounds of another number of phases than the problem's",
        ));
    }
    let mut ocp = p.ocp.clone();
    for (ph, b) in ocp.phases.iter_mut().zip(bounds) {
        ph.duration_bounds = *b;
    }
    // As `bf_problem::build`: a scene given by the caller may have no emitted kernels.
    let kernels = match (&p.settings.scene, p.generated.kernels) {
        (Some(_), KernelUse::Require(f)) => KernelUse::Prefer(f),
        (_, k) => k,
    };
    let meshes: Vec<_> = p
        .settings
        .mesh
        .iter()
        .flatten()
        .cloned()
        .map(Some)
        .collect();
    let nlp = Transcription::with_kernels(&ocp, &meshes, kernels)?;
    Ok(BuiltProblem {
        ocp,
        nlp,
        ..p.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FSF: [PhaseMode; 3] = [PhaseMode::Free, PhaseMode::Stick, PhaseMode::Free];
    const WITHIN: [(f64, f64); 3] = [(0.01, 5.0), (0.01, 5.0), (0.01, 5.0)];

    /// Every bound move excludes the optimum's own durations from its bounds (so the solve must
    /// move), keeps its bounds inside the problem's, and a move that cannot apply (a stick
    /// phase on its lower bound shortened) gives `None`.
    #[test]
    fn every_move_excludes_the_optimum_and_stays_within_the_problem() {
        let d = [0.3, 0.12, 0.5];
        // The flip moves the posture and leaves the durations free.
        assert_eq!(
            Move::ElbowFlip.bounds(&d, &WITHIN, &FSF),
            Some(WITHIN.to_vec())
        );
        for m in MOVES.into_iter().filter(|m| *m != Move::ElbowFlip) {
            let b = m.bounds(&d, &WITHIN, &FSF).expect("applies");
            assert!(
                d.iter().zip(&b).any(|(x, (lo, hi))| x < lo || x > hi),
                "{m:?}: {b:?} contains {d:?}"
            );
            for (i, (lo, hi)) in b.iter().enumerate() {
                assert!(
                    WITHIN[i].0 <= *lo && lo <= hi && *hi <= WITHIN[i].1,
                    "{m:?} {b:?}"
                );
            }
        }
        let tap = [0.3, 0.01, 0.5];
        assert_eq!(
            Move::StickAtMost { factor: 3.0 }.bounds(&tap, &WITHIN, &FSF),
            None
        );
        assert_eq!(
            MOVES[0].bounds(&d, &WITHIN, &[PhaseMode::Free, PhaseMode::Stick]),
            None
        );
        // The shorter period: every phase at most 0.8 of its duration.
        let b = Move::Period { factor: 1.25 }
            .bounds(&d, &WITHIN, &FSF)
            .unwrap();
        for (x, (_, hi)) in d.iter().zip(&b) {
            assert!((hi - 0.8 * x).abs() < 1e-15);
        }
    }
}
