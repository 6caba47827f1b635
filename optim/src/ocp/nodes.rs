//! Pseudospectral nodes, quadrature weights and differentiation matrices (paper Sect. 5: the
//! Legendre–Gauss collocation of PSOPT; Benson et al. 2006, Garg et al. 2010).
//!
//! * [`legendre_gauss`]: the N roots τ_k of P_N with weights w_k = 2 / ((1 − τ_k²) P_N'(τ_k)²),
//!   exact for polynomials of degree ≤ 2N − 1;
//! * [`legendre_gauss_radau`]: the N roots of P_{N−1} + P_N (τ_0 = −1 included) with
//!   w_0 = 2/N², w_k = (1 − τ_k) / (N² P_{N−1}(τ_k)²), exact to degree 2N − 2;
//! * [`differentiation_matrix`]: D_ij = ℓ_j'(τ_i) of the Lagrange basis on support points
//!   (barycentric form), used in the collocation defects Σ_j D_kj X_j = (T/2) f(X_k, U_k).
//!
//! Roots are found by Newton's method on the three-term recurrence from Chebyshev-like
//! initial guesses and polished to machine precision.

/// Legendre polynomial P_n(x) and its derivative P_n'(x) by the three-term recurrence.
pub fn legendre(n: usize, x: f64) -> (f64, f64) {
    if n == 0 {
        return (1.0, 0.0);
    }
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    // P_n' from (1 − x²) P_n' = n (P_{n−1} − x P_n); at x = ±1 use P_n'(±1) = (±1)^{n+1} n(n+1)/2.
    let nf = n as f64;
    let d = if (1.0 - x * x).abs() < 1e-300 {
        let s = if x > 0.0 || n % 2 == 1 { 1.0 } else { -1.0 };
        s * nf * (nf + 1.0) / 2.0
    } else {
        nf * (p0 - x * p1) / (1.0 - x * x)
    };
    (p1, d)
}

/// Legendre–Gauss nodes (ascending) and weights on [−1, 1]; `n ≥ 1`.
pub fn legendre_gauss(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        // Descending guess cos(π (i + 3/4) / (n + 1/2)); stored ascending.
        let mut t = libm::cos(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        for _ in 0..100 {
            let (p, dp) = legendre(n, t);
            let dt = p / dp;
            t -= dt;
            if dt.abs() < 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, t);
        x[n - 1 - i] = t;
        w[n - 1 - i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
    (x, w)
}

/// Legendre–Gauss–Radau nodes (ascending, x_0 = −1) and weights on [−1, 1]; `n ≥ 1`.
pub fn legendre_gauss_radau(n: usize) -> (Vec<f64>, Vec<f64>) {
    let nf = n as f64;
    let mut x = vec![-1.0; n];
    let mut w = vec![2.0 / (nf * nf); n];
    for i in 1..n {
        // Chebyshev–Gauss–Radau guess −cos(2π i / (2n − 1)).
        let mut t = -libm::cos(2.0 * std::f64::consts::PI * i as f64 / (2.0 * nf - 1.0));
        for _ in 0..100 {
            let (a, da) = legendre(n - 1, t);
            let (b, db) = legendre(n, t);
            let dt = (a + b) / (da + db);
            t -= dt;
            if dt.abs() < 1e-16 {
                break;
            }
        }
        let (a, _) = legendre(n - 1, t);
        x[i] = t;
        w[i] = (1.0 - t) / (nf * nf * a * a);
    }
    (x, w)
}

/// Barycentric weights b_j = 1 / Π_{k≠j} (τ_j − τ_k) (scaled by their max magnitude).
pub fn barycentric_weights(tau: &[f64]) -> Vec<f64> {
    let mut b: Vec<f64> = (0..tau.len())
        .map(|j| {
            let mut p = 1.0;
            for k in 0..tau.len() {
                if k != j {
                    p *= tau[j] - tau[k];
                }
            }
            1.0 / p
        })
        .collect();
    let m = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if m > 0.0 {
        b.iter_mut().for_each(|v| *v /= m);
    }
    b
}

/// Differentiation matrix of the Lagrange basis on `tau`: `D[i][j] = ℓ_j'(τ_i)` (square).
pub fn differentiation_matrix(tau: &[f64]) -> Vec<Vec<f64>> {
    let n = tau.len();
    let b = barycentric_weights(tau);
    let mut d = vec![vec![0.0; n]; n];
    for i in 0..n {
        let mut s = 0.0;
        for j in 0..n {
            if i != j {
                d[i][j] = (b[j] / b[i]) / (tau[i] - tau[j]);
                s += d[i][j];
            }
        }
        d[i][i] = -s;
    }
    d
}

/// Values ℓ_j(t) of the Lagrange basis on `tau` at `t` (barycentric formula of the second kind).
pub fn lagrange_basis(tau: &[f64], t: f64) -> Vec<f64> {
    let b = barycentric_weights(tau);
    if let Some(k) = tau.iter().position(|&x| x == t) {
        let mut v = vec![0.0; tau.len()];
        v[k] = 1.0;
        return v;
    }
    let terms: Vec<f64> = tau.iter().zip(&b).map(|(x, bj)| bj / (t - x)).collect();
    let s: f64 = terms.iter().sum();
    terms.into_iter().map(|v| v / s).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact_monomial_integral(k: usize) -> f64 {
        if k % 2 == 1 {
            0.0
        } else {
            2.0 / (k as f64 + 1.0)
        }
    }

    #[test]
    fn gauss_is_exact_to_degree_2n_minus_1() {
        for n in 1..=60 {
            let (x, w) = legendre_gauss(n);
            for k in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!(
                    (q - exact_monomial_integral(k)).abs() < 1e-13,
                    "n={n} k={k} q={q}"
                );
            }
            // Nodes are roots of P_n.
            for &t in &x {
                assert!(legendre(n, t).0.abs() < 1e-13);
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]));
        }
        // Known values: n = 2 → ±1/√3, weights 1.
        let (x, w) = legendre_gauss(2);
        assert!((x[1] - 1.0 / 3f64.sqrt()).abs() < 1e-15 && (w[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn radau_is_exact_to_degree_2n_minus_2() {
        for n in 1..=40 {
            let (x, w) = legendre_gauss_radau(n);
            assert_eq!(x[0], -1.0);
            for k in 0..(2 * n - 1) {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!(
                    (q - exact_monomial_integral(k)).abs() < 1e-13,
                    "n={n} k={k}"
                );
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]));
        }
        // n = 2: nodes −1, 1/3, weights 1/2, 3/2.
        let (x, w) = legendre_gauss_radau(2);
        assert!((x[1] - 1.0 / 3.0).abs() < 1e-15 && (w[1] - 1.5).abs() < 1e-15);
    }

    #[test]
    fn differentiation_is_exact_for_polynomials() {
        let (g, _) = legendre_gauss(12);
        let mut tau = vec![-1.0];
        tau.extend(g);
        let d = differentiation_matrix(&tau);
        // p(t) = t^12 − 3 t^5 + 1 has degree = number of support points − 1.
        let p = |t: f64| t.powi(12) - 3.0 * t.powi(5) + 1.0;
        let dp = |t: f64| 12.0 * t.powi(11) - 15.0 * t.powi(4);
        for i in 0..tau.len() {
            let v: f64 = (0..tau.len()).map(|j| d[i][j] * p(tau[j])).sum();
            assert!((v - dp(tau[i])).abs() < 1e-11, "{i}: {v} vs {}", dp(tau[i]));
        }
        let l = lagrange_basis(&tau, 0.3);
        let v: f64 = l.iter().zip(&tau).map(|(l, t)| l * p(*t)).sum();
        assert!((v - p(0.3)).abs() < 1e-13);
    }
}
