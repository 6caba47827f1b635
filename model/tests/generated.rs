//! The product path (bf_generated kernels) agrees with bf-testkit's independent reference for
//! the paper and human scenes: every evaluated quantity (M_f, C q̇ + g, U, the contact geometry
//! with exact and smooth sat), and therefore the mode accelerations, contact forces and impact
//! results. Also: runtime parameters of the human scene (ball radius) reach both the kernels and
//! the physics parameters; wrong parameter vectors are typed errors.

mod common;

use bf_codegen::spec::SceneId;
use bf_model::registry::{self, CompiledKernels};
use bf_model::{
    ContactKinematics, ContactVariant, HumanKernels, ImpactLaw, Kernels, Mode, ModelError,
    PaperKernels, State, Vec3, fixtures,
};
use common::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn assert_kin_close(g: &ContactKinematics, r: &ContactKinematics, tol: f64) {
    let c = (&g.contact, &r.contact);
    assert!((g.m_f - r.m_f).amax() <= tol * (1.0 + r.m_f.amax()), "M_f");
    assert!(
        (g.cqd_g - r.cqd_g).amax() <= tol * (1.0 + r.cqd_g.amax()),
        "C qd + g"
    );
    assert!(close(g.potential, r.potential, tol), "U");
    assert!(close(c.0.alpha, c.1.alpha, tol) && close(c.0.sat_alpha, c.1.sat_alpha, tol));
    assert!(
        close(c.0.h, c.1.h, tol) && close(c.0.h_dot, c.1.h_dot, tol),
        "h, ḣ"
    );
    for (a, b, what) in [
        (c.0.p_c, c.1.p_c, "p_c"),
        (c.0.r_c, c.1.r_c, "r_c"),
        (c.0.n, c.1.n, "n"),
        (c.0.v_c, c.1.v_c, "v_c"),
        (c.0.delta_v, c.1.delta_v, "Δv"),
        (c.0.rc_dot, c.1.rc_dot, "ṙ_c"),
        (c.0.jc_dot_qd, c.1.jc_dot_qd, "J̇_c q̇"),
    ] {
        assert!(
            (a - b).amax() <= tol * (1.0 + b.amax()),
            "{what}: {a} vs {b}"
        );
    }
    assert!(
        (c.0.j_c - c.1.j_c).amax() <= tol * (1.0 + c.1.j_c.amax()),
        "J_c"
    );
}

#[test]
fn generated_kernels_match_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let paper = fixtures::paper_scene().unwrap();
    let human = fixtures::human_scene().unwrap();
    let rp = paper_ref_model();
    let rh = bf_model::Model::from_kernels(RefKernels::new(HUMAN_TOML)).unwrap();
    for i in 0..200 {
        let x = State::new(
            rvec(&mut rng, 4.0),
            rvec(&mut rng, 3.0),
            rvec(&mut rng, 3.0),
        );
        let variant = if i % 2 == 0 {
            ContactVariant::Exact
        } else {
            ContactVariant::Smooth(0.01)
        };
        let g = paper.kernels().evaluate(&x, variant);
        let r = rp.kernels().evaluate(&x, variant);
        assert_kin_close(&g, &r, 1e-11);
        let g = human.kernels().evaluate(&x, variant);
        let r = rh.kernels().evaluate(&x, variant);
        assert_kin_close(&g, &r, 1e-11);
    }
    // the physical parameters come from the same scene text
    assert_eq!(paper.params(), rp.params());
    assert_eq!(human.params(), rh.params());
}

#[test]
fn generated_physics_matches_reference_physics() {
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    let gm = fixtures::paper_scene().unwrap();
    let rm = paper_ref_model();
    for _ in 0..20 {
        let tau = rvec(&mut rng, 1.0);
        for (mode, x) in [
            (
                Mode::Free,
                State::new(
                    rvec(&mut rng, 3.0),
                    rvec(&mut rng, 2.0),
                    rvec(&mut rng, 2.0),
                ),
            ),
            (Mode::Stick, stick_state(&rm, &mut rng)),
            (Mode::Slip, slip_state(&rm, &mut rng)),
        ] {
            let a = gm.accelerations(mode, &x, &tau).unwrap();
            let b = rm.accelerations(mode, &x, &tau).unwrap();
            let s = 1.0 + b.qdd.amax() + b.omega_dot.amax() + b.force.lambda.amax();
            assert!((a.qdd - b.qdd).amax() < 1e-9 * s, "{mode:?}");
            assert!((a.omega_dot - b.omega_dot).amax() < 1e-9 * s, "{mode:?}");
            assert!(
                (a.force.lambda - b.force.lambda).amax() < 1e-9 * s,
                "{mode:?}"
            );
        }
        let x = approach_state(&rm, &mut rng);
        for law in ImpactLaw::ALL {
            let a = gm.impact(&x, law).unwrap();
            let b = rm.impact(&x, law).unwrap();
            assert!((a.qd - b.qd).amax() < 1e-9 * (1.0 + b.qd.amax()), "{law:?}");
            assert!(
                (a.omega - b.omega).amax() < 1e-9 * (1.0 + b.omega.amax()),
                "{law:?}"
            );
            assert_eq!(a.mode, b.mode);
        }
    }
}

#[test]
fn generated_stick_keeps_relative_velocity_zero() {
    // the same finite-difference check as tests/dynamics.rs, on the product path only
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    for model in [fixtures::paper_scene().unwrap()] {
        for _ in 0..10 {
            let x = stick_state(&model, &mut rng);
            let tau = rvec(&mut rng, 1.0);
            let acc = model.stick(&x, &tau).unwrap();
            let fd: Vec3 = fd_along(&model, &x, &acc, |k| k.contact.delta_v);
            assert!(fd.norm() < 1e-6, "{fd}");
        }
    }
    let model = fixtures::human_scene().unwrap();
    for _ in 0..10 {
        let x = stick_state(&model, &mut rng);
        let tau = rvec(&mut rng, 1.0);
        let acc = model.stick(&x, &tau).unwrap();
        let fd: Vec3 = fd_along(&model, &x, &acc, |k| k.contact.delta_v);
        assert!(fd.norm() < 1e-6, "{fd}");
    }
}

#[test]
fn human_runtime_parameters_reach_kernels_and_physics() {
    let k0 = HumanKernels::new();
    let names = k0.param_names();
    let ir = names
        .iter()
        .position(|n| *n == "ball.radius")
        .expect("ball.radius is runtime");
    let mut p = HumanKernels::new().param_values().to_vec();
    p[ir] = 0.8;
    let k = HumanKernels::with_params(&p).unwrap();
    let model = bf_model::Model::from_kernels(k).unwrap();
    assert_eq!(model.params().ball_radius(), 0.8);
    let x = State::new(Vec3::new(0.3, 0.9, 0.7), Vec3::zeros(), Vec3::zeros());
    let h_default = fixtures::human_scene()
        .unwrap()
        .evaluate(&x)
        .unwrap()
        .contact
        .h;
    let h = model.evaluate(&x).unwrap().contact.h;
    assert!(
        (h - (h_default + 0.2)).abs() < 1e-12,
        "h {h} vs {h_default} + 0.2"
    );
    // wrong length / non-finite parameters are typed errors
    assert!(matches!(
        HumanKernels::with_params(&[1.0]),
        Err(ModelError::ParameterCount {
            expected: 2,
            got: 1,
            ..
        })
    ));
    p[ir] = f64::NAN;
    assert!(matches!(
        HumanKernels::with_params(&p),
        Err(ModelError::NonFinite { .. })
    ));
    assert!(PaperKernels::with_params(&[]).is_ok());
    assert!(CompiledKernels::named(&SceneId::PAPER).is_ok());
    let e = CompiledKernels::named(&SceneId::from_static("nope")).unwrap_err();
    // the compiled contact scenes of the registry, in scenes/*.toml order
    assert!(e.to_string().contains("available: human, paper"), "{e}");
    let e = registry::contact_scene_id("nope").unwrap_err();
    assert!(e.to_string().contains("available: human, paper"), "{e}");
    assert_eq!(registry::contact_scene_id("human").unwrap(), SceneId::HUMAN);
}
