//! `ball-finger verify appendix`: the paper's Appendix A/B entries as printed vs derived and
//! the misprints ([`crate::paper::appendix`]); the status is non-zero when a derivation fails.
//!
//! Also the run-time verification of the compiled `paper` kernels, reported by
//! `ball-finger paper`: compiled code against the generator's interpreter (same expression
//! graph, independent evaluation path), M symmetric positive definite (eq. 22a) and Ṁ − 2C
//! skew-symmetric (Christoffel form of C, eq. 76), at pseudo-random states.

use anyhow::Result;
use bf_codegen::{EvalValue, Scene};
use bf_generated::paper as k;
use std::fmt::Write as _;

/// Runs `verify`: prints the appendix table and the misprints on stdout.
pub fn run(a: &crate::cli::VerifyArgs) -> Result<()> {
    match a.what.as_str() {
        "appendix" => {
            let entries = crate::paper::appendix::check_appendix()?;
            crate::outln!("{}", crate::paper::appendix::markdown(&entries)?)
        }
        other => crate::errors::bail_usage!("unknown verification `{other}`; known: appendix"),
    }
}

/// A tiny deterministic generator (xorshift64*), so the report is reproducible without a
/// dependency on `rand` in the binary.
pub struct Rng(u64);

impl Rng {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let u = (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
}

fn flat(v: &EvalValue) -> Vec<f64> {
    match v {
        EvalValue::Scalar(x) => vec![*x],
        EvalValue::Vector(x) => x.clone(),
        EvalValue::Matrix(m) => m.concat(),
    }
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Leading principal minors of a symmetric 3×3 matrix; all positive ⇔ positive definite.
pub fn minors3(m: &[[f64; 3]; 3]) -> [f64; 3] {
    let d1 = m[0][0];
    let d2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let d3 = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    [d1, d2, d3]
}

/// Check the compiled paper kernels at `n` states; `tick` is called once per state.
/// Returns a markdown section; an error if any check fails (a failed check is a bug).
pub fn verify_paper_scene(n: usize, mut tick: impl FnMut()) -> Result<String> {
    let scene = Scene::from_toml_str(k::SCENE_TOML, "scenes/paper.toml")?;
    let p = &k::PARAM_DEFAULTS;
    let mut rng = Rng::new(0x5eed);
    let (mut d_m, mut d_c, mut d_g, mut d_jc) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut min_minor, mut max_skew, mut max_sym) = (f64::INFINITY, 0.0f64, 0.0f64);
    for _ in 0..n {
        let q = [0; 3].map(|_| rng.uniform(-3.0, 3.0));
        let qd = [0; 3].map(|_| rng.uniform(-2.0, 2.0));
        let omega = [0; 3].map(|_| rng.uniform(-1.0, 1.0));
        let eps = scene.contact.as_ref().map_or(0.01, |c| c.smooth_eps);
        let reference = bf_codegen::eval_all(&scene, &q, &qd, omega, eps)?;
        let get = |name: &str| reference.get(name).map(flat).unwrap_or_default();
        let mut m = [[0.0; 3]; 3];
        k::mass_matrix(&q, p, &mut m);
        let mut c = [[0.0; 3]; 3];
        k::coriolis_matrix(&q, &qd, p, &mut c);
        let mut g = [0.0; 3];
        k::gravity(&q, p, &mut g);
        let mut con = k::Contact::default();
        k::contact(&q, &qd, &omega, p, &mut con);
        d_m = d_m.max(max_abs_diff(&m.concat(), &get("M")));
        d_c = d_c.max(max_abs_diff(&c.concat(), &get("C")));
        d_g = d_g.max(max_abs_diff(&g, &get("g")));
        d_jc = d_jc.max(max_abs_diff(&con.j_c.concat(), &get("J_c")));
        for v in minors3(&m) {
            min_minor = min_minor.min(v);
        }
        let mut dm = [[[0.0; 3]; 3]; 3];
        k::dmass_dq(&q, p, &mut dm);
        for i in 0..3 {
            for j in 0..3 {
                max_sym = max_sym.max((m[i][j] - m[j][i]).abs());
                let mdot = |a: usize, b: usize| (0..3).map(|l| dm[l][a][b] * qd[l]).sum::<f64>();
                let n_ij = mdot(i, j) - 2.0 * c[i][j];
                let n_ji = mdot(j, i) - 2.0 * c[j][i];
                max_skew = max_skew.max((n_ij + n_ji).abs());
            }
        }
        tick();
    }
    let ok = d_m < 1e-12 && d_c < 1e-12 && d_g < 1e-12 && d_jc < 1e-12;
    anyhow::ensure!(
        ok && min_minor > 0.0 && max_sym == 0.0 && max_skew < 1e-12,
        "kernel verification failed: |ΔM| {d_m:e}, |ΔC| {d_c:e}, |Δg| {d_g:e}, |ΔJ_c| {d_jc:e}, \
         min minor {min_minor:e}, asym {max_sym:e}, skew {max_skew:e}"
    );
    let mut s = String::new();
    writeln!(
        s,
        "{n} pseudo-random states of the `paper` scene (q ∈ [−3, 3]³ rad, q̇ ∈ [−2, 2]³ rad/s):\n"
    )?;
    writeln!(s, "| check | worst value over the states |\n|---|---|")?;
    writeln!(
        s,
        "| compiled vs interpreter, max abs diff of M | {d_m:.2e} |"
    )?;
    writeln!(
        s,
        "| compiled vs interpreter, max abs diff of C | {d_c:.2e} |"
    )?;
    writeln!(
        s,
        "| compiled vs interpreter, max abs diff of g | {d_g:.2e} |"
    )?;
    writeln!(
        s,
        "| compiled vs interpreter, max abs diff of J_c | {d_jc:.2e} |"
    )?;
    writeln!(s, "| M − Mᵀ, max abs entry | {max_sym:.2e} |")?;
    writeln!(
        s,
        "| smallest leading principal minor of M (> 0 ⇔ SPD) | {min_minor:.3e} |"
    )?;
    writeln!(
        s,
        "| (Ṁ − 2C) + (Ṁ − 2C)ᵀ, max abs entry (skew-symmetry) | {max_skew:.2e} |"
    )?;
    Ok(s)
}
