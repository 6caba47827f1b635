//! Energy balance (dE/dt = q̇ᵀτ − μ_v|q̇|² − D|ω|² − λ·Δv) in every mode, checked by finite
//! differences of E = ½q̇ᵀM_f q̇ + U + ½ωᵀI_bω along the computed accelerations (this also
//! checks that C is the Christoffel form and g = ∂U/∂q), and the transition predicates and
//! velocity updates of Sect. 3.1 (eq. 48–50).

mod common;

use bf_model::dynamics::{normal_acceleration, relative_acceleration};
use bf_model::transitions::{self, Transition};
use bf_model::{Mode, ModelError, Params, State, TransitionSettings, Vec3};
use common::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn check_energy<K: bf_model::Kernels>(
    model: &bf_model::Model<K>,
    x: &State,
    mode: Mode,
    tau: &Vec3,
) {
    let acc = model.accelerations(mode, x, tau).unwrap();
    let pb = model.power_balance(x, tau, &acc.force).unwrap();
    let fd: f64 = fd_along(model, x, &acc, |k| {
        bf_model::energy::energy(k, model.params()).total
    });
    let scale = pb.input.abs() + pb.joint_viscous + pb.socket + pb.slip.abs() + 1e-3;
    assert!(
        (fd - pb.total).abs() < 1e-7 * scale,
        "{mode:?}: FD {fd} vs balance {} ({pb:?})",
        pb.total
    );
}

#[test]
fn power_balance_matches_energy_rate_in_every_mode() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let model = paper_ref_model_aniso();
    for _ in 0..15 {
        let tau = rvec(&mut rng, 1.0);
        let x = State::new(
            rvec(&mut rng, 3.0),
            rvec(&mut rng, 2.0),
            rvec(&mut rng, 2.0),
        );
        check_energy(&model, &x, Mode::Free, &tau);
        let x = stick_state(&model, &mut rng);
        check_energy(&model, &x, Mode::Stick, &tau);
        let x = slip_state(&model, &mut rng);
        check_energy(&model, &x, Mode::Slip, &tau);
    }
}

#[test]
fn energy_is_conserved_without_friction_and_torque() {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let m = paper_ref_model_aniso();
    let model = m
        .clone()
        .with_params(m.params().with_viscous(0.0, 0.0).unwrap());
    for _ in 0..10 {
        let x = stick_state(&model, &mut rng);
        let acc = model.stick(&x, &Vec3::zeros()).unwrap();
        let fd: f64 = fd_along(&model, &x, &acc, |k| {
            bf_model::energy::energy(k, model.params()).total
        });
        let e = model.energy(&x).unwrap();
        assert!(
            fd.abs() < 1e-7 * (e.kinetic_finger + e.kinetic_ball + 1.0),
            "dE/dt = {fd}"
        );
    }
}

#[test]
fn free_to_contact_follows_eq_50() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let model = paper_ref_model();
    let s = *model.settings();
    let p = *model.params();
    let mut n_grazing = [0, 0];
    for _ in 0..20 {
        let q = contact_configuration(&model, &mut rng);
        let kin0 = model
            .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
            .unwrap();
        let jinv = kin0.contact.j_c.try_inverse().unwrap();
        let n = kin0.contact.n;
        let tau = rvec(&mut rng, 1.0);
        // approaching / separating
        for (sign, expect) in [(-1.0, true), (1.0, false)] {
            let x = State::new(q, jinv * (n * (0.3 * sign)), Vec3::zeros());
            let kin = model.evaluate(&x).unwrap();
            let free = model.free(&x, &tau).unwrap();
            assert_eq!(transitions::free_to_contact(&kin, &p, &free, &s), expect);
        }
        // grazing (ḣ = 0): the sign of ḧ decides; ḧ = FD of ḣ along the free motion
        let v = rvec(&mut rng, 1.0);
        let x = State::new(q, jinv * (v - n * n.dot(&v)), Vec3::zeros());
        let kin = model.evaluate(&x).unwrap();
        assert!(kin.contact.h_dot.abs() < 1e-12);
        let free = model.free(&x, &tau).unwrap();
        let hdd = normal_acceleration(&kin, &free.qdd);
        let fd: f64 = fd_along(&model, &x, &free, |k| k.contact.h_dot);
        assert!(
            (fd - hdd).abs() < 1e-6 * (1.0 + hdd.abs()),
            "ḧ {hdd} vs FD {fd}"
        );
        let fires = transitions::free_to_contact(&kin, &p, &free, &s);
        assert_eq!(fires, hdd < 0.0);
        n_grazing[fires as usize] += 1;
    }
    assert!(n_grazing[0] > 0 && n_grazing[1] > 0, "{n_grazing:?}");
    // h > 0 far from the ball: no transition; the ḣ check is not reached
    let x = State::new(
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::zeros(),
    );
    let kin = model.evaluate(&x).unwrap();
    assert!(kin.contact.h > 0.1);
    let free = model.free(&x, &Vec3::zeros()).unwrap();
    assert!(!transitions::free_to_contact(&kin, &p, &free, &s));
}

#[test]
fn slip_to_stick_update_is_the_minimal_projection() {
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let model = paper_ref_model_aniso();
    for _ in 0..15 {
        let x = slip_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let o = model.slip_to_stick_update(&x).unwrap();
        assert!(o.delta_v.norm() < 1e-10 * (1.0 + kin.contact.delta_v.norm()));
        assert_eq!(o.mode, Mode::Stick);
        // minimal in the kinetic-energy metric: adding any velocity in ker G increases ‖Δu‖_M
        let g = g_matrix(&kin);
        // basis of ker G: [−J_c⁻¹ S(r_c) e_i; e_i]
        let jinv = kin.contact.j_c.try_inverse().unwrap();
        let s_rc = bf_model::skew(&kin.contact.r_c);
        let du0 = nalgebra::SVector::<f64, 6>::from_iterator(
            (o.qd - x.qd)
                .iter()
                .chain((o.omega - x.omega).iter())
                .copied(),
        );
        let mut mm = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        mm.fixed_view_mut::<3, 3>(0, 0).copy_from(&kin.m_f);
        mm.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(model.params().ball_inertia());
        let e0 = du0.dot(&(mm * du0));
        for i in 0..3 {
            let e = Vec3::ith(i, 1.0);
            let top = -(jinv * s_rc * e);
            let null =
                nalgebra::SVector::<f64, 6>::from_iterator(top.iter().chain(e.iter()).copied());
            assert!((g * null).norm() < 1e-10);
            let du = du0 + null * rng.random_range(-0.1..0.1);
            assert!(du.dot(&(mm * du)) >= e0 - 1e-14);
        }
    }
}

#[test]
fn stick_to_slip_update_sets_small_slip_along_friction() {
    let mut rng = ChaCha8Rng::seed_from_u64(25);
    let model = paper_ref_model_aniso();
    let s = *model.settings();
    let mut checked = 0;
    for _ in 0..30 {
        let x = stick_state(&model, &mut rng);
        let tau = rvec(&mut rng, 1.0);
        let st = model.stick(&x, &tau).unwrap();
        if st.force.lambda_n <= 0.0 {
            continue;
        }
        let o = model.stick_to_slip_update(&x, &st.force).unwrap();
        let dir = st.force.lambda_t.normalize();
        assert!((o.delta_v - dir * s.slip_kick).norm() < 1e-9 * s.slip_kick);
        let kin = model.evaluate(&x).unwrap();
        assert!(kin.contact.n.dot(&(kin.contact.j_c * o.qd)).abs() < 1e-12);
        // slip is now defined without a hint, with friction continuing along λ_∥
        let x2 = State::new(x.q, o.qd, o.omega);
        let sl = model.slip(&x2, &tau, None).unwrap();
        assert!((sl.force.lambda_t.normalize() - dir * sl.force.lambda_n.signum()).norm() < 1e-6);
        checked += 1;
    }
    assert!(checked > 5);
}

#[test]
fn slip_to_stick_predicate_uses_the_sign_of_d_abs_dv() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    let model = paper_ref_model();
    let s = *model.settings();
    let p = *model.params();
    let mut seen = [0, 0];
    for _ in 0..40 {
        // a stick state plus a tiny tangential slip Δv = ε/2 · t (t random tangential)
        let x0 = stick_state(&model, &mut rng);
        let kin0 = model.evaluate(&x0).unwrap();
        let n = kin0.contact.n;
        let t = rvec(&mut rng, 1.0);
        let t = (t - n * n.dot(&t)).normalize();
        let dq = kin0.contact.j_c.try_inverse().unwrap() * (t * (-0.5 * s.slip_eps));
        let x = State::new(x0.q, x0.qd + dq, x0.omega);
        let tau = rvec(&mut rng, 1.0);
        let kin = model.evaluate(&x).unwrap();
        let acc = model.slip(&x, &tau, None).unwrap();
        let rate = kin
            .contact
            .delta_v
            .dot(&relative_acceleration(&kin, &acc.qdd, &acc.omega_dot));
        // d/dt Δv by FD (|Δv| itself is not smooth on the FD scale, Δv is)
        let fd: Vec3 = fd_along(&model, &x, &acc, |k| k.contact.delta_v);
        let an = relative_acceleration(&kin, &acc.qdd, &acc.omega_dot);
        assert!(
            (fd - an).norm() < 1e-6 * (1.0 + an.norm()),
            "Δv̇ {an} vs FD {fd}"
        );
        let fd_rate = kin.contact.delta_v.dot(&fd);
        if fd_rate.abs() > 1e-6 * kin.contact.delta_v.norm() * an.norm() {
            assert_eq!(rate < 0.0, fd_rate < 0.0);
        }
        let fires = transitions::slip_to_stick(&kin, &acc, &s);
        assert_eq!(fires, rate < 0.0);
        let t = transitions::check(Mode::Slip, &kin, &p, &acc, &s);
        if acc.force.lambda_n < 0.0 {
            assert_eq!(t, Some(Transition::ContactToFree));
        } else {
            assert_eq!(t == Some(Transition::SlipToStick), fires);
        }
        seen[fires as usize] += 1;
    }
    assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
}

#[test]
fn bad_parameters_and_inputs_are_rejected_with_clear_messages() {
    let model = paper_ref_model();
    let p = *model.params();
    let e = Params::new(*p.ball_inertia(), 1.0, -0.5, 0.6, 0.0, 0.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid parameter `mu_s` = -0.5: must be >= 0"
    );
    let e = Params::new(*p.ball_inertia(), 0.0, 0.8, 0.6, 0.0, 0.0).unwrap_err();
    assert!(e.to_string().contains("ball_radius"));
    let e = p.with_coulomb(0.8, f64::NAN).unwrap_err();
    assert!(e.to_string().contains("mu_k") && e.to_string().contains("finite"));
    let e = model
        .clone()
        .with_contact_variant(bf_model::ContactVariant::Smooth(0.0))
        .unwrap_err();
    assert!(e.to_string().contains("smooth_eps"));
    let bad = TransitionSettings {
        h_eps: -1.0,
        ..Default::default()
    };
    assert!(
        model
            .clone()
            .with_settings(bad)
            .unwrap_err()
            .to_string()
            .contains("h_eps")
    );
    let x = State::new(Vec3::new(f64::NAN, 0.0, 0.0), Vec3::zeros(), Vec3::zeros());
    assert_eq!(
        model.free(&x, &Vec3::zeros()),
        Err(ModelError::NonFinite { what: "state" })
    );
    let x = State::new(Vec3::new(0.1, 0.2, 0.3), Vec3::zeros(), Vec3::zeros());
    let tau = Vec3::new(0.0, f64::INFINITY, 0.0);
    assert_eq!(
        model.free(&x, &tau),
        Err(ModelError::NonFinite { what: "torque" })
    );
}

#[test]
fn projections_remove_drift() {
    let mut rng = ChaCha8Rng::seed_from_u64(27);
    let model = paper_ref_model_aniso();
    for _ in 0..15 {
        // configuration: perturb a contact configuration, one step shrinks h quadratically
        let q0 = contact_configuration(&model, &mut rng);
        let q = q0 + rvec(&mut rng, 1e-3);
        let x = State::new(q, Vec3::zeros(), Vec3::zeros());
        let h0 = model.evaluate(&x).unwrap().contact.h;
        let dq = model.project_configuration(&x).unwrap();
        let h1 = model
            .evaluate(&State::new(q + dq, Vec3::zeros(), Vec3::zeros()))
            .unwrap()
            .contact
            .h;
        assert!(h1.abs() < 50.0 * h0 * h0 + 1e-15, "h {h0} -> {h1}");
        // velocities: slip projection removes n·v_c only, stick projection removes Δv
        let x = slip_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let n = kin.contact.n;
        let drift = kin.contact.j_c.try_inverse().unwrap() * (n * 0.01);
        let xd = State::new(x.q, x.qd + drift, x.omega);
        let o = model.project_velocity(Mode::Slip, &xd).unwrap();
        assert!(n.dot(&(kin.contact.j_c * o.qd)).abs() < 1e-12);
        assert_eq!(o.omega, xd.omega);
        assert!(o.kinetic_energy_change <= 0.0);
        let o = model.project_velocity(Mode::Stick, &xd).unwrap();
        assert!(o.delta_v.norm() < 1e-10);
        let o = model.project_velocity(Mode::Free, &xd).unwrap();
        assert_eq!((o.qd, o.omega), (xd.qd, xd.omega));
    }
}

#[test]
fn guards_agree_with_predicates() {
    let mut rng = ChaCha8Rng::seed_from_u64(28);
    let model = paper_ref_model();
    let (p, s) = (*model.params(), *model.settings());
    for _ in 0..30 {
        let tau = rvec(&mut rng, 1.0);
        let x = stick_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let acc = model.stick(&x, &tau).unwrap();
        let g = transitions::guards(Mode::Stick, &kin, &p, &acc, &s);
        let fired: Vec<Transition> = g
            .iter()
            .flatten()
            .filter(|g| g.value <= 0.0)
            .map(|g| g.transition)
            .collect();
        match transitions::check(Mode::Stick, &kin, &p, &acc, &s) {
            Some(t) => assert!(fired.contains(&t)),
            None => assert!(fired.is_empty() || (acc.force.lambda_n == 0.0)),
        }
        let kin_free = model.evaluate(&x).unwrap();
        let g = transitions::guards(
            Mode::Free,
            &kin_free,
            &p,
            &model.free(&x, &tau).unwrap(),
            &s,
        );
        assert_eq!(g[0].unwrap().value, kin_free.contact.h / p.ball_radius());
    }
}
