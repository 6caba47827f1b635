//! Robot front-end: scene (DH table, inertias, ball) → graph expressions of every kernel.
//!
//! Symbols and paper equations (conventions of docs/parameters.md):
//! * DH link transforms A_i (Table 1), world frames T_i = T_base A_1 ⋯ A_i, tip = T_n T_tool:
//!   p_e and [ê_x3 ê_y3 ê_z3] of eq. 67–68;
//! * or, for links in placement form (a URDF import; [`FrameKind::Placement`],
//!   [`JointPlacement`]), A_i = (R₀, t₀) ∘ motion with the Rodrigues rotation R(u_i, q_i) or the
//!   translation q_i u_i, the joint axis u_i through o_i (as in modified DH, u_i for z);
//! * geometric Jacobians of the tip (eq. 69–71) and of every link COG (J_P^i, J_O^i of eq. 22a),
//!   J̇ q̇ of the tip;
//! * M = Σ m_i J_Pᵢᵀ J_Pᵢ + J_Oᵢᵀ R_i I_i R_iᵀ J_Oᵢ (eq. 22a, 74–75), built from Jacobians
//!   expressed in the link's own frame so M depends only on relative joint angles;
//! * the same M by the composite-rigid-body algorithm on the Newton–Euler pass's link
//!   transforms (`crba` submodule), for kernels that hold both;
//! * ∂M/∂q, Christoffel symbols c_ijk and C (eq. 76–79), C q̇ = Ṁ q̇ − ∂T/∂q;
//! * U = −Σ m_i g_0ᵀ p_i (sign convention of docs/parameters.md; eq. 22b) and g = ∂U/∂q (eq. 72–73);
//! * a recursive Newton–Euler path for C q̇ + g, independent of the Lagrangian one;
//! * contact geometry (Sect. 2.2): α (eq. 2), sat (eq. 3) or smooth sat (eq. 58–59), p_c,
//!   r_c, h (eq. 4), n (eq. 11), J_c (eq. 7), v_c (eq. 6), Δv (eq. 13), ṙ_c, ḣ, J̇_c q̇ (eq. 33).
//!
//! Trigonometry: only sin/cos of single joint coordinates appear; constant DH angles are
//! folded exactly (angle sums in product form).
//!
//! The joint-space dynamics (M, ∂M/∂q, C, g and the Newton–Euler path) live in the `dynamics`
//! submodule, inverse and forward dynamics, their derivatives and the regressor in `inverse`,
//! forward dynamics by the articulated-body algorithm in `aba`;
//! kinematics, Jacobians and contact geometry are here. Joints are revolute (θ_i = q_i +
//! offset) or prismatic (d_i = q_i + d).

mod aba;
mod crba;
mod dynamics;
mod inverse;

pub use dynamics::CHRISTOFFEL_CANDIDATE_MAX_JOINTS;
pub use inverse::ForwardForm;

use crate::diff;
use crate::graph::{Graph, Id, M3, V3, m3_transpose};
use crate::spec::{Angle, DhConvention, JointType, RotationSpec, Scene, TransformSpec};
use crate::{CodegenError, SceneDefect};

/// How a scene's kernels become smaller ([`SymbolicRobot::check_size`]).
pub const KERNELS_ADVICE: &str = "the kernels whose size grows fastest with the joint count are \
     `christoffel` and `dmass_dq` (n³ entries), then `coriolis_matrix`, \
     `inverse_dynamics_dq`, `inverse_dynamics_dqd` and `mass_cqd_g`; list only the kernels you \
     need in the scene's `kernels` (for a URDF read alone: in a scene file with `urdf = \
     \"FILE\"` and `kernels = [...]`, docs/scene-format.md)";

/// How `eval` becomes smaller ([`SymbolicRobot::check_size`]): it computes M, C and the
/// Jacobians whatever the scene's `kernels` say.
pub const EVAL_ADVICE: &str = "`eval` builds M, C (from the n³ Christoffel symbols) and the \
     Jacobians of every scene whatever its `kernels`; `generate` with a shorter `kernels` list \
     needs less";

/// How an optimal-control problem's graphs become smaller ([`SymbolicRobot::check_size`]):
/// they are the dynamics and contact quantities of every joint with their exact derivatives.
pub const PROBLEM_ADVICE: &str = "a problem needs the dynamics and contact quantities of \
     every joint and their exact derivatives, so only a robot with fewer joints needs less";

/// Layout of the input variables of the graph: q, q̇, ω, ε, then the runtime parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Number of joints.
    pub nq: usize,
    /// Number of runtime parameters.
    pub np: usize,
}

impl Layout {
    /// Variable index of q_i.
    pub fn q(&self, i: usize) -> u32 {
        i as u32
    }
    /// Variable index of q̇_i.
    pub fn qd(&self, i: usize) -> u32 {
        (self.nq + i) as u32
    }
    /// Variable index of ω_i (ball angular velocity).
    pub fn omega(&self, i: usize) -> u32 {
        (2 * self.nq + i) as u32
    }
    /// Variable index of ε (smooth saturation): right after the state x = (q, q̇, ω).
    pub fn eps(&self) -> u32 {
        crate::spec::state_len(self.nq) as u32
    }
    /// Variable index of runtime parameter `i`.
    pub fn param(&self, i: usize) -> u32 {
        (2 * self.nq + 4 + i) as u32
    }
    /// Total number of variables of the kinematic, dynamic and contact kernels (q̈, τ and the
    /// inertial parameters of the inverse-dynamics family come after these).
    pub fn n_vars(&self) -> usize {
        2 * self.nq + 4 + self.np
    }
    /// Variable index of q̈_i (input of `inverse_dynamics` and its derivatives).
    pub fn qdd(&self, i: usize) -> u32 {
        (self.n_vars() + i) as u32
    }
    /// Variable index of τ_i (input of `forward_dynamics`).
    pub fn tau(&self, i: usize) -> u32 {
        (self.n_vars() + self.nq + i) as u32
    }
    /// Variable index of inertial parameter `k` (0..10, order of
    /// [`INERTIAL_PARAMETER_NAMES`]) of link `link` (0-based): the variables the regressor
    /// differentiates by; no emitted kernel reads them.
    pub fn inertial(&self, link: usize, k: usize) -> u32 {
        (self.n_vars() + 2 * self.nq + 10 * link + k) as u32
    }
    /// Number of variables including q̈, τ and the inertial parameters.
    pub fn n_vars_all(&self) -> usize {
        self.n_vars() + 12 * self.nq
    }
}

/// The standard inertial parameters π of one link, in the order of the regressor's columns:
/// m, the first moments m·c (c = COG in link-frame coordinates) and the inertia tensor about
/// the link frame's origin in link-frame axes, I_o = I_c + m(|c|² 1 − c cᵀ).
pub const INERTIAL_PARAMETER_NAMES: [&str; 10] = [
    "m", "mcx", "mcy", "mcz", "ixx", "ixy", "ixz", "iyy", "iyz", "izz",
];

/// The inertial parameters π (order [`INERTIAL_PARAMETER_NAMES`]) of every link of `scene`,
/// concatenated link by link: τ = Y(q, q̇, q̈) π with Y the `regressor` kernel.
pub fn inertial_parameters(scene: &Scene) -> Vec<f64> {
    let mut out = Vec::with_capacity(10 * scene.links.len());
    for (i, l) in scene.links.iter().enumerate() {
        let (m, c) = (l.mass, l.com);
        let ic = scene.link_inertia(i);
        let cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        let io = |a: usize, b: usize| {
            let delta = if a == b { cc } else { 0.0 };
            ic[a][b] + m * (delta - c[a] * c[b])
        };
        out.extend([
            m,
            m * c[0],
            m * c[1],
            m * c[2],
            io(0, 0),
            io(0, 1),
            io(0, 2),
            io(1, 1),
            io(1, 2),
            io(2, 2),
        ]);
    }
    out
}

/// A rigid transform (R, t) of graph nodes: x ↦ R x + t.
#[derive(Debug, Clone, Copy)]
pub struct Pose {
    /// Rotation.
    pub r: M3,
    /// Translation.
    pub t: V3,
}

/// A pair of 3 × NQ Jacobians (translational, rotational), row-major.
pub type JacPair = (Vec<Vec<Id>>, Vec<Vec<Id>>);

/// Contact quantities (fields of the emitted `Contact` struct).
#[derive(Debug, Clone)]
pub struct ContactExprs {
    /// α, eq. 2.
    pub alpha: Id,
    /// sat(α) (exact or smooth).
    pub sat_alpha: Id,
    /// p_c, eq. 3.
    pub p_c: V3,
    /// r_c = p_c − o_b.
    pub r_c: V3,
    /// h, eq. 4.
    pub h: Id,
    /// n, eq. 11.
    pub n: V3,
    /// J_c (3 × NQ, row-major), eq. 7.
    pub j_c: Vec<Vec<Id>>,
    /// v_c = J_c q̇, eq. 6.
    pub v_c: V3,
    /// Δv = ω × r_c − v_c, eq. 13.
    pub delta_v: V3,
    /// ḣ = n · ṙ_c.
    pub h_dot: Id,
    /// ṙ_c.
    pub rc_dot: V3,
    /// J̇_c q̇.
    pub jc_dot_qd: V3,
}

/// Which points of the last link the contact kernels let touch the ball.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Segment {
    /// Only the tip (`contact.kind = "tip"`): α is not saturated.
    Tip,
    /// The segment of length `link{n}.a`, a constant or a runtime parameter (standard DH, tip
    /// frame = last link frame).
    LastLinkA,
    /// The segment of this length, checked by the scene.
    Length(f64),
}

/// The scene's symbolic robot model (the graph counterpart of bf-model's numeric `Model`): one
/// graph holding every requested quantity.
#[derive(Debug, Clone)]
pub struct SymbolicRobot {
    /// The expression graph.
    pub g: Graph,
    /// Input layout.
    pub layout: Layout,
    /// Runtime parameter names and default values (in `runtime_parameters` order).
    pub params: Vec<(String, f64)>,
    scene: Scene,
    frames: FrameKind,
    consts: Vec<(String, f64)>,
    sc: Vec<(Id, Id)>,
    a_mats: Vec<Pose>,
    a_invs: Vec<Pose>,
    world: Vec<Pose>,
    tip: Pose,
    cache: Cache,
}

/// How the link frames of a scene are placed (the kinematics front end; see [`JointPlacement`]):
/// the DH readers keep their closed-form link transforms (exact angle folding, DH runtime
/// parameters, and the generated code of DH scenes unchanged); the general form composes a
/// fixed transform with the joint motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameKind {
    /// Standard DH: joint i turns about z of frame i − 1; o_{i−1} is on its axis.
    DhStandard,
    /// Modified DH: joint i turns about z of frame i through o_i.
    DhModified,
    /// General placements: joint i moves about/along a unit axis u_i of frame i through o_i.
    Placement,
}

impl FrameKind {
    /// The front end a scene's links select.
    pub fn of(scene: &Scene) -> FrameKind {
        if scene.is_placement() {
            FrameKind::Placement
        } else if scene.dh == DhConvention::Modified {
            FrameKind::DhModified
        } else {
            FrameKind::DhStandard
        }
    }

    /// Whether joint i's axis passes through o_i and is fixed in frame i (modified DH and
    /// general placements), rather than through o_{i−1} (standard DH).
    pub fn axis_at_own_origin(self) -> bool {
        self != FrameKind::DhStandard
    }
}

/// One joint of the chain in the general form: a fixed transform x ↦ R x + t from the previous
/// link's frame to the joint's frame at q = 0, then the joint motion about/along the unit
/// `axis` (joint-frame coordinates); [`joint_placements`] gives any scene in this form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPlacement {
    /// Fixed rotation (row-major).
    pub rotation: [[f64; 3]; 3],
    /// Fixed translation (m).
    pub translation: [f64; 3],
    /// Unit joint axis in the joint frame.
    pub axis: [f64; 3],
    /// Revolute or prismatic.
    pub joint: JointType,
}

#[derive(Debug, Clone, Default)]
struct Cache {
    com_world: Option<Vec<V3>>,
    tip_jac: Option<JacPair>,
    mass: Option<Vec<Vec<Id>>>,
    mass_crba: Option<Vec<Vec<Id>>>,
    dmass: Option<Vec<Vec<Vec<Id>>>>,
    potential: Option<Id>,
    gravity: Option<Vec<Id>>,
    cqd: Option<Vec<Id>>,
    rnea: Option<Vec<Id>>,
    inverse: Option<Vec<Id>>,
}

impl SymbolicRobot {
    /// Build the kinematic skeleton of `scene` (world frames of every link, tip frame) on a
    /// graph with the process's node limit ([`crate::graph::node_limit`]).
    pub fn new(scene: &Scene) -> Result<Self, CodegenError> {
        Self::with_node_limit(scene, crate::graph::node_limit())
    }

    /// [`SymbolicRobot::new`] on a graph of at most `limit` nodes ([`Graph::with_limit`]).
    pub fn with_node_limit(scene: &Scene, limit: usize) -> Result<Self, CodegenError> {
        let nq = scene.links.len();
        if nq == 0 {
            return Err(SceneDefect::NoLinks.into());
        }
        let consts = scene.constants();
        let mut params = Vec::new();
        for name in &scene.runtime_parameters {
            let Some((_, v)) = consts.iter().find(|(n, _)| n == name) else {
                return Err(SceneDefect::UnknownRuntimeParameter {
                    name: name.clone(),
                    known: consts.iter().map(|c| c.0.clone()).collect(),
                }
                .into());
            };
            if params.iter().any(|(n, _): &(String, f64)| n == name) {
                return Err(SceneDefect::RuntimeParameterTwice { name: name.clone() }.into());
            }
            params.push((name.clone(), *v));
        }
        let layout = Layout {
            nq,
            np: params.len(),
        };
        let mut m = SymbolicRobot {
            g: Graph::with_limit(limit),
            layout,
            params,
            scene: scene.clone(),
            frames: FrameKind::of(scene),
            consts,
            sc: Vec::new(),
            a_mats: Vec::new(),
            a_invs: Vec::new(),
            world: Vec::new(),
            tip: Pose {
                r: [[Id(0); 3]; 3],
                t: [Id(0); 3],
            },
            cache: Cache::default(),
        };
        m.build_kinematics()?;
        Ok(m)
    }

    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.layout.nq
    }

    /// An error naming `what` if the graph has exceeded its node limit ([`Graph::exceeded`]):
    /// what was built since is incomplete. `advice` says how to make the request smaller
    /// ([`KERNELS_ADVICE`], [`EVAL_ADVICE`]).
    pub fn check_size(&self, what: &str, advice: &'static str) -> Result<(), CodegenError> {
        if !self.g.exceeded() {
            return Ok(());
        }
        Err(CodegenError::TooLarge(crate::GraphTooLarge {
            what: what.to_string(),
            joints: self.nq(),
            limit: self.g.limit(),
            advice,
        }))
    }

    /// The scene this model was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// A named constant: a runtime parameter variable or a baked constant.
    pub fn constant(&mut self, name: &str) -> Id {
        if let Some(i) = self.params.iter().position(|(n, _)| n == name) {
            return self.g.var(self.layout.param(i));
        }
        let v = self
            .consts
            .iter()
            .find(|(n, _)| n == name)
            .map(|c| c.1)
            .unwrap_or_else(|| panic!("internal: constant `{name}` not in the table"));
        self.g.constant(v)
    }

    fn cvec(&mut self, prefix: &str) -> V3 {
        [
            self.constant(&format!("{prefix}.x")),
            self.constant(&format!("{prefix}.y")),
            self.constant(&format!("{prefix}.z")),
        ]
    }

    /// (cos, sin) of a named DH angle: of the runtime parameter if `name` is one (a single
    /// variable, so still accurate), else the exact constant.
    fn named_angle_cs(&mut self, name: &str, a: Angle) -> (Id, Id) {
        if self.params.iter().any(|(n, _)| n == name) {
            let v = self.constant(name);
            return (self.g.cos(v), self.g.sin(v));
        }
        self.angle_cs(a)
    }

    fn angle_cs(&mut self, a: Angle) -> (Id, Id) {
        match a {
            Angle::Radians(x) => (self.g.constant(libm::cos(x)), self.g.constant(libm::sin(x))),
            Angle::PiMultiple { num, den } => (self.g.cos_pi(num, den), self.g.sin_pi(num, den)),
        }
    }

    fn rotation(&mut self, r: &Option<RotationSpec>) -> Result<M3, CodegenError> {
        let Some(r) = r else {
            return Ok(self.g.m3_identity());
        };
        match r {
            RotationSpec::Matrix(m) => {
                let mut out = [[Id(0); 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        out[i][j] = self.g.constant(m[i][j]);
                    }
                }
                Ok(out)
            }
            RotationSpec::Axis { axis, angle } => {
                let (c, s) = self.angle_cs(*angle);
                let (z, o) = (self.g.zero(), self.g.one());
                let ns = self.g.neg(s);
                Ok(match axis.as_str() {
                    "x" => [[o, z, z], [z, c, ns], [z, s, c]],
                    "y" => [[c, z, s], [z, o, z], [ns, z, c]],
                    "z" => [[c, ns, z], [s, c, z], [z, z, o]],
                    other => {
                        return Err(SceneDefect::RotationAxis {
                            axis: other.to_string(),
                        }
                        .into());
                    }
                })
            }
        }
    }

    fn transform(&mut self, t: &TransformSpec, prefix: &str) -> Result<Pose, CodegenError> {
        let r = self.rotation(&t.rotation)?;
        let t = self.cvec(&format!("{prefix}.translation"));
        Ok(Pose { r, t })
    }

    fn compose(&mut self, a: &Pose, b: &Pose) -> Pose {
        let r = self.g.m3_mul(&a.r, &b.r);
        let rt = self.g.m3_mul_v(&a.r, b.t);
        let t = self.g.v3_add(rt, a.t);
        Pose { r, t }
    }

    /// Link transform and inverse of a joint in general placement form: A = (R₀, t₀) ∘ motion,
    /// the motion a Rodrigues rotation R(u, q) = cos q (1 − u uᵀ) + u uᵀ + sin q [u]ₓ or a
    /// translation q u.
    fn placement_pose(&mut self, i: usize, p: &JointPlacement) -> (Pose, Pose) {
        let qi = self.g.var(self.layout.q(i));
        let mut r0 = [[Id(0); 3]; 3];
        for (a, row) in r0.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                *x = self.g.constant(p.rotation[a][b]);
            }
        }
        let t0 = p.translation.map(|x| self.g.constant(x));
        let u = p.axis;
        let (r, t) = if p.joint == JointType::Prismatic {
            let z = self.g.zero();
            self.sc.push((z, self.g.one()));
            let uq = u.map(|x| {
                let k = self.g.constant(x);
                self.g.mul(k, qi)
            });
            let ruq = self.g.m3_mul_v(&r0, uq);
            (r0, self.g.v3_add(t0, ruq))
        } else {
            let (s, c) = (self.g.sin(qi), self.g.cos(qi));
            self.sc.push((s, c));
            let skew = [[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]];
            let mut rm = [[Id(0); 3]; 3];
            for (a, row) in rm.iter_mut().enumerate() {
                for (b, x) in row.iter_mut().enumerate() {
                    let delta = if a == b { 1.0 } else { 0.0 };
                    let k1 = self.g.constant(delta - u[a] * u[b]);
                    let k2 = self.g.constant(u[a] * u[b]);
                    let k3 = self.g.constant(skew[a][b]);
                    let kc = self.g.mul(k1, c);
                    let ks = self.g.mul(k3, s);
                    let sum = self.g.add(kc, ks);
                    *x = self.g.add(sum, k2);
                }
            }
            (self.g.m3_mul(&r0, &rm), t0)
        };
        let ri = m3_transpose(&r);
        let rit = self.g.m3_tmul_v(&r, t);
        let ti = [self.g.neg(rit[0]), self.g.neg(rit[1]), self.g.neg(rit[2])];
        (Pose { r, t }, Pose { r: ri, t: ti })
    }

    fn build_kinematics(&mut self) -> Result<(), CodegenError> {
        let n = self.nq();
        let links = self.scene.links.clone();
        if self.frames == FrameKind::Placement {
            for (i, p) in joint_placements(&self.scene).iter().enumerate() {
                let (a_pose, inv_pose) = self.placement_pose(i, p);
                self.a_mats.push(a_pose);
                self.a_invs.push(inv_pose);
            }
        }
        for (i, l) in links.iter().enumerate() {
            if self.frames == FrameKind::Placement {
                break;
            }
            let qi = self.g.var(self.layout.q(i));
            let offset_name = format!("link{}.offset", i + 1);
            let offset_runtime = self.params.iter().any(|(n, _)| *n == offset_name);
            let prismatic = l.joint == JointType::Prismatic;
            let (ct, st) = match (l.offset, offset_runtime) {
                // Prismatic: θ = offset is constant (exact for multiples of π).
                _ if prismatic => {
                    let o = l.offset.unwrap_or(Angle::Radians(0.0));
                    self.named_angle_cs(&offset_name, o)
                }
                (None, false) => {
                    let (sq, cq) = (self.g.sin(qi), self.g.cos(qi));
                    (cq, sq)
                }
                (o, _) => {
                    let (sq, cq) = (self.g.sin(qi), self.g.cos(qi));
                    let o = o.unwrap_or(Angle::Radians(0.0));
                    let (co, so) = self.named_angle_cs(&offset_name, o);
                    let a = self.g.mul(cq, co);
                    let b = self.g.mul(sq, so);
                    let c = self.g.mul(sq, co);
                    let d = self.g.mul(cq, so);
                    (self.g.sub(a, b), self.g.add(c, d))
                }
            };
            self.sc.push((st, ct));
            let (ca, sa) = self.named_angle_cs(&format!("link{}.alpha", i + 1), l.alpha);
            let a = self.constant(&format!("link{}.a", i + 1));
            let d0 = self.constant(&format!("link{}.d", i + 1));
            // Prismatic: d = q + d (the file's d is the offset of the joint coordinate).
            let d = if prismatic { self.g.add(qi, d0) } else { d0 };
            let g = &mut self.g;
            let z = g.zero();
            let (nst, nsa) = (g.neg(st), g.neg(sa));
            let (a_pose, inv_pose) = match self.scene.dh {
                DhConvention::Standard => {
                    // A = Rz(θ) Tz(d) Tx(a) Rx(α)
                    let r = [
                        [ct, g.mul(nst, ca), g.mul(st, sa)],
                        [st, g.mul(ct, ca), g.mul(ct, nsa)],
                        [z, sa, ca],
                    ];
                    let t = [g.mul(a, ct), g.mul(a, st), d];
                    // A⁻¹ = Rx(−α) Tx(−a) Tz(−d) Rz(−θ): Rᵀ and −Rᵀt = −[a, d sα, d cα]
                    // in closed form (no cos²+sin² left for the simplifier).
                    let ri = m3_transpose(&r);
                    let na = g.neg(a);
                    let dsa = g.mul(d, sa);
                    let dca = g.mul(d, ca);
                    let ti = [na, g.neg(dsa), g.neg(dca)];
                    (Pose { r, t }, Pose { r: ri, t: ti })
                }
                DhConvention::Modified => {
                    // A = Rx(α) Tx(a) Rz(θ) Tz(d)
                    let r = [
                        [ct, nst, z],
                        [g.mul(ca, st), g.mul(ca, ct), nsa],
                        [g.mul(sa, st), g.mul(sa, ct), ca],
                    ];
                    let t = [a, g.mul(nsa, d), g.mul(ca, d)];
                    // A⁻¹ = Tz(−d) Rz(−θ) Tx(−a) Rx(−α): t⁻¹ = [−a cθ, a sθ, −d].
                    let ri = m3_transpose(&r);
                    let act = g.mul(a, ct);
                    let ti = [g.neg(act), g.mul(a, st), g.neg(d)];
                    (Pose { r, t }, Pose { r: ri, t: ti })
                }
            };
            self.a_mats.push(a_pose);
            self.a_invs.push(inv_pose);
        }
        let base_spec = self.scene.base.clone();
        let base = self.transform(&base_spec, "base")?;
        self.world.push(base);
        for i in 0..n {
            let prev = self.world[i];
            let a = self.a_mats[i];
            let w = self.compose(&prev, &a);
            self.world.push(w);
        }
        self.tip = match self.scene.tool.clone() {
            None => self.world[n],
            Some(t) => {
                let tool = self.transform(&t, "tool")?;
                let last = self.world[n];
                self.compose(&last, &tool)
            }
        };
        Ok(())
    }

    /// World pose of DH frame `i` (0 = base frame, n = last link, without tool).
    pub fn world_frame(&self, i: usize) -> Pose {
        self.world[i]
    }

    /// World pose of the tip (last DH frame with the tool transform).
    pub fn tip_pose(&self) -> Pose {
        self.tip
    }

    /// World poses of frames 1..NQ, the last one including the tool (kernel `frames`).
    pub fn frames(&self) -> Vec<Pose> {
        let n = self.nq();
        let mut v: Vec<Pose> = self.world[1..n].to_vec();
        v.push(self.tip);
        v
    }

    /// Index of the frame whose z axis is joint j's axis (0-based joint): z_{j−1} for
    /// standard DH (frame j in 1-based numbering of `world`), z_j for modified DH.
    fn axis_frame(&self, j: usize) -> usize {
        if self.frames.axis_at_own_origin() {
            j + 1
        } else {
            j
        }
    }

    /// Joint j's axis in the coordinates of a frame whose rotation to the axis frame is `r`:
    /// the z column of `r` for DH, `r u_j` for general placements.
    fn axis_through(&mut self, r: &M3, j: usize) -> V3 {
        if self.frames == FrameKind::Placement {
            let u = self.joint_axis(j);
            return self.g.m3_mul_v(r, u);
        }
        [r[0][2], r[1][2], r[2][2]]
    }

    /// Whether joint `j` (0-based) is prismatic.
    pub(super) fn prismatic(&self, j: usize) -> bool {
        self.scene.links[j].joint == JointType::Prismatic
    }

    /// Link i's COG in its own frame (0-based link).
    fn com_local(&mut self, i: usize) -> V3 {
        self.cvec(&format!("link{}.com", i + 1))
    }

    /// World COG positions p_i of every link.
    pub fn com_world(&mut self) -> Vec<V3> {
        if let Some(c) = &self.cache.com_world {
            return c.clone();
        }
        let mut out = Vec::new();
        for i in 0..self.nq() {
            let c = self.com_local(i);
            let w = self.world[i + 1];
            let rc = self.g.m3_mul_v(&w.r, c);
            out.push(self.g.v3_add(w.t, rc));
        }
        self.cache.com_world = Some(out.clone());
        out
    }

    /// World geometric Jacobian (J_P, J_O), each 3 × NQ row-major, of a point `p` rigidly
    /// attached to link `link` (0-based); columns of later joints are 0.
    pub fn point_jacobian(&mut self, p: V3, link: usize) -> JacPair {
        let n = self.nq();
        let z = self.g.zero();
        let mut jp = vec![vec![z; n]; 3];
        let mut jo = vec![vec![z; n]; 3];
        for j in 0..=link {
            let f = self.world[self.axis_frame(j)];
            let axis = self.axis_through(&f.r, j);
            if self.prismatic(j) {
                // A prismatic joint translates along its axis and does not rotate.
                for k in 0..3 {
                    jp[k][j] = axis[k];
                }
                continue;
            }
            let d = self.g.v3_sub(p, f.t);
            let c = self.g.v3_cross(axis, d);
            for k in 0..3 {
                jp[k][j] = c[k];
                jo[k][j] = axis[k];
            }
        }
        (jp, jo)
    }

    /// Tip Jacobian (J_p, J_o), eq. 69–71.
    pub fn tip_jacobian(&mut self) -> JacPair {
        if let Some(j) = &self.cache.tip_jac {
            return j.clone();
        }
        let p = self.tip.t;
        let n = self.nq();
        let j = self.point_jacobian(p, n - 1);
        self.cache.tip_jac = Some(j.clone());
        j
    }

    /// Jacobians of every link COG (world axes).
    pub fn com_jacobians(&mut self) -> Vec<JacPair> {
        let coms = self.com_world();
        (0..self.nq())
            .map(|i| self.point_jacobian(coms[i], i))
            .collect()
    }

    fn q_vars(&self) -> Vec<u32> {
        (0..self.nq()).map(|i| self.layout.q(i)).collect()
    }

    fn qd_ids(&mut self) -> Vec<Id> {
        (0..self.nq())
            .map(|i| self.g.var(self.layout.qd(i)))
            .collect()
    }

    fn matvec(&mut self, m: &[Vec<Id>], v: &[Id]) -> Vec<Id> {
        m.iter().map(|r| self.g.dot(r, v)).collect()
    }

    /// d/dt along q̇ (q̇ held constant).
    fn dt(&mut self, outs: &[Id]) -> Vec<Id> {
        let vars = self.q_vars();
        let rates = self.qd_ids();
        diff::time_derivative(&mut self.g, outs, &vars, &rates)
    }

    /// J̇ q̇ of the tip: [linear; angular].
    pub fn tip_jdot_qd(&mut self) -> Vec<Id> {
        let (jp, jo) = self.tip_jacobian();
        let qd = self.qd_ids();
        let mut v = self.matvec(&jp, &qd);
        v.extend(self.matvec(&jo, &qd));
        self.dt(&v)
    }

    /// The length of the contact segment (eq. 3: α saturated to [−ℓ, 0]). A standard DH
    /// table whose tip frame is the last link frame keeps the symbolic a_n (it may be a runtime
    /// parameter); otherwise ℓ is the scene's checked number
    /// ([`Scene::contact_segment_length`]), so no runtime parameter may move it.
    fn segment_length(&self) -> Result<Segment, CodegenError> {
        let scene = &self.scene;
        if let Some((i, _)) = scene.segment_runtime_conflict() {
            let name = scene.runtime_parameters[i].clone();
            return Err(SceneDefect::SegmentLengthRuntime { name }.into());
        }
        if self.frames == FrameKind::DhStandard && scene.has_identity_tool() {
            return Ok(Segment::LastLinkA);
        }
        match scene.contact_segment_length() {
            Some(Ok(l)) => Ok(Segment::Length(l)),
            Some(Err(start)) => Err(SceneDefect::SegmentContactGeometry { start }.into()),
            None => Err(SceneDefect::SegmentContactModifiedDh.into()),
        }
    }

    /// Contact quantities (Sect. 2.2); `smooth` selects the smooth saturation (eq. 58–59).
    pub fn contact(&mut self, smooth: bool) -> Result<ContactExprs, CodegenError> {
        let (Some(_), Some(cs)) = (&self.scene.ball, &self.scene.contact) else {
            return Err(SceneDefect::NoBallOrContact.into());
        };
        let tip_only = cs.kind == "tip";
        if !tip_only && cs.kind != "segment" {
            return Err(SceneDefect::ContactKind {
                kind: cs.kind.clone(),
            }
            .into());
        }
        if !tip_only && self.frames == FrameKind::DhModified {
            return Err(SceneDefect::SegmentContactModifiedDh.into());
        }
        let segment = if tip_only {
            Segment::Tip
        } else {
            self.segment_length()?
        };
        let n = self.nq();
        let tip = self.tip;
        let pe = tip.t;
        let ex = [tip.r[0][0], tip.r[1][0], tip.r[2][0]];
        let ob = self.cvec("ball.center");
        let radius = self.constant("ball.radius");
        let d = self.g.v3_sub(ob, pe);
        let alpha = self.g.v3_dot(d, ex);
        let sat = if let Segment::Tip = segment {
            self.g.zero()
        } else {
            let an = match segment {
                Segment::Length(l) => self.g.constant(l),
                _ => self.constant(&format!("link{n}.a")),
            };
            let lo = self.g.neg(an);
            let hi = self.g.zero();
            if smooth {
                // sat = ½(L + U + |x − L| − |x − U|), |y| ≈ √(y² + ε²)
                let eps = self.g.var(self.layout.eps());
                let e2 = self.g.square(eps);
                let xl = self.g.sub(alpha, lo);
                let xl2 = self.g.square(xl);
                let s1 = self.g.add(xl2, e2);
                let r1 = self.g.sqrt(s1);
                let xu = self.g.sub(alpha, hi);
                let xu2 = self.g.square(xu);
                let s2 = self.g.add(xu2, e2);
                let r2 = self.g.sqrt(s2);
                let lu = self.g.add(lo, hi);
                let t = self.g.add(lu, r1);
                let t = self.g.sub(t, r2);
                let h = self.g.constant(0.5);
                self.g.mul(h, t)
            } else {
                self.g.sat(alpha, lo, hi)
            }
        };
        let sx = self.g.v3_scale(sat, ex);
        let p_c = self.g.v3_add(pe, sx);
        let r_c = self.g.v3_sub(p_c, ob);
        let rr = self.g.v3_dot(r_c, r_c);
        let norm = self.g.sqrt(rr);
        let h = self.g.sub(norm, radius);
        let nv = [
            self.g.div(r_c[0], norm),
            self.g.div(r_c[1], norm),
            self.g.div(r_c[2], norm),
        ];
        let (jp, jo) = self.tip_jacobian();
        let z = self.g.zero();
        let mut j_c = vec![vec![z; n]; 3];
        for col in 0..n {
            let o = [jo[0][col], jo[1][col], jo[2][col]];
            let exo = self.g.v3_cross(ex, o);
            for r in 0..3 {
                let t = self.g.mul(sat, exo[r]);
                j_c[r][col] = self.g.sub(jp[r][col], t);
            }
        }
        let qd = self.qd_ids();
        let vc = self.matvec(&j_c, &qd);
        let v_c = [vc[0], vc[1], vc[2]];
        let om = [
            self.g.var(self.layout.omega(0)),
            self.g.var(self.layout.omega(1)),
            self.g.var(self.layout.omega(2)),
        ];
        let wr = self.g.v3_cross(om, r_c);
        let delta_v = self.g.v3_sub(wr, v_c);
        let rcd = self.dt(&r_c);
        let rc_dot = [rcd[0], rcd[1], rcd[2]];
        let h_dot = self.g.v3_dot(nv, rc_dot);
        let jcd = self.dt(&v_c);
        let jc_dot_qd = [jcd[0], jcd[1], jcd[2]];
        Ok(ContactExprs {
            alpha,
            sat_alpha: sat,
            p_c,
            r_c,
            h,
            n: nv,
            j_c,
            v_c,
            delta_v,
            h_dot,
            rc_dot,
            jc_dot_qd,
        })
    }
}

/// The chain of `scene` in general placement form: its placement links as they are, a DH
/// scene through its reader [`Scene::placement_form`] (which also moves the inertias into
/// the joint frames).
pub fn joint_placements(scene: &Scene) -> Vec<JointPlacement> {
    let converted;
    let scene = if scene.is_placement() {
        scene
    } else {
        converted = scene.placement_form();
        &converted
    };
    scene
        .links
        .iter()
        .map(|l| {
            let o = l.origin.clone().unwrap_or_default();
            JointPlacement {
                rotation: o.rotation_matrix(),
                translation: o.translation(),
                axis: l.axis.unwrap_or([0.0, 0.0, 1.0]),
                joint: l.joint,
            }
        })
        .collect()
}
