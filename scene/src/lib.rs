//! bf-scene: the scene file a user writes (`scenes/*.toml`), its validation, and the physical
//! constants read from it. A leaf crate (serde, toml, thiserror): everything that reads a scene
//! — the generator (bf-codegen, which re-exports this crate as `bf_codegen::spec`), the
//! physics (bf-model), the optimal-control problem (bf-problem) and the CLI — depends on it
//! without linking the code generator.
//!
//! A scene is a serial revolute chain given by a Denavit–Hartenberg table (paper Table 1,
//! standard or modified convention), a base transform (paper Sect. 2.1: translation `o_f`,
//! rotation R_y(-π/2)), per-link inertia (eq. 22a: m_i, COG, I_i), gravity g_0 (eq. 22b),
//! optionally a ball (Sect. 2.1–2.2: radius r, centre o_b, mass, I_b of eq. 25) with friction
//! constants (μ_s, μ_k, μ_v, D of Sect. 2), the list of kernels to emit, and which physical
//! constants are runtime parameters instead of being baked into the code.
//!
//! These types are the contract between the spec parser and the robot front-end. Parsing and
//! validation errors name the file, line and field (see [`SpecError`]).
//!
//! Map to the paper / docs/parameters.md:
//! - [`LinkSpec`] `a`, `alpha`, `d`, `offset`: one row of Table 1 (standard DH,
//!   A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i), θ_i = q_i + offset); [`Angle`] keeps α = π/2 exact.
//! - [`LinkSpec`] `mass`, `com`, `inertia`: m_i, COG and I_i of eq. 22a (about the COG, link axes).
//! - [`Scene::gravity`]: g_0 of U = −Σ m_i g_0ᵀ p_i (eq. 22b, g = ∂U/∂q).
//! - [`Scene::base`]: o_f and R_y(−π/2) of Sect. 2.1; [`BallSpec`]: r, o_b, m_b, I_b (eq. 25).
//! - [`FrictionSpec`]: μ_s, μ_k (Coulomb), μ_v (joints), D (socket), Sect. 2 assumptions 3–4.
//! - [`ContactSpec`]: the segment/tip contact of eq. 2–7 and ε of the smooth sat (eq. 58–59).
//! - [`Scene::constants`]: the registry of every physical constant by name (`link2.mass`,
//!   `ball.radius`, ...); `runtime_parameters` picks the ones that stay variables.
//! - [`Constants`]: I_b (eq. 25), r (eq. 4), μ_s (eq. 18–19), μ_k (eq. 20), μ_v (eq. 24),
//!   D (eq. 25) and the joint and torque limits, read once for bf-model and bf-problem.
//! - Validation ([`Scene::validate`]) also refuses inertias whose principal moments violate
//!   the triangle inequality, unless the table names a published source
//!   (`nonphysical_inertia`); [`Scene::warnings`] lists what is accepted but doubtful.
//! - [`Mode`]: the contact modes free, stick and slip of Sect. 2.6; [`state_len`]: the length
//!   of the state x = (q, q̇, ω) of eq. 44.
//! - [`SceneId`]: the typed scene name the registries and the problem catalogue key scenes by.
//! - [`read_input_text`]: every input file of the program (scenes, URDFs, solutions, torque
//!   series) read with one bound, [`MAX_INPUT_BYTES`].
//!
//! Loading: [`Scene::load`] / [`Scene::from_toml_str`] parse with toml's span-preserving
//! `DeTable`, deserialise with serde (`deny_unknown_fields`), then validate; every error is
//! `FILE:LINE:COLUMN: FIELD.PATH: message`, e.g.
//! `scenes/foo.toml:12:1: links[1].mass: must be > 0 (got -0.02)`.

mod angle;
mod constants;
mod de;
mod error;
mod id;
mod input_file;
mod load;
mod mode;
mod state;
mod urdf;
mod validate;

use serde::Deserialize;

pub use constants::Constants;
pub use error::{ChainEnd, SpecError, SpecErrorKind, UnknownLink, UrdfError};
pub use id::{SceneId, UnknownScene};
pub use input_file::{MAX_INPUT_BYTES, read_input_text};
pub use load::{
    ChainChoice, URDF_GRAVITY, URDF_KERNELS, chain_toml, expand_toml, urdf_path, urdf_scene_text,
};
pub use mode::Mode;
pub use state::state_len;
pub use urdf::{UrdfChain, read_chain as read_urdf_chain, rpy_matrix};
pub use validate::{principal_moments, reserved_scene_name, symmetric_eigenvalues};

use error::SourceIndex;

/// An angle in a scene file: a number (radians) or a string such as `"pi/2"`, `"-pi/2"`,
/// `"3*pi/4"`, `"90deg"`. Rational multiples of π are kept exact (`num/den`), so the
/// generator folds cos(π/2) to exactly 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Angle {
    /// An arbitrary angle in radians.
    Radians(f64),
    /// Exactly `num/den · π` radians (`den > 0`).
    PiMultiple {
        /// Numerator of the rational multiple of π.
        num: i64,
        /// Denominator of the rational multiple of π (positive).
        den: i64,
    },
}

/// Which Denavit–Hartenberg convention the `links` table uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum DhConvention {
    /// Standard (distal) DH: A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i); joint i rotates about z_{i-1}.
    #[default]
    Standard,
    /// Modified (proximal, Craig) DH: A_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i); the row of
    /// link i holds a_{i-1} and α_{i-1}.
    Modified,
}

/// The kind of a DH joint: which DH parameter the joint coordinate q_i drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// Revolute: θ_i = q_i + offset (rad); d_i is constant.
    #[default]
    Revolute,
    /// Prismatic: d_i = q_i + d (m); θ_i = offset is constant.
    Prismatic,
}

/// A rotation in the scene file (deserialised by hand so that errors are precise: a table
/// `{ axis, angle }` or a 3×3 array).
#[derive(Debug, Clone, PartialEq)]
pub enum RotationSpec {
    /// A rotation about a principal axis: `{ axis = "y", angle = "-pi/2" }`.
    Axis {
        /// `"x"`, `"y"` or `"z"`.
        axis: String,
        /// Rotation angle.
        angle: Angle,
    },
    /// A full rotation matrix, row-major.
    Matrix([[f64; 3]; 3]),
}

/// A rigid transform (base of the chain, or a tool frame after the last link).
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Translation in metres (default: zero).
    #[serde(default, deserialize_with = "de::opt_exact3")]
    pub translation: Option<[f64; 3]>,
    /// Rotation (default: identity).
    #[serde(default)]
    pub rotation: Option<RotationSpec>,
}

/// Inertia tensor about the link COG, in link-frame axes (kg m²). Deserialised by hand: a
/// 3-array is the diagonal, a 3×3 array the full tensor.
#[derive(Debug, Clone, PartialEq)]
pub enum InertiaSpec {
    /// Diagonal `[Ixx, Iyy, Izz]`.
    Diagonal([f64; 3]),
    /// Full symmetric tensor, row-major.
    Full([[f64; 3]; 3]),
}

/// One joint and its link: a row of the DH table, or a joint placement (`origin` + `axis`, the
/// form a URDF joint has), plus the link's inertial data.
///
/// Placement form: the link frame of joint i is the previous link's frame (the base frame for
/// i = 1) moved by the fixed transform `origin`, then by the joint motion: a rotation by q_i
/// about `axis` (revolute) or a translation by q_i along it (prismatic); the axis passes
/// through the frame's origin. A scene uses one form for all its links; in placement form `a`,
/// `alpha`, `d` and `offset` are not given.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Optional human-readable name.
    #[serde(default)]
    pub name: Option<String>,
    /// Joint type, `joint = "revolute"` (default) or `"prismatic"`.
    #[serde(default)]
    pub joint: JointType,
    /// DH a (metres); required in DH form.
    #[serde(default)]
    pub a: f64,
    /// DH α; required in DH form.
    #[serde(default)]
    pub alpha: Angle,
    /// DH d (metres).
    #[serde(default)]
    pub d: f64,
    /// Constant joint offset added to q_i: θ_i = q_i + offset (default 0).
    #[serde(default)]
    pub offset: Option<Angle>,
    /// Placement form: the fixed transform from the previous link's frame to this joint's
    /// frame at q_i = 0 (default identity).
    #[serde(default)]
    pub origin: Option<TransformSpec>,
    /// Placement form: the joint axis, a unit vector in the joint's frame; giving it selects
    /// the placement form. In a scene text its norm may be within 1e-6 of 1: it is normalised
    /// when the scene is read.
    #[serde(default, deserialize_with = "de::opt_exact3")]
    pub axis: Option<[f64; 3]>,
    /// Link mass m_i (kg), > 0.
    pub mass: f64,
    /// COG in link-frame coordinates (metres).
    #[serde(deserialize_with = "de::exact3")]
    pub com: [f64; 3],
    /// Inertia about the COG in link-frame axes (kg m²), symmetric positive definite, with
    /// principal moments satisfying the triangle inequality unless `nonphysical_inertia` is set.
    pub inertia: InertiaSpec,
    /// The source of an inertia whose principal moments violate the triangle inequality
    /// (published data kept as published): with it the violation is a warning, not an error.
    /// Must be non-empty, and is refused on an inertia that satisfies the inequality.
    #[serde(default)]
    pub nonphysical_inertia: Option<String>,
    /// Lower joint limit (radians; metres for a prismatic joint), optional; used by the
    /// optimiser. For a revolute joint the file may also write it like an angle (`"-160deg"`,
    /// `"-pi/2"`), converted to radians; a prismatic joint's limit is a plain number.
    #[serde(default, deserialize_with = "de::opt_angle_radians")]
    pub q_min: Option<f64>,
    /// Upper joint limit (radians; metres for a prismatic joint), optional; used by the
    /// optimiser (angle strings accepted for revolute joints as for `q_min`).
    #[serde(default, deserialize_with = "de::opt_angle_radians")]
    pub q_max: Option<f64>,
    /// Torque limit |τ_i| (N m), optional; used by the optimiser.
    #[serde(default)]
    pub tau_max: Option<f64>,
}

/// The ball in its socket (paper Sect. 2.1, eq. 25).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallSpec {
    /// Radius r (m), > 0.
    pub radius: f64,
    /// Centre o_b (m).
    #[serde(default, deserialize_with = "de::exact3")]
    pub center: [f64; 3],
    /// Mass (kg), > 0.
    pub mass: f64,
    /// Inertia I_b about the centre (kg m²); default (2/5) m r² · 1.
    #[serde(default)]
    pub inertia: Option<InertiaSpec>,
    /// The source of a ball inertia that violates the triangle inequality, as for
    /// [`LinkSpec::nonphysical_inertia`].
    #[serde(default)]
    pub nonphysical_inertia: Option<String>,
}

/// Friction constants (paper Sect. 2, assumptions 3–4).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// Static Coulomb coefficient μ_s ≥ 0.
    pub mu_s: f64,
    /// Kinetic Coulomb coefficient μ_k ≥ 0.
    pub mu_k: f64,
    /// Joint viscous friction μ_v ≥ 0 (N m s/rad).
    #[serde(default)]
    pub mu_v: f64,
    /// Ball–socket viscous friction D ≥ 0 (N m s).
    #[serde(default)]
    pub socket_damping: f64,
}

/// Contact geometry between the ball and the last link (paper Sect. 2.2).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// `"segment"`: the last link is the segment from p_e − ℓ e_x to p_e (point or line
    /// contact, eq. 3 with sat), from where the last link leaves its joint's axis to the tip
    /// ([`Scene::contact_segment_length`]; ℓ = a_n for a standard DH table without a tool);
    /// `"tip"`: only the fingertip can touch (α not saturated, no line-contact saturation is
    /// generated).
    #[serde(default = "default_contact_kind")]
    pub kind: String,
    /// Default ε of the smooth saturation |x| ≈ sqrt(x² + ε²) (eq. 59); kernels take ε at run time.
    #[serde(default = "default_eps")]
    pub smooth_eps: f64,
}

fn default_contact_kind() -> String {
    "segment".to_string()
}
fn default_eps() -> f64 {
    0.01
}

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene name: a Rust identifier, used as the generated module name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// DH convention of `links`.
    #[serde(default)]
    pub dh: DhConvention,
    /// Base transform of the chain in world coordinates. For a robot read from a URDF: the
    /// scene file's `[base]` (the root link in the world) followed by the base link's pose in
    /// the root ([`UrdfChain::base`]), as the loaded scene text records it.
    #[serde(default)]
    pub base: TransformSpec,
    /// Tool transform after the last DH frame (default identity).
    #[serde(default)]
    pub tool: Option<TransformSpec>,
    /// Gravity vector g_0 (m/s²).
    #[serde(deserialize_with = "de::exact3")]
    pub gravity: [f64; 3],
    /// The DH table, one entry per joint (revolute or prismatic; at least one).
    pub links: Vec<LinkSpec>,
    /// The ball, if the scene has one.
    #[serde(default)]
    pub ball: Option<BallSpec>,
    /// Friction constants.
    #[serde(default)]
    pub friction: Option<FrictionSpec>,
    /// Contact geometry; requires `ball`.
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// Names of the kernels to emit (see the generator's kernel list).
    pub kernels: Vec<String>,
    /// Names of the constants that stay runtime parameters (e.g. `"link2.mass"`,
    /// `"ball.radius"`); every other constant is baked into the code.
    #[serde(default)]
    pub runtime_parameters: Vec<String>,
    /// Cost kinds whose optimal-control node kernels are emitted ([`OCP_COSTS`]; needs `[ball]`
    /// and `[contact]`). `None`: all of them when the scene has a ball and a contact; `[]`:
    /// none (the optimiser then interprets the node graphs).
    #[serde(default)]
    pub ocp_kernels: Option<Vec<String>>,
}

/// Largest |angle| (rad) of a joint or DH angle, 2²⁰: the range in which the kernels' sine
/// and cosine are defined (bf-codegen's `trig::ANGLE_RANGE`, which a test holds equal).
pub const MAX_ANGLE: f64 = 1048576.0;

/// Largest ε (m) of the smooth saturation sqrt(x² + ε²) (eq. 59): beyond it ε² leaves f64's
/// range and every smoothed quantity is NaN. (An ε far below this but coarse for the ball is
/// a matter for the verification, which compares the smoothed contact with the exact one.)
pub const MAX_SMOOTH_EPS: f64 = 1e150;

/// Smallest ε (m) of the smooth saturation: below it ε² is subnormal or 0, and at x = 0 the
/// saturation's derivative x / sqrt(x² + ε²) is then 0/0.
pub const MIN_SMOOTH_EPS: f64 = 1e-150;

/// The range of ε as the messages state it: [`MIN_SMOOTH_EPS`] to [`MAX_SMOOTH_EPS`] (a test
/// holds the text to the constants).
pub const SMOOTH_EPS_RANGE: &str =
    "a finite number in [1e-150, 1e150] m, where ε² stays a normal f64";

/// Why `eps` cannot be the smooth saturation's ε, if it cannot: it must be finite and in
/// [[`MIN_SMOOTH_EPS`], [`MAX_SMOOTH_EPS`]]. The scene's `contact.smooth_eps`, `optimize
/// --epsilon`, `eval --eps` and the ε a solution file records are checked by this one rule.
pub fn smooth_eps_out_of_range(eps: f64) -> Option<String> {
    if (MIN_SMOOTH_EPS..=MAX_SMOOTH_EPS).contains(&eps) {
        None
    } else {
        Some(format!("must be {SMOOTH_EPS_RANGE}"))
    }
}

/// Cost kinds of the optimal-control node kernels (`bf_problem::CostKind::tag`).
pub const OCP_COSTS: &[&str] = &["qc", "cot", "time_effort", "track", "reorient", "spin"];

// ---------------------------------------------------------------------------------------------
// Kernel names
// ---------------------------------------------------------------------------------------------

/// Every kernel the generator knows (see `docs/kernels.md`); a scene's `kernels` list must be a
/// subset. Order: kinematics, dynamics (eq. 22a–22c and Christoffel form), contact (Sect. 2.2).
pub const KNOWN_KERNELS: &[&str] = &[
    "frames",
    "tip_jacobian",
    "com_jacobians",
    "tip_jdot_qd",
    "mass_matrix",
    "dmass_dq",
    "christoffel",
    "coriolis_matrix",
    "coriolis_qd",
    "gravity",
    "potential",
    "cqd_g",
    "cqd_g_rnea",
    "mass_cqd_g",
    "inverse_dynamics",
    "inverse_dynamics_dq",
    "inverse_dynamics_dqd",
    "forward_dynamics",
    "regressor",
    "contact",
    "contact_smooth",
];

/// The inverse- and forward-dynamics kernels every scene gets in addition to its `kernels`
/// list (`bf-generated` emits them for every scene), in emission order.
pub const ROBOT_KERNELS: &[&str] = &[
    "inverse_dynamics",
    "inverse_dynamics_dq",
    "inverse_dynamics_dqd",
    "forward_dynamics",
    "regressor",
];

/// The kernels of [`KNOWN_KERNELS`] that need a `[ball]` and a `[contact]` section.
pub const CONTACT_KERNELS: &[&str] = &["contact", "contact_smooth"];

/// The contact kinds accepted in `[contact] kind`.
pub const CONTACT_KINDS: &[&str] = &["segment", "tip"];

/// Component names of a vector in the constant registry ([`Scene::constants`]), e.g.
/// `gravity.z`.
pub const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// Component names of a symmetric inertia tensor in the constant registry, with the
/// (row, column) each names (and its mirror), e.g. `link2.inertia.xy`.
pub const INERTIA_NAMES: [(&str, usize, usize); 6] = [
    ("xx", 0, 0),
    ("xy", 0, 1),
    ("xz", 0, 2),
    ("yy", 1, 1),
    ("yz", 1, 2),
    ("zz", 2, 2),
];

/// The index of a vector component name of [`AXIS_NAMES`] (`"y"` → 1).
pub fn axis_index(name: &str) -> Option<usize> {
    AXIS_NAMES.iter().position(|&c| c == name)
}

/// The (row, column) of an inertia component name of [`INERTIA_NAMES`] (`"xz"` → (0, 2)).
pub fn inertia_index(name: &str) -> Option<(usize, usize)> {
    INERTIA_NAMES
        .iter()
        .find(|(c, ..)| *c == name)
        .map(|&(_, i, j)| (i, j))
}

impl RotationSpec {
    /// The rotation matrix (row-major). Exact zeros/ones for axis rotations by multiples of π/2.
    /// An axis other than x/y/z (rejected by validation) yields the identity.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        match self {
            RotationSpec::Matrix(m) => *m,
            RotationSpec::Axis { axis, angle } => {
                let (c, s) = angle.cos_sin();
                match axis.as_str() {
                    "x" => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
                    "y" => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
                    "z" => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
                    _ => IDENTITY,
                }
            }
        }
    }
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl InertiaSpec {
    /// The full 3×3 tensor (row-major).
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        match self {
            InertiaSpec::Diagonal([a, b, c]) => [[*a, 0.0, 0.0], [0.0, *b, 0.0], [0.0, 0.0, *c]],
            InertiaSpec::Full(m) => *m,
        }
    }
}

impl TransformSpec {
    /// Translation (zero if absent).
    pub fn translation(&self) -> [f64; 3] {
        self.translation.unwrap_or([0.0; 3])
    }

    /// Rotation matrix (identity if absent).
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        self.rotation
            .as_ref()
            .map_or(IDENTITY, RotationSpec::matrix)
    }
}

impl LinkSpec {
    /// Whether the link is given in placement form (`axis`), not as a DH row.
    pub fn is_placement(&self) -> bool {
        self.axis.is_some()
    }

    /// Inertia tensor about the COG in link-frame axes (kg m²).
    pub fn inertia_matrix(&self) -> [[f64; 3]; 3] {
        self.inertia.matrix()
    }
}

impl BallSpec {
    /// Inertia about the centre: the given tensor, or (2/5) m r² · 1 (solid sphere, eq. 25).
    pub fn inertia_matrix(&self) -> [[f64; 3]; 3] {
        match &self.inertia {
            Some(i) => i.matrix(),
            None => {
                let j = 0.4 * self.mass * self.radius * self.radius;
                [[j, 0.0, 0.0], [0.0, j, 0.0], [0.0, 0.0, j]]
            }
        }
    }
}

impl Scene {
    /// Parses and validates a scene from TOML text. `origin` (usually the file path) is used in
    /// error messages only. Every error names the origin, the 1-based line and column, and the
    /// field path; see [`SpecError`].
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SpecError> {
        let tree = match toml::de::DeTable::parse(text) {
            Ok(t) => t,
            Err(e) => {
                let (partial, _) = toml::de::DeTable::parse_recoverable(text);
                let ix = SourceIndex::new(text, origin, Some(partial.get_ref()));
                return Err(ix.locate_toml_error(&e, true));
            }
        };
        let ix = SourceIndex::new(text, origin, Some(tree.get_ref()));
        let mut scene: Scene = toml::from_str(text).map_err(|e| ix.locate_toml_error(&e, false))?;
        scene.validate_with(&ix)?;
        scene.normalize_axes();
        Ok(scene)
    }

    /// Reads and validates a scene file (TOML, or a `.urdf` with its default chain); errors
    /// name `path` as given. [`Scene::load_with_text`] also returns the self-contained text.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Scene, SpecError> {
        Scene::load_with_text(path, &ChainChoice::default()).map(|(s, _)| s)
    }

    /// Checks every semantic rule (already applied by [`Scene::from_toml_str`]); for scenes
    /// built in code. Errors carry `origin`, line 1 and the field path. Unlike a scene read
    /// from text, whose placement axes are normalised when read, a scene built in code is
    /// used as it is, so its axes must be unit vectors to 1e-9.
    pub fn validate(&self, origin: &str) -> Result<(), SpecError> {
        self.validate_with(&SourceIndex::new("", origin, None))
    }

    /// Divides every placement `axis` by its norm (validation has checked it is within 1e-6 of
    /// 1), so that the kernels, and any text written from the links, use the unit vector.
    fn normalize_axes(&mut self) {
        for l in &mut self.links {
            if let Some(a) = &mut l.axis {
                let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
                *a = a.map(|x| x / norm);
            }
        }
    }

    /// Accepted but physically doubtful values, one message each naming the field and values:
    /// kinetic friction above static friction (μ_k > μ_s), and link or ball inertias whose
    /// principal moments violate the triangle inequality I₃ ≤ I₁ + I₂ (no rigid body has
    /// them) and that the scene keeps on purpose with a `nonphysical_inertia` source (published
    /// data sets have them, e.g. link 3 of the PUMA 560 of Armstrong et al. 1986). Without that
    /// key such an inertia is a validation error.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut inertia = |path: String, m: [[f64; 3]; 3], source: Option<&String>| {
            if let Some(msg) = validate::triangle_violation(&m) {
                let source = source.map_or(String::new(), |s| format!(" (kept as published: {s})"));
                out.push(format!("{path}: {msg}{source}"));
            }
        };
        for (i, l) in self.links.iter().enumerate() {
            // A URDF's chain has no `links[i]` of the user's: its name (the joint's) finds it.
            let named = l
                .name
                .as_ref()
                .map_or(String::new(), |n| format!(" (`{n}`)"));
            inertia(
                format!("links[{i}].inertia{named}"),
                l.inertia_matrix(),
                l.nonphysical_inertia.as_ref(),
            );
        }
        if let Some(b) = &self.ball {
            inertia(
                "ball.inertia".to_string(),
                b.inertia_matrix(),
                b.nonphysical_inertia.as_ref(),
            );
        }
        if let Some(f) = &self.friction
            && f.mu_k > f.mu_s
        {
            out.push(format!(
                "friction.mu_k = {} > friction.mu_s = {}: kinetic friction above static friction",
                f.mu_k, f.mu_s
            ));
        }
        out
    }

    /// The first revolute joint angle of `q` (index, value) beyond ±[`MAX_ANGLE`] rad, where
    /// the kernels' sine and cosine are not defined; `None` if every one is within it (a
    /// prismatic joint's q is a length, not bounded here).
    pub fn angle_beyond_range(&self, q: &[f64]) -> Option<(usize, f64)> {
        self.links
            .iter()
            .zip(q)
            .enumerate()
            .find(|(_, (l, v))| l.joint == JointType::Revolute && v.abs() > MAX_ANGLE)
            .map(|(i, (_, &v))| (i, v))
    }

    /// Number of joints (= DH links).
    pub fn nq(&self) -> usize {
        self.links.len()
    }

    /// Whether the links are in placement form (a URDF import or `origin`/`axis` links).
    pub fn is_placement(&self) -> bool {
        self.links.first().is_some_and(LinkSpec::is_placement)
    }

    /// Base rotation matrix (identity if absent); exact for axis rotations by multiples of π/2.
    pub fn base_rotation(&self) -> [[f64; 3]; 3] {
        self.base.rotation_matrix()
    }

    /// Base translation (m).
    pub fn base_translation(&self) -> [f64; 3] {
        self.base.translation()
    }

    /// Tool rotation matrix (identity if there is no tool).
    pub fn tool_rotation(&self) -> [[f64; 3]; 3] {
        self.tool
            .as_ref()
            .map_or(IDENTITY, TransformSpec::rotation_matrix)
    }

    /// Tool translation (m; zero if there is no tool).
    pub fn tool_translation(&self) -> [f64; 3] {
        self.tool
            .as_ref()
            .map_or([0.0; 3], TransformSpec::translation)
    }

    /// Whether the tip frame is the last link frame: no `[tool]`, or one that is exactly the
    /// identity transform.
    pub fn has_identity_tool(&self) -> bool {
        self.tool_rotation() == IDENTITY && self.tool_translation() == [0.0; 3]
    }

    /// The start of the contact segment (paper Sect. 2.2) in tip-frame coordinates: the point
    /// where the last link leaves its joint's axis, R_toolᵀ (p − t_tool) for its position p in
    /// the last link frame. In placement form p is that frame's origin (0, 0, 0), which the
    /// last joint's axis passes through; in standard DH p = (−a_n, 0, 0) of frame n, because
    /// the last link runs a_n along x_n from the axis z_{n−1}. `None` for modified DH (its
    /// table holds a_{n−1}, not the last link's length) and for a scene without links.
    pub fn contact_segment_start(&self) -> Option<[f64; 3]> {
        let last = self.links.last()?;
        let p = if self.is_placement() {
            [0.0; 3]
        } else if self.dh == DhConvention::Standard {
            [-last.a, 0.0, 0.0]
        } else {
            return None;
        };
        let (r, t) = (self.tool_rotation(), self.tool_translation());
        Some([0, 1, 2].map(|i| (0..3).map(|k| r[k][i] * (p[k] - t[k])).sum::<f64>()))
    }

    /// The runtime parameter that segment contact cannot leave free, if one is: its index in
    /// `runtime_parameters` and why. The kernels bake the segment's length ℓ in unless the
    /// tip frame is the last DH link frame (then ℓ = a_n stays symbolic), so a tool translation
    /// (it places the tip, one end of the segment) and, with a tool other than the identity,
    /// the last link's `a` cannot be runtime parameters.
    pub fn segment_runtime_conflict(&self) -> Option<(usize, &'static str)> {
        let a_n = format!("link{}.a", self.links.len());
        self.runtime_parameters
            .iter()
            .enumerate()
            .find_map(|(i, r)| {
                if r.starts_with("tool.translation.") {
                    Some((i, "places the tip, one end of the contact segment"))
                } else if *r == a_n && !self.has_identity_tool() {
                    Some((
                        i,
                        "sets the segment's length together with the [tool] (not the identity)",
                    ))
                } else {
                    None
                }
            })
    }

    /// The length ℓ of the contact segment p_e − ℓ e_x … p_e (paper Sect. 2.2, eq. 3): the
    /// contact kernels saturate α to [−ℓ, 0], so the segment must end where the last link
    /// leaves its joint's axis. `Ok(ℓ)` when [`Scene::contact_segment_start`] is (−ℓ, 0, 0)
    /// with ℓ > 0 (y and z zero to 1e-9 relative to ℓ, at least 1e-12 m), `Err(start)` with
    /// the offending point otherwise; `None` where there is no start (modified DH, no links).
    /// With no tool (or the identity) and a standard DH table, ℓ = a_n exactly.
    pub fn contact_segment_length(&self) -> Option<Result<f64, [f64; 3]>> {
        let start = self.contact_segment_start()?;
        let l = -start[0];
        let tol = 1e-9 * l.abs().max(1e-3);
        let on_axis = start[1].abs() <= tol && start[2].abs() <= tol;
        Some(if l > 0.0 && l.is_finite() && on_axis {
            Ok(l)
        } else {
            Err(start)
        })
    }

    /// Inertia tensor of link `i` (0-based index into `links`) about its COG, in link-frame
    /// axes (kg m²). Panics if `i >= links.len()`, like slice indexing.
    pub fn link_inertia(&self, i: usize) -> [[f64; 3]; 3] {
        self.links[i].inertia_matrix()
    }

    /// Ball inertia about its centre (default (2/5) m r² · 1); `None` without a ball.
    pub fn ball_inertia(&self) -> Option<[[f64; 3]; 3]> {
        self.ball.as_ref().map(BallSpec::inertia_matrix)
    }

    /// Whether `kernel` is in the scene's kernel list.
    pub fn wants(&self, kernel: &str) -> bool {
        self.kernels.iter().any(|k| k == kernel)
    }

    /// Registry of the scene's physical constants, each of which the generator may bake or turn
    /// into a runtime parameter. Fixed order (links numbered from 1 like the DH table):
    ///
    /// 1. `gravity.x`, `gravity.y`, `gravity.z`
    /// 2. `base.translation.x|y|z`
    /// 3. per link `k = 1..=n`: `linkk.a`, `linkk.alpha` (rad), `linkk.d`, `linkk.offset` (rad)
    ///    (DH form only), `linkk.mass`, `linkk.com.x|y|z`, `linkk.inertia.xx|xy|xz|yy|yz|zz`
    /// 4. `tool.translation.x|y|z` (only with a `[tool]`)
    /// 5. `ball.radius`, `ball.center.x|y|z`, `ball.mass`, `ball.inertia.xx|xy|xz|yy|yz|zz`
    ///    (the effective tensor, default (2/5) m r²; only with a `[ball]`)
    /// 6. `friction.mu_s`, `friction.mu_k`, `friction.mu_v`, `friction.socket_damping` (only
    ///    with `[friction]`)
    ///
    /// Rotations (base, tool) are always baked and are not in the registry.
    pub fn constants(&self) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let vec3 = |out: &mut Vec<(String, f64)>, stem: &str, v: [f64; 3]| {
            for (c, x) in AXIS_NAMES.iter().zip(v) {
                out.push((format!("{stem}.{c}"), x));
            }
        };
        let sym = |out: &mut Vec<(String, f64)>, stem: &str, m: [[f64; 3]; 3]| {
            for (c, i, j) in INERTIA_NAMES {
                out.push((format!("{stem}.{c}"), m[i][j]));
            }
        };
        vec3(&mut out, "gravity", self.gravity);
        vec3(&mut out, "base.translation", self.base_translation());
        for (i, l) in self.links.iter().enumerate() {
            let s = format!("link{}", i + 1);
            // Placement origins are baked like the base rotation: no DH names for them.
            if !l.is_placement() {
                out.push((format!("{s}.a"), l.a));
                out.push((format!("{s}.alpha"), l.alpha.radians()));
                out.push((format!("{s}.d"), l.d));
                out.push((format!("{s}.offset"), l.offset.map_or(0.0, |o| o.radians())));
            }
            out.push((format!("{s}.mass"), l.mass));
            vec3(&mut out, &format!("{s}.com"), l.com);
            sym(&mut out, &format!("{s}.inertia"), l.inertia_matrix());
        }
        if self.tool.is_some() {
            vec3(&mut out, "tool.translation", self.tool_translation());
        }
        if let Some(b) = &self.ball {
            out.push(("ball.radius".to_string(), b.radius));
            vec3(&mut out, "ball.center", b.center);
            out.push(("ball.mass".to_string(), b.mass));
            sym(&mut out, "ball.inertia", b.inertia_matrix());
        }
        if let Some(f) = &self.friction {
            out.push(("friction.mu_s".to_string(), f.mu_s));
            out.push(("friction.mu_k".to_string(), f.mu_k));
            out.push(("friction.mu_v".to_string(), f.mu_v));
            out.push(("friction.socket_damping".to_string(), f.socket_damping));
        }
        out
    }

    /// Value of one registry constant by name (see [`Scene::constants`]).
    pub fn constant(&self, name: &str) -> Option<f64> {
        self.constants()
            .into_iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }

    /// Whether the registry constant `name` is a runtime parameter in this scene.
    pub fn is_runtime(&self, name: &str) -> bool {
        self.runtime_parameters.iter().any(|r| r == name)
    }

    /// The runtime parameters with their scene values, in the order of `runtime_parameters`
    /// (this order defines the layout of `p: &[f64; NP]`). Names are validated on load;
    /// an unknown name (possible only for scenes built in code) is skipped.
    pub fn runtime_parameter_values(&self) -> Vec<(String, f64)> {
        let all = self.constants();
        self.runtime_parameters
            .iter()
            .filter_map(|r| all.iter().find(|(n, _)| n == r).cloned())
            .collect()
    }
}
