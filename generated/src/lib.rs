//! bf-generated: the flat dynamics kernels of every scene in `scenes/*.toml`, generated at
//! build time by bf-codegen (`build.rs` → `$OUT_DIR/<scene>.rs` → `include!`).
//!
//! One module per scene, named after the scene (`paper`, `human`, `puma560`, `iiwa7`, …).
//! The kernel API (docs/kernels.md) maps to the paper as: `frames` eq. 67–68, `tip_jacobian`
//! eq. 69–71, `mass_matrix` eq. 22a/74–75, `christoffel`/`coriolis_*` eq. 76–79, `gravity`
//! eq. 72–73, `contact`/`contact_smooth` eq. 2–13 and 58–59.

include!(concat!(env!("OUT_DIR"), "/modules.rs"));
