//! The paper's Appendix A (eq. 67–71) and Appendix B (eq. 72–79) transcribed LITERALLY as
//! printed (`*_printed`), next to the corrected forms (`*_corrected`) derived from the DH
//! table. The tests at the bottom compare both against [`crate::reference::Reference`] over
//! random states and non-unit parameters; every disagreement is documented in
//! `docs/appendix-errata.md`.
//!
//! Notation. Appendix A: `s_{ij…k}` = sin(q_i + q_j + … + q_k), a barred index enters with a
//! minus sign (`s_{1\bar2\bar3}` = sin(q1 − q2 − q3)). Appendix B: `s_{xyz}` =
//! sin(x q1 + y q2 + z q3) with integer coefficients, trailing zeros omitted (`s_{11}` =
//! sin(q1 + q2), `s_{01}` = sin q2, `s_{022}` = sin(2q2 + 2q3)), a barred digit is negative.
//!
//! | function | paper | status |
//! |---|---|---|
//! | [`p_e_printed`] / [`p_e_corrected`] | eq. 67 | the constant `2ℓ` must be `2r` (o_f = (2r,0,0)) |
//! | [`frame3_axes_printed`] | eq. 68 | correct |
//! | [`jp_printed`] / [`jp_corrected`] | eq. 70 | sign of entry (3,3) |
//! | [`jo_printed`] | eq. 71 | correct |
//! | [`gravity_printed`] / [`gravity_corrected`] | eq. 72–73 | `s_{11\bar1}` must be `s_{111}` (rows 2, 3); `g_0` is the scalar magnitude g |
//! | [`potential_printed`] / [`potential_corrected`] | eq. 22b | sign (U = −Σ m g_0ᵀ p) |
//! | [`mass_matrix_printed`] | eq. 74–75 | correct |
//! | [`psi_printed`], [`coriolis_printed`] | eq. 76–79 | correct (ψ are Christoffel symbols) |

use crate::reference::{ContactKind, Pose, RefBall, RefLink, Reference};
use crate::small::axis_rotation;
use bf_codegen::spec::DhConvention;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters of the appendix formulas (the paper's numbers use ℓ = r = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AppendixParams {
    /// Link length ℓ (all three links), m.
    pub l: f64,
    /// Ball radius r (base at o_f = (2r, 0, 0)), m.
    pub r: f64,
    /// Link masses m_1..m_3, kg.
    pub m: [f64; 3],
    /// I_xx of links 1..3 about the COG, link axes, kg m².
    pub ixx: [f64; 3],
    /// I_yy of links 1..3.
    pub iyy: [f64; 3],
    /// I_zz of links 1..3.
    pub izz: [f64; 3],
    /// Gravity magnitude g (g_0 = (0, 0, −g)), m/s².
    pub g: f64,
}

impl AppendixParams {
    /// The project's paper scene (docs/parameters.md): ℓ = r = 1, m = 0.02 kg,
    /// I = diag(1.0677, 2.3177, 2.0833)e-3 kg m², g = 9.81.
    pub fn paper() -> Self {
        AppendixParams {
            l: 1.0,
            r: 1.0,
            m: [0.02; 3],
            ixx: [1.0677e-3; 3],
            iyy: [2.3177e-3; 3],
            izz: [2.0833e-3; 3],
            g: 9.81,
        }
    }

    /// A finger of link length `l` on a ball of radius `r` with unequal masses
    /// (0.03, 0.05, 0.011 kg) and unequal, non-isotropic inertias, g = 9.81: no symmetry of the
    /// paper's parameters can hide a wrong index.
    pub fn unequal(l: f64, r: f64) -> Self {
        AppendixParams {
            l,
            r,
            m: [0.03, 0.05, 0.011],
            ixx: [1e-3, 2e-3, 3e-3],
            iyy: [4e-3, 1.5e-3, 2.5e-3],
            izz: [3e-3, 5e-3, 1e-3],
            g: 9.81,
        }
    }

    /// The reference model of the same finger (Table 1 DH, base at (2r,0,0) rotated −90° about
    /// y, COG at the link middle (−ℓ/2, 0, 0), ball of radius r at the origin).
    pub fn reference(&self) -> Reference {
        let half_pi = std::f64::consts::FRAC_PI_2;
        let links = (0..3)
            .map(|i| RefLink {
                a: self.l,
                alpha: if i == 0 { half_pi } else { 0.0 },
                d: 0.0,
                offset: 0.0,
                prismatic: false,
                mass: self.m[i],
                com: [-self.l / 2.0, 0.0, 0.0],
                inertia: [
                    [self.ixx[i], 0.0, 0.0],
                    [0.0, self.iyy[i], 0.0],
                    [0.0, 0.0, self.izz[i]],
                ],
            })
            .collect();
        Reference {
            convention: DhConvention::Standard,
            base: Pose {
                rotation: axis_rotation(1, -half_pi),
                translation: [2.0 * self.r, 0.0, 0.0],
            },
            tool: None,
            gravity: [0.0, 0.0, -self.g],
            links,
            ball: Some(RefBall {
                center: [0.0; 3],
                radius: self.r,
            }),
            contact_kind: Some(ContactKind::Segment),
            mu_v: 0.0,
        }
    }
}

/// Appendix A: sin of a signed sum of joints, `sa(q, &[1, -2, -3])` = s_{1\bar2\bar3}.
fn sa(q: &[f64; 3], idx: &[i32]) -> f64 {
    libm::sin(sum_a(q, idx))
}

/// Appendix A: cos of a signed sum of joints.
fn ca(q: &[f64; 3], idx: &[i32]) -> f64 {
    libm::cos(sum_a(q, idx))
}

fn sum_a(q: &[f64; 3], idx: &[i32]) -> f64 {
    idx.iter()
        .map(|&i| {
            let v = q[(i.unsigned_abs() - 1) as usize];
            if i < 0 { -v } else { v }
        })
        .sum()
}

/// Appendix B: s_{xyz} = sin(x q1 + y q2 + z q3) (missing trailing coefficients are 0).
fn sb(q: &[f64; 3], c: &[i32]) -> f64 {
    libm::sin(sum_b(q, c))
}

/// Appendix B: c_{xyz} = cos(x q1 + y q2 + z q3).
fn cb(q: &[f64; 3], c: &[i32]) -> f64 {
    libm::cos(sum_b(q, c))
}

fn sum_b(q: &[f64; 3], c: &[i32]) -> f64 {
    c.iter().zip(q).map(|(&x, &v)| f64::from(x) * v).sum()
}

/// eq. 67 as printed: p_e = [−s23 − s2 + 2; ½(s123 + s1̄2̄3 + s12 + s12̄) + s1; ½(c12̄3̄ + c123
/// + c12̄ + c12) + c1] ℓ.
pub fn p_e_printed(q: &[f64; 3], l: f64) -> [f64; 3] {
    [
        (-sa(q, &[2, 3]) - sa(q, &[2]) + 2.0) * l,
        (0.5 * (sa(q, &[1, 2, 3]) + sa(q, &[1, -2, -3]) + sa(q, &[1, 2]) + sa(q, &[1, -2]))
            + sa(q, &[1]))
            * l,
        (0.5 * (ca(q, &[1, -2, -3]) + ca(q, &[1, 2, 3]) + ca(q, &[1, -2]) + ca(q, &[1, 2]))
            + ca(q, &[1]))
            * l,
    ]
}

/// eq. 67 corrected: the base offset is o_f = (2r, 0, 0), so the constant is 2r, not 2ℓ.
pub fn p_e_corrected(q: &[f64; 3], l: f64, r: f64) -> [f64; 3] {
    let p = p_e_printed(q, l);
    [p[0] - 2.0 * l + 2.0 * r, p[1], p[2]]
}

/// eq. 68 as printed: the columns are e_x3, e_y3, e_z3 (row-major 3×3).
pub fn frame3_axes_printed(q: &[f64; 3]) -> [[f64; 3]; 3] {
    [
        [-sa(q, &[2, 3]), -ca(q, &[2, 3]), 0.0],
        [
            0.5 * (sa(q, &[1, 2, 3]) + sa(q, &[1, -2, -3])),
            0.5 * (ca(q, &[1, 2, 3]) - ca(q, &[1, -2, -3])),
            -ca(q, &[1]),
        ],
        [
            0.5 * (ca(q, &[1, -2, -3]) + ca(q, &[1, 2, 3])),
            0.5 * (sa(q, &[1, -2, -3]) - sa(q, &[1, 2, 3])),
            sa(q, &[1]),
        ],
    ]
}

/// eq. 70 as printed (with J_21, J_31 below it).
pub fn jp_printed(q: &[f64; 3], l: f64) -> [[f64; 3]; 3] {
    let j21 = 0.5 * (ca(q, &[1, -2, -3]) + ca(q, &[1, 2, 3]) + ca(q, &[1, -2]) + ca(q, &[1, 2]))
        + ca(q, &[1]);
    let j31 = -0.5 * (sa(q, &[1, 2, 3]) + sa(q, &[1, -2, -3]) + sa(q, &[1, 2]) + sa(q, &[1, -2]))
        - sa(q, &[1]);
    let m = [
        [0.0, -ca(q, &[2, 3]) - ca(q, &[2]), -ca(q, &[2, 3])],
        [
            j21,
            0.5 * (ca(q, &[1, 2, 3]) - ca(q, &[1, -2, -3]) - ca(q, &[1, -2]) + ca(q, &[1, 2])),
            0.5 * (ca(q, &[1, 2, 3]) - ca(q, &[1, -2, -3])),
        ],
        [
            j31,
            0.5 * (sa(q, &[1, -2, -3]) - sa(q, &[1, 2, 3]) - sa(q, &[1, 2]) + sa(q, &[1, -2])),
            -0.5 * (sa(q, &[1, -2, -3]) - sa(q, &[1, 2, 3])),
        ],
    ];
    m.map(|row| row.map(|x| x * l))
}

/// eq. 70 corrected: entry (3,3) is +½(s_{1\bar2\bar3} − s_{123}) ℓ = −c1 s23 ℓ.
pub fn jp_corrected(q: &[f64; 3], l: f64) -> [[f64; 3]; 3] {
    let mut m = jp_printed(q, l);
    m[2][2] = -m[2][2];
    m
}

/// eq. 71 as printed.
pub fn jo_printed(q: &[f64; 3]) -> [[f64; 3]; 3] {
    [
        [-1.0, 0.0, 0.0],
        [0.0, -ca(q, &[1]), -ca(q, &[1])],
        [0.0, sa(q, &[1]), sa(q, &[1])],
    ]
}

/// eq. 72–73 as printed, with `g0` the number substituted for the printed symbol g_0.
pub fn gravity_printed(q: &[f64; 3], p: &AppendixParams, g0: f64) -> [f64; 3] {
    gravity_eq72(q, p, g0, -1)
}

/// eq. 72 corrected: `s_{11\bar1}` → `s_{111}` in rows 2 and 3, and g_0 is the magnitude g
/// (g_0 = (0,0,−g) of eq. 22b would flip the sign).
pub fn gravity_corrected(q: &[f64; 3], p: &AppendixParams) -> [f64; 3] {
    gravity_eq72(q, p, p.g, 1)
}

/// eq. 72–73 with `g0` for g_0 and the term of rows 2 and 3 that the paper prints as
/// `s_{11\bar1}` read as `s_{11c}`: c = −1 as printed, c = +1 corrected.
fn gravity_eq72(q: &[f64; 3], p: &AppendixParams, g0: f64, c: i32) -> [f64; 3] {
    let [m1, m2, m3] = p.m;
    let g11 = 2.0 * m1 * sb(q, &[1])
        + (sb(q, &[1, 1]) + sb(q, &[1, -1]) + 4.0 * sb(q, &[1])) * m2
        + (sb(q, &[1, 1, 1])
            + sb(q, &[1, -1, -1])
            + 2.0 * sb(q, &[1, 1])
            + 2.0 * sb(q, &[1, -1])
            + 4.0 * sb(q, &[1]))
            * m3;
    let g2 = m2 * (sb(q, &[1, 1]) - sb(q, &[1, -1]))
        + (sb(q, &[1, 1, c]) - sb(q, &[1, -1, -1]) + 2.0 * sb(q, &[1, 1]) - 2.0 * sb(q, &[1, -1]))
            * m3;
    let g3 = m3 * (sb(q, &[1, 1, c]) - sb(q, &[1, -1, -1]));
    let f = -p.l / 4.0 * g0;
    [f * g11, f * g2, f * g3]
}

/// eq. 22b as printed, U_f = Σ m_i g_0ᵀ p_i with g_0 = (0, 0, −g); `coms` are the world COGs.
pub fn potential_printed(p: &AppendixParams, coms: &[[f64; 3]]) -> f64 {
    coms.iter().zip(p.m).map(|(c, m)| m * (-p.g) * c[2]).sum()
}

/// eq. 22b corrected (docs/parameters.md): U_f = −Σ m_i g_0ᵀ p_i = Σ m_i g z_i.
pub fn potential_corrected(p: &AppendixParams, coms: &[[f64; 3]]) -> f64 {
    -potential_printed(p, coms)
}

/// m_11 of eq. 75 as printed.
pub fn m11_printed(q: &[f64; 3], p: &AppendixParams) -> f64 {
    let [m1, m2, m3] = p.m;
    let [_, ixx2, ixx3] = p.ixx;
    let [iyy1, iyy2, iyy3] = p.iyy;
    let l2 = p.l * p.l;
    (1.0 / 8.0) * (-4.0 * ixx3 + 4.0 * iyy3 + m3 * l2) * cb(q, &[0, 2, 2])
        + 0.5 * m3 * l2 * cb(q, &[0, 2, 1])
        + (1.0 / 8.0) * (8.0 * cb(q, &[0, 1]) + 9.0) * m2 * l2
        + (1.0 / 8.0) * ((m2 + 4.0 * m3) * l2 - 4.0 * ixx2 + 4.0 * iyy2) * cb(q, &[0, 2, 0])
        + 0.5 * (iyy2 + ixx3 + iyy3 + ixx2)
        + (1.0 / 8.0)
            * (16.0 * cb(q, &[0, 1]) + 4.0 * cb(q, &[0, 0, 1]) + 8.0 * cb(q, &[0, 1, 1]) + 13.0)
            * m3
            * l2
        + iyy1
        + 0.25 * m1 * l2
}

/// eq. 74 as printed.
pub fn mass_matrix_printed(q: &[f64; 3], p: &AppendixParams) -> [[f64; 3]; 3] {
    let [_, m2, m3] = p.m;
    let [_, izz2, izz3] = p.izz;
    let l2 = p.l * p.l;
    let c001 = cb(q, &[0, 0, 1]);
    let m22 = 0.25 * m2 * l2 + (c001 + 1.25) * m3 * l2 + izz2 + izz3;
    let m23 = 0.25 * (2.0 * c001 + 1.0) * m3 * l2 + izz3;
    let m33 = 0.25 * m3 * l2 + izz3;
    [
        [m11_printed(q, p), 0.0, 0.0],
        [0.0, m22, m23],
        [0.0, m23, m33],
    ]
}

/// ψ_ijk of eq. 77–79 as printed (`out[i][j][k]`, 0-based), all others zero.
pub fn psi_printed(q: &[f64; 3], p: &AppendixParams) -> [[[f64; 3]; 3]; 3] {
    let [_, m2, m3] = p.m;
    let [_, ixx2, ixx3] = p.ixx;
    let [_, iyy2, iyy3] = p.iyy;
    let l2 = p.l * p.l;
    let psi112 = (1.0 / 8.0) * (4.0 * ixx3 - 4.0 * iyy3 - m3 * l2) * sb(q, &[0, 2, 2])
        - 0.5 * m3 * l2 * sb(q, &[0, 2, 1])
        - (1.0 / 8.0) * ((4.0 * m3 + m2) * l2 - 4.0 * ixx2 + 4.0 * iyy2) * sb(q, &[0, 2])
        - 0.5 * m3 * l2 * sb(q, &[0, 1, 1])
        - (0.5 * m2 + m3) * l2 * sb(q, &[0, 1]);
    let psi113 = (1.0 / 8.0) * (4.0 * ixx3 - 4.0 * iyy3 - m3 * l2) * sb(q, &[0, 2, 2])
        - 0.25 * m3 * l2 * (2.0 * sb(q, &[0, 1, 1]) + sb(q, &[0, 0, 1]) + sb(q, &[0, 2, 1]));
    let psi223 = -0.5 * m3 * l2 * sb(q, &[0, 0, 1]);
    let mut out = [[[0.0; 3]; 3]; 3];
    out[0][0][1] = psi112;
    out[0][1][0] = psi112;
    out[1][0][0] = -psi112;
    out[0][0][2] = psi113;
    out[0][2][0] = psi113;
    out[2][0][0] = -psi113;
    out[1][1][2] = psi223;
    out[1][2][1] = psi223;
    out[1][2][2] = psi223;
    out[2][1][1] = -psi223;
    out
}

/// C(q, q̇) of eq. 76 with the printed ψ.
pub fn coriolis_printed(q: &[f64; 3], qd: &[f64; 3], p: &AppendixParams) -> [[f64; 3]; 3] {
    let psi = psi_printed(q, p);
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| psi[i][j][k] * qd[k]).sum();
        }
    }
    c
}

fn uniform(r: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    r.random_range(lo..hi)
}

/// Distinct, non-unit parameters (ℓ ≠ 1, r ≠ ℓ, unequal masses and inertias).
fn random_params(r: &mut ChaCha8Rng) -> AppendixParams {
    let mut t = || {
        [
            uniform(r, 1e-3, 5e-3),
            uniform(r, 1e-3, 5e-3),
            uniform(r, 1e-3, 5e-3),
        ]
    };
    let (ixx, iyy, izz) = (t(), t(), t());
    AppendixParams {
        l: uniform(r, 0.4, 1.6),
        r: uniform(r, 0.5, 2.0),
        m: [
            uniform(r, 0.01, 0.1),
            uniform(r, 0.01, 0.1),
            uniform(r, 0.01, 0.1),
        ],
        ixx,
        iyy,
        izz,
        g: uniform(r, 5.0, 12.0),
    }
}

/// The error measure of the appendix comparisons, max |a − b| / (1 + max |b|): absolute for
/// entries of order one or below, relative for large ones.
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let scale = 1.0 + b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// A row-major 3×3 matrix as a flat vector of its rows.
pub fn flat3(m: &[[f64; 3]; 3]) -> Vec<f64> {
    m.iter().flatten().copied().collect()
}

/// The parameter sets the appendix is checked on: the paper's (ℓ = r = 1), ℓ = r = 0.7 with
/// unequal masses and inertias, and `n_random` seeded random ones (ℓ ∈ [0.4, 1.6],
/// r ∈ [0.5, 2], unequal masses and inertias, g ∈ [5, 12]); the same sets on every machine.
pub fn param_sets(n_random: usize) -> Vec<AppendixParams> {
    let mut r = ChaCha8Rng::seed_from_u64(67);
    let mut v = vec![AppendixParams::paper(), AppendixParams::unequal(0.7, 0.7)];
    v.extend((0..n_random).map(|_| random_params(&mut r)));
    v
}
