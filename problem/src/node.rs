//! Optimal-control node functions of the ball-and-finger system (paper Sect. 4) on the
//! bf-codegen expression graph.
//!
//! A node function is what one collocation node of a phase imposes and accumulates:
//!
//! * free dynamics (eq. 26): M q̈ + C q̇ + μ_v q̇ + g − τ = 0,  I_b ω̇ + ω × I_b ω + D ω = 0;
//! * stick dynamics (eq. 29): M q̈ + C q̇ + μ_v q̇ + g − τ − J_cᵀ λ = 0,
//!   I_b ω̇ + ω × I_b ω + D ω + r_c × λ = 0, and the stick constraint Δv = 0 (eq. 14/27) or
//!   its time derivative ([`StickLevel::Acceleration`], the index-1 form of eq. 31–32);
//! * validity: h (eq. 4), λ_n = λ·n ≥ 0 (eq. 12) and the friction cone (eq. 18–19) as
//!   σ_δ = μ_s λ_n − (sqrt(‖λ_∥‖² + δ²) − δ) ≥ 0 (the smooth |·| of eq. 59, δ = [`CONE_DELTA`] / r);
//! * cost integrands (eq. 60): QC (eq. 64–65), COT (eq. 61–63), and the effort/time/tracking
//!   integrands of the other problems of Sect. 4.1 ([`CostKind`]).
//!
//! Node variables (graph `Var` indices after the robot layout q, q̇, ω, ε, parameters): q̈, ω̇
//! (algebraic, so the dynamics are imposed implicitly), λ (stick only), τ (control), and the
//! phase duration T. The contact geometry uses the smooth saturation (eq. 58–59). ε, the
//! scene's runtime parameters and every nonzero cost constant (w, ω_ref, ω̂_ref, axes) are
//! graph *inputs* listed in [`NodeFunction::fixed`], not constants baked into the graph: one
//! emitted kernel ([`crate::kernels`]) serves every ε of a continuation and every weight
//! (zeros stay constants, see `Inputs`).

use bf_codegen::graph::{Graph, Id, V3};
use bf_codegen::nodefn::NodeFunction;
use bf_codegen::robot::SymbolicRobot;
use bf_codegen::{CodegenError, Scene, SceneDefect, diff};

/// δ r of the smooth friction-cone margin σ_δ (N m: δ = 1e-4 N on the paper's ball of 1 m);
/// σ_δ ≥ 0 implies σ ≥ −δ. Divided by the ball's radius r because a finger drawn at a scale s
/// with the same dynamics (lengths × s, masses × 1/s², gravity × s) presses with forces 1/s
/// times the paper's, so δ keeps its share of them (decision record 0082).
pub const CONE_DELTA: f64 = 1e-4;

/// Contact mode prescribed to a phase (paper Fig. 3, blue part). Not the hybrid system's
/// [`bf_scene::Mode`]: a phase is free or sticking (the problems of Sect. 4 have no slip
/// phases, so a slip variant would be a case every match must reject), and `solution.json`
/// writes it in lowercase like every mode (`"free"` / `"stick"`); files written before read
/// as well (`"Free"` / `"Stick"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PhaseMode {
    /// No contact (eq. 26).
    #[serde(alias = "Free")]
    Free,
    /// Sticking contact (eq. 29, 14).
    #[serde(alias = "Stick")]
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
    /// Time and effort with the spin about an axis integrated as second cost state:
    /// c_1' = 1 + w‖τ‖², c_2' = ω·ê (so c_2(t_f) = ∫ω·ê dt, the rotation angle about ê only
    /// while ω stays along ê).
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

/// The scene constants the node functions read that are not on the robot's graph (I_b, r, μ_s,
/// μ_v, D), plus the limits the problems use as bounds: the one scene-constants type
/// [`bf_scene::Constants`], shared with bf-model.
pub type Physics = bf_scene::Constants;

/// The constants of `scene`, which needs a `[ball]` and a `[contact]` section.
pub fn physics(scene: &Scene) -> Result<Physics, CodegenError> {
    if scene.contact.is_none() && scene.ball.is_some() {
        return Err(SceneDefect::NoContact.into());
    }
    Physics::of(scene).ok_or_else(|| SceneDefect::NoBall.into())
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
    /// Index of h among the path outputs (`None` without `h_bounds`).
    pub h_path: Option<usize>,
}

/// Settings of a phase's node function.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeSettings {
    /// Contact mode.
    pub mode: PhaseMode,
    /// Cost integrands.
    pub cost: CostKind,
    /// Bounds on h at the nodes (None: no h path constraint).
    pub h_bounds: Option<(f64, f64)>,
    /// Bounds on ḣ at the nodes (Sect. 7 margins).
    pub hdot_bounds: Option<(f64, f64)>,
    /// ε of the smooth saturation.
    pub eps: f64,
    /// Fraction of the friction cone a stick phase leaves unused: its cone row is σ_δ with
    /// (1 − m) μ_s in place of μ_s (eq. 18), so that a controller keeps that share of μ_s λ_n
    /// for its feedback. An input of the node function, like ε: any m uses the same kernel.
    pub cone_margin: f64,
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
    pub model: SymbolicRobot,
    /// (graph variable, value) of ε and of the runtime parameters.
    pub fixed: Vec<(u32, f64)>,
    /// First graph variable index after the robot layout.
    pub base: u32,
}

/// Builds the symbolic model of `scene` with ε = `eps`.
pub fn build_model(scene: &Scene, eps: f64) -> Result<BuiltModel, CodegenError> {
    let model = SymbolicRobot::new(scene)?;
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
/// [`PhaseMode::Stick`]); returns it with the variable indices. Path rows: finger dynamics (nq),
/// ball (3), then [stick: Δv or d(Δv)/dt (3), λ_n, cone], then \[h\], then \[ḣ\].
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
    opt: &NodeSettings,
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
    let lam_v = if opt.mode == PhaseMode::Stick {
        take(3)
    } else {
        vec![]
    };
    let tau_v = take(nq);
    let t_v = take(1)[0];
    // μ (stick phases) and the cost constants become inputs after T.
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
    let lam = if opt.mode == PhaseMode::Stick {
        Some(v3(&vars(g, &lam_v)))
    } else {
        None
    };
    let mut inputs = Inputs {
        next: first_input,
        fixed: &mut fixed,
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
        let delta = CONE_DELTA / ph.radius;
        let d = g.constant(delta);
        let d2 = g.constant(delta * delta);
        let s2 = g.add(par2, d2);
        let root = g.sqrt(s2);
        let sm = g.sub(root, d);
        // μ is an input, so that one kernel serves every scene's μ_s and every planning
        // margin (a zero μ_s stays a constant, as `Inputs` keeps zeros).
        let mu = inputs.scalar(g, (1.0 - opt.cone_margin) * ph.mu_s);
        let a = g.mul(mu, ln);
        path.push(g.sub(a, sm));
        bounds.push((0.0, f64::INFINITY));
    }
    let h_path = opt.h_bounds.map(|b| {
        path.push(ce.h);
        bounds.push(b);
        path.len() - 1
    });
    if let Some(b) = opt.hdot_bounds {
        path.push(ce.h_dot);
        bounds.push(b);
    }
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
            h_path,
        },
    ))
}
