//! The inverse-dynamics family of the robot front-end ([`SymbolicRobot`] methods):
//! * inverse dynamics τ(q, q̇, q̈) = M q̈ + C q̇ + g (eq. 24) by a recursive Newton–Euler pass
//!   written *linearly* in the standard inertial parameters π of every link (m, m·c and the
//!   inertia I_o about the link frame's origin, [`super::INERTIAL_PARAMETER_NAMES`]):
//!   F_i = m a_i + ω̇_i × h + ω_i × (ω_i × h), N_i = I_o ω̇_i + ω_i × I_o ω_i + h × a_i
//!   (h = m c, a_i the acceleration of frame i's origin), revolute and prismatic joints, both
//!   DH conventions; the same pass with the centroidal wrench F_i = m a_{c,i},
//!   N_i = I_c ω̇_i + ω_i × I_c ω_i + c × F_i and q̈ = 0 gives C q̇ + g (`cqd_g_rnea`);
//! * ∂τ/∂q and ∂τ/∂q̇ by forward-mode differentiation of that graph;
//! * the dynamic regressor Y = ∂τ/∂π, exact because τ is linear in π (τ = Y π), by reverse
//!   mode with π as graph variables (π does not survive in Y);
//! * forward dynamics q̈ = M⁻¹(τ − C q̇ − g) (eq. 26a without friction) by an LDLᵀ
//!   factorisation of M unrolled into the graph (no loops, no pivoting: M is positive
//!   definite).

use super::SymbolicRobot;
use crate::diff;

/// How the Newton–Euler pass forms each link's force F and moment N about o_i.
#[derive(Clone, Copy)]
pub(super) enum Wrench<'a> {
    /// Linear in the standard inertial parameters π of every link (module doc), for the
    /// regressor and the inverse-dynamics family.
    Linear(&'a [[Id; 10]]),
    /// From the scene's mass m, COG c and inertia I_c about the COG: F = m a_c,
    /// N = I_c ω̇ + ω × I_c ω + c × F (fewer operations than the π form when I_c is diagonal).
    Centroidal,
}
use crate::graph::{Id, Node, V3};

/// How a forward-dynamics graph was built ([`SymbolicRobot::forward_dynamics_form`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForwardForm {
    /// M (and C q̇ + g) as in the `mass_cqd_g` kernel, an unrolled LDLᵀ factorisation of M.
    Ldl,
    /// The articulated-body algorithm (`aba` module).
    ArticulatedBody,
}

impl SymbolicRobot {
    /// π of link `i` as graph nodes from the scene's values (runtime parameters stay
    /// variables): [m, m c, I_o upper triangle], I_o = I_c + m(|c|² 1 − c cᵀ).
    pub(super) fn inertial_nodes(&mut self, i: usize) -> [Id; 10] {
        let m = self.constant(&format!("link{}.mass", i + 1));
        let c = self.com_local(i);
        let ic = self.link_inertia(i);
        let h = self.g.v3_scale(m, c);
        let cc = self.g.v3_dot(c, c);
        let mut io = |a: usize, b: usize| {
            let cab = self.g.mul(c[a], c[b]);
            let s = if a == b {
                self.g.sub(cc, cab)
            } else {
                self.g.neg(cab)
            };
            let ms = self.g.mul(m, s);
            self.g.add(ic[a][b], ms)
        };
        let (xx, xy, xz, yy, yz, zz) = (io(0, 0), io(0, 1), io(0, 2), io(1, 1), io(1, 2), io(2, 2));
        [m, h[0], h[1], h[2], xx, xy, xz, yy, yz, zz]
    }

    /// π of link `i` as the graph variables [`super::Layout::inertial`].
    fn inertial_vars(&mut self, i: usize) -> [Id; 10] {
        std::array::from_fn(|k| self.g.var(self.layout.inertial(i, k)))
    }

    fn qdd_ids(&mut self) -> Vec<Id> {
        (0..self.nq())
            .map(|i| self.g.var(self.layout.qdd(i)))
            .collect()
    }

    /// Recursive Newton–Euler inverse dynamics with joint accelerations `qdd`, link-frame axes
    /// throughout, each link's wrench formed as `wrench` says.
    pub(super) fn rnea(&mut self, wrench: Wrench<'_>, qdd: &[Id]) -> Vec<Id> {
        let n = self.nq();
        let z = self.g.zero();
        let qd = self.qd_ids();
        let modified = self.frames.axis_at_own_origin();
        let g0 = self.cvec("gravity");
        let base_r = self.world[0].r;
        let ng0 = [self.g.neg(g0[0]), self.g.neg(g0[1]), self.g.neg(g0[2])];
        // Gravity as a fictitious upward acceleration of the base.
        let mut acc = self.g.m3_tmul_v(&base_r, ng0);
        let mut w: V3 = [z; 3];
        let mut wd: V3 = [z; 3];
        // Per link: the force and the moment about o_i formed in the forward pass.
        let mut forces: Vec<(V3, V3)> = Vec::with_capacity(n);
        for i in 0..n {
            let a = self.a_mats[i];
            let u = self.joint_axis(i);
            let prismatic = self.prismatic(i);
            let w_prev = self.g.m3_tmul_v(&a.r, w);
            let wd_prev = self.g.m3_tmul_v(&a.r, wd);
            let (wi, wdi) = if prismatic {
                (w_prev, wd_prev)
            } else {
                let uq = self.g.v3_scale(qd[i], u);
                let uqq = self.g.v3_scale(qdd[i], u);
                let wi = self.g.v3_add(w_prev, uq);
                let cr = self.g.v3_cross(w_prev, uq);
                let s = self.g.v3_add(wd_prev, uqq);
                (wi, self.g.v3_add(s, cr))
            };
            let mut ai = if modified {
                // Frame i's origin sits at t in link i−1 (moving along z_i if prismatic).
                let t = a.t;
                let x = self.g.v3_cross(wd, t);
                let y0 = self.g.v3_cross(w, t);
                let y = self.g.v3_cross(w, y0);
                let s = self.g.v3_add(acc, x);
                let s = self.g.v3_add(s, y);
                self.g.m3_tmul_v(&a.r, s)
            } else {
                // o_{i−1} lies on joint i's axis: a_i = Rᵀa_{i−1} + ω̇_i×r + ω_i×(ω_i×r).
                let r = self.joint_offset(i);
                let ap = self.g.m3_tmul_v(&a.r, acc);
                let x = self.g.v3_cross(wdi, r);
                let y0 = self.g.v3_cross(wi, r);
                let y = self.g.v3_cross(wi, y0);
                let s = self.g.v3_add(ap, x);
                self.g.v3_add(s, y)
            };
            if prismatic {
                // Sliding along u: Coriolis 2 ω × u ḋ and the joint acceleration u d̈.
                let uq = self.g.v3_scale(qd[i], u);
                let c = self.g.v3_cross(wi, uq);
                let two = self.g.constant(2.0);
                let c2 = self.g.v3_scale(two, c);
                let uqq = self.g.v3_scale(qdd[i], u);
                ai = self.g.v3_add(ai, c2);
                ai = self.g.v3_add(ai, uqq);
            }
            forces.push(match wrench {
                Wrench::Linear(pi) => {
                    let p = pi[i];
                    let (m, h) = (p[0], [p[1], p[2], p[3]]);
                    let io = [[p[4], p[5], p[6]], [p[5], p[7], p[8]], [p[6], p[8], p[9]]];
                    let ma = self.g.v3_scale(m, ai);
                    let x = self.g.v3_cross(wdi, h);
                    let y0 = self.g.v3_cross(wi, h);
                    let y = self.g.v3_cross(wi, y0);
                    let f = self.g.v3_add(ma, x);
                    let f = self.g.v3_add(f, y);
                    let iwd = self.g.m3_mul_v(&io, wdi);
                    let iw = self.g.m3_mul_v(&io, wi);
                    let wiw = self.g.v3_cross(wi, iw);
                    let ha = self.g.v3_cross(h, ai);
                    let nn = self.g.v3_add(iwd, wiw);
                    (f, self.g.v3_add(nn, ha))
                }
                Wrench::Centroidal => {
                    let c = self.com_local(i);
                    let x = self.g.v3_cross(wdi, c);
                    let y0 = self.g.v3_cross(wi, c);
                    let y = self.g.v3_cross(wi, y0);
                    let ac = self.g.v3_add(ai, x);
                    let ac = self.g.v3_add(ac, y);
                    let m = self.constant(&format!("link{}.mass", i + 1));
                    let f = self.g.v3_scale(m, ac);
                    let inertia = self.link_inertia(i);
                    let iw = self.g.m3_mul_v(&inertia, wi);
                    let iwd = self.g.m3_mul_v(&inertia, wdi);
                    let wiw = self.g.v3_cross(wi, iw);
                    // Moment about the COG; c × F is added in the backward pass.
                    (f, self.g.v3_add(iwd, wiw))
                }
            });
            acc = ai;
            w = wi;
            wd = wdi;
        }
        let mut f_next: V3 = [z; 3];
        let mut n_next: V3 = [z; 3];
        let mut tau = vec![z; n];
        for i in (0..n).rev() {
            // The child's wrench moved to frame i: R f, R n and t × R f (zero at the last link).
            let (ff, nf, tf) = if i + 1 < n {
                let a = self.a_mats[i + 1];
                let ff = self.g.m3_mul_v(&a.r, f_next);
                let nf = self.g.m3_mul_v(&a.r, n_next);
                let tf = self.g.v3_cross(a.t, ff);
                (ff, nf, tf)
            } else {
                ([z; 3], [z; 3], [z; 3])
            };
            let (f_own, n_own) = forces[i];
            let (fi, ni) = match wrench {
                Wrench::Linear(_) => {
                    let fi = self.g.v3_add(ff, f_own);
                    let ni = self.g.v3_add(nf, tf);
                    (fi, self.g.v3_add(ni, n_own))
                }
                Wrench::Centroidal => {
                    let nt = self.g.v3_add(nf, tf);
                    let fi = self.g.v3_add(ff, f_own);
                    let c = self.com_local(i);
                    let cf = self.g.v3_cross(c, f_own);
                    let ni = self.g.v3_add(nt, cf);
                    (fi, self.g.v3_add(ni, n_own))
                }
            };
            tau[i] = self.joint_component(i, fi, ni);
            f_next = fi;
            n_next = ni;
        }
        tau
    }

    /// Inverse dynamics τ = M q̈ + C q̇ + g (N m, or N for prismatic joints) with q̈ the
    /// variables [`super::Layout::qdd`].
    pub fn inverse_dynamics(&mut self) -> Vec<Id> {
        if let Some(t) = &self.cache.inverse {
            return t.clone();
        }
        let pi: Vec<[Id; 10]> = (0..self.nq()).map(|i| self.inertial_nodes(i)).collect();
        let qdd = self.qdd_ids();
        let tau = self.rnea(Wrench::Linear(&pi), &qdd);
        self.cache.inverse = Some(tau.clone());
        tau
    }

    /// ∂τ/∂q of the inverse dynamics: `out[i][k]` = ∂τ_i/∂q_k.
    pub fn inverse_dynamics_dq(&mut self) -> Vec<Vec<Id>> {
        let vars: Vec<u32> = (0..self.nq()).map(|k| self.layout.q(k)).collect();
        self.inverse_dynamics_jacobian(&vars)
    }

    /// ∂τ/∂q̇ of the inverse dynamics: `out[i][k]` = ∂τ_i/∂q̇_k.
    pub fn inverse_dynamics_dqd(&mut self) -> Vec<Vec<Id>> {
        let vars: Vec<u32> = (0..self.nq()).map(|k| self.layout.qd(k)).collect();
        self.inverse_dynamics_jacobian(&vars)
    }

    fn inverse_dynamics_jacobian(&mut self, vars: &[u32]) -> Vec<Vec<Id>> {
        let tau = self.inverse_dynamics();
        let cols: Vec<Vec<Id>> = vars
            .iter()
            .map(|&v| diff::partial(&mut self.g, &tau, v))
            .collect();
        (0..tau.len())
            .map(|i| cols.iter().map(|c| c[i]).collect())
            .collect()
    }

    /// The dynamic regressor: `out[i][l][k]` = ∂τ_i/∂π_{l,k}, so `τ = Σ_{l,k} Y[i][l][k] π_{l,k}`
    /// with π of [`super::inertial_parameters`].
    pub fn regressor(&mut self) -> Vec<Vec<Vec<Id>>> {
        let n = self.nq();
        let pi: Vec<[Id; 10]> = (0..n).map(|i| self.inertial_vars(i)).collect();
        let qdd = self.qdd_ids();
        let tau = self.rnea(Wrench::Linear(&pi), &qdd);
        let vars: Vec<u32> = (0..n)
            .flat_map(|l| (0..10).map(move |k| (l, k)))
            .map(|(l, k)| self.layout.inertial(l, k))
            .collect();
        let one = self.g.one();
        tau.iter()
            .map(|&t| {
                let row = diff::reverse(&mut self.g, &[(t, one)], &vars);
                row.chunks(10).map(|c| c.to_vec()).collect()
            })
            .collect()
    }

    /// Forward dynamics q̈ = M⁻¹(τ − C q̇ − g) with τ the variables [`super::Layout::tau`], by
    /// the form [`SymbolicRobot::forward_dynamics_form`] picks.
    pub fn forward_dynamics(&mut self) -> Vec<Id> {
        self.forward_dynamics_form().0
    }

    /// Forward dynamics of the LDLᵀ form ([`SymbolicRobot::forward_dynamics_ldl`]) or the
    /// articulated-body algorithm ([`SymbolicRobot::forward_dynamics_aba`]), the one with fewer
    /// operations (LDLᵀ on a tie), each costed on a copy of the graph so the other leaves no
    /// nodes behind; with the form used.
    pub fn forward_dynamics_form(&mut self) -> (Vec<Id>, ForwardForm) {
        let ldl = {
            let mut m = self.clone();
            let x = m.forward_dynamics_ldl();
            m.g.cost(&x)
        };
        let aba = {
            let mut m = self.clone();
            let x = m.forward_dynamics_aba();
            m.g.cost(&x)
        };
        if aba < ldl {
            (self.forward_dynamics_aba(), ForwardForm::ArticulatedBody)
        } else {
            (self.forward_dynamics_ldl(), ForwardForm::Ldl)
        }
    }

    /// Forward dynamics by M = L D Lᵀ unrolled (M and C q̇ + g as in the `mass_cqd_g` kernel),
    /// then L y = b, D z = y, Lᵀ q̈ = z.
    pub fn forward_dynamics_ldl(&mut self) -> Vec<Id> {
        let n = self.nq();
        // The cheapest M and C q̇ + g together, as in the `mass_cqd_g` kernel.
        let (m, h) = self.mass_cqd_g();
        let b: Vec<Id> = (0..n)
            .map(|i| {
                let t = self.g.var(self.layout.tau(i));
                self.g.sub(t, h[i])
            })
            .collect();
        let z = self.g.zero();
        let one = self.g.one();
        // ld[i][j] = L_ij D_j (j < i), l[i][j] = L_ij, dinv[j] = 1/D_j.
        let mut ld = vec![vec![z; n]; n];
        let mut l = vec![vec![z; n]; n];
        let mut dinv = vec![z; n];
        for j in 0..n {
            let mut d = m[j][j];
            for k in 0..j {
                let p = self.g.mul(l[j][k], ld[j][k]);
                d = self.g.sub(d, p);
            }
            dinv[j] = self.g.div(one, d);
            for i in j + 1..n {
                let mut s = m[i][j];
                for k in 0..j {
                    let p = self.g.mul(l[i][k], ld[j][k]);
                    s = self.g.sub(s, p);
                }
                ld[i][j] = s;
                l[i][j] = self.g.mul(s, dinv[j]);
            }
        }
        let mut y = vec![z; n];
        for i in 0..n {
            let mut s = b[i];
            for k in 0..i {
                let p = self.g.mul(l[i][k], y[k]);
                s = self.g.sub(s, p);
            }
            y[i] = s;
        }
        let mut x = vec![z; n];
        for i in (0..n).rev() {
            let mut s = self.g.mul(y[i], dinv[i]);
            for k in i + 1..n {
                let p = self.g.mul(l[k][i], x[k]);
                s = self.g.sub(s, p);
            }
            x[i] = s;
        }
        x
    }

    /// The graph variables in the cone of `roots` (sorted, deduplicated).
    pub fn cone_vars(&self, roots: &[Id]) -> Vec<u32> {
        let mark = self.g.cone(roots);
        let mut out: Vec<u32> = mark
            .iter()
            .enumerate()
            .filter(|(_, m)| **m)
            .filter_map(|(i, _)| match self.g.node(Id(i as u32)) {
                Node::Var(v) => Some(v),
                _ => None,
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}
