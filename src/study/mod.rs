//! Studies on top of the model, the simulator and the optimiser: each runs a fixed set of
//! computations and returns rows that the reports render.
//!
//! * [`extremes`]: numerical stability at the edges of the domain (one file per probe).
//! * [`speed_accuracy`]: error versus computing time for integrators, collocation meshes, the
//!   smoothing ε and the generated-kernel variants (one file per study).

pub mod extremes;
pub mod speed_accuracy;
