//! Initial guesses of the catalogue's problems: the paper's constant guess (docs/parameters.md,
//! Sect. 6.1: q ≡ [`Q_GUESS`], every duration 1 s) or an override ([`StartGuess`]), and the
//! geometric guess that moves the finger linearly to a contact configuration found by
//! bisection on h (eq. 4).

use bf_codegen::Scene;
use bf_optim::ocp::{Phase, PhaseGuess};

use crate::ProblemError;
use crate::node::{CostKind, NodeOptions, PhaseMode, Physics, StickLevel, node_function};
use crate::points::Diagnostics;
pub use crate::start::StartGuess;

/// The constant joint configuration of the default initial guess (docs/parameters.md: "q constant
/// nonzero"): the finger bent towards the ball, h ≈ 0.95 r.
pub const Q_GUESS: [f64; 3] = [0.1, 0.6, 0.9];

/// A configuration pressed into the ball (h < 0) used to find the contact configuration of
/// the geometric guess by bisection on the segment [`Q_GUESS`] → `Q_DEEP`.
pub const Q_DEEP: [f64; 3] = [0.1, 1.0, 1.6];

/// One phase of an archetype: its mode, the bounds of its h and ḣ path rows (`None`: no
/// row), its duration bounds and the duration of the default guess.
pub(crate) struct PhaseDef {
    pub(crate) mode: PhaseMode,
    pub(crate) h: Option<(f64, f64)>,
    pub(crate) hdot: Option<(f64, f64)>,
    pub(crate) duration: (f64, f64),
    pub(crate) guess_duration: f64,
}

/// The phases of `defs` with their node functions, bounds and the default (or `start`)
/// constant guess.
pub(crate) fn make_phases(
    scene: &Scene,
    ph: &Physics,
    defs: &[PhaseDef],
    cost: CostKind,
    eps: f64,
    points: usize,
    q_limits: &[(f64, f64)],
    start: Option<&StartGuess>,
    stick: StickLevel,
) -> Result<Vec<Phase>, ProblemError> {
    let nq = ph.nq;
    if let Some(sg) = start {
        let ok = sg.q.len() == nq
            && sg.durations.len() == defs.len()
            && sg.q.iter().all(|v| v.is_finite())
            && sg.durations.iter().all(|v| v.is_finite() && *v > 0.0);
        if !ok {
            return Err(ProblemError::StartGuess {
                joints: nq,
                phases: defs.len(),
                guess: sg.clone(),
            });
        }
    }
    let mut out = Vec::new();
    for (k, d) in defs.iter().enumerate() {
        let (node, _) = node_function(
            scene,
            ph,
            &NodeOptions {
                mode: d.mode,
                cost,
                h_bounds: d.h,
                hdot_bounds: d.hdot,
                eps,
            },
            stick,
        )
        .map_err(ProblemError::model(&scene.name))?;
        let mut x_bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); 2 * nq + 3];
        x_bounds[..nq].copy_from_slice(q_limits);
        let na = node.a.len();
        let mut xg = vec![0.0; 2 * nq + 3];
        for i in 0..nq {
            xg[i] = start.map_or(Q_GUESS[i % 3], |sg| sg.q[i]);
            let (lo, hi) = q_limits[i];
            if lo.is_finite() || hi.is_finite() {
                xg[i] = xg[i].clamp(lo, hi);
            }
        }
        out.push(Phase {
            name: format!("{:?}", d.mode).to_lowercase(),
            node,
            x_bounds,
            a_bounds: vec![(f64::NEG_INFINITY, f64::INFINITY); na],
            u_bounds: ph.tau_max.iter().map(|&t| (-t, t)).collect(),
            duration_bounds: d.duration,
            points,
            guess: PhaseGuess::constant(
                xg,
                vec![0.0; na],
                vec![0.0; nq],
                start.map_or(d.guess_duration, |sg| {
                    sg.durations[k].clamp(d.duration.0, d.duration.1)
                }),
            ),
        });
    }
    Ok(out)
}

/// The contact configuration q_c on the segment Q_GUESS → Q_DEEP with h(q_c) = 0.
fn contact_configuration(diag: &Diagnostics, nq: usize) -> Vec<f64> {
    let at = |s: f64| -> Vec<f64> {
        let mut x = vec![0.0; 2 * nq + 3];
        for i in 0..nq.min(3) {
            x[i] = Q_GUESS[i] + s * (Q_DEEP[i] - Q_GUESS[i]);
        }
        x
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if diag.eval(&at(mid)).h > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    at(lo)[..nq].to_vec()
}

/// Replaces the phase guesses by the geometric [`super::GuessKind::Contact`] guess.
pub(crate) fn contact_guess(
    scene: &Scene,
    eps: f64,
    phases: &mut [Phase],
    modes: &[PhaseMode],
) -> Result<(), ProblemError> {
    let diag = Diagnostics::new(scene, eps)?;
    let nq = scene.links.len();
    let qc = contact_configuration(&diag, nq);
    let qf: Vec<f64> = phases[0].guess.x[0][..nq].to_vec();
    let n = phases.len();
    for (k, ph) in phases.iter_mut().enumerate() {
        let (qa, qb) = match modes[k] {
            PhaseMode::Stick => (qc.clone(), qc.clone()),
            PhaseMode::Free if k + 1 < n && modes[k + 1] == PhaseMode::Stick => {
                (qf.clone(), qc.clone())
            }
            PhaseMode::Free if k > 0 => (qc.clone(), qf.clone()),
            // A lone free phase (reach) approaches the ball.
            PhaseMode::Free => (qf.clone(), qc.clone()),
        };
        let t = ph.guess.duration;
        let mut xa = ph.guess.x[0].clone();
        let mut xb = xa.clone();
        for i in 0..nq {
            xa[i] = qa[i];
            xb[i] = qb[i];
            let v = (qb[i] - qa[i]) / t;
            xa[nq + i] = v;
            xb[nq + i] = v;
        }
        ph.guess.s = vec![0.0, 1.0];
        ph.guess.x = vec![xa, xb];
    }
    Ok(())
}
