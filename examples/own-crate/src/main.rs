//! Prints the mass matrix M(q), C(q, q̇) q̇ + g(q) and the forward dynamics q̈ = M⁻¹(τ − C q̇ − g)
//! of the arm in `robot.urdf`, computed by the kernels its build script compiled, at the state
//! given as one JSON argument in the keys of `ball-finger eval` (`q`, `qd`, and `tau`, which
//! defaults to zeros):
//!
//! ```text
//! own-crate '{"q": [0.1, -0.5, 0.9, 0.2, -0.3, 0.4], "qd": [0.5, 0, -0.2, 0.1, 0, 0.3]}'
//! ```
//!
//! Output: one JSON object shaped as the `kernels` part of `ball-finger eval`:
//! `{"mass_cqd_g": {"m": [[…]], "cqd_g": […]}, "forward_dynamics": {"qdd": […]}}`.

use serde_json::{Value, json};

/// The generated module (build.rs).
#[allow(clippy::all, unused_variables, unused_parens, dead_code)]
mod ur5 {
    include!(concat!(env!("OUT_DIR"), "/ur5.rs"));
}

use ur5::NQ;

/// The entry `key` of the state as NQ finite numbers; `default` if it is absent.
fn joints(state: &Value, key: &str, default: Option<[f64; NQ]>) -> Result<[f64; NQ], String> {
    let Some(v) = state.get(key) else {
        return default.ok_or_else(|| format!("the state has no `{key}` (a list of {NQ} numbers)"));
    };
    let list = v
        .as_array()
        .ok_or_else(|| format!("`{key}` must be a list of {NQ} numbers, got {v}"))?;
    if list.len() != NQ {
        return Err(format!(
            "`{key}` has {} entries; the arm has {NQ} joints",
            list.len()
        ));
    }
    let mut out = [0.0; NQ];
    for (i, (o, x)) in out.iter_mut().zip(list).enumerate() {
        *o = x
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("`{key}[{i}]` must be a finite number, got {x}"))?;
    }
    Ok(out)
}

fn run(arg: &str) -> Result<Value, String> {
    let state: Value =
        serde_json::from_str(arg).map_err(|e| format!("the state is not JSON: {e}"))?;
    if !state.is_object() {
        return Err(format!("the state must be a JSON object, got {state}"));
    }
    let q = joints(&state, "q", None)?;
    let qd = joints(&state, "qd", None)?;
    let tau = joints(&state, "tau", Some([0.0; NQ]))?;
    let p = ur5::PARAM_DEFAULTS;
    let mut m = [[0.0; NQ]; NQ];
    let mut cqd_g = [0.0; NQ];
    ur5::mass_cqd_g(&q, &qd, &p, &mut m, &mut cqd_g);
    let mut qdd = [0.0; NQ];
    ur5::forward_dynamics(&q, &qd, &tau, &p, &mut qdd);
    if qdd.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "the forward dynamics is not finite at this state (q̈ = {qdd:?})"
        ));
    }
    Ok(json!({
        "mass_cqd_g": {"m": m, "cqd_g": cqd_g},
        "forward_dynamics": {"qdd": qdd},
    }))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [arg] = args.as_slice() else {
        eprintln!(
            "usage: own-crate '{{\"q\": [{NQ} numbers], \"qd\": [{NQ} numbers], \"tau\": [{NQ} numbers]}}'"
        );
        std::process::exit(2);
    };
    match run(arg) {
        Ok(v) => println!("{v}"),
        Err(e) => {
            eprintln!("own-crate: {e}");
            std::process::exit(1);
        }
    }
}
