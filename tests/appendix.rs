//! `ball-finger verify appendix` and its library function
//! (`ball_finger::paper::appendix::check_appendix`): the verdicts are those of
//! docs/appendix-errata.md (each worked out by hand there), and each verdict on a kinematic or
//! dynamic entry is confirmed by a second derivation independent of the one the check uses:
//! the generator's expression graph of the paper scene, evaluated by its interpreter.

#[path = "common/cli.rs"]
mod cli;

use ball_finger::paper::appendix::{Verdict, check_appendix, check_appendix_scaled};
use bf_codegen::{EvalValue, Scene, eval_all};
use bf_testkit::appendix as app;

fn verdict(entries: &[ball_finger::paper::appendix::Entry], eq: &str, what: &str) -> Verdict {
    entries
        .iter()
        .find(|e| e.eq == eq && e.what.contains(what))
        .unwrap_or_else(|| panic!("no entry eq. {eq} {what}"))
        .verdict
}

fn flat(v: &EvalValue) -> Vec<f64> {
    match v {
        EvalValue::Scalar(x) => vec![*x],
        EvalValue::Vector(x) => x.clone(),
        EvalValue::Matrix(m) => m.concat(),
    }
}

/// The paper scene with ball radius (and base offset 2r) `r`, evaluated by the interpreter.
fn interp(r: f64, q: [f64; 3], qd: [f64; 3]) -> impl Fn(&str) -> Vec<f64> {
    let text = bf_generated::paper::SCENE_TOML
        .replace(
            "translation = [2.0, 0.0, 0.0]",
            &format!("translation = [{}, 0.0, 0.0]", 2.0 * r),
        )
        .replace("radius = 1.0", &format!("radius = {r}"));
    assert!(r == 1.0 || text != bf_generated::paper::SCENE_TOML);
    let scene = Scene::from_toml_str(&text, "paper-variant").unwrap();
    let out = eval_all(&scene, &q, &qd, [0.0; 3], 0.01).unwrap();
    move |name: &str| flat(out.get(name).unwrap())
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn verdicts_match_the_errata_and_the_generator() {
    let entries = check_appendix().expect("every derivation agrees with printed or corrected");
    // docs/appendix-errata.md: misprints 1–6, the notation remark, and the correct entries.
    assert_eq!(verdict(&entries, "67", "r = ℓ"), Verdict::Correct);
    assert_eq!(verdict(&entries, "67", "r ≠ ℓ"), Verdict::Misprint);
    assert_eq!(verdict(&entries, "68", ""), Verdict::Correct);
    assert_eq!(verdict(&entries, "70", ""), Verdict::Misprint);
    assert_eq!(verdict(&entries, "71", ""), Verdict::Correct);
    assert_eq!(verdict(&entries, "72–73", ""), Verdict::Misprint);
    assert_eq!(verdict(&entries, "72", "g_0"), Verdict::Misprint);
    assert_eq!(verdict(&entries, "22b", ""), Verdict::Misprint);
    assert_eq!(verdict(&entries, "23", ""), Verdict::Misprint);
    assert_eq!(verdict(&entries, "74–75", ""), Verdict::Correct);
    assert_eq!(verdict(&entries, "76–79", ""), Verdict::Correct);
    assert_eq!(verdict(&entries, "72–79 (notation)", ""), Verdict::Notation);
    for e in &entries {
        assert!(e.printed_error.is_finite() && e.sample.printed.is_finite());
        if e.verdict == Verdict::Misprint {
            // The sample shows the disagreement it reports.
            assert!((e.sample.printed - e.sample.derived).abs() > 1e-3, "{e:?}");
        }
    }

    // The generator's graphs agree with the verdicts, at states of its own choosing.
    let a = app::AppendixParams::paper();
    for (k, q) in [[0.3, -1.1, 2.0], [-2.5, 0.7, -0.4], [1.9, 2.8, -3.0]]
        .into_iter()
        .enumerate()
    {
        let qd = [0.5, -0.2, 1.0];
        let g = interp(1.0, q, qd);
        let flat3 = |m: [[f64; 3]; 3]| m.concat();
        assert!(max_diff(&flat3(app::frame3_axes_printed(&q)), &g("R3")) < 1e-12);
        assert!(max_diff(&flat3(app::jo_printed(&q)), &g("J_o")) < 1e-12);
        assert!(max_diff(&flat3(app::mass_matrix_printed(&q, &a)), &g("M")) < 1e-12);
        assert!(max_diff(&flat3(app::coriolis_printed(&q, &qd, &a)), &g("C")) < 1e-12);
        let jp = flat3(app::jp_printed(&q, 1.0));
        let gjp = g("J_p");
        assert!(max_diff(&jp[..8], &gjp[..8]) < 1e-12);
        assert!(
            (jp[8] + gjp[8]).abs() < 1e-12 && gjp[8].abs() > 1e-3,
            "state {k}"
        );
        let gp = app::gravity_printed(&q, &a, a.g);
        let gg = g("g");
        assert!((gp[0] - gg[0]).abs() < 1e-12);
        assert!(max_diff(&gp[1..], &gg[1..]) > 1e-4, "state {k}");
        // r ≠ ℓ: eq. 67's x-component is off by exactly 2(r − ℓ).
        let g13 = interp(1.3, q, qd);
        let pe = app::p_e_printed(&q, 1.0);
        let gpe = g13("p_e");
        assert!(((gpe[0] - pe[0]) - 0.6).abs() < 1e-12);
        assert!(max_diff(&pe[1..], &gpe[1..]) < 1e-12);
    }
}

#[test]
fn a_failed_derivation_is_an_error_naming_the_entries() {
    // With zero tolerance nothing agrees, so every entry fails.
    let e = check_appendix_scaled(0.0).unwrap_err().to_string();
    assert!(e.contains("eq. 68") && e.contains("eq. 74–75"), "{e}");
}

#[test]
fn command_prints_printed_vs_derived_and_the_misprints() {
    let out = cli::run(&["verify", "appendix"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("| printed | derived |"), "{stdout}");
    assert!(stdout.contains("Misprints (6;"), "{stdout}");
    assert_eq!(stdout.matches("| MISPRINT |").count(), 6, "{stdout}");
    let bad = cli::run(&["verify", "everything"]);
    assert!(!bad.status.success());
}
