//! Study (c), variants of the generated kernels (eq. 22a, 24 and 76–79): `mass_matrix`,
//! `cqd_g` (Lagrangian, Christoffel form), `cqd_g_rnea` (symbolic Newton–Euler) and
//! `mass_cqd_g` of the paper scene with baked constants, with every constant a runtime
//! parameter, with `mul_add` (FMA), and in f32. Error against a double-double evaluation of the
//! same expression graph over random states, versus time per call (in-process timing, median
//! of batches).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use anyhow::{Result, anyhow};
use bf_codegen::dd::Dd;
use bf_codegen::{Scene, SymbolicRobot, interp, kernels};
use bf_generated::{paper, paper_f32, paper_fma, paper_runtime};
use bf_plot::paper::WorkPrecisionSet;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{bar, wp_figure};

/// Kernels compared in part (c) (the variant modules of `bf_generated` emit exactly these).
pub const VARIANT_KERNELS: [&str; 4] = ["mass_matrix", "cqd_g", "cqd_g_rnea", "mass_cqd_g"];

/// Kernel variants of part (c), in table order.
pub const VARIANTS: [&str; 4] = ["f64 baked", "f64 runtime params", "f64 FMA", "f32 baked"];

/// One kernel variant of part (c).
#[derive(Debug, Clone, PartialEq)]
pub struct KernelRow {
    /// Kernel name.
    pub kernel: &'static str,
    /// Variant (one of [`VARIANTS`]).
    pub variant: &'static str,
    /// Median time per call (ns).
    pub ns_per_call: f64,
    /// Largest normwise relative error over the sampled states,
    /// ‖y − y_dd‖∞ / ‖y_dd‖∞, against double-double evaluation of the kernel's graph.
    pub max_rel_error: f64,
    /// Median of the same error over the states.
    pub median_rel_error: f64,
}

type Q = [f64; paper::NQ];

/// `n` states q ∈ [−π, π)³, q̇ ∈ [−3, 3)³, uniform, from a fixed seed (the same in every run).
fn states(n: usize) -> Vec<(Q, Q)> {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_2026);
    (0..n)
        .map(|_| {
            let q: Q = std::array::from_fn(|_| rng.random_range(-PI..PI));
            let qd: Q = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
            (q, qd)
        })
        .collect()
}

/// Double-double values of kernel `name` of `model` at every state.
fn dd_reference(model: &mut SymbolicRobot, name: &str, states: &[(Q, Q)]) -> Result<Vec<Vec<Dd>>> {
    let def = kernels::build_kernel(model, name).map_err(|e| anyhow!("kernel {name}: {e}"))?;
    let ids: Vec<_> = def.output_ids();
    let layout = model.layout;
    let n = layout.nq;
    let mut vars = vec![Dd::new(0.0); layout.n_vars()];
    for (i, p) in model.params.iter().enumerate() {
        vars[layout.param(i) as usize] = Dd::new(p.1);
    }
    Ok(states
        .iter()
        .map(|(q, qd)| {
            for i in 0..n {
                vars[i] = Dd::new(q[i]);
                vars[n + i] = Dd::new(qd[i]);
            }
            interp::eval::<Dd>(&model.g, &ids, &vars)
        })
        .collect())
}

/// (max, median) over states of ‖y − y_dd‖∞ / ‖y_dd‖∞.
fn rel_errors(values: &[Vec<f64>], reference: &[Vec<Dd>]) -> Result<(f64, f64)> {
    let mut errs = Vec::with_capacity(values.len());
    for (y, r) in values.iter().zip(reference) {
        if y.len() != r.len() {
            return Err(anyhow!(
                "kernel output length {} differs from its graph's {}",
                y.len(),
                r.len()
            ));
        }
        let scale = r.iter().map(|v| v.to_f64().abs()).fold(0.0, f64::max);
        let err = y
            .iter()
            .zip(r)
            .map(|(a, b)| (Dd::new(*a) - *b).to_f64().abs())
            .fold(0.0, f64::max);
        errs.push(if scale > 0.0 { err / scale } else { err });
    }
    errs.sort_by(f64::total_cmp);
    let max = errs.last().copied().unwrap_or(f64::NAN);
    let median = errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN);
    Ok((max, median))
}

/// Median over `batches` of the time per call of `f(i)` (i cycling over the states), in ns.
fn time_ns(calls: usize, batches: usize, n_states: usize, mut f: impl FnMut(usize)) -> f64 {
    for i in 0..calls.min(1000) {
        f(i % n_states);
    }
    let mut t: Vec<f64> = (0..batches)
        .map(|_| {
            let start = Instant::now();
            for i in 0..calls {
                f(black_box(i % n_states));
            }
            start.elapsed().as_secs_f64() * 1e9 / calls as f64
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn to32(v: &[f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

/// Flattened outputs of kernel `name` of every variant at `(q, qd)`, in [`VARIANTS`] order.
fn eval_variants(name: &str, q: &Q, qd: &Q) -> Result<[Vec<f64>; 4]> {
    let z = [0.0; 3];
    let missing = || anyhow!("kernel {name} missing in a variant module");
    let base =
        paper::eval_flat(name, q, qd, &z, 0.0, &paper::PARAM_DEFAULTS).ok_or_else(missing)?;
    let rt = paper_runtime::eval_flat(name, q, qd, &z, 0.0, &paper_runtime::PARAM_DEFAULTS)
        .ok_or_else(missing)?;
    let fma = paper_fma::eval_flat(name, q, qd, &z, 0.0, &paper_fma::PARAM_DEFAULTS)
        .ok_or_else(missing)?;
    let f32v = paper_f32::eval_flat(
        name,
        &to32(q),
        &to32(qd),
        &[0.0; 3],
        0.0,
        &paper_f32::PARAM_DEFAULTS,
    )
    .ok_or_else(missing)?
    .into_iter()
    .map(f64::from)
    .collect();
    Ok([base, rt, fma, f32v])
}

/// Time per call of kernel `name` in variant `v` (index into [`VARIANTS`]).
fn time_variant(name: &str, v: usize, states: &[(Q, Q)], calls: usize, batches: usize) -> f64 {
    let n = states.len();
    let s32: Vec<([f32; 3], [f32; 3])> = states.iter().map(|(q, qd)| (to32(q), to32(qd))).collect();
    macro_rules! time_f64 {
        ($m:ident) => {{
            let p = &$m::PARAM_DEFAULTS;
            match name {
                "mass_matrix" => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0; 3]; 3];
                    $m::mass_matrix(black_box(&states[i].0), p, &mut m);
                    black_box(&m);
                }),
                "cqd_g" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0; 3];
                    $m::cqd_g(black_box(&states[i].0), black_box(&states[i].1), p, &mut o);
                    black_box(&o);
                }),
                "cqd_g_rnea" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0; 3];
                    $m::cqd_g_rnea(black_box(&states[i].0), black_box(&states[i].1), p, &mut o);
                    black_box(&o);
                }),
                _ => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0; 3]; 3];
                    let mut o = [0.0; 3];
                    $m::mass_cqd_g(
                        black_box(&states[i].0),
                        black_box(&states[i].1),
                        p,
                        &mut m,
                        &mut o,
                    );
                    black_box((&m, &o));
                }),
            }
        }};
    }
    match v {
        0 => time_f64!(paper),
        1 => time_f64!(paper_runtime),
        2 => time_f64!(paper_fma),
        _ => {
            let p = &paper_f32::PARAM_DEFAULTS;
            match name {
                "mass_matrix" => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0f32; 3]; 3];
                    paper_f32::mass_matrix(black_box(&s32[i].0), p, &mut m);
                    black_box(&m);
                }),
                "cqd_g" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0f32; 3];
                    paper_f32::cqd_g(black_box(&s32[i].0), black_box(&s32[i].1), p, &mut o);
                    black_box(&o);
                }),
                "cqd_g_rnea" => time_ns(calls, batches, n, |i| {
                    let mut o = [0.0f32; 3];
                    paper_f32::cqd_g_rnea(black_box(&s32[i].0), black_box(&s32[i].1), p, &mut o);
                    black_box(&o);
                }),
                _ => time_ns(calls, batches, n, |i| {
                    let mut m = [[0.0f32; 3]; 3];
                    let mut o = [0.0f32; 3];
                    paper_f32::mass_cqd_g(
                        black_box(&s32[i].0),
                        black_box(&s32[i].1),
                        p,
                        &mut m,
                        &mut o,
                    );
                    black_box((&m, &o));
                }),
            }
        }
    }
}

/// Measures every kernel in every variant.
pub(super) fn measure(quick: bool) -> Result<Vec<KernelRow>> {
    let (n_states, calls, batches) = if quick {
        (100, 4_000, 5)
    } else {
        (1000, 40_000, 9)
    };
    let scene = Scene::from_toml_str(paper::SCENE_TOML, "scenes/paper.toml")
        .map_err(|e| anyhow!("paper scene: {e}"))?;
    let mut baked = SymbolicRobot::new(&scene).map_err(|e| anyhow!("paper graph: {e}"))?;
    let all_runtime = Scene {
        runtime_parameters: scene.constants().into_iter().map(|c| c.0).collect(),
        ..scene.clone()
    };
    let mut runtime =
        SymbolicRobot::new(&all_runtime).map_err(|e| anyhow!("runtime-parameter graph: {e}"))?;
    let same_params = runtime.params.len() == paper_runtime::NP
        && runtime
            .params
            .iter()
            .zip(
                paper_runtime::PARAM_NAMES
                    .iter()
                    .zip(&paper_runtime::PARAM_DEFAULTS),
            )
            .all(|(a, (n, v))| a.0 == *n && a.1 == *v);
    if !same_params {
        return Err(anyhow!(
            "bf_generated::paper_runtime was generated with other parameters than the report's graph"
        ));
    }
    let st = states(n_states);
    let pb = bar(VARIANT_KERNELS.len() * VARIANTS.len(), "(c) kernels");
    let mut rows = Vec::new();
    for name in VARIANT_KERNELS {
        pb.set_message(name);
        let ref_baked = dd_reference(&mut baked, name, &st)?;
        let ref_runtime = dd_reference(&mut runtime, name, &st)?;
        let mut values: [Vec<Vec<f64>>; 4] = Default::default();
        for (q, qd) in &st {
            let ys = eval_variants(name, q, qd)?;
            for (v, y) in values.iter_mut().zip(ys) {
                v.push(y);
            }
        }
        for (v, variant) in VARIANTS.iter().enumerate() {
            let reference = if v == 1 { &ref_runtime } else { &ref_baked };
            let (max_rel_error, median_rel_error) = rel_errors(&values[v], reference)?;
            let ns_per_call = time_variant(name, v, &st, calls, batches);
            rows.push(KernelRow {
                kernel: name,
                variant,
                ns_per_call,
                max_rel_error,
                median_rel_error,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    Ok(rows)
}

/// The Markdown of study (c) and its figure `sa_kernels`.
pub(super) fn section(rows: &[KernelRow], fig_dir: &Path) -> Result<String> {
    let mut md = String::new();
    md.push_str(
        "### (c) Generated kernels: variants\n\n\
         Paper scene. Error: ‖y − y_dd‖∞ / ‖y_dd‖∞ against a double-double evaluation of the \
         same expression graph (the runtime-parameter variant against its own graph), over \
         random states q ∈ [−π, π]³, q̇ ∈ [−3, 3]³. `cqd_g` is the Lagrangian (Christoffel) \
         path, `cqd_g_rnea` symbolic Newton–Euler; `mass_cqd_g` returns M and C q̇ + g. FMA: \
         every a·b ± c as `mul_add` (without `-C target-feature=+fma` this is a libm call). \
         f32: arguments, constants and arithmetic in single precision (the error includes \
         rounding the state to f32).\n\n\
         | kernel | variant | ns/call | max rel. error | median rel. error |\n\
         |---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {:.2e} | {:.2e} |",
            r.kernel, r.variant, r.ns_per_call, r.max_rel_error, r.median_rel_error
        );
    }
    let methods: Vec<WorkPrecisionSet> = VARIANTS
        .iter()
        .map(|v| {
            let of_variant: Vec<&KernelRow> = rows.iter().filter(|r| r.variant == *v).collect();
            WorkPrecisionSet {
                name: v.to_string(),
                labels: of_variant.iter().map(|r| r.kernel.to_string()).collect(),
                // Different kernels of one variant are unrelated runs: markers only.
                joined: false,
                // In ns (the x axis below says so): a kernel call takes tens of them.
                time_s: of_variant.iter().map(|r| r.ns_per_call).collect(),
                // A result equal to the double-double one to the last bit has error 0,
                // which a log axis cannot show: clamp to half an ulp.
                error: of_variant
                    .iter()
                    .map(|r| r.max_rel_error.max(f64::EPSILON / 2.0))
                    .collect(),
            }
        })
        .collect();
    let mut fig = wp_figure(
        "Kernels (mass_matrix, cqd_g, cqd_g_rnea, mass_cqd_g): error vs time per call",
        "max ‖y − y_dd‖∞ / ‖y_dd‖∞ [-]",
        &methods,
    )?;
    fig.x_label = "time per call [ns]".into();
    bf_plot::render(&fig, fig_dir.join("sa_kernels"))?;
    md.push_str("\n![kernel error vs time per call](figures/sa_kernels.svg)\n\n");
    Ok(md)
}
