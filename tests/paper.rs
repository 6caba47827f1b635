//! `ball-finger paper --quick` end to end: the report is written atomically into the requested
//! directory, lists every built-in scene, and the verification numbers it states are the ones
//! required of the kernels (compiled = interpreted to 1e-12, M positive definite, Ṁ − 2C skew).

#[path = "common/cli.rs"]
mod cli_util;

use std::process::Command;

fn numbers_after(report: &str, row_prefix: &str) -> f64 {
    let line = report
        .lines()
        .find(|l| l.starts_with(row_prefix))
        .unwrap_or_else(|| panic!("report has no row starting with {row_prefix:?}"));
    let cell = line
        .trim_end_matches('|')
        .rsplit('|')
        .next()
        .unwrap()
        .trim();
    cell.parse()
        .unwrap_or_else(|_| panic!("not a number in {line:?}"))
}

#[test]
fn paper_quick_writes_a_consistent_report() {
    let out = cli_util::tmpdir("quick");
    let status = Command::new(env!("CARGO_BIN_EXE_ball-finger"))
        .args(["paper", "--quick", "--out", out.to_str().unwrap()])
        .output()
        .expect("binary runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md written");
    for scene in ["paper", "human", "puma560", "iiwa7"] {
        assert!(
            report.contains(&format!("| {scene} |")),
            "generation row for {scene}"
        );
    }
    for row in [
        "| compiled vs interpreter, max abs diff of M",
        "| compiled vs interpreter, max abs diff of C",
        "| compiled vs interpreter, max abs diff of g",
        "| compiled vs interpreter, max abs diff of J_c",
        "| (Ṁ − 2C) + (Ṁ − 2C)ᵀ",
    ] {
        let v = numbers_after(&report, row);
        assert!((0.0..1e-12).contains(&v), "{row}: {v}");
    }
    assert!(numbers_after(&report, "| smallest leading principal minor") > 0.0);

    // The results table states what the solution files say.
    for name in ["periodic-cot", "periodic-cot-human", "periodic-qc"] {
        let text = std::fs::read_to_string(out.join(name).join("solution.json"))
            .unwrap_or_else(|e| panic!("{name}/solution.json: {e}"));
        let sol: serde_json::Value = serde_json::from_str(&text).unwrap();
        let row = report
            .lines()
            .find(|l| l.starts_with(&format!("| {name} |")))
            .unwrap_or_else(|| panic!("no results row for {name}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[2], sol["status"].as_str().unwrap(), "{name} status");
        let objective: f64 = cells[3].parse().unwrap();
        let period: f64 = cells[4].parse().unwrap();
        let expect_obj = sol["objective"].as_f64().unwrap();
        let expect_period = sol["period"].as_f64().unwrap();
        assert!(
            (objective - expect_obj).abs() <= 1e-5 * expect_obj.abs(),
            "{name} objective"
        );
        assert!((period - expect_period).abs() <= 1e-4, "{name} period");
        // The active bounds the report lists are the ones the solution file records.
        let listed = report
            .lines()
            .find(|l| l.starts_with(&format!("- `{name}`: ")))
            .unwrap_or_else(|| panic!("no active-bounds line for {name}"));
        let recorded = sol["active_bounds"]
            .as_array()
            .unwrap_or_else(|| panic!("{name}: no active_bounds in solution.json"));
        if recorded.is_empty() {
            assert!(listed.ends_with(": none"), "{listed}");
        } else {
            assert_eq!(listed.matches("; ").count() + 1, recorded.len(), "{listed}");
            for b in recorded {
                let what = b["what"].as_str().unwrap();
                assert!(listed.contains(what), "{name}: {what} not in {listed}");
            }
        }
        // The re-integration defect shown is the one stored with the solution.
        let defect: f64 = cells[10].parse().unwrap();
        let expect_defect = sol["verification"]["max_defect"].as_f64().unwrap();
        assert!(
            (defect - expect_defect).abs() <= 0.06 * expect_defect,
            "{name} defect {defect} vs {expect_defect}"
        );
        // The table shows the solution file's verdict, which also counts the path checks
        // (penetration, friction cone); a re-integration defect above 1e-4 (state units) is
        // never verified. An unverified solution is flagged in the table, and every claim that
        // rests on it says so.
        let verified = sol["verification"]["verified"].as_bool().unwrap();
        assert!(
            expect_defect <= 1e-4 || !verified,
            "{name}: verified with defect {expect_defect}"
        );
        assert_eq!(
            cells[11],
            if verified { "yes" } else { "**no**" },
            "{name}: verified flag for defect {expect_defect}, file verdict {verified}"
        );
        if !verified {
            assert!(
                report
                    .lines()
                    .any(|l| l.contains("(**unverified**: ") && l.contains(name)),
                "{name}: claims on an unverified solution are flagged"
            );
        }
        // The mesh the optimum ends on, from the solution file: its collocation points per
        // phase counted from its nodes (each phase's nodes are its points and its start
        // state), its elements from the refinement's mesh, else from the scheme.
        let node_phase: Vec<u64> = sol["nodes"]["phase"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        let phases = sol["modes"].as_array().unwrap().len() as u64;
        let mesh: Vec<String> = (0..phases)
            .map(|p| {
                let points = node_phase.iter().filter(|&&q| q == p).count() - 1;
                let elements = match sol["refinement"]["mesh"].as_array() {
                    Some(m) => m[p as usize]["degrees"].as_array().unwrap().len() as u64,
                    None => sol["scheme"]["Radau"]["elements"].as_u64().unwrap(),
                };
                format!("{points} ({elements})")
            })
            .collect();
        assert_eq!(cells[12], mesh.join(", "), "{name}: the mesh it ends on");
        assert_eq!(cells[13], "direct", "{name}: --quick solves directly");
        // The scenario's stage listing accounts for every iteration the table counts: its
        // kept chain's solves and verification refinements (a refinement's hp rounds are
        // indented under it, parts of its count), against the file's total.
        let iterations: usize = cells[14].parse().unwrap();
        assert_eq!(iterations as u64, sol["iterations"].as_u64().unwrap());
        let section = &report[report.find(&format!("\n### {name}\n")).unwrap()..];
        let listing = &section[section.find("Solve stages").unwrap()..];
        let listing = &listing[listing.find("```text\n").unwrap() + 8..];
        let listing = &listing[..listing.find("```").unwrap()];
        let head = listing.lines().nth(1).unwrap();
        let status_col = head.find("status").unwrap();
        let mut listed = 0;
        for l in listing.lines().skip(2) {
            // Aligned columns whatever a stage is called: the status starts under its head.
            assert!(
                l[status_col..].starts_with("Solved") || l[status_col..].starts_with('A'),
                "{name}: misaligned {l:?} under {head:?}"
            );
            // "* CHAIN  STAGE": the stage column starts under its head's "stage".
            let stage = l[head.find("stage").unwrap()..status_col].trim_end();
            let indented = stage.starts_with("  ");
            assert_eq!(
                indented,
                stage.trim_start().starts_with("hp round"),
                "{l:?}"
            );
            if !indented && !stage.starts_with("stored optimum") {
                listed += l
                    .split_whitespace()
                    .rev()
                    .nth(1)
                    .unwrap()
                    .parse::<usize>()
                    .unwrap();
            }
        }
        assert_eq!(
            listed, iterations,
            "{name}: the listing's iterations\n{listing}"
        );
        // Independent check of the period: the phase durations add up to it.
        let sum: f64 = sol["phase_durations"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_f64().unwrap())
            .sum();
        assert!(
            (sum - expect_period).abs() < 1e-9,
            "{name}: durations sum to the period"
        );
        let torques = std::fs::read_to_string(out.join(name).join("torques.csv")).unwrap();
        assert!(
            torques.starts_with("t [s],tau1 [N m],tau2 [N m],tau3 [N m]"),
            "{name} torques.csv header"
        );
        assert!(out.join(format!("animation_{name}.html")).exists());
        // Figures with a counterpart in the paper (Sect. 6.1, Figs. 5–16) carry its number in
        // the file name and the title.
        let numbered: &[(&str, u32)] = match name {
            "periodic-cot" => &[
                ("paths", 5),
                ("omega", 6),
                ("distance", 7),
                ("torques", 8),
                ("forces", 9),
            ],
            "periodic-cot-human" => &[("paths", 10)],
            _ => &[
                ("paths", 12),
                ("omega", 13),
                ("distance", 14),
                ("torques", 15),
                ("forces", 16),
            ],
        };
        for fig in ["paths", "omega", "distance", "torques", "forces"] {
            let number = numbered.iter().find(|(f, _)| *f == fig).map(|(_, n)| *n);
            let stem = match number {
                Some(n) => format!("fig{n}_{name}_{fig}"),
                None => format!("{name}_{fig}"),
            };
            for ext in ["svg", "png"] {
                let f = out.join("figures").join(format!("{stem}.{ext}"));
                let len = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
                assert!(len > 1000, "{} is missing or empty", f.display());
            }
            if let Some(n) = number {
                let svg = std::fs::read_to_string(out.join("figures").join(format!("{stem}.svg")))
                    .unwrap();
                assert!(
                    svg.contains(&format!("Fig. {n} counterpart")),
                    "{stem}.svg title names Fig. {n}"
                );
            }
        }
    }
    // Every claim has a verdict, and every "differs" its paragraph (also in the min-stick
    // comparison, which repeats the claims per run).
    let rows: Vec<&str> = report
        .lines()
        .filter(|l| l.ends_with("| agrees |") || l.contains("| differs"))
        .collect();
    assert!(rows.len() >= 7, "{rows:?}");
    let mut paragraphs = report.lines().filter(|l| l.starts_with("- **Claim "));
    for row in rows.iter().filter(|r| r.contains("| differs")) {
        let n = row.split('|').nth(1).unwrap().trim();
        let para = paragraphs
            .find(|p| p.starts_with(&format!("- **Claim {n}**")))
            .unwrap_or_else(|| panic!("no paragraph for the differing claim {row}"));
        assert!(para.contains("sits on"), "{para}");
    }
    // The active bounds are those of the solutions: the COT period on its 10 s maximum.
    let cot: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("periodic-cot").join("solution.json")).unwrap(),
    )
    .unwrap();
    let line = report
        .lines()
        .find(|l| l.starts_with("- `periodic-cot`: "))
        .expect("active bounds of periodic-cot");
    let on_max = (cot["period"].as_f64().unwrap() - 10.0).abs() <= 1e-5 + 1e-3;
    assert_eq!(line.contains("period (s) = "), on_max, "{line}");
    // Penetration and cone margins are stated with their tolerances.
    assert!(
        report.contains("| scenario | min h (m) | smoothing (m) | within | phase | min σ (N) |")
    );
    // The figures built from several scenarios or the open-loop run.
    for (stem, n) in [("fig11_compare_paths", 11), ("fig17_open_loop", 17)] {
        let svg = std::fs::read_to_string(out.join("figures").join(format!("{stem}.svg")))
            .unwrap_or_else(|e| panic!("{stem}.svg: {e}"));
        assert!(svg.contains(&format!("Fig. {n} counterpart")), "{stem}");
        assert!(out.join("figures").join(format!("{stem}.png")).exists());
        assert!(
            report.contains(&format!("figures/{stem}.svg")),
            "{stem} linked"
        );
    }
    // Sect. 6.2: every optimum executed by the three controllers, with a verdict each; the
    // hybrid controller keeps the QC optimum's ω within the 2 % target in its first period
    // (the open loop's error is whatever it is).
    let s5 = &report[report.find("## 5.").unwrap()..report.find("## 6.").unwrap()];
    assert!(s5.contains("### Open loop, PD and hybrid control side by side"));
    for name in ["periodic-cot", "periodic-cot-human", "periodic-qc"] {
        assert!(
            s5.contains(&format!(
                "Verdict on \"the open loop matches well at the beginning\" for `{name}`: "
            )),
            "{name}: no verdict"
        );
    }
    let qc = &s5[s5.find("**`periodic-qc`**").expect("the QC table")..];
    assert!(
        qc.lines().any(|l| l.starts_with("| hybrid |")),
        "bounded row"
    );
    // The cold direct QC optimum of --quick rides the 1 N m bound at 13 nodes, where the
    // bounded controller has no feedback left; the target is checked without the bound.
    let hybrid = qc
        .lines()
        .find(|l| l.starts_with("| hybrid-unbounded |"))
        .expect("hybrid-unbounded row");
    let first: f64 = hybrid.split('|').nth(3).unwrap().trim().parse().unwrap();
    assert!(first <= 2.0, "{hybrid}");
    // §8 is the appendix check computed in the run (printed vs derived, six misprints).
    let s8 = &report[report.find("## 8.").expect("section 8")..];
    assert!(s8.contains("| printed | derived |") && s8.contains("Misprints (6;"));
    // §6 is a summary with the meaning of its "error estimate" column; the rows are in the CSV.
    let s6 = &report[report.find("## 6.").unwrap()..report.find("## 7.").unwrap()];
    assert!(
        s6.contains("\"Error estimate\":") && s6.contains("extremes.csv"),
        "{s6}"
    );
    let csv = std::fs::read_to_string(out.join("extremes.csv")).expect("extremes.csv written");
    assert!(csv.lines().next().unwrap().contains("time [s]"));
    let probes = s6
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| case"))
        .count();
    assert!(
        csv.lines().count() > 2 * probes,
        "the CSV has every row, the report one per probe"
    );
    // No Rust Debug text in the report.
    for pattern in ["Some(", "None", " { ", "Rk4", "Dopri5"] {
        assert!(
            !report.contains(pattern),
            "Debug text `{pattern}` in report.md"
        );
    }
    // Without a terminal (stderr is a pipe here), progress comes as lines, one per stage.
    let stderr = String::from_utf8_lossy(&status.stderr);
    for stage in [
        "paper: 1/8 code generation",
        "paper: 6/8 extremes",
        "paper: 8/8 appendix check",
    ] {
        assert!(
            stderr.contains(stage),
            "no progress line `{stage}`:\n{stderr}"
        );
    }
    // Every artefact is written through a temporary file and a rename: none may be left over.
    let mut stack = vec![out.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                assert!(
                    !p.to_string_lossy().ends_with(".tmp"),
                    "left over: {}",
                    p.display()
                );
            }
        }
    }
    std::fs::remove_dir_all(out).ok();
}
