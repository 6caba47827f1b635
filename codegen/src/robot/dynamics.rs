//! Joint-space dynamics of the robot front-end ([`SymbolicRobot`] methods), conventions of
//! docs/parameters.md:
//! * M = Σ m_i J_Pᵢᵀ J_Pᵢ + J_Oᵢᵀ R_i I_i R_iᵀ J_Oᵢ (eq. 22a, 74–75), built from Jacobians
//!   expressed in the link's own frame so M depends only on relative joint angles;
//! * ∂M/∂q, Christoffel symbols c_ijk and C (eq. 76–79), C q̇ = Ṁ q̇ − ∂T/∂q;
//! * U = −Σ m_i g_0ᵀ p_i (sign convention of docs/parameters.md; eq. 22b) and g = ∂U/∂q (eq. 72–73);
//! * C q̇ + g by the recursive Newton–Euler pass of the `inverse` module with q̈ = 0 and the
//!   centroidal link wrench, independent of the Lagrangian path.

use super::inverse::Wrench;
use super::{Pose, SymbolicRobot};
use crate::diff;
use crate::graph::{Id, M3, V3};

/// The most joints for which [`SymbolicRobot::cqd_g_cheapest`] builds the Christoffel path of
/// C q̇ as a candidate. That graph grows as n⁴ (n³ symbols, each from n-term derivatives of
/// M): a 45-joint chain took 2 GB and half a minute to build it, only to discard it. The
/// Christoffel path wins at two and three joints; from four on the Newton–Euler pass is
/// cheaper on every scene and random chain measured, by 2.5–3.7 times at six joints, and the
/// ratio grows as n² (`codegen/tests/crba.rs` checks it on the scenes and random chains).
pub const CHRISTOFFEL_CANDIDATE_MAX_JOINTS: usize = 6;

impl SymbolicRobot {
    /// Mass matrix M(q), eq. 22a, from link-frame Jacobians.
    pub fn mass_matrix(&mut self) -> Vec<Vec<Id>> {
        if let Some(m) = &self.cache.mass {
            return m.clone();
        }
        let n = self.nq();
        let z = self.g.zero();
        let mut mm = vec![vec![z; n]; n];
        for i in 0..n {
            // Walk from frame i+1 (link i) back to the base: inv = T^{i+1}_{f}.
            let c = self.com_local(i);
            let mass = self.constant(&format!("link{}.mass", i + 1));
            let inertia = self.link_inertia(i);
            let mut cols_p: Vec<V3> = vec![[z; 3]; n];
            let mut cols_o: Vec<V3> = vec![[z; 3]; n];
            let mut inv = Pose {
                r: self.g.m3_identity(),
                t: [z; 3],
            };
            // Frames from i+1 down to 0; record those that are joint-axis frames of joints ≤ i.
            let mut frame = i + 1;
            loop {
                for j in 0..=i {
                    if self.axis_frame(j) == frame && self.prismatic(j) {
                        // Translation along the axis, no rotation.
                        cols_p[j] = self.axis_through(&inv.r, j);
                    } else if self.axis_frame(j) == frame {
                        let axis = self.axis_through(&inv.r, j);
                        let r = self.g.v3_sub(c, inv.t);
                        cols_p[j] = self.g.v3_cross(axis, r);
                        cols_o[j] = axis;
                    }
                }
                if frame == 0 {
                    break;
                }
                let ai = self.a_invs[frame - 1];
                inv = self.compose(&inv, &ai);
                frame -= 1;
            }
            // I ω products: (I J_O)_k for each column.
            let i_cols: Vec<V3> = cols_o
                .iter()
                .map(|&o| self.g.m3_mul_v(&inertia, o))
                .collect();
            for a in 0..=i {
                for b in a..=i {
                    let pp = self.g.v3_dot(cols_p[a], cols_p[b]);
                    let mp = self.g.mul(mass, pp);
                    let oo = self.g.v3_dot(cols_o[a], i_cols[b]);
                    let t = self.g.add(mp, oo);
                    mm[a][b] = self.g.add(mm[a][b], t);
                }
            }
        }
        for a in 0..n {
            for b in 0..a {
                mm[a][b] = mm[b][a];
            }
        }
        self.cache.mass = Some(mm.clone());
        mm
    }

    pub(super) fn link_inertia(&mut self, i: usize) -> M3 {
        let p = format!("link{}.inertia", i + 1);
        let xx = self.constant(&format!("{p}.xx"));
        let yy = self.constant(&format!("{p}.yy"));
        let zz = self.constant(&format!("{p}.zz"));
        let xy = self.constant(&format!("{p}.xy"));
        let xz = self.constant(&format!("{p}.xz"));
        let yz = self.constant(&format!("{p}.yz"));
        [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]
    }

    /// ∂M/∂q: `out[k][i][j]` = ∂M_ij/∂q_k.
    pub fn dmass_dq(&mut self) -> Vec<Vec<Vec<Id>>> {
        if let Some(d) = &self.cache.dmass {
            return d.clone();
        }
        let n = self.nq();
        let m = self.mass_matrix();
        let flat: Vec<Id> = m.iter().flatten().copied().collect();
        let mut out = Vec::new();
        for k in 0..n {
            let d = diff::partial(&mut self.g, &flat, self.layout.q(k));
            out.push(d.chunks(n).map(|c| c.to_vec()).collect::<Vec<_>>());
        }
        self.cache.dmass = Some(out.clone());
        out
    }

    /// Christoffel symbols `c[i][j][k]` = ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i).
    pub fn christoffel(&mut self) -> Vec<Vec<Vec<Id>>> {
        let n = self.nq();
        let dm = self.dmass_dq();
        let half = self.g.constant(0.5);
        let mut c = vec![vec![vec![Id(0); n]; n]; n];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let a = self.g.add(dm[k][i][j], dm[j][i][k]);
                    let b = self.g.sub(a, dm[i][j][k]);
                    c[i][j][k] = self.g.mul(half, b);
                }
            }
        }
        c
    }

    /// C(q, q̇), C_ij = Σ_k c_ijk q̇_k.
    pub fn coriolis_matrix(&mut self) -> Vec<Vec<Id>> {
        let c = self.christoffel();
        let qd = self.qd_ids();
        c.iter()
            .map(|ci| ci.iter().map(|cij| self.g.dot(cij, &qd)).collect())
            .collect()
    }

    /// C q̇ + g with the cheaper of the Newton–Euler and Christoffel paths, counting the
    /// operations shared with `with` (e.g. the entries of M computed in the same kernel).
    /// Above [`CHRISTOFFEL_CANDIDATE_MAX_JOINTS`] joints only the Newton–Euler path is built.
    pub fn cqd_g_cheapest(&mut self, with: &[Id]) -> Vec<Id> {
        let rnea = self.cqd_g_rnea();
        if self.nq() > CHRISTOFFEL_CANDIDATE_MAX_JOINTS {
            return rnea;
        }
        let c = self.coriolis_qd_christoffel();
        let g = self.gravity();
        let chr: Vec<Id> = c.iter().zip(&g).map(|(&a, &b)| self.g.add(a, b)).collect();
        let cost = |m: &SymbolicRobot, v: &[Id]| {
            let mut all = with.to_vec();
            all.extend_from_slice(v);
            m.g.cost(&all)
        };
        if cost(self, &chr) < cost(self, &rnea) {
            chr
        } else {
            rnea
        }
    }

    /// M(q) alone (the `mass_matrix` kernel): of the Jacobian form
    /// ([`SymbolicRobot::mass_matrix`], O(n³) operations on a chain) and the composite-rigid-body
    /// algorithm ([`SymbolicRobot::mass_matrix_crba`], O(n²)), the one with fewer operations (the
    /// Jacobian form on a tie). Costed on copies of the graph as in
    /// [`SymbolicRobot::mass_cqd_g`], so the losing candidate leaves no nodes behind. The
    /// derivative kernels (∂M/∂q, Christoffel symbols) keep differentiating the Jacobian form.
    pub fn mass_matrix_cheapest(&mut self) -> Vec<Vec<Id>> {
        let cost = |m: &mut SymbolicRobot, crba: bool| {
            let mm = if crba {
                m.mass_matrix_crba()
            } else {
                m.mass_matrix()
            };
            let all: Vec<Id> = mm.iter().flatten().copied().collect();
            m.g.cost(&all)
        };
        if cost(&mut self.clone(), true) < cost(&mut self.clone(), false) {
            self.mass_matrix_crba()
        } else {
            self.mass_matrix()
        }
    }

    /// M and C q̇ + g for one kernel: of the mass matrix from link Jacobians
    /// ([`SymbolicRobot::mass_matrix`]) and by the composite-rigid-body algorithm
    /// ([`SymbolicRobot::mass_matrix_crba`]), each with its cheapest C q̇ + g
    /// ([`SymbolicRobot::cqd_g_cheapest`]), the pair with fewer operations in total (the Jacobian form
    /// on a tie). The candidates are costed on a copy of the graph, so the losing one leaves
    /// no nodes behind (the node order, hence the emitted text, of other kernels is unchanged).
    pub fn mass_cqd_g(&mut self) -> (Vec<Vec<Id>>, Vec<Id>) {
        let cost = |m: &mut SymbolicRobot, crba: bool| {
            let mm = if crba {
                m.mass_matrix_crba()
            } else {
                m.mass_matrix()
            };
            let mut all: Vec<Id> = mm.iter().flatten().copied().collect();
            let v = m.cqd_g_cheapest(&all);
            all.extend_from_slice(&v);
            (m.g.cost(&all), mm, v)
        };
        let use_crba = cost(&mut self.clone(), true).0 < cost(&mut self.clone(), false).0;
        let (_, mm, v) = cost(self, use_crba);
        (mm, v)
    }

    /// C q̇ (Lagrangian): the cheaper of Ṁ q̇ − ∂T/∂q (T = ½ q̇ᵀ M q̇) and the contraction of
    /// the Christoffel symbols; both equal Σ_jk c_ijk q̇_j q̇_k.
    pub fn coriolis_qd(&mut self) -> Vec<Id> {
        if let Some(c) = &self.cache.cqd {
            return c.clone();
        }
        let a = self.coriolis_qd_energy();
        let b = self.coriolis_qd_christoffel();
        let out = if self.g.cost(&b) < self.g.cost(&a) {
            b
        } else {
            a
        };
        self.cache.cqd = Some(out.clone());
        out
    }

    /// C q̇ = Ṁ q̇ − ∂T/∂q with T = ½ q̇ᵀ M q̇.
    pub fn coriolis_qd_energy(&mut self) -> Vec<Id> {
        let n = self.nq();
        let m = self.mass_matrix();
        let qd = self.qd_ids();
        let flat: Vec<Id> = m.iter().flatten().copied().collect();
        let mdot = self.dt(&flat);
        let mdot: Vec<Vec<Id>> = mdot.chunks(n).map(|c| c.to_vec()).collect();
        let mdq = self.matvec(&mdot, &qd);
        // T = ½ q̇ᵀ M q̇; ∂T/∂q in one reverse sweep.
        let mq = self.matvec(&m, &qd);
        let tq = self.g.dot(&qd, &mq);
        let half = self.g.constant(0.5);
        let one = self.g.one();
        let t = self.g.mul(half, tq);
        let vars = self.q_vars();
        let dtdq = diff::reverse(&mut self.g, &[(t, one)], &vars);
        (0..n).map(|i| self.g.sub(mdq[i], dtdq[i])).collect()
    }

    /// C q̇ from the Christoffel symbols with the symmetric contraction
    /// (C q̇)_i = Σ_j c_ijj q̇_j² + 2 Σ_{j<k} c_ijk q̇_j q̇_k.
    pub fn coriolis_qd_christoffel(&mut self) -> Vec<Id> {
        let n = self.nq();
        let c = self.christoffel();
        let qd = self.qd_ids();
        let two = self.g.constant(2.0);
        let mut prods = vec![vec![Id(0); n]; n];
        for j in 0..n {
            for k in j..n {
                let p = self.g.mul(qd[j], qd[k]);
                prods[j][k] = if j == k { p } else { self.g.mul(two, p) };
            }
        }
        (0..n)
            .map(|i| {
                let mut acc = self.g.zero();
                for j in 0..n {
                    for k in j..n {
                        let t = self.g.mul(c[i][j][k], prods[j][k]);
                        acc = self.g.add(acc, t);
                    }
                }
                acc
            })
            .collect()
    }

    /// U(q) = −Σ m_i g_0ᵀ p_i.
    pub fn potential(&mut self) -> Id {
        if let Some(u) = self.cache.potential {
            return u;
        }
        let coms = self.com_world();
        let g0 = self.cvec("gravity");
        let mut terms = Vec::new();
        for (i, p) in coms.iter().enumerate() {
            let m = self.constant(&format!("link{}.mass", i + 1));
            let gp = self.g.v3_dot(g0, *p);
            terms.push(self.g.mul(m, gp));
        }
        let s = self.g.sum(&terms);
        let u = self.g.neg(s);
        self.cache.potential = Some(u);
        u
    }

    /// g(q) = ∂U/∂q.
    pub fn gravity(&mut self) -> Vec<Id> {
        if let Some(g) = &self.cache.gravity {
            return g.clone();
        }
        let u = self.potential();
        let one = self.g.one();
        let vars = self.q_vars();
        let gr = diff::reverse(&mut self.g, &[(u, one)], &vars);
        self.cache.gravity = Some(gr.clone());
        gr
    }

    /// C q̇ + g (Lagrangian path).
    pub fn cqd_g(&mut self) -> Vec<Id> {
        let c = self.coriolis_qd();
        let g = self.gravity();
        c.iter().zip(&g).map(|(&a, &b)| self.g.add(a, b)).collect()
    }

    /// C q̇ + g by recursive Newton–Euler with q̈ = 0 in link frames (the pass of the
    /// inverse-dynamics family with the centroidal link wrench).
    pub fn cqd_g_rnea(&mut self) -> Vec<Id> {
        if let Some(r) = &self.cache.rnea {
            return r.clone();
        }
        let z = self.g.zero();
        let tau = self.rnea(Wrench::Centroidal, &vec![z; self.nq()]);
        self.cache.rnea = Some(tau.clone());
        tau
    }
}
