//! The paper's closed forms (App. A eq. 67–71, App. B eq. 72–75) against the generator's
//! graphs for the paper scene, evaluated by the interpreter. Each App. formula is an
//! independent derivation, so agreement checks the DH front-end and eq. 22a.

use bf_codegen::{EvalValue, Scene, eval_all};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn paper() -> Scene {
    Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/paper.toml")).unwrap()
}

fn mat(v: &EvalValue) -> Vec<Vec<f64>> {
    match v {
        EvalValue::Matrix(m) => m.clone(),
        EvalValue::Vector(v) => vec![v.clone()],
        EvalValue::Scalar(s) => vec![vec![*s]],
    }
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol * (1.0 + b.abs()),
        "{what}: generated {a} vs closed form {b}"
    );
}

#[test]
fn appendix_a_kinematics() {
    let scene = paper();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..50 {
        let q: Vec<f64> = (0..3).map(|_| rng.random_range(-3.2..3.2)).collect();
        let s = |x: f64| libm::sin(x);
        let c = |x: f64| libm::cos(x);
        let (q1, q2, q3) = (q[0], q[1], q[2]);
        let l = 1.0;
        // eq. 67 (s_{1-2-3} = sin(q1 − q2 − q3), ...)
        let pe = [
            (-s(q2 + q3) - s(q2) + 2.0) * l,
            (0.5 * (s(q1 + q2 + q3) + s(q1 - q2 - q3) + s(q1 + q2) + s(q1 - q2)) + s(q1)) * l,
            (0.5 * (c(q1 - q2 - q3) + c(q1 + q2 + q3) + c(q1 - q2) + c(q1 + q2)) + c(q1)) * l,
        ];
        // eq. 68, first column ê_x3
        let ex = [
            -s(q2 + q3),
            0.5 * (s(q1 + q2 + q3) + s(q1 - q2 - q3)),
            0.5 * (c(q1 - q2 - q3) + c(q1 + q2 + q3)),
        ];
        // eq. 70–71
        let j21 = 0.5 * (c(q1 - q2 - q3) + c(q1 + q2 + q3) + c(q1 - q2) + c(q1 + q2)) + c(q1);
        let j31 = -0.5 * (s(q1 + q2 + q3) + s(q1 - q2 - q3) + s(q1 + q2) + s(q1 - q2)) - s(q1);
        let jp = [
            [0.0, -c(q2 + q3) - c(q2), -c(q2 + q3)],
            [
                j21,
                0.5 * (c(q1 + q2 + q3) - c(q1 - q2 - q3) - c(q1 - q2) + c(q1 + q2)),
                0.5 * (c(q1 + q2 + q3) - c(q1 - q2 - q3)),
            ],
            [
                j31,
                0.5 * (s(q1 - q2 - q3) - s(q1 + q2 + q3) - s(q1 + q2) + s(q1 - q2)),
                // Misprint in eq. 70: the paper has −½(s_{1̄2̄3̄…}) here, i.e. +c1 s23; the
                // derivative of eq. 67's z row w.r.t. q3 is −c1 s23 = +½(s_{12̄3̄} − s_{123}),
                // the same s23 term as in column 2 (checked against p_e by FD elsewhere).
                0.5 * (s(q1 - q2 - q3) - s(q1 + q2 + q3)),
            ],
        ];
        let jo = [[-1.0, 0.0, 0.0], [0.0, -c(q1), -c(q1)], [0.0, s(q1), s(q1)]];
        let out = eval_all(&scene, &q, &[0.0; 3], [0.0; 3], 0.01).unwrap();
        let gpe = mat(out.get("p_e").unwrap())[0].clone();
        let r3 = mat(out.get("R3").unwrap());
        let gjp = mat(out.get("J_p").unwrap());
        let gjo = mat(out.get("J_o").unwrap());
        for i in 0..3 {
            close(gpe[i], pe[i], 1e-13, "p_e (eq. 67)");
            close(r3[i][0], ex[i], 1e-13, "e_x3 (eq. 68)");
            for j in 0..3 {
                close(
                    gjp[i][j],
                    jp[i][j] * l,
                    1e-13,
                    &format!("J_p[{i}][{j}] (eq. 70)"),
                );
                close(gjo[i][j], jo[i][j], 1e-13, "J_o (eq. 71)");
            }
        }
    }
}

#[test]
fn appendix_b_dynamics() {
    let scene = paper();
    let (l, m1, m2, m3) = (1.0, 0.02, 0.02, 0.02);
    let (ixx, iyy, izz) = (1.0677e-3, 2.3177e-3, 2.0833e-3);
    let g0 = 9.81;
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for _ in 0..50 {
        let q: Vec<f64> = (0..3).map(|_| rng.random_range(-3.2..3.2)).collect();
        let (q1, q2, q3) = (q[0], q[1], q[2]);
        // s_{xyz} = sin(x q1 + y q2 + z q3), c likewise (App. B notation).
        let s = |x: f64, y: f64, z: f64| libm::sin(x * q1 + y * q2 + z * q3);
        let c = |x: f64, y: f64, z: f64| libm::cos(x * q1 + y * q2 + z * q3);
        // eq. 75
        let m11 = 0.125 * (-4.0 * ixx + 4.0 * iyy + m3 * l * l) * c(0., 2., 2.)
            + 0.5 * m3 * l * l * c(0., 2., 1.)
            + 0.125 * (8.0 * c(0., 1., 0.) + 9.0) * m2 * l * l
            + 0.125 * ((m2 + 4.0 * m3) * l * l - 4.0 * ixx + 4.0 * iyy) * c(0., 2., 0.)
            + 0.5 * (iyy + ixx + iyy + ixx)
            + 0.125
                * (16.0 * c(0., 1., 0.) + 4.0 * c(0., 0., 1.) + 8.0 * c(0., 1., 1.) + 13.0)
                * m3
                * l
                * l
            + iyy
            + 0.25 * m1 * l * l;
        // eq. 74
        let m22 = 0.25 * m2 * l * l + (c(0., 0., 1.) + 1.25) * m3 * l * l + izz + izz;
        let m23 = 0.25 * (2.0 * c(0., 0., 1.) + 1.0) * m3 * l * l + izz;
        let m33 = 0.25 * m3 * l * l + izz;
        let mm = [[m11, 0.0, 0.0], [0.0, m22, m23], [0.0, m23, m33]];
        // eq. 72–73 with g_0 read as the magnitude 9.81. Misprint: the paper writes
        // s_{11̄1} − s_{1̄1̄1̄}-type terms as "s_{11-1} − s_{1-1-1}" in rows 2–3; the derivative of
        // the COG heights needs s_{111} − s_{1-1-1} = 2 c1 s23 (as in row 1 of eq. 73).
        let g11 = 2.0 * m1 * s(1., 0., 0.)
            + (s(1., 1., 0.) + s(1., -1., 0.) + 4.0 * s(1., 0., 0.)) * m2
            + (s(1., 1., 1.)
                + s(1., -1., -1.)
                + 2.0 * s(1., 1., 0.)
                + 2.0 * s(1., -1., 0.)
                + 4.0 * s(1., 0., 0.))
                * m3;
        let g2 = m2 * (s(1., 1., 0.) - s(1., -1., 0.))
            + (s(1., 1., 1.) - s(1., -1., -1.) + 2.0 * s(1., 1., 0.) - 2.0 * s(1., -1., 0.)) * m3;
        let g3 = m3 * (s(1., 1., 1.) - s(1., -1., -1.));
        let gg = [g11, g2, g3].map(|x| -l / 4.0 * g0 * x);
        let out = eval_all(&scene, &q, &[0.0; 3], [0.0; 3], 0.01).unwrap();
        let gm = mat(out.get("M").unwrap());
        let gv = mat(out.get("g").unwrap())[0].clone();
        for i in 0..3 {
            close(gv[i], gg[i], 1e-13, &format!("g[{i}] (eq. 72-73)"));
            for j in 0..3 {
                close(
                    gm[i][j],
                    mm[i][j],
                    1e-13,
                    &format!("M[{i}][{j}] (eq. 74-75)"),
                );
            }
        }
    }
}

/// eq. 76–79: the Christoffel symbols ψ_ijk of the paper finger (all others zero).
#[test]
fn appendix_b_christoffel_symbols() {
    use bf_codegen::robot::SymbolicRobot;
    let scene = paper();
    let mut model = SymbolicRobot::new(&scene).unwrap();
    let ch: Vec<_> = model
        .christoffel()
        .into_iter()
        .flatten()
        .flatten()
        .collect();
    let (l, m2, m3) = (1.0, 0.02, 0.02);
    let (ixx, iyy) = (1.0677e-3, 2.3177e-3);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..50 {
        let q: Vec<f64> = (0..3).map(|_| rng.random_range(-3.2..3.2)).collect();
        let (q1, q2, q3) = (q[0], q[1], q[2]);
        let s = |x: f64, y: f64, z: f64| libm::sin(x * q1 + y * q2 + z * q3);
        let l2 = l * l;
        let p112 = 0.125 * (4.0 * ixx - 4.0 * iyy - m3 * l2) * s(0., 2., 2.)
            - 0.5 * m3 * l2 * s(0., 2., 1.)
            - 0.125 * ((4.0 * m3 + m2) * l2 - 4.0 * ixx + 4.0 * iyy) * s(0., 2., 0.)
            - 0.5 * m3 * l2 * s(0., 1., 1.)
            - (0.5 * m2 + m3) * l2 * s(0., 1., 0.);
        let p113 = 0.125 * (4.0 * ixx - 4.0 * iyy - m3 * l2) * s(0., 2., 2.)
            - 0.25 * m3 * l2 * (2.0 * s(0., 1., 1.) + s(0., 0., 1.) + s(0., 2., 1.));
        let p223 = -0.5 * m3 * l2 * s(0., 0., 1.);
        let mut want = [[[0.0; 3]; 3]; 3];
        want[0][0][1] = p112;
        want[0][1][0] = p112;
        want[1][0][0] = -p112;
        want[0][0][2] = p113;
        want[0][2][0] = p113;
        want[2][0][0] = -p113;
        want[1][1][2] = p223;
        want[1][2][1] = p223;
        want[1][2][2] = p223;
        want[2][1][1] = -p223;
        let state: Vec<f64> = q.iter().copied().chain([0.0; 7]).collect();
        let got = bf_codegen::interp::eval::<f64>(&model.g, &ch, &state);
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    close(
                        got[i * 9 + j * 3 + k],
                        want[i][j][k],
                        1e-13,
                        &format!("psi_{}{}{} (eq. 77-79)", i + 1, j + 1, k + 1),
                    );
                }
            }
        }
    }
}
