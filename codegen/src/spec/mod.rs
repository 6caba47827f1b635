//! Scene specification: the TOML file a user writes (`scenes/*.toml`).
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
//!
//! Loading: [`Scene::load`] / [`Scene::from_toml_str`] parse with toml's span-preserving
//! `DeTable`, deserialise with serde (`deny_unknown_fields`), then validate; every error is
//! `FILE:LINE:COLUMN: FIELD.PATH: message`, e.g.
//! `scenes/foo.toml:12:1: links[1].mass: must be > 0 (got -0.02)`.

use serde::Deserialize;

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
    #[serde(default, deserialize_with = "opt_exact3")]
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

/// One row of the DH table plus the link's inertial data.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Optional human-readable name.
    #[serde(default)]
    pub name: Option<String>,
    /// DH a (metres).
    pub a: f64,
    /// DH α.
    pub alpha: Angle,
    /// DH d (metres).
    #[serde(default)]
    pub d: f64,
    /// Constant joint offset added to q_i: θ_i = q_i + offset (default 0).
    #[serde(default)]
    pub offset: Option<Angle>,
    /// Link mass m_i (kg), > 0.
    pub mass: f64,
    /// COG in link-frame coordinates (metres).
    #[serde(deserialize_with = "exact3")]
    pub com: [f64; 3],
    /// Inertia about the COG in link-frame axes (kg m²), symmetric positive definite.
    pub inertia: InertiaSpec,
    /// Lower joint limit (radians), optional; used by the optimiser. In the file it may also be
    /// written like an angle (`"-160deg"`, `"-pi/2"`), converted to radians.
    #[serde(default, deserialize_with = "opt_angle_radians")]
    pub q_min: Option<f64>,
    /// Upper joint limit (radians), optional; used by the optimiser (angle strings accepted as
    /// for `q_min`).
    #[serde(default, deserialize_with = "opt_angle_radians")]
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
    #[serde(default, deserialize_with = "exact3")]
    pub center: [f64; 3],
    /// Mass (kg), > 0.
    pub mass: f64,
    /// Inertia I_b about the centre (kg m²); default (2/5) m r² · 1.
    #[serde(default)]
    pub inertia: Option<InertiaSpec>,
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
    /// `"segment"`: the last link is the segment from p_e − a_n e_x to p_e (point or line
    /// contact, eq. 3 with sat); `"tip"`: only the fingertip can touch (α not saturated,
    /// no line-contact saturation is generated).
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
    /// Base transform of the chain in world coordinates.
    #[serde(default)]
    pub base: TransformSpec,
    /// Tool transform after the last DH frame (default identity).
    #[serde(default)]
    pub tool: Option<TransformSpec>,
    /// Gravity vector g_0 (m/s²).
    #[serde(deserialize_with = "exact3")]
    pub gravity: [f64; 3],
    /// The DH table, one entry per revolute joint (at least one).
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
    "contact",
    "contact_smooth",
];

/// The kernels of [`KNOWN_KERNELS`] that need a `[ball]` and a `[contact]` section.
pub const CONTACT_KERNELS: &[&str] = &["contact", "contact_smooth"];

/// The contact kinds accepted in `[contact] kind`.
pub const CONTACT_KINDS: &[&str] = &["segment", "tip"];

// ---------------------------------------------------------------------------------------------
// Angle
// ---------------------------------------------------------------------------------------------

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Angle {
    /// `num/den · π`, reduced to lowest terms with `den > 0`; `None` if `den == 0` or the
    /// reduced fraction does not fit in `i64`.
    pub fn pi_multiple(num: i64, den: i64) -> Option<Angle> {
        Self::pi_multiple_wide(i128::from(num), i128::from(den))
    }

    fn pi_multiple_wide(num: i128, den: i128) -> Option<Angle> {
        if den == 0 {
            return None;
        }
        let g = gcd(num, den).max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = -n;
            d = -d;
        }
        if n == 0 {
            d = 1;
        }
        Some(Angle::PiMultiple {
            num: i64::try_from(n).ok()?,
            den: i64::try_from(d).ok()?,
        })
    }

    /// The angle in radians (for `PiMultiple`, `num · π / den` rounded once per operation).
    pub fn radians(&self) -> f64 {
        match *self {
            Angle::Radians(x) => x,
            Angle::PiMultiple { num, den } => {
                if num == 0 {
                    0.0
                } else {
                    num as f64 * std::f64::consts::PI / den as f64
                }
            }
        }
    }

    /// `(cos, sin)` of the angle; exact (0, ±1) for multiples of π/2, so that a rotation by
    /// "pi/2" has exact zeros. Otherwise the f64 values of `radians()`.
    pub fn cos_sin(&self) -> (f64, f64) {
        if let Angle::PiMultiple { num, den } = *self {
            // Multiples of π/2: reduce num/den·π modulo 2π to a quarter-turn index.
            if den == 1 || den == 2 {
                let quarter = (i128::from(num) * (2 / i128::from(den))).rem_euclid(4);
                return match quarter {
                    0 => (1.0, 0.0),
                    1 => (0.0, 1.0),
                    2 => (-1.0, 0.0),
                    _ => (0.0, -1.0),
                };
            }
        }
        let x = self.radians();
        (x.cos(), x.sin())
    }

    /// Parses the string form of an angle: `"pi/2"`, `"-pi/2"`, `"3*pi/4"`, `"3pi/4"`,
    /// `"0.5*pi"`, `"pi"`, `"π/2"`, `"0"`, `"90deg"`, `"-90 deg"`, `"22.5deg"`, `"90°"`. Every form
    /// is a rational multiple of π and is returned exactly as a reduced [`Angle::PiMultiple`].
    /// A plain non-zero number in a string is rejected (write radians as a TOML number).
    pub fn parse_str(text: &str) -> Result<Angle, String> {
        let bad = |why: &str| {
            format!(
                "invalid angle {text:?}: {why}; expected a TOML number (radians) or an exact \
                 string such as \"pi/2\", \"-3*pi/4\", \"90deg\""
            )
        };
        let mut s: String = text
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect::<String>()
            .to_lowercase();
        s = s.replace('π', "pi").replace('°', "deg");
        if s.is_empty() {
            return Err(bad("empty string"));
        }
        let (negative, body) = match s.as_bytes()[0] {
            b'-' => (true, &s[1..]),
            b'+' => (false, &s[1..]),
            _ => (false, &s[..]),
        };
        let sign: i128 = if negative { -1 } else { 1 };
        let deg_body = body
            .strip_suffix("degrees")
            .or_else(|| body.strip_suffix("degree"))
            .or_else(|| body.strip_suffix("deg"));
        let (num, den) = if let Some(b) = deg_body {
            let (n, d) = parse_decimal(b).map_err(|e| bad(&e))?;
            (
                sign * n,
                d.checked_mul(180).ok_or_else(|| bad("too many digits"))?,
            )
        } else if let Some(at) = body.find("pi") {
            let before = &body[..at];
            let after = &body[at + 2..];
            let before = before.strip_suffix('*').unwrap_or(before);
            let (cn, cd) = if before.is_empty() {
                (1, 1)
            } else {
                parse_decimal(before).map_err(|e| bad(&e))?
            };
            let extra_den: i128 = if after.is_empty() {
                1
            } else if let Some(d) = after.strip_prefix('/') {
                let (dn, dd) = parse_decimal(d).map_err(|e| bad(&e))?;
                if dd != 1 {
                    return Err(bad("the denominator must be an integer"));
                }
                if dn == 0 {
                    return Err(bad("division by zero"));
                }
                dn
            } else {
                return Err(bad(&format!("unexpected {after:?} after \"pi\"")));
            };
            (
                sign * cn,
                cd.checked_mul(extra_den)
                    .ok_or_else(|| bad("too many digits"))?,
            )
        } else {
            let (n, _) = parse_decimal(body).map_err(|e| bad(&e))?;
            if n != 0 {
                return Err(bad(
                    "a plain number is not an exact multiple of pi; write radians as a TOML \
                     number without quotes",
                ));
            }
            (0, 1)
        };
        Angle::pi_multiple_wide(num, den).ok_or_else(|| bad("numbers too large"))
    }
}

/// Parses an unsigned decimal `123`, `22.5`, `.5` into an exact fraction (num, den), den > 0.
fn parse_decimal(s: &str) -> Result<(i128, i128), String> {
    if s.is_empty() {
        return Err("missing number".to_string());
    }
    let (int, frac) = match s.split_once('.') {
        Some((i, f)) => (i, f),
        None => (s, ""),
    };
    if int.is_empty() && frac.is_empty() {
        return Err(format!("{s:?} is not a number"));
    }
    if !int.chars().chain(frac.chars()).all(|c| c.is_ascii_digit()) {
        return Err(format!("{s:?} is not a decimal number"));
    }
    if int.len() + frac.len() > 18 {
        return Err("too many digits".to_string());
    }
    let mut num: i128 = 0;
    for c in int.chars().chain(frac.chars()) {
        num = num * 10 + i128::from(c as u8 - b'0');
    }
    let den = 10i128.pow(frac.len() as u32);
    Ok((num, den))
}

impl std::str::FromStr for Angle {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Angle::parse_str(s)
    }
}

impl<'de> Deserialize<'de> for Angle {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Angle;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an angle: a number in radians or a string like \"pi/2\" or \"90deg\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Angle, E> {
                if v.is_finite() {
                    Ok(Angle::Radians(v))
                } else {
                    Err(E::custom(format!("must be finite (got {v})")))
                }
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Angle, E> {
                Ok(Angle::Radians(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Angle, E> {
                Ok(Angle::Radians(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Angle, E> {
                Angle::parse_str(v).map_err(E::custom)
            }
        }
        deserializer.deserialize_any(V)
    }
}

// ---------------------------------------------------------------------------------------------
// Rotation and inertia
// ---------------------------------------------------------------------------------------------

impl<'de> Deserialize<'de> for RotationSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RotationSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a rotation: { axis = \"x\"|\"y\"|\"z\", angle = ... } or a 3x3 matrix \
                     [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]]",
                )
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<RotationSpec, A::Error> {
                const FIELDS: &[&str] = &["axis", "angle"];
                let mut axis: Option<String> = None;
                let mut angle: Option<Angle> = None;
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "axis" if axis.is_none() => axis = Some(map.next_value()?),
                        "angle" if angle.is_none() => angle = Some(map.next_value()?),
                        "axis" | "angle" => {
                            return Err(serde::de::Error::custom(format!(
                                "duplicate field `{key}`"
                            )));
                        }
                        other => return Err(serde::de::Error::unknown_field(other, FIELDS)),
                    }
                }
                Ok(RotationSpec::Axis {
                    axis: axis.ok_or_else(|| serde::de::Error::missing_field("axis"))?,
                    angle: angle.ok_or_else(|| serde::de::Error::missing_field("angle"))?,
                })
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<RotationSpec, A::Error> {
                let mut m = [[0.0; 3]; 3];
                for (i, row) in m.iter_mut().enumerate() {
                    *row = seq
                        .next_element::<V3>()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &"3 rows"))?
                        .0;
                }
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &"3 rows"));
                }
                Ok(RotationSpec::Matrix(m))
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// A 3-vector that, unlike `[f64; 3]` with the toml deserializer, rejects extra elements.
struct V3([f64; 3]);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = V3;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an array of 3 numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<V3, A::Error> {
                let mut v = [0.0; 3];
                let mut n = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if n < 3 {
                        v[n] = x;
                    }
                    n += 1;
                }
                if n == 3 {
                    Ok(V3(v))
                } else {
                    Err(serde::de::Error::invalid_length(n, &self))
                }
            }
        }
        deserializer.deserialize_seq(V)
    }
}

fn exact3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    V3::deserialize(d).map(|v| v.0)
}

fn opt_exact3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    Option::<V3>::deserialize(d).map(|v| v.map(|v| v.0))
}

fn opt_angle_radians<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Option::<Angle>::deserialize(d).map(|a| a.map(|a| a.radians()))
}

/// One element of an inertia array: a number (diagonal form) or a row (full form).
enum NumOrRow {
    Num(f64),
    Row(Vec<f64>),
}

impl<'de> Deserialize<'de> for NumOrRow {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NumOrRow;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a row of 3 numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<NumOrRow, A::Error> {
                let mut row = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    row.push(x);
                }
                Ok(NumOrRow::Row(row))
            }
        }
        deserializer.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for InertiaSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = InertiaSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "an inertia: [Ixx, Iyy, Izz] or a 3x3 matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy, \
                     Iyz], [Ixz, Iyz, Izz]] (kg m^2)",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<InertiaSpec, A::Error> {
                let mut items = Vec::new();
                while let Some(x) = seq.next_element::<NumOrRow>()? {
                    items.push(x);
                }
                let shape_err = || {
                    serde::de::Error::custom(
                        "inertia must be [Ixx, Iyy, Izz] or a 3x3 matrix [[..], [..], [..]]",
                    )
                };
                if items.len() != 3 {
                    return Err(shape_err());
                }
                match (&items[0], &items[1], &items[2]) {
                    (NumOrRow::Num(a), NumOrRow::Num(b), NumOrRow::Num(c)) => {
                        Ok(InertiaSpec::Diagonal([*a, *b, *c]))
                    }
                    (NumOrRow::Row(a), NumOrRow::Row(b), NumOrRow::Row(c))
                        if a.len() == 3 && b.len() == 3 && c.len() == 3 =>
                    {
                        Ok(InertiaSpec::Full([
                            [a[0], a[1], a[2]],
                            [b[0], b[1], b[2]],
                            [c[0], c[1], c[2]],
                        ]))
                    }
                    _ => Err(shape_err()),
                }
            }
        }
        deserializer.deserialize_any(V)
    }
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

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

/// What kind of problem a [`SpecError::At`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpecErrorKind {
    /// The text is not valid TOML.
    Syntax,
    /// A key the schema does not have (`deny_unknown_fields`).
    UnknownField,
    /// A required key is absent.
    MissingField,
    /// A value of the wrong type or shape (e.g. a string where a number is expected).
    WrongType,
    /// A well-typed value that is physically or logically invalid (NaN, m ≤ 0, ...).
    Invalid,
}

/// Error from loading or validating a scene. Display format:
/// `FILE:LINE:COLUMN: FIELD.PATH: message`, e.g.
/// `scenes/foo.toml:12:1: links[1].mass: must be > 0 (got -0.02)`.
/// Lines and columns are 1-based; array indices in the field path are 0-based TOML indices
/// (`links[1]` is the second `[[links]]` table, i.e. DH link 2).
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The file could not be read.
    #[error("{file}: cannot read scene file: {source}")]
    Io {
        /// The path as given.
        file: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A located problem in the scene text.
    #[error("{file}:{line}:{column}: {path}: {message}")]
    At {
        /// Problem category.
        kind: SpecErrorKind,
        /// The origin (file name) given to the parser.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// Field path, e.g. `links[1].mass`, `base.rotation[0][2]`; `(document)` if unknown.
        path: String,
        /// What is wrong.
        message: String,
    },
}

impl SpecError {
    /// The field path (`None` for I/O errors).
    pub fn path(&self) -> Option<&str> {
        match self {
            SpecError::At { path, .. } => Some(path),
            SpecError::Io { .. } => None,
        }
    }

    /// The 1-based line (`None` for I/O errors).
    pub fn line(&self) -> Option<usize> {
        match self {
            SpecError::At { line, .. } => Some(*line),
            SpecError::Io { .. } => None,
        }
    }

    /// The problem category (`None` for I/O errors).
    pub fn kind(&self) -> Option<SpecErrorKind> {
        match self {
            SpecError::At { kind, .. } => Some(*kind),
            SpecError::Io { .. } => None,
        }
    }
}

/// Maps field paths to source positions, built from toml's span-preserving parse tree.
struct SourceIndex<'a> {
    text: &'a str,
    origin: &'a str,
    /// (path, position to report, covered span, value span) for every key and array element.
    entries: Vec<(
        String,
        usize,
        std::ops::Range<usize>,
        std::ops::Range<usize>,
    )>,
}

impl<'a> SourceIndex<'a> {
    fn new(text: &'a str, origin: &'a str, root: Option<&toml::de::DeTable<'_>>) -> Self {
        let mut idx = SourceIndex {
            text,
            origin,
            entries: Vec::new(),
        };
        if let Some(t) = root {
            idx.walk_table(t, "");
        }
        idx
    }

    fn walk_table(&mut self, t: &toml::de::DeTable<'_>, prefix: &str) {
        for (k, v) in t.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            let ks = k.span();
            let vs = v.span();
            let cover = ks.start.min(vs.start)..ks.end.max(vs.end);
            self.entries.push((path.clone(), ks.start, cover, vs));
            self.walk_value(v.get_ref(), &path);
        }
    }

    fn walk_value(&mut self, v: &toml::de::DeValue<'_>, path: &str) {
        match v {
            toml::de::DeValue::Table(t) => self.walk_table(t, path),
            toml::de::DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    let s = e.span();
                    self.entries.push((p.clone(), s.start, s.clone(), s));
                    self.walk_value(e.get_ref(), &p);
                }
            }
            _ => {}
        }
    }

    /// The innermost path whose key or value covers byte `offset`.
    fn path_at(&self, offset: usize) -> Option<&str> {
        self.entries
            .iter()
            .filter(|(_, _, s, _)| s.start <= offset && offset < s.end.max(s.start + 1))
            .min_by_key(|(p, _, s, _)| (s.end - s.start, usize::MAX - p.len()))
            .map(|(p, _, _, _)| p.as_str())
    }

    /// Byte offset to report for `path`, falling back to its parents.
    fn offset_of(&self, path: &str) -> usize {
        let mut p = path;
        loop {
            if let Some((_, pos, _, _)) = self.entries.iter().find(|(q, _, _, _)| q == p) {
                return *pos;
            }
            match p.rfind(['.', '[']) {
                Some(i) => p = &p[..i],
                None => return 0,
            }
        }
    }

    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut off = offset.min(self.text.len());
        while !self.text.is_char_boundary(off) {
            off -= 1;
        }
        let before = &self.text[..off];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    fn error(&self, kind: SpecErrorKind, offset: usize, path: &str, message: String) -> SpecError {
        let (line, column) = self.line_col(offset);
        SpecError::At {
            kind,
            file: self.origin.to_string(),
            line,
            column,
            path: if path.is_empty() {
                "(document)".to_string()
            } else {
                path.to_string()
            },
            message,
        }
    }

    /// A semantic error at `path`.
    fn invalid(&self, path: &str, message: String) -> SpecError {
        self.error(SpecErrorKind::Invalid, self.offset_of(path), path, message)
    }

    /// Best-effort path for a position in text that may not parse: the last table header before
    /// the line plus the key on the line (`[[x]]` headers are counted to give `x[i]`).
    fn textual_path(&self, offset: usize) -> Option<String> {
        let off = offset.min(self.text.len());
        let line_start = self.text[..off].rfind('\n').map_or(0, |i| i + 1);
        let line_end = self.text[off..]
            .find('\n')
            .map_or(self.text.len(), |i| off + i);
        let line = self.text[line_start..line_end].trim();
        let key = match line.split_once('=') {
            Some((k, _)) if !line.starts_with('[') && !line.starts_with('#') => {
                let k = k.trim();
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
                bare.then(|| k.to_string())
            }
            _ => None,
        };
        let mut header: Option<String> = None;
        let mut counts: Vec<(String, usize)> = Vec::new();
        for l in self.text[..line_start]
            .lines()
            .chain(line.starts_with('[').then_some(line))
        {
            let l = l.trim();
            if let Some(h) = l.strip_prefix("[[") {
                let name = h.split("]]").next().unwrap_or("").trim().to_string();
                let n = match counts.iter_mut().find(|(k, _)| *k == name) {
                    Some((_, n)) => {
                        *n += 1;
                        *n
                    }
                    None => {
                        counts.push((name.clone(), 0));
                        0
                    }
                };
                header = Some(format!("{name}[{n}]"));
            } else if let Some(h) = l.strip_prefix('[') {
                header = Some(h.split(']').next().unwrap_or("").trim().to_string());
            }
        }
        match (header, key) {
            (Some(h), Some(k)) => Some(format!("{h}.{k}")),
            (Some(h), None) => Some(h),
            (None, Some(k)) => Some(k),
            (None, None) => None,
        }
    }

    /// Converts a toml (syntax or serde) error into a located [`SpecError`].
    fn locate_toml_error(&self, e: &toml::de::Error, syntax: bool) -> SpecError {
        let msg = e.message().trim().to_string();
        let offset = e.span().map_or(0, |s| s.start);
        let mut path = if syntax {
            self.textual_path(offset)
        } else {
            None
        }
        .or_else(|| {
            e.span()
                .and_then(|s| self.path_at(s.start))
                .map(str::to_string)
        })
        .unwrap_or_default();
        let kind = if syntax {
            SpecErrorKind::Syntax
        } else if msg.starts_with("unknown field") {
            SpecErrorKind::UnknownField
        } else if msg.starts_with("missing field") {
            // The span is exactly the enclosing table's (its header or inline braces; the whole
            // document for the root table); name the missing key in the path.
            path = e
                .span()
                .and_then(|s| self.entries.iter().find(|(_, _, _, v)| *v == s))
                .map_or_else(String::new, |(p, _, _, _)| p.clone());
            if let Some(field) = msg.split('`').nth(1) {
                path = if path.is_empty() {
                    field.to_string()
                } else {
                    format!("{path}.{field}")
                };
            }
            SpecErrorKind::MissingField
        } else if msg.starts_with("invalid type")
            || msg.starts_with("invalid length")
            || msg.starts_with("invalid value")
            || msg.starts_with("unknown variant")
            || msg.starts_with("inertia must be")
        {
            SpecErrorKind::WrongType
        } else {
            SpecErrorKind::Invalid
        };
        let msg = if syntax {
            format!("TOML syntax error: {msg}")
        } else {
            msg
        };
        self.error(kind, offset, &path, msg)
    }
}

// ---------------------------------------------------------------------------------------------
// Loading and validation
// ---------------------------------------------------------------------------------------------

const RUST_KEYWORDS: &[&str] = &[
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "gen", "union", "_",
];

/// Relative tolerance for symmetry of inertia tensors and orthonormality of rotation matrices.
const MATRIX_TOL: f64 = 1e-9;

fn check_finite(ix: &SourceIndex<'_>, path: &str, v: f64) -> Result<(), SpecError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ix.invalid(path, format!("must be finite (got {v})")))
    }
}

fn check_vec(ix: &SourceIndex<'_>, path: &str, v: &[f64]) -> Result<(), SpecError> {
    for (i, x) in v.iter().enumerate() {
        check_finite(ix, &format!("{path}[{i}]"), *x)?;
    }
    Ok(())
}

fn check_positive(ix: &SourceIndex<'_>, path: &str, v: f64) -> Result<(), SpecError> {
    check_finite(ix, path, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(ix.invalid(path, format!("must be > 0 (got {v})")))
    }
}

fn check_nonnegative(ix: &SourceIndex<'_>, path: &str, v: f64) -> Result<(), SpecError> {
    check_finite(ix, path, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(ix.invalid(path, format!("must be >= 0 (got {v})")))
    }
}

fn check_angle(ix: &SourceIndex<'_>, path: &str, a: &Angle) -> Result<(), SpecError> {
    match a {
        Angle::Radians(x) => check_finite(ix, path, *x),
        Angle::PiMultiple { den, .. } if *den > 0 => Ok(()),
        Angle::PiMultiple { num, den } => Err(ix.invalid(
            path,
            format!("pi multiple {num}/{den} needs a positive denominator"),
        )),
    }
}

fn check_inertia(ix: &SourceIndex<'_>, path: &str, spec: &InertiaSpec) -> Result<(), SpecError> {
    match spec {
        InertiaSpec::Diagonal(d) => check_vec(ix, path, d)?,
        InertiaSpec::Full(m) => {
            for (i, row) in m.iter().enumerate() {
                check_vec(ix, &format!("{path}[{i}]"), row)?;
            }
        }
    }
    let m = spec.matrix();
    let scale = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..3 {
        for j in (i + 1)..3 {
            if (m[i][j] - m[j][i]).abs() > MATRIX_TOL * scale {
                return Err(ix.invalid(
                    path,
                    format!(
                        "inertia must be symmetric (I[{i}][{j}] = {} but I[{j}][{i}] = {})",
                        m[i][j], m[j][i]
                    ),
                ));
            }
        }
    }
    // Sylvester's criterion on the leading principal minors of the symmetric tensor, scaled by
    // its largest entry first so that tiny (1e-300) or huge inertias neither underflow nor
    // overflow the minors: definiteness does not depend on the unit.
    let n = scaled(&m, scale);
    let m1 = n[0][0];
    let m2 = n[0][0] * n[1][1] - n[0][1] * n[1][0];
    let m3 = det3(&n);
    if !(scale > 0.0 && m1 > 0.0 && m2 > 0.0 && m3 > 0.0) {
        return Err(ix.invalid(
            path,
            format!(
                "inertia must be positive definite (leading minors of I / {scale:e}: \
                 {m1:e}, {m2:e}, {m3:e})"
            ),
        ));
    }
    Ok(())
}

/// `m / scale`, entry by entry.
fn scaled(m: &[[f64; 3]; 3], scale: f64) -> [[f64; 3]; 3] {
    m.map(|row| row.map(|x| x / scale))
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (closed form: Smith 1961).
pub fn symmetric_eigenvalues(a: &[[f64; 3]; 3]) -> [f64; 3] {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
    if p2 == 0.0 {
        return [q; 3];
    }
    let p = (p2 / 6.0).sqrt();
    let b = std::array::from_fn(|i| {
        std::array::from_fn(|j| (a[i][j] - if i == j { q } else { 0.0 }) / p)
    });
    let r = (det3(&b) / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    [lo, 3.0 * q - hi - lo, hi]
}

/// Principal moments (ascending) of a valid inertia and whether they satisfy the triangle
/// inequality I₃ ≤ I₁ + I₂ (up to [`MATRIX_TOL`] of the trace), which every rigid body's
/// inertia about its centre of mass does (Iₖ = ∫ (r² − xₖ²) dm, so I₁ + I₂ − I₃ = 2∫ x₃² dm).
pub fn principal_moments(m: &[[f64; 3]; 3]) -> ([f64; 3], bool) {
    let scale = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    if !(scale > 0.0 && scale.is_finite()) {
        return ([0.0; 3], false);
    }
    let e = symmetric_eigenvalues(&scaled(m, scale));
    let ok = e[2] <= e[0] + e[1] + MATRIX_TOL * (e[0] + e[1] + e[2]).abs();
    (e.map(|x| x * scale), ok)
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

fn check_transform(ix: &SourceIndex<'_>, path: &str, t: &TransformSpec) -> Result<(), SpecError> {
    if let Some(tr) = &t.translation {
        check_vec(ix, &format!("{path}.translation"), tr)?;
    }
    match &t.rotation {
        None => {}
        Some(RotationSpec::Axis { axis, angle }) => {
            if !matches!(axis.as_str(), "x" | "y" | "z") {
                return Err(ix.invalid(
                    &format!("{path}.rotation.axis"),
                    format!("axis must be \"x\", \"y\" or \"z\" (got {axis:?})"),
                ));
            }
            check_angle(ix, &format!("{path}.rotation.angle"), angle)?;
        }
        Some(RotationSpec::Matrix(m)) => {
            let rp = format!("{path}.rotation");
            for (i, row) in m.iter().enumerate() {
                check_vec(ix, &format!("{rp}[{i}]"), row)?;
            }
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    if (dot - want).abs() > MATRIX_TOL {
                        return Err(ix.invalid(
                            &rp,
                            format!(
                                "rotation matrix must be orthonormal (row {i} . row {j} = {dot}, \
                                 expected {want})"
                            ),
                        ));
                    }
                }
            }
            let d = det3(m);
            if d < 0.0 {
                return Err(ix.invalid(
                    &rp,
                    format!("rotation matrix must have determinant +1 (got {d}): a reflection"),
                ));
            }
        }
    }
    Ok(())
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    match chars.next() {
        Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
        _ => return false,
    }
    chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
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
        let scene: Scene = toml::from_str(text).map_err(|e| ix.locate_toml_error(&e, false))?;
        scene.validate_with(&ix)?;
        Ok(scene)
    }

    /// Reads and validates a scene file; errors name `path` as given.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Scene, SpecError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: file.clone(),
            source,
        })?;
        Scene::from_toml_str(&text, &file)
    }

    /// Checks every semantic rule (already applied by [`Scene::from_toml_str`]); for scenes
    /// built in code. Errors carry `origin`, line 1 and the field path.
    pub fn validate(&self, origin: &str) -> Result<(), SpecError> {
        self.validate_with(&SourceIndex::new("", origin, None))
    }

    /// Accepted but physically doubtful values, one message each naming the field and values:
    /// kinetic friction above static friction (μ_k > μ_s), and link or ball inertias whose
    /// principal moments violate the triangle inequality I₃ ≤ I₁ + I₂ (no rigid body has
    /// them; published data sets do, e.g. link 3 of the PUMA 560 of Armstrong et al.).
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut inertia = |path: String, m: [[f64; 3]; 3]| {
            let (e, ok) = principal_moments(&m);
            if !ok {
                out.push(format!(
                    "{path}: principal moments {:e}, {:e}, {:e} kg m² violate the triangle \
                     inequality ({:e} > {:e} + {:e}): no rigid body has this inertia",
                    e[0], e[1], e[2], e[2], e[0], e[1]
                ));
            }
        };
        for (i, l) in self.links.iter().enumerate() {
            inertia(format!("links[{i}].inertia"), l.inertia_matrix());
        }
        if let Some(b) = &self.ball {
            inertia("ball.inertia".to_string(), b.inertia_matrix());
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

    fn validate_with(&self, ix: &SourceIndex<'_>) -> Result<(), SpecError> {
        if !is_identifier(&self.name) || RUST_KEYWORDS.contains(&self.name.as_str()) {
            return Err(ix.invalid(
                "name",
                format!(
                    "scene name {:?} must be an ASCII Rust identifier ([A-Za-z_][A-Za-z0-9_]*) \
                     and not a keyword: it becomes the generated module name",
                    self.name
                ),
            ));
        }
        check_transform(ix, "base", &self.base)?;
        if let Some(t) = &self.tool {
            check_transform(ix, "tool", t)?;
        }
        check_vec(ix, "gravity", &self.gravity)?;
        if self.links.is_empty() {
            return Err(ix.invalid(
                "links",
                "a scene needs at least one link ([[links]] table)".to_string(),
            ));
        }
        for (i, l) in self.links.iter().enumerate() {
            let p = format!("links[{i}]");
            check_finite(ix, &format!("{p}.a"), l.a)?;
            check_angle(ix, &format!("{p}.alpha"), &l.alpha)?;
            check_finite(ix, &format!("{p}.d"), l.d)?;
            if let Some(o) = &l.offset {
                check_angle(ix, &format!("{p}.offset"), o)?;
            }
            check_positive(ix, &format!("{p}.mass"), l.mass)?;
            check_vec(ix, &format!("{p}.com"), &l.com)?;
            check_inertia(ix, &format!("{p}.inertia"), &l.inertia)?;
            if let Some(v) = l.q_min {
                check_finite(ix, &format!("{p}.q_min"), v)?;
            }
            if let Some(v) = l.q_max {
                check_finite(ix, &format!("{p}.q_max"), v)?;
            }
            if let (Some(lo), Some(hi)) = (l.q_min, l.q_max)
                && lo > hi
            {
                return Err(ix.invalid(
                    &format!("{p}.q_min"),
                    format!("q_min must be <= q_max (got q_min = {lo} > q_max = {hi})"),
                ));
            }
            if let Some(v) = l.tau_max {
                check_positive(ix, &format!("{p}.tau_max"), v)?;
            }
        }
        if let Some(b) = &self.ball {
            check_positive(ix, "ball.radius", b.radius)?;
            check_vec(ix, "ball.center", &b.center)?;
            check_positive(ix, "ball.mass", b.mass)?;
            if let Some(i) = &b.inertia {
                check_inertia(ix, "ball.inertia", i)?;
            }
        }
        if let Some(f) = &self.friction {
            check_nonnegative(ix, "friction.mu_s", f.mu_s)?;
            check_nonnegative(ix, "friction.mu_k", f.mu_k)?;
            check_nonnegative(ix, "friction.mu_v", f.mu_v)?;
            check_nonnegative(ix, "friction.socket_damping", f.socket_damping)?;
        }
        if let Some(c) = &self.contact {
            if self.ball.is_none() {
                return Err(ix.invalid(
                    "contact",
                    "a [contact] section needs a [ball] section".to_string(),
                ));
            }
            if !CONTACT_KINDS.contains(&c.kind.as_str()) {
                return Err(ix.invalid(
                    "contact.kind",
                    format!(
                        "contact kind must be \"segment\" or \"tip\" (got {:?})",
                        c.kind
                    ),
                ));
            }
            check_positive(ix, "contact.smooth_eps", c.smooth_eps)?;
        }
        if self.kernels.is_empty() {
            return Err(ix.invalid(
                "kernels",
                format!(
                    "list at least one kernel; known: {}",
                    KNOWN_KERNELS.join(", ")
                ),
            ));
        }
        for (i, k) in self.kernels.iter().enumerate() {
            let p = format!("kernels[{i}]");
            if !KNOWN_KERNELS.contains(&k.as_str()) {
                return Err(ix.invalid(
                    &p,
                    format!("unknown kernel {k:?}; known: {}", KNOWN_KERNELS.join(", ")),
                ));
            }
            if self.kernels[..i].contains(k) {
                return Err(ix.invalid(&p, format!("kernel {k:?} listed twice")));
            }
            if CONTACT_KERNELS.contains(&k.as_str())
                && (self.ball.is_none() || self.contact.is_none())
            {
                return Err(ix.invalid(
                    &p,
                    format!("kernel {k:?} needs both a [ball] and a [contact] section"),
                ));
            }
        }
        for (i, c) in self.ocp_kernels.iter().flatten().enumerate() {
            let p = format!("ocp_kernels[{i}]");
            if !OCP_COSTS.contains(&c.as_str()) {
                return Err(ix.invalid(
                    &p,
                    format!("unknown cost kind {c:?}; known: {}", OCP_COSTS.join(", ")),
                ));
            }
            if self.ocp_kernels.iter().flatten().take(i).any(|x| x == c) {
                return Err(ix.invalid(&p, format!("cost kind {c:?} listed twice")));
            }
            if self.ball.is_none() || self.contact.is_none() {
                return Err(ix.invalid(
                    &p,
                    "optimal-control node kernels need both a [ball] and a [contact] section"
                        .to_string(),
                ));
            }
        }
        let names = self.constants();
        for (i, r) in self.runtime_parameters.iter().enumerate() {
            let p = format!("runtime_parameters[{i}]");
            if !names.iter().any(|(n, _)| n == r) {
                let hint = if let Some((stem, _)) = r.rsplit_once('.') {
                    let similar: Vec<&str> = names
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .filter(|n| n.starts_with(stem))
                        .collect();
                    if similar.is_empty() {
                        String::new()
                    } else {
                        format!("; did you mean one of: {}", similar.join(", "))
                    }
                } else {
                    String::new()
                };
                return Err(ix.invalid(
                    &p,
                    format!(
                        "unknown runtime parameter {r:?} (names come from Scene::constants(), \
                         e.g. \"link1.mass\", \"ball.radius\"){hint}"
                    ),
                ));
            }
            if self.runtime_parameters[..i].contains(r) {
                return Err(ix.invalid(&p, format!("runtime parameter {r:?} listed twice")));
            }
        }
        Ok(())
    }

    /// Number of joints (= DH links).
    pub fn nq(&self) -> usize {
        self.links.len()
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
    /// 3. per link `k = 1..=n`: `linkk.a`, `linkk.alpha` (rad), `linkk.d`, `linkk.offset` (rad),
    ///    `linkk.mass`, `linkk.com.x|y|z`, `linkk.inertia.xx|xy|xz|yy|yz|zz`
    /// 4. `tool.translation.x|y|z` (only with a `[tool]`)
    /// 5. `ball.radius`, `ball.center.x|y|z`, `ball.mass`, `ball.inertia.xx|xy|xz|yy|yz|zz`
    ///    (the effective tensor, default (2/5) m r²; only with a `[ball]`)
    /// 6. `friction.mu_s`, `friction.mu_k`, `friction.mu_v`, `friction.socket_damping` (only
    ///    with `[friction]`)
    ///
    /// Rotations (base, tool) are always baked and are not in the registry.
    pub fn constants(&self) -> Vec<(String, f64)> {
        const XYZ: [&str; 3] = ["x", "y", "z"];
        const SYM: [(&str, usize, usize); 6] = [
            ("xx", 0, 0),
            ("xy", 0, 1),
            ("xz", 0, 2),
            ("yy", 1, 1),
            ("yz", 1, 2),
            ("zz", 2, 2),
        ];
        let mut out = Vec::new();
        let vec3 = |out: &mut Vec<(String, f64)>, stem: &str, v: [f64; 3]| {
            for (c, x) in XYZ.iter().zip(v) {
                out.push((format!("{stem}.{c}"), x));
            }
        };
        let sym = |out: &mut Vec<(String, f64)>, stem: &str, m: [[f64; 3]; 3]| {
            for (c, i, j) in SYM {
                out.push((format!("{stem}.{c}"), m[i][j]));
            }
        };
        vec3(&mut out, "gravity", self.gravity);
        vec3(&mut out, "base.translation", self.base_translation());
        for (i, l) in self.links.iter().enumerate() {
            let s = format!("link{}", i + 1);
            out.push((format!("{s}.a"), l.a));
            out.push((format!("{s}.alpha"), l.alpha.radians()));
            out.push((format!("{s}.d"), l.d));
            out.push((format!("{s}.offset"), l.offset.map_or(0.0, |o| o.radians())));
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
