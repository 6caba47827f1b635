//! The computed-torque law against closed forms, and the generated inverse dynamics against
//! the model's mass matrix:
//! * a 1-joint pendulum (m l² q̈ + m g l sin q + b q̇ = τ) under τ = ID(q, q̇, q̈_cmd) tracks a
//!   sinusoid with exactly the error dynamics ë + 2ζω_n ė + ω_n² e = 0 (underdamped and
//!   critically damped closed forms, RK4 with a small step);
//! * `InverseDynamics` of the paper scene equals M(q) q̈ + C q̇ + g + μ_v q̇ from the model's
//!   `mass_cqd_g` kernel at random states.

use bf_control::{ComputedTorque, InverseDynamics};
use bf_model::Kernels;

const M: f64 = 0.3;
const L: f64 = 0.7;
const G: f64 = 9.81;
const B: f64 = 0.05;

/// Inverse dynamics of the pendulum.
fn pendulum_id(q: f64, qd: f64, qdd: f64) -> f64 {
    M * L * L * qdd + M * G * L * libm::sin(q) + B * qd
}

/// Reference q*(t) = A sin(Ω t) and its derivatives.
fn reference(t: f64) -> (f64, f64, f64) {
    let (a, w) = (0.8, 3.0);
    (
        a * libm::sin(w * t),
        a * w * libm::cos(w * t),
        -a * w * w * libm::sin(w * t),
    )
}

/// Closed-loop state derivative of the pendulum under the computed-torque law.
fn rhs(ct: &ComputedTorque, t: f64, x: [f64; 2]) -> [f64; 2] {
    let (qr, qdr, qddr) = reference(t);
    let mut cmd = [0.0];
    ct.acceleration(&[x[0]], &[x[1]], &[qr], &[qdr], &[qddr], &mut cmd);
    let tau = pendulum_id(x[0], x[1], cmd[0]);
    let qdd = (tau - M * G * L * libm::sin(x[0]) - B * x[1]) / (M * L * L);
    [x[1], qdd]
}

/// e(t) = q*(t) − q(t) by RK4 from e(0) = e0, ė(0) = ed0 over [0, 2] s, sampled every 0.1 s.
fn simulate(ct: &ComputedTorque, e0: f64, ed0: f64) -> Vec<(f64, f64)> {
    let (q0, qd0, _) = reference(0.0);
    let mut x = [q0 - e0, qd0 - ed0];
    let h = 1e-4;
    let mut out = Vec::new();
    for k in 0..=20_000 {
        let t = k as f64 * h;
        if k % 1000 == 0 {
            out.push((t, reference(t).0 - x[0]));
        }
        let add = |a: [f64; 2], b: [f64; 2], s: f64| [a[0] + s * b[0], a[1] + s * b[1]];
        let k1 = rhs(ct, t, x);
        let k2 = rhs(ct, t + h / 2.0, add(x, k1, h / 2.0));
        let k3 = rhs(ct, t + h / 2.0, add(x, k2, h / 2.0));
        let k4 = rhs(ct, t + h, add(x, k3, h));
        for i in 0..2 {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    out
}

#[test]
fn pendulum_error_follows_the_second_order_closed_form() {
    let (e0, ed0) = (0.2, -0.5);
    // Underdamped: e = e^{−ζω t}(e0 cos ω_d t + (ė0 + ζω e0)/ω_d sin ω_d t).
    let ct = ComputedTorque::new(6.0, 0.3).unwrap();
    let (w, z) = (ct.omega_n, ct.zeta);
    let wd = w * (1.0 - z * z).sqrt();
    for (t, e) in simulate(&ct, e0, ed0) {
        let exact = libm::exp(-z * w * t)
            * (e0 * libm::cos(wd * t) + (ed0 + z * w * e0) / wd * libm::sin(wd * t));
        assert!((e - exact).abs() < 1e-9, "ζ = 0.3, t = {t}: {e} vs {exact}");
    }
    // Critically damped: e = (e0 + (ė0 + ω e0) t) e^{−ω t}.
    let ct = ComputedTorque::new(8.0, 1.0).unwrap();
    let w = ct.omega_n;
    for (t, e) in simulate(&ct, e0, ed0) {
        let exact = (e0 + (ed0 + w * e0) * t) * libm::exp(-w * t);
        assert!((e - exact).abs() < 1e-9, "ζ = 1, t = {t}: {e} vs {exact}");
    }
    assert_eq!(ct.kp(), 64.0);
    assert_eq!(ct.kd(), 16.0);
}

#[test]
fn gains_out_of_range_are_refused_with_their_name() {
    for (wn, z, name) in [
        (0.0, 1.0, "omega_n"),
        (f64::NAN, 1.0, "omega_n"),
        (5.0, -0.1, "zeta"),
        (5.0, f64::INFINITY, "zeta"),
    ] {
        let e = ComputedTorque::new(wn, z).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}

#[test]
fn generated_inverse_dynamics_is_mass_matrix_times_acceleration_plus_bias() {
    let model = bf_model::fixtures::paper_scene().unwrap();
    let mu_v = model.params().mu_v();
    let id = InverseDynamics::compiled("paper", &[], mu_v).unwrap();
    assert_eq!(id.nq(), 3);
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
    };
    for _ in 0..20 {
        let q = [rnd(), rnd(), rnd()];
        let qd = [rnd(), rnd(), rnd()];
        let qdd = [rnd(), rnd(), rnd()];
        let mut tau = [0.0; 3];
        id.torque(&q, &qd, &qdd, &mut tau).unwrap();
        let (m, b) = model.kernels().mass_cqd_g(&q, &qd);
        for i in 0..3 {
            let expect: f64 = (0..3).map(|k| m[i][k] * qdd[k]).sum::<f64>() + b[i] + mu_v * qd[i];
            assert!(
                (tau[i] - expect).abs() < 1e-10 * (1.0 + expect.abs()),
                "τ{i}: {} vs {expect}",
                tau[i]
            );
        }
    }
    assert!(InverseDynamics::compiled("no-such-scene", &[], 0.0).is_err());
    assert!(InverseDynamics::compiled("paper", &[1.0], 0.0).is_err());
}
