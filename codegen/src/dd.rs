//! Double-double arithmetic (≈ 106-bit significand) for accuracy measurements of the
//! generated kernels: the interpreter evaluates the same graph in [`Dd`] and the f64 error is
//! measured against it (accuracy at |q| ~ 1e6 rad, `docs/architecture.md`, "Trig").

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A double-double number hi + lo with |lo| ≤ ulp(hi)/2.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct Dd {
    /// Leading part.
    pub hi: f64,
    /// Trailing part.
    pub lo: f64,
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// π as a double-double.
pub const PI: Dd = Dd {
    hi: std::f64::consts::PI,
    lo: 1.2246467991473532e-16,
};

impl Dd {
    /// Exact conversion from `f64`.
    pub fn new(v: f64) -> Self {
        Dd { hi: v, lo: 0.0 }
    }

    fn from_parts(hi: f64, lo: f64) -> Self {
        let (h, l) = quick_two_sum(hi, lo);
        Dd { hi: h, lo: l }
    }

    /// Nearest `f64`.
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// √x (NaN for x < 0).
    pub fn sqrt(self) -> Self {
        if self.hi <= 0.0 {
            return Dd::new(self.hi.sqrt());
        }
        let y = Dd::new(self.hi.sqrt());
        let r = self - y * y;
        y + r / (y * Dd::new(2.0))
    }

    /// |x|.
    pub fn abs(self) -> Self {
        if self.hi < 0.0 { -self } else { self }
    }

    /// (sin x, cos x): reduction by π/2 in double-double, then Taylor series.
    pub fn sin_cos(self) -> (Self, Self) {
        if !self.hi.is_finite() {
            return (Dd::new(f64::NAN), Dd::new(f64::NAN));
        }
        // π/2 as three doubles (≈ 160 bits), so the reduction stays accurate next to
        // multiples of π/2. Any integer k near x/(π/2) works: the series converges for every
        // r; k·P1 is exact as a double-double product.
        const P1: f64 = std::f64::consts::FRAC_PI_2;
        const P2: f64 = 6.123233995736766e-17;
        const P3: f64 = -1.4973849048591698e-33;
        let kf = (self.hi / P1).round();
        let k = Dd::new(kf);
        let r = self - k * Dd::new(P1) - k * Dd::new(P2) - k * Dd::new(P3);
        let (s, c) = taylor_sin_cos(r);
        let q = kf.rem_euclid(4.0) as i64;
        match q {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }
}

fn taylor_sin_cos(r: Dd) -> (Dd, Dd) {
    // |r| ≤ π/4: 30 terms reach far below 1e-32.
    let r2 = r * r;
    let mut term = r;
    let mut s = r;
    let mut n = 1.0;
    for _ in 0..30 {
        term = -(term * r2) / Dd::new((n + 1.0) * (n + 2.0));
        s = s + term;
        n += 2.0;
    }
    let mut term = Dd::new(1.0);
    let mut c = term;
    let mut n = 0.0;
    for _ in 0..30 {
        term = -(term * r2) / Dd::new((n + 1.0) * (n + 2.0));
        c = c + term;
        n += 2.0;
    }
    (s, c)
}

impl Add for Dd {
    type Output = Dd;
    fn add(self, y: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, y.hi);
        let (t, f) = two_sum(self.lo, y.lo);
        let (s, e) = quick_two_sum(s, e + t);
        Dd::from_parts(s, e + f)
    }
}

impl Sub for Dd {
    type Output = Dd;
    fn sub(self, y: Dd) -> Dd {
        self + (-y)
    }
}

impl Neg for Dd {
    type Output = Dd;
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Mul for Dd {
    type Output = Dd;
    fn mul(self, y: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, y.hi);
        Dd::from_parts(p, e + (self.hi * y.lo + self.lo * y.hi))
    }
}

impl Div for Dd {
    type Output = Dd;
    fn div(self, y: Dd) -> Dd {
        let q1 = self.hi / y.hi;
        if !q1.is_finite() {
            return Dd::new(q1);
        }
        let r = self - y * Dd::new(q1);
        let q2 = r.hi / y.hi;
        let r = r - y * Dd::new(q2);
        let q3 = r.hi / y.hi;
        Dd::from_parts(q1, q2) + Dd::new(q3)
    }
}
