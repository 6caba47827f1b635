//! [`Problem`]: the typed identifier of a catalogue problem, its CLI and `solution.json` name
//! and the list of all of them. It sits below the catalogue ([`crate::catalogue`], which adds
//! what a problem is built from) and the errors ([`crate::ProblemError`] lists the names).

use serde::{Deserialize, Serialize};

/// A problem of the catalogue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Problem {
    /// Free–stick–free periodic rotation, QC ratio (eq. 60, 64–65).
    PeriodicQc,
    /// Free–stick–free periodic rotation, COT ratio (eq. 60–63).
    PeriodicCot,
    /// `PeriodicCot` on the human scene.
    PeriodicCotHuman,
    /// Reach the ball from rest (free phase).
    Reach,
    /// Spin the ball by ∫ω_z dt = 90° (free–stick): the z-component of ω integrated, which
    /// is the ball's rotation only while ω stays along z (docs/optima.md, "The other
    /// problems").
    Reorient,
    /// Track ω_ref over a fixed horizon (free–stick).
    RotateRef,
    /// Spin the ball as fast as possible over a fixed horizon (free–stick).
    RotateFast,
}

impl Problem {
    /// Every problem, in catalogue order.
    pub const ALL: [Problem; 7] = [
        Problem::PeriodicQc,
        Problem::PeriodicCot,
        Problem::PeriodicCotHuman,
        Problem::Reach,
        Problem::Reorient,
        Problem::RotateRef,
        Problem::RotateFast,
    ];

    /// The name the CLI and `solution.json` use.
    pub fn name(self) -> &'static str {
        match self {
            Problem::PeriodicQc => "periodic-qc",
            Problem::PeriodicCot => "periodic-cot",
            Problem::PeriodicCotHuman => "periodic-cot-human",
            Problem::Reach => "reach",
            Problem::Reorient => "reorient",
            Problem::RotateRef => "rotate-ref",
            Problem::RotateFast => "rotate-fast",
        }
    }

    /// Every name, comma-separated (error messages, CLI help).
    pub fn names() -> String {
        Problem::ALL.map(Problem::name).join(", ")
    }
}
