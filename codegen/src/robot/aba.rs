//! Forward dynamics q̈ = M⁻¹(τ − C q̇ − g) (eq. 26a without friction) by the articulated-body
//! algorithm ([`SymbolicRobot::forward_dynamics_aba`]), O(n) operations on a chain against the
//! O(n²) of M by the composite-rigid-body algorithm and the O(n³) of its LDLᵀ factorisation.
//! Spatial quantities in the link frames of the Newton–Euler pass, about each frame's origin:
//! motions (ω, v), forces (n, f); joint i's motion subspace S_i as in the `crba` module; the
//! frame change of A_i = (R, t) (frame i → frame i−1) maps motions down the chain as
//! ω ↦ Rᵀ ω, v ↦ Rᵀ (v + ω × t), forces up as f ↦ R f, n ↦ R n + t × R f, and an articulated
//! inertia [[A, B], [Bᵀ, C]] (n = A ω + B v, f = Bᵀ ω + C v) to the parent as
//! A' = R A Rᵀ, B' = R B Rᵀ, C' = R C Rᵀ, then with T = [t]×:
//! A_p = A' − B'T + T B'ᵀ − T C'T, B_p = B' + T C', C_p = C'.
//! Passes (Featherstone, Rigid Body Dynamics Algorithms, Table 7.1): velocities and bias terms
//! base to tip, articulated inertias tip to base, accelerations base to tip, gravity as an
//! upward acceleration of the base (as in the Newton–Euler pass).

use super::SymbolicRobot;
use crate::graph::{Id, M3, V3, m3_transpose};

/// A spatial motion (ω, v) or force (n, f), angular part first.
type Sv = (V3, V3);

/// Articulated-body inertia [[A, B], [Bᵀ, C]] (A, C symmetric).
#[derive(Clone, Copy)]
struct Abi {
    a: M3,
    b: M3,
    c: M3,
}

impl SymbolicRobot {
    fn m3_add(&mut self, x: &M3, y: &M3) -> M3 {
        std::array::from_fn(|i| std::array::from_fn(|j| self.g.add(x[i][j], y[i][j])))
    }

    /// [t]×, the matrix of t × ·.
    fn skew(&mut self, t: V3) -> M3 {
        let z = self.g.zero();
        let n: V3 = t.map(|x| self.g.neg(x));
        [[z, n[2], t[1]], [t[2], z, n[0]], [n[1], t[0], z]]
    }

    /// Force I m of the articulated inertia I and the motion m.
    fn abi_apply(&mut self, i: &Abi, m: Sv) -> Sv {
        let aw = self.g.m3_mul_v(&i.a, m.0);
        let bv = self.g.m3_mul_v(&i.b, m.1);
        let btw = self.g.m3_tmul_v(&i.b, m.0);
        let cv = self.g.m3_mul_v(&i.c, m.1);
        (self.g.v3_add(aw, bv), self.g.v3_add(btw, cv))
    }

    /// mᵀ F = ω · n + v · f.
    fn motion_force(&mut self, m: Sv, f: Sv) -> Id {
        let a = self.g.v3_dot(m.0, f.0);
        let b = self.g.v3_dot(m.1, f.1);
        self.g.add(a, b)
    }

    /// The motion m of frame i−1 in frame i (A_i = (R, t)).
    fn motion_down(&mut self, i: usize, m: Sv) -> Sv {
        let a = self.a_mats[i];
        let wt = self.g.v3_cross(m.0, a.t);
        let v = self.g.v3_add(m.1, wt);
        (self.g.m3_tmul_v(&a.r, m.0), self.g.m3_tmul_v(&a.r, v))
    }

    /// The force F of frame i in frame i−1.
    fn force_up(&mut self, i: usize, f: Sv) -> Sv {
        let a = self.a_mats[i];
        let rf = self.g.m3_mul_v(&a.r, f.1);
        let rn = self.g.m3_mul_v(&a.r, f.0);
        let tf = self.g.v3_cross(a.t, rf);
        (self.g.v3_add(rn, tf), rf)
    }

    /// The articulated inertia of frame i in frame i−1 (module doc). A and C are symmetric,
    /// and so is A_p: only their upper triangles are computed (R S Rᵀ row by column, mirrored),
    /// and T B'ᵀ = −(B'T)ᵀ (T is skew) is B'T transposed instead of a product of its own, which
    /// saves about a fifth of the algorithm's operations.
    fn abi_up(&mut self, i: usize, x: &Abi) -> Abi {
        let a = self.a_mats[i];
        let rt = m3_transpose(&a.r);
        let z = self.g.zero();
        let rot_sym = |m: &mut Self, s: &M3| -> M3 {
            let rs = m.g.m3_mul(&a.r, s);
            let mut out = [[z; 3]; 3];
            for p in 0..3 {
                for q in p..3 {
                    out[p][q] = m.g.dot(&rs[p], &a.r[q]);
                    out[q][p] = out[p][q];
                }
            }
            out
        };
        let (a1, c1) = (rot_sym(self, &x.a), rot_sym(self, &x.c));
        let rb = self.g.m3_mul(&a.r, &x.b);
        let b1 = self.g.m3_mul(&rb, &rt);
        let t = self.skew(a.t);
        let tt = m3_transpose(&t);
        let tc = self.g.m3_mul(&t, &c1);
        let bt = self.g.m3_mul(&b1, &t);
        let mut a_p = [[z; 3]; 3];
        for p in 0..3 {
            for q in p..3 {
                // A' − B'T + T B'ᵀ − T C'T, with T B'ᵀ = −(B'T)ᵀ.
                let tct = self.g.dot(&tc[p], &tt[q]);
                let x0 = self.g.sub(a1[p][q], bt[p][q]);
                let x1 = self.g.sub(x0, bt[q][p]);
                a_p[p][q] = self.g.sub(x1, tct);
                a_p[q][p] = a_p[p][q];
            }
        }
        let b_p = self.m3_add(&b1, &tc);
        Abi {
            a: a_p,
            b: b_p,
            c: c1,
        }
    }

    /// Motion cross product m × s = (ω × ω_s, ω × v_s + v × ω_s).
    fn cross_motion(&mut self, m: Sv, s: Sv) -> Sv {
        let ww = self.g.v3_cross(m.0, s.0);
        let wv = self.g.v3_cross(m.0, s.1);
        let vw = self.g.v3_cross(m.1, s.0);
        (ww, self.g.v3_add(wv, vw))
    }

    /// Force cross product m ×* F = (ω × n + v × f, ω × f).
    fn cross_force(&mut self, m: Sv, f: Sv) -> Sv {
        let wn = self.g.v3_cross(m.0, f.0);
        let vf = self.g.v3_cross(m.1, f.1);
        (self.g.v3_add(wn, vf), self.g.v3_cross(m.0, f.1))
    }

    /// Forward dynamics by the articulated-body algorithm (module doc), τ the variables
    /// [`super::Layout::tau`].
    pub fn forward_dynamics_aba(&mut self) -> Vec<Id> {
        let n = self.nq();
        let z = self.g.zero();
        let zv: V3 = [z; 3];
        let qd = self.qd_ids();
        // Motion subspaces S_i and rigid-body inertias about o_i (as in the `crba` module).
        let s: Vec<Sv> = (0..n)
            .map(|i| {
                let u = self.joint_axis(i);
                if self.prismatic(i) {
                    (zv, u)
                } else {
                    let r = self.joint_offset(i);
                    (u, self.g.v3_cross(u, r))
                }
            })
            .collect();
        let mut ia: Vec<Abi> = (0..n)
            .map(|i| {
                let p = self.inertial_nodes(i);
                let h = [p[1], p[2], p[3]];
                let hx = self.skew(h);
                Abi {
                    a: [[p[4], p[5], p[6]], [p[5], p[7], p[8]], [p[6], p[8], p[9]]],
                    b: hx,
                    c: [[p[0], z, z], [z, p[0], z], [z, z, p[0]]],
                }
            })
            .collect();
        // Pass 1: velocities, velocity-product accelerations c_i, bias forces p_i.
        let mut v: Sv = (zv, zv);
        let mut c = Vec::with_capacity(n);
        let mut pa = Vec::with_capacity(n);
        for i in 0..n {
            let vj = (
                self.g.v3_scale(qd[i], s[i].0),
                self.g.v3_scale(qd[i], s[i].1),
            );
            let vp = self.motion_down(i, v);
            let vi = (self.g.v3_add(vp.0, vj.0), self.g.v3_add(vp.1, vj.1));
            c.push(self.cross_motion(vi, vj));
            let iv = self.abi_apply(&ia[i], vi);
            pa.push(self.cross_force(vi, iv));
            v = vi;
        }
        // Pass 2: articulated inertias and bias forces, tip to base.
        let mut u_vec: Vec<Sv> = vec![(zv, zv); n];
        let mut d_inv = vec![z; n];
        let mut u_sc = vec![z; n];
        let one = self.g.one();
        for i in (0..n).rev() {
            let ui = self.abi_apply(&ia[i], s[i]);
            let d = self.motion_force(s[i], ui);
            let di = self.g.div(one, d);
            let tau = self.g.var(self.layout.tau(i));
            let sp = self.motion_force(s[i], pa[i]);
            let us = self.g.sub(tau, sp);
            (u_vec[i], d_inv[i], u_sc[i]) = (ui, di, us);
            if i == 0 {
                break;
            }
            // I^a = I^A − U D⁻¹ Uᵀ, p^a = p^A + I^a c + U D⁻¹ u.
            let ud: Sv = (self.g.v3_scale(di, ui.0), self.g.v3_scale(di, ui.1));
            let outer = |m: &mut Self, x: V3, y: V3, base: &M3| -> M3 {
                std::array::from_fn(|p| {
                    std::array::from_fn(|q| {
                        let xy = m.g.mul(x[p], y[q]);
                        m.g.sub(base[p][q], xy)
                    })
                })
            };
            let mut small = Abi {
                a: outer(self, ud.0, ui.0, &ia[i].a),
                b: outer(self, ud.0, ui.1, &ia[i].b),
                c: outer(self, ud.1, ui.1, &ia[i].c),
            };
            // A and C stay symmetric: use one triangle so both halves share nodes.
            for p in 0..3 {
                for q in 0..p {
                    small.a[p][q] = small.a[q][p];
                    small.c[p][q] = small.c[q][p];
                }
            }
            let ic = self.abi_apply(&small, c[i]);
            let pa_i = (self.g.v3_add(pa[i].0, ic.0), self.g.v3_add(pa[i].1, ic.1));
            let uu = (self.g.v3_scale(us, ud.0), self.g.v3_scale(us, ud.1));
            let pa_i = (self.g.v3_add(pa_i.0, uu.0), self.g.v3_add(pa_i.1, uu.1));
            let moved = self.abi_up(i, &small);
            ia[i - 1] = Abi {
                a: self.m3_add(&ia[i - 1].a, &moved.a),
                b: self.m3_add(&ia[i - 1].b, &moved.b),
                c: self.m3_add(&ia[i - 1].c, &moved.c),
            };
            let f = self.force_up(i, pa_i);
            pa[i - 1] = (
                self.g.v3_add(pa[i - 1].0, f.0),
                self.g.v3_add(pa[i - 1].1, f.1),
            );
        }
        // Pass 3: accelerations, base to tip; gravity as an upward base acceleration.
        let g0 = self.cvec("gravity");
        let base_r = self.world[0].r;
        let ng0 = g0.map(|x| self.g.neg(x));
        let mut acc: Sv = (zv, self.g.m3_tmul_v(&base_r, ng0));
        let mut qdd = vec![z; n];
        for i in 0..n {
            let ap = self.motion_down(i, acc);
            let ap = (self.g.v3_add(ap.0, c[i].0), self.g.v3_add(ap.1, c[i].1));
            let ua = self.motion_force(ap, u_vec[i]);
            let num = self.g.sub(u_sc[i], ua);
            qdd[i] = self.g.mul(num, d_inv[i]);
            acc = (
                {
                    let x = self.g.v3_scale(qdd[i], s[i].0);
                    self.g.v3_add(ap.0, x)
                },
                {
                    let x = self.g.v3_scale(qdd[i], s[i].1);
                    self.g.v3_add(ap.1, x)
                },
            );
        }
        qdd
    }
}
