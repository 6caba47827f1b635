//! Bounds on a state *between* the state points (a path constraint on the state polynomial,
//! paper Sect. 5: the bounds of eq. 57 are imposed at the state points only).
//!
//! Between its state points a collocated state is the Lagrange polynomial of its element
//! (x(τ) = Σ_p ℓ_p(τ) X_p, what [`PhaseTrajectory::x_at`](super::super::PhaseTrajectory::x_at)
//! evaluates). Where the optimum sits on a state bound with corners (a bang-bang torque that
//! is a state), that polynomial overshoots the bound between the points although every point
//! is within it. [`StateBoundBetweenPoints`] adds linear rows `lo ≤ Σ_p c_p X_p,i ≤ hi` on the
//! element's state values (constant Jacobian entries c_p, no Hessian), in one of two ways
//! ([`Between`]):
//!
//! * **samples**: c_p = ℓ_p(τ_s) at k equally spaced points τ_s inside every interval between
//!   consecutive state points. Between the samples the polynomial can still overshoot; at a
//!   bang-bang switch (a steep transition inside one element) it does, by a few tenths of a
//!   percent of the bound with k = 3 on the test arm of `reach-arm`.
//! * **hull**: the Bernstein coefficients of the element's polynomial, degree-elevated from its
//!   degree N to m·N. A polynomial on an interval lies in the convex hull of its Bernstein
//!   coefficients, so bounding them bounds the polynomial *everywhere* in the element: no
//!   overshoot at all, at the price of a conservative bound (the coefficients approach the
//!   polynomial's values as O(1/(m N)) with the elevation). The coefficients are linear in the
//!   values at the support points: c = E B⁻¹ X with B_pj = b_j,N(u_p), u the support mapped
//!   to [0, 1], and E the elevation matrix.
//!
//! A problem without such bounds transcribes exactly as before (no row is added).
//!
//! Legendre–Gauss phases: the state polynomial's support is the phase start and the Gauss
//! nodes; the samples lie between those, not in the last interval (τ_N, 1], where the final
//! state is the quadrature variable rather than the polynomial.

use super::super::nodes::lagrange_basis;
use super::*;

/// How [`StateBoundBetweenPoints`] bounds the state polynomial between the state points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Between {
    /// At this many equally spaced points inside every interval (1..=[`MAX_PER_INTERVAL`]).
    Samples(usize),
    /// Everywhere, through the Bernstein coefficients of the element polynomial elevated to
    /// this multiple of its degree (1..=[`MAX_ELEVATION`]; elements of degree ≤
    /// [`MAX_HULL_DEGREE`]).
    Hull(usize),
}

/// A bound lo ≤ x_i(τ) ≤ hi on state component `component` of phase `phase` between the
/// state points of each element (the state points themselves carry the state bounds of the
/// phase), the way `how` says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateBoundBetweenPoints {
    /// Phase index.
    pub phase: usize,
    /// State component.
    pub component: usize,
    /// Lower bound (−∞ or NaN: none).
    pub lower: f64,
    /// Upper bound (+∞ or NaN: none).
    pub upper: f64,
    /// Samples or hull.
    pub how: Between,
}

/// The largest number of samples per interval accepted: beyond it the rows only cost.
pub const MAX_PER_INTERVAL: usize = 64;

/// The largest degree elevation factor of [`Between::Hull`].
pub const MAX_ELEVATION: usize = 8;

/// The largest element degree [`Between::Hull`] accepts: the Bernstein basis at the
/// collocation points (B above) grows ill-conditioned with the degree, and beyond this its
/// inverse loses more digits than the bound is worth.
pub const MAX_HULL_DEGREE: usize = 24;

/// Binomial coefficient as f64 (exact up to 2⁵³).
fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Inverse of a small dense matrix by Gauss–Jordan elimination with partial pivoting; `None`
/// when a pivot vanishes.
fn inverse(mut a: Vec<Vec<f64>>) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    for (k, row) in a.iter_mut().enumerate() {
        row.extend((0..n).map(|j| if j == k { 1.0 } else { 0.0 }));
    }
    for col in 0..n {
        let piv = (col..n).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        let p = a[piv][col];
        if p.abs() <= 1e-300 || !p.is_finite() {
            return None;
        }
        a.swap(col, piv);
        a[col].iter_mut().for_each(|v| *v /= p);
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            let f = row[col];
            if r != col && f != 0.0 {
                for (v, pv) in row.iter_mut().zip(&pivot_row) {
                    *v -= f * pv;
                }
            }
        }
    }
    Some(a.into_iter().map(|row| row[n..].to_vec()).collect())
}

/// The rows of the hull bound of one element with support `support` (ascending, degree
/// N = len − 1): the Bernstein coefficients of degree m·N on [support₀, support_N] as
/// combinations of the support values, without the coefficients that equal a support value
/// (the end points, where the support reaches the interval's ends). `None` if B is singular.
pub fn hull_rows(support: &[f64], m: usize) -> Option<Vec<Vec<f64>>> {
    let n = support.len().checked_sub(1)?;
    let (a, b) = (support[0], support[n]);
    if n == 0 || b <= a {
        return None;
    }
    let u: Vec<f64> = support.iter().map(|t| (t - a) / (b - a)).collect();
    let basis = u
        .iter()
        .map(|&x| {
            (0..=n)
                .map(|j| binomial(n, j) * x.powi(j as i32) * (1.0 - x).powi((n - j) as i32))
                .collect()
        })
        .collect();
    let b_inv = inverse(basis)?;
    let big = m * n;
    let rows = (1..big)
        .map(|k| {
            // e_k = Σ_i c_i C(N,i) C(M−N,k−i) / C(M,k), c = B⁻¹ X.
            let lo = k.saturating_sub(big - n);
            let mut row = vec![0.0; n + 1];
            for i in lo..=k.min(n) {
                let w = binomial(n, i) * binomial(big - n, k - i) / binomial(big, k);
                for (r, bi) in row.iter_mut().zip(&b_inv[i]) {
                    *r += w * bi;
                }
            }
            row
        })
        .collect();
    Some(rows)
}

/// The normalised times τ of the samples of one element with support `support` (ascending):
/// `k` equally spaced points strictly inside each interval between consecutive points.
pub fn sample_taus(support: &[f64], k: usize) -> Vec<f64> {
    support
        .windows(2)
        .flat_map(|w| (1..=k).map(move |j| w[0] + (w[1] - w[0]) * j as f64 / (k + 1) as f64))
        .collect()
}

impl Transcription {
    /// Adds the linear rows of `bounds` (module docs) after the existing rows; their block
    /// names are `phase P state I between points`. Returns the number of rows added.
    ///
    /// Errors: a phase or component that does not exist, lower > upper, a sample count or
    /// elevation out of range, a hull bound on an element of degree > [`MAX_HULL_DEGREE`] or
    /// one that does not span its interval (the last, open interval of a Legendre–Gauss
    /// phase is not bounded: see the module docs).
    pub fn bound_states_between_points(
        &mut self,
        bounds: &[StateBoundBetweenPoints],
    ) -> Result<usize, OptimError> {
        let m0 = self.m;
        let mut added: Vec<(usize, usize, f64)> = Vec::new();
        for b in bounds {
            let bad = |reason| OptimError::StateBound {
                phase: b.phase,
                component: b.component,
                reason,
            };
            let l = self
                .phases
                .get(b.phase)
                .ok_or_else(|| bad("no such phase"))?;
            if b.component >= l.nx {
                return Err(bad("no such state component"));
            }
            match b.how {
                Between::Samples(k) if !(1..=MAX_PER_INTERVAL).contains(&k) => {
                    return Err(bad("the samples per interval must be in 1..=64"));
                }
                Between::Hull(m) if !(1..=MAX_ELEVATION).contains(&m) => {
                    return Err(bad("the degree elevation must be in 1..=8"));
                }
                _ => {}
            }
            let (lo, hi) = (clean_bound(b.lower, true), clean_bound(b.upper, false));
            if lo > hi {
                return Err(bad("lower bound above upper bound"));
            }
            let r0 = self.m;
            for el in &l.mesh.elements {
                let support = &l.mesh.state_tau[el.clone()];
                let rows = match b.how {
                    Between::Samples(k) => sample_taus(support, k)
                        .into_iter()
                        .map(|tau| lagrange_basis(support, tau))
                        .collect(),
                    Between::Hull(_) if support.len() > MAX_HULL_DEGREE + 1 => {
                        return Err(bad("an element's degree exceeds 24 (hull bound)"));
                    }
                    Between::Hull(m) => hull_rows(support, m)
                        .ok_or_else(|| bad("singular Bernstein basis of an element"))?,
                };
                for coefficients in rows {
                    let row = self.m;
                    for (p, w) in el.clone().zip(coefficients) {
                        if w != 0.0 {
                            added.push((row, l.x(p, b.component), w));
                        }
                    }
                    self.gl.push(lo);
                    self.gu.push(hi);
                    self.m += 1;
                }
            }
            self.row_blocks.push((
                format!("phase {} state {} between points", b.phase, b.component),
                r0..self.m,
            ));
        }
        // The Jacobian pattern lists the linear entries first, in `linear` order
        // (`jacobian_values` writes them so), then the node and point functions' entries.
        let n_linear = self.linear.len();
        self.jac_pattern
            .splice(n_linear..n_linear, added.iter().map(|&(r, c, _)| (r, c)));
        self.linear.extend(added);
        Ok(self.m - m0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ocp::toys::double_integrator;

    #[test]
    fn samples_lie_strictly_inside_each_interval() {
        let t = sample_taus(&[-1.0, 0.0, 0.5], 3);
        assert_eq!(t, vec![-0.75, -0.5, -0.25, 0.125, 0.25, 0.375]);
    }

    /// The rows evaluate the element polynomial: at a point whose states are the values of a
    /// polynomial of the element's degree, each row equals that polynomial at its sample τ
    /// (Lagrange interpolation is exact for it), independently of the transcription's own
    /// interpolation code.
    #[test]
    fn rows_evaluate_the_state_polynomial_and_leave_the_other_rows_alone() {
        let ocp = double_integrator(false);
        let mut tr = Transcription::new(&ocp).unwrap();
        let (m0, pattern0, linear0) = (tr.m, tr.jac_pattern.len(), tr.linear.len());
        let mut g0 = vec![0.0; tr.m];
        let x_init = tr.initial().to_vec();
        crate::ipm::Nlp::constraints(&tr, &x_init, &mut g0);
        let l = tr.phases[0].clone();
        let added = tr
            .bound_states_between_points(&[StateBoundBetweenPoints {
                phase: 0,
                component: 1,
                lower: -2.0,
                upper: 3.0,
                how: Between::Samples(2),
            }])
            .unwrap();
        let expected: usize = l.mesh.elements.iter().map(|e| 2 * (e.len() - 1)).sum();
        assert_eq!(added, expected);
        assert_eq!(tr.m, m0 + added);
        // A cubic in τ, exact in every element of degree ≥ 3.
        let cubic = |t: f64| 0.3 - 1.1 * t + 0.7 * t * t + 0.4 * t * t * t;
        let mut x = x_init.clone();
        for (p, &t) in l.mesh.state_tau.iter().enumerate() {
            x[l.x(p, 1)] = cubic(t);
        }
        let mut g = vec![0.0; tr.m];
        crate::ipm::Nlp::constraints(&tr, &x, &mut g);
        let mut row = m0;
        for el in &l.mesh.elements {
            assert!(el.len() >= 4, "the toy's elements have degree ≥ 3");
            for t in sample_taus(&l.mesh.state_tau[el.clone()], 2) {
                assert!(
                    (g[row] - cubic(t)).abs() < 1e-12,
                    "row {row}: {} vs {}",
                    g[row],
                    cubic(t)
                );
                let (lo, hi) = tr.row_bounds();
                assert_eq!((lo[row], hi[row]), (-2.0, 3.0));
                row += 1;
            }
        }
        // The Jacobian's values line up with its pattern: the new rows' entries are ℓ_p(τ).
        let pattern = crate::ipm::Nlp::jacobian_structure(&tr);
        assert_eq!(pattern.len(), pattern0 + tr.linear.len() - linear0);
        let mut vals = vec![0.0; pattern.len()];
        crate::ipm::Nlp::jacobian_values(&tr, &x, &mut vals);
        let mut jx = vec![0.0; tr.m];
        for (&(r, c), v) in pattern.iter().zip(&vals) {
            if r >= m0 {
                jx[r] += v * x[c];
            }
        }
        for r in m0..tr.m {
            assert!((jx[r] - g[r]).abs() < 1e-12, "row {r}");
        }
        // The original rows are unchanged at the initial point.
        let mut g1 = vec![0.0; tr.m];
        crate::ipm::Nlp::constraints(&tr, &x_init, &mut g1);
        assert_eq!(&g1[..m0], &g0[..]);
    }

    #[test]
    fn bad_bounds_name_the_phase_and_component() {
        let mut tr = Transcription::new(&double_integrator(false)).unwrap();
        let b = |phase, component, lower, how| StateBoundBetweenPoints {
            phase,
            component,
            lower,
            upper: 1.0,
            how,
        };
        for (bound, reason) in [
            (b(1, 0, 0.0, Between::Samples(1)), "no such phase"),
            (b(0, 9, 0.0, Between::Hull(1)), "no such state component"),
            (
                b(0, 0, 2.0, Between::Samples(1)),
                "lower bound above upper bound",
            ),
            (
                b(0, 0, 0.0, Between::Samples(0)),
                "the samples per interval must be in 1..=64",
            ),
            (
                b(0, 0, 0.0, Between::Hull(9)),
                "the degree elevation must be in 1..=8",
            ),
        ] {
            let e = tr.bound_states_between_points(&[bound]).unwrap_err();
            assert_eq!(
                e,
                OptimError::StateBound {
                    phase: bound.phase,
                    component: bound.component,
                    reason
                }
            );
        }
    }

    /// Rest-to-rest double integrator (distance 1 in time 1, min ∫u²) with |v| ≤ V, V = 1.3
    /// below the unconstrained peak 1.5: the optimum (first-order state constraint, u
    /// continuous at the junctions) accelerates on [0, t₁] with v = V(1 − (1 − t/t₁)²), runs at
    /// v = V, and brakes symmetrically; the distance gives t₁ = 1.5 (1 − 1/V) and the cost
    /// J* = 8V²/(3 t₁). Bounded at the state points only, the velocity polynomial overshoots V
    /// between them; bounded between them too, it stays within V up to the sampling, and the
    /// optimum is the closed form to the discretisation error.
    #[test]
    fn a_velocity_bound_between_points_gives_the_state_constrained_optimum() {
        use crate::ipm::{OutputSettings, Settings};
        use crate::ocp::{extract, solve_nlp};
        let v_max = 1.3;
        let t1 = 1.5 * (1.0 - 1.0 / v_max);
        let j_star = 8.0 * v_max * v_max / (3.0 * t1);
        let mut ocp = double_integrator(false);
        ocp.scheme = Scheme::Radau { elements: 8 };
        ocp.phases[0].points = 48;
        ocp.phases[0].x_bounds[1] = (-v_max, v_max);
        let settings = Settings {
            output: OutputSettings { print_level: 0 },
            ..Settings::default()
        };
        let run = |how: Option<Between>| {
            let mut tr = Transcription::new(&ocp).unwrap();
            if let Some(how) = how {
                tr.bound_states_between_points(&[StateBoundBetweenPoints {
                    phase: 0,
                    component: 1,
                    lower: -v_max,
                    upper: v_max,
                    how,
                }])
                .unwrap();
            }
            let sol = solve_nlp(&tr, &settings, None, None).unwrap();
            assert!(sol.status.is_success(), "{:?}", sol.status);
            let traj = extract(&tr, &sol.x).remove(0);
            let peak = (0..=4000)
                .map(|k| traj.x_at(-1.0 + 2.0 * k as f64 / 4000.0)[1])
                .fold(f64::NEG_INFINITY, f64::max);
            (sol.objective, peak)
        };
        let (j_points, peak_points) = run(None);
        let (j_between, peak_between) = run(Some(Between::Samples(3)));
        let (j_hull, peak_hull) = run(Some(Between::Hull(2)));
        // The hull bounds the polynomial everywhere (to the solver's tolerance), at the price
        // of a slightly smaller feasible set than the true constraint's.
        assert!(peak_hull <= v_max + 1e-8, "{peak_hull}");
        assert!(j_hull >= j_star - 1e-6 * j_star, "{j_hull} < {j_star}");
        assert!(
            (j_hull - j_star).abs() <= 2e-2 * j_star,
            "{j_hull} vs {j_star}"
        );
        assert!(peak_points > v_max + 5e-4, "{peak_points}");
        assert!(peak_between <= v_max + 5e-5, "{peak_between}");
        // A smaller feasible set: the optimum cannot improve.
        assert!(j_between >= j_points - 1e-9, "{j_between} < {j_points}");
        assert!(
            (j_between - j_star).abs() <= 1e-4 * j_star,
            "{j_between} vs {j_star}"
        );
    }

    /// The hull rows are Bernstein coefficients: for p(u) = u on [0, 1] the coefficients of
    /// degree M are k/M (closed form), for a constant they are the constant (partition of
    /// unity), and for any polynomial of the element's degree they enclose its values.
    #[test]
    fn hull_rows_are_the_elevated_bernstein_coefficients() {
        // An element of degree 6 on [−0.2, 0.6] (Radau-like support: both ends included).
        let support = [-0.2, -0.15, -0.02, 0.15, 0.33, 0.5, 0.6];
        let (a, b) = (support[0], support[6]);
        for m in [1, 2, 3] {
            let rows = hull_rows(&support, m).unwrap();
            let big = 6 * m;
            assert_eq!(rows.len(), big - 1);
            let apply = |f: &dyn Fn(f64) -> f64, row: &[f64]| -> f64 {
                support.iter().zip(row).map(|(&t, c)| c * f(t)).sum()
            };
            for (k, row) in rows.iter().enumerate() {
                let k = k + 1;
                assert!((apply(&|_| 1.0, row) - 1.0).abs() < 1e-10);
                let lin = apply(&|t| (t - a) / (b - a), row);
                assert!(
                    (lin - k as f64 / big as f64).abs() < 1e-10,
                    "{lin} vs {k}/{big}"
                );
            }
            let p = |t: f64| 3.0 * t.powi(6) - 2.0 * t.powi(3) + t - 0.1;
            let coef: Vec<f64> = rows.iter().map(|r| apply(&p, r)).collect();
            let hull_lo = coef.iter().copied().fold(p(a).min(p(b)), f64::min);
            let hull_hi = coef.iter().copied().fold(p(a).max(p(b)), f64::max);
            for j in 0..=1000 {
                let v = p(a + (b - a) * j as f64 / 1000.0);
                assert!(
                    v >= hull_lo - 1e-12 && v <= hull_hi + 1e-12,
                    "{v} outside hull"
                );
            }
        }
    }
}
