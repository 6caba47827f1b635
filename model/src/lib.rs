//! bf-model: typed ball-and-finger physics on top of the generated kernels (paper Sect. 2–3).
//!
//! # Layers
//! 1. **Evaluated kinematics** ([`ContactKinematics`]): everything the physics needs at one state
//!    x = (q, q̇, ω) — M_f, C q̇ + g, U, and the contact geometry of eq. 2–13 (h, ḣ, n, r_c, ṙ_c,
//!    J_c, J̇_c q̇, v_c, Δv). It is filled by a [`Kernels`] implementation. The product path is
//!    [`kernels`]: thin wrappers around `bf_generated::<scene>` (every contact quantity comes from
//!    generated code, so the optimiser can differentiate the same expressions). Tests may fill it
//!    from an independent reference (bf-testkit) through the same trait.
//! 2. **Physics** (pure functions of [`ContactKinematics`] + [`Params`]):
//!    - [`dynamics`]: mode dynamics (eq. 26, 29, 31–38, 44–47): [`dynamics::free`],
//!      [`dynamics::stick`], [`dynamics::slip`] return accelerations (q̈, ω̇) and the contact
//!      force λ on the finger (world axes) with its decomposition λ_n, λ_∥, σ (eq. 12, 15–18).
//!    - [`impact`]: the four impact laws of Sect. 2.5 selected by [`ImpactLaw`]
//!      (eq. 39, 40–41, 42, 43), each returning (q̇⁺, ω⁺, ι) and whether the contact sticks;
//!      plus `ImpactLaw::NormalImpulse`, the energy-consistent frictionless reading of eq. 39
//!      (the literal eq. 39 can increase kinetic energy, see [`impact`]).
//!    - [`transitions`]: mode-transition predicates of Sect. 3.1 (eq. 48–50) and the velocity
//!      updates at Slip→Stick / Stick→Slip.
//!    - [`settings`]: [`TransitionSettings`], the model-wide tolerances (contact band, Sect. 3.1
//!      equalities, singular Γ, Painlevé margin) used by dynamics, impacts and transitions.
//!    - [`energy`]: kinetic + potential energy and the power balance.
//! 3. **[`Model`]**: kernels + [`Params`] + [`TransitionSettings`] with convenience methods
//!    (`model.stick(&state, &tau)`, `model.impact(&state, law)`, ...). [`fixtures`] builds the
//!    paper and human scenes from `bf_generated`; [`registry`] gives the kernels of any scene
//!    file (any number of joints): the compiled ones of the build-time registry `bf_generated::SCENE_KERNELS` when the
//!    scene is a compiled one, bf-codegen's interpreter on the same graphs otherwise.
//! 4. **[`arm`]**: free motion of an arm with any number of joints and no ball
//!    (M q̈ = τ − C q̇ − g − μ_v q̇) on the same compiled-or-interpreted kernels.
//!
//! # Simulator recipe (Fig. 2–3)
//! ```text
//! Free:  acc = model.free(x, τ);  transition(Free, ..) == Some(Impact)  (eq. 50, locate h = 0)
//!        → out = model.impact(x, law);  x.qd, x.omega = out.qd, out.omega;  mode = out.mode
//!          (then check λ_n of that mode: λ_n < 0 → Free)
//! Stick: acc = model.stick(x, τ);  ContactToFree if λ_n < 0;  StickToSlip if σ ≤ 0
//!        → out = model.stick_to_slip_update(x, &acc.force)  (Δv⁺ = slip_kick along λ_∥)
//! Slip:  acc = model.slip(x, τ, hint);  ContactToFree if λ_n < 0;  SlipToStick if ‖Δv‖ ≤ ε
//!        and decreasing → out = model.slip_to_stick_update(x)  (projection onto Δv = 0)
//! ```
//! For event location use the continuous [`transitions::guards`] (h/r, λ_n, σ, ‖Δv‖ − ε),
//! and for drift control [`Model::project_configuration`] / [`Model::project_velocity`].
//! Contact modes let h drift within `TransitionSettings::contact_tolerance` (Sect. 3.1);
//! beyond it they return `NotInContact`. `ModelError::Painleve` in slip means the
//! complementarity problem has no / several solutions (Sect. 7): the simulator must decide.
//! The ball's inertia I_b is taken in world axes and constant (the state has no ball
//! orientation): exact for the paper's isotropic ball; for a non-isotropic I_b the equations are
//! the instantaneous world-frame Euler equations I_b ω̇ + ω × I_b ω = torque.
//!
//! # Conventions (docs/parameters.md)
//! - λ and ι are the force / impulse **exerted on the finger**, world axes. The ball receives
//!   −λ at r_c, i.e. the torque −r_c × λ (eq. 29b).
//! - G = [J_c  S(r_c)] (eq. 27), so G [q̇; ω] = J_c q̇ + r_c × ω = −Δv with Δv = ω × r_c − v_c
//!   (eq. 13): Δv is the velocity of the ball surface relative to the finger, and kinetic friction
//!   on the finger points along Δv (eq. 20).
//! - Generalised contact force G^T λ = [J_cᵀ λ; −r_c × λ] (eq. 28, 44).
//! - M_f q̈ + C q̇ + μ_v q̇ + g = τ + J_cᵀ λ;  I_b ω̇ + ω × I_b ω + D ω = −r_c × λ (eq. 29).
//! - SI units throughout. Vectors are `nalgebra` [`Vec3`] / [`Mat3`] in world space and
//!   [`VecN`] / [`MatN`] / [`Mat3xN`] in joint space.
//!
//! # Any number of joints
//! The finger may have any number of joints N: [`State`], [`ContactKinematics`], [`Kernels`],
//! [`Model`] and the physics functions take N as a const parameter with default 3 (the paper's
//! finger), so `Model<PaperKernels>` and `State` mean N = 3 and run exactly the 3-joint
//! arithmetic (see [`kernels`] for the choice of const generics).
//! [`registry::contact_kernels_n`] gives the kernels of a scene with N joints (compiled or
//! interpreted); the contact-space matrices (W, Γ) and the impact laws stay 3×3 for every N.
//!
//! # Failure modes
//! Every failure is a typed [`ModelError`], never a NaN: invalid parameters, non-finite states,
//! contact queries far from contact, singular Γ (finger unable to move along the normal at the
//! contact), and inconsistent / non-unique contact forces (Painlevé, Sect. 7).
//!
//! # Example
//! ```
//! use bf_model::{fixtures, Mode, ModelError, State, Vec3};
//! # fn main() -> Result<(), bf_model::ModelError> {
//! let model = fixtures::paper_scene()?;
//! // finger bent away from the ball (h > 0), ball spinning about z
//! let x = State::new(Vec3::new(0.0, -1.0, 0.0), Vec3::zeros(), Vec3::new(0.0, 0.0, 2.0));
//! let tau = Vec3::new(0.1, 0.0, 0.0);
//! let acc = model.accelerations(Mode::Free, &x, &tau)?;
//! let power = model.power_balance(&x, &tau, &acc.force)?; // dE/dt
//! assert!(power.total < 0.0); // at rest the finger gains no energy; the socket damps ω
//! // contact-mode queries refuse states that are not in contact
//! assert!(matches!(model.stick(&x, &tau), Err(ModelError::NotInContact { .. })));
//! # Ok(())
//! # }
//! ```

pub mod arm;
pub mod dynamics;
pub mod energy;
mod error;
pub mod fixtures;
pub mod impact;
pub mod kernels;
mod kinematics;
mod linalg;
mod params;
pub mod registry;
pub mod settings;
mod state;
pub mod transitions;

pub use dynamics::{Accelerations, ContactForce, ContactMatrices};
pub use error::{ModelError, PainleveKind, Shared};
pub use impact::{ImpactLaw, ImpactOutcome};
pub use kernels::{ContactVariant, HumanKernels, Kernels, Model, PaperKernels};
pub use kinematics::{ContactGeometry, ContactKinematics};
pub use linalg::{
    Mat3, Mat3xN, MatN, MatNx3, Vec3, VecN, normal_projector, skew, tangent_projector,
};
pub use params::Params;
pub use registry::{CompiledKernels, DynKernels, InterpretedKernels, KernelSource};
pub use settings::TransitionSettings;
pub use state::{Mode, State};
pub use transitions::{Guard, Transition};

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, ModelError>;
