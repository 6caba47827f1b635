//! Numerical stability at the extremes (issue 7, item 5): a fixed set of probes that push the
//! kernels, the model and the simulator to the edges of their domain and record, for each, either
//! a number with an error estimate or a clear (typed) error — never NaN, never a hang.
//!
//! | probe | paper | what is measured |
//! |---|---|---|
//! | [`kernel_accuracy`] | eq. 22a, 24, 2–7 (App. A/B) | compiled `paper` kernels M, C q̇ + g, contact h vs the double-double evaluation of the same graph at \|q\| = 1 … 1e6 rad, and vs q reduced mod 2π |
//! | [`velocity_extremes`] | eq. 24 (C q̇, Christoffel form) | C q̇ at \|q̇\| = 1e-12 … 1e3 vs double-double, and the homogeneity C(q, k q̇) k q̇ = k² C(q, q̇) q̇ |
//! | [`scaled_scene`], [`length_only_mass_law`], [`human_link3_mass`] | eq. 22a, 22b, 4, 7 | masses / lengths scaled by 1e±3: f64 vs double-double, M SPD, exact similarity laws |
//! | [`singular_contact`] | eq. 33 (Γ = G M⁻¹ Gᵀ), eq. 7 | last two links aligned and touching along their axis: σ_min(J_c), nᵀWn, and the model's `SingularContact` |
//! | [`slip_small_dv`] | eq. 20, 38, Sect. 3.1 | slip accelerations as \|Δv\| → 0, slip law residual (eq. 38), Slip→Stick predicate, friction direction |
//! | [`smooth_convergence`], [`smooth_corner`] | eq. 58–59 vs eq. 3–4 | h_ε → h and p_c,ε → p_c as ε → 0 (observed orders), NaN-freedom at α = 0 and α = −l |
//! | [`painleve_threshold`] | Sect. 7, eq. 37 | the kinetic friction μ_k above which slip has no consistent normal force (bisection vs closed form) |
//! | [`long_horizon`] | eq. 26, energy of eq. 22 | free motion without damping or torque for 10 s / 100 s: energy drift vs rtol, CPU time, bounded step count |
//!
//! Helpers: [`GraphEval`] (one interpreter tape over M, C q̇, g, C q̇ + g and both contact
//! variants, f64 or double-double), [`InterpKernels`] (a [`bf_model::Kernels`] on the
//! interpreter, for scenes without a compiled module, e.g. the ball moved so that α hits a
//! saturation corner exactly: [`corner_model`], [`corner_stick`]), [`press_torque`] (the finger
//! held against C q̇ + g and pressed on with a known force, so that a static stick has the exact
//! answer λ = f n).
//!
//! Findings worth knowing (numbers in the report): the f64 `rem_euclid(2π)` reduction of
//! |q| = 1e6 rad is itself off by ≈ 3e-11 rad (fl(2π) ≠ 2π), so never reduce q before calling the
//! kernels; the model's stick stops reporting `SingularContact` at q₃ ≈ 4.5e-6 rad from the
//! aligned configuration; the Painlevé threshold of the paper finger at the probed contact is
//! μ_k* ≈ 1.37 with λ_n = f/(1 − μ_k/μ_k*) below it; at an exact saturation corner the smooth
//! kernels give NaN once ε² underflows (ε ≲ 1e-162: √(0 + 0) in the derivative of eq. 59), which
//! the model reports as `NonFinite` — a clear error, never a NaN result.
//!
//! [`run_extremes`] runs all probes and returns an [`ExtremesReport`] whose
//! [`ExtremesReport::to_markdown`] is the report section. A probe whose result contains NaN, or
//! that fails with an unexpected error, becomes an [`Outcome::Failed`] row: such rows are listed
//! first in the markdown and counted in [`ExtremesReport::failures`].
//!
//! Error measures: "rel" is the normwise relative error max|a − b| / max|b| (b the reference).
//! The double-double reference ([`bf_codegen::dd::Dd`], ≈ 106 bits, sin/cos with a 160-bit π/2
//! reduction) is rounded to f64, so it carries at most half an ulp of error itself.

use std::f64::consts::{PI, TAU};
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use bf_codegen::dd::Dd;
use bf_codegen::interp::{Scalar, Tape};
use bf_codegen::spec::{InertiaSpec, Scene};
use bf_model::{
    ContactGeometry, ContactKinematics, ContactVariant, HumanKernels, Kernels, Mat3, Mode, Model,
    ModelError, PaperKernels, Params, State, TransitionSettings, Vec3, dynamics, transitions,
};
use bf_sim::ball_finger::{BallFinger, BallFingerOptions};
use bf_sim::{PdController, SimSettings, simulate};

// ---------------------------------------------------------------------------------------------
// Report types
// ---------------------------------------------------------------------------------------------

/// Result of one probe row.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// A finite number and an estimate of its error (or of the error it measures).
    Number {
        /// The measured value.
        value: f64,
        /// Error estimate of `value` (same unit), or the error bound the value is compared with.
        error_estimate: f64,
    },
    /// The code under test refused the input with a typed, explanatory error (the expected
    /// behaviour at this extreme).
    ClearError {
        /// The error's message.
        message: String,
    },
    /// NaN appeared, or an error that is not the documented one: a failure of the probe.
    Failed {
        /// What went wrong.
        message: String,
    },
}

/// One row of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtremesRow {
    /// Probe group, e.g. `"kernel accuracy"`.
    pub case: String,
    /// The extreme parameter value, e.g. `"|q| = 1e6 rad"`.
    pub parameter: String,
    /// What `outcome` is, e.g. `"rel. error of M vs double-double"`.
    pub quantity: String,
    /// Number, clear error or failure.
    pub outcome: Outcome,
    /// Wall-clock seconds spent on the probe this row belongs to (shared by its rows).
    pub seconds: f64,
}

/// All rows of [`run_extremes`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExtremesReport {
    /// The rows, in probe order.
    pub rows: Vec<ExtremesRow>,
    /// Whether the quick variant (10 s horizon) was run.
    pub quick: bool,
    /// Total wall-clock seconds.
    pub seconds: f64,
}

impl ExtremesReport {
    /// The rows whose outcome is [`Outcome::Failed`].
    pub fn failures(&self) -> Vec<&ExtremesRow> {
        self.rows
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Failed { .. }))
            .collect()
    }

    /// The report section as a markdown table (failures, if any, announced first).
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "### Stability at the extremes ({} variant, {:.1} s)\n\n",
            if self.quick { "quick" } else { "full" },
            self.seconds
        ));
        let fails = self.failures();
        if fails.is_empty() {
            s.push_str(
                "All probes returned a finite number or a clear error (no NaN, no hang).\n\n",
            );
        } else {
            s.push_str(&format!("**{} PROBE(S) FAILED:**\n\n", fails.len()));
            for f in fails {
                if let Outcome::Failed { message } = &f.outcome {
                    s.push_str(&format!(
                        "- **FAILED** {} / {} / {}: {}\n",
                        f.case, f.parameter, f.quantity, message
                    ));
                }
            }
            s.push('\n');
        }
        s.push_str("| case | parameter | quantity | outcome | error estimate | time (s) |\n");
        s.push_str("|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let (out, err) = match &r.outcome {
                Outcome::Number {
                    value,
                    error_estimate,
                } => (fmt_num(*value), fmt_num(*error_estimate)),
                Outcome::ClearError { message } => (
                    format!("error: {}", message.replace('|', "\\|")),
                    "—".into(),
                ),
                Outcome::Failed { message } => (
                    format!("**FAILED: {}**", message.replace('|', "\\|")),
                    "—".into(),
                ),
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {:.3} |\n",
                r.case.replace('|', "\\|"),
                r.parameter.replace('|', "\\|"),
                r.quantity.replace('|', "\\|"),
                out,
                err,
                r.seconds
            ));
        }
        s
    }
}

fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e-2 && v.abs() < 1e4 {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

/// Rows of one probe, with the probe's time filled in afterwards.
struct Rows {
    case: &'static str,
    rows: Vec<ExtremesRow>,
}

impl Rows {
    fn new(case: &'static str) -> Self {
        Rows {
            case,
            rows: Vec::new(),
        }
    }
    /// A number row; NaN/inf in `value` or `err` turns it into a failure.
    fn num(
        &mut self,
        parameter: impl Into<String>,
        quantity: impl Into<String>,
        value: f64,
        err: f64,
    ) {
        let outcome = if value.is_finite() && err.is_finite() {
            Outcome::Number {
                value,
                error_estimate: err,
            }
        } else {
            Outcome::Failed {
                message: format!("non-finite result: value {value}, error estimate {err}"),
            }
        };
        self.push(parameter, quantity, outcome);
    }
    fn push(
        &mut self,
        parameter: impl Into<String>,
        quantity: impl Into<String>,
        outcome: Outcome,
    ) {
        self.rows.push(ExtremesRow {
            case: self.case.to_string(),
            parameter: parameter.into(),
            quantity: quantity.into(),
            outcome,
            seconds: 0.0,
        });
    }
    fn fail(&mut self, parameter: impl Into<String>, message: impl Into<String>) {
        self.push(
            parameter,
            "probe",
            Outcome::Failed {
                message: message.into(),
            },
        );
    }
    fn finish(mut self, start: Instant, out: &mut Vec<ExtremesRow>) {
        let dt = start.elapsed().as_secs_f64();
        for r in &mut self.rows {
            r.seconds = dt;
        }
        out.extend(self.rows);
    }
}

// ---------------------------------------------------------------------------------------------
// Small numerics
// ---------------------------------------------------------------------------------------------

/// Normwise relative error max|a − b| / max|b| (b is the reference); NaN anywhere gives NaN.
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64_max_nan);
    let den = b.iter().map(|y| y.abs()).fold(0.0, f64_max_nan);
    if num == 0.0 { 0.0 } else { num / den }
}

/// max that propagates NaN (f64::max drops it, which would hide failures).
fn f64_max_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn mat_rows(m: &[f64]) -> Mat3 {
    Mat3::from_row_slice(m)
}

/// Eigenvalues of the symmetric part of a 3×3 row-major matrix, ascending.
fn sym_eigenvalues(m: &[f64]) -> [f64; 3] {
    let a = mat_rows(m);
    let a = (a + a.transpose()) * 0.5;
    let mut e: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
    e.sort_by(f64::total_cmp);
    [e[0], e[1], e[2]]
}

/// Singular values of a 3×3 matrix, ascending.
fn singular_values(m: &Mat3) -> [f64; 3] {
    let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
    s.sort_by(f64::total_cmp);
    [s[0], s[1], s[2]]
}

fn flat3(m: &[[f64; 3]; 3]) -> Vec<f64> {
    m.iter().flatten().copied().collect()
}

// ---------------------------------------------------------------------------------------------
// The interpreter reference: one tape over the quantities the probes compare
// ---------------------------------------------------------------------------------------------

/// Names and lengths of the interpreter outputs, in tape order.
const GROUPS: [(&str, usize); 16] = [
    ("M", 9),
    ("Cqd", 3),
    ("g", 3),
    ("Cqd_g", 3),
    ("alpha", 1),
    ("sat", 1),
    ("p_c", 3),
    ("h", 1),
    ("J_c", 9),
    ("r_c_norm", 1),
    ("sat_s", 1),
    ("p_c_s", 3),
    ("h_s", 1),
    ("J_c_s", 9),
    ("rc_dot_s", 3),
    ("jc_dot_qd_s", 3),
];

/// A scene's graph compiled into one [`Tape`] over the fixed output groups listed at
/// [`GraphValues::get`], evaluated in f64 or in double-double: the "same graph" the generator
/// emits for `mass_matrix`, `coriolis_qd`, `gravity`, `cqd_g`, `contact` and `contact_smooth`.
pub struct GraphEval {
    tape: Tape,
    nq: usize,
    n_vars: usize,
    param_names: Vec<String>,
    param_defaults: Vec<f64>,
}

/// Outputs of [`GraphEval`] by group name.
#[derive(Debug, Clone)]
pub struct GraphValues {
    vals: Vec<f64>,
}

impl GraphValues {
    /// The values of group `name` (see the module's group list: `M`, `Cqd`, `g`, `Cqd_g`,
    /// `alpha`, `sat`, `p_c`, `h`, `J_c`, `r_c_norm`, `sat_s`, `p_c_s`, `h_s`, `J_c_s`,
    /// `rc_dot_s`, `jc_dot_qd_s`); empty for an unknown name.
    pub fn get(&self, name: &str) -> &[f64] {
        let mut off = 0;
        for (n, len) in GROUPS {
            if n == name {
                return &self.vals[off..off + len];
            }
            off += len;
        }
        &[]
    }
    /// Every value.
    pub fn all(&self) -> &[f64] {
        &self.vals
    }
}

impl GraphEval {
    /// Build the graph of a 3-joint scene with `[ball]` and `[contact]`.
    pub fn new(scene: &Scene) -> anyhow::Result<Self> {
        let mut m = bf_codegen::Model::new(scene)?;
        if m.nq() != 3 {
            bail!(
                "scene `{}` has {} joints, the probes need 3",
                scene.name,
                m.nq()
            );
        }
        let mass = m.mass_matrix();
        let cqd = m.coriolis_qd();
        let g = m.gravity();
        let cqd_g = m.cqd_g();
        let c = m.contact(false)?;
        let cs = m.contact(true)?;
        let mut ids = Vec::new();
        ids.extend(mass.iter().flatten().copied());
        ids.extend(cqd);
        ids.extend(g);
        ids.extend(cqd_g);
        ids.push(c.alpha);
        ids.push(c.sat_alpha);
        ids.extend(c.p_c);
        ids.push(c.h);
        ids.extend(c.j_c.iter().flatten().copied());
        // |r_c| = h + r, the scale against which the error of h is measured.
        let rr = m.g.v3_dot(c.r_c, c.r_c);
        ids.push(m.g.sqrt(rr));
        ids.push(cs.sat_alpha);
        ids.extend(cs.p_c);
        ids.push(cs.h);
        ids.extend(cs.j_c.iter().flatten().copied());
        ids.extend(cs.rc_dot);
        ids.extend(cs.jc_dot_qd);
        debug_assert_eq!(ids.len(), GROUPS.iter().map(|g| g.1).sum::<usize>());
        Ok(GraphEval {
            tape: Tape::new(&m.g, &ids),
            nq: 3,
            n_vars: m.layout.n_vars(),
            param_names: m.params.iter().map(|p| p.0.clone()).collect(),
            param_defaults: m.params.iter().map(|p| p.1).collect(),
        })
    }

    /// Runtime parameter names (scene order) and their defaults.
    pub fn params(&self) -> (&[String], &[f64]) {
        (&self.param_names, &self.param_defaults)
    }

    fn vars<S: Scalar>(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> Vec<S> {
        let mut v = vec![S::from_f64(0.0); self.n_vars];
        let n = self.nq;
        for i in 0..n {
            v[i] = S::from_f64(q[i]);
            v[n + i] = S::from_f64(qd[i]);
        }
        for i in 0..3 {
            v[2 * n + i] = S::from_f64(w[i]);
        }
        v[2 * n + 3] = S::from_f64(eps);
        for (i, &pv) in p.iter().enumerate().take(self.n_vars - 2 * n - 4) {
            v[2 * n + 4 + i] = S::from_f64(pv);
        }
        v
    }

    /// Evaluate in f64 (`p`: runtime parameters; pass `params().1` for the defaults).
    pub fn eval_f64(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> GraphValues {
        GraphValues {
            vals: self.tape.eval::<f64>(&self.vars(q, qd, w, eps, p)),
        }
    }

    /// Evaluate in double-double, rounded to f64.
    pub fn eval_dd(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> GraphValues {
        GraphValues {
            vals: self
                .tape
                .eval::<Dd>(&self.vars(q, qd, w, eps, p))
                .into_iter()
                .map(|d| d.to_f64())
                .collect(),
        }
    }
}

fn paper_scene_spec() -> anyhow::Result<Scene> {
    Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").map_err(|e| anyhow!("{e}"))
}

fn human_scene_spec() -> anyhow::Result<Scene> {
    Scene::from_toml_str(bf_generated::human::SCENE_TOML, "human").map_err(|e| anyhow!("{e}"))
}

/// A [`Kernels`] implementation on the bf-codegen interpreter (f64) for scenes that have no
/// compiled module (moved ball, scaled scene): the same expressions as the generated kernels,
/// so the model's physics and its NaN screening can be probed at states the compiled scenes
/// cannot reach (e.g. α exactly at a saturation corner).
#[derive(Debug)]
pub struct InterpKernels {
    name: String,
    toml: String,
    dynamics: Tape,
    exact: Tape,
    smooth: Tape,
    n_vars: usize,
    names: Vec<&'static str>,
    values: Vec<f64>,
}

impl InterpKernels {
    /// Build from a 3-joint contact scene; `runtime` names the constants kept as parameters
    /// (their values start at the scene's values; change them with [`InterpKernels::set`]).
    pub fn new(scene: &Scene, runtime: &[&'static str]) -> anyhow::Result<Self> {
        let mut scene = scene.clone();
        scene.runtime_parameters = runtime.iter().map(|s| s.to_string()).collect();
        let mut m = bf_codegen::Model::new(&scene)?;
        if m.nq() != 3 {
            bail!(
                "scene `{}` has {} joints, the model needs 3",
                scene.name,
                m.nq()
            );
        }
        let mass = m.mass_matrix();
        let cg = m.cqd_g();
        let u = m.potential();
        let mut d: Vec<_> = mass.iter().flatten().copied().collect();
        d.extend(cg);
        d.push(u);
        let contact_ids = |c: bf_codegen::robot::ContactExprs| {
            let mut ids = vec![c.alpha, c.sat_alpha];
            ids.extend(c.p_c);
            ids.extend(c.r_c);
            ids.push(c.h);
            ids.extend(c.n);
            ids.extend(c.j_c.iter().flatten().copied());
            ids.extend(c.v_c);
            ids.extend(c.delta_v);
            ids.push(c.h_dot);
            ids.extend(c.rc_dot);
            ids.extend(c.jc_dot_qd);
            ids
        };
        let ce = contact_ids(m.contact(false)?);
        let cs = contact_ids(m.contact(true)?);
        Ok(InterpKernels {
            name: scene.name.clone(),
            toml: String::new(),
            dynamics: Tape::new(&m.g, &d),
            exact: Tape::new(&m.g, &ce),
            smooth: Tape::new(&m.g, &cs),
            n_vars: m.layout.n_vars(),
            names: runtime.to_vec(),
            values: m.params.iter().map(|p| p.1).collect(),
        })
    }

    /// Set runtime parameter `name`; error if it is not one.
    pub fn set(&mut self, name: &str, value: f64) -> anyhow::Result<()> {
        let i = self
            .names
            .iter()
            .position(|n| *n == name)
            .with_context(|| format!("`{name}` is not a runtime parameter"))?;
        self.values[i] = value;
        Ok(())
    }

    fn vars(&self, q: &[f64; 3], qd: &[f64; 3], w: &[f64; 3], eps: f64) -> Vec<f64> {
        let mut v = vec![0.0; self.n_vars];
        v[..3].copy_from_slice(q);
        v[3..6].copy_from_slice(qd);
        v[6..9].copy_from_slice(w);
        v[9] = eps;
        v[10..].copy_from_slice(&self.values);
        v
    }
}

impl Kernels for InterpKernels {
    fn scene_name(&self) -> &str {
        &self.name
    }
    fn scene_toml(&self) -> &str {
        &self.toml
    }
    fn param_names(&self) -> &[&str] {
        &self.names
    }
    fn param_values(&self) -> &[f64] {
        &self.values
    }
    fn mass_cqd_g(&self, q: &[f64; 3], qd: &[f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
        let v = self.dynamics.eval::<f64>(&self.vars(q, qd, &[0.0; 3], 0.0));
        let m = [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]];
        (m, [v[9], v[10], v[11]])
    }
    fn potential(&self, q: &[f64; 3]) -> f64 {
        self.dynamics
            .eval::<f64>(&self.vars(q, &[0.0; 3], &[0.0; 3], 0.0))[12]
    }
    fn contact(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        omega: &[f64; 3],
        variant: ContactVariant,
    ) -> ContactGeometry {
        let v = match variant {
            ContactVariant::Exact => self.exact.eval::<f64>(&self.vars(q, qd, omega, 0.0)),
            ContactVariant::Smooth(e) => self.smooth.eval::<f64>(&self.vars(q, qd, omega, e)),
        };
        let a3 = |i: usize| [v[i], v[i + 1], v[i + 2]];
        let jc = [a3(12), a3(15), a3(18)];
        ContactGeometry::from_arrays(
            v[0],
            v[1],
            &a3(2),
            &a3(5),
            v[8],
            &a3(9),
            &jc,
            &a3(21),
            &a3(24),
            v[27],
            &a3(28),
            &a3(31),
        )
    }
}

/// Model of the paper scene on [`InterpKernels`] with the ball centre and radius as runtime
/// parameters (`ball.center.x/y/z`, `ball.radius`), smooth contact with `eps`.
pub fn corner_model(
    centre: [f64; 3],
    radius: f64,
    eps: f64,
) -> anyhow::Result<Model<InterpKernels>> {
    let scene = paper_scene_spec()?;
    let mut k = InterpKernels::new(
        &scene,
        &[
            "ball.center.x",
            "ball.center.y",
            "ball.center.z",
            "ball.radius",
        ],
    )?;
    for (n, v) in ["ball.center.x", "ball.center.y", "ball.center.z"]
        .iter()
        .zip(centre)
    {
        k.set(n, v)?;
    }
    k.set("ball.radius", radius)?;
    let params = Params::from_scene(&scene)?;
    let params = Params::new(
        *params.ball_inertia(),
        radius,
        params.mu_s(),
        params.mu_k(),
        params.mu_v(),
        params.socket_damping(),
    )?;
    Ok(Model::new(k, params, TransitionSettings::default())?
        .with_contact_variant(ContactVariant::Smooth(eps))?)
}

/// Stick at the exact saturation corner α = 0 (q = 0, ball centre (2, 0.5, 3), radius 0.5, so
/// h = 0 and n = −y) with the smooth contact of width `eps`, finger pressed on with 1 N:
/// `Ok(Ok((λ_n, |λ − n|)))` (exactly (1, 0) in exact arithmetic), or the model's error.
pub fn corner_stick(eps: f64) -> anyhow::Result<Result<(f64, f64), ModelError>> {
    let model = corner_model([2.0, 0.5, 3.0], 0.5, eps)?;
    let x = State::new(Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
    let kin = match model.evaluate(&x) {
        Ok(k) => k,
        Err(e) => return Ok(Err(e)),
    };
    let tau = press_torque(&kin, 1.0);
    let n = kin.contact.n;
    Ok(model
        .stick(&x, &tau)
        .map(|a| (a.force.lambda_n, (a.force.lambda - n).norm())))
}

/// Torque that holds the finger against gravity and C q̇ and presses it onto the ball with
/// force `f` (N) along −n at the contact point: τ = C q̇ + g − J_cᵀ n f. In a static stick this
/// gives λ = f n exactly (q̈ = 0, ω̇ = 0 since r_c ∥ n).
pub fn press_torque(kin: &ContactKinematics, f: f64) -> Vec3 {
    kin.cqd_g - kin.contact.j_c.transpose() * kin.contact.n * f
}

// ---------------------------------------------------------------------------------------------
// Fixed probe states
// ---------------------------------------------------------------------------------------------

/// Direction of q for the |q| sweep (all joints large, different magnitudes and signs).
pub const Q_DIR: [f64; 3] = [0.7, -0.45, 0.9];
/// q̇ used by the kernel-accuracy probe (rad/s).
pub const QD_PROBE: [f64; 3] = [0.3, -0.2, 0.5];
/// Ball angular velocity used by the kernel probes (rad/s).
pub const OMEGA_PROBE: [f64; 3] = [0.1, 0.2, 2.2];

// ---------------------------------------------------------------------------------------------
// Probe 1: kernel accuracy at large |q|
// ---------------------------------------------------------------------------------------------

/// Errors of the compiled `paper` kernels at q = `q_mag` · [`Q_DIR`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KernelAccuracy {
    /// The q evaluated.
    pub q: [f64; 3],
    /// rel. error of `mass_matrix` vs double-double at the same q.
    pub m: f64,
    /// rel. error of `cqd_g` vs double-double at the same q.
    pub cqd_g: f64,
    /// rel. error of `mass_cqd_g`'s C q̇ + g (the model's path) vs double-double.
    pub cqd_g_model: f64,
    /// |h − h_dd| / |r_c| of `contact` (h is a difference of O(r) numbers).
    pub h: f64,
    /// rel. error of `contact`'s J_c vs double-double.
    pub j_c: f64,
    /// The same four errors with the kernels evaluated at q reduced mod 2π in f64
    /// (reference: double-double at the unreduced q): M, C q̇ + g, h, J_c.
    pub reduced: [f64; 4],
    /// max over joints of |q_red − (q − 2πk)| in double-double: the rounding of the
    /// reduction itself, which bounds what `reduced` can reach.
    pub reduction_error: f64,
}

/// Compiled `paper` kernels vs the double-double interpreter at |q| = `q_mag` (probe 1).
pub fn kernel_accuracy(reference: &GraphEval, q_mag: f64) -> KernelAccuracy {
    use bf_generated::paper as k;
    let q = Q_DIR.map(|d| d * q_mag);
    let qd = QD_PROBE;
    let w = OMEGA_PROBE;
    let p = [0.0; 0];
    let dd = reference.eval_dd(&q, &qd, &w, 0.01, &[]);
    let compiled = |q: &[f64; 3]| {
        let mut m = [[0.0; 3]; 3];
        k::mass_matrix(q, &p, &mut m);
        let mut cg = [0.0; 3];
        k::cqd_g(q, &qd, &p, &mut cg);
        let mut m2 = [[0.0; 3]; 3];
        let mut cg2 = [0.0; 3];
        k::mass_cqd_g(q, &qd, &p, &mut m2, &mut cg2);
        let mut c = k::Contact::default();
        k::contact(q, &qd, &w, &p, &mut c);
        (flat3(&m), cg, cg2, c)
    };
    let (m, cg, cg2, c) = compiled(&q);
    let scale = dd.get("r_c_norm")[0];
    let h_err = |h: f64| (h - dd.get("h")[0]).abs() / scale;
    let q_red = q.map(|x| x.rem_euclid(TAU));
    let (mr, cgr, _, cr) = compiled(&q_red);
    let two_pi = Dd::new(TAU) + Dd::new(2.4492935982947064e-16);
    let reduction_error = q
        .iter()
        .zip(&q_red)
        .map(|(&x, &xr)| {
            let kf = ((x - xr) / TAU).round();
            let exact = Dd::new(x) - Dd::new(kf) * two_pi;
            (exact - Dd::new(xr)).to_f64().abs()
        })
        .fold(0.0, f64_max_nan);
    KernelAccuracy {
        q,
        m: rel_err(&m, dd.get("M")),
        cqd_g: rel_err(&cg, dd.get("Cqd_g")),
        cqd_g_model: rel_err(&cg2, dd.get("Cqd_g")),
        h: h_err(c.h),
        j_c: rel_err(&flat3(&c.j_c), dd.get("J_c")),
        reduced: [
            rel_err(&mr, dd.get("M")),
            rel_err(&cgr, dd.get("Cqd_g")),
            h_err(cr.h),
            rel_err(&flat3(&cr.j_c), dd.get("J_c")),
        ],
        reduction_error,
    }
}

// ---------------------------------------------------------------------------------------------
// Probe 2: extreme joint velocities
// ---------------------------------------------------------------------------------------------

/// C q̇ at extreme |q̇| (probe 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityExtreme {
    /// |q̇| scale.
    pub qd_mag: f64,
    /// rel. error of the compiled `coriolis_qd` vs double-double.
    pub cqd: f64,
    /// rel. deviation of C(q, k q̇) k q̇ from k² C(q, q̇) q̇ with q̇ = [`QD_PROBE`], k = `qd_mag`
    /// (exact quadratic homogeneity of the Christoffel form).
    pub homogeneity: f64,
    /// max |C q̇| (N m).
    pub magnitude: f64,
}

/// Compiled `coriolis_qd` at |q̇| = `qd_mag` (probe 2).
pub fn velocity_extremes(reference: &GraphEval, qd_mag: f64) -> VelocityExtreme {
    use bf_generated::paper as k;
    let q = [0.4, -0.7, 1.1];
    let qd = QD_PROBE.map(|v| v * qd_mag);
    let p = [0.0; 0];
    let mut c = [0.0; 3];
    k::coriolis_qd(&q, &qd, &p, &mut c);
    let mut c1 = [0.0; 3];
    k::coriolis_qd(&q, &QD_PROBE, &p, &mut c1);
    let dd = reference.eval_dd(&q, &qd, &[0.0; 3], 0.01, &[]);
    let predicted = c1.map(|v| v * qd_mag * qd_mag);
    VelocityExtreme {
        qd_mag,
        cqd: rel_err(&c, dd.get("Cqd")),
        homogeneity: rel_err(&c, &predicted),
        magnitude: c.iter().map(|v| v.abs()).fold(0.0, f64_max_nan),
    }
}

// ---------------------------------------------------------------------------------------------
// Probe 3: scaled masses and lengths
// ---------------------------------------------------------------------------------------------

/// Geometric similarity: every length × `k_len` (DH a and d, COGs, base translation, ball
/// radius and centre), every mass × `k_mass`, every link inertia × `k_mass · k_len²`.
pub fn scale_scene(scene: &Scene, k_mass: f64, k_len: f64) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.links {
        l.a *= k_len;
        l.d *= k_len;
        l.com = l.com.map(|c| c * k_len);
        l.mass *= k_mass;
        let ki = k_mass * k_len * k_len;
        l.inertia = match &l.inertia {
            InertiaSpec::Diagonal(d) => InertiaSpec::Diagonal(d.map(|v| v * ki)),
            InertiaSpec::Full(m) => InertiaSpec::Full(m.map(|r| r.map(|v| v * ki))),
        };
    }
    if let Some(t) = &mut s.base.translation {
        *t = t.map(|v| v * k_len);
    }
    if let Some(b) = &mut s.ball {
        b.radius *= k_len;
        b.center = b.center.map(|v| v * k_len);
        b.mass *= k_mass;
        b.inertia = b.inertia.as_ref().map(|i| match i {
            InertiaSpec::Diagonal(d) => {
                InertiaSpec::Diagonal(d.map(|v| v * k_mass * k_len * k_len))
            }
            InertiaSpec::Full(m) => {
                InertiaSpec::Full(m.map(|r| r.map(|v| v * k_mass * k_len * k_len)))
            }
        });
    }
    s
}

/// A scaled scene evaluated through the interpreter (probe 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaledScene {
    /// Mass factor.
    pub k_mass: f64,
    /// Length factor.
    pub k_len: f64,
    /// rel. error f64 vs double-double of M, C q̇ + g, h (relative to |r_c|) and J_c.
    pub f64_vs_dd: [f64; 4],
    /// Smallest eigenvalue of M / largest (> 0: SPD; ~1e-2 for the finger).
    pub m_eig_ratio: f64,
    /// Smallest eigenvalue of M (kg m²).
    pub m_eig_min: f64,
    /// Deviation from the similarity laws, relative: M/(k_m k_L²), g/(k_m k_L),
    /// C q̇/(k_m k_L²), h/k_L, J_c/k_L vs the unscaled scene (all exact).
    pub law_deviation: [f64; 5],
}

/// Evaluate the paper scene scaled by (`k_mass`, `k_len`) against the unscaled one (probe 3).
/// The state is the same q, q̇, ω (angles and angular rates are scale-free).
pub fn scaled_scene(base: &GraphEval, k_mass: f64, k_len: f64) -> anyhow::Result<ScaledScene> {
    let scene = scale_scene(&paper_scene_spec()?, k_mass, k_len);
    let ge = GraphEval::new(&scene)?;
    let (q, qd, w) = ([0.4, 0.9, 0.6], QD_PROBE, OMEGA_PROBE);
    let f = ge.eval_f64(&q, &qd, &w, 0.01, &[]);
    let d = ge.eval_dd(&q, &qd, &w, 0.01, &[]);
    let b = base.eval_f64(&q, &qd, &w, 0.01, &[]);
    let eig = sym_eigenvalues(f.get("M"));
    let scaled = |name: &str, k: f64| -> Vec<f64> { b.get(name).iter().map(|v| v * k).collect() };
    let h_rel = (f.get("h")[0] - d.get("h")[0]).abs() / d.get("r_c_norm")[0];
    let h_law = (f.get("h")[0] - b.get("h")[0] * k_len).abs() / (b.get("r_c_norm")[0] * k_len);
    Ok(ScaledScene {
        k_mass,
        k_len,
        f64_vs_dd: [
            rel_err(f.get("M"), d.get("M")),
            rel_err(f.get("Cqd_g"), d.get("Cqd_g")),
            h_rel,
            rel_err(f.get("J_c"), d.get("J_c")),
        ],
        m_eig_ratio: eig[0] / eig[2],
        m_eig_min: eig[0],
        law_deviation: [
            rel_err(f.get("M"), &scaled("M", k_mass * k_len * k_len)),
            rel_err(f.get("g"), &scaled("g", k_mass * k_len)),
            rel_err(f.get("Cqd"), &scaled("Cqd", k_mass * k_len * k_len)),
            h_law,
            rel_err(f.get("J_c"), &scaled("J_c", k_len)),
        ],
    })
}

/// Lengths alone scaled by k (masses and inertias kept): M(k) = k² A + B with A the
/// translational part Σ m_i J_Pᵢᵀ J_Pᵢ and B the rotational part Σ J_Oᵢᵀ R_i I_i R_iᵀ J_Oᵢ
/// (eq. 22a: J_P scales with length, J_O and R_i do not). A and B are identified from
/// k = 1 and k = 2; returns (rel. deviation of the predicted M(k) from the evaluated one,
/// smallest eigenvalue ratio of M(k)).
pub fn length_only_mass_law(k: f64) -> anyhow::Result<(f64, f64)> {
    let base = paper_scene_spec()?;
    let lengths_only = |k: f64| {
        let mut s = scale_scene(&base, 1.0, k);
        // undo the inertia scaling of scale_scene: inertias stay as in the paper scene
        for (l, l0) in s.links.iter_mut().zip(&base.links) {
            l.inertia = l0.inertia.clone();
        }
        s
    };
    let q = [0.4, 0.9, 0.6];
    let m_of = |k: f64| -> anyhow::Result<Vec<f64>> {
        let ge = GraphEval::new(&lengths_only(k))?;
        Ok(ge
            .eval_dd(&q, &[0.0; 3], &[0.0; 3], 0.01, &[])
            .get("M")
            .to_vec())
    };
    let m1 = m_of(1.0)?;
    let m2 = m_of(2.0)?;
    let mk = m_of(k)?;
    let a: Vec<f64> = m1.iter().zip(&m2).map(|(x, y)| (y - x) / 3.0).collect();
    let b: Vec<f64> = m1.iter().zip(&a).map(|(x, a)| x - a).collect();
    let pred: Vec<f64> = a.iter().zip(&b).map(|(a, b)| k * k * a + b).collect();
    let eig = sym_eigenvalues(&mk);
    Ok((rel_err(&pred, &mk), eig[0] / eig[2]))
}

/// The compiled human scene with runtime parameter `link3.mass` = `k` × default (probe 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HumanMass {
    /// Factor on link3.mass.
    pub k: f64,
    /// rel. error of compiled M vs double-double interpreter with the same parameters.
    pub m_vs_dd: f64,
    /// rel. error of compiled C q̇ + g vs double-double.
    pub cqd_g_vs_dd: f64,
    /// Deviation of M(m3) from the affine law M0 + m3 ∂M/∂m3 identified at k = 1 and k = 2.
    pub affine_deviation: f64,
    /// Smallest/largest eigenvalue of M.
    pub m_eig_ratio: f64,
    /// |q̈| of the model's free motion at the probe state (finite).
    pub qdd_norm: f64,
}

/// Probe 3b: the compiled human scene with `link3.mass` scaled by `k`.
pub fn human_link3_mass(reference: &GraphEval, k: f64) -> anyhow::Result<HumanMass> {
    use bf_generated::human as hk;
    let i_mass = hk::PARAM_NAMES
        .iter()
        .position(|n| *n == "link3.mass")
        .context("human scene has no runtime parameter link3.mass")?;
    let (q, qd) = ([0.4, 0.9, 0.6], QD_PROBE);
    let params_for = |k: f64| {
        let mut p = hk::PARAM_DEFAULTS;
        p[i_mass] *= k;
        p
    };
    let compiled = |k: f64| {
        let p = params_for(k);
        let mut m = [[0.0; 3]; 3];
        let mut cg = [0.0; 3];
        hk::mass_cqd_g(&q, &qd, &p, &mut m, &mut cg);
        (flat3(&m), cg)
    };
    let p = params_for(k);
    let (m, cg) = compiled(k);
    let dd = reference.eval_dd(&q, &qd, &[0.0; 3], 0.01, &p);
    let (m1, _) = compiled(1.0);
    let (m2, _) = compiled(2.0);
    let pred: Vec<f64> = m1
        .iter()
        .zip(&m2)
        .map(|(a, b)| a + (k - 1.0) * (b - a))
        .collect();
    let eig = sym_eigenvalues(&m);
    let model = Model::from_kernels(HumanKernels::with_params(&p)?)?;
    let x = State::new(Vec3::from(q), Vec3::from(qd), Vec3::from(OMEGA_PROBE));
    let acc = model.free(&x, &Vec3::zeros())?;
    Ok(HumanMass {
        k,
        m_vs_dd: rel_err(&m, dd.get("M")),
        cqd_g_vs_dd: rel_err(&cg, dd.get("Cqd_g")),
        affine_deviation: rel_err(&m, &pred),
        m_eig_ratio: eig[0] / eig[2],
        qdd_norm: acc.qdd.norm(),
    })
}

// ---------------------------------------------------------------------------------------------
// Probe 4: singular contact configurations
// ---------------------------------------------------------------------------------------------

/// q₂ at which links 2–3 (with q₁ = q₃ = 0) point from the end of link 1 at (2, 0, 1) straight
/// at the ball centre: x₂ = (−sin q₂, 0, cos q₂) = (−2, 0, −1)/√5.
pub fn singular_q2() -> f64 {
    PI - 2f64.atan()
}

/// The human finger touching a ball (radius chosen through the runtime parameter `ball.radius`)
/// at its tip, q = (0, [`singular_q2`], δ): for δ = 0 links 2 and 3 are aligned and point at the
/// ball centre, so J_c loses rank (joints 2 and 3 move the tip the same way) and the finger
/// cannot move along the normal (J_cᵀ n = 0 ⇒ Γ singular, eq. 33).
#[derive(Debug, Clone, PartialEq)]
pub struct SingularProbe {
    /// δ = q₃ (rad).
    pub delta: f64,
    /// Ball radius making h = 0 (m).
    pub radius: f64,
    /// Singular values of J_c, ascending.
    pub jc_singular_values: [f64; 3],
    /// nᵀ W n / ‖W‖_F (W = J_c M_f⁻¹ J_cᵀ): the normal mobility the model thresholds.
    pub normal_mobility: f64,
    /// The model's stick result with the finger pressed on with 1 N ([`press_torque`]):
    /// (λ_n, |λ − n|), exactly (1, 0) in exact arithmetic; or the model's error.
    pub stick: Result<(f64, f64), ModelError>,
}

/// Probe 4 at q₃ = `delta`.
pub fn singular_contact(delta: f64) -> anyhow::Result<SingularProbe> {
    use bf_generated::human as hk;
    let i_r = hk::PARAM_NAMES
        .iter()
        .position(|n| *n == "ball.radius")
        .context("human scene has no runtime parameter ball.radius")?;
    let q = [0.0, singular_q2(), delta];
    let mut c = hk::Contact::default();
    let mut p = hk::PARAM_DEFAULTS;
    hk::contact(&q, &[0.0; 3], &[0.0; 3], &p, &mut c);
    // r_c does not depend on the radius: choose the radius that puts the ball on the tip.
    let radius = c.r_c.iter().map(|v| v * v).sum::<f64>().sqrt();
    p[i_r] = radius;
    let model = Model::from_kernels(HumanKernels::with_params(&p)?)?;
    let x = State::new(Vec3::from(q), Vec3::zeros(), Vec3::zeros());
    let kin = model.evaluate(&x)?;
    let sv = singular_values(&kin.contact.j_c);
    let mats = dynamics::contact_matrices(&kin, model.params())?;
    let tau = press_torque(&kin, 1.0);
    let n = kin.contact.n;
    let stick = model
        .stick(&x, &tau)
        .map(|a| (a.force.lambda_n, (a.force.lambda - n).norm()));
    Ok(SingularProbe {
        delta,
        radius,
        jc_singular_values: sv,
        normal_mobility: mats.n_w_n / mats.w.norm(),
        stick,
    })
}

/// The smallest q₃ = δ at which [`singular_contact`] still returns a force: bisection in log δ
/// on [1e-9, 1e-1] (60 halvings); error if the bracket ends are not singular / regular.
pub fn singular_threshold() -> anyhow::Result<f64> {
    let is_singular = |d: f64| -> anyhow::Result<bool> {
        match singular_contact(d)?.stick {
            Ok(_) => Ok(false),
            Err(ModelError::SingularContact { .. }) => Ok(true),
            Err(e) => Err(anyhow!("unexpected error at δ = {d:e}: {e}")),
        }
    };
    let (mut lo, mut hi) = (1e-9f64.ln(), 1e-1f64.ln());
    if !is_singular(lo.exp())? || is_singular(hi.exp())? {
        bail!("no singular → regular switch of stick on δ ∈ [1e-9, 1e-1]");
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if is_singular(mid.exp())? {
            lo = mid
        } else {
            hi = mid
        }
    }
    Ok(hi.exp())
}

// ---------------------------------------------------------------------------------------------
// Contact states of the paper scene
// ---------------------------------------------------------------------------------------------

/// A configuration of the paper finger touching the ball (|h| < 1e-14 m) with line contact
/// (−l < α < 0), found by M_f-metric Newton steps on h from (0.1, 1.3, 1.2).
pub fn paper_contact_configuration() -> anyhow::Result<Vec3> {
    let model = bf_model::fixtures::paper_scene()?;
    let mut q = Vec3::new(0.1, 1.3, 1.2);
    for _ in 0..50 {
        let x = State::new(q, Vec3::zeros(), Vec3::zeros());
        let kin = model.evaluate(&x)?;
        if kin.contact.h.abs() < 1e-14 {
            return Ok(q);
        }
        q += model.project_configuration(&x)?;
    }
    bail!("Newton on h(q) = 0 did not converge in 50 steps")
}

/// State at contact configuration `q` with q̇ = 0 and ω chosen so that Δv = `s` · `t_hat`
/// (t_hat unit and tangential: ω = s (r_c × t̂)/|r_c|², so ω × r_c = s t̂).
fn state_with_slip(
    model: &Model<PaperKernels>,
    q: Vec3,
    t_hat: &Vec3,
    s: f64,
) -> anyhow::Result<State> {
    let kin = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let rc = kin.contact.r_c;
    let w = rc.cross(t_hat) * (s / rc.norm_squared());
    Ok(State::new(q, Vec3::zeros(), w))
}

/// A unit tangent at the contact of configuration `q` (normal n): T_n applied to world y.
fn some_tangent(model: &Model<PaperKernels>, q: Vec3) -> anyhow::Result<Vec3> {
    let kin = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let n = kin.contact.n;
    let e = Vec3::new(0.3, 1.0, -0.2);
    Ok((e - n * n.dot(&e)).normalize())
}

// ---------------------------------------------------------------------------------------------
// Probe 5: |Δv| → 0 in slip
// ---------------------------------------------------------------------------------------------

/// Slip at |Δv| = `s` (probe 5).
#[derive(Debug, Clone, PartialEq)]
pub struct SlipProbe {
    /// |Δv| (m/s).
    pub s: f64,
    /// λ without a direction hint, or the model's error (`UndefinedSlipDirection` below
    /// `slip_direction_tol`).
    pub lambda: Result<Vec3, ModelError>,
    /// λ with the direction hint t̂ (always defined).
    pub lambda_hint: Vec3,
    /// λ_n of `lambda_hint` (N).
    pub lambda_n: f64,
    /// |λ_∥| of `lambda_hint` (N); eq. 20: μ_k λ_n.
    pub lambda_t_norm: f64,
    /// |eq. 38 residual| / (|λ| |Δv|) (division-free slip law; 0 up to rounding).
    pub law_residual: f64,
    /// Angle (rad) between the friction force λ_∥ and Δv (eq. 20: 0).
    pub friction_angle: f64,
    /// The Slip→Stick predicate (‖Δv‖ ≤ ε and decreasing).
    pub slip_to_stick: bool,
}

/// Probe 5: finger at rest on the ball, pressed on with 1 N ([`press_torque`]), ball spinning
/// so that |Δv| = `s`.
pub fn slip_small_dv(q: Vec3, s: f64) -> anyhow::Result<SlipProbe> {
    let model = bf_model::fixtures::paper_scene()?;
    let t_hat = some_tangent(&model, q)?;
    let x = state_with_slip(&model, q, &t_hat, s)?;
    let kin = model.evaluate(&x)?;
    let tau = press_torque(&kin, 1.0);
    let lambda = model.slip(&x, &tau, None).map(|a| a.force.lambda);
    let acc = model.slip(&x, &tau, Some(&t_hat))?;
    let lam = acc.force.lambda;
    let dv = kin.contact.delta_v;
    let res = dynamics::slip_law_residual(&lam, &kin.contact.n, &dv, model.params().mu_k());
    let law_residual = res[0].abs().max(res[1].abs()) / (lam.norm() * dv.norm());
    let lt = acc.force.lambda_t;
    let cosang = (lt.dot(&t_hat) / lt.norm()).clamp(-1.0, 1.0);
    let slip_to_stick = transitions::slip_to_stick(&kin, &acc, model.settings());
    Ok(SlipProbe {
        s,
        lambda,
        lambda_hint: lam,
        lambda_n: acc.force.lambda_n,
        lambda_t_norm: acc.force.lambda_t.norm(),
        law_residual,
        friction_angle: cosang.acos(),
        slip_to_stick,
    })
}

// ---------------------------------------------------------------------------------------------
// Probe 6: ε → 0 of the smooth saturation
// ---------------------------------------------------------------------------------------------

/// Smooth vs exact contact at one ε (probe 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothError {
    /// ε (m).
    pub eps: f64,
    /// α (m) of the exact contact (interior: −l < α < 0).
    pub alpha: f64,
    /// |sat_ε(α) − sat(α)| (m).
    pub sat: f64,
    /// |h_ε − h| (m).
    pub h: f64,
    /// max |p_c,ε − p_c| (m).
    pub p_c: f64,
    /// Whether every output of `contact_smooth` is finite.
    pub finite: bool,
}

/// Compiled `contact_smooth` vs `contact` of the paper scene at configuration `q` (probe 6).
pub fn smooth_convergence(q: [f64; 3], eps: f64) -> SmoothError {
    use bf_generated::paper as k;
    let p = [0.0; 0];
    let mut c = k::Contact::default();
    k::contact(&q, &QD_PROBE, &OMEGA_PROBE, &p, &mut c);
    let mut s = k::Contact::default();
    k::contact_smooth(&q, &QD_PROBE, &OMEGA_PROBE, eps, &p, &mut s);
    let mut all = vec![s.alpha, s.sat_alpha, s.h, s.h_dot];
    all.extend(s.p_c);
    all.extend(s.n);
    all.extend(flat3(&s.j_c));
    all.extend(s.v_c);
    all.extend(s.delta_v);
    all.extend(s.rc_dot);
    all.extend(s.jc_dot_qd);
    SmoothError {
        eps,
        alpha: c.alpha,
        sat: (s.sat_alpha - c.sat_alpha).abs(),
        h: (s.h - c.h).abs(),
        p_c: rel_err(&s.p_c, &c.p_c) * c.p_c.iter().map(|v| v.abs()).fold(0.0, f64_max_nan),
        finite: all_finite(&all),
    }
}

/// A configuration of the paper finger whose closest point to the ball is inside link 3
/// (α ≈ −0.40 m, h ≈ 0.43 m): the interior of the saturation, where sat_ε − sat = O(ε²) and,
/// because r_c ⟂ e_x3 there (eq. 1), h_ε − h = O(ε⁴).
pub const Q_INTERIOR: [f64; 3] = [0.0, 1.4, 2.2];

/// Observed convergence orders log(e_i/e_{i+1}) / log(ε_i/ε_{i+1}) between consecutive rows
/// (rows whose error is below `floor` are skipped: rounding, not truncation).
pub fn observed_orders(errs: &[(f64, f64)], floor: f64) -> Vec<f64> {
    errs.windows(2)
        .filter(|w| w[1].1 > floor && w[0].1 > floor)
        .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
        .collect()
}

/// The interpreter graph of the paper scene with the ball centre as runtime parameters, so the
/// saturation corners can be hit exactly: at q = 0 the finger is stretched along world z with
/// p_e = (2, 0, 3) and e_x3 = (0, 0, 1) exactly, so α = c_z − 3 exactly.
pub fn corner_graph() -> anyhow::Result<GraphEval> {
    let mut s = paper_scene_spec()?;
    s.runtime_parameters = vec![
        "ball.center.x".into(),
        "ball.center.y".into(),
        "ball.center.z".into(),
        "ball.radius".into(),
    ];
    GraphEval::new(&s)
}

/// At a saturation corner: α exactly 0 (`at_tip`) or exactly −l, ε given. Returns
/// (α, |sat_ε − sat|, |h_ε − h|, all outputs finite).
pub fn smooth_corner(g: &GraphEval, at_tip: bool, eps: f64) -> (f64, f64, f64, bool) {
    let cz = if at_tip { 3.0 } else { 2.0 };
    let p = [2.0, 0.5, cz, 0.5];
    let v = g.eval_f64(&[0.0; 3], &QD_PROBE, &OMEGA_PROBE, eps, &p);
    (
        v.get("alpha")[0],
        (v.get("sat_s")[0] - v.get("sat")[0]).abs(),
        (v.get("h_s")[0] - v.get("h")[0]).abs(),
        all_finite(v.all()),
    )
}

// ---------------------------------------------------------------------------------------------
// Probe 7: Painlevé threshold in μ_k
// ---------------------------------------------------------------------------------------------

/// The Painlevé threshold at a fixed slipping contact state (probe 7).
#[derive(Debug, Clone, PartialEq)]
pub struct PainleveProbe {
    /// μ_k* by bisection on the model's slip (relative bracket width 1e-12).
    pub threshold_bisection: f64,
    /// μ_k* = (1 − margin) nᵀWn / (−nᵀW t̂) from the contact matrices (closed form of the
    /// model's test k = nᵀW(n + μ_k t̂) ≤ margin · nᵀWn).
    pub threshold_closed_form: f64,
    /// (μ_k / μ_k*, λ_n) below the threshold.
    pub below: Vec<(f64, f64)>,
    /// The model's errors at 1.01 μ_k* and at μ_k = 1e6.
    pub above: Vec<(f64, Result<f64, ModelError>)>,
}

/// Probe 7: slip direction t̂ = −T_n W n/|T_n W n| (the direction in which friction reduces the
/// normal mobility fastest), |Δv| = 1e-3 m/s, finger pressed on with 1 N ([`press_torque`]).
pub fn painleve_threshold(q: Vec3) -> anyhow::Result<PainleveProbe> {
    let base = bf_model::fixtures::paper_scene()?;
    let kin0 = base.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let mats = dynamics::contact_matrices(&kin0, base.params())?;
    let n = kin0.contact.n;
    let wn = mats.w * n;
    let t_hat = -(wn - n * n.dot(&wn)).normalize();
    let x = state_with_slip(&base, q, &t_hat, 1e-3)?;
    let kin = base.evaluate(&x)?;
    let tau = press_torque(&kin, 1.0);
    let slip = |mu: f64| -> Result<f64, ModelError> {
        let p = base
            .params()
            .with_coulomb(base.params().mu_s().max(mu), mu)?;
        let m = base.clone().with_params(p);
        m.slip(&x, &tau, None).map(|a| a.force.lambda_n)
    };
    // the direction the model will use (T_n Δv normalised) equals t̂ up to rounding
    let dv = kin.contact.delta_v;
    let t_model = (dv - n * n.dot(&dv)).normalize();
    let margin = base.settings().painleve_margin;
    let ntw = n.dot(&(mats.w * t_model));
    if ntw >= 0.0 {
        bail!("nᵀ W t̂ = {ntw:e} ≥ 0: no Painlevé threshold in this direction");
    }
    let closed = (1.0 - margin) * mats.n_w_n / (-ntw);
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut guard = 0;
    while slip(hi).is_ok() {
        lo = hi;
        hi *= 2.0;
        guard += 1;
        if guard > 60 {
            bail!("no Painlevé error up to μ_k = {hi:e}");
        }
    }
    if slip(lo).is_err() {
        bail!("slip fails already at μ_k = {lo}");
    }
    for _ in 0..200 {
        if hi - lo <= 1e-12 * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if slip(mid).is_ok() {
            lo = mid
        } else {
            hi = mid
        }
    }
    let star = 0.5 * (lo + hi);
    let below = [0.0, 0.5, 0.9, 0.99, 0.999]
        .iter()
        .map(|&f| slip(f * star).map(|l| (f, l)))
        .collect::<Result<Vec<_>, _>>()?;
    let above = vec![(1.01 * star, slip(1.01 * star)), (1e6, slip(1e6))];
    Ok(PainleveProbe {
        threshold_bisection: star,
        threshold_closed_form: closed,
        below,
        above,
    })
}

// ---------------------------------------------------------------------------------------------
// Probe 8: long horizon, energy drift
// ---------------------------------------------------------------------------------------------

/// Free motion over a long horizon (probe 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HorizonRun {
    /// Horizon (s).
    pub t_end: f64,
    /// DOPRI5 rtol (atol = rtol/100).
    pub rtol: f64,
    /// max_t |E(t) − E(0)| / max_t T(t): energy drift relative to the kinetic energy exchanged
    /// (independent of the potential's datum).
    pub drift: f64,
    /// |E(t_end) − E(0)| / max_t T(t).
    pub final_drift: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Events (must be 0: the finger never reaches the ball).
    pub events: usize,
    /// CPU (wall) seconds.
    pub cpu_seconds: f64,
}

/// Initial state of the long-horizon run: the paper finger hanging below its base (q₁ = π puts
/// link 1 along −z), swinging with all three joints; it stays ≥ 1 m away from the ball.
pub const HORIZON_X0: [f64; 9] = [PI + 0.4, 0.5, -0.4, 0.0, 0.8, -0.5, 0.0, 0.0, 0.0];

/// Probe 8: paper finger with μ_v = D = 0 and zero torque, DOPRI5 at `rtol` for `t_end` s.
pub fn long_horizon(t_end: f64, rtol: f64) -> anyhow::Result<HorizonRun> {
    let base = bf_model::fixtures::paper_scene()?;
    let params = base.params().with_viscous(0.0, 0.0)?;
    let model = base.with_params(params);
    let input = PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3])?;
    let sys = BallFinger::new(model, input, BallFingerOptions::default())?;
    let settings = SimSettings {
        rtol,
        atol: rtol * 1e-2,
        // bounded: ~100× what DOPRI5 needs at rtol 1e-10 for this motion
        max_steps: 2_000_000,
        ..SimSettings::default()
    };
    let start = Instant::now();
    let out = simulate(&sys, settings, Mode::Free, 0.0, &HORIZON_X0, t_end)
        .map_err(|f| anyhow!("simulation failed at t = {}: {}", f.t, f.error))?;
    let cpu_seconds = start.elapsed().as_secs_f64();
    let e0 = sys.energy(&HORIZON_X0)?;
    let mut max_dev: f64 = 0.0;
    let mut max_kin: f64 = 0.0;
    let mut last = 0.0;
    for x in &out.trajectory.x {
        let s = State::from_array(x.as_slice().try_into()?);
        let e = sys.model.energy(&s)?;
        if !e.total.is_finite() {
            bail!("NaN energy on the trajectory");
        }
        max_dev = max_dev.max((e.total - e0).abs());
        max_kin = max_kin.max(e.kinetic_finger);
        last = (e.total - e0).abs();
    }
    if (out.t_final - t_end).abs() > 1e-9 * t_end {
        bail!("run stopped at t = {} before t_end = {t_end}", out.t_final);
    }
    Ok(HorizonRun {
        t_end,
        rtol,
        drift: max_dev / max_kin,
        final_drift: last / max_kin,
        steps: out.stats.accepted_steps,
        events: out.stats.events,
        cpu_seconds,
    })
}

// ---------------------------------------------------------------------------------------------
// The report
// ---------------------------------------------------------------------------------------------

fn model_err_outcome(e: &ModelError, expected: fn(&ModelError) -> bool) -> Outcome {
    if expected(e) {
        Outcome::ClearError {
            message: e.to_string(),
        }
    } else {
        Outcome::Failed {
            message: format!("unexpected error: {e}"),
        }
    }
}

/// Run every probe. `quick`: 10 s horizon instead of 100 s (everything else is identical).
/// Each probe is bounded (fixed loop counts, `max_steps` for the simulator).
pub fn run_extremes(quick: bool) -> anyhow::Result<ExtremesReport> {
    let t_all = Instant::now();
    let mut rows = Vec::new();
    let paper = GraphEval::new(&paper_scene_spec()?)?;

    // 1. kernel accuracy at large |q|
    for &qm in &[1.0, 1e3, 1e6] {
        let t = Instant::now();
        let mut r = Rows::new("kernel accuracy (compiled paper vs double-double)");
        let a = kernel_accuracy(&paper, qm);
        let par = format!("|q| = {qm:e} rad");
        r.num(&par, "rel. err. M, same q", a.m, f64::EPSILON);
        r.num(
            &par,
            "rel. err. C q̇ + g (cqd_g), same q",
            a.cqd_g,
            f64::EPSILON,
        );
        r.num(
            &par,
            "rel. err. C q̇ + g (mass_cqd_g), same q",
            a.cqd_g_model,
            f64::EPSILON,
        );
        r.num(&par, "err. h / |r_c|, same q", a.h, f64::EPSILON);
        r.num(&par, "rel. err. J_c, same q", a.j_c, f64::EPSILON);
        r.num(
            &par,
            "rel. err. M, q mod 2π",
            a.reduced[0],
            a.reduction_error,
        );
        r.num(
            &par,
            "rel. err. C q̇ + g, q mod 2π",
            a.reduced[1],
            a.reduction_error,
        );
        r.num(
            &par,
            "err. h / |r_c|, q mod 2π",
            a.reduced[2],
            a.reduction_error,
        );
        r.finish(t, &mut rows);
    }

    // 2. extreme joint velocities
    for &v in &[1e-12, 1.0, 1e3] {
        let t = Instant::now();
        let mut r = Rows::new("joint velocity (C q̇)");
        let a = velocity_extremes(&paper, v);
        let par = format!("|q̇| ~ {v:e} rad/s");
        r.num(&par, "rel. err. C q̇ vs double-double", a.cqd, f64::EPSILON);
        r.num(
            &par,
            "rel. dev. from k² homogeneity",
            a.homogeneity,
            f64::EPSILON,
        );
        r.finish(t, &mut rows);
    }

    // 3. scaled masses / lengths
    for &(km, kl) in &[
        (1e-3, 1.0),
        (1e3, 1.0),
        (1.0, 1e-3),
        (1.0, 1e3),
        (1e-3, 1e3),
    ] {
        let t = Instant::now();
        let mut r = Rows::new("scaled scene (interpreter)");
        let par = format!("mass ×{km:e}, length ×{kl:e}");
        match scaled_scene(&paper, km, kl) {
            Ok(s) => {
                r.num(&par, "rel. err. f64 vs dd: M", s.f64_vs_dd[0], f64::EPSILON);
                r.num(
                    &par,
                    "rel. err. f64 vs dd: C q̇ + g",
                    s.f64_vs_dd[1],
                    f64::EPSILON,
                );
                r.num(
                    &par,
                    "err. f64 vs dd: h / |r_c|",
                    s.f64_vs_dd[2],
                    f64::EPSILON,
                );
                r.num(
                    &par,
                    "λ_min/λ_max of M (SPD if > 0)",
                    s.m_eig_ratio,
                    f64::EPSILON,
                );
                let law = s.law_deviation.iter().copied().fold(0.0, f64_max_nan);
                r.num(
                    &par,
                    "max dev. from similarity laws (M, g, C q̇, h, J_c)",
                    law,
                    f64::EPSILON,
                );
            }
            Err(e) => r.fail(&par, format!("{e:#}")),
        }
        r.finish(t, &mut rows);
    }
    for &k in &[1e-3, 1e3] {
        let t = Instant::now();
        let mut r = Rows::new("scaled scene (interpreter)");
        let par = format!("lengths only ×{k:e}");
        match length_only_mass_law(k) {
            Ok((dev, ratio)) => {
                r.num(&par, "rel. dev. of M from k²·A + B", dev, f64::EPSILON);
                r.num(&par, "λ_min/λ_max of M", ratio, f64::EPSILON);
            }
            Err(e) => r.fail(&par, format!("{e:#}")),
        }
        r.finish(t, &mut rows);
    }
    match human_scene_spec().and_then(|s| GraphEval::new(&s)) {
        Ok(human) => {
            for &k in &[1e-3, 1e3] {
                let t = Instant::now();
                let mut r = Rows::new("scaled link3.mass (compiled human)");
                let par = format!("link3.mass ×{k:e}");
                match human_link3_mass(&human, k) {
                    Ok(h) => {
                        r.num(&par, "rel. err. M vs dd", h.m_vs_dd, f64::EPSILON);
                        r.num(&par, "rel. err. C q̇ + g vs dd", h.cqd_g_vs_dd, f64::EPSILON);
                        r.num(
                            &par,
                            "rel. dev. from affine law in m₃",
                            h.affine_deviation,
                            f64::EPSILON,
                        );
                        r.num(&par, "λ_min/λ_max of M", h.m_eig_ratio, f64::EPSILON);
                        r.num(&par, "|q̈| free motion (rad/s²)", h.qdd_norm, 0.0);
                    }
                    Err(e) => r.fail(&par, format!("{e:#}")),
                }
                r.finish(t, &mut rows);
            }
        }
        Err(e) => {
            let mut r = Rows::new("scaled link3.mass (compiled human)");
            r.fail("human scene", format!("{e:#}"));
            r.finish(Instant::now(), &mut rows);
        }
    }

    // 4. singular configurations
    {
        let t = Instant::now();
        let mut r = Rows::new("singular contact (links 2–3 aligned, touching along their axis)");
        for &d in &[0.0, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1] {
            let par = format!("q₃ = δ = {d:e}");
            match singular_contact(d) {
                Ok(s) => {
                    r.num(
                        &par,
                        "σ_min(J_c) (m)",
                        s.jc_singular_values[0],
                        f64::EPSILON * s.jc_singular_values[2],
                    );
                    r.num(&par, "nᵀWn/‖W‖", s.normal_mobility, f64::EPSILON);
                    match &s.stick {
                        Ok((l, e)) => r.num(&par, "stick λ_n (N), pressed with 1 N", *l, *e),
                        Err(e) => r.push(
                            &par,
                            "stick",
                            model_err_outcome(e, |e| {
                                matches!(e, ModelError::SingularContact { .. })
                            }),
                        ),
                    }
                }
                Err(e) => r.fail(&par, format!("{e:#}")),
            }
        }
        match singular_threshold() {
            Ok(d) => r.num(
                "bisection",
                "δ* where stick stops reporting SingularContact",
                d,
                d * 1e-12,
            ),
            Err(e) => r.fail("bisection", format!("{e:#}")),
        }
        // stretched finger far from the ball: rank loss of J_c without contact
        let par = "paper, q = (0.3, 0, 0), no contact";
        match bf_model::fixtures::paper_scene().and_then(|m| {
            let x = State::new(Vec3::new(0.3, 0.0, 0.0), Vec3::zeros(), Vec3::zeros());
            let kin = m.evaluate(&x)?;
            Ok((
                singular_values(&kin.contact.j_c),
                m.stick(&x, &Vec3::zeros()),
            ))
        }) {
            Ok((sv, st)) => {
                r.num(par, "σ_min(J_c) (m)", sv[0], f64::EPSILON * sv[2]);
                match st {
                    Ok(_) => r.fail(par, "stick accepted a state 1 m away from the ball"),
                    Err(e) => r.push(
                        par,
                        "stick",
                        model_err_outcome(&e, |e| matches!(e, ModelError::NotInContact { .. })),
                    ),
                }
            }
            Err(e) => r.fail(par, e.to_string()),
        }
        r.finish(t, &mut rows);
    }

    // contact configuration for probes 5–7
    let qc = paper_contact_configuration()?;

    // 5. |Δv| → 0
    {
        let t = Instant::now();
        let mut r = Rows::new("slip with |Δv| → 0 (paper, eq. 20/38)");
        let reference = slip_small_dv(qc, 1e-9).map(|p| p.lambda_hint);
        for &s in &[1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
            let par = format!("|Δv| = {s:e} m/s");
            match (slip_small_dv(qc, s), &reference) {
                (Ok(p), Ok(lref)) => {
                    match &p.lambda {
                        Ok(l) => r.num(
                            &par,
                            "|λ| (N), no hint",
                            l.norm(),
                            (l - p.lambda_hint).norm(),
                        ),
                        Err(e) => r.push(
                            &par,
                            "λ, no hint",
                            model_err_outcome(e, |e| {
                                matches!(e, ModelError::UndefinedSlipDirection { .. })
                            }),
                        ),
                    }
                    r.num(
                        &par,
                        "|λ − λ(1e-9)|/|λ|, with hint",
                        (p.lambda_hint - lref).norm() / lref.norm(),
                        f64::EPSILON,
                    );
                    r.num(
                        &par,
                        "eq. 38 residual/(|λ||Δv|)",
                        p.law_residual,
                        f64::EPSILON,
                    );
                    r.num(
                        &par,
                        "angle(λ_∥, Δv) (rad)",
                        p.friction_angle,
                        f64::EPSILON.sqrt(),
                    );
                    r.num(
                        &par,
                        "Slip→Stick fires (1/0)",
                        f64::from(u8::from(p.slip_to_stick)),
                        0.0,
                    );
                }
                (Err(e), _) => r.fail(&par, format!("{e:#}")),
                (_, Err(e)) => r.fail(&par, format!("{e:#}")),
            }
        }
        r.finish(t, &mut rows);
    }

    // 6. ε → 0
    {
        let t = Instant::now();
        let mut r = Rows::new("smooth sat ε → 0 (eq. 58–59)");
        let eps_list = [1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12];
        let qa: [f64; 3] = qc.into();
        for (label, q) in [
            ("interior α", Q_INTERIOR),
            ("saturated α (tip contact)", qa),
        ] {
            let errs: Vec<SmoothError> =
                eps_list.iter().map(|&e| smooth_convergence(q, e)).collect();
            for e in &errs {
                let par = format!("{label} (α = {:.3}), ε = {:e}", e.alpha, e.eps);
                if !e.finite {
                    r.fail(&par, "contact_smooth returned NaN/inf");
                }
                r.num(&par, "|h_ε − h| (m)", e.h, f64::EPSILON);
                r.num(&par, "|p_c,ε − p_c| (m)", e.p_c, f64::EPSILON);
            }
            let hs: Vec<(f64, f64)> = errs.iter().map(|e| (e.eps, e.h)).collect();
            let ps: Vec<(f64, f64)> = errs.iter().map(|e| (e.eps, e.p_c)).collect();
            let min = |v: Vec<f64>| v.into_iter().fold(f64::INFINITY, f64::min);
            r.num(
                label,
                "observed order of h_ε → h (min)",
                min(observed_orders(&hs, 1e-13)),
                0.0,
            );
            r.num(
                label,
                "observed order of p_c,ε → p_c (min)",
                min(observed_orders(&ps, 1e-13)),
                0.0,
            );
        }
        match corner_graph() {
            Ok(g) => {
                for (tip, name) in [(true, "α = 0"), (false, "α = −l")] {
                    let mut corner = Vec::new();
                    for &e in &eps_list {
                        let (alpha, sat_err, h_err, finite) = smooth_corner(&g, tip, e);
                        let par = format!("{name} (α = {alpha:e} exactly), ε = {e:e}");
                        if !finite {
                            r.fail(
                                &par,
                                "contact_smooth graph returned NaN/inf at a saturation corner",
                            );
                        } else {
                            r.num(&par, "|sat_ε − sat| (m)", sat_err, f64::EPSILON);
                            r.num(&par, "|h_ε − h| (m)", h_err, f64::EPSILON);
                        }
                        corner.push((e, sat_err));
                    }
                    let o = observed_orders(&corner, 1e-13);
                    r.num(
                        name,
                        "observed order of sat_ε → sat (min)",
                        o.iter().copied().fold(f64::INFINITY, f64::min),
                        0.0,
                    );
                }
            }
            Err(e) => r.fail("corners", format!("{e:#}")),
        }
        // the model on the interpreter at the exact corner α = 0, down to ε whose square
        // underflows: a number (λ_n = 1 for the pressed, static finger) or a typed error
        for &e in &[1e-12, 1e-100, 1e-160, 1e-200, 1e-300] {
            let par = format!("model at α = 0 exactly, ε = {e:e}");
            match corner_stick(e) {
                Ok(Ok((l, err))) => r.num(&par, "stick λ_n (N), pressed with 1 N", l, err),
                Ok(Err(me)) => r.push(
                    &par,
                    "stick",
                    model_err_outcome(&me, |e| matches!(e, ModelError::NonFinite { .. })),
                ),
                Err(err) => r.fail(&par, format!("{err:#}")),
            }
        }
        // ε = 0 is outside the model's domain: a typed error, not NaN
        match bf_model::fixtures::paper_scene()
            .and_then(|m| m.with_contact_variant(bf_model::ContactVariant::Smooth(0.0)))
        {
            Ok(_) => r.fail("ε = 0 (model)", "the model accepted ε = 0"),
            Err(e) => r.push(
                "ε = 0 (model)",
                "with_contact_variant",
                model_err_outcome(&e, |e| matches!(e, ModelError::InvalidParameter { .. })),
            ),
        }
        r.finish(t, &mut rows);
    }

    // 7. Painlevé
    {
        let t = Instant::now();
        let mut r = Rows::new("large μ_k (Painlevé, Sect. 7)");
        match painleve_threshold(qc) {
            Ok(p) => {
                r.num(
                    "bisection",
                    "threshold μ_k*",
                    p.threshold_bisection,
                    (p.threshold_bisection - p.threshold_closed_form).abs(),
                );
                r.num(
                    "closed form",
                    "(1 − margin) nᵀWn / (−nᵀW t̂)",
                    p.threshold_closed_form,
                    0.0,
                );
                for (f, l) in &p.below {
                    r.num(format!("μ_k = {f} μ_k*"), "slip λ_n (N)", *l, 0.0);
                }
                for (mu, res) in &p.above {
                    let par = format!("μ_k = {mu:.6e}");
                    match res {
                        Ok(l) => r.push(
                            &par,
                            "slip",
                            Outcome::Failed {
                                message: format!(
                                    "no Painlevé error above the threshold (λ_n = {l:e})"
                                ),
                            },
                        ),
                        Err(e) => r.push(
                            &par,
                            "slip",
                            model_err_outcome(e, |e| matches!(e, ModelError::Painleve { .. })),
                        ),
                    }
                }
            }
            Err(e) => r.fail("threshold", format!("{e:#}")),
        }
        r.finish(t, &mut rows);
    }

    // 8. long horizon
    {
        let t_end = if quick { 10.0 } else { 100.0 };
        for &rtol in &[1e-6, 1e-8, 1e-10] {
            let t = Instant::now();
            let mut r = Rows::new("long horizon (free, μ_v = D = τ = 0)");
            let par = format!("{t_end} s, rtol {rtol:e}");
            match long_horizon(t_end, rtol) {
                Ok(h) => {
                    r.num(&par, "max |ΔE| / max T", h.drift, rtol);
                    r.num(&par, "accepted steps", h.steps as f64, 0.0);
                    r.num(&par, "CPU s", h.cpu_seconds, 0.0);
                    if h.events != 0 {
                        r.fail(
                            &par,
                            format!("{} events: the finger reached the ball", h.events),
                        );
                    }
                }
                Err(e) => r.fail(&par, format!("{e:#}")),
            }
            r.finish(t, &mut rows);
        }
    }

    Ok(ExtremesReport {
        rows,
        quick,
        seconds: t_all.elapsed().as_secs_f64(),
    })
}
