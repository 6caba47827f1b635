//! Event location on the dense output of one accepted step (paper Sect. 3.1: "the solver has to
//! pinpoint when the transition condition becomes satisfied with equality").
//!
//! For every guard gⱼ of the current mode:
//! 1. **Bracketing.** gⱼ is sampled at t₀ + k·h/K, k = 0..K (`event_subdivisions` = K), so a
//!    double crossing inside one step (the ball leaves the plane and comes back) is seen as long
//!    as it spans a sub-interval. A crossing in the guard's [`Direction`] between consecutive
//!    samples (a, b) is a bracket with s·g(a) > 0, s·g(b) ≤ 0 (s = ±1 orients it).
//! 2. **Root.** Illinois false position on the dense interpolant, safeguarded by bisection,
//!    shrinks the bracket to width ≤ `event_tol`; the event time is the bracket end on the
//!    *crossed* side, so the event state is past the guard (like "h < 0" in eq. 50).
//! 3. **Earliest wins.** Among all guards the smallest event time is taken (ties: lowest index).
//!
//! **Guards starting on the surface.** Right after a reset (or at the initial time) a guard with
//! |g| ≤ `guard_zero_tol` is *masked*: its start value is not used as a bracket end (that would
//! re-trigger the event just handled, or, if ignored, hide the next genuine crossing — the
//! failure seen with diffsol 0.18's event handling, `docs/decisions/0003-own-integrators.md`).
//! Instead:
//! * the samples are scanned for the first one, t_k, that is clearly off the surface
//!   (directional: on the valid side of the start value, s·g > max(s·g₀, 0), or beyond
//!   −`guard_zero_tol` on the triggered side; `Either`: |g| > |g₀|); if there is none the guard
//!   stays masked into the next step;
//! * (t₀, t_k] is refined by probes t₀ + (t_k − t₀)/2ⁱ down to `event_tol` (≈ 40 guard
//!   evaluations, once per masked guard after a reset), and read in time order: a departure to
//!   the valid side followed by a return (a short flight, even one lower than the tolerance
//!   band) is bracketed and root-found; a departure straight into the triggered region (the
//!   state slid out of the band: eq. 50's h = ḣ = 0 ∧ ḧ < 0) fires at the band-exit time,
//!   bisected to `event_tol` (the "small violation" of Sect. 3.1); otherwise the guard is
//!   unmasked and normal bracketing continues from t_k.
//!
//! A directional guard that is *beyond* the tolerance on its triggered side right after a reset
//! fires immediately (handled by the simulator as a chained transition).

use crate::integrator::Dense;

/// Fraction of `guard_zero_tol` below which a departure from a masked guard's start value is
/// treated as rounding noise (1e-6 · 1e-9 = 1e-15 with the defaults).
const NOISE_FRACTION: f64 = 1e-6;
use crate::{Direction, Guard, HybridSystem, SimError};

/// Evaluates the guards of one mode on a dense interpolant, with scratch space.
pub(crate) struct GuardProbe<'a, S: HybridSystem + ?Sized> {
    pub sys: &'a S,
    pub mode: S::Mode,
    pub dense: &'a Dense,
    pub x: Vec<f64>,
    pub g: Vec<f64>,
    pub evals: usize,
}

impl<S: HybridSystem + ?Sized> GuardProbe<'_, S> {
    /// Evaluates all guards at `t`, then returns guard `j`.
    fn value(&mut self, t: f64, j: usize, name: &str) -> Result<f64, SimError> {
        self.dense.eval(t, &mut self.x);
        self.sys.guard_values(self.mode, t, &self.x, &mut self.g)?;
        self.evals += 1;
        let v = self.g[j];
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SimError::NonFinite {
                what: format!("guard `{name}`"),
                t,
                mode: format!("{:?}", self.mode),
            })
        }
    }
}

/// Orientation s such that s·g > 0 before a crossing and s·g ≤ 0 after, for a directional
/// guard (`None` for [`Direction::Either`]).
pub(crate) fn orientation(dir: Direction) -> Option<f64> {
    match dir {
        Direction::Falling => Some(1.0),
        Direction::Rising => Some(-1.0),
        Direction::Either => None,
    }
}

/// Whether g = `v` is strictly beyond the tolerance on the triggered side of a directional guard.
pub(crate) fn beyond_triggered(dir: Direction, v: f64, tol: f64) -> bool {
    match orientation(dir) {
        Some(s) => s * v < -tol,
        None => false,
    }
}

/// Illinois false position on the oriented function φ(t) = s·g(t), φ(a) > 0 ≥ φ(b), until
/// b − a ≤ tol. Returns the crossed-side end b.
fn illinois<S: HybridSystem + ?Sized>(
    probe: &mut GuardProbe<'_, S>,
    j: usize,
    name: &str,
    s: f64,
    (mut a, mut fa): (f64, f64),
    (mut b, mut fb): (f64, f64),
    tol: f64,
) -> Result<f64, SimError> {
    debug_assert!(fa > 0.0 && fb <= 0.0);
    let mut side = 0i8;
    let mut width_ref = b - a;
    let mut it = 0usize;
    while b - a > tol && fb != 0.0 && it < 400 {
        it += 1;
        let mut m = b - fb * (b - a) / (fb - fa);
        // Bisect when false position stalls (bracket not halved within 3 iterations) or falls
        // outside the open bracket through rounding.
        if it.is_multiple_of(3) {
            if b - a > 0.5 * width_ref {
                m = 0.5 * (a + b);
            }
            width_ref = b - a;
        }
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
            if !(m > a && m < b) {
                break;
            }
        }
        let fm = s * probe.value(m, j, name)?;
        if fm > 0.0 {
            a = m;
            fa = fm;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            b = m;
            fb = fm;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
    }
    Ok(b)
}

/// Result of scanning one guard over one step.
pub(crate) struct GuardScan {
    /// Located event time of this guard, if any.
    pub t_event: Option<f64>,
    /// Whether the guard is still masked at the step end (all samples within tolerance).
    pub still_masked: bool,
}

/// Scans guard `j` over the step described by `ts` (sample times, ts[0] = t₀) and `vals`
/// (vals[k] = gⱼ(ts[k])), locating the earliest event in its direction.
pub(crate) fn scan_guard<S: HybridSystem + ?Sized>(
    probe: &mut GuardProbe<'_, S>,
    j: usize,
    guard: &Guard,
    masked: bool,
    ts: &[f64],
    vals: &[f64],
    event_tol: f64,
    zero_tol: f64,
) -> Result<GuardScan, SimError> {
    let name = guard.name;
    let kmax = ts.len() - 1;
    // First index from which strict bracketing applies.
    let mut start = 0usize;
    if masked {
        match scan_masked(probe, j, guard, ts, vals, event_tol, zero_tol)? {
            Masked::Event(t) => {
                return Ok(GuardScan {
                    t_event: Some(t),
                    still_masked: false,
                });
            }
            Masked::Still => {
                return Ok(GuardScan {
                    t_event: None,
                    still_masked: true,
                });
            }
            Masked::UnmaskAt(k) => start = k,
        }
    }
    for k in start..kmax {
        let (ga, gb) = (vals[k], vals[k + 1]);
        let s = match guard.direction {
            Direction::Falling => 1.0,
            Direction::Rising => -1.0,
            Direction::Either => {
                if ga > 0.0 {
                    1.0
                } else if ga < 0.0 {
                    -1.0
                } else {
                    continue;
                }
            }
        };
        if s * ga > 0.0 && s * gb <= 0.0 {
            let t = illinois(
                probe,
                j,
                name,
                s,
                (ts[k], s * ga),
                (ts[k + 1], s * gb),
                event_tol,
            )?;
            return Ok(GuardScan {
                t_event: Some(t),
                still_masked: false,
            });
        }
    }
    Ok(GuardScan {
        t_event: None,
        still_masked: false,
    })
}

enum Masked {
    Event(f64),
    Still,
    UnmaskAt(usize),
}

#[derive(Clone, Copy, PartialEq)]
enum Class {
    /// Clearly off the surface; for directional guards on the valid side.
    Clear(f64),
    /// Directional guard beyond the band on the triggered side.
    Triggered,
    /// Inside the noise band around the start value.
    Unclear,
}

/// Handles a guard that started on its surface (see the module docs). The samples up to the
/// first clear one, ts[k], are refined by probes t₀ + (ts[k] − t₀)/2ⁱ down to `event_tol`, so
/// the side to which the state departs from the surface is seen however short the excursion.
fn scan_masked<S: HybridSystem + ?Sized>(
    probe: &mut GuardProbe<'_, S>,
    j: usize,
    guard: &Guard,
    ts: &[f64],
    vals: &[f64],
    event_tol: f64,
    zero_tol: f64,
) -> Result<Masked, SimError> {
    let name = guard.name;
    let g0 = vals[0];
    let orient = orientation(guard.direction);
    // A value counts as "clearly departed to the valid side" only above a rounding-noise margin:
    // guards like h = |r_c| − r carry absolute rounding noise ~1e-16 (scale 1), so right after
    // a reset that left h = 0 and a tiny departure speed, probes within nanoseconds would
    // otherwise read noise of either sign as a departure followed by a return (a phantom
    // event).
    let thr = orient.map_or(0.0, |s| (s * g0).max(0.0)) + NOISE_FRACTION * zero_tol;
    let classify = |v: f64| match orient {
        Some(s) => {
            if s * v > thr {
                Class::Clear(1.0)
            } else if s * v < -zero_tol {
                Class::Triggered
            } else {
                Class::Unclear
            }
        }
        None => {
            if v.abs() > g0.abs() {
                Class::Clear(v.signum())
            } else {
                Class::Unclear
            }
        }
    };
    let Some(k) = (1..vals.len()).find(|&k| classify(vals[k]) != Class::Unclear) else {
        return Ok(Masked::Still);
    };
    let t0 = ts[0];
    let mut seq = Vec::new();
    let mut d = 0.5 * (ts[k] - t0);
    while d >= event_tol {
        let p = t0 + d;
        seq.push((p, probe.value(p, j, name)?));
        d *= 0.5;
    }
    seq.reverse();
    seq.push((ts[k], vals[k]));
    match orient {
        Some(s) => {
            let mut prev_valid: Option<(f64, f64)> = None;
            let mut last_inside = t0;
            for &(t, v) in &seq {
                let phi = s * v;
                match classify(v) {
                    Class::Clear(_) => {
                        prev_valid = Some((t, phi));
                        last_inside = t;
                    }
                    Class::Unclear => {
                        if let Some(a) = prev_valid.filter(|_| phi <= 0.0) {
                            let te = illinois(probe, j, name, s, a, (t, phi), event_tol)?;
                            return Ok(Masked::Event(te));
                        }
                        last_inside = t;
                    }
                    Class::Triggered => {
                        if let Some(a) = prev_valid {
                            let te = illinois(probe, j, name, s, a, (t, phi), event_tol)?;
                            return Ok(Masked::Event(te));
                        }
                        // Slid out of the tolerance band: bisect the exit time.
                        let (mut lo, mut hi) = (last_inside, t);
                        while hi - lo > event_tol {
                            let m = 0.5 * (lo + hi);
                            if !(m > lo && m < hi) {
                                break;
                            }
                            if s * probe.value(m, j, name)? < -zero_tol {
                                hi = m;
                            } else {
                                lo = m;
                            }
                        }
                        return Ok(Masked::Event(hi));
                    }
                }
            }
        }
        None => {
            let mut dep: Option<(f64, (f64, f64))> = None;
            for &(t, v) in &seq {
                match (classify(v), dep) {
                    (Class::Clear(sg), None) => dep = Some((sg, (t, sg * v))),
                    (Class::Clear(sg), Some((sd, a))) => {
                        if sg != sd {
                            let te = illinois(probe, j, name, sd, a, (t, sd * v), event_tol)?;
                            return Ok(Masked::Event(te));
                        }
                        dep = Some((sd, (t, sd * v)));
                    }
                    (_, Some((sd, a))) if sd * v <= 0.0 => {
                        let te = illinois(probe, j, name, sd, a, (t, sd * v), event_tol)?;
                        return Ok(Masked::Event(te));
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(Masked::UnmaskAt(k))
}
