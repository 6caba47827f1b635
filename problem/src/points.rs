//! Point functions of the ball-and-finger problems on the bf-codegen expression graph: the
//! sticking impact law (eq. 40a–c) as the Free→Stick reset with the impulse ι as decision
//! variables, ι_n ≥ 0 and the optional impulse cone (eq. 66), or Newton's law (eq. 39: ω⁺ = ω⁻,
//! q̇⁺ within [`NEWTON_VELOCITY_LIMIT`] of the plant's, ḣ⁻ ≤ −[`NEWTON_APPROACH_SPEED`] r, J_c
//! conditioned at least [`NEWTON_MIN_CONDITION`]) in
//! its place; contact quantities (h eq. 4, ḣ,
//! Δv eq. 13–14) at phase end points; continuity and periodicity; and [`Diagnostics`], an
//! evaluator of the contact quantities at a state. The contact geometry uses the smooth
//! saturation (eq. 58–59) with ε as a fixed input.

use bf_codegen::Scene;
use bf_codegen::graph::{Graph, Id};
use bf_codegen::interp::Tape;
use bf_codegen::robot::SymbolicRobot;
use bf_optim::ocp::{PointFunction, VarRef};
use bf_scene::state_len;

use crate::ProblemError;

use crate::node::{Physics, m3_const, v3, vars};

/// Reads the physical constants of `scene` (needs `[ball]`, `[contact]`).
pub fn physics(scene: &Scene) -> Result<Physics, ProblemError> {
    crate::node::physics(scene).map_err(ProblemError::model(&scene.name))
}

struct Built {
    model: SymbolicRobot,
    fixed: Vec<(u32, f64)>,
    base: u32,
}

fn build_model(scene: &Scene, eps: f64) -> Result<Built, ProblemError> {
    let b = crate::node::build_model(scene, eps).map_err(ProblemError::model(&scene.name))?;
    Ok(Built {
        model: b.model,
        fixed: b.fixed,
        base: b.base,
    })
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
) -> Result<PointFunction, ProblemError> {
    let Built {
        mut model, fixed, ..
    } = build_model(scene, eps)?;
    let nq = model.nq();
    let nx = state_len(nq);
    let ce = model
        .contact(true)
        .map_err(ProblemError::model(&scene.name))?;
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
        row_names: Vec::new(),
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
        row_names: Vec::new(),
    }
}

/// Largest distance (rad/s, Euclidean over the joints) between a Newton plan's post-impact
/// joint velocity q̇⁺ and the one Newton's law gives the plant from the same pre-impact state:
/// small enough that the plant's slip after the impact (at most ‖J_c‖ times this) ends within
/// a millisecond, large enough to leave the inequality an interior.
pub const NEWTON_VELOCITY_LIMIT: f64 = 1e-3;

/// Least normal speed, in ball radii per second (0.1 m/s on the paper's ball of 1 m), at which
/// a Newton plan's finger reaches the ball, ḣ⁻ ≤ −v r: the
/// Newton impact costs nothing in ω, so the plans otherwise land with ḣ⁻ = 0, and a plant a
/// gap error δh off the plan then touches down δh / |ḣ| late, unboundedly (`track` lost the
/// ball of such a plan: its finger hovered 5 mm above it). The sticking plans reach the ball at
/// 0.3–7 m/s. In radii, so that a finger drawn at another scale gets the same plan.
pub const NEWTON_APPROACH_SPEED: f64 = 0.1;

/// Least conditioning of J_c at a Newton plan's impact, |det J_c| ≥ κ (‖J_c‖_F² / 3)^{3/2}: the
/// ratio is σ₁σ₂σ₃ over the cube of the singular values' quadratic mean, 1 for a multiple of an
/// orthogonal matrix and 0 at a singular one. Newton's law q̇⁺ = J_c⁻¹ T_n J_c q̇⁻ amplifies a
/// state error by 1/σ_min; near a singular J_c the velocity bound above holds with any q̇⁺
/// (both sides scale with det), so the plans went there: periodic-qc optima with κ ≈ 2e-5 at
/// q₂ = π and the impulse on its 1000 N s bound, which no plant executes. Executed plans have
/// κ ≈ 0.44–0.58 (docs/decisions/0033-newton-impact-plan.md).
pub const NEWTON_MIN_CONDITION: f64 = 0.1;

/// Sticking impact (eq. 40) between the end of `free_phase` and the start of `free_phase + 1`,
/// with the impulse ι = params `iota0..iota0+3`: q⁺ = q⁻, M (q̇⁺ − q̇⁻) − J_cᵀ ι = 0,
/// I_b (ω⁺ − ω⁻) + r_c × ι = 0, ω⁺ × r_c − J_c q̇⁺ = 0, ι_n ≥ 0 and optionally the impulse
/// cone (eq. 66, squared form).
///
/// `newton` plans the impact with Newton's law instead (eq. 39, restitution 0, the law of the
/// paper's Sect. 6.2 simulations): ω⁺ = ω⁻ replaces the ball's impulse balance, ι
/// is the impulse the finger receives, and the post-impact joint velocity must be within
/// [`NEWTON_VELOCITY_LIMIT`] of the plant's (for 3 joints q̇_N = J_c⁻¹ T_n J_c q̇⁻, T_n = 1 − n nᵀ), so that
/// the stick phase that follows starts sticking under Newton's law as well (paper Sect. 7),
/// and the finger must arrive at [`NEWTON_APPROACH_SPEED`] or faster, at a J_c conditioned at
/// least [`NEWTON_MIN_CONDITION`]. Without J_c⁻¹ (which the graph cannot form where J_c is
/// singular) q̇⁺ − q̇_N = e / det(J_c) with e = det(J_c) q̇⁺ − adj(J_c) T_n J_c q̇⁻
/// (adj(J_c) J_c = det(J_c) 1). The bound is a box inside the ball of radius v, |q̇⁺_i − q̇_N,i|
/// ≤ v / √3 for each joint, as six rows ±e_i det − (v / √3) det² ≤ 0 (the box's condition
/// |e_i| ≤ (v / √3) |det| multiplied by |det|, which holds for either sign of det).
///
/// Why a box of linear rows: the ball ‖e‖² ≤ v² det² as one row has a double root at Newton's
/// law (its gradient in q̇⁺ vanishes at e = 0), so Newton steps approach it by halves and the
/// barrier around its thin interior is stiff: cold starts took 3–5 times the iterations of the
/// sticking law's (docs/decisions/0065-the-newton-bound-as-a-box.md). The box rows are linear
/// in e, with gradient det² in q̇⁺_i. Their margin at Newton's law, (v / √3) det² (about 5e-6
/// on the paper's finger), is about 500 times the solver's bound relaxation (1e-8): a margin
/// of the relaxation's size let solves creep to `Acceptable` with huge multipliers
/// (docs/decisions/0063-the-newton-row-scaled.md).
///
/// Why in ball radii: every length in these rows is divided by the ball's radius r (J_c / r,
/// v_c / r, the approach speed in r per second; 1 on the paper's ball, where the rows are
/// those above). The box and conditioning rows are of degree 6 in J_c, so in metres a finger
/// a twentieth of the paper's size had rows and margins s⁶ ≈ 1.6e-8 times as large, below the
/// solver's bound relaxation: its plan ended `Acceptable`, 13 % off the dynamically similar
/// optimum, and lost the ball (BENCHMARKS.md, "The plan for the plant in ball radii").
///
/// Why in joint space: the stick node's Δv⁺ = 0 makes J_c (q̇⁺ − q̇_N) = T_n Δv⁻, the
/// tangential relative velocity before the impact. A bound on that alone (how this law was
/// first planned) let the plans put the contact point on a singular J_c (joint 1's axis passes
/// through the ball's centre), where a slip of 1 mm/s moves q̇⁺ by rad/s: the optimum used an
/// impulse of 75–1000 N s that no plant applies (docs/decisions/0033-newton-impact-plan.md).
///
/// A redundant finger (N > 3 joints; `newton` needs at least 3): J_c is 3 × N, and the plant's
/// law takes, of the velocities with J_c q̇ = T_n J_c q̇⁻, the one closest to q̇⁻ in the
/// kinetic-energy norm: q̇_N = q̇⁻ + M⁻¹ J_cᵀ ι_N with (J_c M⁻¹ J_cᵀ) ι_N = −n (n · v_c⁻)
/// (bf-model's `ImpactLaw::Newton`). The graph forms neither M⁻¹ nor an adjugate of
/// J_c here: q̇_N and ι_N are N + 3 more parameters after ι (`iota0 + 3 ..`, in that order,
/// [`newton_lifted_param_names`]), held by M (q̇_N − q̇⁻) − J_cᵀ ι_N = 0 and
/// J_c q̇_N = T_n J_c q̇⁻ (regular wherever J_c has rank 3). The plan's q̇⁺ then lies in the box
/// |q̇⁺_i − q̇_N,i| ≤ v / √N, and det(J_c J_cᵀ) ≥ κ² (‖J_c‖_F² / 3)³, the 3-joint row on the
/// Gram determinant (det(J_c)² for N = 3). The 3-joint rows stay as above, so its plans are
/// unchanged.
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
    newton: bool,
    delta_v_plus: bool,
) -> Result<PointFunction, ProblemError> {
    let Built {
        mut model,
        fixed,
        base,
    } = build_model(scene, eps)?;
    let nq = ph.nq;
    if newton && nq < 3 {
        return Err(ProblemError::InvalidSetting {
            name: "the joint count of a Newton impact plan (J_c of rank 3)",
            value: nq as f64,
            expected: "at least 3",
        });
    }
    let lay = model.layout;
    let mass = model.mass_matrix();
    let ce = model
        .contact(true)
        .map_err(ProblemError::model(&scene.name))?;
    let g = &mut model.g;
    let mut vars_list = Vec::new();
    let qm: Vec<u32> = (0..nq).map(|i| lay.q(i)).collect();
    let qdm: Vec<u32> = (0..nq).map(|i| lay.qd(i)).collect();
    let wm: Vec<u32> = (0..3).map(|i| lay.omega(i)).collect();
    let qp: Vec<u32> = (0..nq as u32).map(|i| base + i).collect();
    let qdp: Vec<u32> = (0..nq as u32).map(|i| base + nq as u32 + i).collect();
    let wp: Vec<u32> = (0..3u32).map(|i| base + 2 * nq as u32 + i).collect();
    let io: Vec<u32> = (0..3u32).map(|i| base + 2 * nq as u32 + 3 + i).collect();
    let nx = state_len(nq);
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
    // A redundant finger's Newton plan carries the plant's post-impact velocity and impulse
    // as parameters after ι (see the function's docs).
    let lifted = newton && nq > 3;
    let qdn: Vec<u32> = (0..nq as u32)
        .map(|i| base + 2 * nq as u32 + 6 + i)
        .collect();
    let ion: Vec<u32> = (0..3u32).map(|i| base + 3 * nq as u32 + 6 + i).collect();
    if lifted {
        for (i, &v) in qdn.iter().chain(&ion).enumerate() {
            vars_list.push((v, VarRef::Param(iota0 + 3 + i)));
        }
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
    let dw = g.v3_sub(wpi, wmi);
    if newton {
        out.extend(dw);
    } else {
        let ib = m3_const(g, ph.ib);
        let ibdw = g.m3_mul_v(&ib, dw);
        let rci = g.v3_cross(ce.r_c, iota);
        out.extend(g.v3_add(ibdw, rci));
    }
    if delta_v_plus {
        let wr = g.v3_cross(wpi, ce.r_c);
        for r in 0..3 {
            let jq = g.dot(&ce.j_c[r], &qdpi);
            out.push(g.sub(wr[r], jq));
        }
    }
    let mut rows = Rows::equalities(out);
    let iota_n = g.v3_dot(iota, ce.n);
    rows.push(iota_n, (0.0, f64::INFINITY), "impulse pushes: iota.n >= 0");
    if impulse_cone {
        let n2 = g.square(iota_n);
        let k = g.constant(1.0 + ph.mu_s * ph.mu_s);
        let a = g.mul(k, n2);
        let ii = g.v3_dot(iota, iota);
        rows.push(
            g.sub(a, ii),
            (0.0, f64::INFINITY),
            "impulse cone (eq. 66): (1 + mu_s^2) (iota.n)^2 - |iota|^2 >= 0",
        );
    }
    if lifted {
        newton_lifted_rows(
            g, &ce, ph.radius, &mass, &qdmi, &qdpi, &qdn, &ion, &mut rows,
        );
    } else if newton {
        // J_c and v_c in ball radii (see the function's docs): rows a_r of J_c / r,
        // adj = [a₁ × a₂ | a₂ × a₀ | a₀ × a₁], det = a₀ · (a₁ × a₂).
        let per_radius = g.constant(1.0 / ph.radius);
        let row = |g: &mut Graph, r: usize| {
            let a = [ce.j_c[r][0], ce.j_c[r][1], ce.j_c[r][2]];
            g.v3_scale(per_radius, a)
        };
        let (a0, a1, a2) = (row(g, 0), row(g, 1), row(g, 2));
        let adj = [g.v3_cross(a1, a2), g.v3_cross(a2, a0), g.v3_cross(a0, a1)];
        let det = g.v3_dot(a0, adj[0]);
        // T_n v_c⁻ / r, the contact point's velocity without its normal part (eq. 39).
        let vc = ce.v_c;
        let vn = g.v3_dot(vc, ce.n);
        let vnn = g.v3_scale(vn, ce.n);
        let tv = g.v3_sub(vc, vnn);
        let t = g.v3_scale(per_radius, tv);
        // |e_i| ≤ (v / √3) |det| for each joint, multiplied by |det| so that no sign of det
        // is assumed (see the function's docs): ±e_i det − (v / √3) det² ≤ 0.
        let d2 = g.square(det);
        let half_width = g.constant(NEWTON_VELOCITY_LIMIT / 3f64.sqrt());
        let wd2 = g.mul(half_width, d2);
        for i in 0..3 {
            let dq = g.mul(det, qdpi[i]);
            let terms: Vec<Id> = (0..3).map(|c| g.mul(adj[c][i], t[c])).collect();
            let at = g.sum(&terms);
            let e = g.sub(dq, at);
            let ed = g.mul(e, det);
            // The row is det² (±(q̇⁺_i − q̇_N,i) − v/√3): 0 on the bound whatever the posture,
            // so its name carries the formula (as the conditioning row's does).
            let name = format!(
                "{}: det(J_c)^2 (+-(qd+_{j} - qdN_{j}) - v/sqrt(3)) <= 0",
                box_row_name(i),
                j = i + 1
            );
            rows.push(g.sub(ed, wd2), (f64::NEG_INFINITY, 0.0), &name);
            let ned = g.neg(ed);
            rows.push(g.sub(ned, wd2), (f64::NEG_INFINITY, 0.0), &name);
        }
        // det² ≥ κ² (‖J_c‖_F² / 3)³ (NEWTON_MIN_CONDITION), squared so that its sign is free.
        let fro_terms: Vec<Id> = [a0, a1, a2].iter().map(|&r| g.v3_dot(r, r)).collect();
        let fro = g.sum(&fro_terms);
        let speed = NEWTON_APPROACH_SPEED * ph.radius;
        conditioning_and_approach_rows(g, d2, fro, ce.h_dot, speed, &mut rows);
    }
    let Rows { out, bounds, names } = rows;
    Ok(PointFunction {
        name: if newton {
            "impact (eq. 39)"
        } else {
            "impact (eq. 40)"
        }
        .into(),
        graph: std::mem::take(&mut model.g),
        vars: vars_list,
        fixed,
        outputs: out,
        bounds,
        row_names: names,
    })
}

/// The rows of a point function as they are built: expressions, bounds and names in step
/// (`PointFunction::row_names`: the inequality rows are named, so that a bound one sits on is
/// reported by what it is; the equality rows need no name).
struct Rows {
    out: Vec<Id>,
    bounds: Vec<(f64, f64)>,
    names: Vec<String>,
}

impl Rows {
    /// The equality rows `out` = 0, unnamed.
    fn equalities(out: Vec<Id>) -> Rows {
        Rows {
            bounds: vec![(0.0, 0.0); out.len()],
            names: vec![String::new(); out.len()],
            out,
        }
    }

    /// Row `e` within `bounds`, named `name` (empty for none).
    fn push(&mut self, e: Id, bounds: (f64, f64), name: &str) {
        self.out.push(e);
        self.bounds.push(bounds);
        self.names.push(name.to_string());
    }
}

/// The name of joint `i`'s rows (0-based) of a Newton plan's box about the plant's velocity.
fn box_row_name(i: usize) -> String {
    format!(
        "q̇⁺ of joint {} within its box about Newton's velocity",
        i + 1
    )
}

/// The Newton rows of a redundant finger (N > 3 joints, see [`impact`]): the plant's
/// post-impact velocity q̇_N and impulse ι_N (variables `qdn`, `ion`) solve
/// M (q̇_N − q̇⁻) − J_cᵀ ι_N = 0 and J_c q̇_N = T_n J_c q̇⁻, the plan's q̇⁺ lies in the box
/// |q̇⁺_i − q̇_N,i| ≤ v / √N, J_c J_cᵀ is conditioned at least κ, and ḣ⁻ ≤ −v_approach.
#[allow(clippy::too_many_arguments)]
fn newton_lifted_rows(
    g: &mut Graph,
    ce: &bf_codegen::robot::ContactExprs,
    radius: f64,
    mass: &[Vec<Id>],
    qdm: &[Id],
    qdp: &[Id],
    qdn: &[u32],
    ion: &[u32],
    rows: &mut Rows,
) {
    let nq = qdm.len();
    let qdn = vars(g, qdn);
    let iota_n = v3(&vars(g, ion));
    // M (q̇_N − q̇⁻) − J_cᵀ ι_N = 0: the plant's impulse balance (eq. 40a).
    let dqd: Vec<Id> = (0..nq).map(|i| g.sub(qdn[i], qdm[i])).collect();
    for (i, m_row) in mass.iter().enumerate() {
        let m = g.dot(m_row, &dqd);
        let col = [ce.j_c[0][i], ce.j_c[1][i], ce.j_c[2][i]];
        let ji = g.v3_dot(col, iota_n);
        rows.push(g.sub(m, ji), (0.0, 0.0), "");
    }
    // (J_c q̇_N − T_n v_c⁻) / r = 0 (eq. 39): with the balance above, the q̇_N closest to q̇⁻ in
    // the kinetic-energy norm, which is what the plant's law computes (bf_model::impact). J_c
    // is taken in ball radii here and below (see [`impact`]).
    let per_radius = g.constant(1.0 / radius);
    let j_c: Vec<Vec<Id>> = ce
        .j_c
        .iter()
        .map(|row| row.iter().map(|&x| g.mul(per_radius, x)).collect())
        .collect();
    let vc = ce.v_c;
    let vn = g.v3_dot(vc, ce.n);
    let vnn = g.v3_scale(vn, ce.n);
    let tv = g.v3_sub(vc, vnn);
    let t = g.v3_scale(per_radius, tv);
    for (r, &tr) in t.iter().enumerate() {
        let jq = g.dot(&j_c[r], &qdn);
        rows.push(g.sub(jq, tr), (0.0, 0.0), "");
    }
    // |q̇⁺_i − q̇_N,i| ≤ v / √N: the box inside the ball of radius v, as for 3 joints.
    let half_width = NEWTON_VELOCITY_LIMIT / (nq as f64).sqrt();
    for i in 0..nq {
        let d = g.sub(qdp[i], qdn[i]);
        rows.push(d, (-half_width, half_width), &box_row_name(i));
    }
    // det(J_c J_cᵀ) ≥ κ² (‖J_c‖_F² / 3)³: the Gram determinant is det(J_c)² for 3 joints, so
    // this is the 3-joint row on the product of J_c's three squared singular values.
    let gram: Vec<[Id; 3]> = (0..3)
        .map(|r| [0, 1, 2].map(|c| g.dot(&j_c[r], &j_c[c])))
        .collect();
    // det G = G₀ · (G₁ × G₂) over its rows, as the 3-joint det(J_c) is formed above.
    let cross = g.v3_cross(gram[1], gram[2]);
    let det = g.v3_dot(gram[0], cross);
    let fro = g.sum(&[gram[0][0], gram[1][1], gram[2][2]]);
    let speed = NEWTON_APPROACH_SPEED * radius;
    conditioning_and_approach_rows(g, det, fro, ce.h_dot, speed, rows);
}

/// The name of a Newton plan's conditioning row, with its formula and κ: on its bound the
/// row's value is 0 whatever the posture, so `active bounds` needs the formula to say which
/// bound a plan sits on.
fn conditioning_row_name() -> String {
    format!(
        "J_c conditioning: det(J_c J_c^T) - k^2 (|J_c|_F^2 / 3)^3 >= 0, k = {NEWTON_MIN_CONDITION}"
    )
}

/// The last two rows of every Newton plan: `det2` ≥ κ² (`fro` / 3)³
/// ([`NEWTON_MIN_CONDITION`]; `det2` = det(J_c J_cᵀ), `fro` = ‖J_c‖_F², J_c in ball radii) and
/// ḣ⁻ ≤ −`speed` ([`NEWTON_APPROACH_SPEED`] ball radii per second).
fn conditioning_and_approach_rows(
    g: &mut Graph,
    det2: Id,
    fro: Id,
    h_dot: Id,
    speed: f64,
    rows: &mut Rows,
) {
    let third = g.constant(1.0 / 3.0);
    let mean = g.mul(fro, third);
    let mean2 = g.square(mean);
    let cube = g.mul(mean2, mean);
    let k2 = g.constant(NEWTON_MIN_CONDITION * NEWTON_MIN_CONDITION);
    let least = g.mul(k2, cube);
    rows.push(
        g.sub(det2, least),
        (0.0, f64::INFINITY),
        &conditioning_row_name(),
    );
    rows.push(
        h_dot,
        (f64::NEG_INFINITY, -speed),
        "approach speed: hdot(tf) <= -v",
    );
}

/// The names of the parameters a Newton impact plan adds after the impulse ι for a finger of
/// `nq` joints, in [`impact`]'s order: q̇_N (`qd_newton1..N`) and ι_N (`iota_newton1..3`) of
/// the plant's law for a redundant finger (N > 3), none for 3 joints or fewer.
pub fn newton_lifted_param_names(nq: usize) -> Vec<String> {
    if nq <= 3 {
        return Vec::new();
    }
    let qd = (1..=nq).map(|i| format!("qd_newton{i}"));
    qd.chain((1..=3).map(|i| format!("iota_newton{i}")))
        .collect()
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
    pub fn new(scene: &Scene, eps: f64) -> Result<Self, ProblemError> {
        let Built {
            mut model,
            fixed,
            base,
        } = build_model(scene, eps)?;
        let ce = model
            .contact(true)
            .map_err(ProblemError::model(&scene.name))?;
        let mut outs = vec![ce.alpha, ce.sat_alpha, ce.h, ce.h_dot];
        outs.extend(ce.n);
        outs.extend(ce.delta_v);
        model
            .check_size("the contact quantities", bf_codegen::robot::PROBLEM_ADVICE)
            .map_err(ProblemError::model(&scene.name))?;
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
        let nx = state_len(self.nq);
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
