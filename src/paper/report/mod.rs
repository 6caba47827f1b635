//! Stand-alone reports of the `ball-finger report` command, also embedded in the
//! `ball-finger paper` report.
//!
//! * `speed-accuracy`: [`crate::paper::speed_accuracy::speed_accuracy`], what users trade
//!   speed for accuracy with — integrator tolerances (paper Sect. 3, Fig. 3), collocation
//!   meshes and the smoothing ε of eq. 58–59 (Sect. 4), and the variants of the generated
//!   dynamics kernels (eq. 22a, 76–79).
//! * [`impulse_cone`]: the planned impulses against the friction cone (eq. 66), and COT with
//!   and without the cone imposed, as the paper's Sect. 7 discusses it (`paper` only).
//! * [`min_stick`]: QC under a short and a longer minimum stick duration, the tap optimum and
//!   the claims of Sect. 6.1 on each (`paper` only).
//! * [`strategies_report`]: cold start vs continuation vs multi-start on the periodic
//!   problems of Sect. 6.1 (eq. 60–65), with re-integration defects.

pub mod impulse_cone;
pub mod min_stick;
pub mod strategies;

pub use strategies::strategies_report;
