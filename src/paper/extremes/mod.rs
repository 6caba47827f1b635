//! Numerical stability at the extremes: a fixed set of probes that push the kernels, the
//! model and the simulator to the edges of their domain and record, for each, either a number
//! with an error estimate or a clear (typed) error — never NaN, never a hang. One file per
//! probe:
//!
//! | probe | file | paper | what is measured |
//! |---|---|---|---|
//! | 1 [`kernel_accuracy`] | [`large_angles`] | eq. 22a, 24, 2–7 (App. A/B) | compiled `paper` kernels M, C q̇ + g, contact h vs the double-double evaluation of the same graph at \|q\| = 1 … 1e6 rad, and vs q reduced mod 2π |
//! | 2 [`velocity_extremes`] | [`velocities`] | eq. 24 (C q̇, Christoffel form) | C q̇ at \|q̇\| = 1e-12 … 1e3 vs double-double, and the homogeneity C(q, k q̇) k q̇ = k² C(q, q̇) q̇ |
//! | 3 [`scaled_scene`], [`length_only_mass_law`], [`human_link3_mass`] | [`scaling`] | eq. 22a, 22b, 4, 7 | masses / lengths scaled by 1e±3: f64 vs double-double, M SPD, exact similarity laws |
//! | 4 [`singular_contact`] | [`singular`] | eq. 33 (Γ = G M⁻¹ Gᵀ), eq. 7 | last two links aligned and touching along their axis: σ_min(J_c), nᵀWn, and the model's `SingularContact` |
//! | 5 [`slip_small_dv`] | [`slip`] | eq. 20, 38, Sect. 3.1 | slip accelerations as \|Δv\| → 0, slip law residual (eq. 38), Slip→Stick predicate, friction direction |
//! | 6 [`smooth_convergence`], [`smooth_corner`], [`corner_stick`] | [`smoothing`] | eq. 58–59 vs eq. 3–4 | h_ε → h and p_c,ε → p_c as ε → 0 (observed orders), NaN-freedom at α = 0 and α = −l |
//! | 7 [`painleve_threshold`] | [`painleve`] | Sect. 7, eq. 37 | the kinetic friction μ_k above which slip has no consistent normal force (bisection vs closed form) |
//! | 8 [`long_horizon`] | [`horizon`] | eq. 26, energy of eq. 22 | free motion without damping or torque for 10 s / 100 s: energy drift vs rtol, CPU time, bounded step count |
//!
//! Shared pieces: [`GraphEval`] ([`graph_eval`]: one interpreter tape over M, C q̇, g,
//! C q̇ + g and both contact variants, f64 or double-double; scenes without a compiled
//! module, such as a moved ball, run on [`bf_model::InterpretedKernels`]), the probe states and
//! [`press_torque`] ([`states`]: the finger held against C q̇ + g and pressed on with a known
//! force, so that a static stick has the exact answer λ = f n), and the rows
//! ([`report`]).
//!
//! [`run_extremes`] runs all probes in the order of the table and returns an
//! [`ExtremesReport`] whose [`ExtremesReport::to_markdown`] is the report section. A probe
//! whose result contains NaN, or that fails with an unexpected error, becomes an
//! [`Outcome::Failed`] row: such rows are listed first in the markdown and counted in
//! [`ExtremesReport::failures`].
//!
//! Error measures: "rel" is the normwise relative error max|a − b| / max|b| (b the reference,
//! [`rel_err`]). The double-double reference ([`bf_codegen::dd::Dd`], ≈ 106 bits, sin/cos with
//! a 160-bit π/2 reduction) is rounded to f64, so it carries at most half an ulp of error
//! itself. What the probes found on the paper and human fingers is recorded in BENCHMARKS.md.

use std::time::Instant;

pub mod graph_eval;
pub mod horizon;
pub mod large_angles;
pub mod numerics;
pub mod painleve;
pub mod report;
pub mod scaling;
pub mod singular;
pub mod slip;
pub mod smoothing;
pub mod states;
pub mod velocities;

pub use graph_eval::{GraphEval, GraphValues};
pub use horizon::{HORIZON_X0, HorizonRun, long_horizon};
pub use large_angles::{KernelAccuracy, kernel_accuracy};
pub use numerics::rel_err;
pub use painleve::{PainleveProbe, painleve_threshold};
pub use report::{ExtremesReport, ExtremesRow, Outcome};
pub use scaling::{
    HumanMass, ScaledScene, human_link3_mass, length_only_mass_law, scale_scene, scaled_scene,
};
pub use singular::{SingularProbe, singular_contact, singular_q2, singular_threshold};
pub use slip::{SlipProbe, slip_small_dv};
pub use smoothing::{
    Q_INTERIOR, SmoothError, corner_graph, corner_model, corner_stick, observed_orders,
    smooth_convergence, smooth_corner,
};
pub use states::{OMEGA_PROBE, Q_DIR, QD_PROBE, paper_contact_configuration, press_torque};
pub use velocities::{VelocityExtreme, velocity_extremes};

/// Run every probe. `quick`: 10 s horizon instead of 100 s (everything else is identical).
/// Each probe is bounded (fixed loop counts, `max_steps` for the simulator).
pub fn run_extremes(quick: bool) -> anyhow::Result<ExtremesReport> {
    let t_all = Instant::now();
    let mut rows = Vec::new();
    let paper = GraphEval::new(&graph_eval::paper_scene_spec()?)?;
    large_angles::report(&paper, &mut rows);
    velocities::report(&paper, &mut rows);
    scaling::report(&paper, &mut rows);
    singular::report(&mut rows);
    // the contact configuration of probes 5–7
    let qc = paper_contact_configuration()?;
    slip::report(qc, &mut rows);
    smoothing::report(qc, &mut rows);
    painleve::report(qc, &mut rows);
    horizon::report(if quick { 10.0 } else { 100.0 }, &mut rows);
    Ok(ExtremesReport {
        rows,
        quick,
        seconds: t_all.elapsed().as_secs_f64(),
    })
}
