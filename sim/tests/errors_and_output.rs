//! Bad inputs give clear errors, failures keep the partial trajectory, writers round-trip.
//!
//! x' = x² blows up at t = 1/x₀: the run must fail (step size / non-finite) and return the
//! samples computed before, which must still match x = 1/(1/x₀ − t). A system error raised
//! mid-run (the model's "singular Γ") must likewise come back with the partial data.

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

use bf_sim::toys::{BallMode, BlowUp, BouncingBall, Oscillator};
use bf_sim::{Guard, HybridSystem, SimError, SimSettings, Transition, simulate};

fn tmpdir(tag: &str) -> TempDir {
    TempDir::fresh(std::env::temp_dir().join(format!("bf-sim-{tag}-{}", std::process::id())))
}

#[test]
fn setup_errors_are_specific() {
    let osc = Oscillator { omega: 1.0 };
    let set = SimSettings::default;
    let e = simulate(&osc, set(), (), 0.0, &[f64::NAN, 0.0], 1.0).unwrap_err();
    assert!(matches!(e.error, SimError::NonFinite { .. }), "{}", e.error);
    assert!(e.partial.trajectory.is_empty());
    for t_end in [0.0, -1.0, f64::NAN] {
        let e = simulate(&osc, set(), (), 0.0, &[1.0, 0.0], t_end).unwrap_err();
        assert!(
            matches!(e.error, SimError::InvalidSetting { name: "t_end", .. }),
            "{}",
            e.error
        );
    }
    let e = simulate(&osc, set(), (), 0.0, &[1.0], 1.0).unwrap_err();
    assert!(matches!(
        e.error,
        SimError::DimensionMismatch {
            expected: 2,
            found: 1,
            ..
        }
    ));
    let bad = SimSettings {
        rtol: -1.0,
        ..set()
    };
    let e = simulate(&osc, bad, (), 0.0, &[1.0, 0.0], 1.0).unwrap_err();
    assert!(matches!(
        e.error,
        SimError::InvalidSetting { name: "rtol", .. }
    ));
    let bad = SimSettings {
        h_min: 1.0,
        h_max: 0.1,
        ..set()
    };
    assert!(bad.validate().is_err());
}

#[test]
fn blow_up_returns_partial_trajectory() {
    let x0 = 2.0; // blow-up at t = 0.5
    let fail = simulate(&BlowUp, SimSettings::default(), (), 0.0, &[x0], 1.0).unwrap_err();
    assert!(
        matches!(
            fail.error,
            SimError::StepSizeTooSmall { .. }
                | SimError::NonFinite { .. }
                | SimError::MaxSteps { .. }
        ),
        "{}",
        fail.error
    );
    // The last accepted steps may straddle the pole by a few ulps of the step size.
    assert!(
        fail.t < 0.5 + 1e-6 && fail.t > 0.49,
        "stopped at {}",
        fail.t
    );
    let tr = &fail.partial.trajectory;
    assert!(tr.len() > 10);
    for (t, x) in tr.t.iter().zip(&tr.x).filter(|(t, _)| **t < 0.499) {
        let exact = 1.0 / (1.0 / x0 - t);
        assert!(
            ((x[0] - exact) / exact).abs() < 1e-5,
            "t = {t}: {} vs {exact}",
            x[0]
        );
    }
}

/// x' = 1 whose vector field fails (like a singular contact matrix) once t > 0.3; one guard
/// at x = 0.1 switches to a guard-less second mode.
struct Fails;

impl HybridSystem for Fails {
    type Mode = bool;
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _: bool, t: f64, _: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        if t > 0.3 {
            return Err(SimError::system("singular Gamma"));
        }
        dx[0] = 1.0;
        Ok(())
    }
    fn guards(&self, m: bool) -> Vec<Guard> {
        if m {
            vec![]
        } else {
            vec![Guard::rising("x=0.1")]
        }
    }
    fn guard_values(&self, m: bool, _: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        if !m {
            out[0] = x[0] - 0.1;
        }
        Ok(())
    }
    fn reset(
        &self,
        _: bool,
        _: usize,
        _: f64,
        _: &mut [f64],
    ) -> Result<Transition<bool>, SimError> {
        Ok(Transition::To(true))
    }
}

#[test]
fn system_error_mid_run_keeps_events_and_samples() {
    let set = SimSettings {
        h_max: 0.05,
        ..SimSettings::default()
    };
    let fail = simulate(&Fails, set, false, 0.0, &[0.0], 1.0).unwrap_err();
    match &fail.error {
        SimError::System { msg } => assert!(msg.contains("singular Gamma")),
        e => panic!("expected System error, got {e}"),
    }
    assert_eq!(fail.partial.events.len(), 1);
    assert!((fail.partial.events[0].t - 0.1).abs() < 1e-12);
    let t_last = *fail.partial.trajectory.t.last().unwrap();
    assert!(t_last <= 0.3 && t_last > 0.2);
    let msg = fail.to_string();
    assert!(
        msg.contains("singular Gamma") && msg.contains("samples"),
        "{msg}"
    );
    let dir = tmpdir("fail");
    let p = dir.join("partial.json");
    fail.write_json(&p).unwrap();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    assert!(v["error"].as_str().unwrap().contains("singular Gamma"));
    assert_eq!(v["events"].as_array().unwrap().len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn json_and_csv_writers_round_trip() {
    let b = BouncingBall {
        g: 9.81,
        e: 0.5,
        drag: 0.0,
        v_rest: Some(1.0),
    };
    let out = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        2.0,
    )
    .unwrap();
    let dir = tmpdir("writers");
    let (pj, pc, pe) = (
        dir.join("run.json"),
        dir.join("traj.csv"),
        dir.join("events.csv"),
    );
    out.write_json(&pj).unwrap();
    out.trajectory.write_csv(&pc).unwrap();
    out.write_events_csv(&pe).unwrap();
    assert!(!dir.join("run.json.tmp").exists());

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&pj).unwrap()).unwrap();
    let t = v["trajectory"]["t"].as_array().unwrap();
    assert_eq!(t.len(), out.trajectory.len());
    let ev = v["events"].as_array().unwrap();
    assert_eq!(ev.len(), out.events.len());
    assert_eq!(ev.last().unwrap()["mode_after"], "Resting");
    assert_eq!(v["mode_final"], "Resting");
    assert_eq!(
        ev[0]["t"].as_f64().unwrap().to_bits(),
        out.events[0].t.to_bits()
    );

    let mut rdr = csv::Reader::from_path(&pc).unwrap();
    assert_eq!(
        rdr.headers().unwrap().iter().collect::<Vec<_>>(),
        vec!["t", "mode", "kind", "drift", "x0", "x1"]
    );
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), out.trajectory.len());
    for (r, (t, x)) in rows
        .iter()
        .zip(out.trajectory.t.iter().zip(&out.trajectory.x))
    {
        assert_eq!(r[0].parse::<f64>().unwrap().to_bits(), t.to_bits());
        assert_eq!(r[5].parse::<f64>().unwrap().to_bits(), x[1].to_bits());
    }
    let mut rdr = csv::Reader::from_path(&pe).unwrap();
    assert_eq!(rdr.records().count(), out.events.len());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn write_to_missing_directory_is_io_error() {
    let out = simulate(
        &Oscillator { omega: 1.0 },
        SimSettings::default(),
        (),
        0.0,
        &[1.0, 0.0],
        0.1,
    )
    .unwrap();
    let e = out
        .write_json(std::path::Path::new("/nonexistent-dir/x/run.json"))
        .unwrap_err();
    assert!(matches!(e, SimError::Io { .. }));
    assert!(e.to_string().contains("run.json"));
}

/// x' = v, v' = g − k v with a huge damping k (the simulator's view of `μ_v` = 10⁹): an
/// explicit step much longer than 1/k carries its stages to |v| ~ 10¹⁵ and beyond, where this
/// system (like a model whose kernels overflow) refuses to evaluate.
struct StiffDrag {
    k: f64,
    refused: std::cell::Cell<usize>,
}

impl HybridSystem for StiffDrag {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _: (), _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        if x.iter().any(|v| v.abs() > 1e13) {
            self.refused.set(self.refused.get() + 1);
            return Err(SimError::system("non-finite mass matrix"));
        }
        dx[0] = x[1];
        dx[1] = 9.81 - self.k * x[1];
        Ok(())
    }
}

/// A trial step whose stages blew up far beyond the state it started from is a rejected step,
/// retried shorter, not the end of the run with the system's complaint about the blown-up
/// state: the run reaches its end at the closed-form terminal velocity g / k. A system error
/// at a state the step did not blow up still ends the run as before.
#[test]
fn a_step_that_blows_up_is_retried_shorter() {
    let sys = StiffDrag {
        k: 1e9,
        refused: std::cell::Cell::new(0),
    };
    // A first step of 10 µs, ten thousand times 1/k: its stages grow by about h k per stage.
    let set = SimSettings {
        h_init: Some(1e-5),
        // v settles at about 1e-8 m/s: an absolute tolerance well below that.
        atol: 1e-18,
        ..SimSettings::default()
    };
    let out = simulate(&sys, set.clone(), (), 0.0, &[0.0, 0.0], 1e-4).unwrap_or_else(|e| {
        panic!("{}", e.error);
    });
    assert!(
        sys.refused.get() > 0,
        "no stage blew up: the test tests nothing"
    );
    assert!(out.stats.rejected_steps > 0);
    let v = out.trajectory.x.last().unwrap()[1];
    let terminal = 9.81 / 1e9;
    assert!(
        ((v - terminal) / terminal).abs() < 1e-6,
        "{v} against {terminal}"
    );
    // Started where the system refuses outright: its own error, unchanged.
    let e = simulate(&sys, set, (), 0.0, &[0.0, 1e14], 1e-6).unwrap_err();
    assert!(
        matches!(&e.error, SimError::System { msg } if msg.contains("mass matrix")),
        "{}",
        e.error
    );
}
