//! bf-generated: the flat dynamics kernels of every scene in `scenes/*.toml`, generated at
//! build time by bf-codegen (`build.rs` → `$OUT_DIR/<scene>.rs` → `include!`).
//!
//! One module per scene, named after the scene (`paper`, `human`, `puma560`, `iiwa7`, …), and
//! the registry [`SCENES`] of every scene's name and TOML text ([`scene_toml`]).
//! The kernel API (docs/kernels.md) maps to the paper as: `frames` eq. 67–68, `tip_jacobian`
//! eq. 69–71, `mass_matrix` eq. 22a/74–75, `christoffel`/`coriolis_*` eq. 76–79, `gravity`
//! eq. 72–73, `contact`/`contact_smooth` eq. 2–13 and 58–59.

include!(concat!(env!("OUT_DIR"), "/modules.rs"));

/// The TOML text of the scene `name` (a scene file's `name`, not its file name), if one was
/// compiled.
pub fn scene_toml(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|s| s.0 == name).map(|s| s.1)
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
}

/// The emitted optimal-control node kernels (`NODE_KERNELS`, sorted by fingerprint).
#[allow(clippy::all, clippy::pedantic, unused_variables, unused_parens)]
pub mod ocp {
    use super::NodeKernel;
    include!(concat!(env!("OUT_DIR"), "/ocp_kernels.rs"));
}

/// The emitted node kernel with this fingerprint, if any.
pub fn node_kernel(fingerprint: u128) -> Option<&'static NodeKernel> {
    ocp::NODE_KERNELS
        .binary_search_by_key(&fingerprint, |k| k.fingerprint)
        .ok()
        .map(|i| &ocp::NODE_KERNELS[i])
}
