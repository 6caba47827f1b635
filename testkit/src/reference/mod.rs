//! Independent reference implementation of the finger kinematics, dynamics and contact
//! geometry, for ANY [`Scene`](bf_codegen::spec::Scene) (standard or modified DH, base and tool
//! transforms, full inertia tensors). Written from the paper and docs/parameters.md only, never from
//! `bf-codegen`'s code, so the generated kernels can be checked against it.
//!
//! Joints are revolute (θ_i = q_i + offset) or prismatic (d_i = q_i + d; Jacobian column
//! (z_j, 0), the Newton–Euler pass adds the sliding terms 2ω × z ḋ + z d̈).
//!
//! Method: plain 4×4 homogeneous transforms built by multiplying the elementary DH factors, a
//! geometric Jacobian from the z-axis cross-product construction, and the Lagrangian quantities
//! evaluated generically over [`Real`]; running the same code on `num_dual::Dual64` gives
//! *exact* first derivatives.
//!
//! | symbol | paper | method |
//! |---|---|---|
//! | A_i | Table 1, Sect. 2.1 | `Rz(θ) Tz(d) Tx(a) Rx(α)` (standard) or `Rx(α) Tx(a) Rz(θ) Tz(d)` (modified) |
//! | J_p, J_o | eq. 69–71 | columns z_j × (p − o_j), z_j |
//! | M(q) | eq. 22a | Σ m_i J_Pᵢᵀ J_Pᵢ + J_Oᵢᵀ R_i I_i R_iᵀ J_Oᵢ |
//! | U(q) | eq. 22b (PARAMS sign) | −Σ m_i g_0ᵀ p_i |
//! | ∂M/∂q_k, g = ∂U/∂q | eq. 24, 72 | dual numbers seeded on q_k |
//! | c_ijk, C | eq. 76 | ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) |
//! | J̇ q̇ | eq. 33 | dual numbers seeded with q̇ (directional derivative along q̇) |
//! | α, sat, p_c, r_c, h, n, J_c, v_c, Δv | eq. 2–7, 11, 13 | direct |
//! | smooth sat | eq. 58–59 | ½(L + U + √((x−L)²+ε²) − √((x−U)²+ε²)) |
//! | ṙ_c, ḣ, J̇_c q̇ | eq. 33 | dual numbers seeded with q̇ |
//! | inverse dynamics | eq. 24 | recursive Newton–Euler in world axes (independent of M, C) |
//!
//! Construction from a scene file and the setting of its constants by name are in `scene.rs`.

mod scene;

pub use scene::angle_rad;

use bf_codegen::spec::DhConvention;
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;

use crate::error::TestkitError;
use crate::small::*;

/// A rigid transform in f64: `x_world = rotation · x_local + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation matrix, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation (m).
    pub translation: [f64; 3],
}

impl Pose {
    /// The identity transform.
    pub const IDENTITY: Pose = Pose {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };
}

/// One DH row with the link's inertial data, all in f64 (angles in radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefLink {
    /// DH a (m).
    pub a: f64,
    /// DH α (rad).
    pub alpha: f64,
    /// DH d (m).
    pub d: f64,
    /// Joint offset: θ = q + offset (rad).
    pub offset: f64,
    /// Prismatic joint: d_i = q_i + `d` and θ_i = `offset` (otherwise θ_i = q_i + `offset`).
    pub prismatic: bool,
    /// Mass m_i (kg).
    pub mass: f64,
    /// COG in link-frame coordinates (m).
    pub com: [f64; 3],
    /// Inertia about the COG in link-frame axes (kg m²), row-major.
    pub inertia: [[f64; 3]; 3],
}

/// The ball (only its geometry matters here).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefBall {
    /// Centre o_b (m).
    pub center: [f64; 3],
    /// Radius r (m).
    pub radius: f64,
}

/// Which points of the last link can touch the ball (scene `[contact] kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactKind {
    /// The segment from p_e − a_n e_x to p_e (eq. 3 with sat).
    Segment,
    /// The fingertip only: sat ≡ 0.
    Tip,
}

/// Contact quantities of eq. 2–7, 11, 13 and the bias terms of eq. 33 (mirrors `Contact` of
/// docs/kernels.md, with `j_c` as a 3×n matrix).
#[derive(Debug, Clone, PartialEq)]
pub struct RefContact {
    /// eq. 2: (o_b − p_e)·e_x.
    pub alpha: f64,
    /// sat_{−a_n}^{0}(α), exact or smooth.
    pub sat_alpha: f64,
    /// eq. 3: p_e + sat(α) e_x.
    pub p_c: [f64; 3],
    /// r_c = p_c − o_b.
    pub r_c: [f64; 3],
    /// eq. 4: |r_c| − r.
    pub h: f64,
    /// eq. 11: r_c / |r_c|.
    pub n: [f64; 3],
    /// eq. 7: J_p − sat(α) S(e_x) J_o (3 × n).
    pub j_c: DMatrix<f64>,
    /// eq. 6: J_c q̇.
    pub v_c: [f64; 3],
    /// eq. 13: ω × r_c − v_c.
    pub delta_v: [f64; 3],
    /// dh/dt = n·ṙ_c.
    pub h_dot: f64,
    /// ṙ_c (includes d sat(α)/dt).
    pub rc_dot: [f64; 3],
    /// J̇_c q̇ (includes d sat(α)/dt).
    pub jc_dot_qd: [f64; 3],
}

/// Forward kinematics of one configuration, generic over the scalar.
#[derive(Debug, Clone)]
pub struct Kinematics<T: Real> {
    /// `frames[0]` = base frame, `frames[i]` = DH frame i (i = 1..n), WITHOUT the tool.
    pub frames: Vec<H4<T>>,
    /// The last DH frame followed by the tool transform (the "tip" frame).
    pub tip: H4<T>,
    /// World direction of joint axis i (0-based).
    pub axis_z: Vec<V3<T>>,
    /// A world point on joint axis i that is fixed in both adjacent links.
    pub axis_o: Vec<V3<T>>,
}

/// Generic contact geometry (no velocities).
#[derive(Debug, Clone)]
pub struct ContactGeom<T: Real> {
    /// α of eq. 2.
    pub alpha: T,
    /// sat(α).
    pub sat: T,
    /// p_c.
    pub p_c: V3<T>,
    /// r_c.
    pub r_c: V3<T>,
    /// h.
    pub h: T,
    /// n.
    pub n: V3<T>,
    /// J_c columns.
    pub jc_cols: Vec<V3<T>>,
}

/// The reference model: all scene constants as plain public f64 fields (tests may change them,
/// e.g. to unequal masses, and compare against kernels called with matching runtime parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// DH convention of `links`.
    pub convention: DhConvention,
    /// Base transform.
    pub base: Pose,
    /// Tool transform after the last DH frame (None = identity).
    pub tool: Option<Pose>,
    /// Gravity g_0 (m/s²).
    pub gravity: [f64; 3],
    /// DH rows and inertial data.
    pub links: Vec<RefLink>,
    /// The ball, if any.
    pub ball: Option<RefBall>,
    /// Contact kind (None when the scene has no `[contact]`; contact then defaults to Segment).
    pub contact_kind: Option<ContactKind>,
    /// Joint viscous friction μ_v (0 without `[friction]`).
    pub mu_v: f64,
}

fn eps3(v: V3<Dual64>) -> [f64; 3] {
    [v[0].eps, v[1].eps, v[2].eps]
}

fn re3(v: V3<Dual64>) -> [f64; 3] {
    [v[0].re, v[1].re, v[2].re]
}

/// q as dual numbers with derivative direction `dir` (q + ε·dir).
pub fn dual_along(q: &[f64], dir: &[f64]) -> Vec<Dual64> {
    q.iter()
        .zip(dir)
        .map(|(&x, &d)| Dual64::new(x, d))
        .collect()
}

/// q as dual numbers seeded on coordinate `k` (∂/∂q_k).
pub fn dual_unit(q: &[f64], k_: usize) -> Vec<Dual64> {
    q.iter()
        .enumerate()
        .map(|(j, &x)| Dual64::new(x, if j == k_ { 1.0 } else { 0.0 }))
        .collect()
}

impl Reference {
    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.links.len()
    }

    // ------------------------------------------------------------------ generic core

    /// Forward kinematics: every DH frame as a 4×4 world transform, the tip frame and the joint
    /// axes, by literally multiplying the elementary DH factors.
    ///
    /// # Panics
    /// If `q.len() != self.nq()` (a test-programming error; every method taking `q` calls this).
    pub fn kinematics<T: Real>(&self, q: &[T]) -> Kinematics<T> {
        assert_eq!(q.len(), self.nq(), "q has the wrong length");
        let base: H4<T> = h_from(&lift33(self.base.rotation), lift3(self.base.translation));
        let mut frames = Vec::with_capacity(self.nq() + 1);
        frames.push(base);
        let mut axis_z = Vec::with_capacity(self.nq());
        let mut axis_o = Vec::with_capacity(self.nq());
        for (i, l) in self.links.iter().enumerate() {
            let (theta, dd) = if l.prismatic {
                (k::<T>(l.offset), q[i] + k::<T>(l.d))
            } else {
                (q[i] + k::<T>(l.offset), k::<T>(l.d))
            };
            let (st, ct) = theta.sin_cos();
            let (sa, ca) = sin_cos_const(l.alpha);
            let prev = frames[i];
            let a = match self.convention {
                DhConvention::Standard => {
                    // Joint i turns about z_{i-1} through o_{i-1} (both fixed in link i-1).
                    axis_z.push(col(&h_rot(&prev), 2));
                    axis_o.push(h_pos(&prev));
                    let m = mul4(&rot_z(st, ct), &trans_z(dd));
                    let m = mul4(&m, &trans_x(k(l.a)));
                    mul4(&m, &rot_x(k(sa), k(ca)))
                }
                DhConvention::Modified => {
                    let m = mul4(&rot_x(k(sa), k(ca)), &trans_x(k(l.a)));
                    // Joint i turns about z_i through the origin of Rx(α)Tx(a), fixed in link i-1.
                    let pre = mul4(&prev, &m);
                    axis_z.push(col(&h_rot(&pre), 2));
                    axis_o.push(h_pos(&pre));
                    let m = mul4(&m, &rot_z(st, ct));
                    mul4(&m, &trans_z(dd))
                }
            };
            frames.push(mul4(&prev, &a));
        }
        let last = frames[self.nq()];
        let tip = match &self.tool {
            Some(t) => mul4(&last, &h_from(&lift33(t.rotation), lift3(t.translation))),
            None => last,
        };
        Kinematics {
            frames,
            tip,
            axis_z,
            axis_o,
        }
    }

    /// Geometric Jacobian columns (linear, angular) of a world point `p` rigidly attached to
    /// link `link` (1-based): column j is z_j × (p − o_j), z_j for j < link, zero otherwise.
    pub fn point_jacobian<T: Real>(
        &self,
        kin: &Kinematics<T>,
        link: usize,
        p: V3<T>,
    ) -> (Vec<V3<T>>, Vec<V3<T>>) {
        let n = self.nq();
        let mut jp = vec![zero3(); n];
        let mut jo = vec![zero3(); n];
        for j in 0..link.min(n) {
            if self.links[j].prismatic {
                jp[j] = kin.axis_z[j];
            } else {
                jp[j] = cross(kin.axis_z[j], sub(p, kin.axis_o[j]));
                jo[j] = kin.axis_z[j];
            }
        }
        (jp, jo)
    }

    /// World COG of every link.
    pub fn com_positions<T: Real>(&self, kin: &Kinematics<T>) -> Vec<V3<T>> {
        self.links
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let f = &kin.frames[i + 1];
                add(h_pos(f), matvec(&h_rot(f), lift3(l.com)))
            })
            .collect()
    }

    /// Tip Jacobian columns (linear, angular).
    pub fn tip_jacobian_t<T: Real>(&self, q: &[T]) -> (Vec<V3<T>>, Vec<V3<T>>) {
        let kin = self.kinematics(q);
        let p = h_pos(&kin.tip);
        self.point_jacobian(&kin, self.nq(), p)
    }

    /// M(q) of eq. 22a, generic.
    pub fn mass_matrix_t<T: Real>(&self, q: &[T]) -> Vec<Vec<T>> {
        let n = self.nq();
        let kin = self.kinematics(q);
        let coms = self.com_positions(&kin);
        let mut m = vec![vec![k::<T>(0.0); n]; n];
        for (i, l) in self.links.iter().enumerate() {
            let (jp, jo) = self.point_jacobian(&kin, i + 1, coms[i]);
            let r = h_rot(&kin.frames[i + 1]);
            let iw = matmul(&matmul(&r, &lift33(l.inertia)), &transpose(&r));
            let iw_jo: Vec<V3<T>> = jo.iter().map(|c| matvec(&iw, *c)).collect();
            for a in 0..n {
                for b in 0..n {
                    m[a][b] += k::<T>(l.mass) * dot(jp[a], jp[b]) + dot(jo[a], iw_jo[b]);
                }
            }
        }
        m
    }

    /// U(q) = −Σ m_i g_0ᵀ p_i (docs/parameters.md sign), generic.
    pub fn potential_t<T: Real>(&self, q: &[T]) -> T {
        let kin = self.kinematics(q);
        let g0 = lift3::<T>(self.gravity);
        let mut u = k::<T>(0.0);
        for (l, p) in self.links.iter().zip(self.com_positions(&kin)) {
            u -= k::<T>(l.mass) * dot(g0, p);
        }
        u
    }

    /// Contact geometry (eq. 2–4, 7, 11); `smooth_eps = Some(ε)` uses eq. 58–59.
    pub fn contact_geom_t<T: Real>(
        &self,
        q: &[T],
        smooth_eps: Option<f64>,
    ) -> Result<ContactGeom<T>, TestkitError> {
        let ball = self.ball.ok_or(TestkitError::NoBall)?;
        let kin = self.kinematics(q);
        let p_e = h_pos(&kin.tip);
        let e_x = col(&h_rot(&kin.tip), 0);
        let o_b = lift3::<T>(ball.center);
        let alpha = dot(sub(o_b, p_e), e_x);
        let lower = -self.links[self.nq() - 1].a;
        let sat = match self.contact_kind.unwrap_or(ContactKind::Segment) {
            ContactKind::Tip => k::<T>(0.0),
            ContactKind::Segment => match smooth_eps {
                None => {
                    if re(alpha) < lower {
                        k(lower)
                    } else if re(alpha) > 0.0 {
                        k(0.0)
                    } else {
                        alpha
                    }
                }
                Some(eps) => {
                    // eq. 58 with |x| ≈ sqrt(x² + ε²) (eq. 59), L = −a_n, U = 0.
                    let e2 = k::<T>(eps * eps);
                    let xl = alpha - k::<T>(lower);
                    let absl = (xl * xl + e2).sqrt();
                    let absu = (alpha * alpha + e2).sqrt();
                    (k::<T>(lower) + absl - absu) * 0.5
                }
            },
        };
        let p_c = add(p_e, scale(sat, e_x));
        let r_c = sub(p_c, o_b);
        let dist = norm(r_c);
        let h = dist - k::<T>(ball.radius);
        let n = scale(dist.recip(), r_c);
        let (jp, jo) = self.point_jacobian(&kin, self.nq(), p_e);
        let jc_cols = jp
            .iter()
            .zip(&jo)
            .map(|(p, o)| sub(*p, scale(sat, cross(e_x, *o))))
            .collect();
        Ok(ContactGeom {
            alpha,
            sat,
            p_c,
            r_c,
            h,
            n,
            jc_cols,
        })
    }

    // ------------------------------------------------------------------ f64 API

    /// World origins and rotations of DH frames 1..n (frame n includes the tool), as the
    /// `frames` kernel.
    pub fn frames(&self, q: &[f64]) -> (Vec<[f64; 3]>, Vec<[[f64; 3]; 3]>) {
        let kin = self.kinematics(q);
        let n = self.nq();
        let mut pos = Vec::with_capacity(n);
        let mut rot = Vec::with_capacity(n);
        for i in 1..=n {
            let f = if i == n { &kin.tip } else { &kin.frames[i] };
            pos.push(h_pos(f));
            rot.push(h_rot(f));
        }
        (pos, rot)
    }

    /// Tip position p_e (origin of the tip frame).
    pub fn tip_position(&self, q: &[f64]) -> [f64; 3] {
        h_pos(&self.kinematics(q).tip)
    }

    /// Tip geometric Jacobian (J_p, J_o), each 3 × n.
    pub fn tip_jacobian(&self, q: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let (jp, jo) = self.tip_jacobian_t(q);
        (cols_to_mat(&jp), cols_to_mat(&jo))
    }

    /// World COG positions of every link.
    pub fn com_positions_f64(&self, q: &[f64]) -> Vec<[f64; 3]> {
        let kin = self.kinematics(q);
        self.com_positions(&kin)
    }

    /// COG Jacobians (J_Pᵢ, J_Oᵢ) of every link, each 3 × n.
    pub fn com_jacobians(&self, q: &[f64]) -> Vec<(DMatrix<f64>, DMatrix<f64>)> {
        let kin = self.kinematics(q);
        let coms = self.com_positions(&kin);
        (0..self.nq())
            .map(|i| {
                let (jp, jo) = self.point_jacobian(&kin, i + 1, coms[i]);
                (cols_to_mat(&jp), cols_to_mat(&jo))
            })
            .collect()
    }

    /// J̇ q̇ of the tip (linear part then angular part), exact via dual numbers along q̇.
    pub fn tip_jdot_qd(&self, q: &[f64], qd: &[f64]) -> [f64; 6] {
        let (jp, jo) = self.tip_jacobian_t(&dual_along(q, qd));
        let mut out = [0.0; 6];
        for (j, &v) in qd.iter().enumerate() {
            for r in 0..3 {
                out[r] += jp[j][r].eps * v;
                out[3 + r] += jo[j][r].eps * v;
            }
        }
        out
    }

    /// M(q), eq. 22a.
    pub fn mass_matrix(&self, q: &[f64]) -> DMatrix<f64> {
        rows_to_mat(&self.mass_matrix_t(q))
    }

    /// ∂M/∂q_k, exact: `out[k][(i, j)] = ∂M_ij/∂q_k`.
    pub fn dmass_dq(&self, q: &[f64]) -> Vec<DMatrix<f64>> {
        (0..self.nq())
            .map(|kk| {
                let m = self.mass_matrix_t(&dual_unit(q, kk));
                let n = self.nq();
                DMatrix::from_fn(n, n, |i, j| m[i][j].eps)
            })
            .collect()
    }

    /// Christoffel symbols of the first kind, `out[i][j][k] = c_ijk`.
    pub fn christoffel(&self, q: &[f64]) -> Vec<Vec<Vec<f64>>> {
        let dm = self.dmass_dq(q);
        let n = self.nq();
        let mut c = vec![vec![vec![0.0; n]; n]; n];
        for i in 0..n {
            for j in 0..n {
                for kk in 0..n {
                    c[i][j][kk] = 0.5 * (dm[kk][(i, j)] + dm[j][(i, kk)] - dm[i][(j, kk)]);
                }
            }
        }
        c
    }

    /// C(q, q̇) in Christoffel form, C_ij = Σ_k c_ijk q̇_k (eq. 76).
    pub fn coriolis_matrix(&self, q: &[f64], qd: &[f64]) -> DMatrix<f64> {
        let c = self.christoffel(q);
        let n = self.nq();
        DMatrix::from_fn(n, n, |i, j| (0..n).map(|kk| c[i][j][kk] * qd[kk]).sum())
    }

    /// C(q, q̇) q̇.
    pub fn coriolis_qd(&self, q: &[f64], qd: &[f64]) -> DVector<f64> {
        self.coriolis_matrix(q, qd) * DVector::from_column_slice(qd)
    }

    /// g(q) = ∂U/∂q, exact.
    pub fn gravity(&self, q: &[f64]) -> DVector<f64> {
        DVector::from_fn(self.nq(), |kk, _| self.potential_t(&dual_unit(q, kk)).eps)
    }

    /// U(q) = −Σ m_i g_0ᵀ p_i.
    pub fn potential(&self, q: &[f64]) -> f64 {
        self.potential_t(q)
    }

    /// Kinetic energy ½ q̇ᵀ M q̇.
    pub fn kinetic_energy(&self, q: &[f64], qd: &[f64]) -> f64 {
        let v = DVector::from_column_slice(qd);
        0.5 * v.dot(&(self.mass_matrix(q) * &v))
    }

    /// C q̇ + g.
    pub fn cqd_g(&self, q: &[f64], qd: &[f64]) -> DVector<f64> {
        self.coriolis_qd(q, qd) + self.gravity(q)
    }

    /// Forward dynamics of the free finger (eq. 26a): q̈ = M⁻¹(τ − C q̇ − μ_v q̇ − g).
    pub fn forward_dynamics(
        &self,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
    ) -> Result<DVector<f64>, TestkitError> {
        let qdv = DVector::from_column_slice(qd);
        let rhs = DVector::from_column_slice(tau) - self.cqd_g(q, qd) - &qdv * self.mu_v;
        let chol = self
            .mass_matrix(q)
            .cholesky()
            .ok_or(TestkitError::SingularMassMatrix)?;
        let x = chol.solve(&rhs);
        if x.iter().all(|v| v.is_finite()) {
            Ok(x)
        } else {
            Err(TestkitError::SingularMassMatrix)
        }
    }

    /// Inverse dynamics by the recursive Newton–Euler algorithm in world axes (no friction):
    /// τ = M q̈ + C q̇ + g, computed WITHOUT M, C or g, so it cross-checks the Lagrangian path.
    /// Gravity enters as a base acceleration −g_0.
    pub fn inverse_dynamics_ne(&self, q: &[f64], qd: &[f64], qdd: &[f64]) -> DVector<f64> {
        let n = self.nq();
        let kin = self.kinematics(q);
        let coms = self.com_positions(&kin);
        // Forward pass: ω, ω̇ of each link, acceleration of its joint point x_i.
        let mut w = [0.0; 3];
        let mut wd = [0.0; 3];
        let mut a_x = scale(-1.0, self.gravity);
        let mut x_prev = kin.axis_o[0];
        let mut w_l = Vec::with_capacity(n);
        let mut wd_l = Vec::with_capacity(n);
        let mut a_c = Vec::with_capacity(n);
        for i in 0..n {
            let z = kin.axis_z[i];
            let x = kin.axis_o[i];
            // x_i is fixed in link i−1: carry the acceleration along link i−1.
            let r = sub(x, x_prev);
            a_x = add(a_x, add(cross(wd, r), cross(w, cross(w, r))));
            if self.links[i].prismatic {
                // The point of link i at x_i slides along z relative to link i−1.
                a_x = add(a_x, add(scale(2.0 * qd[i], cross(w, z)), scale(qdd[i], z)));
            } else {
                let w_new = add(w, scale(qd[i], z));
                wd = add(add(wd, scale(qdd[i], z)), scale(qd[i], cross(w, z)));
                w = w_new;
            }
            let rc = sub(coms[i], x);
            a_c.push(add(a_x, add(cross(wd, rc), cross(w, cross(w, rc)))));
            w_l.push(w);
            wd_l.push(wd);
            x_prev = x;
        }
        // Backward pass: force and moment (about x_i) that link i−1 exerts on link i.
        let mut tau = DVector::zeros(n);
        let mut f_next = [0.0; 3];
        let mut m_next = [0.0; 3];
        for i in (0..n).rev() {
            let l = &self.links[i];
            let x = kin.axis_o[i];
            let r = h_rot(&kin.frames[i + 1]);
            let iw = matmul(&matmul(&r, &l.inertia), &transpose(&r));
            let f_i = scale(l.mass, a_c[i]);
            let n_i = add(matvec(&iw, wd_l[i]), cross(w_l[i], matvec(&iw, w_l[i])));
            let x_next = if i + 1 < n { kin.axis_o[i + 1] } else { x };
            let f = add(f_i, f_next);
            let m = add(
                add(n_i, cross(sub(coms[i], x), f_i)),
                add(m_next, cross(sub(x_next, x), f_next)),
            );
            // A prismatic joint carries the force along its axis, a revolute one the moment.
            tau[i] = dot(kin.axis_z[i], if l.prismatic { f } else { m });
            f_next = f;
            m_next = m;
        }
        tau
    }

    /// Contact quantities of docs/kernels.md at (q, q̇, ω); `smooth_eps = Some(ε)` for the
    /// smooth saturation (the `contact_smooth` kernel).
    pub fn contact(
        &self,
        q: &[f64],
        qd: &[f64],
        omega: &[f64; 3],
        smooth_eps: Option<f64>,
    ) -> Result<RefContact, TestkitError> {
        let g = self.contact_geom_t(&dual_along(q, qd), smooth_eps)?;
        let n = self.nq();
        let j_c = DMatrix::from_fn(3, n, |r, j| g.jc_cols[j][r].re);
        let mut v_c = [0.0; 3];
        let mut jc_dot_qd = [0.0; 3];
        for j in 0..n {
            for r in 0..3 {
                v_c[r] += g.jc_cols[j][r].re * qd[j];
                jc_dot_qd[r] += g.jc_cols[j][r].eps * qd[j];
            }
        }
        let r_c = re3(g.r_c);
        let delta_v = sub(cross(*omega, r_c), v_c);
        Ok(RefContact {
            alpha: g.alpha.re,
            sat_alpha: g.sat.re,
            p_c: re3(g.p_c),
            r_c,
            h: g.h.re,
            n: re3(g.n),
            j_c,
            v_c,
            delta_v,
            h_dot: g.h.eps,
            rc_dot: eps3(g.r_c),
            jc_dot_qd,
        })
    }
}

/// 3 × n matrix from n column vectors.
pub fn cols_to_mat(cols: &[[f64; 3]]) -> DMatrix<f64> {
    DMatrix::from_fn(3, cols.len(), |r, c| cols[c][r])
}

/// Matrix from nested rows.
pub fn rows_to_mat(rows: &[Vec<f64>]) -> DMatrix<f64> {
    let n = rows.len();
    let m = rows.first().map_or(0, |r| r.len());
    DMatrix::from_fn(n, m, |i, j| rows[i][j])
}
