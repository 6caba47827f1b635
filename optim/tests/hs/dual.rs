//! Hyper-dual numbers `a + b ε₁ + c ε₂ + d ε₁ε₂` (ε₁² = ε₂² = 0): one evaluation gives f,
//! ∂f/∂x_i (b), ∂f/∂x_j (c) and ∂²f/∂x_i∂x_j (d) exactly. Used so that the test problems are
//! written once and their derivatives cannot disagree with their values; the finite-difference
//! check in `hock_schittkowski.rs` verifies this machinery independently.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// Hyper-dual number.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct D {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
}

impl D {
    pub fn cst(a: f64) -> Self {
        D {
            a,
            b: 0.0,
            c: 0.0,
            d: 0.0,
        }
    }
    /// Applies a scalar function with value f0, first derivative f1, second derivative f2.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> Self {
        D {
            a: f0,
            b: f1 * self.b,
            c: f1 * self.c,
            d: f1 * self.d + f2 * self.b * self.c,
        }
    }
    pub fn powi(self, n: i32) -> Self {
        if n == 0 {
            return D::cst(1.0);
        }
        let a = self.a;
        let nf = n as f64;
        self.chain(
            a.powi(n),
            nf * a.powi(n - 1),
            nf * (nf - 1.0) * a.powi(n - 2),
        )
    }
    pub fn sqrt(self) -> Self {
        let s = self.a.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.a))
    }
    pub fn exp(self) -> Self {
        let e = libm::exp(self.a);
        self.chain(e, e, e)
    }
    pub fn ln(self) -> Self {
        let a = self.a;
        self.chain(libm::log(a), 1.0 / a, -1.0 / (a * a))
    }
    pub fn sin(self) -> Self {
        let a = self.a;
        self.chain(libm::sin(a), libm::cos(a), -libm::sin(a))
    }
    pub fn cos(self) -> Self {
        let a = self.a;
        self.chain(libm::cos(a), -libm::sin(a), -libm::cos(a))
    }
}

impl Add for D {
    type Output = D;
    fn add(self, o: D) -> D {
        D {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
            d: self.d + o.d,
        }
    }
}
impl Sub for D {
    type Output = D;
    fn sub(self, o: D) -> D {
        D {
            a: self.a - o.a,
            b: self.b - o.b,
            c: self.c - o.c,
            d: self.d - o.d,
        }
    }
}
impl Mul for D {
    type Output = D;
    fn mul(self, o: D) -> D {
        D {
            a: self.a * o.a,
            b: self.a * o.b + self.b * o.a,
            c: self.a * o.c + self.c * o.a,
            d: self.a * o.d + self.b * o.c + self.c * o.b + self.d * o.a,
        }
    }
}
impl Div for D {
    type Output = D;
    fn div(self, o: D) -> D {
        let inv = o.chain(1.0 / o.a, -1.0 / (o.a * o.a), 2.0 / (o.a * o.a * o.a));
        self * inv
    }
}
impl Neg for D {
    type Output = D;
    fn neg(self) -> D {
        D {
            a: -self.a,
            b: -self.b,
            c: -self.c,
            d: -self.d,
        }
    }
}
macro_rules! scalar_ops {
    ($($tr:ident $f:ident),*) => {$(
        impl $tr<f64> for D { type Output = D; fn $f(self, o: f64) -> D { self.$f(D::cst(o)) } }
        impl $tr<D> for f64 { type Output = D; fn $f(self, o: D) -> D { D::cst(self).$f(o) } }
    )*};
}
scalar_ops!(Add add, Sub sub, Mul mul, Div div);
