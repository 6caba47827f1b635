//! Probe 3, scaled masses and lengths (eq. 22a, 22b, 4, 7): the paper scene with masses and
//! lengths scaled by 1e±3 through the interpreter (f64 vs double-double, M SPD, and the exact
//! similarity laws M ∝ k_m k_L², g ∝ k_m k_L, h, J_c ∝ k_L); lengths alone (M = k² A + B,
//! translational and rotational parts of eq. 22a); and the compiled human scene with its
//! runtime parameter `link3.mass` scaled (M affine in m₃).

use std::time::Instant;

use anyhow::Context;
use bf_codegen::spec::{InertiaSpec, Scene};
use bf_model::{HumanKernels, Model, State, Vec3};

use super::graph_eval::{GraphEval, human_scene_spec, paper_scene_spec};
use super::numerics::{flat3, rel_err, sym_eigenvalues};
use super::report::{ExtremesRow, Rows};
use super::states::{OMEGA_PROBE, QD_PROBE};
use crate::pipeline::verify::nan_max;

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

/// The report rows of probe 3: five mass/length scalings, lengths alone ×1e±3, and the human
/// scene's `link3.mass` ×1e±3.
pub(super) fn report(paper: &GraphEval, rows: &mut Vec<ExtremesRow>) {
    similarity_rows(paper, rows);
    length_only_rows(rows);
    human_mass_rows(rows);
}

/// Masses and lengths scaled together (interpreter, vs double-double and the similarity laws).
fn similarity_rows(paper: &GraphEval, rows: &mut Vec<ExtremesRow>) {
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
        match scaled_scene(paper, km, kl) {
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
                let law = s.law_deviation.iter().copied().fold(0.0, nan_max);
                r.num(
                    &par,
                    "max dev. from similarity laws (M, g, C q̇, h, J_c)",
                    law,
                    f64::EPSILON,
                );
            }
            Err(e) => r.fail(&par, format!("{e:#}")),
        }
        r.finish(t, rows);
    }
}

/// Lengths alone scaled: M = k² A + B.
fn length_only_rows(rows: &mut Vec<ExtremesRow>) {
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
        r.finish(t, rows);
    }
}

/// The compiled human scene with `link3.mass` scaled.
fn human_mass_rows(rows: &mut Vec<ExtremesRow>) {
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
                r.finish(t, rows);
            }
        }
        Err(e) => {
            let mut r = Rows::new("scaled link3.mass (compiled human)");
            r.fail("human scene", format!("{e:#}"));
            r.finish(Instant::now(), rows);
        }
    }
}
