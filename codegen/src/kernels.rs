//! The kernel catalogue: each kernel of docs/kernels.md as a signature plus the graph nodes of
//! its outputs (row-major). Paper mapping: `frames` eq. 67–68, `tip_jacobian` eq. 69–71,
//! `mass_matrix` eq. 22a/74–75, `christoffel`/`coriolis_*` eq. 76–79, `gravity` eq. 72–73,
//! `potential` eq. 22b, `contact*` eq. 2–13 and 58–59.

use crate::graph::Id;
use crate::robot::{ForwardForm, SymbolicRobot};
use crate::{CodegenError, InternalDefect, SceneDefect};

/// The graph nodes of the contact quantities in [`CONTACT_FIELDS`] order, row-major: the
/// outputs of the `contact` and `contact_smooth` kernels.
pub fn contact_ids(c: &crate::robot::ContactExprs) -> Vec<Id> {
    let mut ids = vec![c.alpha, c.sat_alpha];
    ids.extend(c.p_c);
    ids.extend(c.r_c);
    ids.push(c.h);
    ids.extend(c.n);
    ids.extend(flat2(&c.j_c));
    ids.extend(c.v_c);
    ids.extend(c.delta_v);
    ids.push(c.h_dot);
    ids.extend(c.rc_dot);
    ids.extend(c.jc_dot_qd);
    ids
}

/// Names of all kernels the generator knows, in emission order (the spec's list, so the
/// parser and the generator can never disagree).
pub const ALL_KERNELS: &[&str] = crate::spec::KNOWN_KERNELS;

/// `scene` with [`ROBOT_KERNELS`] appended to its `kernels` list (those it does not list
/// already): the kernel list of the module `bf-generated` and `generate` emit.
pub fn with_robot_kernels(scene: &crate::Scene) -> crate::Scene {
    let mut s = scene.clone();
    for k in ROBOT_KERNELS {
        if !s.kernels.iter().any(|x| x == k) {
            s.kernels.push(k.to_string());
        }
    }
    s
}

/// An input argument of a kernel (emitted in this order; `P` is always last).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arg {
    /// `q: &[f64; NQ]`, joint angles (rad).
    Q,
    /// `qd: &[f64; NQ]`, joint velocities (rad/s).
    Qd,
    /// `omega: &[f64; 3]`, ball angular velocity (rad/s, world axes).
    Omega,
    /// `eps: f64`, smooth-saturation ε (m).
    Eps,
    /// `qdd: &[f64; NQ]`, joint accelerations (rad/s², m/s² for prismatic joints).
    Qdd,
    /// `tau: &[f64; NQ]`, joint torques (N m, N for prismatic joints).
    Tau,
    /// `p: &[f64; NP]`, runtime parameters.
    P,
}

pub use crate::spec::ROBOT_KERNELS;

/// A dimension of an output array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    /// `NQ`.
    Nq,
    /// A fixed size.
    Lit(usize),
}

/// The type of an output argument.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutKind {
    /// `&mut f64`.
    Scalar,
    /// `&mut [..[f64; d_last]..; d_0]` with dims outermost first.
    Array(Vec<Dim>),
    /// `&mut Contact` (fields in [`CONTACT_FIELDS`] order).
    Contact,
}

/// One output argument and its nodes (row-major).
#[derive(Debug, Clone)]
pub struct OutArg {
    /// Argument name.
    pub name: String,
    /// Argument type.
    pub kind: OutKind,
    /// The graph node of every element, row-major.
    pub ids: Vec<Id>,
}

/// A kernel: name, documentation, inputs and outputs.
#[derive(Debug, Clone)]
pub struct KernelDef {
    /// Function name.
    pub name: String,
    /// Documentation (meaning, layout, units).
    pub doc: String,
    /// Input arguments.
    pub inputs: Vec<Arg>,
    /// Output arguments.
    pub outputs: Vec<OutArg>,
}

impl KernelDef {
    /// The graph nodes of every output, in argument order and each argument's layout (the
    /// flat output vector of the kernel, e.g. the roots of an interpreter tape).
    pub fn output_ids(&self) -> Vec<Id> {
        self.outputs
            .iter()
            .flat_map(|o| o.ids.iter().copied())
            .collect()
    }
}

/// Fields of the emitted `Contact` struct: name, dims, doc.
pub const CONTACT_FIELDS: &[(&str, &[Dim], &str)] = &[
    ("alpha", &[], "eq. 2: α = (o_b − p_e)·ê_x3 (m)"),
    (
        "sat_alpha",
        &[],
        "sat_{−a_n}^{0}(α) (m), exact or smooth (eq. 3, 58–59); 0 for tip-only contact",
    ),
    ("p_c", &[Dim::Lit(3)], "eq. 3: potential contact point (m)"),
    ("r_c", &[Dim::Lit(3)], "r_c = p_c − o_b (m)"),
    ("h", &[], "eq. 4: h = |r_c| − r (m)"),
    ("n", &[Dim::Lit(3)], "eq. 11: n = r_c/|r_c|"),
    (
        "j_c",
        &[Dim::Lit(3), Dim::Nq],
        "eq. 7: J_c = J_p − sat(α) S(ê_x3) J_o (m), row-major 3 × NQ",
    ),
    ("v_c", &[Dim::Lit(3)], "eq. 6: v_c = J_c q̇ (m/s)"),
    (
        "delta_v",
        &[Dim::Lit(3)],
        "eq. 13: Δv = ω × r_c − v_c (m/s)",
    ),
    ("h_dot", &[], "dh/dt = n·ṙ_c (m/s)"),
    (
        "rc_dot",
        &[Dim::Lit(3)],
        "ṙ_c = d/dt r_c (m/s), includes d sat(α)/dt",
    ),
    (
        "jc_dot_qd",
        &[Dim::Lit(3)],
        "J̇_c q̇ (m/s²), time derivative along q̇ including d sat(α)/dt (eq. 33)",
    ),
];

fn arr(name: &str, dims: &[Dim], ids: Vec<Id>) -> OutArg {
    OutArg {
        name: name.to_string(),
        kind: OutKind::Array(dims.to_vec()),
        ids,
    }
}

fn flat2(m: &[Vec<Id>]) -> Vec<Id> {
    m.iter().flatten().copied().collect()
}

fn flat3(m: &[Vec<Vec<Id>>]) -> Vec<Id> {
    m.iter().flatten().flatten().copied().collect()
}

/// Build the definition of kernel `name` on `model`.
pub fn build_kernel(model: &mut SymbolicRobot, name: &str) -> Result<KernelDef, CodegenError> {
    use Arg::*;
    use Dim::*;
    let (inputs, outputs, doc): (Vec<Arg>, Vec<OutArg>, String) = match name {
        "frames" => {
            let fr = model.frames();
            let pos: Vec<Id> = fr.iter().flat_map(|f| f.t).collect();
            let rot: Vec<Id> = fr.iter().flat_map(|f| f.r.into_iter().flatten()).collect();
            (
                vec![Q, P],
                vec![
                    arr("pos", &[Nq, Lit(3)], pos),
                    arr("rot", &[Nq, Lit(3), Lit(3)], rot),
                ],
                "World origin `pos[i]` (m) and rotation `rot[i]` (row-major, columns = frame axes \
                 in world coordinates) of DH frames 1..NQ (eq. 67–68); frame NQ includes the tool \
                 transform if any."
                    .into(),
            )
        }
        "tip_jacobian" => {
            let (jp, jo) = model.tip_jacobian();
            (
                vec![Q, P],
                vec![
                    arr("jp", &[Lit(3), Nq], flat2(&jp)),
                    arr("jo", &[Lit(3), Nq], flat2(&jo)),
                ],
                "Geometric Jacobian of the tip (origin of the last frame), world axes (eq. 69–71): \
                 `jp` translational (m/rad), `jo` rotational (1), each row-major 3 × NQ."
                    .into(),
            )
        }
        "com_jacobians" => {
            let js = model.com_jacobians();
            let jp: Vec<Id> = js.iter().flat_map(|(p, _)| flat2(p)).collect();
            let jo: Vec<Id> = js.iter().flat_map(|(_, o)| flat2(o)).collect();
            (
                vec![Q, P],
                vec![
                    arr("jp", &[Nq, Lit(3), Nq], jp),
                    arr("jo", &[Nq, Lit(3), Nq], jo),
                ],
                "Geometric Jacobians J_P^i, J_O^i of every link COG (eq. 22a), world axes: \
                 `jp[i]`, `jo[i]` for link i+1, each row-major 3 × NQ (columns of later joints \
                 are 0)."
                    .into(),
            )
        }
        "tip_jdot_qd" => {
            let v = model.tip_jdot_qd();
            (
                vec![Q, Qd, P],
                vec![arr("out", &[Lit(6)], v)],
                "J̇ q̇ of the tip: `out[0..3]` linear (m/s²), `out[3..6]` angular (rad/s²), world \
                 axes."
                    .into(),
            )
        }
        "mass_matrix" => {
            // The cheaper of the link-Jacobian form and the composite-rigid-body algorithm
            // (arms: CRBA, O(n²) against O(n³) operations; docs/decisions/0023). The doc line
            // stays as it was so modules whose choice did not change stay byte-identical.
            let m = model.mass_matrix_cheapest();
            (
                vec![Q, P],
                vec![arr("m", &[Nq, Nq], flat2(&m))],
                "Mass matrix M(q) (eq. 22a, 74), symmetric NQ × NQ, kg m².".into(),
            )
        }
        "dmass_dq" => {
            let d = model.dmass_dq();
            (
                vec![Q, P],
                vec![arr("out", &[Nq, Nq, Nq], flat3(&d))],
                "∂M/∂q: `out[k][i][j]` = ∂M_ij/∂q_k (kg m²/rad).".into(),
            )
        }
        "christoffel" => {
            let c = model.christoffel();
            (
                vec![Q, P],
                vec![arr("out", &[Nq, Nq, Nq], flat3(&c))],
                "Christoffel symbols `out[i][j][k]` = c_ijk = ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − \
                 ∂M_jk/∂q_i) (eq. 76–79)."
                    .into(),
            )
        }
        "coriolis_matrix" => {
            let c = model.coriolis_matrix();
            (
                vec![Q, Qd, P],
                vec![arr("c", &[Nq, Nq], flat2(&c))],
                "C(q, q̇), C_ij = Σ_k c_ijk q̇_k (eq. 76), so Ṁ − 2C is skew-symmetric.".into(),
            )
        }
        "coriolis_qd" => {
            let c = model.coriolis_qd();
            (
                vec![Q, Qd, P],
                vec![arr("out", &[Nq], c)],
                "C(q, q̇) q̇ (N m).".into(),
            )
        }
        "gravity" => {
            let g = model.gravity();
            (
                vec![Q, P],
                vec![arr("out", &[Nq], g)],
                "g(q) = ∂U/∂q (N m), eq. 72–73.".into(),
            )
        }
        "potential" => {
            let u = model.potential();
            (
                vec![Q, P],
                vec![OutArg {
                    name: "out".into(),
                    kind: OutKind::Scalar,
                    ids: vec![u],
                }],
                "Potential energy U(q) = −Σ m_i g_0ᵀ p_i (J).".into(),
            )
        }
        "cqd_g" => {
            let v = model.cqd_g();
            (
                vec![Q, Qd, P],
                vec![arr("out", &[Nq], v)],
                "C q̇ + g (N m), Lagrangian path (Ṁ q̇ − ∂T/∂q + ∂U/∂q).".into(),
            )
        }
        "cqd_g_rnea" => {
            let v = model.cqd_g_rnea();
            (
                vec![Q, Qd, P],
                vec![arr("out", &[Nq], v)],
                "C q̇ + g (N m) by recursive Newton–Euler with q̈ = 0.".into(),
            )
        }
        "mass_cqd_g" => {
            // M from link Jacobians or by the composite-rigid-body algorithm, C q̇ + g by
            // Newton–Euler or by the Christoffel symbols: the combination with the fewest
            // operations (arms: CRBA + Newton–Euler, sharing the link transforms; the finger:
            // Jacobians + Christoffel). All agree to rounding (tested).
            let (m, v) = model.mass_cqd_g();
            (
                vec![Q, Qd, P],
                vec![arr("m", &[Nq, Nq], flat2(&m)), arr("cqd_g", &[Nq], v)],
                "M(q) (kg m², eq. 22a; link Jacobians or composite-rigid-body algorithm) and \
                 C q̇ + g (N m; recursive Newton–Euler or Christoffel symbols), the cheapest \
                 combination, in one kernel (shared subexpressions)."
                    .into(),
            )
        }
        "inverse_dynamics" => {
            let t = model.inverse_dynamics();
            (
                vec![Q, Qd, Qdd, P],
                vec![arr("tau", &[Nq], t)],
                "Inverse dynamics τ = M(q) q̈ + C(q, q̇) q̇ + g(q) (N m; N for prismatic joints) \
                 by recursive Newton–Euler (eq. 24, no friction)."
                    .into(),
            )
        }
        "inverse_dynamics_dq" => {
            let d = model.inverse_dynamics_dq();
            (
                vec![Q, Qd, Qdd, P],
                vec![arr("out", &[Nq, Nq], flat2(&d))],
                "∂τ/∂q of the inverse dynamics: `out[i][k]` = ∂τ_i/∂q_k (exact, by \
                 differentiation of the Newton–Euler graph)."
                    .into(),
            )
        }
        "inverse_dynamics_dqd" => {
            let d = model.inverse_dynamics_dqd();
            (
                vec![Q, Qd, P],
                vec![arr("out", &[Nq, Nq], flat2(&d))],
                "∂τ/∂q̇ of the inverse dynamics: `out[i][k]` = ∂τ_i/∂q̇_k (exact; independent of \
                 q̈)."
                .into(),
            )
        }
        "forward_dynamics" => {
            // The cheaper of LDLᵀ and the articulated-body algorithm (docs/decisions/0023); the
            // LDLᵀ doc line is the one modules had before the choice existed.
            let (a, form) = model.forward_dynamics_form();
            let doc = match form {
                ForwardForm::Ldl => {
                    "Forward dynamics q̈ = M⁻¹(τ − C q̇ − g) (eq. 26a without friction) by an \
                     unrolled LDLᵀ factorisation of M."
                }
                ForwardForm::ArticulatedBody => {
                    "Forward dynamics q̈ = M⁻¹(τ − C q̇ − g) (eq. 26a without friction) by the \
                     articulated-body algorithm (fewer operations than an LDLᵀ of M here)."
                }
            };
            (vec![Q, Qd, Tau, P], vec![arr("qdd", &[Nq], a)], doc.into())
        }
        "regressor" => {
            let y = model.regressor();
            (
                vec![Q, Qd, Qdd, P],
                vec![arr("y", &[Nq, Nq, Lit(10)], flat3(&y))],
                "Dynamic regressor: `y[i][l][k]` = ∂τ_i/∂π_{l,k}, so `τ = Σ y[i][l][k] π_{l,k}` \
                 with π_l = [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz] of link \
                 l + 1 (c the COG and I the inertia about the link frame's origin, link-frame \
                 axes)."
                    .into(),
            )
        }
        "contact" | "contact_smooth" => {
            let smooth = name == "contact_smooth";
            let ids = contact_ids(&model.contact(smooth)?);
            let inputs = if smooth {
                vec![Q, Qd, Omega, Eps, P]
            } else {
                vec![Q, Qd, Omega, P]
            };
            let doc = if smooth {
                "Contact geometry between the last link and the ball (Sect. 2.2) with the smooth \
                 saturation sat(α) = ½(L + U + √((α−L)² + ε²) − √((α−U)² + ε²)), L = −a_n, U = 0 \
                 (eq. 58–59)."
            } else {
                "Contact geometry between the last link and the ball (Sect. 2.2, eq. 2–7, 11, 13) \
                 with the exact saturation sat_{−a_n}^{0}(α)."
            };
            (
                inputs,
                vec![OutArg {
                    name: "out".into(),
                    kind: OutKind::Contact,
                    ids,
                }],
                doc.into(),
            )
        }
        other => {
            return Err(SceneDefect::UnknownKernel {
                name: other.to_string(),
                in_list: false,
                known: ALL_KERNELS,
            }
            .into());
        }
    };
    model.check_size(&format!("kernel `{name}`"), crate::robot::KERNELS_ADVICE)?;
    check_inputs(model, name, &inputs, &outputs)?;
    Ok(KernelDef {
        name: name.to_string(),
        doc,
        inputs,
        outputs,
    })
}

/// Every graph variable a kernel's outputs read must be one of its arguments (the emitter
/// names variables by the layout, so a stray one would not compile).
fn check_inputs(
    model: &SymbolicRobot,
    name: &str,
    inputs: &[Arg],
    outputs: &[OutArg],
) -> Result<(), CodegenError> {
    let l = model.layout;
    let n = l.nq as u32;
    let roots: Vec<Id> = outputs.iter().flat_map(|o| o.ids.iter().copied()).collect();
    for v in model.cone_vars(&roots) {
        let needs = if v < n {
            Arg::Q
        } else if v < 2 * n {
            Arg::Qd
        } else if v < l.eps() {
            Arg::Omega
        } else if v == l.eps() {
            Arg::Eps
        } else if (v as usize) < l.n_vars() {
            Arg::P
        } else if v < l.qdd(0) + n {
            Arg::Qdd
        } else if v < l.tau(0) + n {
            Arg::Tau
        } else {
            return Err(InternalDefect::UnboundVariable {
                kernel: name.to_string(),
                variable: v,
            }
            .into());
        };
        if !inputs.contains(&needs) {
            return Err(InternalDefect::MissingArgument {
                kernel: name.to_string(),
                argument: format!("{needs:?}"),
            }
            .into());
        }
    }
    Ok(())
}
