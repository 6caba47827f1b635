//! bf-generated: the flat dynamics kernels of every scene in `scenes/*.toml`, generated at
//! build time by bf-codegen (`build.rs` → `$OUT_DIR/<scene>.rs` → `include!`).
//!
//! One module per scene, named after the scene (`paper`, `human`, `puma560`, `iiwa7`, …), and
//! the registry [`SCENES`] of every scene's name and TOML text ([`scene_toml`]), and the
//! model-kernel registry [`SCENE_KERNELS`] ([`scene`]): every scene's `mass_cqd_g`,
//! `potential` and (contact scenes) `contact`/`contact_smooth` behind fn pointers of one
//! signature, which bf-model wraps into its typed physics for any compiled scene, and every
//! kernel of the scene's module by name behind one slice-signature dispatcher
//! ([`SceneKernels::eval_into`]), which `eval` and `bench` call for any compiled scene.
//! The kernel API (docs/kernels.md) maps to the paper as: `frames` eq. 67–68, `tip_jacobian`
//! eq. 69–71, `mass_matrix` eq. 22a/74–75, `christoffel`/`coriolis_*` eq. 76–79, `gravity`
//! eq. 72–73, `contact`/`contact_smooth` eq. 2–13 and 58–59.

include!(concat!(env!("OUT_DIR"), "/modules.rs"));

/// The TOML text of the scene `name` (a scene file's `name`, not its file name), if one was
/// compiled.
pub fn scene_toml(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|s| s.0 == name).map(|s| s.1)
}

/// `mass_cqd_g` of a scene on slices: M(q) row-major (NQ × NQ, eq. 22a) into `m` and
/// C(q, q̇) q̇ + g(q) (eq. 24) into `cqd_g`. `q`, `qd` have NQ entries and `p` NP (the scene's
/// runtime parameters); other lengths write NaN.
pub type MassCqdGFn = fn(q: &[f64], qd: &[f64], p: &[f64], m: &mut [f64], cqd_g: &mut [f64]);

/// `potential` of a scene on slices: U(q) (eq. 22b); NaN if a length is wrong.
pub type PotentialFn = fn(q: &[f64], p: &[f64]) -> f64;

/// The contact kernels of a scene with a ball (any number of joints NQ): `eps = None` runs
/// `contact` (exact saturation, eq. 2–13), `Some(ε)` runs `contact_smooth` (eq. 58–59). Writes
/// the fields of the scene's `Contact` struct flat into `out`, in bf-codegen's
/// `CONTACT_FIELDS` order (J_c row-major 3 × NQ): 25 + 3 NQ values. Wrong lengths of `q`,
/// `qd`, `p` or `out` write NaN.
pub type ContactFn =
    fn(q: &[f64], qd: &[f64], omega: &[f64; 3], eps: Option<f64>, p: &[f64], out: &mut [f64]);

/// Every kernel of a scene's module on slices: runs kernel `KERNELS[k]` (see
/// [`SceneKernels::kernels`]) on q, q̇ (NQ each), ω, ε, `u` (NQ: q̈ for the inverse-dynamics
/// kernels and the regressor, τ for `forward_dynamics`, ignored by the others) and the runtime
/// parameters `p` (NP), and writes its outputs into the front of `out`, each output flattened
/// row-major in argument order (`Contact` fields in bf-codegen's `CONTACT_FIELDS` order).
/// Returns the number of values written; `None` if a length is wrong, `k` is out of range or
/// `out` is too short. Does not allocate.
pub type EvalIntoFn = fn(
    k: usize,
    q: &[f64],
    qd: &[f64],
    omega: &[f64; 3],
    eps: f64,
    u: &[f64],
    p: &[f64],
    out: &mut [f64],
) -> Option<usize>;

/// The compiled model kernels of one scene (an entry of [`SCENE_KERNELS`]).
#[derive(Debug, Clone, Copy)]
pub struct SceneKernels {
    /// Scene name (the module's `SCENE_NAME`).
    pub name: &'static str,
    /// The scene file's text it was generated from (`SCENE_TOML`).
    pub toml: &'static str,
    /// Number of joints.
    pub nq: usize,
    /// Runtime parameter names (`PARAM_NAMES`).
    pub param_names: &'static [&'static str],
    /// Their default values (`PARAM_DEFAULTS`).
    pub param_defaults: &'static [f64],
    /// `mass_cqd_g`, if the scene emits it.
    pub mass_cqd_g: Option<MassCqdGFn>,
    /// `potential`, if the scene emits it.
    pub potential: Option<PotentialFn>,
    /// `contact` / `contact_smooth`, if the scene emits both.
    pub contact: Option<ContactFn>,
    /// Names of every kernel of the scene's module, in emission order (its `kernels` list,
    /// then the inverse-dynamics family): the index [`SceneKernels::eval_into`] takes.
    pub kernels: &'static [&'static str],
    /// Every kernel of the scene's module on slices ([`EvalIntoFn`]).
    pub eval_into: EvalIntoFn,
}

impl SceneKernels {
    /// The index of kernel `name` in [`SceneKernels::kernels`], if the scene emits it.
    pub fn kernel_index(&self, name: &str) -> Option<usize> {
        self.kernels.iter().position(|k| *k == name)
    }
}

#[allow(clippy::all, clippy::pedantic)]
mod registry {
    use super::*;
    include!(concat!(env!("OUT_DIR"), "/registry.rs"));
}
pub use registry::SCENE_KERNELS;

/// The compiled model kernels of scene `name` (a scene file's `name`), if it was compiled.
pub fn scene(name: &str) -> Option<&'static SceneKernels> {
    SCENE_KERNELS.iter().find(|s| s.name == name)
}

/// One kernel function of an optimal-control node: `f(local, fixed, w, out)` writes the
/// outputs (value), the Jacobian values (pattern order) or the lower-triangle Hessian values of
/// Σ w_i y_i (pattern order) into `out`; `w` is read by the Hessian only.
pub type NodeKernelFn = fn(local: &[f64], fixed: &[f64], w: &[f64], out: &mut [f64]);

/// The emitted kernels of one optimal-control node function (paper eq. 26/29 dynamics in
/// implicit form, stick constraint eq. 14/27, validity h, λ_n, σ eq. 4/12/18, cost integrands
/// eq. 60–65, scaled for collocation), emitted by `bf_problem::kernels` at build time for the
/// scenes with a ball and a contact.
#[derive(Debug, Clone, Copy)]
pub struct NodeKernel {
    /// `<scene>_<cost>_<phase>`.
    pub name: &'static str,
    /// Structural fingerprint (`bf_codegen::nodefn::fingerprint`) of the graphs it was emitted
    /// from.
    pub fingerprint: u128,
    /// Number of outputs.
    pub n_out: usize,
    /// Number of local variables (x, a, u, T).
    pub n_local: usize,
    /// Number of fixed inputs (ε, runtime parameters, cost constants), in the node's order.
    pub n_fixed: usize,
    /// Jacobian pattern (output, local).
    pub jacobian_pattern: &'static [(u32, u32)],
    /// Lower-triangle Hessian pattern (local i ≥ local j).
    pub hessian_pattern: &'static [(u32, u32)],
    /// Output values.
    pub value: NodeKernelFn,
    /// Jacobian values.
    pub jacobian: NodeKernelFn,
    /// Weighted Hessian values.
    pub hessian: NodeKernelFn,
    /// The same three kernels on four nodes at once, if emitted.
    pub x4: Option<NodeKernelX4>,
}

/// The batched variants of a [`NodeKernel`]'s kernels: four nodes per call, `local`, `w` and
/// `out` holding the four nodes' entries interleaved (node `l`'s entry `k` at `4·k + l`),
/// `fixed` shared;
/// each node's results are bitwise those of the scalar kernel.
#[derive(Debug, Clone, Copy)]
pub struct NodeKernelX4 {
    /// Output values.
    pub value: NodeKernelFn,
    /// Jacobian values.
    pub jacobian: NodeKernelFn,
    /// Weighted Hessian values.
    pub hessian: NodeKernelFn,
}

/// The emitted optimal-control node kernels (`NODE_KERNELS`, sorted by fingerprint).
#[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens)]
pub mod ocp {
    use super::{NodeKernel, NodeKernelX4};
    include!(concat!(env!("OUT_DIR"), "/ocp_kernels.rs"));
}

/// The emitted node kernel with this fingerprint, if any.
pub fn node_kernel(fingerprint: u128) -> Option<&'static NodeKernel> {
    ocp::NODE_KERNELS
        .binary_search_by_key(&fingerprint, |k| k.fingerprint)
        .ok()
        .map(|i| &ocp::NODE_KERNELS[i])
}
