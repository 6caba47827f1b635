//! Validation of a deserialised [`Scene`]: identifiers, finiteness, m_i > 0 and
//! symmetric positive inertias (eq. 22a, eq. 25), orthonormal rotations (the base rotation of
//! paper Sect. 2.1), non-negative friction constants (μ_s, μ_k, μ_v, D of Sect. 2), the contact
//! kind and ε > 0 (eq. 58–59), known kernels, costs and runtime parameters, and no body whose
//! mass or inertia is negligible next to the scene's largest (a unit-free floor, so M(q) of
//! eq. 22a stays meaningful in f64). Errors are located via `SourceIndex` (see [`SpecError`]).
//!
//! Inertias must also satisfy the triangle inequality of their principal moments (every rigid
//! body does); published data that violate it are kept only with a `nonphysical_inertia`
//! source and then reported by [`Scene::warnings`]. Also [`symmetric_eigenvalues`] and
//! [`principal_moments`] of 3×3 inertia tensors.

use super::{
    Angle, CONTACT_KERNELS, CONTACT_KINDS, DhConvention, InertiaSpec, JointType, KNOWN_KERNELS,
    OCP_COSTS, RotationSpec, Scene, SourceIndex, SpecError, SpecErrorKind, TransformSpec,
};

const RUST_KEYWORDS: &[&str] = &[
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "gen", "union", "_",
];

/// Names that `bf-generated` defines beside its scene modules, with what each is there; a scene
/// module of the same name would clash with it or overwrite its file. From
/// `generated/src/lib.rs` and `generated/build.rs`: the modules and types at the crate root,
/// the files the build script writes to `OUT_DIR` as `<name>.rs`, the variant modules of the
/// `paper` scene, and the standard crates, which a module at the crate root would shadow.
/// (The root's functions and statics live in the value namespace and do not clash with a
/// module.)
const RESERVED_NAMES: &[(&str, &str)] = &[
    ("ocp", "the module of the optimal-control node kernels"),
    (
        "registry",
        "the module of the model-kernel registry (and its file registry.rs)",
    ),
    (
        "modules",
        "the file modules.rs that declares the scene modules",
    ),
    (
        "ocp_kernels",
        "the file ocp_kernels.rs of the optimal-control node kernels",
    ),
    ("SceneKernels", "the type of a registry entry"),
    ("MassCqdGFn", "the type of a registered mass_cqd_g"),
    ("PotentialFn", "the type of a registered potential"),
    ("ContactFn", "the type of a registered contact kernel"),
    ("EvalIntoFn", "the type of a registered kernel dispatcher"),
    ("NodeKernelFn", "the type of a node kernel function"),
    ("NodeKernel", "the type of an optimal-control node kernel"),
    ("NodeKernelX4", "the type of a batched node kernel"),
    (
        "paper_f32",
        "the single-precision variant module of the `paper` scene",
    ),
    (
        "paper_fma",
        "the fused-multiply-add variant module of the `paper` scene",
    ),
    (
        "paper_runtime",
        "the all-runtime-parameter variant module of the `paper` scene",
    ),
    (
        "std",
        "the standard library, which the generated code names",
    ),
    ("core", "the core library"),
    ("alloc", "the alloc library"),
];

/// What `bf-generated` already calls `name` (see the list in this module's source), if it is
/// taken there: such a name cannot be a scene's, whose module would clash with it.
pub fn reserved_scene_name(name: &str) -> Option<&'static str> {
    RESERVED_NAMES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, what)| *what)
}

/// Relative tolerance for symmetry of inertia tensors and orthonormality of rotation matrices.
const MATRIX_TOL: f64 = 1e-9;

/// How far from 1 the norm of a placement `axis` read from a scene text may be: such an axis
/// is normalised when the scene is read, so an axis written with eight digits
/// (`[0.0, 0.70710678, 0.70710678]`) is the unit vector meant. A scene built in code is not
/// normalised and needs a unit axis to [`MATRIX_TOL`].
const AXIS_NORM_TOL: f64 = 1e-6;

/// Smallest mass (inertia trace) of a body relative to the scene's largest one. Below it the
/// body's rows of M(q) (eq. 22a) vanish next to the others' in f64 (relative 1e-16 rounding,
/// 1e-12 leaves four digits), so accelerations of its joints are rounding noise: the
/// scene describes no physical system at the working precision.
const SCALE_FLOOR: f64 = 1e-12;

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
        Angle::Radians(x) => check_finite(ix, path, *x)?,
        Angle::PiMultiple { den, .. } if *den > 0 => {}
        Angle::PiMultiple { num, den } => {
            return Err(ix.invalid(
                path,
                format!("pi multiple {num}/{den} needs a positive denominator"),
            ));
        }
    }
    // A DH angle that is a runtime parameter goes through the kernels' sine and cosine, which
    // are defined within ±MAX_ANGLE only; no scene needs one beyond it.
    let x = a.radians();
    if x.abs() > crate::MAX_ANGLE {
        return Err(ix.invalid(
            path,
            format!(
                "{x:e} rad is beyond ±2²⁰ = ±{} rad, where the kernels' sine and cosine are \
                 defined; give the angle modulo 2π",
                crate::MAX_ANGLE
            ),
        ));
    }
    Ok(())
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
    match definiteness_violation(&m) {
        Some(msg) => Err(ix.invalid(path, msg)),
        None => Ok(()),
    }
}

/// The message for a symmetric inertia tensor that is not positive definite, naming its
/// leading minors; `None` if it is.
pub(super) fn definiteness_violation(m: &[[f64; 3]; 3]) -> Option<String> {
    let scale = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    // Scaling by a zero or infinite entry would turn every minor into NaN and the message
    // into noise; these two cases have plainer words.
    if scale == 0.0 {
        return Some(
            "inertia must be positive definite (it is zero: a point mass has no rotational \
             inertia)"
                .to_string(),
        );
    }
    if !scale.is_finite() {
        return Some(format!(
            "inertia must be positive definite and finite (an entry is {scale})"
        ));
    }
    // Sylvester's criterion on the leading principal minors of the symmetric tensor, scaled by
    // its largest entry first so that tiny (1e-300) or huge inertias neither underflow nor
    // overflow the minors: definiteness does not depend on the unit.
    let n = scaled(m, scale);
    let m1 = n[0][0];
    let m2 = n[0][0] * n[1][1] - n[0][1] * n[1][0];
    let m3 = det3(&n);
    (!(m1 > 0.0 && m2 > 0.0 && m3 > 0.0)).then(|| {
        format!(
            "inertia must be positive definite (leading minors of I / {scale:e}: \
             {m1:e}, {m2:e}, {m3:e})"
        )
    })
}

/// `m / scale`, entry by entry.
fn scaled(m: &[[f64; 3]; 3], scale: f64) -> [[f64; 3]; 3] {
    m.map(|row| row.map(|x| x / scale))
}

/// The message for an inertia whose principal moments violate the triangle inequality
/// (see [`principal_moments`]), naming the moments; `None` if they satisfy it.
pub(super) fn triangle_violation(m: &[[f64; 3]; 3]) -> Option<String> {
    let (e, ok) = principal_moments(m);
    (!ok).then(|| {
        format!(
            "principal moments {:e}, {:e}, {:e} kg m² violate the triangle inequality \
             ({:e} > {:e} + {:e}): no rigid body has this inertia",
            e[0], e[1], e[2], e[2], e[0], e[1]
        )
    })
}

/// The triangle inequality of a link or ball inertia (already checked to be symmetric positive
/// definite): a violation is an error unless `source` names where the published values come
/// from; a source on a physical inertia is an error too, so the key cannot go stale.
fn check_triangle(
    ix: &SourceIndex<'_>,
    path: &str,
    table: &str,
    m: &[[f64; 3]; 3],
    source: Option<&String>,
) -> Result<(), SpecError> {
    let key = format!("{table}.nonphysical_inertia");
    match (triangle_violation(m), source) {
        (Some(msg), None) => Err(ix.invalid(
            path,
            format!(
                "{msg}; to keep published values as they are, name their source with \
                 `nonphysical_inertia = \"...\"` in the same table"
            ),
        )),
        (_, Some(s)) if s.trim().is_empty() => Err(ix.invalid(
            &key,
            "nonphysical_inertia must name the source of the published inertia (got an empty \
             string)"
                .to_string(),
        )),
        (None, Some(_)) => Err(ix.invalid(
            &key,
            "the inertia satisfies the triangle inequality of its principal moments; remove \
             nonphysical_inertia"
                .to_string(),
        )),
        _ => Ok(()),
    }
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
    let phi = libm::acos(r) / 3.0;
    let hi = q + 2.0 * p * libm::cos(phi);
    let lo = q + 2.0 * p * libm::cos(phi + 2.0 * std::f64::consts::FRAC_PI_3);
    [lo, 3.0 * q - hi - lo, hi]
}

/// Principal moments (ascending) of a valid inertia and whether they satisfy the triangle
/// inequality I₃ ≤ I₁ + I₂ (up to `MATRIX_TOL` of the trace), which every rigid body's
/// inertia about its centre of mass does (Iₖ = ∫ (r² − xₖ²) dm, so I₁ + I₂ − I₃ = 2∫ x₃² dm).
pub fn principal_moments(m: &[[f64; 3]; 3]) -> ([f64; 3], bool) {
    let scale = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    if !(scale > 0.0 && scale.is_finite()) {
        return ([0.0; 3], false);
    }
    // Compared unit-free (divided by the largest entry), so the tolerance does not depend on the
    // unit and nothing under- or overflows.
    let e = symmetric_eigenvalues(&scaled(m, scale));
    let ok = e[2] <= e[0] + e[1] + MATRIX_TOL * (e[0] + e[1] + e[2]).abs();
    let diagonal = (0..3).all(|i| (0..3).all(|j| i == j || m[i][j] == 0.0));
    let moments = if diagonal {
        // The moments exactly as written, for messages.
        let mut d = [m[0][0], m[1][1], m[2][2]];
        d.sort_by(f64::total_cmp);
        d
    } else {
        e.map(|x| x * scale)
    };
    (moments, ok)
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// A link in the scene's form: placement (`axis`, optional `origin`, no DH keys) or DH (`a`
/// and `alpha` given, no `origin`); the unit axis of a placement.
fn check_link_form(
    ix: &SourceIndex<'_>,
    p: &str,
    l: &crate::LinkSpec,
    placement: bool,
) -> Result<(), SpecError> {
    if placement && !l.is_placement() {
        return Err(ix.missing(
            &format!("{p}.axis"),
            "missing field `axis`: the first link is in placement form (axis), and one form \
             serves all links"
                .to_string(),
        ));
    }
    if !placement && l.is_placement() {
        return Err(ix.invalid(
            p,
            "link is in placement form (axis) but the first link is a DH row: one form for all \
             links"
                .to_string(),
        ));
    }
    if let Some(axis) = &l.axis {
        for key in ["a", "alpha", "d", "offset"] {
            if ix.has(&format!("{p}.{key}")) == Some(true) {
                return Err(ix.invalid(
                    &format!("{p}.{key}"),
                    format!("a link in placement form (axis) takes no DH `{key}`"),
                ));
            }
        }
        let ap = format!("{p}.axis");
        check_vec(ix, &ap, axis)?;
        let norm = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
        // A text is normalised after validation (`Scene::from_toml_str`); a scene built in
        // code is used as it is, so its axis must already be unit.
        let (tol, what) = if ix.parsed() {
            (AXIS_NORM_TOL, "; it is normalised when read")
        } else {
            (MATRIX_TOL, "; a scene built in code is not normalised")
        };
        if (norm - 1.0).abs() > tol {
            return Err(ix.invalid(
                &ap,
                format!(
                    "the joint axis must be a unit vector, its norm within {tol:e} of 1 (got \
                     {axis:?}, norm {norm}){what}"
                ),
            ));
        }
        if let Some(o) = &l.origin {
            check_transform(ix, &format!("{p}.origin"), o)?;
        }
        return Ok(());
    }
    if l.origin.is_some() {
        return Err(ix.invalid(
            &format!("{p}.origin"),
            "`origin` needs `axis` (placement form); a DH row has none".to_string(),
        ));
    }
    for key in ["a", "alpha"] {
        if ix.has(&format!("{p}.{key}")) == Some(false) {
            return Err(ix.missing(
                &format!("{p}.{key}"),
                format!("missing field `{key}` (a DH row needs a and alpha; or give `axis`)"),
            ));
        }
    }
    Ok(())
}

pub(crate) fn check_transform(
    ix: &SourceIndex<'_>,
    path: &str,
    t: &TransformSpec,
) -> Result<(), SpecError> {
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

/// Whether `s` is a Rust keyword (not usable as a scene name).
pub(super) fn is_keyword(s: &str) -> bool {
    RUST_KEYWORDS.contains(&s)
}

impl Scene {
    /// Masses and inertia traces of every body (links, then the ball) at or above
    /// [`SCALE_FLOOR`] times the scene's largest: a unit-free floor, so any consistent unit
    /// system passes and only bodies negligible next to the others are refused.
    fn check_scale_floor(&self, ix: &SourceIndex<'_>) -> Result<(), SpecError> {
        let trace = |m: [[f64; 3]; 3]| m[0][0] + m[1][1] + m[2][2];
        let mut bodies: Vec<(String, f64, f64)> = self
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| (format!("links[{i}]"), l.mass, trace(l.inertia_matrix())))
            .collect();
        if let Some(b) = &self.ball {
            bodies.push(("ball".into(), b.mass, trace(b.inertia_matrix())));
        }
        // The largest body is named too: it may be the one whose value is wrong.
        let largest = |key: fn(&(String, f64, f64)) -> f64| {
            bodies.iter().fold(
                ("", 0.0f64),
                |a, b| if key(b) > a.1 { (&b.0, key(b)) } else { a },
            )
        };
        // A trace that overflows would make every other body negligible beside it: refuse
        // the body itself (each moment is finite, their sum is not).
        if let Some((p, _, i)) = bodies.iter().find(|b| !b.2.is_finite()) {
            return Err(ix.invalid(
                &format!("{p}.inertia"),
                format!(
                    "inertia trace {i:e} kg m²: the principal moments overflow f64 when \
                     summed, as M(q) sums them"
                ),
            ));
        }
        let (m_name, m_max) = largest(|b| b.1);
        let (i_name, i_max) = largest(|b| b.2);
        for (p, m, i) in &bodies {
            if *m < SCALE_FLOOR * m_max {
                return Err(ix.invalid(
                    &format!("{p}.mass"),
                    format!(
                        "mass {m:e} kg is below {SCALE_FLOOR:e} × the scene's largest mass \
                         ({m_name}: {m_max:e} kg): negligible at f64 precision, the body's \
                         joint accelerations would be rounding noise"
                    ),
                ));
            }
            if *i < SCALE_FLOOR * i_max {
                return Err(ix.invalid(
                    &format!("{p}.inertia"),
                    format!(
                        "inertia trace {i:e} kg m² is below {SCALE_FLOOR:e} × the scene's \
                         largest ({i_name}: {i_max:e} kg m²): negligible at f64 precision, the \
                         body's joint accelerations would be rounding noise"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The last link carries the contact (Sect. 2.2): the finger turns it about a revolute
    /// joint, and in standard DH form its length a_N > 0 is the contact segment's (a point
    /// finger of length 0 has no segment, and the simulator measures ℓ > 0 from the contact
    /// kernel). Refused here so that every command says so, not only the simulator.
    fn check_contact_link(&self, ix: &SourceIndex<'_>) -> Result<(), SpecError> {
        let last = self.links.len().saturating_sub(1);
        let Some(l) = self.links.last() else {
            return Ok(());
        };
        if l.joint == JointType::Prismatic {
            return Err(ix.invalid(
                &format!("links[{last}].joint"),
                "a finger touching a ball ([contact]) needs a revolute last joint: the contact \
                 link turns about it (paper Sect. 2.2)"
                    .to_string(),
            ));
        }
        if !self.is_placement() && self.dh == DhConvention::Standard && (l.a.is_nan() || l.a <= 0.0)
        {
            return Err(ix.invalid(
                &format!("links[{last}].a"),
                format!(
                    "a finger touching a ball ([contact]) needs a last link of length a > 0 \
                     (got {}): the contact link runs from p_e - a e_x to the tip p_e (paper \
                     Sect. 2.2)",
                    l.a
                ),
            ));
        }
        if self.contact.as_ref().is_some_and(|c| c.kind == "segment") {
            self.check_contact_segment(ix)?;
        }
        Ok(())
    }

    /// Segment contact (eq. 3: α saturated to [−ℓ, 0]) needs a segment from where the last
    /// link leaves its joint's axis to the tip along the tip frame's x axis
    /// ([`Scene::contact_segment_length`]), and an ℓ that the kernels' runtime parameters
    /// cannot move, because the generator bakes it in unless it is the DH `a_n` itself.
    fn check_contact_segment(&self, ix: &SourceIndex<'_>) -> Result<(), SpecError> {
        let placement = self.is_placement();
        if !placement && self.dh == DhConvention::Modified {
            return Err(ix.invalid(
                "contact.kind",
                "contact kind \"segment\" needs the length of the last link, which a modified \
                 DH table does not hold (its last row gives a and alpha of the link before); \
                 use kind = \"tip\", or give the links in placement form (`axis`, `origin`) \
                 with a [tool] at the tip"
                    .to_string(),
            ));
        }
        if let Some(Err(start)) = self.contact_segment_length() {
            let (key, turn) = if placement {
                ("contact.kind", "the tip link's frame (the [tool])")
            } else {
                ("tool", "the [tool]")
            };
            return Err(ix.invalid(
                key,
                format!(
                    "contact kind \"segment\" runs from where the last link leaves its joint's \
                     axis to the tip, along the tip frame's x axis, so that point must be \
                     (-l, 0, 0) with l > 0 in tip-frame coordinates; it is {start:?}: turn or \
                     move {turn} so that its x axis points along the last link, away from the \
                     joint, or use kind = \"tip\""
                ),
            ));
        }
        if let Some((i, why)) = self.segment_runtime_conflict() {
            let r = &self.runtime_parameters[i];
            let l = self.contact_segment_length().and_then(Result::ok);
            return Err(ix.invalid(
                &format!("runtime_parameters[{i}]"),
                format!(
                    "{r:?} cannot be a runtime parameter with contact kind \"segment\": it \
                     {why}, and the generated kernels bake the segment's length in \
                     (l = {} m at the scene's values); keep it baked, or use kind = \"tip\"",
                    l.unwrap_or(f64::NAN)
                ),
            ));
        }
        Ok(())
    }

    pub(super) fn validate_with(&self, ix: &SourceIndex<'_>) -> Result<(), SpecError> {
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
        if let Some(what) = reserved_scene_name(&self.name) {
            return Err(ix.invalid(
                "name",
                format!(
                    "scene name {:?} clashes with the generated crate (bf-generated), where it \
                     is {what}; the scene's module would take the same name: choose another",
                    self.name
                ),
            ));
        }
        if self.is_placement() && ix.has("dh") == Some(true) {
            return Err(ix.invalid(
                "dh",
                "`dh` is the convention of a DH table, but this scene's links are in placement \
                 form (`axis`/`origin`, or read from a `urdf`), which has none: remove `dh`"
                    .to_string(),
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
        let placement = self.is_placement();
        for (i, l) in self.links.iter().enumerate() {
            let p = format!("links[{i}]");
            check_link_form(ix, &p, l, placement)?;
            check_finite(ix, &format!("{p}.a"), l.a)?;
            check_angle(ix, &format!("{p}.alpha"), &l.alpha)?;
            check_finite(ix, &format!("{p}.d"), l.d)?;
            if let Some(o) = &l.offset {
                check_angle(ix, &format!("{p}.offset"), o)?;
            }
            check_positive(ix, &format!("{p}.mass"), l.mass)?;
            check_vec(ix, &format!("{p}.com"), &l.com)?;
            check_inertia(ix, &format!("{p}.inertia"), &l.inertia)?;
            check_triangle(
                ix,
                &format!("{p}.inertia"),
                &p,
                &l.inertia_matrix(),
                l.nonphysical_inertia.as_ref(),
            )?;
            if l.joint == JointType::Prismatic {
                for key in ["q_min", "q_max"] {
                    let kp = format!("{p}.{key}");
                    if ix.is_string(&kp) == Some(true) {
                        return Err(ix.at(
                            SpecErrorKind::WrongType,
                            &kp,
                            format!(
                                "a prismatic joint's {key} is a length in metres: give a plain \
                                 number (an angle such as \"-90deg\" or \"pi/2\" is for \
                                 revolute joints)"
                            ),
                        ));
                    }
                }
            }
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
            } else {
                let j = b.inertia_matrix()[0][0];
                if !(j.is_finite() && j > 0.0) {
                    return Err(ix.invalid(
                        "ball.radius",
                        format!(
                            "the ball's inertia (2/5) m r² = {j:e} kg m² (mass {:e} kg, \
                             radius {:e} m) is not a finite number > 0 in f64",
                            b.mass, b.radius
                        ),
                    ));
                }
            }
            check_triangle(
                ix,
                "ball.inertia",
                "ball",
                &b.inertia_matrix(),
                b.nonphysical_inertia.as_ref(),
            )?;
        }
        self.check_scale_floor(ix)?;
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
            check_finite(ix, "contact.smooth_eps", c.smooth_eps)?;
            if let Some(why) = crate::smooth_eps_out_of_range(c.smooth_eps) {
                return Err(ix.invalid(
                    "contact.smooth_eps",
                    format!("{why} (got {})", c.smooth_eps),
                ));
            }
            self.check_contact_link(ix)?;
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
}
