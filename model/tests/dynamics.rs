//! Mode dynamics (paper eq. 26, 29–38) checked against finite differences of kinematics
//! evaluated by bf-testkit's independent reference:
//! - stick: with λ of eq. 33 the relative velocity Δv stays 0 (d/dt Δv = 0 along the computed
//!   accelerations), Γ is symmetric positive definite;
//! - slip: n·v_c stays 0, |λ_∥| = μ_k λ_n along +Δv (friction on the finger opposes the finger's
//!   sliding −Δv), eq. 38 residual vanishes, friction dissipates;
//! - free: Euler's equations for the ball (gyroscopic term), closed form;
//! - failure modes: Painlevé (Sect. 7), singular Γ, no contact.

mod common;

use bf_model::dynamics::{self, contact_matrices, relative_acceleration, slip_law_residual};
use bf_model::{Mat3, ModelError, PainleveKind, State, Vec3};
use common::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn stick_keeps_relative_velocity_zero() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for model in [paper_ref_model(), paper_ref_model_aniso()] {
        let mut seen_positive = 0;
        for _ in 0..25 {
            let x = stick_state(&model, &mut rng);
            let tau = rvec(&mut rng, 1.0);
            let kin = model.evaluate(&x).unwrap();
            assert!(kin.contact.delta_v.norm() < 1e-12);
            let acc = model.stick(&x, &tau).unwrap();
            // Scale: the relative acceleration without contact force must be O(1) so that a
            // wrong λ would be visible.
            let free = model.free(&x, &tau).unwrap();
            let scale = relative_acceleration(&kin, &free.qdd, &free.omega_dot).norm();
            assert!(scale > 1e-2, "vacuous test state (scale {scale})");
            let fd: Vec3 = fd_along(&model, &x, &acc, |k| k.contact.delta_v);
            assert!(fd.norm() < 1e-6 * scale, "d/dt Δv = {fd} (scale {scale})");
            // the analytic relative acceleration agrees with the FD too
            let an = relative_acceleration(&kin, &acc.qdd, &acc.omega_dot);
            assert!(an.norm() < 1e-9 * scale);
            if acc.force.lambda_n > 0.0 {
                seen_positive += 1;
            }
            // decomposition (eq. 12, 15–18)
            let f = acc.force;
            assert!(
                (f.lambda_n * kin.contact.n + f.lambda_t - f.lambda).norm()
                    < 1e-12 * f.lambda.norm()
            );
            assert!(f.lambda_t.dot(&kin.contact.n).abs() < 1e-12 * f.lambda.norm());
            let sigma = model.params().mu_s() * f.lambda_n - f.lambda_t.norm();
            assert!((f.sigma - sigma).abs() < 1e-12 * (1.0 + sigma.abs()));
        }
        assert!(seen_positive > 0);
    }
}

#[test]
fn gamma_is_symmetric_positive_definite() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let model = paper_ref_model_aniso();
    for _ in 0..30 {
        let x = stick_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let m = contact_matrices(&kin, model.params()).unwrap();
        let g = m.gamma;
        assert!((g - g.transpose()).amax() < 1e-12 * g.amax());
        let eig = nalgebra::SymmetricEigen::new(g).eigenvalues;
        assert!(eig.min() > 1e-6 * eig.max(), "eigenvalues {eig}");
        // Γ = G M⁻¹ Gᵀ assembled independently as a 6×6 product
        let gm = g_matrix(&kin);
        let mut minv = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        minv.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&kin.m_f.try_inverse().unwrap());
        minv.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(model.params().ball_inertia_inv());
        let g2 = gm * minv * gm.transpose();
        assert!((g2 - g).amax() < 1e-10 * g.amax());
    }
}

#[test]
fn slip_force_law_and_normal_constraint() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let model = paper_ref_model_aniso();
    let mu_k = model.params().mu_k();
    let mut active = 0;
    for _ in 0..30 {
        let x = slip_state(&model, &mut rng);
        let tau = rvec(&mut rng, 1.0);
        let kin = model.evaluate(&x).unwrap();
        let acc = model.slip(&x, &tau, None).unwrap();
        let f = acc.force;
        let dv = kin.contact.delta_v;
        // |λ_∥| = μ_k |λ_n| and λ_∥ along sign(λ_n) Δv (eq. 20)
        assert!((f.lambda_t.norm() - mu_k * f.lambda_n.abs()).abs() < 1e-10 * f.lambda.norm());
        assert!(
            (f.lambda_t - dv * (mu_k * f.lambda_n / dv.norm())).norm() < 1e-10 * f.lambda.norm()
        );
        let r = slip_law_residual(&f.lambda, &kin.contact.n, &dv, mu_k);
        assert!(r[0].abs() < 1e-10 * f.lambda.norm() * dv.norm());
        assert!(r[1].abs() < 1e-10 * f.lambda.norm() * dv.norm());
        // normal constraint: d/dt(n·v_c) = 0 along the computed motion
        let free = model.free(&x, &tau).unwrap();
        let scale = dynamics::normal_acceleration(&kin, &free.qdd).abs() + 1.0;
        let fd: f64 = fd_along(&model, &x, &acc, |k| k.contact.n.dot(&k.contact.v_c));
        assert!(fd.abs() < 1e-6 * scale, "d/dt n·v_c = {fd}");
        if f.lambda_n > 0.0 {
            active += 1;
            // friction does no positive work: contact power −λ·Δv = −μ_k λ_n |Δv| ≤ 0
            let pb = model.power_balance(&x, &tau, &f).unwrap();
            assert!(pb.slip > 0.0);
            assert!((pb.slip - mu_k * f.lambda_n * dv.norm()).abs() < 1e-10 * pb.slip);
            // friction opposes the finger's sliding velocity relative to the ball (−Δv)
            assert!(f.lambda_t.dot(&(-dv)) < 0.0);
        }
    }
    assert!(active > 5);
}

#[test]
fn slip_needs_direction_at_zero_relative_velocity() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let model = paper_ref_model();
    let x = stick_state(&model, &mut rng);
    let tau = rvec(&mut rng, 1.0);
    let e = model.slip(&x, &tau, None).unwrap_err();
    assert!(
        matches!(e, ModelError::UndefinedSlipDirection { .. }),
        "{e}"
    );
    // with the sticking friction direction as hint the result is the eq. 20 limit
    let st = model.stick(&x, &tau).unwrap();
    let acc = model.slip(&x, &tau, Some(&st.force.lambda_t)).unwrap();
    let lt = acc.force.lambda_t;
    assert!(
        (lt.normalize() - st.force.lambda_t.normalize() * acc.force.lambda_n.signum()).norm()
            < 1e-10
    );
}

#[test]
fn free_ball_follows_euler_equations() {
    let model = paper_ref_model();
    let x0 = State::new(
        Vec3::new(0.3, 0.2, 0.1),
        Vec3::zeros(),
        Vec3::new(0.7, -1.3, 2.1),
    );
    // isotropic: ω̇ = −(D/I) ω exactly
    let acc = model.free(&x0, &Vec3::zeros()).unwrap();
    let i0 = model.params().ball_inertia()[(0, 0)];
    let d = model.params().socket_damping();
    assert!((acc.omega_dot + x0.omega * (d / i0)).norm() < 1e-12);
    // diagonal anisotropic, D = 0: Euler's equations I1 ω̇1 = (I2 − I3) ω2 ω3, ...
    let (i1, i2, i3) = (0.004, 0.007, 0.013);
    let p = model
        .params()
        .with_ball_inertia(Mat3::from_diagonal(&Vec3::new(i1, i2, i3)))
        .unwrap()
        .with_viscous(0.0, 0.0)
        .unwrap();
    let m2 = model.clone().with_params(p);
    let w = x0.omega;
    let acc = m2.free(&x0, &Vec3::zeros()).unwrap();
    let euler = Vec3::new(
        (i2 - i3) * w.y * w.z / i1,
        (i3 - i1) * w.z * w.x / i2,
        (i1 - i2) * w.x * w.y / i3,
    );
    assert!((acc.omega_dot - euler).norm() < 1e-12 * euler.norm());
    // rotated tensor: covariance ω̇(R I Rᵀ, R ω) = R ω̇(I, ω)
    let r = nalgebra::Rotation3::from_euler_angles(0.4, 1.0, -0.2);
    let ib = r.matrix() * m2.params().ball_inertia() * r.matrix().transpose();
    let m3 = m2
        .clone()
        .with_params(m2.params().with_ball_inertia(ib).unwrap());
    let xr = State::new(x0.q, x0.qd, r * w);
    let acc_r = m3.free(&xr, &Vec3::zeros()).unwrap();
    assert!((acc_r.omega_dot - r * euler).norm() < 1e-11 * euler.norm());
}

#[test]
fn painleve_configuration_is_an_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let base = paper_ref_model();
    let mut found = 0;
    for _ in 0..20 {
        let q = contact_configuration(&base, &mut rng);
        let kin0 = base
            .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
            .unwrap();
        let mats = contact_matrices(&kin0, base.params()).unwrap();
        let n = kin0.contact.n;
        let wn = mats.w * n;
        let wn_t = wn - n * n.dot(&wn);
        if wn_t.norm() < 1e-3 * wn.norm() {
            continue;
        }
        // slip direction t* = −T_n W n / |T_n W n| makes nᵀ W t* = −|T_n W n| < 0
        let t_star = -wn_t.normalize();
        let mu_crit = n.dot(&wn) / wn_t.norm();
        let rc = kin0.contact.r_c;
        // a finger velocity tangential to the ball, and ω giving Δv = 0.5 t*
        let v = rvec(&mut rng, 0.5);
        let vt = v - n * n.dot(&v);
        let qd = kin0.contact.j_c.try_inverse().unwrap() * vt;
        let target = t_star * 0.5 + vt;
        let omega = rc.cross(&target) / rc.norm_squared();
        let x = State::new(q, qd, omega);
        let kin = base.evaluate(&x).unwrap();
        assert!((kin.contact.delta_v.normalize() - t_star).norm() < 1e-9);
        // below the critical μ_k slip is fine, above it is a Painlevé error of either kind
        let ok_model = base.clone().with_params(
            base.params()
                .with_coulomb(5.0 * mu_crit, 0.5 * mu_crit)
                .unwrap(),
        );
        assert!(ok_model.slip(&x, &Vec3::zeros(), None).is_ok());
        let bad = base.clone().with_params(
            base.params()
                .with_coulomb(5.0 * mu_crit, 3.0 * mu_crit)
                .unwrap(),
        );
        // torques along ±J_cᵀ n push the free normal acceleration to either sign
        let push = kin.contact.j_c.transpose() * n;
        for (sign, kind) in [
            (-1.0, PainleveKind::Inconsistent),
            (1.0, PainleveKind::NonUnique),
        ] {
            let tau = push * (sign * 50.0 / push.norm());
            match bad.slip(&x, &tau, None) {
                Err(ModelError::Painleve {
                    kind: k,
                    effective_inverse_mass,
                    free_normal_acceleration,
                }) => {
                    assert_eq!(k, kind);
                    assert!(effective_inverse_mass < 0.0);
                    assert_eq!(free_normal_acceleration < 0.0, sign < 0.0);
                }
                other => panic!("expected Painlevé, got {other:?}"),
            }
        }
        found += 1;
    }
    assert!(found >= 10);
}

#[test]
fn stretched_finger_along_normal_gives_singular_gamma() {
    // With q3 = 0 and links 2–3 pointing at the ball centre, every joint moves the tip
    // perpendicular to the link, so J_cᵀ n = 0 and Γ is singular. For the paper geometry
    // the tip then sits at distance |o_1| − 2l = √5 − 2 from the centre: use that radius.
    let mut kern = RefKernels::new(PAPER_TOML);
    let r = 5f64.sqrt() - 2.0;
    kern.reference.ball.as_mut().unwrap().radius = r;
    let base = bf_model::Model::from_kernels(kern).unwrap();
    let params = *base.params();
    let p = bf_model::Params::new(*params.ball_inertia(), r, 0.8, 0.6, 1e-3, 4e-3).unwrap();
    let model = base.with_params(p);
    // golden-section on |p_e(q2)| for q1 = 0.4, q3 = 0
    let tip = |q2: f64| {
        let k = model
            .evaluate(&State::new(
                Vec3::new(0.4, q2, 0.0),
                Vec3::zeros(),
                Vec3::zeros(),
            ))
            .unwrap();
        k.contact.h
    };
    let (mut a, mut b) = (-std::f64::consts::PI, std::f64::consts::PI);
    // coarse scan first (h has one minimum per turn)
    let mut best = (0.0, f64::INFINITY);
    for i in 0..360 {
        let q2 = a + (b - a) * i as f64 / 360.0;
        let h = tip(q2);
        if h < best.1 {
            best = (q2, h);
        }
    }
    a = best.0 - 0.02;
    b = best.0 + 0.02;
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let c = b - gr * (b - a);
        let d = a + gr * (b - a);
        if tip(c) < tip(d) { b = d } else { a = c }
    }
    let q = Vec3::new(0.4, 0.5 * (a + b), 0.0);
    let x = State::new(q, Vec3::zeros(), Vec3::new(0.1, 0.2, 0.3));
    let kin = model.evaluate(&x).unwrap();
    assert!(kin.contact.h.abs() < 1e-12, "h = {}", kin.contact.h);
    assert!((kin.contact.j_c.transpose() * kin.contact.n).norm() < 1e-7);
    let e = model.stick(&x, &Vec3::zeros()).unwrap_err();
    assert!(matches!(e, ModelError::SingularContact { .. }), "{e}");
    let e = model
        .slip(&x, &Vec3::zeros(), Some(&Vec3::x()))
        .unwrap_err();
    assert!(matches!(e, ModelError::SingularContact { .. }), "{e}");
    for law in [
        bf_model::ImpactLaw::Stick,
        bf_model::ImpactLaw::MaxDissipation,
        bf_model::ImpactLaw::MinRelativeVelocity,
        bf_model::ImpactLaw::NormalImpulse,
    ] {
        let e = model.impact(&x, law).unwrap_err();
        assert!(
            matches!(e, ModelError::SingularContact { .. }),
            "{law:?}: {e}"
        );
    }
    // free motion is unaffected
    assert!(model.free(&x, &Vec3::zeros()).is_ok());
}

#[test]
fn contact_queries_far_from_contact_are_errors() {
    let model = paper_ref_model();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut checked = 0;
    for _ in 0..200 {
        let x = State::new(
            rvec(&mut rng, 3.0),
            rvec(&mut rng, 1.0),
            rvec(&mut rng, 1.0),
        );
        let h = model.evaluate(&x).unwrap().contact.h;
        if h.abs() < 0.01 {
            continue;
        }
        assert!(matches!(
            model.stick(&x, &Vec3::zeros()),
            Err(ModelError::NotInContact { .. })
        ));
        assert!(matches!(
            model.slip(&x, &Vec3::zeros(), None),
            Err(ModelError::NotInContact { .. })
        ));
        assert!(matches!(
            model.impact(&x, bf_model::ImpactLaw::Newton),
            Err(ModelError::NotInContact { .. })
        ));
        assert!(model.free(&x, &Vec3::zeros()).is_ok());
        checked += 1;
    }
    assert!(checked > 100);
}

#[test]
fn random_states_never_return_nan() {
    // Whatever the state, every call returns either finite numbers or a typed error.
    let model = paper_ref_model();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for i in 0..200 {
        let x = if i % 2 == 0 {
            State::new(
                rvec(&mut rng, 3.0),
                rvec(&mut rng, 2.0),
                rvec(&mut rng, 2.0),
            )
        } else {
            slip_state(&model, &mut rng)
        };
        let tau = rvec(&mut rng, 1.0);
        for mode in [
            bf_model::Mode::Free,
            bf_model::Mode::Stick,
            bf_model::Mode::Slip,
        ] {
            if let Ok(a) = model.accelerations(mode, &x, &tau) {
                assert!(
                    a.qdd
                        .iter()
                        .chain(a.omega_dot.iter())
                        .chain(a.force.lambda.iter())
                        .all(|v| v.is_finite())
                );
            }
        }
        for law in bf_model::ImpactLaw::ALL {
            if let Ok(o) = model.impact(&x, law) {
                assert!(
                    o.qd.iter()
                        .chain(o.omega.iter())
                        .chain(o.impulse.iter())
                        .all(|v| v.is_finite())
                );
            }
        }
    }
    let _ = rng.random::<f64>();
}
