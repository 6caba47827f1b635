//! Accuracy of the compiled kernels at extreme states, measured against the double-double
//! interpreter of the same graphs: |q| up to 1e6 rad (and periodicity in q), q̇ of 1e3 and
//! 1e-12, stretched (q2 = q3 = 0) and folded (q3 = π) fingers.

use bf_codegen::Scene;
use bf_codegen::dd::Dd;
use bf_codegen::interp::Tape;
use bf_codegen::kernels::build_kernel;
use bf_codegen::robot::SymbolicRobot;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// max |got − exact| / max(max |exact|, floor)
fn rel(got: &[f64], exact: &[Dd], floor: f64) -> f64 {
    let scale = exact.iter().fold(floor, |m, x| m.max(x.to_f64().abs()));
    got.iter()
        .zip(exact)
        .fold(0.0f64, |m, (g, e)| m.max((Dd::new(*g) - *e).to_f64().abs()))
        / scale
}

macro_rules! accuracy {
    ($m:ident, $kernels:expr, $states:expr, $tol:expr) => {{
        use bf_generated::$m as s;
        let scene = Scene::from_toml_str(s::SCENE_TOML, stringify!($m)).unwrap();
        let mut model = SymbolicRobot::new(&scene).unwrap();
        let mut worst = 0.0f64;
        for &k in $kernels {
            if !s::KERNELS.contains(&k) {
                continue;
            }
            let def = build_kernel(&mut model, k).unwrap();
            let ids: Vec<_> = def.output_ids();
            let tape = Tape::new(&model.g, &ids);
            for &(q, qd) in &$states {
                let q: [f64; s::NQ] = q;
                let qd: [f64; s::NQ] = qd;
                let omega = [0.3, -0.2, 2.2];
                let eps = 0.01;
                let p = s::PARAM_DEFAULTS;
                let l = model.layout;
                let mut vars = vec![Dd::new(0.0); l.n_vars()];
                for i in 0..s::NQ {
                    vars[i] = Dd::new(q[i]);
                    vars[s::NQ + i] = Dd::new(qd[i]);
                }
                for i in 0..3 {
                    vars[2 * s::NQ + i] = Dd::new(omega[i]);
                }
                vars[2 * s::NQ + 3] = Dd::new(eps);
                for (i, pi) in p.iter().enumerate() {
                    vars[l.param(i) as usize] = Dd::new(*pi);
                }
                let exact = tape.eval::<Dd>(&vars);
                let got = s::eval_flat(k, &q, &qd, &omega, eps, &p).unwrap();
                let e = rel(&got, &exact, 1e-300);
                assert!(
                    e < $tol,
                    "{}::{k}: relative error {e:e} at q = {q:?}, qd = {qd:?}",
                    stringify!($m)
                );
                worst = worst.max(e);
            }
        }
        worst
    }};
}

const DYN: &[&str] = &[
    "mass_matrix",
    "coriolis_matrix",
    "coriolis_qd",
    "gravity",
    "cqd_g",
    "cqd_g_rnea",
    "mass_cqd_g",
    "dmass_dq",
    "christoffel",
];
const KIN: &[&str] = &[
    "frames",
    "tip_jacobian",
    "com_jacobians",
    "tip_jdot_qd",
    "contact",
    "contact_smooth",
];

fn finger_states(rng: &mut ChaCha8Rng, qscale: f64, qdscale: f64) -> Vec<([f64; 3], [f64; 3])> {
    (0..30)
        .map(|_| {
            let q = std::array::from_fn(|_| rng.random_range(-qscale..qscale));
            let qd = std::array::from_fn(|_| rng.random_range(-qdscale..qdscale));
            (q, qd)
        })
        .collect()
}

#[test]
fn paper_accurate_for_huge_angles_and_velocities() {
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    for (qs, qds) in [(1e6, 1.0), (3.2, 1e3), (3.2, 1e-12), (1e6, 1e3)] {
        let states = finger_states(&mut rng, qs, qds);
        let w1 = accuracy!(paper, DYN, states.clone(), 1e-13);
        let w2 = accuracy!(paper, KIN, states.clone(), 1e-13);
        let w3 = accuracy!(human, DYN, states, 1e-13);
        eprintln!(
            "|q| < {qs:e}, |qd| < {qds:e}: worst relative error dyn {w1:.1e}, kin {w2:.1e}, human {w3:.1e}"
        );
    }
}

#[test]
fn paper_accurate_stretched_and_folded() {
    let mut states = Vec::new();
    for q1 in [0.0, 0.7, -2.0] {
        for (q2, q3) in [
            (0.0, 0.0),
            (0.0, std::f64::consts::PI),
            (std::f64::consts::FRAC_PI_2, -std::f64::consts::PI),
        ] {
            states.push(([q1, q2, q3], [0.5, -1.0, 2.0]));
        }
    }
    let w1 = accuracy!(paper, DYN, states.clone(), 1e-13);
    let w2 = accuracy!(paper, KIN, states, 1e-12);
    eprintln!("stretched/folded: worst relative error dyn {w1:.1e}, kin {w2:.1e}");
}

#[test]
fn arms_accurate() {
    let mut rng = ChaCha8Rng::seed_from_u64(52);
    for (qs, qds) in [(3.2, 1.0), (1e6, 1e3)] {
        let s6: Vec<([f64; 6], [f64; 6])> = (0..10)
            .map(|_| {
                (
                    std::array::from_fn(|_| rng.random_range(-qs..qs)),
                    std::array::from_fn(|_| rng.random_range(-qds..qds)),
                )
            })
            .collect();
        let s7: Vec<([f64; 7], [f64; 7])> = (0..10)
            .map(|_| {
                (
                    std::array::from_fn(|_| rng.random_range(-qs..qs)),
                    std::array::from_fn(|_| rng.random_range(-qds..qds)),
                )
            })
            .collect();
        let w1 = accuracy!(puma560, DYN, s6, 1e-11);
        let w2 = accuracy!(iiwa7, DYN, s7, 1e-11);
        eprintln!("arms |q| < {qs:e}: worst relative error puma560 {w1:.1e}, iiwa7 {w2:.1e}");
    }
}

/// The kernels are 2π-periodic in each joint: q and q mod 2π give the same values (the
/// reduction of a 1e6 rad angle is exact in f64 sin/cos; only the rounding of q mod 2π to
/// f64, about 1e-15, separates the two).
#[test]
fn periodic_in_joint_angles() {
    use bf_generated::paper as s;
    let mut rng = ChaCha8Rng::seed_from_u64(53);
    let two_pi = Dd::new(2.0) * bf_codegen::dd::PI;
    for _ in 0..100 {
        let q: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1e6..1e6));
        let qr: [f64; 3] = std::array::from_fn(|i| {
            let x = Dd::new(q[i]);
            let k = (q[i] / two_pi.to_f64()).floor();
            (x - Dd::new(k) * two_pi).to_f64()
        });
        let qd = [0.3, -0.4, 1.1];
        for &k in s::KERNELS {
            let a = s::eval_flat(k, &q, &qd, &[0.0, 0.0, 1.0], 0.01, &s::PARAM_DEFAULTS).unwrap();
            let b = s::eval_flat(k, &qr, &qd, &[0.0, 0.0, 1.0], 0.01, &s::PARAM_DEFAULTS).unwrap();
            let scale = b.iter().fold(1e-3f64, |m, x| m.max(x.abs()));
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-12 * scale, "{k}: {x} vs {y}");
            }
        }
    }
}

/// The `human` module's runtime parameters (`ball.radius`, `link3.mass`) scaled by 1e±3 in the
/// compiled kernels: results stay within 1e-13 of double-double, and the link-3 mass enters M
/// linearly (M(s m3) − M(m3) = (s − 1)(M(2 m3) − M(m3))).
#[test]
fn human_runtime_parameters_scaled() {
    use bf_generated::human as s;
    let scene = Scene::from_toml_str(s::SCENE_TOML, "human").unwrap();
    let mut model = SymbolicRobot::new(&scene).unwrap();
    let im = s::PARAM_NAMES
        .iter()
        .position(|n| *n == "link3.mass")
        .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(54);
    for &k in &["mass_cqd_g", "contact", "contact_smooth", "cqd_g"] {
        let def = build_kernel(&mut model, k).unwrap();
        let ids: Vec<_> = def.output_ids();
        let tape = Tape::new(&model.g, &ids);
        for _ in 0..20 {
            let q: [f64; 3] = std::array::from_fn(|_| rng.random_range(-3.2..3.2));
            let qd: [f64; 3] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
            for scale in [1e-3, 1e3] {
                let p: [f64; s::NP] = std::array::from_fn(|i| s::PARAM_DEFAULTS[i] * scale);
                let mut vars = vec![Dd::new(0.0); model.layout.n_vars()];
                for i in 0..3 {
                    vars[i] = Dd::new(q[i]);
                    vars[3 + i] = Dd::new(qd[i]);
                }
                vars[2 * 3 + 2] = Dd::new(1.0);
                vars[2 * 3 + 3] = Dd::new(0.01);
                for (i, pi) in p.iter().enumerate() {
                    vars[model.layout.param(i) as usize] = Dd::new(*pi);
                }
                let exact = tape.eval::<Dd>(&vars);
                let got = s::eval_flat(k, &q, &qd, &[0.0, 0.0, 1.0], 0.01, &p).unwrap();
                let e = rel(&got, &exact, 1e-300);
                assert!(
                    e < 1e-13,
                    "human::{k} with parameters × {scale}: error {e:e}"
                );
            }
        }
    }
    // Linearity of M in m3.
    let q = [0.4, -0.3, 0.9];
    let mut m = [[[0.0; 3]; 3]; 3];
    for (j, f) in [1.0, 2.0, 1e3].into_iter().enumerate() {
        let mut p = s::PARAM_DEFAULTS;
        p[im] *= f;
        s::mass_matrix(&q, &p, &mut m[j]);
    }
    for a in 0..3 {
        for b in 0..3 {
            let want = m[0][a][b] + (1e3 - 1.0) * (m[1][a][b] - m[0][a][b]);
            assert!((m[2][a][b] - want).abs() < 1e-11 * m[2][a][b].abs().max(1e-3));
        }
    }
}
