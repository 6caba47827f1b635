//! `ball-finger bench SCENE [--time SECS] [--states N] [--seed S] [--json]`: times every
//! kernel of a scene's module (its `kernels` list and the inverse-dynamics family) over
//! cycling random states, through the compiled kernels of `bf-generated`'s registry when the
//! file is a compiled scene of `scenes/` (as `eval` decides: equal up to comments, description
//! and limits, with the same kernel list) and through the run-time interpreter
//! (`bf_codegen::interp`, the same graphs and f64 operations) for any scene file.
//!
//! Method: a fixed set of random states (seeded; q uniform in the joint limits within [−π, π],
//! or in the 2π of the limits next to it when they lie outside it (`q_range`),
//! q̇ in [−2, 2], ω in [−2, 2]³, q̈ and τ in [−5, 5]) is cycled through in short batches of
//! consecutive calls (about 50 µs each); the reported figure is the median over batches of
//! wall-clock time per call, so batches preempted on a loaded machine do not count.
//! The compiled path calls the registry's `bf_generated::SceneKernels::eval_into` (the scene
//! module's `eval_index_into` behind slices: outputs on the stack, copied into a buffer; no
//! allocation), the interpreted path a compiled tape (`RuntimeKernel::eval_into`: values in
//! a scratch vector kept across calls, outputs into a buffer; no allocation either).
//! The budget `--time` is split evenly over the kernels and the two paths. Before timing,
//! both paths are evaluated at every state and their largest relative difference is reported
//! (the two must agree; a difference above 1e-12 is an error).

use crate::errors::bail_usage;
use std::hint::black_box;
use std::time::Instant;

use crate::cli::BenchArgs;
use anyhow::{Context, Result, bail};
use bf_codegen::Scene;
use bf_codegen::interp::SceneKernels;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Largest relative difference tolerated between the compiled and interpreted outputs.
pub const AGREEMENT_TOL: f64 = 1e-12;

/// One random state.
struct State {
    q: Vec<f64>,
    qd: Vec<f64>,
    omega: [f64; 3],
    eps: f64,
    u: Vec<f64>,
}

/// The compiled kernels of `scene` and its runtime parameters' values (the interpreter's),
/// when the scene is a compiled one up to what does not enter the kernels
/// (`bf_model::registry::compiled_match`, as `eval` decides: comments, description, limits)
/// and lists the kernels `rt` builds; any other scene is timed through the interpreter alone.
fn compiled_for(
    scene: &Scene,
    rt: &SceneKernels,
) -> Option<(&'static bf_generated::SceneKernels, Vec<f64>)> {
    let (entry, p) = bf_model::registry::compiled_match(scene)?;
    let rt_names: Vec<&str> = rt.kernels.iter().map(|k| k.name.as_str()).collect();
    (rt_names.as_slice() == entry.kernels).then_some((entry, p))
}

/// Kernel `k` of the compiled `entry` on one state, outputs into `out`.
fn call_compiled(
    (entry, params): (&bf_generated::SceneKernels, &[f64]),
    k: usize,
    s: &State,
    out: &mut [f64],
) -> Option<usize> {
    (entry.eval_into)(k, &s.q, &s.qd, &s.omega, s.eps, &s.u, params, out)
}

/// One row of the table.
#[derive(Debug, Serialize)]
pub struct Row {
    /// Kernel name.
    pub kernel: String,
    /// Number of output values.
    pub outputs: usize,
    /// Compiled kernel, median ns per call (`None` if the scene is not compiled in).
    pub compiled_ns: Option<f64>,
    /// Interpreted kernel, median ns per call.
    pub interpreted_ns: f64,
    /// interpreted / compiled.
    pub ratio: Option<f64>,
    /// Largest |compiled − interpreted| / max(1, max |interpreted|) over the states.
    pub max_rel_diff: Option<f64>,
}

/// The `--json` output.
#[derive(Debug, Serialize)]
pub struct Bench {
    /// Scene name.
    pub scene: String,
    /// Whether the compiled kernels of `bf-generated` were timed.
    pub compiled: bool,
    /// Number of random states cycled through.
    pub states: usize,
    /// Seed of the states.
    pub seed: u64,
    /// Time budget (s).
    pub time_s: f64,
    /// One row per kernel, in emission order.
    pub kernels: Vec<Row>,
}

/// The interval joint `i` (from 0) of `scene` draws its angles from: its limits within
/// [−π, π] (the whole of [−π, π] without limits); for limits that lie outside [−π, π], the
/// stretch of 2π of them next to it. A range of limits wider than a double holds (±1.7e308
/// in a URDF that means "unlimited") or far beyond ±2²⁰ rad, where the kernels' sine and cosine
/// are NaN, would time NaN paths or fail to draw at all; a revolute joint's stretch is cut to
/// ±2²⁰ rad, and an error when nothing of it is left.
fn q_range(scene: &Scene, i: usize) -> Result<(f64, f64)> {
    let pi = std::f64::consts::PI;
    let l = &scene.links[i];
    let (lo, hi) = (l.q_min.unwrap_or(-pi), l.q_max.unwrap_or(pi));
    let range = if lo > pi {
        (lo, hi.min(lo + 2.0 * pi))
    } else if hi < -pi {
        (lo.max(hi - 2.0 * pi), hi)
    } else {
        (lo.max(-pi), hi.min(pi))
    };
    if l.joint != bf_codegen::spec::JointType::Revolute {
        return Ok(range);
    }
    // Within ±2²⁰ rad the kernels' sine and cosine are defined; an angle beyond would time
    // their NaN path.
    let limit = bf_codegen::trig::ANGLE_RANGE;
    let clamped = (range.0.max(-limit), range.1.min(limit));
    if clamped.0 > clamped.1 {
        bail!(
            "joint {} (q_min {}, q_max {}): every angle within its limits is beyond ±2²⁰ = \
             ±{limit} rad, where the kernels' sine and cosine are not defined; give the limits \
             modulo 2π",
            i + 1,
            crate::cli::shown(lo),
            crate::cli::shown(hi)
        );
    }
    Ok(clamped)
}

fn random_states(scene: &Scene, n: usize, seed: u64) -> Result<Vec<State>> {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let eps = scene.contact.as_ref().map_or(0.01, |c| c.smooth_eps);
    let ranges = (0..scene.links.len())
        .map(|i| q_range(scene, i))
        .collect::<Result<Vec<_>>>()?;
    Ok((0..n)
        .map(|_| {
            let q = ranges
                .iter()
                .map(|&(lo, hi)| if hi > lo { r.random_range(lo..hi) } else { lo })
                .collect();
            let nq = scene.links.len();
            State {
                q,
                qd: (0..nq).map(|_| r.random_range(-2.0..2.0)).collect(),
                omega: std::array::from_fn(|_| r.random_range(-2.0..2.0)),
                eps,
                u: (0..nq).map(|_| r.random_range(-5.0..5.0)).collect(),
            }
        })
        .collect())
}

/// Target length of one timed batch: short against a scheduler time slice, so the median
/// over batches skips the ones a loaded machine preempted.
const BATCH_SECONDS: f64 = 50e-6;

/// Median over batches of ns per call of `call(i)`, i cycling through `0..n_states`, within
/// `budget` seconds (at least three batches). A batch is as many consecutive calls as take
/// about [`BATCH_SECONDS`] (at least one).
fn time_batches(n_states: usize, budget: f64, mut call: impl FnMut(usize)) -> f64 {
    // Calibrate the batch length on one pass over (up to) 16 states.
    let probe = n_states.min(16);
    let t = Instant::now();
    for i in 0..probe {
        call(i);
    }
    let single = t.elapsed().as_secs_f64() / probe as f64;
    let per_batch = ((BATCH_SECONDS / single.max(1e-12)) as usize).clamp(1, 1 << 16);
    let mut per_call = Vec::new();
    let mut next = 0usize;
    let start = Instant::now();
    while per_call.len() < 3 || start.elapsed().as_secs_f64() < budget {
        let t = Instant::now();
        for _ in 0..per_batch {
            call(next);
            next = (next + 1) % n_states;
        }
        per_call.push(t.elapsed().as_secs_f64() * 1e9 / per_batch as f64);
        if per_call.len() >= 1_000_000 {
            break;
        }
    }
    per_call.sort_by(f64::total_cmp);
    per_call[per_call.len() / 2]
}

/// Times every kernel of `scene`.
pub fn bench(scene: &Scene, time: f64, n_states: usize, seed: u64) -> Result<Bench> {
    let rt = SceneKernels::new(scene).context("cannot build the kernels")?;
    let compiled = compiled_for(scene, &rt);
    let states = random_states(scene, n_states, seed)?;
    let vars: Vec<Vec<f64>> = states
        .iter()
        .map(|s| rt.vars(&s.q, &s.qd, s.omega, s.eps, &s.u, None))
        .collect();
    let paths = if compiled.is_some() { 2.0 } else { 1.0 };
    let budget = time / (rt.kernels.len() as f64 * paths);
    let mut rows = Vec::new();
    for (k, kern) in rt.kernels.iter().enumerate() {
        let len: usize = kern.outputs.iter().map(|o| o.len()).sum();
        let mut out = vec![0.0; len];
        let (mut compiled_ns, mut max_rel) = (None, None);
        if let Some((entry, p)) = &compiled {
            let call = |k: usize, s: &State, out: &mut [f64]| call_compiled((entry, p), k, s, out);
            let mut worst: f64 = 0.0;
            for (s, v) in states.iter().zip(&vars) {
                let want = kern.eval(v);
                let got = call(k, s, &mut out)
                    .with_context(|| format!("internal: compiled kernel `{}` failed", kern.name))?;
                let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                for (a, b) in out[..got].iter().zip(&want) {
                    worst = worst.max((a - b).abs() / scale);
                }
            }
            if worst.is_nan() || worst > AGREEMENT_TOL {
                bail!(
                    "kernel `{}` of {}: compiled and interpreted outputs differ by {worst:e} \
                     (relative), more than {AGREEMENT_TOL:e}",
                    kern.name,
                    scene.name
                );
            }
            max_rel = Some(worst);
            compiled_ns = Some(time_batches(states.len(), budget, |i| {
                black_box(call(k, black_box(&states[i]), &mut out));
            }));
        }
        let mut scratch = Vec::new();
        let interpreted_ns = time_batches(states.len(), budget, |i| {
            kern.eval_into(black_box(&vars[i]), &mut scratch, &mut out[..len]);
            black_box(&out);
        });
        rows.push(Row {
            kernel: kern.name.clone(),
            outputs: len,
            compiled_ns,
            interpreted_ns,
            ratio: compiled_ns.map(|c| interpreted_ns / c),
            max_rel_diff: max_rel,
        });
    }
    Ok(Bench {
        scene: scene.name.clone(),
        compiled: compiled.is_some(),
        states: n_states,
        seed,
        time_s: time,
        kernels: rows,
    })
}

/// Largest `--time` budget (s): one hour. The medians settle within seconds; a longer
/// budget only keeps the machine busy (and 1e300 would never end).
pub const MAX_TIME: f64 = 3600.0;

/// Largest `--states`: 100 000 states (some 25 MB for a 7-joint scene) already cycle through
/// more memory than the caches hold, so more would time the memory, not the kernels, and a
/// huge count would exhaust the memory before any timing.
pub const MAX_STATES: usize = 100_000;

/// Run `bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    if !(args.time.is_finite() && args.time > 0.0 && args.time <= MAX_TIME) {
        bail_usage!(
            "--time must be a positive number of seconds, at most {MAX_TIME} (got {})",
            crate::cli::shown(args.time)
        );
    }
    if args.states > MAX_STATES {
        bail_usage!(
            "--states must be at most {MAX_STATES} (got {})",
            args.states
        );
    }
    let (scene, _) = super::load_scene(&args.scene, &args.chain)?;
    let b = bench(&scene, args.time, args.states, args.seed)
        .with_context(|| format!("{}: bench failed", args.scene.display()))?;
    if args.json {
        return crate::outln!("{}", serde_json::to_string_pretty(&b)?);
    }
    let source = if b.compiled {
        "compiled kernels and run-time interpreter"
    } else {
        "run-time interpreter only (the file is not a built-in scene, up to comments, description and limits)"
    };
    crate::outln!(
        "bench {}: {source}; {} random states (seed {}), median wall-clock ns/call over batches",
        b.scene,
        b.states,
        b.seed
    )?;
    crate::outln!(
        "{:<22} {:>8} {:>14} {:>16} {:>9} {:>13}",
        "kernel",
        "outputs",
        "compiled ns",
        "interpreted ns",
        "ratio",
        "max rel diff"
    )?;
    let opt = |v: Option<f64>, digits: usize| match v {
        Some(x) => format!("{x:.digits$}"),
        None => "-".to_string(),
    };
    for r in &b.kernels {
        crate::outln!(
            "{:<22} {:>8} {:>14} {:>16.1} {:>9} {:>13}",
            r.kernel,
            r.outputs,
            opt(r.compiled_ns, 1),
            r.interpreted_ns,
            opt(r.ratio, 1),
            r.max_rel_diff
                .map_or("-".to_string(), |d| format!("{d:.1e}"))
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::q_range;
    use std::f64::consts::PI;

    /// The PUMA 560 scene with the first joint's limits replaced by `limits` (TOML text of
    /// `q_min`/`q_max`, empty for none).
    fn puma(limits: &str) -> bf_codegen::Scene {
        let text = bf_generated::scene_toml("puma560").unwrap().replacen(
            "q_min = \"-160deg\"\nq_max = \"160deg\"",
            limits,
            1,
        );
        assert!(!text.contains("\"160deg\""));
        bf_codegen::Scene::from_toml_str(&text, "puma.toml").unwrap()
    }

    #[test]
    fn angles_are_drawn_within_the_limits_next_to_one_turn() {
        let pi = PI;
        for (limits, want) in [
            ("", (-pi, pi)),
            ("q_min = -1.0\nq_max = 0.5", (-1.0, 0.5)),
            ("q_min = -1.7e308\nq_max = 1.7e308", (-pi, pi)),
            ("q_min = -1e10\nq_max = 2.0", (-pi, 2.0)),
            ("q_min = 4.0\nq_max = 100.0", (4.0, 4.0 + 2.0 * pi)),
            ("q_min = -100.0\nq_max = -5.0", (-5.0 - 2.0 * pi, -5.0)),
            ("q_min = 4.0\nq_max = 5.0", (4.0, 5.0)),
            // A turn that reaches past 2^20 rad is cut there.
            ("q_min = 1048570.0\nq_max = 2e6", (1048570.0, 1048576.0)),
        ] {
            assert_eq!(q_range(&puma(limits), 0).unwrap(), want, "{limits}");
        }
        // Every angle the limits allow is beyond 2^20 rad: no state the kernels can evaluate.
        let err = q_range(&puma("q_min = 1e7\nq_max = 2e7"), 0).unwrap_err();
        assert!(err.to_string().contains("joint 1 (q_min 1e7"), "{err}");
    }
}
