//! The node limit of expression graphs: a construction past it gets the NaN poison instead of
//! new nodes, so memory stays bounded; evaluating an exceeded graph gives NaN, a replayed
//! differentiation that does not fit gives the poison, and the builders that finish a kernel
//! report the kernel as an error. Up to the limit nothing changes: a scene whose graph has
//! exactly N nodes generates the same module with a limit of N as without one, and fails with
//! N − 1.

#[path = "common/chain.rs"]
mod chain;

use bf_codegen::emit::{EmitSettings, ModuleSplit};
use bf_codegen::graph::{Graph, Id};
use bf_codegen::interp::Tape;
use bf_codegen::nodefn::Derivatives;
use bf_codegen::{CodegenError, Scene, SymbolicRobot, generate, generate_bounded};

/// `eval_all` takes the process's node limit, which one test sets: the tests of this file run
/// one at a time so that no other sees it.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// y₀ = x₀·x₁ − √(1 + x₂²), y₁ = sin(x₁) / (2 + cos(x₀)) on `g`.
fn build(g: &mut Graph) -> Vec<Id> {
    let (x0, x1, x2) = (g.var(0), g.var(1), g.var(2));
    let prod = g.mul(x0, x1);
    let one = g.one();
    let sq = g.square(x2);
    let under = g.add(one, sq);
    let root = g.sqrt(under);
    let y0 = g.sub(prod, root);
    let s = g.sin(x1);
    let two = g.constant(2.0);
    let c = g.cos(x0);
    let den = g.add(two, c);
    let y1 = g.div(s, den);
    vec![y0, y1]
}

#[test]
fn a_graph_past_its_limit_holds_the_poison_and_evaluates_to_nan() {
    let _serial = serial();
    let mut full = Graph::new();
    let outs = build(&mut full);
    let n = full.len();
    let x = [0.3, -1.2, 0.7];
    let want = Tape::new(&full, &outs).eval(&x);
    let exact = [
        0.3 * -1.2 - libm::sqrt(1.49),
        libm::sin(-1.2) / (2.0 + libm::cos(0.3)),
    ];
    for (w, e) in want.iter().zip(exact) {
        assert!((w - e).abs() < 1e-15, "{w} {e}");
    }

    // A limit of exactly the nodes needed changes nothing.
    let mut fits = Graph::with_limit(n);
    let same = build(&mut fits);
    assert!(!fits.exceeded());
    assert_eq!((fits.len(), &same), (n, &outs));
    assert_eq!(Tape::new(&fits, &same).eval(&x), want);

    // One node fewer: the graph keeps its limit plus the poison, and says so.
    let mut short = Graph::with_limit(n - 1);
    let cut = build(&mut short);
    assert!(short.exceeded());
    assert_eq!(short.len(), n);
    let poison = short.poison().unwrap();
    assert!(short.as_const(poison).unwrap().is_nan());
    // Growing on stays within the limit: every new node is the poison.
    let before = short.len();
    let more = short.sqrt(cut[0]);
    let v9 = short.var(9);
    let sum = short.add(more, v9);
    assert_eq!((more, sum, short.len()), (poison, poison, before));
    // Nodes it already holds are still found: x₀ is the same node on both graphs.
    assert_eq!(short.var(0), full.var(0));
    // Whatever is evaluated on it is NaN, even outputs built before the limit was reached.
    let early = short.var(1);
    let values = Tape::new(&short, &[cut[0], cut[1], early]).eval(&x);
    assert!(values.iter().all(|v| v.is_nan()), "{values:?}");
}

#[test]
fn a_replayed_differentiation_that_does_not_fit_is_the_poison() {
    let _serial = serial();
    let mut g = Graph::new();
    let outs = build(&mut g);
    let locals = [0, 1, 2];
    let d = Derivatives::new(&mut g, &outs, &locals, &[]);
    let needed = g.len();

    // The same history with room for the model but not for its derivatives: the cache's
    // replay stops at the limit, and no entry may name a node the graph does not hold.
    let mut small = Graph::with_limit(needed - 3);
    let outs_small = build(&mut small);
    assert!(!small.exceeded());
    let r = Derivatives::new(&mut small, &outs_small, &locals, &[]);
    assert!(small.exceeded());
    let p = small.poison().unwrap();
    assert_eq!(
        (r.jac.clone(), r.hess.clone()),
        (d.jac.clone(), d.hess.clone())
    );
    assert!(r.jac_ids.iter().chain(&r.hess_ids).all(|&id| id == p));
    assert!(small.len() <= needed - 2);

    // Differentiated afresh (no cache entry for this history) the same holds.
    let mut other = Graph::with_limit(needed - 3);
    let _ = other.var(11);
    let outs_other = build(&mut other);
    let fresh = Derivatives::new(&mut other, &outs_other, &locals, &[]);
    assert!(other.exceeded());
    let vals = Tape::new(&other, &fresh.jac_ids).eval(&[0.3, -1.2, 0.7, 0.0]);
    assert!(vals.iter().all(|v| v.is_nan()));
}

fn chain_scene(n: usize, kernels: &[&str]) -> (Scene, String) {
    let text = chain::chain_scene(n, kernels);
    (Scene::from_toml_str(&text, "chain.toml").unwrap(), text)
}

#[test]
fn a_kernel_past_the_limit_is_an_error_that_names_it() {
    let _serial = serial();
    let kernels = ["gravity", "mass_matrix", "christoffel"];
    let (scene, text) = chain_scene(6, &kernels);
    let want = generate(&scene, &text).unwrap();
    let n = want.report.graph_nodes;
    let opts = EmitSettings::default();
    let at = generate_bounded(&scene, &text, &opts, ModuleSplit::Auto, n).unwrap();
    assert_eq!(at.code, want.code);
    let Err(CodegenError::TooLarge(e)) =
        generate_bounded(&scene, &text, &opts, ModuleSplit::Auto, n - 1)
    else {
        panic!("a limit one node short must fail");
    };
    // The last kernel added the last node, so it is the one that does not fit.
    assert_eq!(
        (e.what.as_str(), e.joints, e.limit),
        ("kernel `christoffel`", 6, n - 1)
    );
    let msg = e.to_string();
    for m in ["6-joint", "christoffel", "--max-graph-nodes", "`kernels`"] {
        assert!(msg.contains(m), "{m}: {msg}");
    }

    // Which kernel: the limit reached while the mass matrix is built names it.
    let mut model = SymbolicRobot::with_node_limit(&scene, usize::MAX).unwrap();
    bf_codegen::kernels::build_kernel(&mut model, "gravity").unwrap();
    let after_gravity = model.g.len();
    let Err(CodegenError::TooLarge(e)) =
        generate_bounded(&scene, &text, &opts, ModuleSplit::Auto, after_gravity)
    else {
        panic!("no room for the mass matrix");
    };
    assert_eq!(e.what, "kernel `mass_matrix`");
}

#[test]
fn eval_past_the_limit_is_an_error() {
    let _serial = serial();
    let (scene, _) = chain_scene(4, &["gravity"]);
    let q = [0.1, -0.4, 0.9, 0.3];
    let out = bf_codegen::eval_all(&scene, &q, &q, [0.0; 3], 1e-3).unwrap();
    assert!(out.get("M").is_some());
    let model = SymbolicRobot::new(&scene).unwrap();
    // The kinematic skeleton fits, M and C do not.
    let limit = model.g.len() + 10;
    bf_codegen::graph::set_node_limit(limit);
    let r = bf_codegen::eval_all(&scene, &q, &q, [0.0; 3], 1e-3);
    bf_codegen::graph::set_node_limit(bf_codegen::graph::DEFAULT_NODE_LIMIT);
    let Err(CodegenError::TooLarge(e)) = r else {
        panic!("{r:?}");
    };
    assert_eq!((e.what.as_str(), e.limit), ("eval", limit));
}
