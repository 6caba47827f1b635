//! The inverse-dynamics family of the robot front-end ([`Model`] methods):
//! * inverse dynamics τ(q, q̇, q̈) = M q̈ + C q̇ + g (eq. 24) by a recursive Newton–Euler pass
//!   written *linearly* in the standard inertial parameters π of every link (m, m·c and the
//!   inertia I_o about the link frame's origin, [`super::INERTIAL_PARAMETER_NAMES`]):
//!   F_i = m a_i + ω̇_i × h + ω_i × (ω_i × h), N_i = I_o ω̇_i + ω_i × I_o ω_i + h × a_i
//!   (h = m c, a_i the acceleration of frame i's origin), revolute and prismatic joints, both
//!   DH conventions;
//! * ∂τ/∂q and ∂τ/∂q̇ by forward-mode differentiation of that graph;
//! * the dynamic regressor Y = ∂τ/∂π, exact because τ is linear in π (τ = Y π), by reverse
//!   mode with π as graph variables (π does not survive in Y);
//! * forward dynamics q̈ = M⁻¹(τ − C q̇ − g) (eq. 26a without friction) by an LDLᵀ
//!   factorisation of M unrolled into the graph (no loops, no pivoting: M is positive
//!   definite).

use super::Model;
use crate::diff;
use crate::graph::{Id, Node, V3};
use crate::spec::DhConvention;

impl Model {
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

    /// Recursive Newton–Euler inverse dynamics, linear in `pi` (one π per link), with joint
    /// accelerations `qdd`; link-frame axes throughout.
    pub(super) fn rnea_linear(&mut self, pi: &[[Id; 10]], qdd: &[Id]) -> Vec<Id> {
        let n = self.nq();
        let z = self.g.zero();
        let one = self.g.one();
        let qd = self.qd_ids();
        let modified = self.scene.dh == DhConvention::Modified;
        let g0 = self.cvec("gravity");
        let base_r = self.world[0].r;
        let ng0 = [self.g.neg(g0[0]), self.g.neg(g0[1]), self.g.neg(g0[2])];
        // Gravity as a fictitious upward acceleration of the base.
        let mut acc = self.g.m3_tmul_v(&base_r, ng0);
        let mut w: V3 = [z; 3];
        let mut wd: V3 = [z; 3];
        let mut forces: Vec<(V3, V3)> = Vec::with_capacity(n);
        // Standard DH: r = o_i − o_{i−1} in frame i (closed form, see `build_kinematics`).
        let r_std = |m: &mut Model, i: usize| -> V3 {
            let t = m.a_invs[i].t;
            [m.g.neg(t[0]), m.g.neg(t[1]), m.g.neg(t[2])]
        };
        for i in 0..n {
            let a = self.a_mats[i];
            // Joint i's axis in frame i.
            let u = if modified {
                [z, z, one]
            } else {
                [a.r[2][0], a.r[2][1], a.r[2][2]]
            };
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
                let r = r_std(self, i);
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
            let nn = self.g.v3_add(nn, ha);
            forces.push((f, nn));
            acc = ai;
            w = wi;
            wd = wdi;
        }
        let mut f_next: V3 = [z; 3];
        let mut n_next: V3 = [z; 3];
        let mut tau = vec![z; n];
        for i in (0..n).rev() {
            let (fi, ni) = if i + 1 < n {
                let a = self.a_mats[i + 1];
                let ff = self.g.m3_mul_v(&a.r, f_next);
                let nf = self.g.m3_mul_v(&a.r, n_next);
                let tf = self.g.v3_cross(a.t, ff);
                let fi = self.g.v3_add(ff, forces[i].0);
                let ni = self.g.v3_add(nf, tf);
                (fi, self.g.v3_add(ni, forces[i].1))
            } else {
                forces[i]
            };
            let prismatic = self.prismatic(i);
            tau[i] = if modified {
                if prismatic { fi[2] } else { ni[2] }
            } else {
                let a = self.a_mats[i];
                let u = [a.r[2][0], a.r[2][1], a.r[2][2]];
                if prismatic {
                    self.g.v3_dot(u, fi)
                } else {
                    // Moment about o_{i−1}, a point of joint i's axis.
                    let r = r_std(self, i);
                    let rf = self.g.v3_cross(r, fi);
                    let m = self.g.v3_add(ni, rf);
                    self.g.v3_dot(u, m)
                }
            };
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
        let tau = self.rnea_linear(&pi, &qdd);
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

    /// The dynamic regressor: `out[i][l][k]` = ∂τ_i/∂π_{l,k}, so τ = Σ_{l,k} Y[i][l][k] π_{l,k}
    /// with π of [`super::inertial_parameters`].
    pub fn regressor(&mut self) -> Vec<Vec<Vec<Id>>> {
        let n = self.nq();
        let pi: Vec<[Id; 10]> = (0..n).map(|i| self.inertial_vars(i)).collect();
        let qdd = self.qdd_ids();
        let tau = self.rnea_linear(&pi, &qdd);
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

    /// Forward dynamics q̈ = M⁻¹(τ − C q̇ − g) with τ the variables [`super::Layout::tau`]:
    /// M = L D Lᵀ unrolled, then L y = b, D z = y, Lᵀ q̈ = z.
    pub fn forward_dynamics(&mut self) -> Vec<Id> {
        let n = self.nq();
        let m = self.mass_matrix();
        let flat: Vec<Id> = m.iter().flatten().copied().collect();
        let h = self.cqd_g_cheapest(&flat);
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
