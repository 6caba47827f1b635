//! Initial guesses of the catalogue's problems: the paper's constant guess (docs/parameters.md,
//! Sect. 6.1: q ≡ q⁰, every duration 1 s) or an override ([`StartGuess`]), and the geometric
//! guess that moves the finger linearly to a contact configuration found by bisection on h
//! (eq. 4).
//!
//! The guess configurations of a scene ([`GuessConfigurations`], [`guess_configurations`]):
//! a 3-joint finger starts from the paper's q⁰ = [`Q_GUESS`] and the pressed-in [`Q_DEEP`]
//! where they are guesses for its geometry: q⁰ clear of the ball, `Q_DEEP` pressed into it,
//! both within the joint limits. Any other finger (another number of joints N, or a 3-joint
//! finger of other proportions, such as a URDF robot's) starts from configurations solved for
//! on its own geometry. They lie on the curl family q(c) = (q⁰₁, c, …, c) (N = 1:
//! q(c) = (c)): the first joint at the paper's q⁰₁ and the others bent alike, as the paper's
//! q⁰ bends joints 2 and 3 towards the ball, each joint held within its limits. The first c
//! (scanned in steps of [`CURL_STEP`], either sign) with h(q(c)) < 0 is the pressed-in
//! configuration, the root c_c of h(q(c)) = 0 before it (bisection) the contact
//! configuration, and q(c_c / 2) the free configuration q⁰.

use bf_codegen::Scene;
use bf_optim::ocp::{EndRamp, Phase, PhaseGuess};
use bf_scene::state_len;

use crate::ProblemError;
use crate::node::{CostKind, NodeSettings, PhaseMode, Physics, StickLevel, node_function};
use crate::points::Diagnostics;
pub use crate::start::StartGuess;

/// The constant joint configuration of the default initial guess of a 3-joint finger
/// (docs/parameters.md: "q constant nonzero"): the finger bent towards the ball, h ≈ 0.95 r.
pub const Q_GUESS: [f64; 3] = [0.1, 0.6, 0.9];

/// A configuration of a 3-joint finger pressed into the ball (h < 0) used to find the contact
/// configuration of the geometric guess by bisection on the segment [`Q_GUESS`] → `Q_DEEP`.
pub const Q_DEEP: [f64; 3] = [0.1, 1.0, 1.6];

/// Step of the scan of the curl family for fingers other than 3-joint ones (rad).
pub const CURL_STEP: f64 = std::f64::consts::PI / 64.0;

/// Bisection steps on h (eq. 4) for a contact configuration.
const BISECTIONS: usize = 60;

/// The joint configurations the guesses of a scene are made of (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct GuessConfigurations {
    /// q⁰: the constant configuration of the default guess and the rest configuration the
    /// `reach` and free–stick problems start from (h > 0).
    pub free: Vec<f64>,
    /// A configuration pressed into the ball (h < 0); the contact configuration of the
    /// geometric guess lies on the segment `free` → `deep`.
    pub deep: Vec<f64>,
}

/// The curl family q(c) of a finger with the joint limits `limits` (module docs): each joint
/// held within its limits, so that a limit stops that joint and the others bend on.
fn curl(limits: &[(f64, f64)], c: f64) -> Vec<f64> {
    let first = if limits.len() == 1 { c } else { Q_GUESS[0] };
    std::iter::once(first)
        .chain(std::iter::repeat_n(c, limits.len() - 1))
        .zip(limits)
        .map(|(v, &(lo, hi))| v.max(lo).min(hi))
        .collect()
}

/// Whether every joint of `q` is within `limits`.
fn within(q: &[f64], limits: &[(f64, f64)]) -> bool {
    q.iter()
        .zip(limits)
        .all(|(v, &(lo, hi))| lo <= *v && *v <= hi)
}

/// h(q) at rest.
fn h_at(diag: &Diagnostics, q: &[f64]) -> f64 {
    let mut x = vec![0.0; 2 * q.len() + 3];
    x[..q.len()].copy_from_slice(q);
    diag.eval(&x).h
}

/// The guess configurations of `scene` (module docs), with the smooth saturation of ε = `eps`
/// in h (the catalogue passes the scene's `smooth_eps`). Errors when a finger that the paper's
/// configurations do not fit touches the ball straight or never reaches it on its curl family.
pub fn guess_configurations(scene: &Scene, eps: f64) -> Result<GuessConfigurations, ProblemError> {
    let nq = scene.links.len();
    let limits = crate::arm::joint_limits(scene);
    let diag = Diagnostics::new(scene, eps)?;
    if nq == 3
        && within(&Q_GUESS, &limits)
        && within(&Q_DEEP, &limits)
        && h_at(&diag, &Q_GUESS) > 0.0
        && h_at(&diag, &Q_DEEP) < 0.0
    {
        return Ok(GuessConfigurations {
            free: Q_GUESS.to_vec(),
            deep: Q_DEEP.to_vec(),
        });
    }
    let fail = |reason: String| ProblemError::NoContactConfiguration {
        scene: scene.name.clone(),
        joints: nq,
        reason,
    };
    let h0 = h_at(&diag, &curl(&limits, 0.0));
    if h0.is_nan() || h0 <= 0.0 {
        return Err(fail(format!(
            "h = {h0:e} m at q = {:?}, the finger touches the ball unbent",
            curl(&limits, 0.0)
        )));
    }
    let steps = (std::f64::consts::PI / CURL_STEP).round() as usize;
    // The smallest |c| at which the curled finger presses into the ball, either sign.
    let deep = (1..=steps).find_map(|k| {
        [1.0, -1.0].into_iter().find_map(|sign| {
            let c = sign * k as f64 * CURL_STEP;
            (h_at(&diag, &curl(&limits, c)) < 0.0).then_some((c, sign))
        })
    });
    let Some((c_deep, sign)) = deep else {
        let family = if nq == 1 {
            "(c)".to_string()
        } else {
            format!("({}, c, ..., c)", Q_GUESS[0])
        };
        let held = if limits.iter().any(|l| l.0.is_finite() || l.1.is_finite()) {
            " (each joint held within its limits)"
        } else {
            ""
        };
        return Err(fail(format!(
            "h > 0 at every q(c) = {family}{held} with |c| <= pi, the curled finger never \
             reaches the ball"
        )));
    };
    let (mut lo, mut hi) = (c_deep - sign * CURL_STEP, c_deep);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if h_at(&diag, &curl(&limits, mid)) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    Ok(GuessConfigurations {
        free: curl(&limits, 0.5 * lo),
        deep: curl(&limits, c_deep),
    })
}

/// The shares of the friction cone and of the torque limits a plan leaves to feedback
/// ([`crate::ProblemSettings::cone_margin`], [`crate::ProblemSettings::torque_margin`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct PlanMargins {
    pub(crate) cone: f64,
    pub(crate) torque: f64,
}

/// One phase of an archetype: its mode, the bounds of its h and ḣ path rows (`None`: no
/// row), its duration bounds and the duration of the default guess.
pub(crate) struct PhaseDef {
    pub(crate) mode: PhaseMode,
    pub(crate) h: Option<(f64, f64)>,
    pub(crate) hdot: Option<(f64, f64)>,
    pub(crate) duration: (f64, f64),
    pub(crate) guess_duration: f64,
    /// Extra lower bound on h (m) away from the phase's end and the share of the phase over
    /// which it falls to 0 (an `EndRamp` on h; with `h` only; none for a clearance of 0).
    pub(crate) clearance: Option<(f64, f64)>,
}

/// The phases of `defs` with their node functions, bounds and the default (q ≡ `q_guess`) or
/// `start` constant guess.
pub(crate) fn make_phases(
    scene: &Scene,
    ph: &Physics,
    defs: &[PhaseDef],
    cost: CostKind,
    eps: f64,
    points: usize,
    q_limits: &[(f64, f64)],
    q_guess: &[f64],
    start: Option<&StartGuess>,
    stick: StickLevel,
    margins: PlanMargins,
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
        let (node, vars) = node_function(
            scene,
            ph,
            &NodeSettings {
                mode: d.mode,
                cost,
                h_bounds: d.h,
                hdot_bounds: d.hdot,
                eps,
                cone_margin: margins.cone,
            },
            stick,
        )
        .map_err(ProblemError::model(&scene.name))?;
        let mut x_bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); state_len(nq)];
        x_bounds[..nq].copy_from_slice(q_limits);
        let na = node.a.len();
        let mut xg = vec![0.0; state_len(nq)];
        for i in 0..nq {
            xg[i] = start.map_or(q_guess[i], |sg| sg.q[i]);
            let (lo, hi) = q_limits[i];
            if lo.is_finite() || hi.is_finite() {
                xg[i] = xg[i].clamp(lo, hi);
            }
        }
        let end_ramp = vars.h_path.zip(d.clearance.filter(|&(c, _)| c > 0.0)).map(
            |(index, (clearance, ramp))| EndRamp {
                index,
                clearance,
                ramp,
            },
        );
        out.push(Phase {
            name: format!("{:?}", d.mode).to_lowercase(),
            node,
            x_bounds,
            a_bounds: vec![(f64::NEG_INFINITY, f64::INFINITY); na],
            u_bounds: ph
                .tau_max
                .iter()
                .map(|&t| {
                    let t = (1.0 - margins.torque) * t;
                    (-t, t)
                })
                .collect(),
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
            end_ramp,
        });
    }
    Ok(out)
}

/// The contact configuration q_c on the segment `conf.free` → `conf.deep` with h(q_c) = 0.
fn contact_configuration(diag: &Diagnostics, nq: usize, conf: &GuessConfigurations) -> Vec<f64> {
    let at = |s: f64| -> Vec<f64> {
        let mut x = vec![0.0; state_len(nq)];
        for i in 0..nq {
            x[i] = conf.free[i] + s * (conf.deep[i] - conf.free[i]);
        }
        x
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..BISECTIONS {
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
    conf: &GuessConfigurations,
) -> Result<(), ProblemError> {
    let diag = Diagnostics::new(scene, eps)?;
    let nq = scene.links.len();
    let qc = contact_configuration(&diag, nq, conf);
    let qf: Vec<f64> = phases[0].guess.x[0][..nq].to_vec();
    let n = phases.len();
    for (k, phase) in phases.iter_mut().enumerate() {
        let (qa, qb) = match modes[k] {
            PhaseMode::Stick => (qc.clone(), qc.clone()),
            PhaseMode::Free if k + 1 < n && modes[k + 1] == PhaseMode::Stick => {
                (qf.clone(), qc.clone())
            }
            PhaseMode::Free if k > 0 => (qc.clone(), qf.clone()),
            // A lone free phase (reach) approaches the ball.
            PhaseMode::Free => (qf.clone(), qc.clone()),
        };
        let t = phase.guess.duration;
        let mut xa = phase.guess.x[0].clone();
        let mut xb = xa.clone();
        for i in 0..nq {
            xa[i] = qa[i];
            xb[i] = qb[i];
            let v = (qb[i] - qa[i]) / t;
            xa[nq + i] = v;
            xb[nq + i] = v;
        }
        phase.guess.s = vec![0.0, 1.0];
        phase.guess.x = vec![xa, xb];
    }
    Ok(())
}
