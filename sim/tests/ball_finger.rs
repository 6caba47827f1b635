//! Ball and finger through the hybrid machinery: the finger (paper scene, docs/parameters.md) is thrown
//! at the ball with τ = 0 and no viscous friction (μ_v = D = 0), under gravity.
//!
//! Physics that must hold (paper Sect. 2.4–3):
//! * free motion and sticking conserve E = T + U (the sticking force does no work, λ·Δv = 0);
//!   a wrong λ (eq. 33) or a wrong C shows up as energy drift inside those segments;
//! * impacts (eq. 39–43) and slipping (eq. 20) never add energy;
//! * no penetration: h ≥ −tol at every sample (the impact guard fires, the contact modes keep
//!   h ≈ 0 through projection);
//! * every event is consistent with the Fig. 2 transition structure.
//!
//! Kernels come from bf-testkit's independent reference (the generated product kernels are
//! exercised by bf-model's own tests), so this test does not depend on codegen output.

use bf_model::{ImpactLaw, Mode, Model, State, Vec3};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{PdController, SampleKind, SimSettings, TorqueSeries, simulate};

const PAPER_TOML: &str = include_str!("../../scenes/paper.toml");

// The adapter that runs bf-model on bf-testkit's reference kernels, shared with bf-model's
// own tests (one copy, so both crates test against the same oracle wiring).
#[path = "../../model/tests/common/mod.rs"]
mod common;
use common::RefKernels;

fn conservative_model() -> Model<RefKernels> {
    let m = Model::from_kernels(RefKernels::new(PAPER_TOML)).unwrap();
    let p = m.params().with_viscous(0.0, 0.0).unwrap();
    m.with_params(p)
}

fn zero_torque() -> PdController {
    PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]).unwrap()
}

/// Finger 0.05 rad (along ∇h) away from contact (h(q) = 0 near (0.1, 0.5, 0.5)), moving
/// towards the ball.
fn approach(model: &Model<RefKernels>, speed: f64) -> [f64; 9] {
    let (qc, grad) = model
        .contact_configuration_near(Vec3::new(0.1, 0.5, 0.5), 1e-14, 100)
        .unwrap();
    let dir = grad / grad.norm();
    State::new(qc + dir * 0.05, -dir * speed, Vec3::new(0.0, 0.0, 0.3)).to_array()
}

fn settings() -> SimSettings {
    SimSettings {
        rtol: 1e-10,
        atol: 1e-12,
        h_max: 0.01,
        ..SimSettings::default()
    }
}

fn run_and_check(law: ImpactLaw) -> usize {
    let model = conservative_model();
    let x0 = approach(&model, 1.0);
    let sys = BallFinger::new(
        model,
        zero_torque(),
        BallFingerSettings {
            impact_law: law,
            ..BallFingerSettings::default()
        },
    )
    .unwrap();
    assert!(sys.gap(&x0).unwrap() > 0.01);
    let out = match simulate(&sys, settings(), Mode::Free, 0.0, &x0, 0.4) {
        Ok(o) => o,
        Err(f) => panic!(
            "{law:?}: {} (events: {:?})",
            f.error,
            f.partial
                .events
                .iter()
                .map(|e| (e.t, e.guard, e.mode_before, e.mode_after))
                .collect::<Vec<_>>()
        ),
    };
    assert!(
        !out.events.is_empty(),
        "{law:?}: the finger must hit the ball"
    );
    assert_eq!(out.events[0].guard, "h");
    assert_eq!(out.events[0].mode_before, Mode::Free);

    let tr = &out.trajectory;
    let e0 = sys.energy(&x0).unwrap();
    let kin0 = 0.5; // energy scale (J) for tolerances: T0 is O(0.01..1)
    let mut seg_start_energy = e0;
    let mut seg_mode = Mode::Free;
    for i in 0..tr.len() {
        let x = &tr.x[i];
        let h = sys.gap(x).unwrap();
        assert!(
            h > -1e-10,
            "{law:?}: penetration h = {h:e} at t = {}",
            tr.t[i]
        );
        let e = sys.energy(x).unwrap();
        assert!(
            e <= e0 + 1e-9 * kin0,
            "{law:?}: energy grew to {e} from {e0} at t = {}",
            tr.t[i]
        );
        match tr.kind[i] {
            SampleKind::EventPost | SampleKind::Initial => {
                seg_start_energy = e;
                seg_mode = tr.mode[i];
            }
            _ => {
                if seg_mode != Mode::Slip {
                    assert!(
                        (e - seg_start_energy).abs() < 1e-9 * kin0,
                        "{law:?}: energy drift {:e} in {seg_mode:?} at t = {}",
                        e - seg_start_energy,
                        tr.t[i]
                    );
                }
            }
        }
    }
    for ev in &out.events {
        let (ea, eb) = (
            sys.energy(&ev.x_pre).unwrap(),
            sys.energy(&ev.x_post).unwrap(),
        );
        assert!(
            eb <= ea + 1e-9 * kin0,
            "{law:?}: {} added energy {:e}",
            ev.guard,
            eb - ea
        );
        let after = ev.mode_after.unwrap();
        match ev.mode_before {
            Mode::Free => assert!(matches!(after, Mode::Stick | Mode::Slip)),
            _ => assert!(after != ev.mode_before),
        }
    }
    out.events.len()
}

#[test]
fn sticking_impact_conserves_energy_and_does_not_penetrate() {
    run_and_check(ImpactLaw::Stick);
}

#[test]
fn other_impact_laws_keep_invariants() {
    for law in [
        ImpactLaw::Newton,
        ImpactLaw::MinRelativeVelocity,
        ImpactLaw::MaxDissipation,
    ] {
        run_and_check(law);
    }
}

/// Max |h| over contact-mode samples of the sticking run, with or without projection.
fn contact_drift(project: bool) -> f64 {
    let model = conservative_model();
    let x0 = approach(&model, 1.0);
    let opts = BallFingerSettings {
        project,
        ..BallFingerSettings::default()
    };
    let sys = BallFinger::new(model, zero_torque(), opts).unwrap();
    let set = SimSettings {
        rtol: 1e-4,
        atol: 1e-6,
        ..settings()
    };
    let out = simulate(&sys, set, Mode::Free, 0.0, &x0, 0.15).unwrap();
    let tr = &out.trajectory;
    (0..tr.len())
        .filter(|&i| tr.mode[i] != Mode::Free && tr.kind[i] == SampleKind::Step)
        .map(|i| sys.gap(&tr.x[i]).unwrap().abs())
        .fold(0.0, f64::max)
}

#[test]
fn projection_controls_contact_drift() {
    let (with, without) = (contact_drift(true), contact_drift(false));
    assert!(with < 1e-12, "projected drift {with:e}");
    assert!(
        without > 10.0 * with,
        "projection had no effect: {with:e} vs {without:e}"
    );
}

/// The same run driven by a zero torque series read from a CSV file must be bit-identical to
/// the zero PD controller: the Input plumbing adds nothing.
#[test]
fn torque_series_from_csv_drives_the_same_run() {
    let dir = std::env::temp_dir().join(format!("bf-sim-bf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("tau.csv");
    std::fs::write(&path, "t,tau1,tau2,tau3\n0,0,0,0\n0.1,0,0,0\n1,0,0,0\n").unwrap();
    let series = TorqueSeries::from_path(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let model = conservative_model();
    let x0 = approach(&model, 1.0);
    let a = BallFinger::new(model.clone(), series, BallFingerSettings::default()).unwrap();
    let b = BallFinger::new(model, zero_torque(), BallFingerSettings::default()).unwrap();
    let ra = simulate(&a, settings(), Mode::Free, 0.0, &x0, 0.1).unwrap();
    let rb = simulate(&b, settings(), Mode::Free, 0.0, &x0, 0.1).unwrap();
    assert_eq!(ra.trajectory.x, rb.trajectory.x);
    assert_eq!(ra.events.len(), rb.events.len());
    assert!(
        BallFinger::new(
            conservative_model(),
            TorqueSeries::new(vec![0.0], vec![vec![0.0; 2]]).unwrap(),
            BallFingerSettings::default()
        )
        .is_err()
    );
}
