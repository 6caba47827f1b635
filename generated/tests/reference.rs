//! Every generated kernel of every scene against the independent reference of bf-testkit
//! (`bf_testkit::Reference`, built from the module's own `SCENE_TOML`): frames and Jacobians
//! (eq. 67–71), M (eq. 22a), ∂M/∂q, Christoffel symbols and C (eq. 76), g = ∂U/∂q and U
//! (eq. 22b with the docs/parameters.md sign), C q̇ + g by both the Lagrangian and the RNEA path,
//! the inverse-dynamics family (τ against the reference's Newton–Euler pass, forward dynamics
//! by its residual with the reference's M and C q̇ + g, Y π = τ, ∂τ/∂q and ∂τ/∂q̇ against central
//! differences), and the contact quantities of eq. 2–13, 33 and 58–59.
//!
//! States (seeded): random configurations, the stretched finger (q2 = … = 0), folded ones
//! (q_i = ±π), q̇ of size 1e3 and 1e-12, large |q| (~1e4 rad), and — for the scenes with a
//! ball — states exactly on the ball (h = 0 by bisection) touching with the fingertip and
//! with the side of the last link; for `human` (runtime parameters) also non-default `p`.
//! Tolerance per output array: |kernel − reference|∞ ≤ 1e-12 · max(1, ‖ref‖∞, s), with s the
//! size of the summed terms for velocity-dependent outputs (|q̇|·|M| for C, |q̇|²·|M| for C q̇,
//! |q̇| for v_c, ṙ_c, ḣ, |q̇|² for J̇ q̇).

use bf_testkit::Reference;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

const TOL: f64 = 1e-12;

/// Call a kernel through an opaque function pointer, so each large `#[inline]` kernel is
/// compiled once as its own function instead of being inlined into these long test functions
/// (a rustc/LLVM stack overflow in debug-info emission was seen while building this file).
macro_rules! call {
    ($f:path; $($a:expr),* $(,)?) => {{
        let f = std::hint::black_box($f as fn($(call!(@ty $a)),*));
        f($($a),*)
    }};
    (@ty $a:expr) => { _ };
}

/// |got − want|∞ ≤ TOL · max(1, |want|∞), and everything finite.
fn cmp(ctx: &str, got: &[f64], want: &[f64]) {
    cmp_s(ctx, got, want, 1.0);
}

/// As [`cmp`] with the scale raised to `natural` (the size of the terms that are summed, e.g.
/// |q̇|²·|M| for C q̇: at q̇ ~ 1e3 an exactly-zero output is the cancellation of ~1e6 terms).
fn cmp_s(ctx: &str, got: &[f64], want: &[f64], natural: f64) {
    assert_eq!(got.len(), want.len(), "{ctx}: length");
    let scale = want.iter().fold(natural.max(1.0), |a, b| a.max(b.abs()));
    let err = got
        .iter()
        .zip(want)
        .fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
    assert!(
        got.iter().all(|x| x.is_finite()) && err <= TOL * scale,
        "{ctx}: error {err:e} > {TOL:e} * {scale:e}\n kernel    {got:?}\n reference {want:?}"
    );
}

fn flat2<const R: usize, const C: usize>(a: &[[f64; C]; R]) -> Vec<f64> {
    a.iter().flatten().copied().collect()
}

fn flat3<const A: usize, const R: usize, const C: usize>(a: &[[[f64; C]; R]; A]) -> Vec<f64> {
    a.iter().flatten().flatten().copied().collect()
}

/// Row-major entries of a nalgebra matrix.
fn rows(m: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    m.transpose().iter().copied().collect()
}

/// The generic test states for an `N`-joint arm: (label, q, q̇).
fn states<const N: usize>(seed: u64) -> Vec<(String, [f64; N], [f64; N])> {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let mut rv = |s: f64| -> [f64; N] { std::array::from_fn(|_| r.random_range(-s..s)) };
    let mut out = Vec::new();
    for i in 0..20 {
        out.push((format!("random {i}"), rv(PI), rv(2.0)));
    }
    let q0 = rv(PI);
    let qd0 = rv(2.0);
    let stretched: [f64; N] = std::array::from_fn(|i| if i == 0 { q0[0] } else { 0.0 });
    let folded: [f64; N] = std::array::from_fn(|i| if i == 0 { q0[0] } else { PI });
    let folded_alt: [f64; N] = std::array::from_fn(|i| {
        if i == 0 {
            q0[0]
        } else if i % 2 == 0 {
            -PI
        } else {
            PI
        }
    });
    let last_folded: [f64; N] = std::array::from_fn(|i| if i + 1 == N { PI } else { q0[i] });
    out.push(("stretched".into(), stretched, qd0));
    out.push(("folded".into(), folded, qd0));
    out.push(("folded alternating".into(), folded_alt, qd0));
    out.push(("last joint folded".into(), last_folded, qd0));
    out.push(("stretched, fast".into(), stretched, qd0.map(|v| v * 1e3)));
    out.push(("random, qd 1e3".into(), q0, qd0.map(|v| v * 1e3)));
    out.push(("random, qd 1e-12".into(), q0, qd0.map(|v| v * 1e-12)));
    out.push(("folded, qd 1e-12".into(), folded, qd0.map(|v| v * 1e-12)));
    out.push(("at rest".into(), q0, [0.0; N]));
    let big = rv(1.0).map(|v| v + 1e4);
    out.push(("large |q| ~ 1e4".into(), big, qd0));
    out
}

/// States exactly on the ball (h = 0 by bisection in q2), touching with the fingertip
/// (α ≥ 0) and with the side of the last link (−a_n < α < 0): at least 3 of each.
fn contact_states<const N: usize>(rf: &Reference, seed: u64) -> Vec<(String, [f64; N], [f64; N])> {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let a_n = rf.links[N - 1].a;
    let (mut tip, mut side) = (Vec::new(), Vec::new());
    let h = |q: &[f64; N]| {
        rf.contact(q, &[0.0; N], &[0.0; 3], None)
            .map(|c| c.h)
            .unwrap_or(f64::NAN)
    };
    for _ in 0..2000 {
        if tip.len() >= 3 && side.len() >= 3 {
            break;
        }
        let mut q: [f64; N] = std::array::from_fn(|_| r.random_range(-PI..PI));
        let qd: [f64; N] = std::array::from_fn(|_| r.random_range(-2.0..2.0));
        // Scan q2 for a sign change of h, then bisect.
        let grid = 64;
        let mut lo = None;
        for k in 0..grid {
            let (a, b) = (
                -PI + 2.0 * PI * k as f64 / grid as f64,
                -PI + 2.0 * PI * (k + 1) as f64 / grid as f64,
            );
            let (mut qa, mut qb) = (q, q);
            qa[1] = a;
            qb[1] = b;
            if h(&qa) > 0.0 && h(&qb) < 0.0 {
                lo = Some((a, b));
                break;
            }
        }
        let Some((mut a, mut b)) = lo else { continue };
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            let mut qm = q;
            qm[1] = m;
            if h(&qm) > 0.0 {
                a = m
            } else {
                b = m
            }
            if b - a < 1e-15 {
                break;
            }
        }
        q[1] = a;
        let Ok(c) = rf.contact(&q, &qd, &[0.0; 3], None) else {
            continue;
        };
        assert!(c.h.abs() < 1e-12, "bisection did not converge: h = {}", c.h);
        if c.alpha >= 1e-6 {
            if tip.len() < 3 {
                tip.push((format!("on ball, tip (alpha {:.3})", c.alpha), q, qd));
            }
        } else if c.alpha < -1e-6 && c.alpha > -a_n + 1e-6 && side.len() < 3 {
            side.push((format!("on ball, side (alpha {:.3})", c.alpha), q, qd));
        }
    }
    assert!(
        tip.len() >= 3 && side.len() >= 3,
        "contact states: tip {} side {}",
        tip.len(),
        side.len()
    );
    tip.into_iter().chain(side).collect()
}

/// Kernels of the Lagrangian/RNEA dynamics family.
macro_rules! check_dynamics {
    ($m:ident, $rf:expr, $p:expr, $label:expr, $q:expr, $qd:expr) => {{
        use bf_generated::$m as g;
        const N: usize = g::NQ;
        let (rf, p, q, qd): (&Reference, &[f64; g::NP], [f64; N], [f64; N]) = ($rf, $p, $q, $qd);
        let ctx = |k: &str| format!("{}::{k} at {}", stringify!($m), $label);
        let qv = nalgebra::DVector::from_column_slice(&qd);
        let v = qd.iter().fold(0.0f64, |a, b| a.max(b.abs()));

        let mut m = [[0.0; N]; N];
        call!(g::mass_matrix; &q, p, &mut m);
        let m_ref = rf.mass_matrix(&q);
        cmp(&ctx("mass_matrix"), &flat2(&m), &rows(&m_ref));
        let ms = m_ref.amax().max(1.0);

        let mut dm = [[[0.0; N]; N]; N];
        call!(g::dmass_dq; &q, p, &mut dm);
        let dm_ref: Vec<f64> = rf.dmass_dq(&q).iter().flat_map(rows).collect();
        cmp(&ctx("dmass_dq"), &flat3(&dm), &dm_ref);

        let mut ch = [[[0.0; N]; N]; N];
        call!(g::christoffel; &q, p, &mut ch);
        let ch_ref: Vec<f64> = rf.christoffel(&q).into_iter().flatten().flatten().collect();
        cmp(&ctx("christoffel"), &flat3(&ch), &ch_ref);

        let mut c = [[0.0; N]; N];
        call!(g::coriolis_matrix; &q, &qd, p, &mut c);
        let c_ref = rf.coriolis_matrix(&q, &qd);
        cmp_s(&ctx("coriolis_matrix"), &flat2(&c), &rows(&c_ref), v * ms);

        let mut cqd = [0.0; N];
        call!(g::coriolis_qd; &q, &qd, p, &mut cqd);
        let cqd_ref = &c_ref * &qv;
        cmp_s(&ctx("coriolis_qd"), &cqd, cqd_ref.as_slice(), v * v * ms);

        let mut grav = [0.0; N];
        call!(g::gravity; &q, p, &mut grav);
        let g_ref = rf.gravity(&q);
        cmp(&ctx("gravity"), &grav, g_ref.as_slice());

        let mut u = 0.0;
        call!(g::potential; &q, p, &mut u);
        cmp(&ctx("potential"), &[u], &[rf.potential(&q)]);

        let cg_ref = rf.cqd_g(&q, &qd);
        let mut cg = [0.0; N];
        call!(g::cqd_g; &q, &qd, p, &mut cg);
        cmp_s(&ctx("cqd_g"), &cg, cg_ref.as_slice(), v * v * ms);
        let mut cg_rnea = [0.0; N];
        call!(g::cqd_g_rnea; &q, &qd, p, &mut cg_rnea);
        cmp_s(&ctx("cqd_g_rnea"), &cg_rnea, cg_ref.as_slice(), v * v * ms);
        // The reference's own Newton–Euler path agrees with its Lagrangian one.
        cmp_s(
            &ctx("reference NE"),
            rf.inverse_dynamics_ne(&q, &qd, &[0.0; N]).as_slice(),
            cg_ref.as_slice(),
            v * v * ms,
        );

        let mut m2 = [[0.0; N]; N];
        let mut cg2 = [0.0; N];
        call!(g::mass_cqd_g; &q, &qd, p, &mut m2, &mut cg2);
        cmp(&ctx("mass_cqd_g.m"), &flat2(&m2), &rows(&m_ref));
        cmp_s(&ctx("mass_cqd_g.cqd_g"), &cg2, cg_ref.as_slice(), v * v * ms);

        // Inverse dynamics against the reference's world-axes Newton–Euler pass, at a q̈
        // derived from the state (|q̈| ≤ 2).
        let qdd: [f64; N] = std::array::from_fn(|i| 2.0 * libm::sin(1.7 * q[i] + 0.3 * i as f64));
        let tau_ref = rf.inverse_dynamics_ne(&q, &qd, &qdd);
        let s_tau = (v * v + 2.0) * ms;
        let mut tau = [0.0; N];
        call!(g::inverse_dynamics; &q, &qd, &qdd, p, &mut tau);
        cmp_s(&ctx("inverse_dynamics"), &tau, tau_ref.as_slice(), s_tau);
        // Forward dynamics: the residual M q̈ − (τ − C q̇ − g) with the reference's M, C q̇, g.
        let mut acc = [0.0; N];
        call!(g::forward_dynamics; &q, &qd, &tau, p, &mut acc);
        let res = &m_ref * nalgebra::DVector::from_column_slice(&acc);
        let rhs = nalgebra::DVector::from_column_slice(&tau) - &cg_ref;
        cmp_s(&ctx("forward_dynamics"), res.as_slice(), rhs.as_slice(), s_tau);
        // Regressor: Y π = τ with π from the reference's link data.
        let mut y = [[[0.0; 10]; N]; N];
        call!(g::regressor; &q, &qd, &qdd, p, &mut y);
        let pis: Vec<[f64; 10]> = rf
            .links
            .iter()
            .map(|l| {
                let (m, c, i) = (l.mass, l.com, l.inertia);
                let cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
                let io = |a: usize, b: usize| {
                    i[a][b] + m * (if a == b { cc } else { 0.0 } - c[a] * c[b])
                };
                [m, m * c[0], m * c[1], m * c[2], io(0, 0), io(0, 1), io(0, 2), io(1, 1), io(1, 2), io(2, 2)]
            })
            .collect();
        let ypi: Vec<f64> = y
            .iter()
            .map(|row| {
                row.iter()
                    .zip(&pis)
                    .map(|(yl, pl)| yl.iter().zip(pl).map(|(a, b)| a * b).sum::<f64>())
                    .sum()
            })
            .collect();
        cmp_s(&ctx("regressor"), &ypi, tau_ref.as_slice(), s_tau);
        // ∂τ/∂q and ∂τ/∂q̇ against central differences of the compiled inverse dynamics
        // (moderate states only: the step must resolve the derivative).
        if $label.starts_with("random ") {
            let mut dq = [[0.0; N]; N];
            let mut dqd = [[0.0; N]; N];
            call!(g::inverse_dynamics_dq; &q, &qd, &qdd, p, &mut dq);
            call!(g::inverse_dynamics_dqd; &q, &qd, p, &mut dqd);
            let h = 1e-6;
            for k in 0..N {
                for (which, exact) in [("dq", &dq), ("dqd", &dqd)] {
                    let (mut qa, mut qda, mut qb, mut qdb) = (q, qd, q, qd);
                    if which == "dq" {
                        qa[k] += h;
                        qb[k] -= h;
                    } else {
                        qda[k] += h;
                        qdb[k] -= h;
                    }
                    let (mut ta, mut tb) = ([0.0; N], [0.0; N]);
                    call!(g::inverse_dynamics; &qa, &qda, &qdd, p, &mut ta);
                    call!(g::inverse_dynamics; &qb, &qdb, &qdd, p, &mut tb);
                    for i in 0..N {
                        let fd = (ta[i] - tb[i]) / (2.0 * h);
                        assert!(
                            (exact[i][k] - fd).abs() <= 1e-6 * s_tau,
                            "{}: ∂τ_{i}/∂{which}_{k} = {} vs central difference {fd}",
                            ctx("inverse_dynamics_dq"),
                            exact[i][k]
                        );
                    }
                }
            }
        }
    }};
}

/// Kinematic kernels.
macro_rules! check_kinematics {
    ($m:ident, $rf:expr, $p:expr, $label:expr, $q:expr, $qd:expr) => {{
        use bf_generated::$m as g;
        const N: usize = g::NQ;
        let (rf, p, q, qd): (&Reference, &[f64; g::NP], [f64; N], [f64; N]) = ($rf, $p, $q, $qd);
        let ctx = |k: &str| format!("{}::{k} at {}", stringify!($m), $label);

        let mut pos = [[0.0; 3]; N];
        let mut rot = [[[0.0; 3]; 3]; N];
        call!(g::frames; &q, p, &mut pos, &mut rot);
        let (pos_ref, rot_ref) = rf.frames(&q);
        let pos_ref: Vec<f64> = pos_ref.into_iter().flatten().collect();
        let rot_ref: Vec<f64> = rot_ref.into_iter().flatten().flatten().collect();
        cmp(&ctx("frames.pos"), &flat2(&pos), &pos_ref);
        cmp(&ctx("frames.rot"), &flat3(&rot), &rot_ref);

        let mut jp = [[0.0; N]; 3];
        let mut jo = [[0.0; N]; 3];
        call!(g::tip_jacobian; &q, p, &mut jp, &mut jo);
        let (jp_ref, jo_ref) = rf.tip_jacobian(&q);
        cmp(&ctx("tip_jacobian.jp"), &flat2(&jp), &rows(&jp_ref));
        cmp(&ctx("tip_jacobian.jo"), &flat2(&jo), &rows(&jo_ref));

        let mut cjp = [[[0.0; N]; 3]; N];
        let mut cjo = [[[0.0; N]; 3]; N];
        call!(g::com_jacobians; &q, p, &mut cjp, &mut cjo);
        let cj_ref = rf.com_jacobians(&q);
        let cjp_ref: Vec<f64> = cj_ref.iter().flat_map(|(a, _)| rows(a)).collect();
        let cjo_ref: Vec<f64> = cj_ref.iter().flat_map(|(_, b)| rows(b)).collect();
        cmp(&ctx("com_jacobians.jp"), &flat3(&cjp), &cjp_ref);
        cmp(&ctx("com_jacobians.jo"), &flat3(&cjo), &cjo_ref);

        let mut jd = [0.0; 6];
        call!(g::tip_jdot_qd; &q, &qd, p, &mut jd);
        let v = qd.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        cmp_s(&ctx("tip_jdot_qd"), &jd, &rf.tip_jdot_qd(&q, &qd), v * v);
    }};
}

/// Contact kernels, exact and smooth sat.
macro_rules! check_contact {
    ($m:ident, $rf:expr, $p:expr, $label:expr, $q:expr, $qd:expr, $omega:expr) => {{
        use bf_generated::$m as g;
        const N: usize = g::NQ;
        let (rf, p, q, qd, omega): (&Reference, &[f64; g::NP], [f64; N], [f64; N], [f64; 3]) =
            ($rf, $p, $q, $qd, $omega);
        let v = qd.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for eps in [None, Some(0.01), Some(0.3)] {
            let mut c = g::Contact::default();
            match eps {
                None => call!(g::contact; &q, &qd, &omega, p, &mut c),
                Some(e) => call!(g::contact_smooth; &q, &qd, &omega, e, p, &mut c),
            }
            let r = rf.contact(&q, &qd, &omega, eps).expect("scene has a ball");
            let ctx = |k: &str| format!("{}::contact(eps {eps:?}).{k} at {}", stringify!($m), $label);
            cmp(&ctx("alpha"), &[c.alpha], &[r.alpha]);
            cmp(&ctx("sat_alpha"), &[c.sat_alpha], &[r.sat_alpha]);
            cmp(&ctx("p_c"), &c.p_c, &r.p_c);
            cmp(&ctx("r_c"), &c.r_c, &r.r_c);
            cmp(&ctx("h"), &[c.h], &[r.h]);
            cmp(&ctx("n"), &c.n, &r.n);
            cmp(&ctx("j_c"), &flat2(&c.j_c), &rows(&r.j_c));
            cmp_s(&ctx("v_c"), &c.v_c, &r.v_c, v);
            cmp_s(&ctx("delta_v"), &c.delta_v, &r.delta_v, v);
            cmp_s(&ctx("h_dot"), &[c.h_dot], &[r.h_dot], v);
            cmp_s(&ctx("rc_dot"), &c.rc_dot, &r.rc_dot, v);
            cmp_s(&ctx("jc_dot_qd"), &c.jc_dot_qd, &r.jc_dot_qd, v * v);
        }
    }};
}

/// The kernels this file checks; a scene emitting anything else fails the coverage test.
const CHECKED: &[&str] = &[
    "inverse_dynamics",
    "inverse_dynamics_dq",
    "inverse_dynamics_dqd",
    "forward_dynamics",
    "regressor",
    "frames",
    "tip_jacobian",
    "com_jacobians",
    "tip_jdot_qd",
    "mass_matrix",
    "dmass_dq",
    "christoffel",
    "coriolis_matrix",
    "coriolis_qd",
    "gravity",
    "potential",
    "cqd_g",
    "cqd_g_rnea",
    "mass_cqd_g",
    "contact",
    "contact_smooth",
];

fn reference_of(toml: &str, name: &str, names: &[&str], p: &[f64]) -> Reference {
    Reference::from_scene_toml(toml, name)
        .expect("SCENE_TOML parses")
        .with_params(names, p)
        .expect("runtime parameter names are known to the reference")
}

/// The finger scenes (all kernels, with contact).
macro_rules! finger_test {
    ($test:ident, $m:ident, $seed:expr, $perturb:expr) => {
        #[test]
        fn $test() {
            use bf_generated::$m as g;
            for k in g::KERNELS {
                assert!(
                    CHECKED.contains(k),
                    "kernel {k} of {} is not checked",
                    stringify!($m)
                );
            }
            let mut params = vec![g::PARAM_DEFAULTS];
            // Non-default runtime parameters, mirrored into the reference by name.
            if g::NP > 0 {
                let perturb: fn(&str, f64) -> f64 = $perturb;
                params.push(std::array::from_fn(|i| {
                    perturb(g::PARAM_NAMES[i], g::PARAM_DEFAULTS[i])
                }));
            }
            let mut r = ChaCha8Rng::seed_from_u64($seed);
            for p in &params {
                let rf = reference_of(g::SCENE_TOML, stringify!($m), &g::PARAM_NAMES, p);
                let mut all = states::<{ g::NQ }>($seed);
                all.extend(contact_states::<{ g::NQ }>(&rf, $seed + 1));
                for (label, q, qd) in all {
                    let label = format!("{label}, p = {p:?}");
                    let omega = [
                        r.random_range(-3.0..3.0),
                        r.random_range(-3.0..3.0),
                        r.random_range(-3.0..3.0),
                    ];
                    check_dynamics!($m, &rf, p, &label, q, qd);
                    check_kinematics!($m, &rf, p, &label, q, qd);
                    check_contact!($m, &rf, p, &label, q, qd, omega);
                }
            }
        }
    };
}

/// The arm scenes (dynamics and kinematics, no ball).
macro_rules! arm_test {
    ($test:ident, $m:ident, $seed:expr) => {
        #[test]
        fn $test() {
            use bf_generated::$m as g;
            for k in g::KERNELS {
                assert!(
                    CHECKED.contains(k),
                    "kernel {k} of {} is not checked",
                    stringify!($m)
                );
            }
            let p = g::PARAM_DEFAULTS;
            let rf = reference_of(g::SCENE_TOML, stringify!($m), &g::PARAM_NAMES, &p);
            assert!(
                !g::KERNELS.contains(&"contact"),
                "{}: contact kernels present, extend this test",
                stringify!($m)
            );
            for (label, q, qd) in states::<{ g::NQ }>($seed) {
                check_dynamics!($m, &rf, &p, &label, q, qd);
                check_kinematics!($m, &rf, &p, &label, q, qd);
            }
        }
    };
}

finger_test!(paper_kernels_match_reference, paper, 101, |_, v| v);
finger_test!(
    human_kernels_match_reference,
    human,
    202,
    |name, v| match name {
        "ball.radius" => 0.85 * v,
        "link3.mass" => 1.7 * v,
        _ => 1.1 * v,
    }
);
arm_test!(puma560_kernels_match_reference, puma560, 303);
arm_test!(iiwa7_kernels_match_reference, iiwa7, 404);
