//! The hybrid ball-and-finger system with 2 and 4 joints (tests/fixtures/finger2.toml,
//! finger4.toml: μ_v = D = 0, interpreted kernels): the finger is thrown at the ball under
//! gravity with τ = 0, and the run must obey the physics of Sect. 2.4–3 whatever N is:
//! * no penetration: h ≥ −tol at every sample;
//! * impacts and slipping never add energy; free flight and sticking conserve it (their
//!   forces do no work), so E never rises above E(0) and the energy balance of the run closes;
//! * while sticking the contact point does not slide (‖Δv‖ ≈ 0) and λ stays inside the
//!   friction cone (λ_n ≥ 0, σ ≥ 0, eq. 18–19).

use bf_model::{DynKernels, ImpactLaw, Mode, Model, State, Vec3, VecN, registry};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{PdController, SampleKind, SimSettings, simulate};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FINGER2: &str = include_str!("../../tests/fixtures/finger2.toml");
const FINGER4: &str = include_str!("../../tests/fixtures/finger4.toml");

fn model<const N: usize>(text: &str) -> (Model<DynKernels<N>, N>, f64) {
    let scene = bf_scene::Scene::from_toml_str(text, "fixture").unwrap();
    let (k, _) = registry::contact_kernels_n::<N>(&scene).unwrap();
    (Model::from_kernels(k).unwrap(), scene.links[N - 1].a)
}

/// A configuration touching the ball on the side of the last link, and ∇h = J_cᵀ n there.
fn contact_configuration<const N: usize>(
    m: &Model<DynKernels<N>, N>,
    link: f64,
) -> (VecN<N>, VecN<N>) {
    let mut rng = ChaCha8Rng::seed_from_u64(N as u64);
    let guesses = (0..500).map(|_| VecN::<N>::from_fn(|_, _| rng.random_range(-1.6..1.6)));
    let (x, kin) = m
        .line_contact_configuration(guesses, link, 0.2)
        .expect("no contact configuration");
    (x.q, kin.contact.j_c.transpose() * kin.contact.n)
}

fn throw_at_the_ball<const N: usize>(text: &str, law: ImpactLaw) {
    let (model, link) = model::<N>(text);
    let (qc, grad) = contact_configuration(&model, link);
    let dir = grad / grad.norm();
    let x0 = State::new(qc + dir * 0.05, -dir * 1.0, Vec3::new(0.0, 0.0, 0.3)).to_vec();
    let zero = PdController::new(vec![0.0; N], vec![0.0; N], vec![0.0; N]).unwrap();
    let opts = BallFingerSettings {
        impact_law: law,
        ..BallFingerSettings::default()
    };
    let sys = BallFinger::new(model, zero, opts).unwrap();
    assert!(sys.gap(&x0).unwrap() > 0.01);
    let set = SimSettings {
        rtol: 1e-10,
        atol: 1e-12,
        h_max: 0.01,
        ..SimSettings::default()
    };
    let out = simulate(&sys, set, Mode::Free, 0.0, &x0, 0.4)
        .unwrap_or_else(|f| panic!("N = {N}, {law:?}: {}", f.error));
    assert_eq!(
        out.events[0].guard, "h",
        "N = {N}: the finger hits the ball"
    );
    let report = sys.report(&out, 0.0, 1.0);
    let e0 = report.samples[0].energy;
    let tr = &out.trajectory;
    let mut contact_samples = 0;
    for (i, s) in report.samples.iter().enumerate() {
        assert!(
            s.h > -1e-10,
            "N = {N}, {law:?}: h = {:e} at t = {}",
            s.h,
            tr.t[i]
        );
        assert!(
            s.energy <= e0 + 1e-9,
            "N = {N}, {law:?}: energy rose at t = {}",
            tr.t[i]
        );
        assert_eq!(s.tau, [0.0; N]);
        // Within a mode (a step, not an event), E is constant in Free and Stick (no force
        // does work) and does not increase in Slip (kinetic friction dissipates, eq. 20).
        if tr.kind[i] == SampleKind::Step && i > 0 {
            let de = s.energy - report.samples[i - 1].energy;
            match tr.mode[i] {
                Mode::Free | Mode::Stick => assert!(de.abs() < 1e-9, "N = {N}: ΔE = {de:e}"),
                Mode::Slip => assert!(de < 1e-10, "N = {N}: slip added {de:e} J"),
            }
        }
        // Steps in stick (event samples may sit at a kink of sat(α), where λ jumps and the
        // contact may end at once): the contact point does not slide, λ inside the cone.
        if tr.mode[i] == Mode::Stick && tr.kind[i] == SampleKind::Step {
            assert!(
                s.slip_speed < 1e-8,
                "N = {N}: Δv = {:e} in stick",
                s.slip_speed
            );
            assert!(
                s.lambda_n >= -1e-9 && s.sigma >= -1e-9,
                "N = {N}: λ outside the cone at t = {}: {s:?}",
                tr.t[i]
            );
        }
        if tr.mode[i] != Mode::Free {
            contact_samples += 1;
        }
    }
    assert!(contact_samples > 0, "N = {N}, {law:?}: no contact phase");
    let sm = &report.summary;
    // The run's energy balance (trapezoidal ∫ P dt over the samples) closes.
    assert!(
        sm.energy_error < 1e-5,
        "N = {N}: energy balance {:e}",
        sm.energy_error
    );
    assert!(sm.max_penetration < 1e-10);
    assert!(sm.max_impact_energy_gain <= 1e-12);
}

#[test]
fn a_2_joint_finger_hits_touches_and_conserves() {
    // Every law, Newton's too: a rank-2 contact Jacobian resolves the impact (bf-model's
    // impact module docs) instead of stopping the run.
    for law in ImpactLaw::ALL.into_iter().chain([ImpactLaw::NormalImpulse]) {
        throw_at_the_ball::<2>(FINGER2, law);
    }
}

#[test]
fn a_4_joint_finger_hits_touches_and_conserves() {
    for law in [ImpactLaw::Stick, ImpactLaw::MaxDissipation] {
        throw_at_the_ball::<4>(FINGER4, law);
    }
}

#[test]
fn the_input_must_have_one_torque_per_joint() {
    let (model, _) = model::<4>(FINGER4);
    let three = PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]).unwrap();
    let e = BallFinger::new(model, three, BallFingerSettings::default()).unwrap_err();
    assert!(e.to_string().contains('4'), "{e}");
}
