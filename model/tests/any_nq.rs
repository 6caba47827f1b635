//! The contact model with 2 and 4 joints (tests/fixtures/finger2.toml, finger4.toml; no joint
//! or socket damping), on kernels interpreted at run time, against bf-testkit's independent
//! reference (dual-number kinematics and dynamics) and the invariants of the physics: energy
//! conservation where no force does work, the stick constraint Δv = 0, the friction cone,
//! restitution 0 and momentum balance of the impact laws. The 3-joint generic path is the
//! paper's (bitwise, see the last test and the existing suites).

use bf_model::dynamics::{contact_matrices, normal_acceleration, relative_acceleration};
use bf_model::{
    DynKernels, ImpactLaw, KernelSource, MatN, Mode, Model, PaperKernels, State, Vec3, VecN,
    registry,
};
use bf_testkit::Reference;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FINGER2: &str = include_str!("../../tests/fixtures/finger2.toml");
const FINGER4: &str = include_str!("../../tests/fixtures/finger4.toml");

type M<const N: usize> = Model<DynKernels<N>, N>;

/// The interpreted model of a fixture and the independent reference of the same scene.
fn setup<const N: usize>(text: &str) -> (M<N>, Reference, f64) {
    let scene = bf_scene::Scene::from_toml_str(text, "fixture").unwrap();
    let (k, source) = registry::contact_kernels_n::<N>(&scene).unwrap();
    assert_eq!(source, KernelSource::Interpreted);
    let link = scene.links.last().unwrap().a;
    (
        Model::from_kernels(k).unwrap(),
        Reference::new(&scene).unwrap(),
        link,
    )
}

fn random_vec<const N: usize>(rng: &mut ChaCha8Rng, s: f64) -> VecN<N> {
    VecN::<N>::from_fn(|_, _| rng.random_range(-s..s))
}

/// A configuration touching the ball on the side of the last link (away from the kinks of
/// sat(α)), by Newton steps on h from seeded random guesses.
fn touching<const N: usize>(m: &M<N>, link: f64, rng: &mut ChaCha8Rng) -> State<N> {
    let guesses = (0..500).map(|_| random_vec::<N>(rng, 1.6));
    m.line_contact_configuration(guesses, link, 0.1)
        .expect("no contact configuration found")
        .0
}

/// Reference M(q), C q̇ + g, J_c and r_c.
fn reference<const N: usize>(
    r: &Reference,
    x: &State<N>,
) -> (MatN<N>, VecN<N>, nalgebra::SMatrix<f64, 3, N>, Vec3) {
    let m = r.mass_matrix(x.q.as_slice());
    let c = r.cqd_g(x.q.as_slice(), x.qd.as_slice());
    let k = r
        .contact(x.q.as_slice(), x.qd.as_slice(), &x.omega.into(), None)
        .unwrap();
    (
        MatN::<N>::from_fn(|i, j| m[(i, j)]),
        VecN::<N>::from_fn(|i, _| c[i]),
        nalgebra::SMatrix::<f64, 3, N>::from_fn(|i, j| k.j_c[(i, j)]),
        Vec3::from(k.r_c),
    )
}

/// Kinetic energy from the reference mass matrix.
fn kinetic<const N: usize>(r: &Reference, m: &M<N>, x: &State<N>) -> f64 {
    let (mm, ..) = reference(r, x);
    0.5 * x.qd.dot(&(mm * x.qd)) + 0.5 * x.omega.dot(&(m.params().ball_inertia() * x.omega))
}

/// Classical RK4 step of the mode dynamics with zero torque.
fn rk4<const N: usize>(m: &M<N>, mode: Mode, x: &State<N>, dt: f64) -> State<N> {
    let f = |s: &State<N>| {
        let a = m.accelerations(mode, s, &VecN::zeros()).unwrap();
        (s.qd, a.qdd, a.omega_dot)
    };
    let add = |s: &State<N>, d: &(VecN<N>, VecN<N>, Vec3), h: f64| {
        State::new(s.q + d.0 * h, s.qd + d.1 * h, s.omega + d.2 * h)
    };
    let k1 = f(x);
    let k2 = f(&add(x, &k1, dt / 2.0));
    let k3 = f(&add(x, &k2, dt / 2.0));
    let k4 = f(&add(x, &k3, dt));
    State::new(
        x.q + (k1.0 + k2.0 * 2.0 + k3.0 * 2.0 + k4.0) * (dt / 6.0),
        x.qd + (k1.1 + k2.1 * 2.0 + k3.1 * 2.0 + k4.1) * (dt / 6.0),
        x.omega + (k1.2 + k2.2 * 2.0 + k3.2 * 2.0 + k4.2) * (dt / 6.0),
    )
}

fn kernels_match_reference<const N: usize>(text: &str) {
    let (m, r, _) = setup::<N>(text);
    let mut rng = ChaCha8Rng::seed_from_u64(N as u64);
    for _ in 0..20 {
        let x = State::new(
            random_vec::<N>(&mut rng, 2.0),
            random_vec::<N>(&mut rng, 1.0),
            Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0)),
        );
        let kin = m.evaluate(&x).unwrap();
        let (mm, cg, jc, rc) = reference(&r, &x);
        let k = r
            .contact(x.q.as_slice(), x.qd.as_slice(), &x.omega.into(), None)
            .unwrap();
        let c = &kin.contact;
        assert!((kin.m_f - mm).amax() < 1e-12, "M");
        assert!((kin.cqd_g - cg).amax() < 1e-12, "C qd + g");
        assert!((kin.potential - r.potential(x.q.as_slice())).abs() < 1e-12);
        assert!((c.j_c - jc).amax() < 1e-12, "J_c");
        assert!((c.r_c - rc).amax() < 1e-12, "r_c");
        assert!((c.h - k.h).abs() < 1e-12 && (c.h_dot - k.h_dot).abs() < 1e-12);
        for (a, b) in [
            (c.n, k.n),
            (c.v_c, k.v_c),
            (c.delta_v, k.delta_v),
            (c.rc_dot, k.rc_dot),
            (c.jc_dot_qd, k.jc_dot_qd),
        ] {
            assert!((a - Vec3::from(b)).amax() < 1e-11, "{a} vs {b:?}");
        }
    }
}

#[test]
fn interpreted_kernels_of_2_and_4_joints_match_the_reference() {
    kernels_match_reference::<2>(FINGER2);
    kernels_match_reference::<4>(FINGER4);
}

fn free_flight<const N: usize>(text: &str) {
    let (m, r, _) = setup::<N>(text);
    let mut rng = ChaCha8Rng::seed_from_u64(10 + N as u64);
    let mut x = State::new(
        random_vec::<N>(&mut rng, 1.0),
        random_vec::<N>(&mut rng, 2.0),
        Vec3::new(0.3, -1.0, 2.0),
    );
    let e0 = m.energy(&x).unwrap().total;
    // The model's kinetic energy is the reference's.
    let ke = m.energy(&x).unwrap();
    assert!((ke.kinetic_finger + ke.kinetic_ball - kinetic(&r, &m, &x)).abs() < 1e-12);
    for _ in 0..2000 {
        x = rk4(&m, Mode::Free, &x, 2.5e-4);
    }
    let e1 = m.energy(&x).unwrap().total;
    assert!((e1 - e0).abs() < 1e-9 * (1.0 + e0.abs()), "{e0} -> {e1}");
    // With damping and torques, dE/dt along the flow is the power balance.
    let m = {
        let p = m.params().with_viscous(0.01, 0.02).unwrap();
        m.with_params(p)
    };
    let tau = random_vec::<N>(&mut rng, 0.5);
    let acc = m.free(&x, &tau).unwrap();
    let h = 1e-6;
    let at = |s: f64| {
        let y = State::new(
            x.q + x.qd * s,
            x.qd + acc.qdd * s,
            x.omega + acc.omega_dot * s,
        );
        m.energy(&y).unwrap().total
    };
    let de = (at(h) - at(-h)) / (2.0 * h);
    let p = m.power_balance(&x, &tau, &acc.force).unwrap().total;
    assert!((de - p).abs() < 1e-6 * (1.0 + p.abs()), "{de} vs {p}");
}

#[test]
fn free_flight_conserves_energy_and_follows_the_power_balance() {
    free_flight::<2>(FINGER2);
    free_flight::<4>(FINGER4);
}

fn stick<const N: usize>(text: &str) {
    let (m, r, link) = setup::<N>(text);
    let mut rng = ChaCha8Rng::seed_from_u64(20 + N as u64);
    let mut x = touching(&m, link, &mut rng);
    x.qd = random_vec::<N>(&mut rng, 0.3);
    x.omega = Vec3::from_fn(|_, _| rng.random_range(-0.3..0.3));
    let p = m.project_velocity(Mode::Stick, &x).unwrap();
    x.qd = p.qd;
    x.omega = p.omega;
    let kin = m.evaluate(&x).unwrap();
    assert!(kin.contact.delta_v.norm() < 1e-12);
    // Push the contact point into the ball: τ = J_cᵀ (−n) f.
    let n = kin.contact.n;
    let tau = kin.contact.j_c.transpose() * (-n * 2.0);
    let acc = m.stick(&x, &tau).unwrap();
    // The stick constraint holds at acceleration level.
    assert!(relative_acceleration(&kin, &acc.qdd, &acc.omega_dot).norm() < 1e-9);
    assert!(normal_acceleration(&kin, &acc.qdd).abs() < 1e-9);
    // λ satisfies the equations of motion of eq. 29 with the reference M, C q̇ + g, J_c, r_c.
    let (mm, cg, jc, rc) = reference(&r, &x);
    let lambda = acc.force.lambda;
    let finger = mm * acc.qdd + cg - tau - jc.transpose() * lambda;
    let ib = m.params().ball_inertia();
    let ball = ib * acc.omega_dot + x.omega.cross(&(ib * x.omega)) + rc.cross(&lambda);
    assert!(
        finger.amax() < 1e-9 && ball.amax() < 1e-9,
        "{finger} {ball}"
    );
    // Pushing in: λ_n > 0 and λ inside the static friction cone (eq. 18–19).
    let ln = lambda.dot(&n);
    let lt = (lambda - n * ln).norm();
    assert!(ln > 0.5, "λ_n = {ln}");
    assert!(lt < m.params().mu_s() * ln, "|λ_t| = {lt}, λ_n = {ln}");
    assert!((acc.force.sigma - (m.params().mu_s() * ln - lt)).abs() < 1e-12);
    // Unactuated sticking (bilateral, no damping): Δv stays 0 and the energy constant, since
    // the sticking force does no work.
    let e0 = m.energy(&x).unwrap().total;
    for _ in 0..500 {
        x = rk4(&m, Mode::Stick, &x, 1e-4);
        let kin = m.evaluate(&x).unwrap();
        assert!(kin.contact.delta_v.norm() < 1e-9, "Δv drift");
        assert!(kin.contact.h.abs() < 1e-9, "h drift");
    }
    let e1 = m.energy(&x).unwrap().total;
    assert!((e1 - e0).abs() < 1e-10 * (1.0 + e0.abs()), "{e0} -> {e1}");
}

#[test]
fn sticking_keeps_the_contact_point_at_rest_inside_the_cone() {
    stick::<2>(FINGER2);
    stick::<4>(FINGER4);
}

fn slip<const N: usize>(text: &str) {
    let (m, _, link) = setup::<N>(text);
    let mut rng = ChaCha8Rng::seed_from_u64(30 + N as u64);
    let mut x = touching(&m, link, &mut rng);
    x.qd = random_vec::<N>(&mut rng, 0.5);
    x.omega = Vec3::new(0.0, 0.0, 1.5);
    let p = m.project_velocity(Mode::Slip, &x).unwrap();
    x.qd = p.qd;
    let kin = m.evaluate(&x).unwrap();
    assert!(kin.contact.normal_velocity().abs() < 1e-12);
    assert!(kin.contact.delta_v.norm() > 0.1);
    // Kinetic friction opposes the slip: its power λ·Δv = μ_k λ_n ‖Δv‖ (eq. 20).
    let tau = kin.contact.j_c.transpose() * (-kin.contact.n);
    let acc = m.slip(&x, &tau, None).unwrap();
    let pw = m.power_balance(&x, &tau, &acc.force).unwrap();
    let expect = m.params().mu_k() * acc.force.lambda_n * kin.contact.delta_v.norm();
    assert!(
        (pw.slip - expect).abs() < 1e-12 * (1.0 + expect),
        "{} vs {expect}",
        pw.slip
    );
    assert!(normal_acceleration(&kin, &acc.qdd).abs() < 1e-9);
    // Frictionless sliding conserves the energy and keeps n·v_c = 0.
    let m = {
        let p = m.params().with_coulomb(0.0, 0.0).unwrap();
        m.with_params(p)
    };
    let e0 = m.energy(&x).unwrap().total;
    for _ in 0..200 {
        x = rk4(&m, Mode::Slip, &x, 1e-4);
        let kin = m.evaluate(&x).unwrap();
        assert!(kin.contact.normal_velocity().abs() < 1e-9);
    }
    let e1 = m.energy(&x).unwrap().total;
    assert!((e1 - e0).abs() < 1e-10 * (1.0 + e0.abs()), "{e0} -> {e1}");
}

#[test]
fn slipping_dissipates_by_kinetic_friction_and_conserves_energy_without_it() {
    slip::<2>(FINGER2);
    slip::<4>(FINGER4);
}

fn impacts<const N: usize>(text: &str) {
    let (m, r, link) = setup::<N>(text);
    let mut rng = ChaCha8Rng::seed_from_u64(40 + N as u64);
    for _ in 0..5 {
        let mut x = touching(&m, link, &mut rng);
        x.qd = random_vec::<N>(&mut rng, 0.5);
        x.omega = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        // Approach at n·v_c = −0.5 m/s.
        let kin = m.evaluate(&x).unwrap();
        let mats = contact_matrices(&kin, m.params()).unwrap();
        let vn = kin.contact.normal_velocity();
        x.qd += mats.minv_jct * kin.contact.n * ((-0.5 - vn) / mats.n_w_n);
        let kin = m.evaluate(&x).unwrap();
        let n = kin.contact.n;
        assert!((kin.contact.normal_velocity() + 0.5).abs() < 1e-12);
        let (mm, _, jc, rc) = reference(&r, &x);
        let ib = m.params().ball_inertia();
        let t0 = kinetic(&r, &m, &x);
        for law in [
            ImpactLaw::Stick,
            ImpactLaw::MaxDissipation,
            ImpactLaw::MinRelativeVelocity,
            ImpactLaw::NormalImpulse,
        ] {
            let out = m.impact(&x, law).unwrap();
            let y = State::new(x.q, out.qd, out.omega);
            // Restitution 0: no normal approach after the impact (no penetration).
            let vn_plus = n.dot(&(jc * out.qd));
            assert!(vn_plus.abs() < 1e-10, "{law:?}: n·v_c⁺ = {vn_plus}");
            // Momentum balance of eq. 40 with the reference M, J_c, r_c.
            let fin = mm * (out.qd - x.qd) - jc.transpose() * out.impulse;
            let ball = ib * (out.omega - x.omega) + rc.cross(&out.impulse);
            assert!(fin.amax() < 1e-10 && ball.amax() < 1e-10, "{law:?}");
            // Dissipative.
            let t1 = kinetic(&r, &m, &y);
            assert!(t1 <= t0 + 1e-12, "{law:?}: {t0} -> {t1}");
            assert!((out.kinetic_energy_change - (t1 - t0)).abs() < 1e-10);
            let dv = out.omega.cross(&rc) - jc * out.qd;
            match law {
                ImpactLaw::Stick => assert!(dv.norm() < 1e-10, "Δv⁺ = {dv}"),
                ImpactLaw::MaxDissipation => {
                    let i_n = out.impulse.dot(&n);
                    let i_t = (out.impulse - n * i_n).norm();
                    assert!(i_t <= m.params().mu_k() * i_n * (1.0 + 1e-9) + 1e-14);
                }
                _ => {}
            }
        }
        let newton = m.impact(&x, ImpactLaw::Newton);
        if N > 3 {
            // Eq. 39: the tangential velocity of the contact point is kept, ω unchanged.
            let out = newton.unwrap();
            let v0 = jc * x.qd;
            let target = v0 - n * n.dot(&v0);
            assert!((jc * out.qd - target).amax() < 1e-10);
            assert_eq!(out.omega, x.omega);
            assert!((mm * (out.qd - x.qd) - jc.transpose() * out.impulse).amax() < 1e-10);
        } else {
            // J_c of rank < 3: n·v_c⁺ = 0 by the impulse along n that changes the kinetic
            // energy least (Gauss's least constraint), ω unchanged; it loses exactly
            // ½ (n·v_c⁻)² / nᵀ W n, W = J_c M⁻¹ J_cᵀ of the reference model.
            let out = newton.unwrap();
            assert!(n.dot(&(jc * out.qd)).abs() < 1e-10);
            assert_eq!(out.omega, x.omega);
            let i_n = out.impulse.dot(&n);
            assert!((out.impulse - n * i_n).norm() <= 1e-12 * i_n.abs());
            assert!((mm * (out.qd - x.qd) - jc.transpose() * out.impulse).amax() < 1e-10);
            let w = jc * mm.try_inverse().unwrap() * jc.transpose();
            let loss = 0.5 * 0.5 * 0.5 / n.dot(&(w * n));
            let y = State::new(x.q, out.qd, out.omega);
            let change = kinetic(&r, &m, &y) - t0;
            assert!(
                (change + loss).abs() < 1e-10 * (1.0 + loss),
                "{change} vs −{loss}"
            );
        }
    }
}

#[test]
fn impact_laws_stop_the_approach_and_balance_momentum() {
    impacts::<2>(FINGER2);
    impacts::<4>(FINGER4);
}

#[test]
fn joint_count_mismatch_and_non_contact_scenes_are_named() {
    let scene = bf_scene::Scene::from_toml_str(FINGER4, "fixture").unwrap();
    let e = registry::contact_kernels_n::<3>(&scene)
        .unwrap_err()
        .to_string();
    assert!(e.contains("finger4") && e.contains("4 joints"), "{e}");
    assert!(registry::contact_kernels(&scene).is_err());
}

#[test]
fn the_generic_3_joint_path_is_the_compiled_paper_model() {
    // The registry's N = 3 kernels of the paper scene run the same arithmetic as the
    // compiled `PaperKernels`: every result is bitwise equal.
    let scene = bf_scene::Scene::from_toml_str(
        include_str!("../../scenes/paper.toml"),
        "scenes/paper.toml",
    )
    .unwrap();
    let (k, source) = registry::contact_kernels_n::<3>(&scene).unwrap();
    assert_eq!(source, KernelSource::Compiled);
    let a = Model::from_kernels(k).unwrap();
    let b = Model::from_kernels(PaperKernels::new()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x = touching(&a, 1.0, &mut rng);
    let mut x = x;
    x.qd = random_vec::<3>(&mut rng, 0.5);
    x.omega = Vec3::new(0.1, 0.2, 0.3);
    let tau = Vec3::new(0.1, -0.2, 0.05);
    assert_eq!(a.evaluate(&x).unwrap(), b.evaluate(&x).unwrap());
    for mode in [Mode::Free, Mode::Stick] {
        assert_eq!(
            a.accelerations(mode, &x, &tau).unwrap(),
            b.accelerations(mode, &x, &tau).unwrap()
        );
    }
    assert_eq!(
        a.project_velocity(Mode::Stick, &x).unwrap(),
        b.project_velocity(Mode::Stick, &x).unwrap()
    );
}
