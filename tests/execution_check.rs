//! The closed-loop check that verifies a plan for the plant (decision record 0048,
//! `paper::closed_loop::execution_check`, run by the search on every candidate of a Newton
//! plan whose re-integration verifies):
//! * the human finger's plan of J = 0.0452 (a fixture: the default search's optimum before the
//!   check) re-integrates within its tolerance and passes every path check, yet the bounded
//!   hybrid controller does not execute it (its release grazes the ball, and the plant falls
//!   back onto it after the lift-off): the check fails it, far beyond the tolerance;
//! * the stored default plans that `paper` executes pass it;
//! * a verification record with a failed check is not verified, and its verdict names the
//!   closed loop, while the same record without the check is verified.

use std::path::{Path, PathBuf};

use ball_finger::paper::closed_loop::{EXECUTION_TOLERANCE, execution_check};
use ball_finger::pipeline::verify::{execution_failure, is_verified, verdict_failure};
use ball_finger::pipeline::{OcpSolution, SolutionIo};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn grazing_plan() -> OcpSolution {
    OcpSolution::read_json(&root().join("tests/fixtures/grazing-human-plan/solution.json")).unwrap()
}

#[test]
fn the_grazing_human_plan_verifies_by_its_reintegration_but_fails_the_closed_loop() {
    let mut sol = grazing_plan();
    assert!(sol.objective < 0.046, "J = {}", sol.objective);
    let mut v = sol.verification.clone().expect("a verification record");
    v.execution = None;
    sol.verification = Some(v.clone());
    assert!(
        is_verified(&sol),
        "the fixture's re-integration verifies: {:?}",
        verdict_failure(&v)
    );

    let check = execution_check(&sol).expect("the human scene is compiled in");
    // It fails on the nominal plant already, so the perturbed plants are not run.
    assert_eq!(check.robustness_periods, 0);
    assert!(
        check.max_omega_error > 10.0 * EXECUTION_TOLERANCE,
        "max error {}",
        check.max_omega_error
    );
    assert!(check.failure.is_some());

    v.execution = Some(check);
    sol.verification = Some(v.clone());
    assert!(!is_verified(&sol));
    let why = verdict_failure(&v).expect("a reason");
    assert!(why.contains("closed loop"), "{why}");
    assert_eq!(execution_failure(&v).as_deref(), Some(why.as_str()));
}

#[test]
fn the_stored_default_plans_pass_the_closed_loop_check() {
    for dir in ["periodic-qc-plan", "periodic-cot-human-plan"] {
        let sol =
            OcpSolution::read_json(&root().join("data/optima").join(dir).join("solution.json"))
                .unwrap();
        let check = execution_check(&sol).expect("a compiled scene");
        assert!(
            check.failure.is_none() && check.max_omega_error <= EXECUTION_TOLERANCE,
            "{dir}: {check:?}"
        );
        // The search that stored it ran the same check, with the same verdict.
        let stored = sol
            .verification
            .as_ref()
            .and_then(|v| v.execution.as_ref())
            .expect("the stored plan's check");
        assert!(stored.failure.is_none(), "{dir}: {stored:?}");
    }
}
