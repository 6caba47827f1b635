//! `no_std` modules ([`bf_codegen::EmitSettings::no_std`]): the paper scene (f64, with the
//! contact kernels and their square roots, and f32) and a URDF arm (the UR5-like arm of the
//! test kit, f64) are compiled by `rustc --edition 2021` inside a `#![no_std]` library that
//! denies warnings, then called from a small std program linked against it. Checked:
//! - a copy of the arm's module with every kernel in a submodule of its own
//!   ([`bf_codegen::ModuleSplit::All`], the form of large modules) compiles as well and gives
//!   the arm's numbers bit for bit;
//! - every kernel of every module against the interpreter (`SceneKernels`, the same graphs in
//!   std f64): f64 to 1e-13 relative to the output's largest entry, f32 to 2e-4;
//! - the modules' own square root equals `f64::sqrt` bit for bit (random, subnormal, huge);
//! - their sine and cosine are within 1 ulp of the double-double reference next to multiples
//!   of π/2 (the lanes the no_std fallback reduces) and equal to `f64::sin_cos` within 1 ulp on
//!   random arguments up to 1e6 rad; beyond 2²⁰ rad and for non-finite x they are NaN;
//! - f32 sine, cosine and root are the f64 values rounded once (so within 1 ulp of f32).
//!
//! `rustc` is `$RUSTC` or the one on `PATH` (where Cargo is, it is).

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

use std::path::{Path, PathBuf};
use std::process::Command;

use bf_codegen::dd::{self, Dd};
use bf_codegen::interp::SceneKernels;
use bf_codegen::{EmitSettings, FloatTy, ModuleSplit, Scene};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn rustc() -> String {
    std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into())
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// One module of the test: its name, scene (kernel list set), scene text and float type.
struct Module {
    name: &'static str,
    scene: Scene,
    text: String,
    float: FloatTy,
    split: ModuleSplit,
}

fn modules() -> Vec<Module> {
    let (paper, paper_text) =
        Scene::load_with_text(root().join("scenes/paper.toml"), &Default::default()).unwrap();
    let arm_path = root().join("testkit/tests/urdf/ur5_like.urdf");
    let (mut arm, arm_text) = Scene::load_with_text(&arm_path, &Default::default()).unwrap();
    arm.kernels = [
        "mass_cqd_g",
        "forward_dynamics",
        "tip_jacobian",
        "potential",
    ]
    .map(String::from)
    .to_vec();
    let mut paper_small = paper.clone();
    paper_small.kernels = ["mass_cqd_g", "gravity", "contact_smooth"]
        .map(String::from)
        .to_vec();
    vec![
        Module {
            name: "paper",
            scene: paper,
            text: paper_text.clone(),
            float: FloatTy::F64,
            split: ModuleSplit::Auto,
        },
        Module {
            name: "paper_f32",
            scene: paper_small,
            text: paper_text,
            float: FloatTy::F32,
            split: ModuleSplit::Auto,
        },
        Module {
            name: "arm",
            scene: arm.clone(),
            text: arm_text.clone(),
            float: FloatTy::F64,
            split: ModuleSplit::Auto,
        },
        Module {
            name: "arm_split",
            scene: arm,
            text: arm_text,
            float: FloatTy::F64,
            split: ModuleSplit::All,
        },
    ]
}

/// The state every kernel is evaluated at: (q, qd, omega, eps, u).
fn state(nq: usize) -> (Vec<f64>, Vec<f64>, [f64; 3], f64, Vec<f64>) {
    let q: Vec<f64> = (0..nq).map(|i| 0.3 + 0.4 * i as f64).collect();
    let qd: Vec<f64> = (0..nq).map(|i| 0.5 - 0.3 * i as f64).collect();
    let u: Vec<f64> = (0..nq).map(|i| 0.2 * (i as f64 + 1.0)).collect();
    (q, qd, [0.4, -1.2, 0.7], 0.01, u)
}

/// The std driver: prints every kernel of every module at [`state`], then the math probes of
/// the arguments in `probes.txt` (one f64 bit pattern per line, hex).
fn driver(mods: &[Module]) -> String {
    let mut s = String::from(
        "extern crate nostd_kernels as k;\nfn main() {\n    let probes: Vec<f64> = \
         std::fs::read_to_string(std::env::args().nth(1).unwrap()).unwrap().lines()\
         .map(|l| f64::from_bits(u64::from_str_radix(l, 16).unwrap())).collect();\n",
    );
    for m in mods {
        let (q, qd, omega, eps, u) = state(m.scene.nq());
        let ty = match m.float {
            FloatTy::F64 => "f64",
            FloatTy::F32 => "f32",
        };
        let arr = |v: &[f64]| {
            let items: Vec<String> = v.iter().map(|x| format!("{x:?} as {ty}")).collect();
            format!("[{}]", items.join(", "))
        };
        s.push_str(&format!(
            "    {{ use k::{n}::*; let (q, qd, omega, u) = ({}, {}, {}, {});\n\
             for (i, name) in KERNELS.iter().enumerate() {{ let mut out = vec![0.0 as {ty}; 4096];\n\
             let len = eval_index_into(i, &q, &qd, &omega, {eps:?} as {ty}, &u, &PARAM_DEFAULTS, &mut out).unwrap();\n\
             let v: Vec<String> = out[..len].iter().map(|x| format!(\"{{:?}}\", *x as f64)).collect();\n\
             println!(\"kernel {n} {{name}} {{}}\", v.join(\" \")); }} }}\n",
            arr(&q),
            arr(&qd),
            arr(&omega),
            arr(&u),
            n = m.name,
        ));
    }
    s.push_str(
        "    for x in probes {\n\
         let (s, c) = k::paper::probe_sin_cos(x);\n\
         let r = k::paper::probe_sqrt(x);\n\
         let (s32, c32) = k::paper_f32::probe_sin_cos(x as f32);\n\
         let r32 = k::paper_f32::probe_sqrt(x as f32);\n\
         println!(\"probe {:x} {:x} {:x} {:x} {:x} {:x} {:x}\", x.to_bits(), s.to_bits(), c.to_bits(), \
         r.to_bits(), s32.to_bits(), c32.to_bits(), r32.to_bits());\n    }\n}\n",
    );
    s
}

/// |got − exact| in units of the last place of the exact value rounded to f64.
fn ulps(got: f64, exact: Dd) -> f64 {
    let a = exact.to_f64().abs();
    let ulp = if a < f64::MIN_POSITIVE {
        f64::from_bits(1)
    } else {
        f64::from_bits(a.to_bits() + 1) - a
    };
    ((Dd::new(got) - exact).to_f64() / ulp).abs()
}

fn ulps_f64(a: f64, b: f64) -> f64 {
    ulps(a, Dd::new(b))
}

fn probes() -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut xs: Vec<f64> = (0..2000)
        .map(|_| rng.random_range(-1.0..1.0) * libm::pow(10f64, rng.random_range(-8.0..6.0)))
        .collect();
    // Next to multiples of π/2 (the no_std fallback's lanes), up to k = 600 000.
    for k in [1i64, 2, 3, 4, 7, 100, 1001, 65_536, 600_000, -3, -777] {
        let x = (Dd::new(k as f64) * dd::PI * Dd::new(0.5)).to_f64();
        for d in -3i64..=3 {
            xs.push(f64::from_bits((x.to_bits() as i64 + d) as u64));
        }
    }
    xs.extend([0.0, -0.0, 1e-310, 5e-324, f64::MAX, 1e300, 2.0, 4.0]);
    xs
}

#[test]
fn no_std_modules_compile_and_agree_with_std() {
    let dir = TempDir::fresh(
        std::env::temp_dir().join(format!("bf-codegen-nostd-{}", std::process::id())),
    );
    let mods = modules();
    let mut lib = String::from("#![no_std]\n#![deny(warnings)]\n");
    for m in &mods {
        let opts = EmitSettings {
            float: m.float,
            fma: false,
            no_std: true,
        };
        let code = bf_codegen::generate_split(&m.scene, &m.text, &opts, m.split)
            .unwrap()
            .code;
        assert_eq!(
            code.matches("\nmod kernel_").count(),
            if m.split == ModuleSplit::All {
                m.scene.kernels.len()
            } else {
                0
            },
            "{}: kernels in submodules",
            m.name
        );
        assert!(
            !code.replace("core::", "").contains("std::"),
            "{}: names std",
            m.name
        );
        std::fs::write(dir.join(format!("{}.rs", m.name)), &code).unwrap();
        let (ty, sc) = match m.float {
            FloatTy::F64 => ("f64", "sin_cos"),
            FloatTy::F32 => ("f32", "sin_cos_f32"),
        };
        lib.push_str(&format!(
            "#[allow(unused_variables, unused_parens, clippy::all)]\npub mod {n} {{\n    \
             include!(\"{n}.rs\");\n    \
             pub fn probe_sin_cos(x: {ty}) -> ({ty}, {ty}) {{ {sc}(x) }}\n    \
             pub fn probe_sqrt(x: {ty}) -> {ty} {{ KernelMath::sqrt(x) }}\n}}\n",
            n = m.name
        ));
    }
    std::fs::write(dir.join("lib.rs"), lib).unwrap();
    std::fs::write(dir.join("main.rs"), driver(&mods)).unwrap();
    run(Command::new(rustc())
        .current_dir(&dir)
        .args([
            "--crate-type",
            "lib",
            "--edition",
            "2021",
            "-C",
            "opt-level=1",
        ])
        .args(["--crate-name", "nostd_kernels", "lib.rs"]));
    run(Command::new(rustc())
        .current_dir(&dir)
        .args(["--edition", "2021", "-C", "opt-level=1", "-L", "."])
        .args(["--extern", "nostd_kernels=libnostd_kernels.rlib", "main.rs"]));
    let xs = probes();
    let list: Vec<String> = xs.iter().map(|x| format!("{:x}", x.to_bits())).collect();
    std::fs::write(dir.join("probes.txt"), list.join("\n")).unwrap();
    let out = run(Command::new(dir.join("main"))
        .current_dir(&dir)
        .arg("probes.txt"));

    // The split arm module computes exactly what the arm module does.
    let lines_of = |module: &str| -> Vec<String> {
        let prefix = format!("kernel {module} ");
        out.lines()
            .filter_map(|l| l.strip_prefix(&prefix).map(String::from))
            .collect()
    };
    assert_eq!(lines_of("arm"), lines_of("arm_split"));
    assert_eq!(lines_of("arm").len(), 4);

    // Kernels against the interpreter.
    let mut seen = 0;
    for line in out.lines().filter(|l| l.starts_with("kernel ")) {
        let mut it = line.split(' ').skip(1);
        let (module, name) = (it.next().unwrap(), it.next().unwrap());
        let got: Vec<f64> = it.map(|v| v.parse().unwrap()).collect();
        let m = mods.iter().find(|m| m.name == module).unwrap();
        let rt = SceneKernels::new(&m.scene).unwrap();
        let kern = rt.kernels.iter().find(|k| k.name == name).unwrap();
        let (q, qd, omega, eps, u) = state(m.scene.nq());
        let want = kern.eval(&rt.vars(&q, &qd, omega, eps, &u, None));
        let tol = if m.float == FloatTy::F32 { 2e-4 } else { 1e-13 };
        let scale = want.iter().fold(1e-300f64, |a, x| a.max(x.abs()));
        assert_eq!(got.len(), want.len(), "{module}::{name}");
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!(
                (g - w).abs() <= tol * scale,
                "{module}::{name}[{i}]: no_std {g} vs interpreter {w}"
            );
        }
        seen += 1;
    }
    let expected: usize = mods.iter().map(|m| m.scene.kernels.len()).sum();
    assert_eq!(seen, expected, "kernels run");

    // Square root, sine and cosine against std and the double-double reference.
    let hex = |s: &str| u64::from_str_radix(s, 16).unwrap();
    let mut probes_seen = 0;
    for line in out.lines().filter(|l| l.starts_with("probe ")) {
        let v: Vec<u64> = line.split(' ').skip(1).map(hex).collect();
        let x = f64::from_bits(v[0]);
        let (s, c, r) = (
            f64::from_bits(v[1]),
            f64::from_bits(v[2]),
            f64::from_bits(v[3]),
        );
        let (s32, c32, r32) = (
            f32::from_bits(v[4] as u32),
            f32::from_bits(v[5] as u32),
            f32::from_bits(v[6] as u32),
        );
        let std_r = x.sqrt();
        assert!(
            r.to_bits() == std_r.to_bits() || (r.is_nan() && std_r.is_nan()),
            "sqrt({x:e}): {r:e} vs std {std_r:e}"
        );
        let x32 = x as f32;
        let want_r32 = x32.sqrt();
        assert!(
            r32.to_bits() == want_r32.to_bits() || (r32.is_nan() && want_r32.is_nan()),
            "f32 sqrt({x32:e}): {r32:e} vs std {want_r32:e}"
        );
        if x.abs() > 1048576.0 {
            assert!(
                s.is_nan() && c.is_nan(),
                "sin_cos({x:e}) beyond 2^20 is NaN"
            );
            continue;
        }
        let (es, ec) = Dd::new(x).sin_cos();
        assert!(
            ulps(s, es) <= 1.0 && ulps(c, ec) <= 1.0,
            "sin_cos({x:e}): {s:e} ({:.2} ulp), {c:e} ({:.2} ulp)",
            ulps(s, es),
            ulps(c, ec)
        );
        let (ls, lc) = libm::sincos(x);
        assert!(
            ulps_f64(s, ls) <= 1.0 && ulps_f64(c, lc) <= 1.0,
            "vs std at {x:e}"
        );
        // f32: the f64 value of the f32 argument, rounded once.
        let ([s64], [c64]) = bf_codegen::trig::sin_cos_n([x32 as f64]);
        if (x32 as f64).abs() <= 1048576.0 {
            assert_eq!(s32, s64 as f32, "f32 sin({x32:e})");
            assert_eq!(c32, c64 as f32, "f32 cos({x32:e})");
        }
        probes_seen += 1;
    }
    assert!(probes_seen > 2000, "{probes_seen} probes");
    std::fs::remove_dir_all(dir).unwrap();
}
