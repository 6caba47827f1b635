//! Explicit Runge–Kutta steps with dense output: Dormand–Prince 5(4) and classic RK4.
//!
//! * DOPRI5 (Dormand & Prince 1980; Hairer, Nørsett & Wanner, *Solving ODEs I*, Sect. II.5):
//!   7 stages, FSAL (k7 = f(t₁, x₁) is the next step's k1), 5th-order solution x₁, embedded
//!   4th-order error estimate e = h Σ eᵢ kᵢ, and Hairer's continuous extension (`CONTD5`)
//!   x(t₀ + θh) = r₁ + θ(r₂ + (1−θ)(r₃ + θ(r₄ + (1−θ) r₅))), 4th order uniformly in θ and equal
//!   to the 5th-order solution at θ = 1.
//! * RK4 (classic 1/6, 1/3, 1/3, 1/6) with a cubic Hermite interpolant built from x₀, x₁,
//!   f(t₀, x₀), f(t₁, x₁) (3rd order locally, O(h⁴) event times).
//! * Error norm: ‖e‖ = sqrt(1/n Σ (eᵢ / (atol + rtol·max(|x₀ᵢ|, |x₁ᵢ|)))²); a step is accepted
//!   when ‖e‖ ≤ 1. PI control: h_new = h · clamp(0.9 · ‖e‖^(−α) · ‖e_old‖^β, 0.2, 10) with
//!   α = 0.2 − 0.75β, β = 0.04 (Hairer's DOPRI5 constants).
//!
//! The step functions are public so convergence orders can be measured on fixed step sizes.

use crate::{HybridSystem, SimError};

// Butcher tableau of DOPRI5.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense-output coefficients (Hairer's CONTD5).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// PI controller constants (Hairer's DOPRI5 defaults).
pub(crate) const PI_BETA: f64 = 0.04;
pub(crate) const PI_SAFE: f64 = 0.9;
/// Largest step shrink per rejection / growth per acceptance.
pub(crate) const FAC_MIN: f64 = 0.2;
pub(crate) const FAC_MAX: f64 = 10.0;

/// Which interpolant a [`Dense`] holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DenseKind {
    Dopri5,
    Hermite,
}

/// Dense output of one accepted step over [t₀, t₀ + h].
#[derive(Debug, Clone)]
pub struct Dense {
    t0: f64,
    h: f64,
    n: usize,
    kind: DenseKind,
    /// DOPRI5: r₁..r₅ (5n values); Hermite: x₀, x₁, h f₀, h f₁ (4n values).
    coef: Vec<f64>,
}

impl Dense {
    fn new(n: usize) -> Self {
        Dense {
            t0: 0.0,
            h: 0.0,
            n,
            kind: DenseKind::Dopri5,
            coef: vec![0.0; 5 * n],
        }
    }

    /// Start of the step.
    pub fn t0(&self) -> f64 {
        self.t0
    }

    /// End of the step.
    pub fn t1(&self) -> f64 {
        self.t0 + self.h
    }

    /// Writes the interpolated state at time `t` (meant for t ∈ [t₀, t₁]) into `out`.
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        let n = self.n;
        let th = if self.h == 0.0 {
            0.0
        } else {
            (t - self.t0) / self.h
        };
        let th1 = 1.0 - th;
        match self.kind {
            DenseKind::Dopri5 => {
                let (r1, rest) = self.coef.split_at(n);
                let (r2, rest) = rest.split_at(n);
                let (r3, rest) = rest.split_at(n);
                let (r4, r5) = rest.split_at(n);
                for i in 0..n {
                    out[i] = r1[i] + th * (r2[i] + th1 * (r3[i] + th * (r4[i] + th1 * r5[i])));
                }
            }
            DenseKind::Hermite => {
                let (x0, rest) = self.coef.split_at(n);
                let (x1, rest) = rest.split_at(n);
                let (hf0, hf1) = rest.split_at(n);
                hermite_point(th, x0, x1, hf0, hf1, out);
            }
        }
    }
}

/// The cubic Hermite interpolant at θ ∈ [0, 1] of a step through x₀ and x₁ with the scaled
/// slopes h·f₀ and h·f₁, written into `out`.
fn hermite_point(th: f64, x0: &[f64], x1: &[f64], hf0: &[f64], hf1: &[f64], out: &mut [f64]) {
    let th2 = th * th;
    let th3 = th2 * th;
    let h00 = 2.0 * th3 - 3.0 * th2 + 1.0;
    let h10 = th3 - 2.0 * th2 + th;
    let h01 = -2.0 * th3 + 3.0 * th2;
    let h11 = th3 - th2;
    for i in 0..x0.len() {
        out[i] = h00 * x0[i] + h10 * hf0[i] + h01 * x1[i] + h11 * hf1[i];
    }
}

/// One end of a step for [`simpson_over_step`]: time, state, slope f = ẋ there, and the
/// integrand's value.
#[derive(Debug, Clone, Copy)]
pub struct StepEnd<'a> {
    /// Time (s).
    pub t: f64,
    /// State.
    pub x: &'a [f64],
    /// Its derivative ẋ.
    pub f: &'a [f64],
    /// The integrand g at (t, x).
    pub g: f64,
}

/// ∫ g dt over the step from `a` to `b` by Simpson's rule, g at the midpoint evaluated by `g_at`
/// on the state of the step's cubic Hermite interpolant (RK4's dense output): O(h⁵) per step,
/// so that a balance of g against the state measures the integration, not the quadrature
/// (the energy checks of the run reports). `None` when the midpoint cannot be evaluated or the
/// result is not finite; 0 for a step of no length.
pub fn simpson_over_step(
    a: StepEnd<'_>,
    b: StepEnd<'_>,
    g_at: impl FnOnce(f64, &[f64]) -> Option<f64>,
) -> Option<f64> {
    let h = b.t - a.t;
    if h == 0.0 {
        return Some(0.0);
    }
    let tm = a.t + 0.5 * h;
    let scaled = |f: &[f64]| f.iter().map(|v| h * v).collect::<Vec<f64>>();
    let mut mid = vec![0.0; a.x.len()];
    hermite_point(0.5, a.x, b.x, &scaled(a.f), &scaled(b.f), &mut mid);
    let gm = g_at(tm, &mid)?;
    Some(h / 6.0 * (a.g + 4.0 * gm + b.g)).filter(|w| w.is_finite())
}

/// Work arrays and results of one Runge–Kutta step.
#[derive(Debug, Clone)]
pub struct StepBuffers {
    /// State at the step end, x₁.
    pub x1: Vec<f64>,
    /// f(t₁, x₁) (DOPRI5's FSAL stage; RK4 evaluates it for the Hermite interpolant).
    pub f1: Vec<f64>,
    /// Local error estimate (DOPRI5: x₁ − x̂₁ of the embedded 4th-order method; RK4: zeros).
    pub err: Vec<f64>,
    /// Dense output of the step.
    pub dense: Dense,
    k: [Vec<f64>; 5],
    tmp: Vec<f64>,
}

impl StepBuffers {
    /// Allocates buffers for a state of dimension `n`.
    pub fn new(n: usize) -> Self {
        StepBuffers {
            x1: vec![0.0; n],
            f1: vec![0.0; n],
            err: vec![0.0; n],
            dense: Dense::new(n),
            k: std::array::from_fn(|_| vec![0.0; n]),
            tmp: vec![0.0; n],
        }
    }
}

/// The vector field at a stage state `x` of the step from `x0` into `dx`. A system error at a
/// stage the step has blown up to (not finite, or more than [`BLOWN_UP`] times beyond the
/// largest |x0|, plus 1) is the step's, not the model's (a step far too long for stiff
/// dynamics, e.g. a huge damping or torque): the stage gets a NaN field, so the trial counts as
/// non-finite and is retried shorter, instead of ending the run with the model's complaint
/// about a state no trajectory reaches (e.g. "non-finite mass matrix"). Looked at only when
/// the system fails.
fn stage<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: S::Mode,
    t: f64,
    (x, x0): (&[f64], &[f64]),
    dx: &mut [f64],
) -> Result<(), SimError> {
    match sys.rhs(mode, t, x, dx) {
        Err(SimError::System { .. }) if blown_up(x, x0) => {
            dx.iter_mut().for_each(|v| *v = f64::NAN);
            Ok(())
        }
        r => r,
    }
}

/// How far beyond the largest |x0| (plus 1) a stage state counts as blown up: no step of a
/// resolved trajectory moves a state by a factor of 10¹².
pub(crate) const BLOWN_UP: f64 = 1e12;

fn blown_up(x: &[f64], x0: &[f64]) -> bool {
    let scale = 1.0 + x0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    x.iter()
        .any(|v| !v.is_finite() || v.abs() > BLOWN_UP * scale)
}

/// One DOPRI5 step of size `h` from (t₀, x₀) with f₀ = f(t₀, x₀) in mode `mode`. Fills
/// `buf.x1`, `buf.f1`, `buf.err` and `buf.dense`; errors only if the system returns one.
pub fn dopri5_step<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: S::Mode,
    t0: f64,
    x0: &[f64],
    f0: &[f64],
    h: f64,
    buf: &mut StepBuffers,
) -> Result<(), SimError> {
    let n = x0.len();
    let StepBuffers {
        x1,
        f1,
        err,
        dense,
        k,
        tmp,
    } = buf;
    let [k2, k3, k4, k5, k6] = k;
    for i in 0..n {
        tmp[i] = x0[i] + h * A21 * f0[i];
    }
    stage(sys, mode, t0 + C2 * h, (tmp, x0), k2)?;
    for i in 0..n {
        tmp[i] = x0[i] + h * (A31 * f0[i] + A32 * k2[i]);
    }
    stage(sys, mode, t0 + C3 * h, (tmp, x0), k3)?;
    for i in 0..n {
        tmp[i] = x0[i] + h * (A41 * f0[i] + A42 * k2[i] + A43 * k3[i]);
    }
    stage(sys, mode, t0 + C4 * h, (tmp, x0), k4)?;
    for i in 0..n {
        tmp[i] = x0[i] + h * (A51 * f0[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
    }
    stage(sys, mode, t0 + C5 * h, (tmp, x0), k5)?;
    for i in 0..n {
        tmp[i] = x0[i] + h * (A61 * f0[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
    }
    let t1 = t0 + h;
    stage(sys, mode, t1, (tmp, x0), k6)?;
    for i in 0..n {
        x1[i] = x0[i] + h * (A71 * f0[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
    }
    stage(sys, mode, t1, (x1, x0), f1)?;
    for i in 0..n {
        err[i] = h * (E1 * f0[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * f1[i]);
    }
    dense.t0 = t0;
    dense.h = h;
    dense.kind = DenseKind::Dopri5;
    dense.coef.resize(5 * n, 0.0);
    let (r1, rest) = dense.coef.split_at_mut(n);
    let (r2, rest) = rest.split_at_mut(n);
    let (r3, rest) = rest.split_at_mut(n);
    let (r4, r5) = rest.split_at_mut(n);
    for i in 0..n {
        let ydiff = x1[i] - x0[i];
        let bspl = h * f0[i] - ydiff;
        r1[i] = x0[i];
        r2[i] = ydiff;
        r3[i] = bspl;
        r4[i] = ydiff - h * f1[i] - bspl;
        r5[i] = h * (D1 * f0[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * f1[i]);
    }
    Ok(())
}

/// One classic RK4 step of size `h` from (t₀, x₀) with f₀ = f(t₀, x₀). Fills `buf.x1`,
/// `buf.f1` = f(t₁, x₁), `buf.err` = 0 and a cubic Hermite `buf.dense`.
pub fn rk4_step<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: S::Mode,
    t0: f64,
    x0: &[f64],
    f0: &[f64],
    h: f64,
    buf: &mut StepBuffers,
) -> Result<(), SimError> {
    let n = x0.len();
    let StepBuffers {
        x1,
        f1,
        err,
        dense,
        k,
        tmp,
    } = buf;
    let [k2, k3, k4, _, _] = k;
    for i in 0..n {
        tmp[i] = x0[i] + 0.5 * h * f0[i];
    }
    stage(sys, mode, t0 + 0.5 * h, (tmp, x0), k2)?;
    for i in 0..n {
        tmp[i] = x0[i] + 0.5 * h * k2[i];
    }
    stage(sys, mode, t0 + 0.5 * h, (tmp, x0), k3)?;
    for i in 0..n {
        tmp[i] = x0[i] + h * k3[i];
    }
    let t1 = t0 + h;
    stage(sys, mode, t1, (tmp, x0), k4)?;
    for i in 0..n {
        x1[i] = x0[i] + h / 6.0 * (f0[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    stage(sys, mode, t1, (x1, x0), f1)?;
    err.iter_mut().for_each(|e| *e = 0.0);
    dense.t0 = t0;
    dense.h = h;
    dense.kind = DenseKind::Hermite;
    dense.coef.resize(4 * n, 0.0);
    let (c0, rest) = dense.coef.split_at_mut(n);
    let (c1, rest) = rest.split_at_mut(n);
    let (c2, c3) = rest.split_at_mut(n);
    c0.copy_from_slice(x0);
    c1.copy_from_slice(x1);
    for i in 0..n {
        c2[i] = h * f0[i];
        c3[i] = h * f1[i];
    }
    Ok(())
}

/// Weighted RMS norm of the local error (see the module docs); non-finite data gives +∞ so the
/// step is rejected.
pub fn error_norm(err: &[f64], x0: &[f64], x1: &[f64], rtol: f64, atol: f64) -> f64 {
    let n = err.len().max(1);
    let mut s = 0.0;
    for i in 0..err.len() {
        let sk = atol + rtol * x0[i].abs().max(x1[i].abs());
        let r = err[i] / sk;
        s += r * r;
    }
    let v = (s / n as f64).sqrt();
    if v.is_finite() { v } else { f64::INFINITY }
}

/// Starting step size (Hairer, Nørsett & Wanner, Sect. II.4): h₀ from ‖x₀‖/‖f₀‖, refined by an
/// estimate of the second derivative from one explicit Euler step, for a method of order 5.
pub(crate) fn initial_step<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: S::Mode,
    t0: f64,
    x0: &[f64],
    f0: &[f64],
    rtol: f64,
    atol: f64,
    h_max: f64,
) -> Result<f64, SimError> {
    let n = x0.len();
    let mut dnf = 0.0;
    let mut dny = 0.0;
    for i in 0..n {
        let sk = atol + rtol * x0[i].abs();
        dnf += (f0[i] / sk).powi(2);
        dny += (x0[i] / sk).powi(2);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
        1e-6
    } else {
        (dny / dnf).sqrt() * 0.01
    };
    h = h.min(h_max);
    let x1: Vec<f64> = (0..n).map(|i| x0[i] + h * f0[i]).collect();
    let mut f1 = vec![0.0; n];
    stage(sys, mode, t0 + h, (&x1, x0), &mut f1)?;
    let mut der2 = 0.0;
    for i in 0..n {
        let sk = atol + rtol * x0[i].abs();
        der2 += ((f1[i] - f0[i]) / sk).powi(2);
    }
    let der2 = der2.sqrt() / h;
    let der12 = der2.abs().max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        libm::pow(0.01 / der12, 0.2)
    };
    let h = (100.0 * h).min(h1).min(h_max);
    Ok(if h.is_finite() && h > 0.0 { h } else { 1e-6 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toys::Oscillator;

    /// Error of the fixed-step solution of x'' = −x at t = 1 with `n` steps.
    fn fixed_step_error(n: usize, rk4: bool) -> f64 {
        let sys = Oscillator { omega: 1.0 };
        let mut x = vec![1.0, 0.0];
        let mut f = vec![0.0; 2];
        let mut buf = StepBuffers::new(2);
        let h = 1.0 / n as f64;
        for k in 0..n {
            let t = k as f64 * h;
            sys.rhs((), t, &x, &mut f).unwrap();
            if rk4 {
                rk4_step(&sys, (), t, &x, &f, h, &mut buf).unwrap();
            } else {
                dopri5_step(&sys, (), t, &x, &f, h, &mut buf).unwrap();
            }
            x.copy_from_slice(&buf.x1);
        }
        ((x[0] - libm::cos(1f64)).powi(2) + (x[1] + libm::sin(1f64)).powi(2)).sqrt()
    }

    #[test]
    fn dopri5_is_fifth_order() {
        let e1 = fixed_step_error(10, false);
        let e2 = fixed_step_error(20, false);
        let order = libm::log2(e1 / e2);
        assert!((order - 5.0).abs() < 0.3, "observed order {order}");
    }

    #[test]
    fn rk4_is_fourth_order() {
        let e1 = fixed_step_error(10, true);
        let e2 = fixed_step_error(20, true);
        let order = libm::log2(e1 / e2);
        assert!((order - 4.0).abs() < 0.2, "observed order {order}");
    }

    /// The embedded estimate is the error of a 4th-order method: local error O(h⁵), so halving h
    /// must shrink it ≈ 32×; and the dense output must interpolate with local error O(h⁵).
    #[test]
    fn dopri5_error_estimate_and_dense_output_orders() {
        let sys = Oscillator { omega: 1.0 };
        let x0 = [1.0, 0.0];
        let mut f0 = [0.0; 2];
        sys.rhs((), 0.0, &x0, &mut f0).unwrap();
        let mut buf = StepBuffers::new(2);
        let mut est = Vec::new();
        let mut dens = Vec::new();
        for h in [0.2, 0.1] {
            dopri5_step(&sys, (), 0.0, &x0, &f0, h, &mut buf).unwrap();
            est.push(buf.err[0].abs().max(buf.err[1].abs()));
            let mut xm = [0.0; 2];
            let tm = 0.37 * h;
            buf.dense.eval(tm, &mut xm);
            dens.push(
                (xm[0] - libm::cos(tm))
                    .abs()
                    .max((xm[1] + libm::sin(tm)).abs()),
            );
            // End point of the interpolant is the step's solution.
            let mut xe = [0.0; 2];
            buf.dense.eval(h, &mut xe);
            assert!((xe[0] - buf.x1[0]).abs() < 1e-15 && (xe[1] - buf.x1[1]).abs() < 1e-15);
        }
        let p_est = libm::log2(est[0] / est[1]);
        let p_dense = libm::log2(dens[0] / dens[1]);
        assert!((p_est - 5.0).abs() < 0.4, "estimate order {p_est}");
        assert!(p_dense > 4.5, "dense local order {p_dense}");
    }

    #[test]
    fn hermite_dense_output_is_cubic_exact() {
        // x' = 3t² has x = t³, which the cubic Hermite interpolant reproduces exactly given
        // exact end values and slopes (RK4 itself is exact for this quadrature).
        struct Cubic;
        impl HybridSystem for Cubic {
            type Mode = ();
            fn dim(&self) -> usize {
                1
            }
            fn rhs(&self, _: (), t: f64, _: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
                dx[0] = 3.0 * t * t;
                Ok(())
            }
        }
        let mut buf = StepBuffers::new(1);
        rk4_step(&Cubic, (), 1.0, &[1.0], &[3.0], 0.5, &mut buf).unwrap();
        let mut x = [0.0];
        for t in [1.1, 1.25, 1.4] {
            buf.dense.eval(t, &mut x);
            assert!((x[0] - t * t * t).abs() < 1e-13);
        }
    }

    /// Simpson's rule on the Hermite midpoint is exact when the state is a cubic and g linear in
    /// it (x = t³, ∫ x dt = t⁴/4), and its error over one step falls as h⁵ otherwise
    /// (x = sin t, g = x²: 32 times less for half the step).
    #[test]
    fn simpson_over_a_step_is_exact_for_cubics_and_fifth_order() {
        let end = |t: f64, x: &'static [f64], f: &'static [f64], g: f64| StepEnd { t, x, f, g };
        let w = simpson_over_step(
            end(1.0, &[1.0], &[3.0], 1.0),
            end(1.5, &[3.375], &[6.75], 3.375),
            |_, x| Some(x[0]),
        )
        .unwrap();
        assert!((w - (1.5f64.powi(4) - 1.0) / 4.0).abs() < 1e-14, "{w}");
        let error = |h: f64| {
            let (x0, x1) = ([libm::sin(0.3)], [libm::sin(0.3 + h)]);
            let (f0, f1) = ([libm::cos(0.3)], [libm::cos(0.3 + h)]);
            let a = StepEnd {
                t: 0.3,
                x: &x0,
                f: &f0,
                g: x0[0] * x0[0],
            };
            let b = StepEnd {
                t: 0.3 + h,
                x: &x1,
                f: &f1,
                g: x1[0] * x1[0],
            };
            let w = simpson_over_step(a, b, |_, x| Some(x[0] * x[0])).unwrap();
            // ∫ sin² = t/2 − sin(2t)/4.
            let exact = |t: f64| t / 2.0 - libm::sin(2.0 * t) / 4.0;
            (w - (exact(0.3 + h) - exact(0.3))).abs()
        };
        let ratio = error(0.2) / error(0.1);
        assert!((24.0..40.0).contains(&ratio), "{ratio}");
        assert_eq!(
            simpson_over_step(
                end(1.0, &[1.0], &[3.0], 1.0),
                end(1.5, &[3.375], &[6.75], 3.375),
                |_, _| None
            ),
            None
        );
    }
}
