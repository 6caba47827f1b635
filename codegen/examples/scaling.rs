//! How the generated kernels grow with the number of joints: random standard-DH chains of
//! 3 … 20 revolute joints (seeded, so every run sees the same chains), and per chain the
//! operations of every kernel, the generation time, the code size, the `rustc -O` time of the
//! module and the nanoseconds per call of its kernels; at the end the growth exponent b of
//! y ≈ a nᵇ fitted by least squares on log y against log n.
//!
//! ```text
//! cargo run --release -p bf-codegen --example scaling -- [--joints 3,5,7,10,14,20]
//!     [--rustc-max 14] [--out DIR] [--compare-unsplit]
//! ```
//!
//! `--rustc-max N` compiles (and times calls of) only the chains of at most N joints, since
//! `rustc -O` of a large module takes minutes on a loaded machine; `--out` keeps the generated
//! files (default: a directory under the system's temporary directory). Modules are emitted
//! as `generate` emits them (large ones split into a submodule per kernel, so that `rustc`
//! optimises the kernels in parallel, `bf_codegen::ModuleSplit`); `--compare-unsplit` also
//! compiles each chain's module in one piece, before the split one, and prints its `rustc -O`
//! time in a column of its own. CPU times are the
//! process's own (generation) and its waited children's (rustc), read from `/proc/self/stat`,
//! so they do not count time lost to other processes; wall time is printed next to them.
//! Nanoseconds per call are the median of 11 timed batches of random states (min–max in
//! brackets) in a binary compiled with `rustc -O`: a measurement for the growth with n, not a
//! replacement for the criterion benches of the shipped scenes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[path = "../tests/common/chain.rs"]
mod chain;

/// The kernels of every chain's module: those whose cost the dynamics algorithms set.
const KERNELS: [&str; 6] = [
    "tip_jacobian",
    "mass_matrix",
    "gravity",
    "mass_cqd_g",
    "inverse_dynamics",
    "forward_dynamics",
];

/// User and system CPU seconds of this process and of its waited children (`/proc/self/stat`
/// fields 14–17, in clock ticks of 1/100 s); `None` off Linux.
fn cpu_seconds() -> Option<(f64, f64)> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name in parentheses may hold spaces: count fields after the last ')'.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<f64> = rest
        .split(' ')
        .skip(11)
        .take(4)
        .map(|x| x.parse().unwrap_or(f64::NAN))
        .collect();
    (f.len() == 4).then(|| ((f[0] + f[1]) / 100.0, (f[2] + f[3]) / 100.0))
}

/// A binary that times every kernel of module `{module}.rs` and prints `name ns lo hi` lines.
fn bench_main(module: &str) -> String {
    let mut calls = String::new();
    for k in KERNELS {
        let call = match k {
            "tip_jacobian" => {
                "let mut a = [[0.0; m::NQ]; 3]; let mut b = a; \
                 m::tip_jacobian(&s.q, &p, &mut a, &mut b); a[0][0] + b[0][0]"
            }
            "mass_matrix" => {
                "let mut o = [[0.0; m::NQ]; m::NQ]; m::mass_matrix(&s.q, &p, &mut o); o[0][0]"
            }
            "gravity" => "let mut o = [0.0; m::NQ]; m::gravity(&s.q, &p, &mut o); o[0]",
            "mass_cqd_g" => {
                "let mut o = [[0.0; m::NQ]; m::NQ]; let mut v = [0.0; m::NQ]; \
                 m::mass_cqd_g(&s.q, &s.qd, &p, &mut o, &mut v); o[0][0] + v[0]"
            }
            "inverse_dynamics" => {
                "let mut o = [0.0; m::NQ]; m::inverse_dynamics(&s.q, &s.qd, &s.x, &p, &mut o); o[0]"
            }
            _ => {
                "let mut o = [0.0; m::NQ]; m::forward_dynamics(&s.q, &s.qd, &s.x, &p, &mut o); o[0]"
            }
        };
        let _ = writeln!(calls, "    time(\"{k}\", &states, |s| {{ {call} }});");
    }
    format!(
        "#[allow(clippy::all, unused_variables, unused_parens, dead_code)]\n\
         mod m {{ include!(\"{module}.rs\"); }}\n\
         struct S {{ q: [f64; m::NQ], qd: [f64; m::NQ], x: [f64; m::NQ] }}\n\
         const P: [f64; m::NP] = m::PARAM_DEFAULTS;\n\
         fn time(name: &str, states: &[S], f: impl Fn(&S) -> f64) {{\n\
         \x20   let mut reps = 1usize;\n\
         \x20   loop {{\n\
         \x20       let t = std::time::Instant::now();\n\
         \x20       for _ in 0..reps {{ for s in states {{ std::hint::black_box(f(std::hint::black_box(s))); }} }}\n\
         \x20       if t.elapsed().as_secs_f64() > 0.02 {{ break; }}\n\
         \x20       reps *= 2;\n\
         \x20   }}\n\
         \x20   let mut ns: Vec<f64> = (0..11).map(|_| {{\n\
         \x20       let t = std::time::Instant::now();\n\
         \x20       for _ in 0..reps {{ for s in states {{ std::hint::black_box(f(std::hint::black_box(s))); }} }}\n\
         \x20       t.elapsed().as_secs_f64() * 1e9 / (reps * states.len()) as f64\n\
         \x20   }}).collect();\n\
         \x20   ns.sort_by(|a, b| a.total_cmp(b));\n\
         \x20   println!(\"{{name}} {{}} {{}} {{}}\", ns[5], ns[0], ns[10]);\n\
         }}\n\
         fn main() {{\n\
         \x20   let mut seed = 1u64;\n\
         \x20   let mut r = || {{ seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); ((seed >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0 }};\n\
         \x20   let states: Vec<S> = (0..64).map(|_| S {{ q: std::array::from_fn(|_| r()), qd: std::array::from_fn(|_| r()), x: std::array::from_fn(|_| r()) }}).collect();\n\
         \x20   let p = P;\n\
         {calls}}}\n"
    )
}

/// Compiles `{module}_bench.rs` in `dir` with `rustc -O`: (wall s, CPU s of rustc), or the
/// compiler's message.
fn compile(dir: &Path, module: &str) -> Result<(f64, Option<f64>, PathBuf), String> {
    let src = dir.join(format!("{module}_bench.rs"));
    let exe = dir.join(format!("{module}_bench"));
    let before = cpu_seconds();
    let t = Instant::now();
    let out = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .args(["-O", "--edition", "2021", "-o"])
        .arg(&exe)
        .arg(&src)
        .output()
        .map_err(|e| format!("cannot run rustc: {e}"))?;
    let wall = t.elapsed().as_secs_f64();
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let cpu = before.zip(cpu_seconds()).map(|(a, b)| b.1 - a.1);
    Ok((wall, cpu, exe))
}

/// Least-squares slope of log y on log x.
fn exponent(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|&v| libm::log(v)).collect();
    let ly: Vec<f64> = y.iter().map(|&v| libm::log(v)).collect();
    let k = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / k, ly.iter().sum::<f64>() / k);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// One chain's figures: operations per kernel, generation s (wall), code bytes, rustc s wall
/// and CPU.
type Row = (Vec<usize>, f64, f64, f64, Option<f64>);

struct Args {
    joints: Vec<usize>,
    rustc_max: usize,
    out: PathBuf,
    compare_unsplit: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        joints: vec![3, 5, 7, 10, 14, 20],
        rustc_max: 14,
        out: std::env::temp_dir().join("bf-scaling"),
        compare_unsplit: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--compare-unsplit" {
            a.compare_unsplit = true;
            continue;
        }
        let val = it
            .next()
            .ok_or_else(|| format!("option `{flag}` needs a value"))?;
        match flag.as_str() {
            "--joints" => {
                a.joints = val
                    .split(',')
                    .map(|x| match x.trim().parse::<usize>() {
                        Ok(n) if (1..=64).contains(&n) => Ok(n),
                        _ => Err(format!("`--joints`: `{x}` is not a joint count in 1..=64")),
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--rustc-max" => {
                a.rustc_max = val
                    .parse()
                    .map_err(|_| format!("`--rustc-max`: `{val}` is not a joint count"))?;
            }
            "--out" => a.out = PathBuf::from(val),
            _ => {
                return Err(format!(
                    "unknown option `{flag}` (--joints, --rustc-max, --out, --compare-unsplit)"
                ));
            }
        }
    }
    Ok(a)
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create `{}`: {e}", args.out.display()))?;
    let mut ns_f = Vec::new();
    let mut rows: Vec<Row> = Vec::new();
    let unsplit_head = if args.compare_unsplit {
        " unsplit: rustc -O s wall (CPU) |"
    } else {
        ""
    };
    println!(
        "| n | {} | generate s (CPU) | code bytes | rustc -O s wall (CPU) |{unsplit_head}",
        KERNELS.map(|k| format!("`{k}` ops")).join(" | ")
    );
    println!(
        "|---|{}---|---|---|{}",
        "---|".repeat(KERNELS.len()),
        if args.compare_unsplit { "---|" } else { "" }
    );
    let mut timings = String::new();
    for &n in &args.joints {
        let text = chain::chain_scene(n, &KERNELS);
        let path = args.out.join(format!("chain{n}.toml"));
        let scene = bf_codegen::Scene::from_toml_str(&text, &path.display().to_string())
            .map_err(|e| format!("chain {n}: {e}"))?;
        let c0 = cpu_seconds();
        let generated =
            bf_codegen::generate(&scene, &text).map_err(|e| format!("chain {n}: {e}"))?;
        let gen_cpu = c0.zip(cpu_seconds()).map(|(a, b)| b.0 - a.0);
        let ops: Vec<usize> = KERNELS
            .iter()
            .map(|k| {
                generated
                    .report
                    .kernels
                    .iter()
                    .find(|r| r.name == *k)
                    .map_or(0, |r| r.ops.total())
            })
            .collect();
        let write = |name: String, body: &str| {
            std::fs::write(args.out.join(&name), body).map_err(|e| format!("{name}: {e}"))
        };
        let module = format!("chain{n}");
        write(format!("{module}.rs"), &generated.code)?;
        write(format!("{module}_bench.rs"), &bench_main(&module))?;
        let opt = |x: Option<f64>| x.map_or("?".into(), |v| format!("{v:.2}"));
        let mut unsplit = String::new();
        if args.compare_unsplit && n <= args.rustc_max {
            let single = format!("chain{n}_unsplit");
            let code = bf_codegen::generate_split(
                &scene,
                &text,
                &Default::default(),
                bf_codegen::ModuleSplit::Never,
            )
            .map_err(|e| format!("chain {n}: {e}"))?
            .code;
            write(format!("{single}.rs"), &code)?;
            write(format!("{single}_bench.rs"), &bench_main(&single))?;
            let (wall, cpu, _) = compile(&args.out, &single)?;
            unsplit = format!(" {wall:.1} ({}) |", opt(cpu));
        }
        let (rs_wall, rs_cpu) = if n <= args.rustc_max {
            let (wall, cpu, exe) = compile(&args.out, &module)?;
            let out = Command::new(&exe)
                .output()
                .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
            for line in String::from_utf8_lossy(&out.stdout).lines() {
                let f: Vec<&str> = line.split(' ').collect();
                if let [k, med, lo, hi] = f.as_slice() {
                    let p = |x: &str| x.parse::<f64>().unwrap_or(f64::NAN);
                    let _ = writeln!(
                        timings,
                        "| {n} | `{k}` | {:.0} [{:.0}, {:.0}] |",
                        p(med),
                        p(lo),
                        p(hi)
                    );
                    if *k == "forward_dynamics" {
                        ns_f.push((n as f64, p(med)));
                    }
                }
            }
            (wall, cpu)
        } else {
            (f64::NAN, None)
        };
        println!(
            "| {n} | {} | {:.2} ({}) | {} | {} |{unsplit}",
            ops.iter()
                .map(|o| o.to_string())
                .collect::<Vec<_>>()
                .join(" | "),
            generated.report.seconds,
            opt(gen_cpu),
            generated.code.len(),
            if rs_wall.is_nan() {
                "not compiled".into()
            } else {
                format!("{rs_wall:.1} ({})", opt(rs_cpu))
            }
        );
        rows.push((
            ops,
            generated.report.seconds,
            generated.code.len() as f64,
            rs_wall,
            rs_cpu,
        ));
    }
    println!(
        "\nns per call (median of 11 batches [min, max]):\n\n| n | kernel | ns |\n|---|---|---|"
    );
    print!("{timings}");
    let ns: Vec<f64> = args.joints.iter().map(|&n| n as f64).collect();
    if ns.len() < 2 {
        // A growth exponent needs two chain lengths at least.
        return Ok(());
    }
    println!(
        "\nfitted exponent b of y ≈ a nᵇ over n = {:?}:",
        args.joints
    );
    for (k, name) in KERNELS.iter().enumerate() {
        let y: Vec<f64> = rows.iter().map(|r| r.0[k] as f64).collect();
        println!("  `{name}` operations: {:.2}", exponent(&ns, &y));
    }
    let generated: Vec<f64> = rows.iter().map(|r| r.1).collect();
    println!("  generation time (wall): {:.2}", exponent(&ns, &generated));
    let bytes: Vec<f64> = rows.iter().map(|r| r.2).collect();
    println!("  code bytes: {:.2}", exponent(&ns, &bytes));
    let compiled: Vec<(f64, f64)> = ns
        .iter()
        .zip(&rows)
        .filter_map(|(&n, r)| r.4.or(Some(r.3)).filter(|t| t.is_finite()).map(|t| (n, t)))
        .collect();
    if compiled.len() > 1 {
        let (x, y): (Vec<f64>, Vec<f64>) = compiled.into_iter().unzip();
        println!("  rustc -O CPU time: {:.2}", exponent(&x, &y));
    }
    if ns_f.len() > 1 {
        let (x, y): (Vec<f64>, Vec<f64>) = ns_f.into_iter().unzip();
        println!("  `forward_dynamics` ns per call: {:.2}", exponent(&x, &y));
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("scaling: {e}");
        std::process::exit(1);
    }
}
