//! `eval` on every scene of `scenes/`: it runs the compiled kernels of the generated registry
//! (no scene is wired in by hand), prints every kernel the scene's spec emits under the
//! scene's own kernel names, in emission order, says which kernels ran, and agrees with `eval`
//! on a renamed copy of the file (the interpreter, an independent evaluation path) on every
//! named quantity and every kernel output.

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{root, run, tmpdir};

fn csv(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// `eval` of `scene` at a fixed state of `n` joints: (JSON, stdout text, stderr).
fn eval(scene: &str, n: usize) -> (serde_json::Value, String, String) {
    let q: Vec<f64> = (0..n).map(|i| 0.3 - 0.17 * i as f64).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.1 + 0.05 * i as f64).collect();
    let qdd: Vec<f64> = (0..n).map(|i| 0.7 - 0.2 * i as f64).collect();
    let (q, qd, qdd) = (csv(&q), csv(&qd), csv(&qdd));
    let mut args = vec!["eval", scene, "--q", &q, "--qd", &qd, "--qdd", &qdd];
    // The ball's velocity, where there is a ball (an arm's `eval` refuses it).
    let ball = bf_codegen::Scene::load(scene).unwrap().ball.is_some();
    if ball {
        args.extend(["--omega", "0,0.5,1"]);
    }
    let out = run(&args);
    let (stdout, stderr) = (
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    );
    assert!(out.status.success(), "{scene}: {stderr}");
    (
        serde_json::from_str(&stdout).expect("eval prints one JSON object"),
        stdout,
        stderr,
    )
}

fn flatten(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(n) => out.push(n.as_f64().unwrap()),
        serde_json::Value::Array(a) => a.iter().for_each(|x| flatten(x, out)),
        serde_json::Value::Object(o) => o.values().for_each(|x| flatten(x, out)),
        other => panic!("unexpected JSON value {other}"),
    }
}

fn assert_close(what: &str, a: &serde_json::Value, b: &serde_json::Value) {
    let (mut x, mut y) = (Vec::new(), Vec::new());
    flatten(a, &mut x);
    flatten(b, &mut y);
    assert_eq!(x.len(), y.len(), "{what}");
    for (i, (u, v)) in x.iter().zip(&y).enumerate() {
        assert!(
            (u - v).abs() <= 1e-12 * (1.0 + u.abs()),
            "{what}[{i}]: {u} vs {v}"
        );
    }
}

#[test]
fn eval_prints_every_kernel_of_every_scene_from_the_registry() {
    let dir = tmpdir("eval-registry");
    let mut files: Vec<_> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 4, "{files:?}");
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let scene = bf_codegen::Scene::from_toml_str(&text, "scene").unwrap();
        let spec = bf_codegen::kernels::with_robot_kernels(&scene).kernels;
        let n = scene.links.len();
        let (compiled, stdout, stderr) = eval(file.to_str().unwrap(), n);
        assert!(
            stderr.contains(&format!("compiled kernels of `{}`", scene.name)),
            "{stderr}"
        );
        // Every kernel the spec emits, in emission order, and nothing else.
        let kernels = compiled["kernels"].as_object().unwrap();
        let printed: Vec<&String> = kernels.keys().collect();
        assert_eq!(printed.len(), spec.len(), "{}: {printed:?}", scene.name);
        let at: Vec<usize> = spec
            .iter()
            .map(|k| stdout.find(&format!("\"{k}\":{{")).expect(k))
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{}: order", scene.name);
        for k in &spec {
            assert!(stderr.contains(k.as_str()), "stderr names `{k}`: {stderr}");
        }
        // The same numbers under a name that was not compiled: the interpreter.
        let renamed = text.replacen(
            &format!("name = \"{}\"", scene.name),
            &format!("name = \"{}_copy\"", scene.name),
            1,
        );
        assert_ne!(renamed, text, "{}", scene.name);
        let copy = dir.join(format!("{}_copy.toml", scene.name));
        std::fs::write(&copy, renamed).unwrap();
        let (interpreted, _, stderr) = eval(copy.to_str().unwrap(), n);
        assert!(stderr.contains("interpreted"), "{stderr}");
        let a = compiled.as_object().unwrap();
        let b = interpreted.as_object().unwrap();
        assert_eq!(
            a.keys().collect::<Vec<_>>(),
            b.keys().collect::<Vec<_>>(),
            "{}",
            scene.name
        );
        for (key, v) in a {
            assert_close(&format!("{} {key}", scene.name), v, &b[key]);
        }
        // Two output paths of the compiled registry: the named mass matrix is the kernel's
        // (a scene that does not emit `mass_matrix` gets M from the interpreter).
        if spec.iter().any(|k| k == "mass_matrix") {
            assert_eq!(compiled["M"], compiled["kernels"]["mass_matrix"]["m"]);
        }
        // Physics independent of the code: M symmetric, and inverse dynamics at the given q̈
        // is M q̈ + C q̇ + g.
        let row = |v: &serde_json::Value, i: usize| -> Vec<f64> {
            v[i].as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        let qd: Vec<f64> = (0..n).map(|i| 0.1 + 0.05 * i as f64).collect();
        let qdd: Vec<f64> = (0..n).map(|i| 0.7 - 0.2 * i as f64).collect();
        let tau = &compiled["kernels"]["inverse_dynamics"]["tau"];
        for i in 0..n {
            let (m, c) = (row(&compiled["M"], i), row(&compiled["C"], i));
            let g = compiled["g"][i].as_f64().unwrap();
            let want: f64 = (0..n).map(|j| m[j] * qdd[j] + c[j] * qd[j]).sum::<f64>() + g;
            let got = tau[i].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
                "{} tau[{i}] {got} vs {want}",
                scene.name
            );
            for (j, mj) in m.iter().enumerate() {
                let mji = row(&compiled["M"], j)[i];
                assert!((mj - mji).abs() <= 1e-12 * (1.0 + mj.abs()), "M symmetric");
            }
        }
    }
}

#[test]
fn a_compiled_scene_with_a_shorter_kernel_list_prints_its_own_kernels() {
    // The paper scene listing two kernels: its numbers are the compiled scene's, so the
    // compiled kernels run, but only the kernels this file's spec emits are printed.
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    let start = text
        .find("\nkernels = [")
        .expect("paper.toml lists its kernels");
    let end = start + text[start..].find(']').unwrap() + 1;
    let short = format!(
        "{}\nkernels = [\"gravity\", \"mass_matrix\"]{}",
        &text[..start],
        &text[end..]
    );
    let dir = tmpdir("eval-registry-short");
    let file = dir.join("paper_short.toml");
    std::fs::write(&file, &short).unwrap();
    let scene = bf_codegen::Scene::from_toml_str(&short, "short").unwrap();
    let spec = bf_codegen::kernels::with_robot_kernels(&scene).kernels;
    assert_eq!(&spec[..2], ["gravity", "mass_matrix"]);
    let (out, stdout, stderr) = eval(file.to_str().unwrap(), 3);
    assert!(stderr.contains("compiled kernels of `paper`"), "{stderr}");
    let printed: Vec<&String> = out["kernels"].as_object().unwrap().keys().collect();
    assert_eq!(printed.len(), spec.len(), "{printed:?}");
    let at: Vec<usize> = spec
        .iter()
        .map(|k| stdout.find(&format!("\"{k}\":{{")).expect(k))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "emission order");
    assert!(
        !stdout.contains("\"frames\":{"),
        "frames is not in this file's list"
    );
    // The kernels are those of the full compiled file at the same state.
    let (full, _, _) = eval(root().join("scenes/paper.toml").to_str().unwrap(), 3);
    for k in &spec {
        assert_eq!(out["kernels"][k], full["kernels"][k], "{k}");
    }
    assert_eq!(out["M"], full["M"]);
}
