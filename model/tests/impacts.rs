//! Impact laws (paper Sect. 2.5, eq. 39–43) at random approaching contact states of the paper
//! scene (reference kinematics from bf-testkit):
//! - every law: n·J_c q̇⁺ = 0 (restitution 0) and the reported impulse reproduces the
//!   velocity jumps through eq. 40a–b (for Newton through 40a only: ω is unchanged);
//! - stick: Δv⁺ = 0, energy does not increase;
//! - Newton: tangential finger velocity kept, ω unchanged;
//! - maximum dissipation: |ι_∥| ≤ μ_k ι_n, energy does not increase, and its kinetic energy is
//!   the minimum found by a brute-force search over the friction cone (dense grid + local
//!   refinement, computed without Γ);
//! - minimum relative velocity: ι_∥ ∥ Δv_∥⁻, 0 ≤ μ ≤ μ_k, |Δv⁺| minimal over a dense μ grid;
//! - normal impulse (frictionless reading of eq. 39): ι ∥ n, ω unchanged, energy loss
//!   ½ (n·v_c⁻)² / nᵀW n.

mod common;

use bf_model::{ImpactLaw, Mode, ModelError, State, Vec3};
use common::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn every_law_removes_normal_velocity_and_is_momentum_consistent() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let model = paper_ref_model_aniso();
    for _ in 0..25 {
        let x = approach_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let vn = kin.contact.normal_velocity();
        assert!(vn < 0.0);
        for law in ImpactLaw::ALL {
            let o = model.impact(&x, law).unwrap();
            let vn_plus = kin.contact.n.dot(&(kin.contact.j_c * o.qd));
            assert!(
                vn_plus.abs() < 1e-10 * (1.0 + vn.abs()),
                "{law:?}: n·v_c⁺ = {vn_plus}"
            );
            // eq. 40a: M_f (q̇⁺ − q̇⁻) = J_cᵀ ι
            let lhs = kin.m_f * (o.qd - x.qd);
            let rhs = kin.contact.j_c.transpose() * o.impulse;
            assert!((lhs - rhs).norm() < 1e-10 * (1.0 + lhs.norm()), "{law:?}");
            if law != ImpactLaw::Newton {
                // eq. 40b: I_b (ω⁺ − ω⁻) = −r_c × ι
                let lhs = model.params().ball_inertia() * (o.omega - x.omega);
                let rhs = -kin.contact.r_c.cross(&o.impulse);
                assert!((lhs - rhs).norm() < 1e-10 * (1.0 + lhs.norm()), "{law:?}");
            }
            let dv = delta_v(&kin, &o.qd, &o.omega);
            assert!((dv - o.delta_v).norm() < 1e-12 * (1.0 + dv.norm()));
            assert_eq!(
                o.mode == Mode::Stick,
                dv.norm() <= model.settings().slip_eps
            );
            let t_minus = kinetic(&kin.m_f, model.params(), &x.qd, &x.omega);
            let t_plus = kinetic(&kin.m_f, model.params(), &o.qd, &o.omega);
            assert!((o.kinetic_energy_change - (t_plus - t_minus)).abs() < 1e-12 * (1.0 + t_minus));
        }
    }
}

#[test]
fn stick_and_newton_laws() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let model = paper_ref_model_aniso();
    for _ in 0..25 {
        let x = approach_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let t_minus = kinetic(&kin.m_f, model.params(), &x.qd, &x.omega);
        let s = model.impact(&x, ImpactLaw::Stick).unwrap();
        assert!(s.delta_v.norm() < 1e-10 * (1.0 + kin.contact.delta_v.norm()));
        assert_eq!(s.mode, Mode::Stick);
        assert!(s.kinetic_energy_change <= 1e-12 * t_minus);
        assert_eq!(
            s.within_static_cone,
            s.impulse_t.norm() <= model.params().mu_s() * s.impulse_n
        );

        let nw = model.impact(&x, ImpactLaw::Newton).unwrap();
        let n = kin.contact.n;
        let tn = |v: Vec3| v - n * n.dot(&v);
        let before = tn(kin.contact.j_c * x.qd);
        let after = tn(kin.contact.j_c * nw.qd);
        assert!((after - before).norm() < 1e-10 * (1.0 + before.norm()));
        assert_eq!(nw.omega, x.omega);
    }
}

/// Brute force for eq. 42: ι = ι_n (n + ρ e(θ)), ρ ∈ [0, μ_k], ι_n from n·J_c q̇⁺ = 0;
/// kinetic energy from the post-impact velocities (no Γ). Returns the minimum found.
fn brute_max_dissipation(kin: &bf_model::ContactKinematics, params: &bf_model::Params) -> f64 {
    let n = kin.contact.n;
    let a = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    let minv = kin.m_f.try_inverse().unwrap();
    let mu = params.mu_k();
    let energy = |rho: f64, th: f64| {
        let d = n + (t1 * libm::cos(th) + t2 * libm::sin(th)) * rho;
        let den = n.dot(&(kin.contact.j_c * minv * kin.contact.j_c.transpose() * d));
        if den <= 0.0 {
            return f64::INFINITY;
        }
        let iota_n = -kin.contact.normal_velocity() / den;
        let (qd, w) = apply(kin, params, &(d * iota_n));
        kinetic(&kin.m_f, params, &qd, &w)
    };
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for i in 0..=120 {
        let rho = mu * i as f64 / 120.0;
        for j in 0..360 {
            let th = j as f64 / 360.0 * std::f64::consts::TAU;
            let e = energy(rho, th);
            if e < best.0 {
                best = (e, rho, th);
            }
        }
    }
    // pattern search refinement with step halving (ρ clamped to [0, μ_k])
    let (mut e0, mut rho, mut th) = best;
    let (mut dr, mut dt) = (mu / 120.0, std::f64::consts::TAU / 360.0);
    for _ in 0..200 {
        let mut improved = false;
        for (a, b) in [
            (dr, 0.0),
            (-dr, 0.0),
            (0.0, dt),
            (0.0, -dt),
            (dr, dt),
            (-dr, -dt),
            (dr, -dt),
            (-dr, dt),
        ] {
            let r2 = (rho + a).clamp(0.0, mu);
            let e = energy(r2, th + b);
            if e < e0 {
                (e0, rho, th) = (e, r2, th + b);
                improved = true;
            }
        }
        if !improved {
            dr *= 0.5;
            dt *= 0.5;
            if dr < 1e-13 && dt < 1e-13 {
                break;
            }
        }
    }
    e0
}

#[test]
fn max_dissipation_is_the_cone_constrained_energy_minimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let base = paper_ref_model_aniso();
    let (mut interior, mut boundary) = (0, 0);
    for i in 0..24 {
        let mu_k = [0.1, 0.6, 2.0][i % 3];
        let model = base
            .clone()
            .with_params(base.params().with_coulomb(0.8, mu_k).unwrap());
        let x = approach_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let o = model.impact(&x, ImpactLaw::MaxDissipation).unwrap();
        assert!(o.impulse_t.norm() <= mu_k * o.impulse_n * (1.0 + 1e-10) + 1e-14);
        assert!(o.impulse_n >= 0.0);
        let t_minus = kinetic(&kin.m_f, model.params(), &x.qd, &x.omega);
        assert!(o.kinetic_energy_change <= 1e-12 * t_minus);
        let t_plus = t_minus + o.kinetic_energy_change;
        let brute = brute_max_dissipation(&kin, model.params());
        assert!(
            t_plus <= brute + 1e-10 * t_minus,
            "solver {t_plus} > brute {brute}"
        );
        assert!(
            t_plus >= brute - 1e-7 * t_minus,
            "solver {t_plus} << brute {brute}: infeasible?"
        );
        let stick = model.impact(&x, ImpactLaw::Stick).unwrap();
        if stick.impulse_t.norm() <= mu_k * stick.impulse_n {
            interior += 1;
            assert!((o.impulse - stick.impulse).norm() < 1e-9 * stick.impulse.norm());
            assert_eq!(o.mode, Mode::Stick);
        } else {
            boundary += 1;
            assert!((o.impulse_t.norm() - mu_k * o.impulse_n).abs() < 1e-9 * o.impulse.norm());
            assert_eq!(o.mode, Mode::Slip);
        }
    }
    assert!(
        interior >= 3 && boundary >= 3,
        "interior {interior}, boundary {boundary}"
    );
}

#[test]
fn min_relative_velocity_minimises_post_impact_slip() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let base = paper_ref_model_aniso();
    for i in 0..24 {
        let mu_k = [0.1, 0.6, 2.0][i % 3];
        let model = base
            .clone()
            .with_params(base.params().with_coulomb(0.8, mu_k).unwrap());
        let x = approach_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let n = kin.contact.n;
        let dv = kin.contact.delta_v;
        let d = (dv - n * n.dot(&dv)).normalize();
        let o = model.impact(&x, ImpactLaw::MinRelativeVelocity).unwrap();
        // ι_∥ = μ ι_n d with 0 ≤ μ ≤ μ_k (eq. 43e–f)
        let mu = o.impulse_t.dot(&d) / o.impulse_n;
        assert!((o.impulse_t - d * (mu * o.impulse_n)).norm() < 1e-10 * o.impulse.norm());
        assert!((-1e-12..=mu_k * (1.0 + 1e-12)).contains(&mu), "μ = {mu}");
        // brute force over μ (ι_n from n·J_c q̇⁺ = 0, no Γ)
        let minv = kin.m_f.try_inverse().unwrap();
        let mut best = f64::INFINITY;
        for j in 0..=20_000 {
            let m = mu_k * j as f64 / 20_000.0;
            let dir = n + d * m;
            let den = n.dot(&(kin.contact.j_c * minv * kin.contact.j_c.transpose() * dir));
            if den <= 0.0 {
                continue;
            }
            let iota = dir * (-kin.contact.normal_velocity() / den);
            let (qd, w) = apply(&kin, model.params(), &iota);
            best = best.min(delta_v(&kin, &qd, &w).norm());
        }
        assert!(
            o.delta_v.norm() <= best * (1.0 + 1e-9) + 1e-12,
            "{} > {best}",
            o.delta_v.norm()
        );
        assert!(o.delta_v.norm() >= best - 1e-3 * (1.0 + best));
    }
}

#[test]
fn separating_contact_is_refused() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let model = paper_ref_model();
    let x = approach_state(&model, &mut rng);
    let away = State::new(x.q, -x.qd, x.omega);
    for law in ImpactLaw::ALL {
        assert!(matches!(
            model.impact(&away, law),
            Err(ModelError::Separating { .. })
        ));
    }
}

#[test]
fn normal_impulse_law_is_frictionless_and_dissipative() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let model = paper_ref_model_aniso();
    for _ in 0..20 {
        let x = approach_state(&model, &mut rng);
        let kin = model.evaluate(&x).unwrap();
        let o = model.impact(&x, ImpactLaw::NormalImpulse).unwrap();
        let n = kin.contact.n;
        assert!(o.impulse_t.norm() < 1e-12 * o.impulse.norm());
        assert!(o.impulse_n > 0.0);
        assert!((o.omega - x.omega).norm() < 1e-12 * (1.0 + x.omega.norm()));
        assert!(n.dot(&(kin.contact.j_c * o.qd)).abs() < 1e-10);
        // ΔT = −½ (n·v_c⁻)² / nᵀ W n with W from M_f directly
        let w = kin.contact.j_c * kin.m_f.try_inverse().unwrap() * kin.contact.j_c.transpose();
        let vn = kin.contact.normal_velocity();
        let expect = -0.5 * vn * vn / n.dot(&(w * n));
        assert!((o.kinetic_energy_change - expect).abs() < 1e-10 * expect.abs());
    }
}
