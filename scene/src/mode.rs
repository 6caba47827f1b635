//! [`Mode`]: the discrete contact mode of the hybrid ball-and-finger system (paper Sect. 2.6,
//! Fig. 2–3), named once for the physics (bf-model), the simulator's traces (bf-sim) and the
//! figures (bf-plot).

/// Discrete contact mode (Sect. 2.6, Fig. 2–3). Serialised in lowercase (`"free"`, `"stick"`,
/// `"slip"`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// No contact, λ = 0 (eq. 26, 45).
    Free,
    /// Sticking contact, Δv = 0 (eq. 29, 46).
    Stick,
    /// Slipping contact, n·v_c = 0 with kinetic friction (eq. 37, 47).
    Slip,
}
