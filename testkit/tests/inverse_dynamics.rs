//! bf-codegen's inverse-dynamics family against this kit's independent reference: the
//! world-axes recursive Newton–Euler `Reference::inverse_dynamics_ne` (PUMA 560, iiwa7, the
//! finger scenes, modified DH and the prismatic test scenes), forward dynamics against a
//! nalgebra Cholesky solve of M q̈ = τ − C q̇ − g with the reference's M, C q̇ and g, and the
//! prismatic kinematics and mass matrix against the reference's.

use bf_codegen::Scene;
use bf_codegen::interp::Tape;
use bf_codegen::kernels::build_kernel;
use bf_codegen::robot::SymbolicRobot;
use bf_testkit::reference::Reference;
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn scenes() -> Vec<(String, Scene)> {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut v = Vec::new();
    for n in ["paper", "human", "puma560", "iiwa7"] {
        v.push(format!("{root}/../scenes/{n}.toml"));
    }
    for n in ["modified4", "polar_rp", "prismatic_mod", "prismatic_std"] {
        v.push(format!("{root}/../codegen/tests/scenes/{n}.toml"));
    }
    v.into_iter()
        .map(|p| (p.clone(), Scene::load(&p).unwrap_or_else(|e| panic!("{e}"))))
        .collect()
}

/// Kernel `name` of `model` at (q, q̇, u), u the q̈ or τ argument; parameters at defaults.
fn kernel(model: &mut SymbolicRobot, name: &str, q: &[f64], qd: &[f64], u: &[f64]) -> Vec<f64> {
    let def = build_kernel(model, name).unwrap();
    let ids: Vec<_> = def.outputs.iter().flat_map(|o| o.ids.clone()).collect();
    let l = model.layout;
    let n = l.nq;
    let mut v = vec![0.0; l.n_vars_all()];
    v[..n].copy_from_slice(q);
    v[n..2 * n].copy_from_slice(qd);
    for (i, p) in model.params.iter().enumerate() {
        v[l.param(i) as usize] = p.1;
    }
    for i in 0..n {
        v[l.qdd(i) as usize] = u[i];
        v[l.tau(i) as usize] = u[i];
    }
    Tape::new(&model.g, &ids).eval::<f64>(&v)
}

fn close(a: &[f64], b: &[f64], rel: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: length");
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= rel * scale,
            "{what}[{i}]: {x} vs reference {y}"
        );
    }
}

#[test]
fn inverse_and_forward_dynamics_match_the_reference() {
    let mut r = ChaCha8Rng::seed_from_u64(21);
    for (path, scene) in scenes() {
        let rf = Reference::new(&scene).unwrap();
        let mut model = SymbolicRobot::new(&scene).unwrap();
        let n = model.nq();
        for _ in 0..10 {
            let mut rv = |s: f64| -> Vec<f64> { (0..n).map(|_| r.random_range(-s..s)).collect() };
            let (q, qd, qdd, tau) = (rv(3.0), rv(2.0), rv(4.0), rv(20.0));
            let ne = rf.inverse_dynamics_ne(&q, &qd, &qdd);
            let got = kernel(&mut model, "inverse_dynamics", &q, &qd, &qdd);
            close(&got, ne.as_slice(), 1e-11, &format!("{path}: τ"));
            // q̈ = M⁻¹(τ − C q̇ − g) by nalgebra from the reference's M, C q̇, g.
            let rhs = DVector::from_column_slice(&tau) - rf.cqd_g(&q, &qd);
            let want = rf.mass_matrix(&q).cholesky().unwrap().solve(&rhs);
            let fwd = kernel(&mut model, "forward_dynamics", &q, &qd, &tau);
            close(&fwd, want.as_slice(), 1e-10, &format!("{path}: q̈"));
        }
    }
}

#[test]
fn prismatic_kinematics_and_mass_matrix_match_the_reference() {
    let mut r = ChaCha8Rng::seed_from_u64(22);
    for (path, scene) in scenes()
        .into_iter()
        .filter(|(p, _)| p.contains("prismatic") || p.contains("polar"))
    {
        let rf = Reference::new(&scene).unwrap();
        let mut model = SymbolicRobot::new(&scene).unwrap();
        let n = model.nq();
        for _ in 0..10 {
            let q: Vec<f64> = (0..n).map(|_| r.random_range(-2.0..2.0)).collect();
            let qd: Vec<f64> = (0..n).map(|_| r.random_range(-2.0..2.0)).collect();
            let (pos, _) = rf.frames(&q);
            let got = kernel(&mut model, "frames", &q, &qd, &qd);
            let want: Vec<f64> = pos.iter().flatten().copied().collect();
            close(
                &got[..3 * n],
                &want,
                1e-13,
                &format!("{path}: frame origins"),
            );
            let (jp, jo) = rf.tip_jacobian(&q);
            let got = kernel(&mut model, "tip_jacobian", &q, &qd, &qd);
            let want: Vec<f64> = jp
                .row_iter()
                .chain(jo.row_iter())
                .flat_map(|r| r.iter().copied().collect::<Vec<_>>())
                .collect();
            close(&got, &want, 1e-13, &format!("{path}: tip Jacobian"));
            let m = kernel(&mut model, "mass_matrix", &q, &qd, &qd);
            let want: Vec<f64> = rf.mass_matrix(&q).transpose().iter().copied().collect();
            close(&m, &want, 1e-13, &format!("{path}: M"));
            let h = kernel(&mut model, "cqd_g_rnea", &q, &qd, &qd);
            close(
                &h,
                rf.cqd_g(&q, &qd).as_slice(),
                1e-12,
                &format!("{path}: C q̇ + g"),
            );
        }
    }
}
