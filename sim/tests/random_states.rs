//! Robustness of the ball-and-finger simulator on random initial states (paper scene with its
//! default parameters, generated kernels, zero torque, the CLI's default integrator settings).
//!
//! Physics that must hold for every valid initial state and every impact law (Sect. 2.4–3):
//! * the run reaches t_end: no abort, whatever the contact does (kinks of sat(α) in eq. 3 are
//!   events, trial steps leaving the contact band are retried shorter, Zeno cascades end in the
//!   documented fallback);
//! * with τ = 0 and viscous friction the energy E = T + U (eq. 22) never rises: dE/dt = −μ_v‖q̇‖²
//!   − D‖ω‖² − λ·Δv ≤ 0 in every mode and the impact laws of eq. 40–43 dissipate; the one
//!   exception is Newton's law (eq. 39), whose energy-raising impacts must be reported as
//!   warnings;
//! * no penetration: h ≥ −1e-6 m at every output sample.
//!
//! 200 seeded states × 5 laws × 3 s take a few seconds in release.

use bf_model::{ImpactLaw, Mode, Model, PaperKernels, State, Vec3};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{PdController, SampleKind, SimSettings, simulate};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Largest energy rise between consecutive samples that is not an impact (J).
const ENERGY_RISE_TOL: f64 = 1e-8;
/// Largest penetration accepted at a sample (m).
const PENETRATION_TOL: f64 = 1e-6;

/// The integrator settings of `ball-finger simulate` by default (rtol 1e-8, atol 1e-2 rtol,
/// h_max 0.05 s).
fn cli_settings() -> SimSettings {
    SimSettings {
        rtol: 1e-8,
        atol: 1e-10,
        h_max: 0.05,
        max_steps: 10_000_000,
        ..SimSettings::default()
    }
}

fn zero_torque() -> PdController {
    PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]).expect("zero gains are valid")
}

fn system(law: ImpactLaw) -> BallFinger<PaperKernels, PdController> {
    let model = Model::from_kernels(PaperKernels::new()).expect("paper model");
    let opts = BallFingerSettings {
        impact_law: law,
        ..BallFingerSettings::default()
    };
    BallFinger::new(model, zero_torque(), opts).expect("system")
}

/// Random free initial state near the ball (1 mm < h < 0.5 r, so most runs make contact):
/// q ∈ [−π, π]³, q̇ ∈ [−2.5, 2.5]³ rad/s, ω ∈ [−1.5, 1.5]³ rad/s.
fn random_state(sys: &BallFinger<PaperKernels, PdController>, rng: &mut ChaCha8Rng) -> [f64; 9] {
    let pi = std::f64::consts::PI;
    let mut v = |a: f64| {
        Vec3::new(
            rng.random_range(-a..a),
            rng.random_range(-a..a),
            rng.random_range(-a..a),
        )
    };
    loop {
        let x = State::new(v(pi), v(2.5), v(1.5)).to_array();
        let h = sys.gap(&x).expect("finite state");
        if h > 1e-3 && h < 0.5 {
            return x;
        }
    }
}

/// Counts of one batch of runs.
#[derive(Debug, Default)]
struct Tally {
    runs: usize,
    events: usize,
    kinks: usize,
    impacts: usize,
    energy_raising_impacts: usize,
    zeno_fallbacks: usize,
    energy_error_warnings: usize,
    domain_rejections: usize,
    max_impact_gain: f64,
    /// The Zeno fallbacks used (law, time, message).
    fallbacks: Vec<String>,
}

/// Runs one state with one law for `t_end` seconds and checks the invariants.
fn run_and_check(law: ImpactLaw, x0: &[f64; 9], t_end: f64, tally: &mut Tally) {
    let sys = system(law);
    let out = match simulate(&sys, cli_settings(), Mode::Free, 0.0, x0, t_end) {
        Ok(out) => out,
        Err(f) => panic!("{law:?} from {x0:?}: the run aborted: {f}"),
    };
    assert_eq!(out.t_final, t_end, "{law:?} from {x0:?}: stopped early");
    let report = sys.report(&out, 0.0, 1.0);
    let tr = &out.trajectory;
    for (i, s) in report.samples.iter().enumerate() {
        assert!(
            s.h >= -PENETRATION_TOL,
            "{law:?} from {x0:?}: penetration h = {:e} m at t = {}",
            s.h,
            tr.t[i]
        );
    }
    for i in 1..tr.len() {
        let rise = report.samples[i].energy - report.samples[i - 1].energy;
        if rise <= ENERGY_RISE_TOL {
            continue;
        }
        // Only an impact reported as energy-raising may add energy.
        let reported_impact = tr.kind[i] == SampleKind::EventPost
            && report.events.iter().any(|e| {
                e.t == tr.t[i] && e.kind == "impact" && e.post.energy - e.pre.energy > 0.0
            })
            && report
                .summary
                .warnings
                .iter()
                .any(|w| w.kind == "energy_raising_impact" && w.t == tr.t[i]);
        assert!(
            reported_impact && law == ImpactLaw::Newton,
            "{law:?} from {x0:?}: energy rose by {rise:e} J at t = {} ({:?} sample)",
            tr.t[i],
            tr.kind[i]
        );
    }
    let sum = &report.summary;
    tally.runs += 1;
    tally.events += out.events.len();
    tally.kinks += report.events.iter().filter(|e| e.kind == "kink").count();
    tally.impacts += report.events.iter().filter(|e| e.kind == "impact").count();
    let count = |kind: &str| sum.warnings.iter().filter(|w| w.kind == kind).count();
    tally.energy_raising_impacts += count("energy_raising_impact");
    tally.zeno_fallbacks += count("zeno_fallback");
    for w in sum.warnings.iter().filter(|w| w.kind == "zeno_fallback") {
        tally
            .fallbacks
            .push(format!("{law:?} t = {}: {}", w.t, w.message));
    }
    tally.energy_error_warnings += count("energy_error");
    tally.domain_rejections += out.stats.domain_rejections;
    tally.max_impact_gain = tally.max_impact_gain.max(sum.max_impact_energy_gain);
}

/// `states` seeded random states × every impact law (the paper's four and the frictionless
/// normal impulse), `t_end` seconds each.
fn batch(states: usize, t_end: f64) -> Tally {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let laws = [
        ImpactLaw::Newton,
        ImpactLaw::Stick,
        ImpactLaw::MaxDissipation,
        ImpactLaw::MinRelativeVelocity,
        ImpactLaw::NormalImpulse,
    ];
    let probe = system(ImpactLaw::Stick);
    let x0s: Vec<[f64; 9]> = (0..states)
        .map(|_| random_state(&probe, &mut rng))
        .collect();
    let mut tally = Tally::default();
    for law in laws {
        for x0 in &x0s {
            run_and_check(law, x0, t_end, &mut tally);
        }
    }
    eprintln!(
        "{states} states x {} laws, {t_end} s each: {tally:?}",
        laws.len()
    );
    tally
}

#[test]
fn random_states_never_abort_and_keep_energy_and_contact() {
    let tally = batch(200, 3.0);
    // The batch must exercise what it claims to: contacts, kink crossings, and Newton impacts
    // that add energy (reported, checked in `run_and_check`).
    assert!(
        tally.runs == 1000 && tally.impacts > 500 && tally.kinks > 0,
        "{tally:?}"
    );
    assert!(tally.energy_raising_impacts > 0, "{tally:?}");
}

/// The energy-balance warning separates an accurate run from one whose fixed step is too long:
/// with τ = 0 the energy may only fall by the work of friction, so E(t) − E(t₀) − ∫P dt measures
/// the integration error.
#[test]
fn energy_balance_error_is_small_for_dopri5_and_warned_for_a_long_rk4_step() {
    let sys = system(ImpactLaw::Stick);
    let x0 = State::new(Vec3::new(0.1, 0.5, 0.5), Vec3::zeros(), Vec3::zeros()).to_array();
    let run = |set: SimSettings| {
        let out = simulate(&sys, set, Mode::Free, 0.0, &x0, 10.0).expect("runs");
        sys.report(&out, 0.0, 1.0).summary
    };
    let fine = run(cli_settings());
    assert!(fine.energy_error < 1e-3, "{}", fine.energy_error);
    assert!(!fine.warnings.iter().any(|w| w.kind == "energy_error"));
    let coarse = run(SimSettings {
        method: bf_sim::Method::Rk4 { h: 0.05 },
        ..cli_settings()
    });
    assert!(coarse.energy_error > 1e-2, "{}", coarse.energy_error);
    assert!(
        coarse.warnings.iter().any(|w| w.kind == "energy_error"),
        "{:?}",
        coarse.warnings
    );
}

/// The state of the reliability report: with the sticking law the contact point reaches the
/// fingertip (α crossing 0, the kink of eq. 3) while in contact; the run used to abort with
/// "not in contact" at |h| = 1.6e-3 m.
#[test]
fn fingertip_kink_regression() {
    let x0 = State::new(
        Vec3::new(0.496441, 1.391013, 0.044663),
        Vec3::new(-1.701004, 2.200894, 1.981726),
        Vec3::new(1.043772, 0.550432, -1.070549),
    )
    .to_array();
    let mut tally = Tally::default();
    run_and_check(ImpactLaw::Stick, &x0, 3.0, &mut tally);
    assert!(tally.kinks > 0, "the run must cross a kink: {tally:?}");
}
