//! Shared test helpers: a [`Kernels`] implementation on bf-testkit's independent reference
//! (dual-number kinematics and dynamics), contact-state generators, and finite differences.
#![allow(dead_code)]

use bf_model::dynamics::Accelerations;
use bf_model::{ContactGeometry, ContactVariant, Kernels, Mat3, Model, Params, State, Vec3, skew};
use bf_testkit::Reference;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Paper scene text.
pub const PAPER_TOML: &str = include_str!("../../../scenes/paper.toml");
/// Human scene text.
pub const HUMAN_TOML: &str = include_str!("../../../scenes/human.toml");

/// Kernels evaluated by bf-testkit's reference implementation (tests only).
#[derive(Debug, Clone)]
pub struct RefKernels {
    name: String,
    toml: String,
    /// The reference model (public so tests can change e.g. the ball radius).
    pub reference: Reference,
}

impl RefKernels {
    /// From scene text.
    pub fn new(toml: &str) -> Self {
        let scene = bf_scene::Scene::from_toml_str(toml, "test").expect("scene parses");
        let reference = Reference::new(&scene).expect("reference builds");
        Self {
            name: scene.name.clone(),
            toml: toml.to_string(),
            reference,
        }
    }
}

impl Kernels for RefKernels {
    fn scene_name(&self) -> &str {
        &self.name
    }
    fn scene_toml(&self) -> &str {
        &self.toml
    }
    fn param_names(&self) -> &[&str] {
        &[]
    }
    fn param_values(&self) -> &[f64] {
        &[]
    }
    fn mass_cqd_g(&self, q: &[f64; 3], qd: &[f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
        let m = self.reference.mass_matrix(q);
        let c = self.reference.cqd_g(q, qd);
        let mut mm = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                mm[i][j] = m[(i, j)];
            }
        }
        (mm, [c[0], c[1], c[2]])
    }
    fn potential(&self, q: &[f64; 3]) -> f64 {
        self.reference.potential(q)
    }
    fn contact(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        omega: &[f64; 3],
        variant: ContactVariant,
    ) -> ContactGeometry {
        let eps = variant.eps();
        let c = self
            .reference
            .contact(q, qd, omega, eps)
            .expect("scene has a ball");
        let mut jc = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                jc[i][j] = c.j_c[(i, j)];
            }
        }
        ContactGeometry::from_arrays(
            c.alpha,
            c.sat_alpha,
            &c.p_c,
            &c.r_c,
            c.h,
            &c.n,
            &jc,
            &c.v_c,
            &c.delta_v,
            c.h_dot,
            &c.rc_dot,
            &c.jc_dot_qd,
        )
    }
}

/// Reference-backed paper model with the scene parameters.
pub fn paper_ref_model() -> Model<RefKernels> {
    Model::from_kernels(RefKernels::new(PAPER_TOML)).expect("paper model")
}

/// An anisotropic, non-diagonal ball inertia (world axes) of the paper ball's size.
pub fn anisotropic_inertia() -> Mat3 {
    let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
    let d = Mat3::from_diagonal(&Vec3::new(0.006, 0.008, 0.011));
    r.matrix() * d * r.matrix().transpose()
}

/// Paper model with an anisotropic ball.
pub fn paper_ref_model_aniso() -> Model<RefKernels> {
    let m = paper_ref_model();
    let p = m.params().with_ball_inertia(anisotropic_inertia()).unwrap();
    m.with_params(p)
}

/// Uniform random 3-vector in [-a, a]³.
pub fn rvec(rng: &mut ChaCha8Rng, a: f64) -> Vec3 {
    Vec3::new(
        rng.random_range(-a..a),
        rng.random_range(-a..a),
        rng.random_range(-a..a),
    )
}

/// Configuration with h(q) = 0 (|h| < 1e-12) found by Newton along ∇h = J_cᵀ n from a random
/// start, away from the kinks of sat(α) and from kinematic singularities.
pub fn contact_configuration<K: Kernels>(model: &Model<K>, rng: &mut ChaCha8Rng) -> Vec3 {
    let l = 1.0;
    for _ in 0..10_000 {
        let mut q = rvec(rng, std::f64::consts::PI);
        let mut ok = false;
        for _ in 0..60 {
            let kin = model
                .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
                .unwrap();
            let c = kin.contact;
            if c.h.abs() < 1e-13 {
                ok = true;
                break;
            }
            let grad = c.j_c.transpose() * c.n;
            let g2 = grad.norm_squared();
            if g2 < 1e-8 {
                break;
            }
            q -= grad * (c.h / g2);
        }
        if !ok {
            continue;
        }
        let kin = model
            .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
            .unwrap();
        let c = kin.contact;
        let near_kink = c.alpha.abs() < 0.02 || (c.alpha + l).abs() < 0.02;
        let jc_ok = c
            .j_c
            .try_inverse()
            .is_some_and(|inv| 1.0 / (c.j_c.norm() * inv.norm()) > 1e-3);
        let normal_ok = (c.j_c.transpose() * c.n).norm() > 0.05;
        if !near_kink && jc_ok && normal_ok {
            return q;
        }
    }
    panic!("no contact configuration found");
}

/// Contact state with Δv = 0 (sticking): random ω, q̇ = J_c⁻¹ (ω × r_c).
pub fn stick_state<K: Kernels>(model: &Model<K>, rng: &mut ChaCha8Rng) -> State {
    let q = contact_configuration(model, rng);
    let kin = model
        .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
        .unwrap();
    let omega = rvec(rng, 2.0);
    let qd = kin.contact.j_c.try_inverse().unwrap() * omega.cross(&kin.contact.r_c);
    State::new(q, qd, omega)
}

/// Contact state with n·v_c = 0 and Δv ≠ 0 (slipping).
pub fn slip_state<K: Kernels>(model: &Model<K>, rng: &mut ChaCha8Rng) -> State {
    let q = contact_configuration(model, rng);
    let kin = model
        .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
        .unwrap();
    let n = kin.contact.n;
    let v = rvec(rng, 1.5);
    let vt = v - n * n.dot(&v);
    let qd = kin.contact.j_c.try_inverse().unwrap() * vt;
    State::new(q, qd, rvec(rng, 2.0))
}

/// Contact state approaching the ball (n·v_c < 0), for impacts.
pub fn approach_state<K: Kernels>(model: &Model<K>, rng: &mut ChaCha8Rng) -> State {
    let q = contact_configuration(model, rng);
    let kin = model
        .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
        .unwrap();
    let n = kin.contact.n;
    let v = rvec(rng, 1.5);
    let v = v - n * n.dot(&v) - n * rng.random_range(0.05..1.5);
    let qd = kin.contact.j_c.try_inverse().unwrap() * v;
    State::new(q, qd, rvec(rng, 2.0))
}

/// x + d ẋ with ẋ = (q̇, q̈, ω̇).
pub fn advance(x: &State, acc: &Accelerations, d: f64) -> State {
    State::new(
        x.q + x.qd * d,
        x.qd + acc.qdd * d,
        x.omega + acc.omega_dot * d,
    )
}

/// Central difference of `f` along the vector field given by `acc`.
pub fn fd_along<K: Kernels, T, F>(model: &Model<K>, x: &State, acc: &Accelerations, f: F) -> T
where
    F: Fn(&bf_model::ContactKinematics) -> T,
    T: std::ops::Sub<Output = T> + std::ops::Div<f64, Output = T>,
{
    // Keep the state change per step small even for large accelerations (near-Painlevé states).
    let a = (acc.qdd.norm_squared() + acc.omega_dot.norm_squared()).sqrt();
    let d = 1e-5 / (1.0 + a / 10.0).sqrt();
    let p = f(&model.evaluate(&advance(x, acc, d)).unwrap());
    let m = f(&model.evaluate(&advance(x, acc, -d)).unwrap());
    (p - m) / (2.0 * d)
}

/// Kinetic energy computed directly from M_f and I_b.
pub fn kinetic(m_f: &Mat3, params: &Params, qd: &Vec3, w: &Vec3) -> f64 {
    0.5 * qd.dot(&(m_f * qd)) + 0.5 * w.dot(&(params.ball_inertia() * w))
}

/// Velocities after impulse ι, computed from eq. 40a–b without Γ.
pub fn apply(kin: &bf_model::ContactKinematics, params: &Params, iota: &Vec3) -> (Vec3, Vec3) {
    let qd = kin.state.qd + kin.m_f.try_inverse().unwrap() * kin.contact.j_c.transpose() * iota;
    let w = kin.state.omega - params.ball_inertia_inv() * kin.contact.r_c.cross(iota);
    (qd, w)
}

/// Δv = ω × r_c − J_c q̇ at the configuration of `kin` for other velocities.
pub fn delta_v(kin: &bf_model::ContactKinematics, qd: &Vec3, w: &Vec3) -> Vec3 {
    w.cross(&kin.contact.r_c) - kin.contact.j_c * qd
}

/// G = [J_c S(r_c)] as a 3×6 matrix.
pub fn g_matrix(kin: &bf_model::ContactKinematics) -> nalgebra::SMatrix<f64, 3, 6> {
    let mut g = nalgebra::SMatrix::<f64, 3, 6>::zeros();
    g.fixed_view_mut::<3, 3>(0, 0).copy_from(&kin.contact.j_c);
    g.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&skew(&kin.contact.r_c));
    g
}
