//! Ball-and-finger node and point functions on the bf-codegen expression graph.
//!
//! Node variables (graph `Var` indices after the robot layout q, q̇, ω, ε, parameters):
//! q̈, ω̇ (algebraic, so the dynamics are imposed implicitly), λ (stick only), τ (control),
//! and the phase duration T. Residuals:
//!
//! * free dynamics (eq. 26): M q̈ + C q̇ + μ_v q̇ + g − τ = 0,  I_b ω̇ + ω × I_b ω + D ω = 0;
//! * stick dynamics (eq. 29): M q̈ + C q̇ + μ_v q̇ + g − τ − J_cᵀ λ = 0,
//!   I_b ω̇ + ω × I_b ω + D ω + r_c × λ = 0, and the stick constraint Δv = 0 (eq. 14/27), or
//!   its time derivative d(Δv)/dt = 0 ([`StickLevel::Acceleration`], the index-1 form used with
//!   Legendre–Gauss, see [`node_function_with`]);
//! * validity: h (eq. 4), λ_n = λ·n ≥ 0 (eq. 12) and the friction cone (eq. 18–19) as
//!   σ_δ = μ_s λ_n − (sqrt(‖λ_∥‖² + δ²) − δ) ≥ 0 (the smooth |·| of eq. 59, δ = [`CONE_DELTA`]);
//! * cost integrands: QC (eq. 64–65) and COT (eq. 61–63), effort and time;
//! * the sticking impact law (eq. 40a–c) as the Free→Stick reset with the impulse ι as
//!   decision variables, ι_n ≥ 0, and the optional impulse cone (eq. 66).
//!
//! The contact geometry uses the smooth saturation (eq. 58–59) with ε as a fixed input.

use bf_codegen::graph::{Graph, Id, V3};
use bf_codegen::robot::Model;
use bf_codegen::{Scene, interp::Tape};

use crate::ocp::{NodeFunction, OcpError, PointFunction, VarRef};

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

/// Physical constants of the scene used outside the generated graph.
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
    pub fn new(scene: &Scene) -> Result<Physics, OcpError> {
        let ball = scene
            .ball
            .as_ref()
            .ok_or_else(|| OcpError::Model("the scene has no [ball]".into()))?;
        if scene.contact.is_none() {
            return Err(OcpError::Model("the scene has no [contact]".into()));
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

struct Built {
    model: Model,
    fixed: Vec<(u32, f64)>,
    base: u32,
}

fn build_model(scene: &Scene, eps: f64) -> Result<Built, OcpError> {
    let model = Model::new(scene).map_err(|e| OcpError::Model(e.to_string()))?;
    let lay = model.layout;
    let mut fixed = vec![(lay.eps(), eps)];
    for (i, p) in model.params.iter().enumerate() {
        fixed.push((lay.param(i), p.1));
    }
    let base = lay.n_vars() as u32;
    Ok(Built { model, fixed, base })
}

fn m3_const(g: &mut Graph, a: [[f64; 3]; 3]) -> [[Id; 3]; 3] {
    let mut r = [[Id(0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = g.constant(a[i][j]);
        }
    }
    r
}

fn vars(g: &mut Graph, idx: &[u32]) -> Vec<Id> {
    idx.iter().map(|&i| g.var(i)).collect()
}

fn v3(v: &[Id]) -> V3 {
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

/// The squared-norm cost pieces.
fn sq_norm(g: &mut Graph, v: &[Id]) -> Id {
    let t: Vec<Id> = v.iter().map(|&x| g.square(x)).collect();
    g.sum(&t)
}

fn cost_integrands(g: &mut Graph, cost: CostKind, tau: &[Id], w: V3) -> Vec<Id> {
    let one = g.one();
    let tt = sq_norm(g, tau);
    match cost {
        CostKind::Qc { w: wq, omega_ref } => {
            let r = g.v3_const(omega_ref);
            let d = g.v3_sub(w, r);
            let dd = sq_norm(g, &d);
            let wc = g.constant(wq);
            let a = g.mul(wc, tt);
            vec![g.add(a, dd), one]
        }
        CostKind::Cot { w: wc, omega_hat } => {
            let h = g.v3_const(omega_hat);
            let along = g.v3_dot(w, h);
            let par = g.v3_scale(along, h);
            let perp = g.v3_sub(w, par);
            let pp = sq_norm(g, &perp);
            let wcc = g.constant(wc);
            let pen = g.mul(wcc, pp);
            vec![tt, g.sub(along, pen)]
        }
        CostKind::TimeEffort { w: we } => {
            let wc = g.constant(we);
            let a = g.mul(wc, tt);
            vec![g.add(one, a), one]
        }
        CostKind::Track { w: we, omega_ref } => {
            let r = g.v3_const(omega_ref);
            let d = g.v3_sub(w, r);
            let dd = sq_norm(g, &d);
            let wc = g.constant(we);
            let a = g.mul(wc, tt);
            vec![g.add(a, dd), one]
        }
        CostKind::Reorient { w: we, axis } => {
            let ax = g.v3_const(axis);
            let along = g.v3_dot(w, ax);
            let wc = g.constant(we);
            let a = g.mul(wc, tt);
            vec![g.add(one, a), along]
        }
        CostKind::Spin { w: we, axis } => {
            let ax = g.v3_const(axis);
            let along = g.v3_dot(w, ax);
            let wc = g.constant(we);
            let a = g.mul(wc, tt);
            vec![g.sub(a, along), one]
        }
    }
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
    /// see [`node_function_with`].
    Acceleration,
}

/// Node function of one phase; returns it with the variable indices. Path rows: finger
/// dynamics (nq), ball (3), then [stick: Δv (3), λ_n, cone], then [h], then [ḣ].
pub fn node_function(
    scene: &Scene,
    ph: &Physics,
    opt: &NodeOptions,
) -> Result<(NodeFunction, NodeVars), OcpError> {
    node_function_with(scene, ph, opt, StickLevel::Velocity)
}

/// [`node_function`] with the stick constraint at the given level (only matters for
/// [`Mode::Stick`]; the path row layout is the same, with d(Δv)/dt in place of Δv).
///
/// Why LG needs [`StickLevel::Acceleration`]: with Δv = 0 at the Gauss nodes the stick phase
/// is collocated as an index-2 DAE, and Gauss collocation is not stiffly accurate
/// (|R(∞)| = 1): the algebraic λ and the state polynomial keep an undamped alternating mode
/// between the nodes, whose conditioning worsens with N (LG-30 stalls with δ_w ≈ 1e-3 every
/// iteration, Δv ≈ 5e-4 between nodes). At the acceleration level the phase is index 1, λ is
/// fixed node by node (eq. 31–32), and Δv(t) = Δv(t_0) + ∫ dΔv/dt stays 0 up to the Gauss
/// quadrature error, also at the quadrature end point.
pub fn node_function_with(
    scene: &Scene,
    ph: &Physics,
    opt: &NodeOptions,
    level: StickLevel,
) -> Result<(NodeFunction, NodeVars), OcpError> {
    let Built {
        mut model,
        fixed,
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
    let mass = model.mass_matrix();
    let bias = model.cqd_g_rnea();
    let ce = model
        .contact(true)
        .map_err(|e| OcpError::Model(e.to_string()))?;
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
                path.extend(bf_codegen::diff::time_derivative(
                    g,
                    &ce.delta_v,
                    &xv,
                    &rates,
                ));
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
    let costs = cost_integrands(g, opt.cost, &tau, w);
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

fn state_refs(phase: usize, nx: usize, fin: bool) -> Vec<VarRef> {
    (0..nx)
        .map(|i| {
            if fin {
                VarRef::Final { phase, i }
            } else {
                VarRef::Initial { phase, i }
            }
        })
        .collect()
}

/// Contact quantity of a phase end-point state, bounded: `h` or `ḣ` or the stick constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EndQuantity {
    /// h(q) in bounds.
    H(f64, f64),
    /// ḣ in bounds.
    HDot(f64, f64),
    /// Δv = 0 (eq. 14).
    DeltaV,
}

/// A point function on the state at the start (`fin = false`) or end of `phase`.
pub fn end_point(
    scene: &Scene,
    eps: f64,
    phase: usize,
    fin: bool,
    what: EndQuantity,
    name: &str,
) -> Result<PointFunction, OcpError> {
    let Built {
        mut model, fixed, ..
    } = build_model(scene, eps)?;
    let nq = model.nq();
    let nx = 2 * nq + 3;
    let ce = model
        .contact(true)
        .map_err(|e| OcpError::Model(e.to_string()))?;
    let (outputs, bounds) = match what {
        EndQuantity::H(lo, hi) => (vec![ce.h], vec![(lo, hi)]),
        EndQuantity::HDot(lo, hi) => (vec![ce.h_dot], vec![(lo, hi)]),
        EndQuantity::DeltaV => (ce.delta_v.to_vec(), vec![(0.0, 0.0); 3]),
    };
    let lay = model.layout;
    let gv: Vec<u32> = (0..nq)
        .map(|i| lay.q(i))
        .chain((0..nq).map(|i| lay.qd(i)))
        .chain((0..3).map(|i| lay.omega(i)))
        .collect();
    let refs = state_refs(phase, nx, fin);
    // Only the variables the outputs depend on (q for h; all for ḣ and Δv).
    let needed: Vec<(u32, VarRef)> = match what {
        EndQuantity::H(..) => gv[..nq]
            .iter()
            .copied()
            .zip(refs[..nq].iter().copied())
            .collect(),
        _ => gv.iter().copied().zip(refs).collect(),
    };
    Ok(PointFunction {
        name: name.into(),
        graph: std::mem::take(&mut model.g),
        vars: needed,
        fixed,
        outputs,
        bounds,
    })
}

/// Continuity x⁽ᵇ⁾(start) − x⁽ᵃ⁾(end) = 0 (or periodicity x⁽ᵃ⁾(end) = x⁽ᵇ⁾(start)).
pub fn continuity(nx: usize, from_phase: usize, to_phase: usize, name: &str) -> PointFunction {
    let mut g = Graph::new();
    let mut vars = Vec::new();
    let mut outputs = Vec::new();
    for i in 0..nx {
        let a = g.var(2 * i as u32);
        let b = g.var(2 * i as u32 + 1);
        outputs.push(g.sub(b, a));
        vars.push((
            2 * i as u32,
            VarRef::Final {
                phase: from_phase,
                i,
            },
        ));
        vars.push((2 * i as u32 + 1, VarRef::Initial { phase: to_phase, i }));
    }
    PointFunction {
        name: name.into(),
        graph: g,
        vars,
        fixed: vec![],
        outputs,
        bounds: vec![(0.0, 0.0); nx],
    }
}

/// Sticking impact (eq. 40) between the end of `free_phase` and the start of `free_phase + 1`,
/// with the impulse ι = params `iota0..iota0+3`: q⁺ = q⁻, M (q̇⁺ − q̇⁻) − J_cᵀ ι = 0,
/// I_b (ω⁺ − ω⁻) + r_c × ι = 0, ω⁺ × r_c − J_c q̇⁺ = 0, ι_n ≥ 0 and optionally the impulse
/// cone (eq. 66, squared form).
///
/// `delta_v_plus` adds ω⁺ × r_c − J_c q̇⁺ = 0 (eq. 40c); leave it out when the stick phase's
/// first state point is a collocation node (Radau), where the node's Δv = 0 already imposes
/// it (a duplicate row would make the constraint Jacobian rank deficient).
pub fn impact(
    scene: &Scene,
    ph: &Physics,
    eps: f64,
    free_phase: usize,
    iota0: usize,
    impulse_cone: bool,
    delta_v_plus: bool,
) -> Result<PointFunction, OcpError> {
    let Built {
        mut model,
        fixed,
        base,
    } = build_model(scene, eps)?;
    let nq = ph.nq;
    let lay = model.layout;
    let mass = model.mass_matrix();
    let ce = model
        .contact(true)
        .map_err(|e| OcpError::Model(e.to_string()))?;
    let g = &mut model.g;
    let mut vars_list = Vec::new();
    let qm: Vec<u32> = (0..nq).map(|i| lay.q(i)).collect();
    let qdm: Vec<u32> = (0..nq).map(|i| lay.qd(i)).collect();
    let wm: Vec<u32> = (0..3).map(|i| lay.omega(i)).collect();
    let qp: Vec<u32> = (0..nq as u32).map(|i| base + i).collect();
    let qdp: Vec<u32> = (0..nq as u32).map(|i| base + nq as u32 + i).collect();
    let wp: Vec<u32> = (0..3u32).map(|i| base + 2 * nq as u32 + i).collect();
    let io: Vec<u32> = (0..3u32).map(|i| base + 2 * nq as u32 + 3 + i).collect();
    let nx = 2 * nq + 3;
    let pre: Vec<u32> = qm.iter().chain(&qdm).chain(&wm).copied().collect();
    let post: Vec<u32> = qp.iter().chain(&qdp).chain(&wp).copied().collect();
    for i in 0..nx {
        vars_list.push((
            pre[i],
            VarRef::Final {
                phase: free_phase,
                i,
            },
        ));
        vars_list.push((
            post[i],
            VarRef::Initial {
                phase: free_phase + 1,
                i,
            },
        ));
    }
    for (i, &v) in io.iter().enumerate() {
        vars_list.push((v, VarRef::Param(iota0 + i)));
    }
    let qmi = vars(g, &qm);
    let qpi = vars(g, &qp);
    let qdmi = vars(g, &qdm);
    let qdpi = vars(g, &qdp);
    let wmi = v3(&vars(g, &wm));
    let wpi = v3(&vars(g, &wp));
    let iota = v3(&vars(g, &io));
    let mut out = Vec::new();
    for i in 0..nq {
        out.push(g.sub(qpi[i], qmi[i]));
    }
    let dqd: Vec<Id> = (0..nq).map(|i| g.sub(qdpi[i], qdmi[i])).collect();
    for i in 0..nq {
        let m = g.dot(&mass[i], &dqd);
        let col = [ce.j_c[0][i], ce.j_c[1][i], ce.j_c[2][i]];
        let ji = g.v3_dot(col, iota);
        out.push(g.sub(m, ji));
    }
    let ib = m3_const(g, ph.ib);
    let dw = g.v3_sub(wpi, wmi);
    let ibdw = g.m3_mul_v(&ib, dw);
    let rci = g.v3_cross(ce.r_c, iota);
    out.extend(g.v3_add(ibdw, rci));
    if delta_v_plus {
        let wr = g.v3_cross(wpi, ce.r_c);
        for r in 0..3 {
            let jq = g.dot(&ce.j_c[r], &qdpi);
            out.push(g.sub(wr[r], jq));
        }
    }
    let mut bounds = vec![(0.0, 0.0); out.len()];
    let iota_n = g.v3_dot(iota, ce.n);
    out.push(iota_n);
    bounds.push((0.0, f64::INFINITY));
    if impulse_cone {
        let n2 = g.square(iota_n);
        let k = g.constant(1.0 + ph.mu_s * ph.mu_s);
        let a = g.mul(k, n2);
        let ii = g.v3_dot(iota, iota);
        out.push(g.sub(a, ii));
        bounds.push((0.0, f64::INFINITY));
    }
    Ok(PointFunction {
        name: "impact (eq. 40)".into(),
        graph: std::mem::take(&mut model.g),
        vars: vars_list,
        fixed,
        outputs: out,
        bounds,
    })
}

/// Evaluator of contact diagnostics (α, sat α, h, ḣ, n, r_c, Δv) at a state.
#[derive(Debug, Clone)]
pub struct Diagnostics {
    tape: Tape,
    n_vars: usize,
    nq: usize,
    fixed: Vec<(u32, f64)>,
}

/// Values returned by [`Diagnostics::eval`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactValues {
    /// α (eq. 2).
    pub alpha: f64,
    /// sat(α) (smooth).
    pub sat_alpha: f64,
    /// h (eq. 4).
    pub h: f64,
    /// ḣ.
    pub h_dot: f64,
    /// n (eq. 11).
    pub n: [f64; 3],
    /// Δv (eq. 13).
    pub delta_v: [f64; 3],
}

impl Diagnostics {
    /// Compiles the contact quantities of `scene` with smooth-saturation ε.
    pub fn new(scene: &Scene, eps: f64) -> Result<Self, OcpError> {
        let Built {
            mut model,
            fixed,
            base,
        } = build_model(scene, eps)?;
        let ce = model
            .contact(true)
            .map_err(|e| OcpError::Model(e.to_string()))?;
        let mut outs = vec![ce.alpha, ce.sat_alpha, ce.h, ce.h_dot];
        outs.extend(ce.n);
        outs.extend(ce.delta_v);
        Ok(Diagnostics {
            tape: Tape::new(&model.g, &outs),
            n_vars: base as usize,
            nq: model.nq(),
            fixed,
        })
    }

    /// Evaluates at x = (q, q̇, ω).
    pub fn eval(&self, x: &[f64]) -> ContactValues {
        let mut v = vec![0.0; self.n_vars];
        let nx = 2 * self.nq + 3;
        v[..nx].copy_from_slice(&x[..nx]);
        for &(i, val) in &self.fixed {
            v[i as usize] = val;
        }
        let o = self.tape.eval(&v);
        ContactValues {
            alpha: o[0],
            sat_alpha: o[1],
            h: o[2],
            h_dot: o[3],
            n: [o[4], o[5], o[6]],
            delta_v: [o[7], o[8], o[9]],
        }
    }
}
