//! The files of `optimize` describe themselves and replay: `solution.json` carries its schema
//! version, units, named state components and a status/verification block, the internals are
//! in `solution-internals.json`, and `simulate --init solution.json --torques torques.csv`
//! reproduces the first phase of the optimum to the verification tolerance (1e-4) — an
//! independent integration (the simulator's hybrid model, event location and torque
//! interpolation) of the optimum's own torques from its own initial state.

#[path = "common/cli.rs"]
mod cli;

use ball_finger::pipeline::OcpSolution;
use ball_finger::pipeline::solution_io::{INTERNALS_FILE, SCHEMA_VERSION, SolutionIo};
use serde_json::Value;

fn json(path: &std::path::Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn col(v: &Value, name: &str) -> Vec<f64> {
    v[name]
        .as_array()
        .unwrap_or_else(|| panic!("column {name}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn optimize_then_simulate_replays_the_first_phase() {
    let dir = cli::tmpdir("replay");
    let opt = dir.join("opt");
    let out = cli::run(&[
        "optimize",
        "--problem",
        "reach",
        "--refine",
        "1e-7",
        "--out",
        opt.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sol = json(&opt.join("solution.json"));
    assert_eq!(sol["schema_version"], SCHEMA_VERSION);
    assert_eq!(sol["units"]["nodes.q1, dense.q1"], "rad");
    assert_eq!(sol["units"]["nodes.tau3, dense.tau3"], "N m");
    assert_eq!(sol["state_names"][3], "qd1");
    assert_eq!(sol["state_names"][8], "omega_z");
    assert_eq!(sol["modes"][0], "free");
    assert_eq!(sol["status"], "Solved");
    let ver = &sol["verification"];
    assert_eq!(ver["tolerance"], 1e-4);
    assert_eq!(ver["verified"], sol["verified"]);
    assert_eq!(ver["verified"], true);
    assert!(ver["defect"].as_f64().unwrap() <= 1e-4, "{ver}");
    assert_eq!(ver["defect"], ver["max_defect"]);
    for internal in ["raw", "nlp_warm", "timing", "counters", "params"] {
        assert!(sol.get(internal).is_none(), "{internal} in solution.json");
    }
    let internals = json(&opt.join(INTERNALS_FILE));
    assert!(internals["raw"].is_array() && internals["nlp_warm"].is_object());
    assert!(internals["timing_seconds"]["total"].as_f64().unwrap() > 0.0);
    // The record reads back whole, internals included.
    let back = OcpSolution::read_json(&opt.join("solution.json")).unwrap();
    assert_eq!(back.raw.len(), 1);
    assert!(back.nlp_warm.is_some() && back.timing.total.as_secs_f64() > 0.0);
    assert_eq!(back.nodes.q.len(), col(&sol["nodes"], "q1").len());
    // A file of the format before schema 2 (the record in one file) still reads.
    let old = dir.join("old.json");
    std::fs::write(&old, serde_json::to_string(&back).unwrap()).unwrap();
    let again = OcpSolution::read_json(&old).unwrap();
    assert_eq!(again.objective, back.objective);
    assert_eq!(again.raw.len(), 1);

    // Replay phase 1 (free motion up to the contact) from the solution's own initial state.
    let t1 = sol["phase_durations"][0].as_f64().unwrap();
    let sim = dir.join("sim");
    let out = cli::run(&[
        "simulate",
        "--init",
        opt.join("solution.json").to_str().unwrap(),
        "--torques",
        opt.join("torques.csv").to_str().unwrap(),
        "--t-end",
        &format!("{t1}"),
        "--rtol",
        "1e-10",
        "--output-dt",
        "1e-4",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let traj = json(&sim.join("trajectory.json"));
    let t: Vec<f64> = traj["t"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let x = traj["x"].as_array().unwrap();
    // The simulator's state at t = 0 is the solution's first node.
    let nodes = &sol["nodes"];
    let names = ["q1", "q2", "q3", "qd1", "qd2", "qd3"];
    for (i, n) in names.iter().enumerate() {
        assert_eq!(x[0][i].as_f64().unwrap(), col(nodes, n)[0], "{n}(0)");
    }
    // At every collocation point of phase 1 (before any event), the replay (linearly
    // interpolated between its samples, 1e-4 s apart) matches the optimum's state to the
    // verification tolerance.
    let first_event = json(&sim.join("events.json"))["events"]
        .as_array()
        .and_then(|e| e.first())
        .and_then(|e| e["t"].as_f64())
        .unwrap_or(f64::INFINITY);
    let tn = col(nodes, "t");
    let phase = col(nodes, "phase");
    let mut worst = 0.0f64;
    let mut checked = 0;
    for (k, &tk) in tn.iter().enumerate() {
        if phase[k] != 0.0 || tk >= first_event || tk > t[t.len() - 1] {
            continue;
        }
        let j = t.partition_point(|&s| s <= tk).clamp(1, t.len() - 1);
        let w = if t[j] > t[j - 1] {
            (tk - t[j - 1]) / (t[j] - t[j - 1])
        } else {
            0.0
        };
        for (i, n) in names.iter().enumerate() {
            let (a, b) = (x[j - 1][i].as_f64().unwrap(), x[j][i].as_f64().unwrap());
            worst = worst.max((a + w * (b - a) - col(nodes, n)[k]).abs());
        }
        checked += 1;
    }
    assert!(checked > 10, "{checked} collocation points checked");
    assert!(
        worst < 1e-4,
        "the replay differs from the optimum by {worst:e} (rad, rad/s)"
    );
}

#[test]
fn old_and_future_solution_files() {
    let dir = cli::tmpdir("schema");
    // A file from a newer program is refused with its version named.
    let p = dir.join("solution.json");
    std::fs::write(&p, r#"{"schema_version": 99, "problem": "reach"}"#).unwrap();
    let e = OcpSolution::read_json(&p).unwrap_err().to_string();
    assert!(
        e.contains("schema_version 99") && e.contains("solution.json"),
        "{e}"
    );
    // A schema-2 file without its internals names the missing file.
    std::fs::write(&p, r#"{"schema_version": 2, "problem": "reach"}"#).unwrap();
    let e = OcpSolution::read_json(&p).unwrap_err().to_string();
    assert!(e.contains(INTERNALS_FILE), "{e}");
}

#[test]
fn edited_phase_lists_are_blamed_on_the_field() {
    let dir = cli::tmpdir("phases");
    let stored = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/optima/periodic-qc");
    std::fs::copy(stored.join(INTERNALS_FILE), dir.join(INTERNALS_FILE)).unwrap();
    let text = std::fs::read_to_string(stored.join("solution.json")).unwrap();
    let sol: serde_json::Value = serde_json::from_str(&text).unwrap();
    let p = dir.join("solution.json");
    // The copy reads: its internals belong to it.
    std::fs::write(&p, &text).unwrap();
    assert!(OcpSolution::read_json(&p).is_ok());
    for (modes, needle) in [
        (serde_json::json!([]), "`modes` is empty"),
        (
            serde_json::json!(["free", "stick"]),
            "`modes` lists 2 phases and `phase_durations` 3",
        ),
    ] {
        let mut edited = sol.clone();
        edited["modes"] = modes;
        std::fs::write(&p, edited.to_string()).unwrap();
        let e = OcpSolution::read_json(&p).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains("solution.json"), "{e}");
        assert!(!e.contains("internals"), "{e}");
    }
}

/// What a solution records of its problem is checked by the one reader every command uses,
/// whether or not the command at hand needs the field: `track` without `--replan` used to
/// execute a plan whose file recorded a cone margin of 2 or a negative ε, `--warm-start` to take
/// a file whose scene text did not parse, and `optimize merge` a candidate with q₁ = 1e300. Each
/// edit of the stored `periodic-qc` optimum below is refused by `read_json`, by the public
/// reader of `simulate --init` and, for one case each, by the commands themselves (exit 1, the
/// file and the field named).
#[test]
fn every_reader_checks_the_recorded_problem() {
    use ball_finger::pipeline::solution_io::check_public_fields;
    let dir = cli::tmpdir("recorded");
    let stored = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/optima/periodic-qc");
    let text = std::fs::read_to_string(stored.join("solution.json")).unwrap();
    let internals = std::fs::read_to_string(stored.join(INTERNALS_FILE)).unwrap();
    let sol: Value = serde_json::from_str(&text).unwrap();
    let inner: Value = serde_json::from_str(&internals).unwrap();
    let p = dir.join("solution.json");
    let edits: Vec<(&str, Value, &str)> = vec![
        ("problem", "bogus".into(), "unknown problem `bogus`"),
        (
            "verified",
            "yes".into(),
            "`verified` is \"yes\", not true or false",
        ),
        ("points", 0.into(), "at least 2 are needed"),
        (
            "points",
            1_000_000_000_000u64.into(),
            "at most 5000 per phase",
        ),
        (
            "scheme",
            serde_json::json!({"Radau": {"elements": 0}}),
            "0 elements",
        ),
        (
            "epsilon",
            (-1.0).into(),
            "epsilon must be a finite number in [1e-150, 1e150]",
        ),
        ("cone_margin", 2.0.into(), "cone_margin must be in [0, 1)"),
        (
            "torque_margin",
            (-1.0).into(),
            "torque_margin must be in [0, 1)",
        ),
        (
            "approach_clearance",
            1e6.into(),
            "approach_clearance must be in [0, r / 10]",
        ),
        ("scene_toml", "name = ".into(), "its `scene_toml`"),
        (
            "objective",
            1e300.into(),
            "`objective` = 1e300 is out of range",
        ),
    ];
    let mut unversioned = sol.clone();
    unversioned
        .as_object_mut()
        .unwrap()
        .remove("schema_version");
    let e = check_public_fields(&unversioned, &p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`schema_version` is missing"), "{e}");
    let mut far = sol.clone();
    far["nodes"]["q1"][2] = 1e11.into();
    let e = check_public_fields(&far, &p).unwrap_err().to_string();
    assert!(
        e.contains("`nodes.q1` = 1e11 rad at sample 2 is beyond ±2²⁰"),
        "{e}"
    );
    for (field, value, needle) in &edits {
        let mut edited = sol.clone();
        edited[*field] = value.clone();
        std::fs::write(dir.join(INTERNALS_FILE), &internals).unwrap();
        std::fs::write(&p, edited.to_string()).unwrap();
        let e = OcpSolution::read_json(&p).unwrap_err().to_string();
        assert!(
            e.contains(needle) && e.contains("solution.json"),
            "{field}: {e}"
        );
        let e = check_public_fields(&edited, &p).unwrap_err().to_string();
        assert!(e.contains(needle), "{field}, public reader: {e}");
    }
    // The internals: another schema, and a number out of range, named in their own file.
    for (edit, needle) in [
        (("schema_version", Value::from(99)), "schema_version 99"),
        (
            ("params", serde_json::json!([1e300])),
            "`params[0]` = 1e300",
        ),
    ] {
        let mut edited = inner.clone();
        edited[edit.0] = edit.1;
        std::fs::write(&p, &text).unwrap();
        std::fs::write(dir.join(INTERNALS_FILE), edited.to_string()).unwrap();
        let e = OcpSolution::read_json(&p).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains(INTERNALS_FILE), "{e}");
    }
    // The commands: each refuses its edited file before any work.
    std::fs::write(dir.join(INTERNALS_FILE), &internals).unwrap();
    let p_str = p.to_str().unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    for (field, value, args) in [
        (
            "cone_margin",
            Value::from(2.0),
            vec!["track", p_str, "--periods", "1", "--out", out],
        ),
        (
            "epsilon",
            Value::from(-1.0),
            vec!["simulate", "--init", p_str, "--out", out],
        ),
        (
            "scene_toml",
            Value::from("name = "),
            vec![
                "optimize",
                "--problem",
                "periodic-qc",
                "--warm-start",
                p_str,
                "--out",
                out,
            ],
        ),
    ] {
        let mut edited = sol.clone();
        edited[field] = value;
        std::fs::write(&p, edited.to_string()).unwrap();
        let o = cli::run(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains(field) && stderr.contains("solution.json"),
            "{stderr}"
        );
        assert!(!dir.join("out").exists(), "{args:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every f64 the commands write to JSON reads back bit for bit (serde_json's
/// `float_roundtrip`), so `simulate --init solution.json` starts exactly at the optimum's first
/// node and a warm start from a file is the solution itself. The first value was 1 ulp off
/// through one write and read with the default parser (a replay check failed on it).
#[test]
fn json_floats_read_back_bit_for_bit() {
    let mut values = vec![
        -1.920420079242028e-18,
        -1.9204200792420282e-18,
        0.1,
        1.0 / 3.0,
    ];
    // Deterministic pseudo-random bit patterns (xorshift64*) over the whole finite range.
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    while values.len() < 200_000 {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        let x = f64::from_bits(state.wrapping_mul(0x2545_f491_4f6c_dd1d));
        if x.is_finite() {
            values.push(x);
        }
    }
    let text = serde_json::to_string(&values).unwrap();
    let back: Vec<f64> = serde_json::from_str(&text).unwrap();
    for (x, y) in values.iter().zip(&back) {
        assert_eq!(x.to_bits(), y.to_bits(), "{x:e} read back as {y:e}");
    }
}

/// Solver settings written before the 2026-11-26 changes still read: the extrapolation scope that began
/// at the floor of μ (`FinalBarrier`) reads as today's default scope, and settings without
/// the proximal term's fields take its defaults, which are what `ProblemSettings` JSON without
/// `proximal_weight` gives too.
#[test]
fn older_solver_settings_still_read() {
    use bf_optim::ipm::{ExtrapolationScope, Settings};
    let old: Settings =
        serde_json::from_str(r#"{"extrapolation_scope": "FinalBarrier", "tol": 1e-7}"#).unwrap();
    let default = Settings::default();
    assert_eq!(
        old.experimental.extrapolation_scope,
        ExtrapolationScope::Answers
    );
    assert_eq!(old.termination.tol, 1e-7);
    assert_eq!(
        (old.barrier.proximal_weight, old.barrier.proximal_after),
        (
            default.barrier.proximal_weight,
            default.barrier.proximal_after
        )
    );
    let ps: bf_problem::ProblemSettings = serde_json::from_str("{}").unwrap();
    assert_eq!(ps.proximal_weight, None);
}
