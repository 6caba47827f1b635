//! Optimal-control node functions of the ball-and-finger system (paper Sect. 4), their exact
//! derivative graphs, and their emission as flat Rust kernels (issue 6, deliverable 3).
//!
//! A node function is what one collocation node of a phase imposes and accumulates:
//!
//! * free dynamics (eq. 26): M q̈ + C q̇ + μ_v q̇ + g − τ = 0,  I_b ω̇ + ω × I_b ω + D ω = 0;
//! * stick dynamics (eq. 29): M q̈ + C q̇ + μ_v q̇ + g − τ − J_cᵀ λ = 0,
//!   I_b ω̇ + ω × I_b ω + D ω + r_c × λ = 0, and the stick constraint Δv = 0 (eq. 14/27) or
//!   its time derivative ([`StickLevel::Acceleration`], the index-1 form of eq. 31–32);
//! * validity: h (eq. 4), λ_n = λ·n ≥ 0 (eq. 12) and the friction cone (eq. 18–19) as
//!   σ_δ = μ_s λ_n − (sqrt(‖λ_∥‖² + δ²) − δ) ≥ 0 (the smooth |·| of eq. 59, δ = [`CONE_DELTA`]);
//! * cost integrands (eq. 60): QC (eq. 64–65), COT (eq. 61–63), and the effort/time/tracking
//!   integrands of the other problems of Sect. 4.1 ([`CostKind`]).
//!
//! The contact geometry uses the smooth saturation (eq. 58–59). ε, the scene's runtime
//! parameters and every nonzero cost constant (w, ω_ref, ω̂_ref, axes) are graph *inputs*
//! listed in [`NodeFunction::fixed`], not constants baked into the graph: one emitted kernel
//! serves every ε of a continuation and every weight (zeros stay constants, see `Inputs`).
//!
//! [`NodeFunction::collocation`] forms the outputs a collocation node evaluates (ẋ and the cost
//! integrands scaled by T/2, eq. 51 mapped to τ ∈ [−1, 1]); [`Derivatives`] builds their exact
//! sparse Jacobian and the lower triangle of the weighted Lagrangian Hessian by symbolic
//! differentiation (forward mode, and forward over reverse). [`fingerprint`] hashes the
//! structure of those graphs, so that a solver can recognise, at run time, a node function
//! whose kernels were emitted at build time by [`emit_node_kernels`] (bf-generated's
//! `node_kernel`) and fall back to interpreting the graphs otherwise.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

use crate::emit::{EmitOptions, Ssa, f64_tokens, ssa};
use crate::graph::{Graph, Id, Node, V3};
use crate::robot::Model;
use crate::{CodegenError, Scene, diff};

/// δ of the smooth friction-cone margin σ_δ (N); σ_δ ≥ 0 implies σ ≥ −δ.
pub const CONE_DELTA: f64 = 1e-4;

/// Contact mode prescribed to a phase (paper Fig. 3, blue part).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// No contact (eq. 26).
    Free,
    /// Sticking contact (eq. 29, 14).
    Stick,
}

/// Cost integrands (c_1, c_2) of eq. 60.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CostKind {
    /// QC (eq. 64–65): c_1' = w‖τ‖² + ‖ω − ω_ref‖², c_2' = 1.
    Qc {
        /// w^QC.
        w: f64,
        /// ω_ref.
        omega_ref: [f64; 3],
    },
    /// COT (eq. 61–63): c_1' = ‖τ‖², c_2' = −w‖ω_⊥‖² + ω·ω̂_ref.
    Cot {
        /// w^COT.
        w: f64,
        /// Unit direction ω̂_ref.
        omega_hat: [f64; 3],
    },
    /// Effort plus time: c_1' = 1 + w‖τ‖², c_2' = 1 (reach).
    TimeEffort {
        /// Effort weight.
        w: f64,
    },
    /// Tracking: c_1' = ‖ω − ω_ref‖² + w‖τ‖², c_2' = 1.
    Track {
        /// Effort weight.
        w: f64,
        /// ω_ref.
        omega_ref: [f64; 3],
    },
    /// Time and effort with the rotation angle about an axis as second cost state:
    /// c_1' = 1 + w‖τ‖², c_2' = ω·ê (so c_2(t_f) is the rotation angle for a fixed axis).
    Reorient {
        /// Effort weight.
        w: f64,
        /// Axis ê.
        axis: [f64; 3],
    },
    /// Effort minus ball speed along an axis: c_1' = w‖τ‖² − ω·ê, c_2' = 1.
    Spin {
        /// Effort weight.
        w: f64,
        /// Axis ê.
        axis: [f64; 3],
    },
}

impl CostKind {
    /// Short name of the kind (kernel names).
    pub fn tag(&self) -> &'static str {
        match self {
            CostKind::Qc { .. } => "qc",
            CostKind::Cot { .. } => "cot",
            CostKind::TimeEffort { .. } => "time_effort",
            CostKind::Track { .. } => "track",
            CostKind::Reorient { .. } => "reorient",
            CostKind::Spin { .. } => "spin",
        }
    }

    /// One representative of every kind, with the zero pattern of the paper's problems
    /// (Sect. 6.1: ω_ref and the rotation axes along z, ω̂_ref in the xy plane). Nonzero
    /// constants are runtime inputs, so only which constants are zero matters: the emitted
    /// kernels serve every cost of these kinds with this zero pattern.
    pub fn all_kinds() -> [CostKind; 6] {
        let z = [0.0, 0.0, 1.0];
        let s = std::f64::consts::FRAC_1_SQRT_2;
        [
            CostKind::Qc {
                w: 1.0,
                omega_ref: z,
            },
            CostKind::Cot {
                w: 1.0,
                omega_hat: [s, -s, 0.0],
            },
            CostKind::TimeEffort { w: 1.0 },
            CostKind::Track {
                w: 1.0,
                omega_ref: z,
            },
            CostKind::Reorient { w: 1.0, axis: z },
            CostKind::Spin { w: 1.0, axis: z },
        ]
    }
}

/// Physical constants of a scene with a ball and a contact (the node functions' inputs that
/// are not on the robot's graph, plus limits the problems use as bounds).
#[derive(Debug, Clone, PartialEq)]
pub struct Physics {
    /// Joints.
    pub nq: usize,
    /// Ball inertia I_b.
    pub ib: [[f64; 3]; 3],
    /// Ball radius r.
    pub radius: f64,
    /// μ_s.
    pub mu_s: f64,
    /// μ_v.
    pub mu_v: f64,
    /// D.
    pub damping: f64,
    /// Joint limits (NaN-free; ±∞ where none).
    pub q_limits: Vec<(f64, f64)>,
    /// Torque limits.
    pub tau_max: Vec<f64>,
}

impl Physics {
    /// Reads the constants of `scene` (needs `[ball]`, `[contact]`).
    pub fn new(scene: &Scene) -> Result<Physics, CodegenError> {
        let ball = scene
            .ball
            .as_ref()
            .ok_or_else(|| CodegenError::Scene("the scene has no [ball]".into()))?;
        if scene.contact.is_none() {
            return Err(CodegenError::Scene("the scene has no [contact]".into()));
        }
        let (mu_s, mu_v, damping) = scene
            .friction
            .as_ref()
            .map_or((0.0, 0.0, 0.0), |f| (f.mu_s, f.mu_v, f.socket_damping));
        Ok(Physics {
            nq: scene.links.len(),
            ib: scene.ball_inertia().unwrap_or([[0.0; 3]; 3]),
            radius: ball.radius,
            mu_s,
            mu_v,
            damping,
            q_limits: scene
                .links
                .iter()
                .map(|l| {
                    (
                        l.q_min.unwrap_or(f64::NEG_INFINITY),
                        l.q_max.unwrap_or(f64::INFINITY),
                    )
                })
                .collect(),
            tau_max: scene
                .links
                .iter()
                .map(|l| l.tau_max.unwrap_or(f64::INFINITY))
                .collect(),
        })
    }
}

/// What a phase's dynamics, path constraints and cost integrands are, at one collocation node.
///
/// Graph variables `x`, `a`, `u` and `duration` are the node's local variables; `fixed` sets
/// other graph inputs (ε, runtime parameters, cost constants). `xdot` must have `x.len()`
/// entries (the collocation imposes ẋ = xdot); `costs` has one integrand per cost state of the
/// problem.
#[derive(Debug, Clone)]
pub struct NodeFunction {
    /// Expression graph.
    pub graph: Graph,
    /// Graph variables of the differential states.
    pub x: Vec<u32>,
    /// Graph variables of the algebraic node variables.
    pub a: Vec<u32>,
    /// Graph variables of the controls.
    pub u: Vec<u32>,
    /// A graph variable (unused by the expressions) for the phase duration.
    pub duration: u32,
    /// Values of other graph inputs.
    pub fixed: Vec<(u32, f64)>,
    /// State derivatives ẋ.
    pub xdot: Vec<Id>,
    /// Path constraints g (equalities have equal bounds).
    pub path: Vec<Id>,
    /// Bounds of `path`.
    pub path_bounds: Vec<(f64, f64)>,
    /// Cost integrands L_j (one per problem cost state).
    pub costs: Vec<Id>,
}

/// The outputs one collocation node evaluates, as a function of its local variables.
#[derive(Debug, Clone)]
pub struct Collocation {
    /// The node's graph plus the scaling nodes.
    pub graph: Graph,
    /// (T/2) ẋ (`x.len()` rows), the path constraints, (T/2) L_j.
    pub outputs: Vec<Id>,
    /// Local variables in order x, a, u, T.
    pub locals: Vec<u32>,
}

impl NodeFunction {
    /// The collocation outputs: on τ ∈ [−1, 1] the dynamics read dx/dτ = (T/2) ẋ and the cost
    /// integrals ∫ L dt = ∫ (T/2) L dτ (eq. 51 under t = t_0 + (τ + 1) T/2).
    pub fn collocation(&self) -> Collocation {
        let mut graph = self.graph.clone();
        let mut outputs = Vec::new();
        let t_var = graph.var(self.duration);
        let half = graph.constant(0.5);
        let ht = graph.mul(half, t_var);
        for &e in &self.xdot {
            outputs.push(graph.mul(ht, e));
        }
        outputs.extend(self.path.iter().copied());
        for &e in &self.costs {
            outputs.push(graph.mul(ht, e));
        }
        let mut locals = self.x.clone();
        locals.extend(&self.a);
        locals.extend(&self.u);
        locals.push(self.duration);
        Collocation {
            graph,
            outputs,
            locals,
        }
    }
}

/// Graph variable indices of one node.
#[derive(Debug, Clone)]
pub struct NodeVars {
    /// q, q̇, ω.
    pub x: Vec<u32>,
    /// q̈.
    pub qdd: Vec<u32>,
    /// ω̇.
    pub wd: Vec<u32>,
    /// λ.
    pub lambda: Vec<u32>,
    /// τ.
    pub tau: Vec<u32>,
    /// T.
    pub duration: u32,
}

/// Options of a phase's node function.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeOptions {
    /// Contact mode.
    pub mode: Mode,
    /// Cost integrands.
    pub cost: CostKind,
    /// Bounds on h at the nodes (None: no h path constraint).
    pub h_bounds: Option<(f64, f64)>,
    /// Bounds on ḣ at the nodes (Sect. 7 margins).
    pub hdot_bounds: Option<(f64, f64)>,
    /// ε of the smooth saturation.
    pub eps: f64,
}

/// Level at which a stick phase's nodes impose the no-slip constraint (eq. 14/27).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StickLevel {
    /// Δv = 0 at every node (index-2 DAE; right for Radau, whose nodes include one end of
    /// every element).
    #[default]
    Velocity,
    /// d(Δv)/dt = 0 at every node (the index-1 form that also yields λ in eq. 31–32), with
    /// Δv = 0 imposed once at the phase start by the impact law (eq. 40c). For Legendre–Gauss:
    /// see [`node_function`].
    Acceleration,
}

/// The scene's model graph with ε and the runtime parameters as fixed inputs; `base` is the
/// first free graph variable index.
#[derive(Debug)]
pub struct BuiltModel {
    /// The symbolic model.
    pub model: Model,
    /// (graph variable, value) of ε and of the runtime parameters.
    pub fixed: Vec<(u32, f64)>,
    /// First graph variable index after the robot layout.
    pub base: u32,
}

/// Builds the symbolic model of `scene` with ε = `eps`.
pub fn build_model(scene: &Scene, eps: f64) -> Result<BuiltModel, CodegenError> {
    let model = Model::new(scene)?;
    let lay = model.layout;
    let mut fixed = vec![(lay.eps(), eps)];
    for (i, p) in model.params.iter().enumerate() {
        fixed.push((lay.param(i), p.1));
    }
    let base = lay.n_vars() as u32;
    Ok(BuiltModel { model, fixed, base })
}

/// A constant 3 × 3 matrix on the graph.
pub fn m3_const(g: &mut Graph, a: [[f64; 3]; 3]) -> [[Id; 3]; 3] {
    let mut r = [[Id(0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = g.constant(a[i][j]);
        }
    }
    r
}

/// The graph nodes of variables `idx`.
pub fn vars(g: &mut Graph, idx: &[u32]) -> Vec<Id> {
    idx.iter().map(|&i| g.var(i)).collect()
}

/// The first three entries of `v` as a 3-vector.
pub fn v3(v: &[Id]) -> V3 {
    [v[0], v[1], v[2]]
}

/// Ball Newton–Euler residual I_b ω̇ + ω × I_b ω + D ω (+ r_c × λ), eq. 25/26b/29b.
fn ball_residual(g: &mut Graph, ph: &Physics, w: V3, wd: V3, rc_cross_lambda: Option<V3>) -> V3 {
    let ib = m3_const(g, ph.ib);
    let ibwd = g.m3_mul_v(&ib, wd);
    let ibw = g.m3_mul_v(&ib, w);
    let gyro = g.v3_cross(w, ibw);
    let d = g.constant(ph.damping);
    let dw = g.v3_scale(d, w);
    let s = g.v3_add(ibwd, gyro);
    let mut r = g.v3_add(s, dw);
    if let Some(t) = rc_cross_lambda {
        r = g.v3_add(r, t);
    }
    r
}

fn sq_norm(g: &mut Graph, v: &[Id]) -> Id {
    let t: Vec<Id> = v.iter().map(|&x| g.square(x)).collect();
    g.sum(&t)
}

/// Runtime inputs of the cost integrands: each constant becomes a fresh graph variable with
/// its value recorded in `fixed`.
struct Inputs<'a> {
    next: u32,
    fixed: &'a mut Vec<(u32, f64)>,
}

impl Inputs<'_> {
    /// A zero stays a constant, so that the graph keeps the sparsity it has with every
    /// constant baked (ω_ref = (0, 0, 2.2) has no ω_x, ω_y terms): an input that is zero would
    /// add structurally nonzero, numerically zero derivative entries, change the KKT pattern,
    /// its ordering and rounding, and with it the solver's path (`rotate-fast` went from 273
    /// to 1618 iterations and to another local optimum). Kernels are therefore emitted per
    /// zero pattern of the cost constants ([`CostKind::all_kinds`]).
    fn scalar(&mut self, g: &mut Graph, value: f64) -> Id {
        if value == 0.0 {
            return g.constant(0.0);
        }
        let v = self.next;
        self.next += 1;
        self.fixed.push((v, value));
        g.var(v)
    }

    fn vector(&mut self, g: &mut Graph, value: [f64; 3]) -> V3 {
        value.map(|x| self.scalar(g, x))
    }
}

fn cost_integrands(
    g: &mut Graph,
    cost: CostKind,
    tau: &[Id],
    w: V3,
    inp: &mut Inputs<'_>,
) -> Vec<Id> {
    let one = g.one();
    let tt = sq_norm(g, tau);
    match cost {
        CostKind::Qc { w: wq, omega_ref } | CostKind::Track { w: wq, omega_ref } => {
            let r = inp.vector(g, omega_ref);
            let d = g.v3_sub(w, r);
            let dd = sq_norm(g, &d);
            let wc = inp.scalar(g, wq);
            let a = g.mul(wc, tt);
            vec![g.add(a, dd), one]
        }
        CostKind::Cot { w: wc, omega_hat } => {
            let h = inp.vector(g, omega_hat);
            let along = g.v3_dot(w, h);
            let par = g.v3_scale(along, h);
            let perp = g.v3_sub(w, par);
            let pp = sq_norm(g, &perp);
            let wcc = inp.scalar(g, wc);
            let pen = g.mul(wcc, pp);
            vec![tt, g.sub(along, pen)]
        }
        CostKind::TimeEffort { w: we } => {
            let wc = inp.scalar(g, we);
            let a = g.mul(wc, tt);
            vec![g.add(one, a), one]
        }
        CostKind::Reorient { w: we, axis } => {
            let ax = inp.vector(g, axis);
            let along = g.v3_dot(w, ax);
            let wc = inp.scalar(g, we);
            let a = g.mul(wc, tt);
            vec![g.add(one, a), along]
        }
        CostKind::Spin { w: we, axis } => {
            let ax = inp.vector(g, axis);
            let along = g.v3_dot(w, ax);
            let wc = inp.scalar(g, we);
            let a = g.mul(wc, tt);
            vec![g.sub(a, along), one]
        }
    }
}

/// Node function of one phase with the stick constraint at `level` (only matters for
/// [`Mode::Stick`]); returns it with the variable indices. Path rows: finger dynamics (nq),
/// ball (3), then [stick: Δv or d(Δv)/dt (3), λ_n, cone], then [h], then [ḣ].
///
/// Why Legendre–Gauss needs [`StickLevel::Acceleration`]: with Δv = 0 at the Gauss nodes the
/// stick phase is collocated as an index-2 DAE, and Gauss collocation is not stiffly accurate
/// (|R(∞)| = 1): the algebraic λ and the state polynomial keep an undamped alternating mode
/// between the nodes, whose conditioning worsens with N (LG-30 stalls with δ_w ≈ 1e-3 every
/// iteration, Δv ≈ 5e-4 between nodes). At the acceleration level the phase is index 1, λ is
/// fixed node by node (eq. 31–32), and Δv(t) = Δv(t_0) + ∫ dΔv/dt stays 0 up to the Gauss
/// quadrature error, also at the quadrature end point.
pub fn node_function(
    scene: &Scene,
    ph: &Physics,
    opt: &NodeOptions,
    level: StickLevel,
) -> Result<(NodeFunction, NodeVars), CodegenError> {
    let BuiltModel {
        mut model,
        mut fixed,
        base,
    } = build_model(scene, opt.eps)?;
    let nq = ph.nq;
    let lay = model.layout;
    let xv: Vec<u32> = (0..nq)
        .map(|i| lay.q(i))
        .chain((0..nq).map(|i| lay.qd(i)))
        .chain((0..3).map(|i| lay.omega(i)))
        .collect();
    let mut next = base;
    let mut take = |n: usize| -> Vec<u32> {
        let r = (next..next + n as u32).collect();
        next += n as u32;
        r
    };
    let qdd_v = take(nq);
    let wd_v = take(3);
    let lam_v = if opt.mode == Mode::Stick {
        take(3)
    } else {
        vec![]
    };
    let tau_v = take(nq);
    let t_v = take(1)[0];
    // Cost constants become inputs after T.
    let first_input = t_v + 1;
    let mass = model.mass_matrix();
    let bias = model.cqd_g_rnea();
    let ce = model.contact(true)?;
    let g = &mut model.g;
    let qd = vars(g, &xv[nq..2 * nq]);
    let w = v3(&vars(g, &xv[2 * nq..]));
    let qdd = vars(g, &qdd_v);
    let wd = v3(&vars(g, &wd_v));
    let tau = vars(g, &tau_v);
    let lam = if opt.mode == Mode::Stick {
        Some(v3(&vars(g, &lam_v)))
    } else {
        None
    };
    let muv = g.constant(ph.mu_v);
    let mut path = Vec::new();
    let mut bounds = Vec::new();
    for i in 0..nq {
        let mq = g.dot(&mass[i], &qdd);
        let fr = g.mul(muv, qd[i]);
        let mut r = g.add(mq, bias[i]);
        r = g.add(r, fr);
        r = g.sub(r, tau[i]);
        if let Some(l) = lam {
            let col = [ce.j_c[0][i], ce.j_c[1][i], ce.j_c[2][i]];
            let jl = g.v3_dot(col, l);
            r = g.sub(r, jl);
        }
        path.push(r);
        bounds.push((0.0, 0.0));
    }
    let rcl = lam.map(|l| g.v3_cross(ce.r_c, l));
    let br = ball_residual(g, ph, w, wd, rcl);
    path.extend(br);
    bounds.extend([(0.0, 0.0); 3]);
    if let Some(l) = lam {
        match level {
            StickLevel::Velocity => path.extend(ce.delta_v),
            StickLevel::Acceleration => {
                // d/dt Δv(q, q̇, ω) along (q̇, q̈, ω̇), all node variables.
                let rates: Vec<Id> = qd.iter().chain(&qdd).chain(&wd).copied().collect();
                path.extend(diff::time_derivative(g, &ce.delta_v, &xv, &rates));
            }
        }
        bounds.extend([(0.0, 0.0); 3]);
        let ln = g.v3_dot(l, ce.n);
        path.push(ln);
        bounds.push((0.0, f64::INFINITY));
        // σ_δ = μ_s λ_n − (sqrt(‖λ_∥‖² + δ²) − δ): eq. 18 with the smooth |·| of eq. 59,
        // shifted so that σ_δ(0) = 0; its gradient μ_s n never vanishes (unlike the squared
        // cone at λ = 0), and σ ≥ σ_δ − δ.
        let ll = g.v3_dot(l, l);
        let ln2 = g.square(ln);
        let par2 = g.sub(ll, ln2);
        let d = g.constant(CONE_DELTA);
        let d2 = g.constant(CONE_DELTA * CONE_DELTA);
        let s2 = g.add(par2, d2);
        let root = g.sqrt(s2);
        let sm = g.sub(root, d);
        let mu = g.constant(ph.mu_s);
        let a = g.mul(mu, ln);
        path.push(g.sub(a, sm));
        bounds.push((0.0, f64::INFINITY));
    }
    if let Some(b) = opt.h_bounds {
        path.push(ce.h);
        bounds.push(b);
    }
    if let Some(b) = opt.hdot_bounds {
        path.push(ce.h_dot);
        bounds.push(b);
    }
    let mut inputs = Inputs {
        next: first_input,
        fixed: &mut fixed,
    };
    let costs = cost_integrands(g, opt.cost, &tau, w, &mut inputs);
    let mut xdot = qd.clone();
    xdot.extend(&qdd);
    xdot.extend(wd);
    let mut a_v = qdd_v.clone();
    a_v.extend(&wd_v);
    a_v.extend(&lam_v);
    let nf = NodeFunction {
        graph: std::mem::take(&mut model.g),
        x: xv.clone(),
        a: a_v,
        u: tau_v.clone(),
        duration: t_v,
        fixed,
        xdot,
        path,
        path_bounds: bounds,
        costs,
    };
    Ok((
        nf,
        NodeVars {
            x: xv,
            qdd: qdd_v,
            wd: wd_v,
            lambda: lam_v,
            tau: tau_v,
            duration: t_v,
        },
    ))
}

/// The exact sparse first and second derivatives of graph outputs y = f(v) with respect to
/// local variables v, as graph nodes.
///
/// The Jacobian comes from one forward sweep per local variable, its entries row-major with
/// structural zeros dropped; the Hessian is the lower triangle (i ≥ j) of ∇²(Σ_i w_i y_i) by
/// forward over reverse, with the weights w as extra graph variables `weight_base + i`.
#[derive(Debug, Clone)]
pub struct Derivatives {
    /// Graph variable of the first weight (after every variable the outputs, the locals or the
    /// fixed inputs use).
    pub weight_base: u32,
    /// Jacobian pattern (output, local).
    pub jac: Vec<(usize, usize)>,
    /// Jacobian entries, in `jac` order.
    pub jac_ids: Vec<Id>,
    /// Lower-triangle Hessian pattern (local i ≥ local j).
    pub hess: Vec<(usize, usize)>,
    /// Hessian entries, in `hess` order.
    pub hess_ids: Vec<Id>,
}

impl Derivatives {
    /// Differentiates `outputs` of `g` with respect to the graph variables `locals`.
    pub fn new(g: &mut Graph, outputs: &[Id], locals: &[u32], fixed: &[(u32, f64)]) -> Self {
        let mark = g.cone(outputs);
        let mut max_var = 0usize;
        for (i, m) in mark.iter().enumerate() {
            if *m && let Node::Var(v) = g.node(Id(i as u32)) {
                max_var = max_var.max(v as usize + 1);
            }
        }
        for &v in locals.iter().chain(fixed.iter().map(|f| &f.0)) {
            max_var = max_var.max(v as usize + 1);
        }
        let weight_base = max_var as u32;
        let mut jac = Vec::new();
        let mut jac_ids = Vec::new();
        for (l, &v) in locals.iter().enumerate() {
            let col = diff::partial(g, outputs, v);
            for (o, id) in col.into_iter().enumerate() {
                if !g.is_zero(id) {
                    jac.push((o, l));
                    jac_ids.push(id);
                }
            }
        }
        // Row-major entries, for readable patterns.
        let mut order: Vec<usize> = (0..jac.len()).collect();
        order.sort_by_key(|&k| jac[k]);
        let jac: Vec<(usize, usize)> = order.iter().map(|&k| jac[k]).collect();
        let jac_ids: Vec<Id> = order.iter().map(|&k| jac_ids[k]).collect();
        let weighted: Vec<(Id, Id)> = outputs
            .iter()
            .enumerate()
            .map(|(i, &o)| (o, g.var(weight_base + i as u32)))
            .collect();
        let h = diff::hessian(g, &weighted, locals);
        let mut hess = Vec::new();
        let mut hess_ids = Vec::new();
        for i in 0..locals.len() {
            for j in 0..=i {
                let id = h[i][j];
                if !g.is_zero(id) {
                    hess.push((i, j));
                    hess_ids.push(id);
                }
            }
        }
        Derivatives {
            weight_base,
            jac,
            jac_ids,
            hess,
            hess_ids,
        }
    }
}

/// What a graph variable is to a compiled node function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VarRole {
    /// Local variable `l` (an argument).
    Local(u32),
    /// Fixed input `k` (position in the `fixed` list; its value is an argument of a kernel
    /// and a constant of an interpreted program).
    Fixed(u32, f64),
    /// Hessian weight `w`.
    Weight(u32),
    /// Anything else: reads as 0.
    Zero,
}

/// The role of every graph variable below `weight_base + n_out`: fixed inputs first, then
/// locals (a variable that is both is local), then the weights.
pub fn var_roles(
    locals: &[u32],
    fixed: &[(u32, f64)],
    weight_base: u32,
    n_out: usize,
) -> Vec<VarRole> {
    let mut role = vec![VarRole::Zero; weight_base as usize + n_out];
    for (k, &(v, x)) in fixed.iter().enumerate() {
        role[v as usize] = VarRole::Fixed(k as u32, x);
    }
    for (l, &v) in locals.iter().enumerate() {
        role[v as usize] = VarRole::Local(l as u32);
    }
    for w in 0..n_out {
        role[weight_base as usize + w] = VarRole::Weight(w as u32);
    }
    role
}

/// 128-bit FNV-1a (two independent 64-bit streams): stable across platforms and compiler
/// versions, unlike `std`'s hashers, so build time and run time agree.
struct Fnv([u64; 2]);

impl Fnv {
    fn new() -> Self {
        Fnv([0xcbf2_9ce4_8422_2325, 0x6c62_272e_07bb_0142])
    }
    fn byte(&mut self, b: u8) {
        self.0[0] = (self.0[0] ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        self.0[1] = (self.0[1] ^ b as u64).wrapping_mul(0x0000_0100_0000_0193);
    }
    fn u64(&mut self, x: u64) {
        for b in x.to_le_bytes() {
            self.byte(b);
        }
    }
    fn finish(&self) -> u128 {
        ((self.0[0] as u128) << 64) | self.0[1] as u128
    }
}

/// Structural fingerprint of a compiled node function: the cone of the outputs and of their
/// derivatives, node by node in graph order, with operands renumbered within the cone,
/// constants by their bits and variables by their [`VarRole`] (fixed inputs by position, not
/// value), plus the output lists and patterns. Two node functions with the same fingerprint
/// compute the same values with the same operations for the same locals, fixed values and
/// weights.
pub fn fingerprint(g: &Graph, outputs: &[Id], d: &Derivatives, roles: &[VarRole]) -> u128 {
    let mut roots: Vec<Id> = outputs.to_vec();
    roots.extend(&d.jac_ids);
    roots.extend(&d.hess_ids);
    let mark = g.cone(&roots);
    let mut pos = vec![u32::MAX; mark.len()];
    let mut h = Fnv::new();
    let mut count = 0u32;
    for (i, &m) in mark.iter().enumerate() {
        if !m {
            continue;
        }
        pos[i] = count;
        count += 1;
        let node = g.node(Id(i as u32));
        let ops = |tag: u8, args: &[Id], h: &mut Fnv| {
            h.byte(tag);
            for a in args {
                h.u64(pos[a.index()] as u64);
            }
        };
        match node {
            Node::Const(b) => {
                h.byte(0);
                h.u64(b);
            }
            Node::Var(v) => {
                h.byte(1);
                match roles.get(v as usize).copied().unwrap_or(VarRole::Zero) {
                    VarRole::Local(l) => {
                        h.byte(0);
                        h.u64(l as u64);
                    }
                    VarRole::Fixed(k, _) => {
                        h.byte(1);
                        h.u64(k as u64);
                    }
                    VarRole::Weight(w) => {
                        h.byte(2);
                        h.u64(w as u64);
                    }
                    VarRole::Zero => h.byte(3),
                }
            }
            Node::Add(a, b) => ops(2, &[a, b], &mut h),
            Node::Sub(a, b) => ops(3, &[a, b], &mut h),
            Node::Mul(a, b) => ops(4, &[a, b], &mut h),
            Node::Div(a, b) => ops(5, &[a, b], &mut h),
            Node::Neg(a) => ops(6, &[a], &mut h),
            Node::Sin(a) => ops(7, &[a], &mut h),
            Node::Cos(a) => ops(8, &[a], &mut h),
            Node::Sqrt(a) => ops(9, &[a], &mut h),
            Node::Abs(a) => ops(10, &[a], &mut h),
            Node::Min(a, b) => ops(11, &[a, b], &mut h),
            Node::Max(a, b) => ops(12, &[a, b], &mut h),
            Node::IfLt(a, b, t, f) => ops(13, &[a, b, t, f], &mut h),
        }
    }
    for list in [outputs, &d.jac_ids[..], &d.hess_ids[..]] {
        h.byte(0xff);
        h.u64(list.len() as u64);
        for id in list {
            h.u64(pos[id.index()] as u64);
        }
    }
    for pattern in [&d.jac, &d.hess] {
        h.byte(0xfe);
        for &(a, b) in pattern.iter() {
            h.u64(a as u64);
            h.u64(b as u64);
        }
    }
    h.finish()
}

/// A node function ready for emission: its collocation outputs, derivatives, roles and
/// fingerprint.
#[derive(Debug, Clone)]
pub struct CompiledNode {
    /// Graph holding outputs and derivatives.
    pub graph: Graph,
    /// Collocation outputs.
    pub outputs: Vec<Id>,
    /// Local variables.
    pub locals: Vec<u32>,
    /// Fixed inputs (values are those of the build; kernels take them as arguments).
    pub fixed: Vec<(u32, f64)>,
    /// Derivative graphs.
    pub derivs: Derivatives,
    /// Role of every graph variable.
    pub roles: Vec<VarRole>,
    /// [`fingerprint`].
    pub fingerprint: u128,
}

impl CompiledNode {
    /// Differentiates and fingerprints `outputs` of `graph` over `locals`.
    pub fn new(
        mut graph: Graph,
        outputs: Vec<Id>,
        locals: Vec<u32>,
        fixed: Vec<(u32, f64)>,
    ) -> Self {
        let derivs = Derivatives::new(&mut graph, &outputs, &locals, &fixed);
        let roles = var_roles(&locals, &fixed, derivs.weight_base, outputs.len());
        let fingerprint = fingerprint(&graph, &outputs, &derivs, &roles);
        CompiledNode {
            graph,
            outputs,
            locals,
            fixed,
            derivs,
            roles,
            fingerprint,
        }
    }
}

/// The node functions emitted as kernels for a scene with a ball and a contact, for every cost
/// kind of the scene's `ocp_kernels` (default: all), shaped as the problem library uses them:
/// a free phase (h row) for every kind; for the periodic costs (QC, COT) also the free phase
/// with the Sect. 7 ḣ margin row and the stick phase at both levels; for the free–stick
/// archetypes' costs (track, reorient, spin) the stick phase with the |h| row at both levels;
/// `reach`'s time–effort cost has no stick phase. Other shapes are interpreted. Names are
/// `<scene>_<cost>_<phase>`. Empty without a ball or a contact.
pub fn node_kernel_specs(scene: &Scene) -> Vec<(String, NodeOptions, StickLevel)> {
    let mut out = Vec::new();
    if scene.ball.is_none() || scene.contact.is_none() {
        return out;
    }
    for cost in CostKind::all_kinds() {
        if let Some(list) = &scene.ocp_kernels
            && !list.iter().any(|c| c == cost.tag())
        {
            continue;
        }
        let base = NodeOptions {
            mode: Mode::Free,
            cost,
            h_bounds: Some((0.0, f64::INFINITY)),
            hdot_bounds: None,
            eps: 0.01,
        };
        let name = |s: &str| format!("{}_{}_{s}", scene.name, cost.tag());
        out.push((name("free"), base.clone(), StickLevel::Velocity));
        let (stick, tag) = match cost {
            CostKind::Qc { .. } | CostKind::Cot { .. } => {
                let margin = NodeOptions {
                    hdot_bounds: Some((f64::NEG_INFINITY, 0.0)),
                    ..base.clone()
                };
                out.push((name("free_hdot"), margin, StickLevel::Velocity));
                let stick = NodeOptions {
                    mode: Mode::Stick,
                    h_bounds: None,
                    ..base
                };
                (stick, "stick")
            }
            CostKind::TimeEffort { .. } => continue,
            _ => {
                let stick = NodeOptions {
                    mode: Mode::Stick,
                    ..base
                };
                (stick, "stick_h")
            }
        };
        out.push((name(tag), stick.clone(), StickLevel::Velocity));
        out.push((name(&format!("{tag}_acc")), stick, StickLevel::Acceleration));
    }
    out
}

/// Compiles the node function `opt` of `scene` at `level` for collocation.
pub fn compile_node(
    scene: &Scene,
    opt: &NodeOptions,
    level: StickLevel,
) -> Result<CompiledNode, CodegenError> {
    let ph = Physics::new(scene)?;
    let (nf, _) = node_function(scene, &ph, opt, level)?;
    let c = nf.collocation();
    Ok(CompiledNode::new(c.graph, c.outputs, c.locals, nf.fixed))
}

/// Tokens of one kernel function `fn name(local, fixed, w, out)` computing `roots` into
/// `out[0..roots.len()]`.
fn kernel_fn(name: &Ident, doc: &str, node: &CompiledNode, roots: &[Id]) -> TokenStream {
    let lit = |i: u32| Literal::u32_unsuffixed(i);
    let var_tokens = |v: u32| -> TokenStream {
        match node.roles.get(v as usize).copied().unwrap_or(VarRole::Zero) {
            VarRole::Local(l) => {
                let i = lit(l);
                quote!(local[#i])
            }
            VarRole::Fixed(k, _) => {
                let i = lit(k);
                quote!(fixed[#i])
            }
            VarRole::Weight(w) => {
                let i = lit(w);
                quote!(w[#i])
            }
            VarRole::Zero => f64_tokens(0.0),
        }
    };
    let Ssa {
        mut stmts,
        refs,
        ops,
    } = ssa(&node.graph, roots, &var_tokens, &EmitOptions::default());
    for (k, id) in roots.iter().enumerate() {
        let v = refs[id.index()].clone().unwrap_or_else(|| f64_tokens(0.0));
        let i = Literal::usize_unsuffixed(k);
        stmts.push(quote!(out[#i] = #v;));
    }
    let nl = Literal::usize_unsuffixed(node.locals.len());
    let nf = Literal::usize_unsuffixed(node.fixed.len());
    let no = Literal::usize_unsuffixed(roots.len());
    let doc = format!(
        " {doc} Cost: {} operations, {} temporaries.",
        ops.total(),
        ops.temporaries
    );
    quote! {
        #[doc = #doc]
        #[allow(unused_variables, clippy::all)]
        fn #name(local: &[f64], fixed: &[f64], w: &[f64], out: &mut [f64]) {
            // Lengths are checked once so that every constant index below is in bounds
            // without a per-access check.
            let local = &local[..#nl];
            let fixed = &fixed[..#nf];
            let out = &mut out[..#no];
            #(#stmts)*
        }
    }
}

/// Tokens of the three kernels of `node` and of its `NodeKernel` table entry.
fn node_tokens(name: &str, what: &str, node: &CompiledNode) -> (TokenStream, TokenStream) {
    let id = |s: &str| Ident::new(&format!("{name}_{s}"), Span::call_site());
    let (fv, fj, fh) = (id("value"), id("jacobian"), id("hessian"));
    let d = &node.derivs;
    let value = kernel_fn(
        &fv,
        &format!("Outputs of the {what} node function (T/2·ẋ, path rows, T/2·L)."),
        node,
        &node.outputs,
    );
    let jac = kernel_fn(
        &fj,
        &format!("Jacobian values of the {what} node function, pattern order."),
        node,
        &d.jac_ids,
    );
    let hess = kernel_fn(
        &fh,
        &format!("Lower-triangle Lagrangian Hessian values of the {what} node function."),
        node,
        &d.hess_ids,
    );
    let pairs = |p: &[(usize, usize)]| {
        let items = p.iter().map(|&(a, b)| {
            let (a, b) = (
                Literal::u32_unsuffixed(a as u32),
                Literal::u32_unsuffixed(b as u32),
            );
            quote!((#a, #b))
        });
        quote!(&[#(#items),*])
    };
    let (jp, hp) = (pairs(&d.jac), pairs(&d.hess));
    let fp = Literal::u128_unsuffixed(node.fingerprint);
    let n_out = Literal::usize_unsuffixed(node.outputs.len());
    let n_local = Literal::usize_unsuffixed(node.locals.len());
    let n_fixed = Literal::usize_unsuffixed(node.fixed.len());
    let entry = quote! {
        NodeKernel {
            name: #name,
            fingerprint: #fp,
            n_out: #n_out,
            n_local: #n_local,
            n_fixed: #n_fixed,
            jacobian_pattern: #jp,
            hessian_pattern: #hp,
            value: #fv,
            jacobian: #fj,
            hessian: #fh,
        },
    };
    (quote!(#value #jac #hess), entry)
}

/// The Rust source of the OCP node kernels of `scenes` (those with a ball and a contact; the
/// others are skipped): one value, Jacobian and Hessian function per
/// [`node_kernel_specs`] entry, and `pub static NODE_KERNELS: &[NodeKernel]` sorted by
/// fingerprint. The including module must define `NodeKernel`. Deterministic: the same
/// scenes give the same text.
pub fn emit_node_kernels(scenes: &[&Scene]) -> Result<String, CodegenError> {
    let mut fns = Vec::new();
    let mut entries: Vec<(u128, TokenStream)> = Vec::new();
    for scene in scenes {
        for (name, opt, level) in node_kernel_specs(scene) {
            let node = compile_node(scene, &opt, level)?;
            // Same structure as an earlier spec (QC and tracking share their integrands, the
            // constants being inputs): that kernel serves both.
            if entries.iter().any(|e| e.0 == node.fingerprint) {
                continue;
            }
            let what = format!("`{name}` (scene `{}`, {:?} level)", scene.name, level);
            let (f, e) = node_tokens(&name, &what, &node);
            fns.push(f);
            entries.push((node.fingerprint, e));
        }
    }
    entries.sort_by_key(|e| e.0);
    let items = entries.iter().map(|e| &e.1);
    let tokens = quote! {
        /// Every emitted node kernel, sorted by fingerprint (binary search).
        pub static NODE_KERNELS: &[NodeKernel] = &[#(#items)*];
        #(#fns)*
    };
    let file: syn::File = syn::parse2(tokens)
        .map_err(|e| CodegenError::Internal(format!("emitted node kernels do not parse: {e}")))?;
    let mut out =
        String::from("// @generated by bf-codegen (ocp::emit_node_kernels). Do not edit.\n");
    out.push_str(&prettyplease::unparse(&file));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> Scene {
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/paper.toml")).unwrap()
    }

    fn opts(mode: Mode, eps: f64, w: f64) -> NodeOptions {
        NodeOptions {
            mode,
            cost: CostKind::Qc {
                w,
                omega_ref: [0.0, 0.0, 2.2],
            },
            h_bounds: Some((0.0, f64::INFINITY)),
            hdot_bounds: None,
            eps,
        }
    }

    #[test]
    fn fingerprint_ignores_input_values_but_not_structure() {
        let s = paper();
        let fp = |o: &NodeOptions, l| compile_node(&s, o, l).unwrap().fingerprint;
        let base = fp(&opts(Mode::Free, 0.01, 1.0), StickLevel::Velocity);
        // ε and the cost weight are inputs: same kernel.
        assert_eq!(base, fp(&opts(Mode::Free, 0.05, 3.0), StickLevel::Velocity));
        // Another mode, stick level, row set or baked constant: another function.
        let stick = fp(&opts(Mode::Stick, 0.01, 1.0), StickLevel::Velocity);
        let stick_acc = fp(&opts(Mode::Stick, 0.01, 1.0), StickLevel::Acceleration);
        let no_h = fp(
            &NodeOptions {
                h_bounds: None,
                ..opts(Mode::Free, 0.01, 1.0)
            },
            StickLevel::Velocity,
        );
        // A nonzero where the pattern had a zero is another structure.
        let tilted = fp(
            &NodeOptions {
                cost: CostKind::Qc {
                    w: 1.0,
                    omega_ref: [0.1, 0.0, 2.2],
                },
                ..opts(Mode::Free, 0.01, 1.0)
            },
            StickLevel::Velocity,
        );
        let mut other = s.clone();
        if let Some(f) = other.friction.as_mut() {
            f.mu_v *= 2.0;
        }
        let other_mu =
            compile_node(&other, &opts(Mode::Free, 0.01, 1.0), StickLevel::Velocity).unwrap();
        let all = [base, stick, stick_acc, no_h, tilted, other_mu.fingerprint];
        for i in 0..all.len() {
            for j in 0..i {
                assert_ne!(all[i], all[j], "{i} vs {j}");
            }
        }
    }

    #[test]
    fn emission_is_deterministic_and_covers_the_requested_costs() {
        let mut s = paper();
        s.ocp_kernels = Some(vec!["cot".into()]);
        let a = emit_node_kernels(&[&s]).unwrap();
        let b = emit_node_kernels(&[&s]).unwrap();
        assert_eq!(a, b);
        for k in [
            "paper_cot_free",
            "paper_cot_free_hdot",
            "paper_cot_stick",
            "paper_cot_stick_acc",
        ] {
            assert!(a.contains(&format!("name: \"{k}\"")), "{k} missing");
            assert!(
                a.contains(&format!("fn {k}_hessian(")),
                "{k} hessian missing"
            );
        }
        assert!(!a.contains("paper_qc_"));
        // Entries sorted by fingerprint, as `node_kernel`'s binary search needs.
        let fps: Vec<u128> = a
            .lines()
            .filter_map(|l| l.trim().strip_prefix("fingerprint: "))
            .map(|v| v.trim_end_matches(',').parse().unwrap())
            .collect();
        assert_eq!(fps.len(), 4);
        assert!(fps.windows(2).all(|w| w[0] < w[1]));
        // An empty list emits no kernel.
        s.ocp_kernels = Some(vec![]);
        assert!(!emit_node_kernels(&[&s]).unwrap().contains("name:"));
    }
}
