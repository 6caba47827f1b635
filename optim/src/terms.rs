//! The small value types that name parts of a multiphase problem (paper Sect. 4–5): the
//! transcription [`Scheme`], the [`Objective`] (eq. 60) and the variable a point function reads
//! ([`VarRef`]). The problem description ([`crate::ocp::problem`], which re-exports them) and
//! the errors ([`crate::error`]) both name them, so they sit below both.

/// Transcription scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Scheme {
    /// Legendre–Gauss collocation (Benson/Garg form): N Gauss points plus the initial point,
    /// final state by Gauss quadrature. `points` = N per phase.
    Lg,
    /// Legendre–Gauss–Radau collocation with `elements` equal elements per phase (hp), each
    /// with `points / elements` (rounded up) Radau points.
    Radau {
        /// Number of elements per phase (≥ 1).
        elements: usize,
    },
}

/// A variable a [`PointFunction`](crate::ocp::PointFunction) reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarRef {
    /// State component `i` at the start of phase `phase`.
    Initial {
        /// Phase index.
        phase: usize,
        /// State component.
        i: usize,
    },
    /// State component `i` at the end of phase `phase`.
    Final {
        /// Phase index.
        phase: usize,
        /// State component.
        i: usize,
    },
    /// Duration of phase `phase`.
    Duration(usize),
    /// Static parameter `i`.
    Param(usize),
}

/// The objective φ(c(t_f)) (eq. 60).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Objective {
    /// c_j(t_f).
    Cost(usize),
    /// c_j(t_f) / c_k(t_f) (eq. 60).
    Ratio(usize, usize),
}
