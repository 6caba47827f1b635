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
//! Two moves change the posture instead, where no bound reaches: the elbow flip
//! ([`flip_elbow`], the other inverse-kinematics branch of the last two joints) and the mirror
//! ([`mirror_first_joint`], q₁ → −q₁ with the ball's spin ω, the contact force λ (eq. 29) and
//! the impact impulse ι (eq. 40) mirrored about the plane through the ball centre that holds
//! the first joint's axis and gravity), each also applied to a small hop of the optimum
//! ([`Move::ElbowFlipOfHop`], [`Move::MirrorOfHop`]: the solve from a transformed point is
//! sensitive to that point, docs/decisions/0046-posture-moves-of-a-hop.md).
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
    /// The mirror about the plane through the ball centre that contains the first joint's axis
    /// and gravity (world y = 0 on the paper's scenes: base at (2r, 0, 0), first axis along
    /// world x): q'₁ = −q₁ with q₂, q₃ kept, the ball's angular velocity, a pseudovector,
    /// mirrored as ω' = (−ω_x, ω_y, −ω_z), and likewise τ₁, q̈₁, ω̇ and the y components of
    /// λ and of the impact impulse ι, at every point; the durations unbounded
    /// ([`mirror_first_joint`]). On a mirror-symmetric scene the mirrored point satisfies every
    /// dynamics, contact and periodicity row; only the objective differs (its reference spin is
    /// not mirrored), and the solve starts from the finger on the other side of the ball, which
    /// neither a hop nor the elbow flip reaches (the `periodic-qc` optima 0.0769 and 0.0876
    /// have q₁ ≈ +π/2 and −π/2).
    Mirror,
    /// The elbow flip of a small hop of the optimum (its durations scaled by e^(±s), its joint
    /// angles shifted by up to 0.6·s rad, s = [`POSTURE_HOP_SCALE`]): the solve from a
    /// flipped point is sensitive to the point, so the flip gets a second, nearby start. The
    /// `periodic-qc` tap 0.0769, reached by two paths of two searches and flipped, was solved
    /// to the 0.0876 optimum from one of them and to 0.333 from the other (the two points
    /// equal to the solver's tolerance).
    ElbowFlipOfHop,
    /// The mirror ([`Move::Mirror`]) of a small hop of the optimum, as [`Move::ElbowFlipOfHop`].
    MirrorOfHop,
    /// The first free phase at least `factor`·d₀ and the second at most d₂ / `factor` long
    /// (time moved into the first free phase), or the reverse for `factor` < 1.
    Shift {
        /// Multiple of the first free phase's duration.
        factor: f64,
    },
}

/// Relative size of the hop that [`Move::ElbowFlipOfHop`] and [`Move::MirrorOfHop`] apply
/// before the posture change (a third of the search's default hop).
pub const POSTURE_HOP_SCALE: f64 = 0.1;

/// The moves tried from every reshaped optimum, in this order (the move number is its index).
pub const MOVES: [Move; 13] = [
    Move::ElbowFlip,
    Move::Mirror,
    Move::ElbowFlipOfHop,
    Move::MirrorOfHop,
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
            Move::ElbowFlip | Move::Mirror | Move::ElbowFlipOfHop | Move::MirrorOfHop => {
                return Some(b);
            }
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

    /// Whether the move transforms the posture ([`flip_elbow`], [`mirror_first_joint`])
    /// rather than bounding the durations: solved once from the transformed point, with no
    /// bounds to release.
    pub fn moves_posture(&self) -> bool {
        matches!(
            self,
            Move::ElbowFlip | Move::Mirror | Move::ElbowFlipOfHop | Move::MirrorOfHop
        )
    }

    /// Whether the move is the mirror ([`Move::Mirror`], [`Move::MirrorOfHop`]) rather than
    /// the elbow flip among the posture moves.
    pub fn mirrors(&self) -> bool {
        matches!(self, Move::Mirror | Move::MirrorOfHop)
    }

    /// The relative size of the hop applied before the posture change (0: none).
    pub fn hop_scale(&self) -> f64 {
        match self {
            Move::ElbowFlipOfHop | Move::MirrorOfHop => POSTURE_HOP_SCALE,
            _ => 0.0,
        }
    }

    /// A short description for the search's records.
    pub fn describe(&self) -> String {
        match *self {
            Move::ElbowFlip => "elbow flip".to_string(),
            Move::Mirror => "mirror q1".to_string(),
            Move::ElbowFlipOfHop => format!("elbow flip of a hop ({POSTURE_HOP_SCALE})"),
            Move::MirrorOfHop => format!("mirror q1 of a hop ({POSTURE_HOP_SCALE})"),
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

/// The mirror ([`Move::Mirror`]) of the primal point `x` of `p` (`nq` joints; states
/// [q, q̇, ω, …] at every state point, node variables [q̈, ω̇, λ] and \[τ\], the impact impulse
/// ι and a redundant finger's Newton parameters q̇_N, ι_N, found by name, when the problem has
/// them), each value kept inside its variable bounds. Nothing without joints.
pub fn mirror_first_joint(p: &BuiltProblem, nq: usize, x: &mut [f64], lo: &[f64], up: &[f64]) {
    if nq == 0 {
        return;
    }
    let mut negate = |k: usize| x[k] = (-x[k]).clamp(lo[k], up[k]);
    // Components that change sign: q₁ and q̇₁, and ω_x, ω_z (ω' = −S ω for the reflection
    // S = diag(1, −1, 1)); in the node variables q̈₁, ω̇_x, ω̇_z and λ_y (λ is a force: S λ).
    let states = [0, nq, 2 * nq, 2 * nq + 2];
    let nodes = [0, nq, nq + 2, nq + 4];
    for l in &p.nlp.phases {
        for pt in 0..l.mesh.state_tau.len() {
            states
                .iter()
                .filter(|&&i| i < l.nx)
                .for_each(|&i| negate(l.x(pt, i)));
        }
        for k in 0..l.mesh.colloc.len() {
            nodes
                .iter()
                .filter(|&&i| i < l.na)
                .for_each(|&i| negate(l.a(k, i)));
            if l.nu > 0 {
                negate(l.u(k, 0));
            }
        }
    }
    // ι (and a redundant finger's Newton impulse ι_N) is a Cartesian impulse (eq. 40): its y
    // component changes sign; the Newton plan's post-impact q̇_N as q̇ (its first joint's).
    for (k, q) in p.ocp.params.iter().enumerate() {
        if matches!(q.name.as_str(), "iota2" | "iota_newton2" | "qd_newton1") {
            negate(p.nlp.p0 + k);
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
        // The flip and the mirror, alone and of a small hop, move the posture and leave the
        // durations free; the hop variants start from a hop, the plain ones from the optimum.
        for m in [
            Move::ElbowFlip,
            Move::Mirror,
            Move::ElbowFlipOfHop,
            Move::MirrorOfHop,
        ] {
            assert!(m.moves_posture() && MOVES.contains(&m));
            assert_eq!(m.bounds(&d, &WITHIN, &FSF), Some(WITHIN.to_vec()));
            let of_hop = matches!(m, Move::ElbowFlipOfHop | Move::MirrorOfHop);
            assert_eq!(m.hop_scale() > 0.0, of_hop, "{m:?}");
            assert_eq!(m.mirrors(), matches!(m, Move::Mirror | Move::MirrorOfHop));
        }
        assert_eq!(MOVES.iter().filter(|m| m.moves_posture()).count(), 4);
        for m in MOVES.into_iter().filter(|m| !m.moves_posture()) {
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

    /// The mirror is an exact symmetry of the paper's scene: at a generic point of the
    /// `periodic-qc` NLP (every variable perturbed, so nothing is symmetric by accident),
    /// every dynamics, contact, path, linkage and periodicity row of the mirrored point has the
    /// magnitude of the original's (rows map to ± themselves), while the cost-state rows differ
    /// (the reference spin ω_ref is not mirrored); mirroring twice is the identity. Mirroring
    /// q₁ alone, or with ω unmirrored, breaks the dynamics rows (so the test can fail).
    #[test]
    fn the_mirror_keeps_every_constraint_row_of_the_paper_scene_but_the_cost() {
        use bf_optim::ipm::Nlp;
        use bf_problem::{Problem, ProblemSettings};

        let settings = ProblemSettings {
            points: 12,
            scheme: bf_optim::ocp::Scheme::Radau { elements: 3 },
            ..ProblemSettings::default()
        };
        let p = crate::pipeline::build(Problem::PeriodicQc, &settings).expect("builds");
        let (n, m) = (Nlp::num_variables(&p.nlp), Nlp::num_constraints(&p.nlp));
        let mut x = vec![0.0; n];
        Nlp::initial_point(&p.nlp, &mut x);
        // A deterministic generic point (a golden-ratio sequence in [−0.5, 0.5)).
        for (i, v) in x.iter_mut().enumerate() {
            *v += ((i as f64 * 0.618_033_988_749_895).fract() - 0.5) * 0.8;
        }
        for l in &p.nlp.phases {
            x[l.t] = 0.3;
        }
        let (lo, up) = (vec![f64::NEG_INFINITY; n], vec![f64::INFINITY; n]);
        let nq = p.guess.free.len();
        let nc = p.nlp.row_blocks[0].1.end;
        assert_eq!(p.nlp.row_blocks[0].0, "cost states");
        let rows = |x: &[f64]| {
            let mut g = vec![0.0; m];
            Nlp::constraints(&p.nlp, x, &mut g);
            g
        };
        let g = rows(&x);
        let mismatched = |y: &[f64]| {
            let gy = rows(y);
            (nc..m)
                .filter(|&i| (gy[i].abs() - g[i].abs()).abs() > 1e-9 * (1.0 + g[i].abs()))
                .count()
        };
        let mut y = x.clone();
        mirror_first_joint(&p, nq, &mut y, &lo, &up);
        assert_eq!(mismatched(&y), 0);
        let gy = rows(&y);
        assert!(
            (0..nc).any(|i| (gy[i] - g[i]).abs() > 1e-6),
            "cost rows unchanged"
        );
        let mut z = y.clone();
        mirror_first_joint(&p, nq, &mut z, &lo, &up);
        assert_eq!(z, x);
        // The joint alone (q₁, q̇₁ and τ₁) is not the mirror of the whole system.
        let mut q_only = x.clone();
        for l in &p.nlp.phases {
            for pt in 0..l.mesh.state_tau.len() {
                q_only[l.x(pt, 0)] *= -1.0;
                q_only[l.x(pt, nq)] *= -1.0;
            }
            for k in 0..l.mesh.colloc.len() {
                q_only[l.a(k, 0)] *= -1.0;
                q_only[l.u(k, 0)] *= -1.0;
            }
        }
        assert!(mismatched(&q_only) > 10, "{}", mismatched(&q_only));
    }
}
