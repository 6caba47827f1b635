//! The mass matrix by the composite-rigid-body algorithm ([`SymbolicRobot`] methods), in the link
//! frames and with the link transforms A_i of the recursive Newton–Euler pass, so a kernel
//! holding both shares the rotations R_i, the offsets t_i and the joint axes u_i:
//! * composite inertia of the subtree of link i about o_i in frame i, as the standard inertial
//!   parameters (m, h = m c, I_o) of [`super::INERTIAL_PARAMETER_NAMES`]: C_i = π_i ⊕ A_{i+1} C_{i+1}
//!   with, for x ↦ R x + t, m' = m, h' = R h + m t and
//!   I_o' = R I_o Rᵀ + (2 (R h)·t + m |t|²) 1 − ((R h) tᵀ + t (R h)ᵀ + m t tᵀ);
//! * the spatial force of the subtree under a unit acceleration of joint i,
//!   f = m v + ω × h, n = I_o ω + h × v (ω, v = motion of frame i's origin for q̇_i = 1), moved
//!   to lower frames as in the backward Newton–Euler pass (f ↦ R f, n ↦ R n + t × R f);
//! * M_ji = M_ij = the joint-j component of that force (moment about joint j's axis for a
//!   revolute joint, force along it for a prismatic one) — eq. 22a without Jacobians.

use super::{FrameKind, SymbolicRobot};
use crate::graph::{Id, M3, V3};

/// Composite inertia (m, h = m c, I_o about the frame origin), link-frame axes.
#[derive(Clone, Copy)]
struct Inertia {
    m: Id,
    h: V3,
    io: M3,
}

impl SymbolicRobot {
    /// Standard DH: o_i − o_{i−1} in frame i (closed form of `build_kinematics`); modified DH
    /// and general placements: the zero vector (joint i's axis passes through o_i).
    pub(super) fn joint_offset(&mut self, i: usize) -> V3 {
        if self.frames.axis_at_own_origin() {
            let z = self.g.zero();
            return [z; 3];
        }
        let t = self.a_invs[i].t;
        [self.g.neg(t[0]), self.g.neg(t[1]), self.g.neg(t[2])]
    }

    /// Joint i's axis u_i in frame i.
    pub(super) fn joint_axis(&mut self, i: usize) -> V3 {
        if let Some(u) = self.scene.links[i].axis {
            return u.map(|x| self.g.constant(x));
        }
        if self.frames == FrameKind::DhModified {
            let (z, o) = (self.g.zero(), self.g.one());
            return [z, z, o];
        }
        let r = self.a_mats[i].r;
        [r[2][0], r[2][1], r[2][2]]
    }

    /// The joint-i component of a spatial force (f, n about o_i) in frame i.
    pub(super) fn joint_component(&mut self, i: usize, f: V3, n: V3) -> Id {
        let u = self.joint_axis(i);
        if self.prismatic(i) {
            return self.g.v3_dot(u, f);
        }
        if self.frames.axis_at_own_origin() {
            return self.g.v3_dot(u, n);
        }
        let r = self.joint_offset(i);
        let rf = self.g.v3_cross(r, f);
        let m = self.g.v3_add(n, rf);
        self.g.v3_dot(u, m)
    }

    /// Sᵀ F = ω · n + v · f for a motion (ω, v) and a force (f, n about the same origin).
    fn motion_dot_force(&mut self, s: (V3, V3), f: V3, n: V3) -> Id {
        let a = self.g.v3_dot(s.0, n);
        let b = self.g.v3_dot(s.1, f);
        self.g.add(a, b)
    }

    /// C ⊕ A C' with A = a_mats[k] (frame k+1 → frame k).
    fn add_moved_inertia(&mut self, c: Inertia, child: Inertia, k: usize) -> Inertia {
        let a = self.a_mats[k];
        let g = &mut self.g;
        let rh = g.m3_mul_v(&a.r, child.h);
        let mt = g.v3_scale(child.m, a.t);
        let h_moved = g.v3_add(rh, mt);
        let ri = g.m3_mul(&a.r, &child.io);
        let rt = crate::graph::m3_transpose(&a.r);
        let rir = g.m3_mul(&ri, &rt);
        // Parallel-axis shift of the origin by −t, with the rotated first moment.
        let rht = g.v3_dot(rh, a.t);
        let tt = g.v3_dot(a.t, a.t);
        let two = g.constant(2.0);
        let a2 = g.mul(two, rht);
        let mtt = g.mul(child.m, tt);
        let diag = g.add(a2, mtt);
        let mut io = c.io;
        for p in 0..3 {
            for q in p..3 {
                let x = g.mul(rh[p], a.t[q]);
                let y = g.mul(a.t[p], rh[q]);
                let w = g.mul(mt[p], a.t[q]);
                let s = g.add(x, y);
                let s = g.add(s, w);
                let mut e = g.sub(rir[p][q], s);
                if p == q {
                    e = g.add(e, diag);
                }
                io[p][q] = g.add(c.io[p][q], e);
                io[q][p] = io[p][q];
            }
        }
        Inertia {
            m: g.add(c.m, child.m),
            h: g.v3_add(c.h, h_moved),
            io,
        }
    }

    /// Mass matrix M(q), eq. 22a, by the composite-rigid-body algorithm (module doc).
    pub fn mass_matrix_crba(&mut self) -> Vec<Vec<Id>> {
        if let Some(m) = &self.cache.mass_crba {
            return m.clone();
        }
        let n = self.nq();
        let z = self.g.zero();
        let own: Vec<Inertia> = (0..n)
            .map(|i| {
                let p = self.inertial_nodes(i);
                Inertia {
                    m: p[0],
                    h: [p[1], p[2], p[3]],
                    io: [[p[4], p[5], p[6]], [p[5], p[7], p[8]], [p[6], p[8], p[9]]],
                }
            })
            .collect();
        let mut comp = own.clone();
        for i in (0..n.saturating_sub(1)).rev() {
            comp[i] = self.add_moved_inertia(own[i], comp[i + 1], i + 1);
        }
        // Motion subspace S_i = (ω, v) of every joint in its link frame, for q̇_i = 1:
        // (u, u × r) revolute, (0, u) prismatic; M_ji = S_jᵀ F with F in frame j.
        let motion: Vec<(V3, V3)> = (0..n)
            .map(|i| {
                let u = self.joint_axis(i);
                if self.prismatic(i) {
                    ([z; 3], u)
                } else {
                    let r = self.joint_offset(i);
                    (u, self.g.v3_cross(u, r))
                }
            })
            .collect();
        let mut mm = vec![vec![z; n]; n];
        for i in 0..n {
            let c = comp[i];
            let (w, v) = motion[i];
            let mv = self.g.v3_scale(c.m, v);
            let wh = self.g.v3_cross(w, c.h);
            let mut f = self.g.v3_add(mv, wh);
            let iw = self.g.m3_mul_v(&c.io, w);
            let hv = self.g.v3_cross(c.h, v);
            let mut nn = self.g.v3_add(iw, hv);
            mm[i][i] = self.motion_dot_force(motion[i], f, nn);
            for j in (0..i).rev() {
                let a = self.a_mats[j + 1];
                let rf = self.g.m3_mul_v(&a.r, f);
                let rn = self.g.m3_mul_v(&a.r, nn);
                let tf = self.g.v3_cross(a.t, rf);
                f = rf;
                nn = self.g.v3_add(rn, tf);
                mm[j][i] = self.motion_dot_force(motion[j], f, nn);
                mm[i][j] = mm[j][i];
            }
        }
        self.cache.mass_crba = Some(mm.clone());
        mm
    }
}
