//! The default search of `optimize` (`ball_finger::pipeline::search::search`) on the paper's
//! problems (the sticking law, eq. 40, asked for by `--impact-law stick`): on `periodic-qc`
//! it must reach at least the best optimum known before it (J = 0.1065805,
//! confirmed as a KKT point of the same transcription by an independent CasADi + IPOPT solve)
//! with a re-integration that verifies it, bit for bit the same with one and two worker threads; shards of a multi-start
//! merged must give the unsharded choice; a solution whose re-integration does not verify it
//! is marked FAILED with `verification.verified: false` and a non-zero exit; `--min-stick`
//! bounds the stick phase.

use std::path::Path;

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{bin, root, run, tmpdir};

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `optimize --out DIR EXTRA` on the paper's problems: the sticking law (eq. 40) unless
/// `extra` names `--impact-law` (the figures below are the paper problems' searches).
fn optimize_in(dir: &Path, threads: Option<&str>, extra: &[&str]) -> std::process::Output {
    let mut c = bin();
    c.current_dir(root())
        .args(["optimize", "--out", dir.to_str().unwrap()])
        .args(extra);
    if !extra.contains(&"--impact-law") {
        c.args(["--impact-law", "stick"]);
    }
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t);
    }
    c.output().unwrap()
}

use cli_util::ok;

/// The fields that define a solution (not its timings).
fn essence(v: &serde_json::Value) -> Vec<serde_json::Value> {
    [
        "status",
        "objective",
        "period",
        "phase_durations",
        "impulse",
        "nodes",
    ]
    .iter()
    .map(|k| v[*k].clone())
    .chain([
        v["strategy"]["chosen"].clone(),
        v["verification"]["max_defect"].clone(),
    ])
    .collect()
}

#[test]
#[ignore = "slow: two full default searches (about 50 s CPU, over 60 s wall on a loaded 2-core \
            machine); run with `cargo test --release --test search -- --ignored`"]
fn default_periodic_qc_finds_the_best_known_optimum_verified_and_thread_independent() {
    let dir = tmpdir("qc-default");
    let (one, two) = (dir.join("one"), dir.join("two"));
    ok(&optimize_in(&one, Some("1"), &["--problem", "periodic-qc"]));
    let stdout = ok(&optimize_in(&two, Some("2"), &["--problem", "periodic-qc"]));
    assert!(stdout.contains("verified: yes"), "{stdout}");
    let (a, b) = (
        json(&one.join("solution.json")),
        json(&two.join("solution.json")),
    );
    // The global search reaches the best known basins (issue 37's target).
    let j = a["objective"].as_f64().unwrap();
    assert!(j <= 0.08761, "J = {j}");
    assert_eq!(a["status"], "Solved");
    let v = &a["verification"];
    assert!(
        v["max_defect"].as_f64().unwrap() <= 1e-6,
        "{}",
        v["max_defect"]
    );
    assert_eq!(v["verified"], true);
    assert_eq!(v["tolerance"].as_f64(), Some(1e-4));
    // Every one of the 128 starts ran the stick continuation: bounded to >= 0.1 s, then
    // relaxed to 0.01 s; the chosen optimum was re-solved on the problem's mesh last.
    let recs = a["strategy"]["records"].as_array().unwrap();
    let relaxed = recs
        .iter()
        .filter(|r| r["stage"].as_str().unwrap().starts_with("relax stick"))
        .count();
    assert_eq!(relaxed, 128);
    let chosen = a["strategy"]["chosen"].as_u64().unwrap();
    let last = recs
        .iter()
        .rfind(|r| r["chain"].as_u64() == Some(chosen))
        .unwrap();
    assert!(
        last["stage"]
            .as_str()
            .is_some_and(|s| s.starts_with("full mesh")),
        "{last}"
    );
    // The relaxed optimum respects the default bound.
    assert!(a["phase_durations"][1].as_f64().unwrap() >= 0.01 * (1.0 - 1e-8));
    // Same solution to the bit (JSON writes the shortest round-trip text of each f64).
    assert_eq!(essence(&a), essence(&b));
    std::fs::remove_dir_all(dir).ok();
}

/// The default search of `periodic-cot` (the 32-start multi-start) verifies an optimum below
/// the continuation's (0.011405, BENCHMARKS.md "Default search: multi-start for every
/// periodic problem"), the same on one and on two threads.
#[test]
#[ignore = "slow: two full default searches of periodic-cot and one continuation (about 90 s \
            CPU); run with `cargo test --release --test search -- --ignored`"]
fn default_periodic_cot_search_beats_the_continuation_verified_and_thread_independent() {
    let dir = tmpdir("cot-default");
    let (one, two, cont) = (dir.join("one"), dir.join("two"), dir.join("cont"));
    ok(&optimize_in(
        &one,
        Some("1"),
        &["--problem", "periodic-cot"],
    ));
    ok(&optimize_in(
        &two,
        Some("2"),
        &["--problem", "periodic-cot"],
    ));
    ok(&optimize_in(
        &cont,
        None,
        &["--problem", "periodic-cot", "--strategy", "continuation"],
    ));
    let (a, b, c) = (
        json(&one.join("solution.json")),
        json(&two.join("solution.json")),
        json(&cont.join("solution.json")),
    );
    for s in [&a, &c] {
        assert_eq!(s["status"], "Solved");
        assert_eq!(s["verification"]["verified"], true);
    }
    let (ja, jc) = (
        a["objective"].as_f64().unwrap(),
        c["objective"].as_f64().unwrap(),
    );
    assert!(
        ja < jc,
        "multi-start J {ja} against the continuation's {jc}"
    );
    assert_eq!(essence(&a), essence(&b));
    std::fs::remove_dir_all(dir).ok();
}

/// A merge takes neither a candidate's stated status nor its stated verification on trust:
/// a failed start whose file was edited to say `Solved` and verified is refused (its own
/// point violates the constraints far beyond what `Solved` allows), and a candidate whose
/// verification was edited to pass is verified anew, so the merge ends as with the files
/// as written (it used to choose the edited candidate with exit 0).
#[test]
fn a_merge_checks_the_status_and_verification_its_files_state() {
    let dir = tmpdir("merge-claims");
    let shard = dir.join("shard");
    let o = run(&[
        "optimize",
        "--problem",
        "reach",
        "--starts",
        "4",
        "--shard",
        "2/2",
        "--out",
        shard.to_str().unwrap(),
    ]);
    ok(&o);
    let merge = |from: &Path, to: &str| {
        run(&[
            "optimize",
            "merge",
            from.to_str().unwrap(),
            "--out",
            dir.join(to).to_str().unwrap(),
        ])
    };
    let plain = merge(&shard, "plain");
    ok(&plain);
    // One shard of two: the merge is that of its starts, and says so on stderr.
    let e = String::from_utf8_lossy(&plain.stderr);
    assert!(
        e.contains("warning: the shards ran 2 of the 4 starts"),
        "{e}"
    );
    let copy = |tag: &str| {
        let to = dir.join(tag);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(&shard).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
        to
    };
    let candidates: Vec<(String, serde_json::Value)> = std::fs::read_dir(&shard)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("candidate-") && !n.ends_with("-internals.json"))
        .map(|n| {
            let v = json(&shard.join(&n));
            (n, v)
        })
        .collect();
    // Every defect of a verification record set to `value`, and its verdict to `verified`.
    fn claim(v: &mut serde_json::Value, value: f64) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    if k.contains("defect") && x.is_number() {
                        *x = serde_json::json!(value);
                    } else {
                        claim(x, value);
                    }
                }
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(|x| claim(x, value)),
            _ => {}
        }
    }
    let verified_claim = |c: &mut serde_json::Value| {
        claim(&mut c["verification"], 1e-7);
        c["verification"]["verified"] = serde_json::json!(true);
        c["verified"] = serde_json::json!(true);
    };
    let (failed, mut c) = candidates
        .iter()
        .find(|(_, c)| c["status"] != "Solved" && c["constraint_violation"].as_f64() > Some(1e-2))
        .cloned()
        .expect("a start of reach that ends infeasible");
    c["status"] = serde_json::json!("Solved");
    verified_claim(&mut c);
    let edited = copy("edited-status");
    std::fs::write(edited.join(&failed), c.to_string()).unwrap();
    let o = merge(&edited, "refused");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&failed) && e.contains("status Solved") && e.contains("violated"),
        "{e}"
    );
    let (unverified, mut c) = candidates
        .iter()
        .find(|(_, c)| c["status"] == "Solved" && c["verified"] == false)
        .cloned()
        .expect("a solved start of reach that its own mesh does not verify");
    verified_claim(&mut c);
    let edited = copy("edited-verification");
    std::fs::write(edited.join(&unverified), c.to_string()).unwrap();
    let o = merge(&edited, "reverified");
    ok(&o);
    let (a, b) = (
        json(&dir.join("plain").join("solution.json")),
        json(&dir.join("reverified").join("solution.json")),
    );
    assert_eq!(a["objective"], b["objective"]);
    assert_eq!(a["strategy"]["chosen"], b["strategy"]["chosen"]);
    assert_eq!(
        a["verification"]["max_defect"],
        b["verification"]["max_defect"]
    );
    assert!(b["verification"]["max_defect"].as_f64().unwrap() > 1e-7);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn shards_merged_give_the_unsharded_multistart_choice() {
    let dir = tmpdir("shards");
    // The shards sample; the merge runs the global search's basin hops on their union.
    let base = ["--problem", "periodic-qc", "--starts", "12", "--hops", "8"];
    let whole = dir.join("whole");
    ok(&optimize_in(&whole, None, &base));
    let mut shard_dirs = Vec::new();
    for k in ["1/2", "2/2"] {
        let d = dir.join(format!("shard{}", &k[..1]));
        let mut a = base.to_vec();
        a.extend(["--shard", k]);
        let out = ok(&optimize_in(&d, None, &a));
        assert!(out.contains(&format!("shard {k}")), "{out}");
        let names: Vec<String> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("candidate-"))
            .collect();
        assert!(!names.is_empty());
        // Shard k holds the starts ≡ k − 1 (mod 2) only; every candidate has its own
        // internals file (no candidate's warm-start data replaces another's).
        let parity = usize::from(k == "2/2");
        for n in names.iter().filter(|n| !n.ends_with("-internals.json")) {
            let idx: usize = n[10..14].parse().unwrap();
            assert_eq!(idx % 2, parity, "{n}");
            let internals = n.replace(".json", "-internals.json");
            assert_eq!(json(&d.join(n))["internals"], internals.as_str());
            assert_eq!(
                json(&d.join(&internals))["problem"],
                json(&d.join(n))["problem"]
            );
        }
        shard_dirs.push(d);
    }
    let merged = dir.join("merged");
    let o = run(&[
        "optimize",
        "merge",
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[1].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    let merged_out = ok(&o);
    let (w, m) = (
        json(&whole.join("solution.json")),
        json(&merged.join("solution.json")),
    );
    assert_eq!(w["strategy"]["chosen"], m["strategy"]["chosen"]);
    // The merge ran the shards' recorded `--hops 8` without being told, and records the run's
    // scene and settings as the unsharded file does (a replay reads its scene from there).
    assert_eq!(w["search_settings"]["hops"], 8);
    for k in ["scene_toml", "scene_params", "search_settings"] {
        assert_eq!(m[k], w[k], "{k}");
    }
    assert!(!w["scene_toml"].as_str().unwrap().is_empty());
    // The merge verifies and refines as the unsharded run does: the shards' coarse candidates
    // carry no verification, so its tolerance is the shards' own (before, the merge ran
    // without verification and chose an unverified 0.0769202 tap that the unsharded run
    // had rejected on its friction-cone margin).
    assert_eq!(w["verified"], true);
    assert_eq!(m["verified"], w["verified"]);
    // The same hops (after the 12 starts, numbered on from 12) with the same outcome, and
    // the same count of the winning optimum's hits, printed as recorded.
    let hits = w["strategy"]["basin_hits"].as_u64().expect("basin_hits");
    assert!(hits >= 1);
    assert_eq!(m["strategy"]["basin_hits"], w["strategy"]["basin_hits"]);
    assert!(
        merged_out.contains(&format!("basin: {hits} of")),
        "{merged_out}"
    );
    let hops = w["strategy"]["records"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["chain"].as_u64().unwrap() >= 12)
        .count();
    // The reshaping (every move from the best shapes) and at most 8 hops and 8 polishing hops,
    // then the winner's neighbourhood: every move and the 4 hops and 2 polishing solves of
    // `POLISH_HOPS` from the verified winner (the same in the merge: records compared below).
    let stages = |prefix: &str| {
        w["strategy"]["records"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["stage"].as_str().unwrap().starts_with(prefix))
            .count()
    };
    let reshaped = stages("reshape");
    assert!(reshaped >= 1, "no reshaping record");
    let neighbourhood = stages(ball_finger::pipeline::search::POLISH_LABEL);
    assert_eq!(
        neighbourhood,
        ball_finger::pipeline::reshape::MOVES.len() + 4 + 2
    );
    assert!(
        (8..=reshaped + 8 + 8 + 8 + neighbourhood).contains(&hops),
        "{hops} hop records, {reshaped} reshaped, {neighbourhood} in the winner's neighbourhood"
    );
    let close = |x: &serde_json::Value, y: &serde_json::Value| {
        let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
        // One JSON round trip more on the merged side (serde_json parses to within an ulp).
        (x - y).abs() <= 1e-14 * x.abs().max(y.abs())
    };
    for k in ["objective", "period", "c1", "c2"] {
        assert!(close(&w[k], &m[k]), "{k}: {} vs {}", w[k], m[k]);
    }
    // The starts ran on the coarse mesh and the best optima were re-solved on the mesh: the
    // shards' candidates are coarse (12 points per phase), the chosen solution is not, and the
    // merge re-solved the same optima as the unsharded run (compared record by record below).
    assert_eq!(w["points"], 30);
    let promoted = |v: &serde_json::Value| {
        v["strategy"]["records"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["stage"] == "full mesh")
            .map(|r| r["chain"].as_u64().unwrap())
            .collect::<Vec<_>>()
    };
    assert!(!promoted(&w).is_empty());
    assert_eq!(promoted(&w), promoted(&m));
    for d in &shard_dirs {
        for e in std::fs::read_dir(d).unwrap() {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            if n.starts_with("candidate-") && !n.ends_with("-internals.json") {
                assert_eq!(json(&d.join(&n))["points"], 12, "{n}");
            }
        }
    }
    // Every start of the unsharded run appears once in the merged record, same outcome.
    let (rw, rm) = (
        w["strategy"]["records"].as_array().unwrap(),
        m["strategy"]["records"].as_array().unwrap(),
    );
    assert_eq!(rw.len(), rm.len());
    for (x, y) in rw.iter().zip(rm) {
        assert_eq!(x["chain"], y["chain"]);
        assert_eq!(x["status"], y["status"]);
        assert!(close(&x["objective"], &y["objective"]), "{x} vs {y}");
    }
    // A candidate edited to claim a lower objective than its own trajectory gives is refused,
    // as is a shard solved on another scene file.
    let copy = |tag: &str| {
        let to = dir.join(tag);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(&shard_dirs[1]).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
        to
    };
    let merge_with = |other: &Path| {
        run(&[
            "optimize",
            "merge",
            shard_dirs[0].to_str().unwrap(),
            other.to_str().unwrap(),
            "--out",
            dir.join("refused").to_str().unwrap(),
        ])
    };
    let tampered = copy("tampered");
    let cand = std::fs::read_dir(&tampered)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .find(|n| n.starts_with("candidate-") && !n.ends_with("-internals.json"))
        .unwrap();
    let mut c = json(&tampered.join(&cand));
    c["objective"] = serde_json::json!(c["objective"].as_f64().unwrap() * 0.5);
    std::fs::write(tampered.join(&cand), c.to_string()).unwrap();
    let o = merge_with(&tampered);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        e.contains(&cand) && e.contains("objective") && e.contains("own trajectory"),
        "{e}"
    );
    let other_scene = copy("other-scene");
    let mut sol = json(&other_scene.join("solution.json"));
    let text = sol["scene_toml"]
        .as_str()
        .unwrap()
        .replace("radius = 1.0", "radius = 1.1");
    assert_ne!(text, sol["scene_toml"].as_str().unwrap());
    sol["scene_toml"] = serde_json::json!(text);
    std::fs::write(other_scene.join("solution.json"), sol.to_string()).unwrap();
    let o = merge_with(&other_scene);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        e.contains("another scene file text") && e.contains("line"),
        "{e}"
    );
    // A shard planned with another friction-cone margin is another problem.
    let other_margin = copy("other-margin");
    let mut sol = json(&other_margin.join("solution.json"));
    sol["cone_margin"] = serde_json::json!(0.2);
    std::fs::write(other_margin.join("solution.json"), sol.to_string()).unwrap();
    let o = merge_with(&other_margin);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("cone margin 2e-1"), "{e}");
    // Shards verified with other tolerances are refused, naming the option.
    let other_rtol = copy("other-rtol");
    let mut sol = json(&other_rtol.join("solution.json"));
    let rtol = sol["verification"]["rtol"]
        .as_f64()
        .expect("a verified shard");
    sol["verification"]["rtol"] = serde_json::json!(10.0 * rtol);
    std::fs::write(other_rtol.join("solution.json"), sol.to_string()).unwrap();
    let o = merge_with(&other_rtol);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        e.contains("verified with rtol") && e.contains("--verify-rtol"),
        "{e}"
    );
    // Shards searched with another --min-stick or refinement limit are refused, naming the
    // option and both values; the files record the settings the command line gave.
    let shard_settings = json(&shard_dirs[1].join("solution.json"))["search_settings"].clone();
    assert_eq!(shard_settings["min_stick"], serde_json::json!(0.01));
    assert_eq!(shard_settings["verify_refinements"], serde_json::json!(5));
    for (field, value, option, shown) in [
        ("min_stick", serde_json::json!(0.1), "--min-stick", "1e-1"),
        (
            "verify_refinements",
            serde_json::json!(2),
            "--verify-refinements",
            "2",
        ),
        (
            "max_points",
            serde_json::json!(400),
            "verification refinement point limit",
            "400",
        ),
    ] {
        let other = copy(&format!("other-{field}"));
        let mut sol = json(&other.join("solution.json"));
        sol["search_settings"][field] = value;
        std::fs::write(other.join("solution.json"), sol.to_string()).unwrap();
        let o = merge_with(&other);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        let ours = shard_settings["min_stick"].as_f64().unwrap();
        assert!(
            e.contains(&format!("searched with {option} {shown},"))
                && e.contains(option)
                && (field != "min_stick" || e.contains(&format!("{ours:e}"))),
            "{e}"
        );
    }
    // A shard that records no settings (an older file) beside one that does is refused.
    let older = copy("older");
    let mut sol = json(&older.join("solution.json"));
    sol.as_object_mut().unwrap().remove("search_settings");
    std::fs::write(older.join("solution.json"), sol.to_string()).unwrap();
    let o = merge_with(&older);
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("records no search settings"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A merge told other hops than the shards searched with would run another search.
    let o = run(&[
        "optimize",
        "merge",
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[1].to_str().unwrap(),
        "--hops",
        "0",
        "--out",
        dir.join("refused").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--hops 0") && e.contains("--hops 8"), "{e}");
    assert!(!dir.join("refused").exists());
    // A whole search is no shard: its records hold the chains of its hops after its starts.
    let o = merge_with(&whole);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("not the output of optimize --shard"), "{e}");
    assert!(!e.contains("the shards ran"), "{e}");
    // Without hops a whole search's records are its starts only, as a shard's; merged alone,
    // its directory is named as one without the candidate files every shard keeps.
    let hopless = dir.join("hopless");
    std::fs::create_dir_all(&hopless).unwrap();
    for e in std::fs::read_dir(&whole).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), hopless.join(e.file_name())).unwrap();
    }
    let mut sol = json(&hopless.join("solution.json"));
    sol["strategy"]["records"]
        .as_array_mut()
        .unwrap()
        .retain(|r| r["chain"].as_u64().unwrap() < 12);
    std::fs::write(hopless.join("solution.json"), sol.to_string()).unwrap();
    let o = run(&[
        "optimize",
        "merge",
        hopless.to_str().unwrap(),
        "--out",
        dir.join("refused").to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        e.contains("hopless") && e.contains("no candidate files") && e.contains("whole search"),
        "{e}"
    );
    // Another multi-start is refused naming both files.
    let other_seed = copy("other-seed");
    let mut sol = json(&other_seed.join("solution.json"));
    sol["strategy"]["strategy"]["Multistart"]["seed"] = serde_json::json!(7);
    std::fs::write(other_seed.join("solution.json"), sol.to_string()).unwrap();
    let o = merge_with(&other_seed);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("other-seed") && e.contains("shard1"), "{e}");
    // A start in two directories is refused.
    let o = run(&[
        "optimize",
        "merge",
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[0].to_str().unwrap(),
        "--out",
        dir.join("twice").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("appears in two"));
    // Bad shard specifications are usage errors naming the option.
    for bad in ["0/2", "3/2", "x", "1/0"] {
        let o = optimize_in(
            &dir.join("bad"),
            None,
            &["--problem", "periodic-qc", "--shard", bad],
        );
        assert!(!o.status.success());
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("--shard"),
            "{bad}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

/// `--shard 1/1` runs the whole search and keeps its candidates: `optimize merge` takes it as
/// a shard (its hop chains beyond the starts made it look like a whole search's directory),
/// continues from its starts, and chooses what the unsharded run chooses.
#[test]
#[ignore = "about 40 s on a loaded 2-core machine: a search and a merge"]
fn a_single_shard_merges_to_the_unsharded_choice() {
    let dir = tmpdir("one-shard");
    let base = ["--problem", "periodic-qc", "--starts", "2", "--hops", "1"];
    let whole = dir.join("whole");
    ok(&optimize_in(&whole, None, &base));
    let shard = dir.join("shard");
    let mut a = base.to_vec();
    a.extend(["--shard", "1/1"]);
    ok(&optimize_in(&shard, None, &a));
    let merged = dir.join("merged");
    let o = run(&[
        "optimize",
        "merge",
        shard.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("the shards ran"));
    let (w, m) = (
        json(&whole.join("solution.json")),
        json(&merged.join("solution.json")),
    );
    assert_eq!(w["strategy"]["chosen"], m["strategy"]["chosen"]);
    assert_eq!(w["objective"], m["objective"]);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn unverified_solution_is_marked_failed_with_its_defect() {
    // periodic-cot on the default 3 × 10 mesh: the 6–9 s free phase is far too coarse, and
    // without refinement its replay drifts by metres and radians.
    let dir = tmpdir("unverified");
    let out = dir.join("out");
    let o = optimize_in(
        &out,
        None,
        &[
            "--problem",
            "periodic-cot",
            "--strategy",
            "direct",
            "--verify-refinements",
            "0",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("unverified"), "{stderr}");
    assert!(out.join(bf_output::FAILED).exists());
    let sol = json(&out.join("solution.json"));
    assert!(sol["status"] == "Solved" || sol["status"] == "Acceptable");
    let v = &sol["verification"];
    assert_eq!(v["verified"], false);
    assert!(v["max_defect"].as_f64().unwrap() > 1e-4);
    assert_eq!(v["tolerance"].as_f64(), Some(1e-4));
    let failed = std::fs::read_to_string(out.join(bf_output::FAILED)).unwrap();
    assert!(failed.contains("unverified"), "{failed}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn min_stick_bounds_the_stick_phase() {
    let dir = tmpdir("minstick");
    for (secs, lo) in [("0.1", 0.1), ("0.25", 0.25)] {
        let out = dir.join(secs);
        ok(&optimize_in(
            &out,
            None,
            &[
                "--problem",
                "periodic-qc",
                "--strategy",
                "direct",
                "--min-stick",
                secs,
                // This test is about the bound; whether the optimum verifies is tested above.
                "--verify-rtol",
                "0",
            ],
        ));
        let sol = json(&out.join("solution.json"));
        let d = sol["phase_durations"][1].as_f64().unwrap();
        assert!(d >= lo * (1.0 - 1e-8), "stick {d} < {lo}");
    }
    for bad in ["0", "-1", "nan", "5"] {
        let o = optimize_in(
            &dir.join("bad"),
            None,
            &[
                "--problem",
                "periodic-qc",
                "--strategy",
                "direct",
                "--min-stick",
                bad,
            ],
        );
        assert!(!o.status.success(), "{bad}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            e.contains("--min-stick") || e.contains("stick duration"),
            "{bad}: {e}"
        );
        assert!(!e.contains("panicked"), "{e}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// An hp refinement that cannot change the mesh (here the point limit is the mesh's own
/// size) ends the attempts: each further attempt's tighter tolerance would mark a superset of
/// the elements, stop on the same limit and only solve the same mesh again.
#[test]
fn a_refinement_stopped_by_the_point_limit_is_not_repeated() {
    use ball_finger::pipeline::search::{VerifyPolicy, search};
    use ball_finger::pipeline::strategy::{Shard, Strategy};
    use bf_problem::{Problem, ProblemSettings};

    let settings = ProblemSettings::default();
    let policy = VerifyPolicy {
        refine_attempts: 3,
        max_points: settings.points,
        clusters: 1,
        ..VerifyPolicy::default()
    };
    let problem: Problem = "periodic-cot".parse().unwrap();
    let found = search(
        problem,
        &settings,
        Strategy::Direct,
        Shard::WHOLE,
        &policy,
        None,
    )
    .unwrap();
    // periodic-cot's direct solve on the default mesh does not verify (see above), so it is
    // refined once; the limit stops that refinement on its starting mesh.
    assert_eq!(found.refinements.len(), 1, "{:?}", found.refinements);
    let (_, sol) = found.best().unwrap();
    let report = sol.refinement.as_ref().expect("refined once");
    assert!(!report.converged, "{}", report.stop_reason);
    assert!(
        report.stop_reason.contains("point limit"),
        "{}",
        report.stop_reason
    );
    assert!(report.mesh.iter().all(|m| m.n_points() == settings.points));
    assert_eq!(sol.verification.as_ref().map(|v| v.verified), Some(false));
}

/// Runs the default search of `optimize` with `args`, asserts that its solution verifies, and
/// returns its stdout (with the refinement records) and solution.json.
fn verified_default_search(tag: &str, args: &[&str]) -> (String, serde_json::Value) {
    let dir = tmpdir(tag);
    let out = dir.join("out");
    let stdout = ok(&optimize_in(&out, None, args));
    let sol = json(&out.join("solution.json"));
    assert_eq!(sol["verification"]["verified"], true, "{stdout}");
    std::fs::remove_dir_all(dir).ok();
    (stdout, sol)
}

/// `--verify-refinements` bounds each candidate's refinements, and the default five let a
/// candidate verify that three do not. The 32 starts on the problem's mesh (no global
/// search) of `periodic-cot --impact-law stick --seed 3`: of the candidates refined in turn
/// (starts 12, 21, 10, 2, …), start 2 fails at its first four refinements and verifies at its
/// fifth (defects 1.2e-2, 7.8e-3, 2.7e-4 and 1.2e-3 with the path 6.1–1.0x its allowance,
/// then 1.6e-7; J = 2.2718e-2), and the search returns it. With three refinements it does not
/// verify, and the search refines the next candidates instead; one of them verifies lower
/// (start 28, J = 8.266e-4 when measured): a chain of refinements does not converge
/// monotonically, and more refinements per candidate do not always give a lower result.
/// (Before `optimize` planned for a Newton plant by default, decision record 0040, these were
/// the default's arguments; which candidate needs the fifth refinement moves with the path.)
#[test]
#[ignore = "about 3.5 min: two searches"]
fn five_refinements_verify_a_candidate_that_three_do_not() {
    let refined_starts = |stdout: &str| -> Vec<String> {
        stdout
            .lines()
            .filter_map(|l| l.strip_prefix("verification refinement: refine start "))
            .filter_map(|l| l.split_whitespace().next())
            .map(str::to_owned)
            .collect()
    };
    let count = |starts: &[String], s: &str| starts.iter().filter(|x| *x == s).count();
    // The 32 starts on the problem's mesh (no global search).
    let args = [
        "--problem",
        "periodic-cot",
        "--impact-law",
        "stick",
        "--hops",
        "0",
        "--seed",
        "3",
    ];
    let (three, sol3) = verified_default_search(
        "seed3-3",
        &[&args[..], &["--verify-refinements", "3"]].concat(),
    );
    let (five, sol5) = verified_default_search("seed3-5", &args);
    let (starts3, starts5) = (refined_starts(&three), refined_starts(&five));
    // The candidates come in the same order either way.
    assert_eq!(starts3.first(), starts5.first(), "{three}\n{five}");
    // Five: the choice verified at its fifth refinement.
    let chosen = sol5["strategy"]["chosen"].to_string();
    assert_eq!(count(&starts5, &chosen), 5, "{five}");
    // Three: no candidate is refined more than three times, the five-refinement choice was
    // refined three times without verifying, and the refinements went on to other candidates.
    let distinct: std::collections::BTreeSet<&String> = starts3.iter().collect();
    assert!(distinct.iter().all(|s| count(&starts3, s) <= 3), "{three}");
    assert_eq!(count(&starts3, &chosen), 3, "{three}");
    assert_ne!(sol3["strategy"]["chosen"].to_string(), chosen, "{three}");
}

/// The default `periodic-cot-human` search: the first refinement of its best coarse candidate
/// (start 1) ends on its starting mesh without verifying, because the refined mesh's solve
/// failed; the second attempt, with a tighter tolerance, refines differently and reaches the
/// lower optimum J ≈ 0.066532 (stopping after the first attempt, as for a refinement the point
/// limit stopped, gave start 0's J ≈ 0.066536 instead). Its release phase dips 2.55 mm into
/// the ball between its nodes, so it does not verify (decision record 0028); the further
/// attempts split the penetrating elements and verify J ≈ 0.0665675 with min h ≥ −1e-4 m.
#[test]
#[ignore = "about 60 s: the default periodic-cot-human search"]
fn a_refinement_whose_refined_mesh_failed_is_retried() {
    // The 32 starts on the problem's mesh (no global search), where start 1 is the best.
    let (stdout, sol) =
        verified_default_search("human", &["--problem", "periodic-cot-human", "--hops", "0"]);
    let attempts = stdout
        .lines()
        .filter(|l| l.starts_with("verification refinement: refine start 1 "))
        .count();
    assert!(attempts >= 3, "{stdout}");
    let j = sol["objective"].as_f64().unwrap();
    assert!(j < 0.06658, "J = {j}");
    for ph in sol["verification"]["phases"].as_array().unwrap() {
        if let Some(h) = ph["min_h"].as_f64() {
            assert!(h >= -1e-4, "phase {}: min h {h}", ph["phase"]);
        }
    }
}

/// Issue target of the global search: the default `periodic-qc` search (128 coarse starts,
/// the reshaping moves, 64 hops) reaches J ≤ 0.08761 (the best known optimum before it,
/// 0.0876082, with the stick phase on its 0.01 s bound), verified, on every seed 0–9.
/// BENCHMARKS.md ("Mirror move and refinement progress") records the optimum of each seed:
/// 0.0876082 on all, the lower 0.0769202 tap that the mirror move reaches on every seed
/// failing the friction-cone verdict; without the elbow flip, seeds 0, 3, 5, 7, 8, 9 missed
/// the target, and without the posture moves of a hop (decision record 0046) seed 8;
/// BENCHMARKS.md ("Reshaping down the ranking") records the seeds with decision record 0047.
#[test]
#[ignore = "about 4 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_reaches_the_best_known_qc_optimum -- --ignored`"]
fn every_seed_reaches_the_best_known_qc_optimum() {
    every_seed_verifies_at_most("periodic-qc", 0.08761);
}

/// Issue target of the global search for the human finger: the default `periodic-cot-human`
/// search verifies within 2 % of the best known optimum, J = 0.0157881 (period 8.46 s, the
/// stick phase on its 0.01 s bound; five seeds of ten find it since the promotion below the
/// best verified plan, decision record 0053, the others 0.0158121–0.0158145), on every seed
/// 0–9. Before the period continuation of the
/// starts (decision record 0037) seeds 5 and 6 verified 0.0665669, on the 10 s period bound.
/// With the search's arithmetic independent of the CPU (decision record 0045), seed 1 verified
/// 0.0665669 while the reshaping stopped once the 4 best shapes had been moved: its way into
/// the best basin starts from the seventh best shape, which the reshaping now reaches by
/// going down the ranking (decision record 0047). BENCHMARKS.md ("Reshaping down the
/// ranking") records each seed.
#[test]
#[ignore = "about 6 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_reaches_the_best_known_cot_human_optimum -- --ignored`"]
fn every_seed_reaches_the_best_known_cot_human_optimum() {
    every_seed_verifies_at_most("periodic-cot-human", 1.02 * 0.0157881);
}

/// Issue target of the global search for the paper's robotic-finger COT problem (the sticking
/// law): every seed 0–9 verifies within 2 % of the best known optimum, J = 8.0564e-5 (period
/// 3.86 s). BENCHMARKS.md ("Refinement rounds that change their shape") records each seed:
/// 8.05640e-5–8.05675e-5 (8.0564e-5–8.0776e-5 before decision record 0060); before the
/// promotion below the best verified plan (decision record 0053) four seeds ended 12–68 %
/// higher.
#[test]
#[ignore = "about 7 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_reaches_the_best_known_cot_optimum -- --ignored`"]
fn every_seed_reaches_the_best_known_cot_optimum() {
    every_seed_verifies_at_most("periodic-cot", 1.02 * 8.0564e-5);
}

/// The plan that `paper` executes in closed loop: the default `periodic-cot-human` plan
/// (Newton's law with the margins and the clearance) verifies on every seed 0–9 within 2 % of
/// J = 0.0447430 (seed 1's, the lowest of the ten), executed in closed loop on the nominal and
/// every perturbed plant. Before the winner's neighbourhood (decision record 0052) seeds 0, 1
/// and 6 returned J = 0.0509500, 14 % higher; before decisions 0050 and 0051 every seed
/// returned the 0.0674639 family. BENCHMARKS.md ("The winner's neighbourhood") records each
/// seed.
#[test]
#[ignore = "about 6 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_verifies_an_executed_human_plan -- --ignored`"]
fn every_seed_verifies_an_executed_human_plan() {
    every_seed_verifies_at_most_with(
        "periodic-cot-human",
        1.02 * 0.0447430,
        &["--impact-law", "newton"],
    );
}

/// The default `periodic-qc` plan (Newton's law with the margins and the clearance): every
/// seed 0–9 returns a verified plan that the hybrid controller executes on every perturbed
/// plant of the robustness table, within 2 % of J = 0.0961834, the plan every seed found in
/// the sweep of BENCHMARKS.md ("The reshaping stops on evidence"; seed 9 0.0965813 before
/// decision record 0066; 0.0961814 on every seed with the bound as a ball, 0.0961760 before
/// decision record 0063). Its best basin is reached by 9–46 distinct sampled optima and hops
/// per search, so a seed that misses it means the sampling or the exploration broke.
#[test]
#[ignore = "about 4.5 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_returns_the_same_robust_qc_plan -- --ignored`"]
fn every_seed_returns_the_same_robust_qc_plan() {
    every_seed_returns_a_robust_plan_below("periodic-qc", 1.02 * 0.0961834);
}

/// The default `periodic-cot` plan (Newton's law with the margins and the clearance): every
/// seed 0–9 returns a verified plan that the bounded hybrid controller executes on every
/// perturbed plant of the robustness table. Before the clearance floor's rise (decision record
/// 0050) and the flight's pace (0051), seven seeds returned a plan that missed the target with
/// 50 % more socket damping. BENCHMARKS.md ("The flight's pace") records each seed. And no
/// seed ends in the family that holds the base joint still (J ≈ 1e-2, three seeds in ten
/// while the starts stayed within ±0.6 rad of the default guess, decision record 0054), and
/// every seed ends in the low family (7.429e-4–7.836e-4 with the box of decision record 0065,
/// 7.507e-4–8.220e-4 with the ball of 0063): every
/// plan is below 9e-4. Before the controller of decision record 0056 and the promotion below
/// the best verified plan (0053), seeds 2, 4 and 7 ended at 2.2e-3, 1.2e-3 and 9.2e-4.
#[test]
#[ignore = "about 15 min on 2 idle cores (ten searches); run with `cargo test --release \
            --test search every_seed_returns_a_robust_cot_plan -- --ignored`"]
fn every_seed_returns_a_robust_cot_plan() {
    every_seed_returns_a_robust_plan_below("periodic-cot", 9e-4);
}

/// The default plan search (Newton's law) of `problem` over seeds 0–9: every seed verifies,
/// executes on every perturbed plant of the robustness table, and ends at J ≤ `limit`.
fn every_seed_returns_a_robust_plan_below(problem: &str, limit: f64) {
    let mut misses = Vec::new();
    for seed in 0..10 {
        let seed = seed.to_string();
        let (_, v) = verified_default_search(
            &format!("{problem}-plan-seed-{seed}"),
            &[
                "--problem",
                problem,
                "--seed",
                &seed,
                "--impact-law",
                "newton",
            ],
        );
        let check = &v["verification"]["execution"];
        if check.is_null() || !check["robustness_failure"].is_null() {
            misses.push(format!("seed {seed}: {check}"));
        }
        let j = v["objective"].as_f64().unwrap();
        if j > limit {
            misses.push(format!("seed {seed}: J {j}"));
        }
    }
    assert!(misses.is_empty(), "{problem}: {misses:?}");
}

/// The promotion's bound (decision record 0053). The coarse mesh under-prices the long free
/// phases of the `periodic-cot` orbits, so the lowest coarse shapes need not be the lowest on
/// the problem's mesh. On seed 0 the first round of eight promoted shapes re-solves at
/// J ≥ 9.3e-4; coarse shapes below that go on being promoted, and the fourth round's
/// re-solve at 8.3e-4, which the search verifies and executes.
#[test]
fn the_promotion_goes_on_while_a_coarse_shape_can_still_win() {
    let (_, v) = verified_default_search(
        "cot-plan-seed-0-bound",
        &[
            "--problem",
            "periodic-cot",
            "--seed",
            "0",
            "--impact-law",
            "newton",
        ],
    );
    let j = v["objective"].as_f64().unwrap();
    assert!(j < 9e-4, "J {j}");
    // Executed in closed loop, and robust.
    assert!(v["verification"]["execution"].is_object());
    assert!(
        v["verification"]["execution"]["robustness_failure"].is_null(),
        "{}",
        v["verification"]["execution"]
    );
    let promoted = v["strategy"]["records"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["stage"] == "full mesh")
        .count();
    let round = ball_finger::pipeline::search::DEFAULT_COARSE.promote;
    assert!(promoted > round, "{promoted} promoted");
}

/// The promotion's bound against what verified (decision record 0053), on `periodic-cot`
/// seed 3. The refinement of chain 376 verified at 8.276e-4, and the search went on below it:
/// the shapes promoted after it refined to 7.890e-4 and to the winner, 7.814e-4. (Before
/// decision record 0065 the test ran seed 8, whose winner also came from the promotion's
/// close start; the box's seed 8 verifies nothing above its winner, and the close start has
/// its own test, `a_promotion_stays_in_the_basin_of_its_coarse_optimum`. The seeds' spread
/// is in BENCHMARKS.md, "The Newton bound as a box".)
#[test]
fn the_promotion_goes_on_below_the_best_verified_plan() {
    let (stdout, v) = verified_default_search(
        "cot-plan-seed-3-bound",
        &[
            "--problem",
            "periodic-cot",
            "--seed",
            "3",
            "--impact-law",
            "newton",
        ],
    );
    let j = v["objective"].as_f64().unwrap();
    assert!(j < 8.1e-4, "J {j}");
    assert!(
        v["verification"]["execution"]["robustness_failure"].is_null(),
        "{}",
        v["verification"]["execution"]
    );
    // A refinement verified (its line names no failure and its defect is within the
    // tolerance) at an objective more than 3 % above the winner's: the search went on past it.
    let verified_above = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("verification refinement: "))
        .filter(|l| {
            !["path", "missed", "failed", "not executed"]
                .iter()
                .any(|w| l.contains(w))
        })
        .filter_map(|l| {
            let defect: f64 = l
                .split("(defect ")
                .nth(1)?
                .split(')')
                .next()?
                .parse()
                .ok()?;
            let objective: f64 = l
                .split("objective ")
                .nth(1)?
                .split(',')
                .next()?
                .parse()
                .ok()?;
            Some((defect, objective))
        })
        .any(|(d, o)| d <= 1e-4 && o > 1.03 * j);
    assert!(verified_above, "{stdout}");
}

/// The promotion's barrier start (decision record 0059). The fixture is a coarse optimum of
/// `periodic-cot` seed 5's exploration (a basin hop, chain 342; 3 Radau elements of 4 points
/// per phase, J = 5.991e-4, period 9.60 s). Re-solved on the problem's mesh from its
/// interpolated trajectory at a warm start's μ₀ = 1e-4, the iterates leave its basin for a
/// period on the 10 s bound and seven times the objective (4.25e-3); from `PROMOTE_MU_INIT`
/// they stay in it (7.58e-4, period 8.94 s: within 50 % of the coarse objective, which prices
/// the long free phases low), in fewer iterations (63 against 109).
#[test]
fn a_promotion_stays_in_the_basin_of_its_coarse_optimum() {
    use ball_finger::pipeline::search::PROMOTE_MU_INIT;
    use ball_finger::pipeline::solve::{INTERPOLATED_MU_INIT_MAX, settings_of, solve_with_mu_max};
    use ball_finger::pipeline::{OcpSolution, SolutionIo, build};
    use bf_problem::ProblemSettings;

    let coarse =
        OcpSolution::read_json(&root().join("tests/fixtures/coarse-cot-shape/solution.json"))
            .unwrap();
    let (name, settings) = settings_of(&coarse).unwrap();
    let on_the_mesh = ProblemSettings {
        points: ProblemSettings::default().points,
        warm_start: Some(coarse.clone()),
        ..settings
    };
    let b = build(name, &on_the_mesh).unwrap();
    assert!(b.settings.points > coarse.points);
    let away = solve_with_mu_max(&b, INTERPOLATED_MU_INIT_MAX, None).unwrap();
    let close = solve_with_mu_max(&b, PROMOTE_MU_INIT, None).unwrap();
    let (j0, t0) = (coarse.objective, coarse.period);
    assert!(away.status.is_success() && close.status.is_success());
    assert!(
        away.objective > 5.0 * j0 && away.period > 10.0 - 1e-6,
        "from 1e-4: J {} T {} (coarse J {j0} T {t0})",
        away.objective,
        away.period
    );
    assert!(
        close.objective < 1.5 * j0 && close.period < 10.0 - 0.1,
        "from {PROMOTE_MU_INIT:e}: J {} T {} (coarse J {j0} T {t0})",
        close.objective,
        close.period
    );
    assert!(close.iterations < away.iterations);
}

/// The choice between two solves of one problem (`pipeline::solve::better_solve`: the
/// promotion's two starts, a refinement round and its solve again): a successful solve beats
/// a failed one whatever the objectives, a non-finite objective never wins, between two
/// successful ones the lower wins, and of two equal ones neither (the first is kept).
#[test]
fn the_better_of_two_solves_is_the_successful_lower_one() {
    use ball_finger::pipeline::solve::better_solve;
    use ball_finger::pipeline::{OcpSolution, SolutionIo};
    use bf_optim::ipm::Status;

    let base =
        OcpSolution::read_json(&root().join("tests/fixtures/coarse-cot-shape/solution.json"))
            .unwrap();
    let with = |status, objective| OcpSolution {
        status,
        objective,
        ..base.clone()
    };
    let (low, high) = (with(Status::Solved, 1.0), with(Status::Acceptable, 2.0));
    assert!(better_solve(&low, &high) && !better_solve(&high, &low));
    assert!(!better_solve(&low, &low.clone()));
    let failed = with(Status::MaxIterations, 0.5);
    assert!(better_solve(&high, &failed) && !better_solve(&failed, &high));
    let nan = with(Status::Solved, f64::NAN);
    assert!(better_solve(&high, &nan) && !better_solve(&nan, &high));
    assert!(!better_solve(&failed, &nan) && !better_solve(&nan, &failed));
}

/// Runs the default search of `problem` for seeds 0–9 and asserts that each verifies at an
/// objective of at most `target`, naming every seed that does not.
fn every_seed_verifies_at_most(problem: &str, target: f64) {
    every_seed_verifies_at_most_with(problem, target, &[]);
}

/// [`every_seed_verifies_at_most`] with the options `extra` (the sticking law unless they name
/// one).
fn every_seed_verifies_at_most_with(problem: &str, target: f64, extra: &[&str]) {
    let mut misses = Vec::new();
    for seed in 0..10 {
        let seed = seed.to_string();
        let mut args = vec!["--problem", problem, "--seed", &seed];
        args.extend_from_slice(extra);
        let (_, v) = verified_default_search(&format!("{problem}-seed-{seed}"), &args);
        let j = v["objective"].as_f64().unwrap();
        if j > target {
            misses.push(format!("seed {seed}: J {j}"));
        }
    }
    assert!(misses.is_empty(), "{problem}: {misses:?}");
}

/// The winner's neighbourhood on its own mesh (`Search::polish_the_winner`, decision record
/// 0052). The fixture is a human finger's plan solved on the box rows of decision record 0065
/// warm from the plan that seeds 0, 1 and 6 returned before that polishing (J = 0.0509500,
/// phases 8.10 / 0.19 / 0.17 s; `optimize --warm-start` of that file): J = 0.0505279, phases
/// 9.64 / 0.19 / 0.17 s on the 10 s period bound, verified, executed in closed loop and
/// robust. From it alone, the reshaping moves and hops solved on its refined mesh reach
/// the family that the searches return, at J ≈ 0.0448 (phases 2.53 / 0.19 / 7.28 s): more
/// than 10 % lower, verified, executed and robust.
#[test]
fn the_winners_neighbourhood_leads_to_the_lower_plan_beside_it() {
    use ball_finger::paper::closed_loop::execution_check;
    use ball_finger::pipeline::search::{Candidate, DEFAULT_HOPS, Execution, Search, VerifyPolicy};
    use ball_finger::pipeline::solve::{own_problem, settings_of};
    use ball_finger::pipeline::strategy::{Shard, Strategy};
    use ball_finger::pipeline::verify::{is_robust, is_verified};
    use ball_finger::pipeline::{OcpSolution, SolutionIo, build};

    let sol =
        OcpSolution::read_json(&root().join("tests/fixtures/human-plan-j0505279/solution.json"))
            .unwrap();
    assert!(is_verified(&sol) && is_robust(&sol));
    let j0 = sol.objective;
    let fixture = sol.clone();
    let (name, settings) = settings_of(&sol).unwrap();
    let on_its_mesh = bf_problem::ProblemSettings {
        mesh: sol.refinement.as_ref().map(|r| r.mesh.clone()),
        ..settings.clone()
    };
    let built = build(name, &on_its_mesh).unwrap();
    let policy = VerifyPolicy {
        rtol: sol.verification.as_ref().unwrap().rtol,
        execution: Some(Execution(execution_check)),
        ..VerifyPolicy::default()
    }
    .global(DEFAULT_HOPS);
    let mut found = Search {
        strategy: Strategy::Multistart {
            starts: 128,
            seed: 0,
        },
        shard: Shard::WHOLE,
        candidates: vec![Candidate {
            index: 0,
            problem: Some(built),
            solution: sol,
        }],
        sampled: Vec::new(),
        records: Vec::new(),
        refinements: Vec::new(),
        seconds: 0.0,
        basin_hits: None,
    };
    found.polish_the_winner(name, &settings, &policy, None);
    // Every candidate records the mesh it was solved on (the neighbourhood's solves that were
    // not refined, that of their origin).
    assert!(found.candidates.len() > 1);
    for c in &found.candidates {
        let built = c.problem.as_ref().unwrap();
        assert_eq!(
            c.solution.refinement.as_ref().map(|r| &r.mesh),
            built.settings.mesh.as_ref(),
            "candidate {}",
            c.index
        );
    }
    let (_, best) = found.best().unwrap();
    assert!(
        is_verified(&best) && is_robust(&best),
        "{:?}",
        best.verification
    );
    assert!(best.objective < 0.9 * j0, "J {} from {j0}", best.objective);
    assert!((best.period - 10.0).abs() < 1e-3, "period {}", best.period);
    // Solved on a refined mesh, the plan records that mesh: with the scene that `optimize`
    // records beside it, its file can be solved again on its own problem.
    let mut file = best.clone();
    file.scene_toml.clone_from(&fixture.scene_toml);
    file.scene_params.clone_from(&fixture.scene_params);
    file.search_settings.clone_from(&fixture.search_settings);
    if let Err(e) = own_problem(&file) {
        panic!("{e}");
    }
}
