//! The optimum as a reference, phase by phase, indexed by the time s since the phase began
//! (not by the clock: [`crate::HybridController`] starts each phase at the plant's event).
//!
//! Per phase the dense samples of the optimum (q*, q̇*, ω*, τ*, λ*), the planned contact point
//! r_c* (eq. 3) with its rate ṙ_c*, plus the accelerations the
//! controller's model gives them: q̈* from free motion (eq. 26) in free phases, ω̇* (and q̈*)
//! from sticking (eq. 29, 33) in contact phases, so the reference is consistent with the model
//! the feedback inverts. Between samples q* and q̇* (free phases), ω* (contact phases) and r_c*
//! are cubic Hermite interpolants of their values and derivatives (third-order accurate, where a
//! linear interpolation of 100 samples per phase would leave errors of order 10⁻⁴ of the
//! accelerations); q̈*, ω̇* and λ* are linear. Past the end of a free phase the reference
//! continues at the planned pre-impact velocity (q* = q*_T + q̇*_T (s − T), q̈* = 0), so a
//! plant that reaches the ball late keeps approaching it as planned; past the end of a contact
//! phase its last values are held.

use crate::error::ControlError;
use bf_model::{Kernels, Model, State, Vec3};

/// One phase of the reference of a finger with `N` joints.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePhase<const N: usize = 3> {
    /// Whether the phase is a contact (stick) phase.
    pub contact: bool,
    /// Planned duration T (s).
    pub duration: f64,
    /// Sample times since the phase began (s), strictly increasing, from 0 to T.
    pub s: Vec<f64>,
    /// q* (rad).
    pub q: Vec<[f64; N]>,
    /// q̇* (rad/s).
    pub qd: Vec<[f64; N]>,
    /// q̈* (rad/s²).
    pub qdd: Vec<[f64; N]>,
    /// ω* (rad/s).
    pub omega: Vec<[f64; 3]>,
    /// ω̇* (rad/s²).
    pub omega_dot: Vec<[f64; 3]>,
    /// λ* on the finger (N, world axes; zero in free phases).
    pub lambda: Vec<[f64; 3]>,
    /// r_c* = p_c* − o_b, the planned contact point relative to the ball's centre (m, world
    /// axes; eq. 3), in every phase (in free phases the closest point of the last link).
    pub contact_point: Vec<[f64; 3]>,
    /// ṙ_c* (m/s), the slope of the interpolation of r_c*.
    pub contact_point_dot: Vec<[f64; 3]>,
    /// h* (m): the planned gap between the finger and the ball (eq. 4), zero in contact.
    pub gap: Vec<f64>,
    /// ḣ* (m/s), the slope of the interpolation of h*.
    pub gap_rate: Vec<f64>,
}

/// The reference at one instant of a phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point<const N: usize = 3> {
    /// q*.
    pub q: [f64; N],
    /// q̇*.
    pub qd: [f64; N],
    /// q̈*.
    pub qdd: [f64; N],
    /// ω*.
    pub omega: [f64; 3],
    /// ω̇*.
    pub omega_dot: [f64; 3],
    /// λ*.
    pub lambda: [f64; 3],
    /// r_c*.
    pub contact_point: [f64; 3],
}

/// The optimum's phases of one period, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference<const N: usize = 3> {
    /// The phases.
    pub phases: Vec<ReferencePhase<N>>,
    /// Mean ω over one period of the optimum (rad/s).
    pub mean_omega: [f64; 3],
}

/// Samples of an optimum over one period, as `solution.json`'s `dense` stores them.
#[derive(Debug, Clone, Copy)]
pub struct Samples<'a> {
    /// Times (s).
    pub t: &'a [f64],
    /// Phase index of each sample.
    pub phase: &'a [usize],
    /// q.
    pub q: &'a [Vec<f64>],
    /// q̇.
    pub qd: &'a [Vec<f64>],
    /// ω.
    pub omega: &'a [Vec<f64>],
    /// τ.
    pub tau: &'a [Vec<f64>],
    /// λ.
    pub lambda: &'a [Vec<f64>],
}

fn arr<const L: usize>(v: &[f64], what: &'static str, k: usize) -> Result<[f64; L], ControlError> {
    let a: [f64; L] = v.try_into().map_err(|_| ControlError::Reference {
        msg: format!(
            "sample {k}: {what} has {} components, expected {L}",
            v.len()
        ),
    })?;
    if a.iter().any(|x| !x.is_finite()) {
        return Err(ControlError::Reference {
            msg: format!("sample {k}: {what} is not finite"),
        });
    }
    Ok(a)
}

impl<const N: usize> Reference<N> {
    /// Builds the reference from the samples of one period, the contact flag and duration of
    /// every phase, and the period's mean ω; q̈* and ω̇* come from `model` (module doc).
    /// Errors name the sample or phase: missing or non-finite values, fewer than two samples
    /// in a phase, times not increasing within a phase, a model error at a sample.
    pub fn from_samples<K: Kernels<N>>(
        model: &Model<K, N>,
        contact: &[bool],
        durations: &[f64],
        samples: Samples<'_>,
        mean_omega: [f64; 3],
    ) -> Result<Self, ControlError> {
        if contact.len() != durations.len() || contact.is_empty() {
            return Err(ControlError::Reference {
                msg: format!(
                    "{} phase modes but {} durations",
                    contact.len(),
                    durations.len()
                ),
            });
        }
        let n = samples.t.len();
        for (what, len) in [
            ("phase", samples.phase.len()),
            ("q", samples.q.len()),
            ("qd", samples.qd.len()),
            ("omega", samples.omega.len()),
            ("tau", samples.tau.len()),
            ("lambda", samples.lambda.len()),
        ] {
            if len != n {
                return Err(ControlError::Reference {
                    msg: format!("{n} sample times but {len} values of {what}"),
                });
            }
        }
        let mut t0 = 0.0;
        let mut phases = Vec::with_capacity(contact.len());
        for (p, (&c, &d)) in contact.iter().zip(durations).enumerate() {
            if !(d.is_finite() && d > 0.0) {
                return Err(ControlError::Reference {
                    msg: format!("phase {p}: duration {d} is not positive"),
                });
            }
            let mut ph = ReferencePhase {
                contact: c,
                duration: d,
                s: Vec::new(),
                q: Vec::new(),
                qd: Vec::new(),
                qdd: Vec::new(),
                omega: Vec::new(),
                omega_dot: Vec::new(),
                lambda: Vec::new(),
                contact_point: Vec::new(),
                contact_point_dot: Vec::new(),
                gap: Vec::new(),
                gap_rate: Vec::new(),
            };
            for k in (0..n).filter(|&k| samples.phase[k] == p) {
                let s = samples.t[k] - t0;
                if ph.s.last().is_some_and(|&l| s <= l) {
                    continue;
                }
                let q: [f64; N] = arr(&samples.q[k], "q", k)?;
                let qd: [f64; N] = arr(&samples.qd[k], "qd", k)?;
                let omega: [f64; 3] = arr(&samples.omega[k], "omega", k)?;
                let tau: [f64; N] = arr(&samples.tau[k], "tau", k)?;
                let lambda: [f64; 3] = arr(&samples.lambda[k], "lambda", k)?;
                let state = State::new(q.into(), qd.into(), omega.into());
                let model_err = |e| ControlError::Reference {
                    msg: format!("sample {k} (phase {p}): {e}"),
                };
                let geometry = model.evaluate(&state).map_err(model_err)?.contact;
                let acc = if c {
                    model.stick(&state, &tau.into()).map_err(model_err)?
                } else {
                    model.free(&state, &tau.into()).map_err(model_err)?
                };
                ph.s.push(s);
                ph.q.push(q);
                ph.qd.push(qd);
                ph.qdd.push(acc.qdd.into());
                ph.omega.push(omega);
                ph.omega_dot.push(acc.omega_dot.into());
                ph.lambda.push(if c { lambda } else { [0.0; 3] });
                ph.contact_point.push(geometry.r_c.into());
                ph.contact_point_dot.push(geometry.rc_dot.into());
                ph.gap.push(geometry.h);
                ph.gap_rate.push(geometry.h_dot);
            }
            if ph.s.len() < 2 {
                return Err(ControlError::Reference {
                    msg: format!("phase {p} has {} samples, at least 2 needed", ph.s.len()),
                });
            }
            phases.push(ph);
            t0 += d;
        }
        Ok(Reference { phases, mean_omega })
    }

    /// The period T = Σ durations (s).
    pub fn period(&self) -> f64 {
        self.phases.iter().map(|p| p.duration).sum()
    }
}

/// Cubic Hermite interpolation on [0, h] of values a, b with slopes da, db at w = s/h.
fn hermite(a: f64, b: f64, da: f64, db: f64, h: f64, w: f64) -> f64 {
    let w2 = w * w;
    let w3 = w2 * w;
    (2.0 * w3 - 3.0 * w2 + 1.0) * a
        + (w3 - 2.0 * w2 + w) * h * da
        + (-2.0 * w3 + 3.0 * w2) * b
        + (w3 - w2) * h * db
}

/// The slope of [`hermite`] with respect to s (not w).
fn hermite_slope(a: f64, b: f64, da: f64, db: f64, h: f64, w: f64) -> f64 {
    let w2 = w * w;
    ((6.0 * w2 - 6.0 * w) * (a - b)) / h
        + (3.0 * w2 - 4.0 * w + 1.0) * da
        + (3.0 * w2 - 2.0 * w) * db
}

impl<const N: usize> ReferencePhase<N> {
    /// The planned gap h*(s) and its rate ḣ*(s): the cubic Hermite interpolant of the samples
    /// h*, ḣ* and its slope (consistent with the interpolation of q*); outside [0, T] the end
    /// values.
    pub fn gap_at(&self, s: f64) -> (f64, f64) {
        let last = self.s.len() - 1;
        if s >= self.s[last] {
            return (self.gap[last], self.gap_rate[last]);
        }
        if s.is_nan() || s <= self.s[0] {
            return (self.gap[0], self.gap_rate[0]);
        }
        let k = self.s.partition_point(|&x| x <= s);
        let (a, b) = (k - 1, k);
        let h = self.s[b] - self.s[a];
        let w = (s - self.s[a]) / h;
        let (g, r) = (&self.gap, &self.gap_rate);
        (
            hermite(g[a], g[b], r[a], r[b], h, w),
            hermite_slope(g[a], g[b], r[a], r[b], h, w),
        )
    }

    /// The time σ ∈ [`from`, T] at which the planned gap is `h`, for a phase whose h* falls
    /// on that interval (the approach to a planned impact): the segment by bisection on the
    /// samples, then bisection on its cubic to the rounding of s. A gap above h*(`from`)
    /// gives `from`, one below h*(T) gives T.
    pub fn time_of_gap(&self, h: f64, from: f64) -> f64 {
        let last = self.s.len() - 1;
        let end = self.s[last];
        let from = from.clamp(self.s[0], end);
        if !h.is_finite() || h >= self.gap_at(from).0 {
            return from;
        }
        if h <= self.gap[last] {
            return end;
        }
        // The samples after `from` fall with s: the first one at or below h ends the segment.
        let first = self.s.partition_point(|&x| x <= from);
        let k = first + self.gap[first..].partition_point(|&g| g > h);
        let (a, b) = (k - 1, k.min(last));
        let (s0, width) = (self.s[a], self.s[b] - self.s[a]);
        let (g, r) = (&self.gap, &self.gap_rate);
        // The segment's cubic itself (what `gap_at` evaluates there), without its search.
        let gap = |s: f64| hermite(g[a], g[b], r[a], r[b], width, (s - s0) / width);
        let (mut lo, mut hi) = (s0.max(from), self.s[b]);
        while hi - lo > 1e-15 * (1.0 + hi.abs()) {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if gap(mid) > h {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The reference at time `s` since the phase began (module doc for s outside [0, T]).
    pub fn at(&self, s: f64) -> Point<N> {
        let last = self.s.len() - 1;
        if s >= self.s[last] {
            let mut p = self.point(last);
            if !self.contact {
                let ds = s - self.s[last];
                for i in 0..N {
                    p.q[i] += p.qd[i] * ds;
                }
                p.qdd = [0.0; N];
            }
            return p;
        }
        if s.is_nan() || s <= self.s[0] {
            return self.point(0);
        }
        let k = self.s.partition_point(|&x| x <= s);
        let (a, b) = (k - 1, k);
        let h = self.s[b] - self.s[a];
        let w = (s - self.s[a]) / h;
        fn lin<const L: usize>(v: &[[f64; L]], a: usize, b: usize, w: f64) -> [f64; L] {
            std::array::from_fn(|i| v[a][i] + w * (v[b][i] - v[a][i]))
        }
        fn herm<const L: usize>(
            v: &[[f64; L]],
            d: &[[f64; L]],
            (a, b, h, w): (usize, usize, f64, f64),
        ) -> [f64; L] {
            std::array::from_fn(|i| hermite(v[a][i], v[b][i], d[a][i], d[b][i], h, w))
        }
        let at = (a, b, h, w);
        Point {
            q: herm(&self.q, &self.qd, at),
            qd: herm(&self.qd, &self.qdd, at),
            qdd: lin(&self.qdd, a, b, w),
            omega: herm(&self.omega, &self.omega_dot, at),
            omega_dot: lin(&self.omega_dot, a, b, w),
            lambda: lin(&self.lambda, a, b, w),
            contact_point: herm(&self.contact_point, &self.contact_point_dot, at),
        }
    }

    fn point(&self, k: usize) -> Point<N> {
        Point {
            q: self.q[k],
            qd: self.qd[k],
            qdd: self.qdd[k],
            omega: self.omega[k],
            omega_dot: self.omega_dot[k],
            lambda: self.lambda[k],
            contact_point: self.contact_point[k],
        }
    }

    /// The reference λ_n* = λ*·n along the unit normal `n` at time `s`.
    pub fn lambda_n(&self, s: f64, n: &Vec3) -> f64 {
        Vec3::from(self.at(s).lambda).dot(n)
    }
}
