//! [`bf_scene::Constants`]: the values of the paper's finger (docs/parameters.md, written here
//! independently of the scene files), the limits of the human finger (paper Sect. 6), the
//! runtime-parameter overrides, and `None` without a ball.

use bf_scene::{Constants, Scene};

fn scene(name: &str) -> Scene {
    Scene::load(format!(
        "{}/../scenes/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn paper_constants_are_the_papers() {
    let c = Constants::of(&scene("paper")).unwrap();
    assert_eq!(c.nq, 3);
    assert_eq!(c.radius, 1.0);
    // Solid sphere, m = 0.02 kg, r = 1 m: I_b = (2/5) m r² 1 (eq. 25).
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { 0.008 } else { 0.0 };
            assert!((c.ib[i][j] - want).abs() < 1e-18, "{:?}", c.ib);
        }
    }
    assert_eq!(
        (c.mu_s, c.mu_k, c.mu_v, c.damping),
        (0.8, 0.6, 0.001, 0.004)
    );
    assert_eq!(c.tau_max, [1.0; 3]);
    assert!(
        c.q_limits
            .iter()
            .all(|&(lo, hi)| lo == f64::NEG_INFINITY && hi == f64::INFINITY)
    );
}

#[test]
fn human_limits_are_flexion_ranges() {
    let c = Constants::of(&scene("human")).unwrap();
    let deg = std::f64::consts::PI / 180.0;
    assert_eq!(c.q_limits[1].0, 0.0);
    assert!((c.q_limits[1].1 - 90.0 * deg).abs() < 1e-15);
    assert_eq!(c.q_limits[2].0, 0.0);
    assert!((c.q_limits[2].1 - 100.0 * deg).abs() < 1e-15);
}

#[test]
fn runtime_parameters_override_ball_and_friction_only() {
    let base = Constants::of(&scene("paper")).unwrap();
    let c = base.clone().with_runtime_parameters(
        &[
            "ball.radius",
            "ball.inertia.xy",
            "friction.mu_k",
            "friction.socket_damping",
            "link2.mass",
        ],
        &[0.5, 1e-4, 0.3, 0.01, 7.0],
    );
    assert_eq!(c.radius, 0.5);
    assert_eq!((c.ib[0][1], c.ib[1][0]), (1e-4, 1e-4), "symmetric");
    assert_eq!(c.ib[0][0], base.ib[0][0]);
    assert_eq!((c.mu_s, c.mu_k, c.damping), (0.8, 0.3, 0.01));
    assert_eq!(c.mu_v, base.mu_v);
    assert_eq!((c.q_limits, c.tau_max), (base.q_limits, base.tau_max));
}

#[test]
fn a_scene_without_a_ball_has_none() {
    assert!(Constants::of(&scene("puma560")).is_none());
}

/// A default ball inertia, (2/5) m r² 1, follows a runtime radius as a scene file with that
/// radius would have it; one given by `ball.inertia.*` stays as given.
#[test]
fn a_default_ball_inertia_follows_the_runtime_radius() {
    let base = Constants::of(&scene("paper")).unwrap();
    assert!(!base.inertia_given);
    let c = base
        .clone()
        .with_runtime_parameters(&["ball.radius"], &[0.5]);
    let mut file = scene("paper");
    file.ball.as_mut().unwrap().radius = 0.5;
    assert_eq!(c, Constants::of(&file).unwrap());
    assert!((c.ib[1][1] / base.ib[1][1] - 0.25).abs() < 1e-15);
    let given = base.with_runtime_parameters(&["ball.inertia.yy", "ball.radius"], &[0.003, 0.5]);
    assert_eq!(given.ib[1][1], 0.003);
    assert_eq!(
        given.ib[0][0],
        Constants::of(&scene("paper")).unwrap().ib[0][0]
    );
}
