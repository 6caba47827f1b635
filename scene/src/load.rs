//! Loading a scene from a file: a TOML scene (whose robot may come from a URDF named by its
//! `urdf` key) or a URDF file directly. Either way the result is a self-contained scene text
//! — the URDF chain written out as `[[links]]` in placement form, a `[tool]`, and a `[base]`
//! where the base link is not the root's frame — so what a command records (solution files,
//! the generated module's scene text) parses again without the URDF, to the same kinematics.

use crate::error::{ChainEnd, UnknownLink};
use crate::urdf::{UrdfChain, read_chain};
use crate::{Scene, SpecError, SpecErrorKind, TransformSpec};
use std::fmt::Write as _;
use std::path::Path;

/// Gravity of a scene made from a URDF when it does not give one (m/s², world z up).
pub const URDF_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// The kernels of a scene made from a URDF file alone (no TOML around it).
pub const URDF_KERNELS: &[&str] = &[
    "frames",
    "tip_jacobian",
    "mass_matrix",
    "gravity",
    "cqd_g",
    "mass_cqd_g",
    "potential",
];

/// Which serial chain of a URDF tree to take (`--base LINK --tip LINK`): `None` takes the
/// root, respectively the only leaf of a tree that does not branch.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChainChoice {
    /// The base link.
    pub base: Option<String>,
    /// The tip link.
    pub tip: Option<String>,
}

/// Whether the file at `path` with the text `raw` is a URDF: its extension says so, or its
/// text starts with `<` (XML; no TOML document does), so that a URDF saved as `.xml` is read
/// as one instead of failing as TOML.
fn is_urdf(path: &Path, raw: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
        || raw
            .trim_start_matches('\u{feff}')
            .trim_start()
            .starts_with('<')
}

fn read(path: &Path) -> Result<String, SpecError> {
    crate::read_input_text(path).map_err(|cause| SpecError::Io {
        file: path.display().to_string(),
        cause,
    })
}

/// `x` as a TOML float that parses back to the same f64 (Rust's shortest round-trip form).
fn num(x: f64) -> String {
    let s = format!("{x:?}");
    if s.contains(['.', 'e', 'n', 'i']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// `s` as a TOML string that reads back as `s`, written by the TOML crate the scene is read
/// with. Rust's `{:?}` is no such form: it writes combining marks and some spaces (U+0301,
/// U+00A0) as `\u{301}`, which TOML refuses, so a URDF joint named `coude` + U+0301 would read
/// as a TOML syntax error.
fn toml_string(s: &str) -> String {
    toml::Value::from(s).to_string()
}

fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

fn mat3(m: [[f64; 3]; 3]) -> String {
    format!("[{}, {}, {}]", vec3(m[0]), vec3(m[1]), vec3(m[2]))
}

fn transform(out: &mut String, t: &TransformSpec) {
    let _ = writeln!(out, "translation = {}", vec3(t.translation()));
    let _ = writeln!(out, "rotation = {}", mat3(t.rotation_matrix()));
}

/// The `[base]` (only when the base link is not at the root's frame, [`UrdfChain::base`]),
/// `[tool]` and `[[links]]` tables of a URDF chain, in placement form.
pub fn chain_toml(chain: &UrdfChain) -> String {
    chain_tables(
        chain,
        chain.base.as_ref().map(|b| (b, placement_note(chain))),
    )
}

/// The comment of a `[base]` that is the base link's placement alone.
fn placement_note(chain: &UrdfChain) -> String {
    format!(
        "# Link {:?} where the joints from the root link {:?} put it (moving joints at q = 0).",
        chain.base_link, chain.root_link
    )
}

/// [`chain_toml`] with `base` (a transform and the comment that says what it is) as the
/// `[base]` table.
fn chain_tables(chain: &UrdfChain, base: Option<(&TransformSpec, String)>) -> String {
    let mut out = String::new();
    if let Some((t, note)) = base {
        let _ = writeln!(out, "\n[base]\n{note}");
        transform(&mut out, t);
    }
    if let Some(t) = &chain.tool {
        let _ = writeln!(out, "\n[tool]");
        transform(&mut out, t);
    }
    for l in &chain.links {
        let _ = writeln!(out, "\n[[links]]");
        if let Some(n) = &l.name {
            let _ = writeln!(out, "name = {}", toml_string(n));
        }
        if l.joint == crate::JointType::Prismatic {
            let _ = writeln!(out, "joint = \"prismatic\"");
        }
        if let Some(o) = &l.origin {
            let _ = writeln!(
                out,
                "origin = {{ translation = {}, rotation = {} }}",
                vec3(o.translation()),
                mat3(o.rotation_matrix())
            );
        }
        if let Some(a) = l.axis {
            let _ = writeln!(out, "axis = {}", vec3(a));
        }
        let _ = writeln!(out, "mass = {}", num(l.mass));
        let _ = writeln!(out, "com = {}", vec3(l.com));
        let _ = writeln!(out, "inertia = {}", mat3(l.inertia_matrix()));
        if let Some(src) = &l.nonphysical_inertia {
            let _ = writeln!(out, "nonphysical_inertia = {}", toml_string(src));
        }
        for (key, v) in [
            ("q_min", l.q_min),
            ("q_max", l.q_max),
            ("tau_max", l.tau_max),
        ] {
            if let Some(v) = v {
                let _ = writeln!(out, "{key} = {}", num(v));
            }
        }
    }
    out
}

/// The file name of `path` without its directory, for the provenance comment of a scene text:
/// the text (and the code generated from it) must not depend on the directory the command
/// was started from or on how the path was spelt.
fn provenance(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// A Rust identifier from a URDF robot name (`ur5-arm` → `ur5_arm`), with `_robot` appended to
/// a keyword or a name the generated crate takes itself.
fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert_str(0, "robot_");
    }
    if crate::validate::is_keyword(&s) || crate::validate::reserved_scene_name(&s).is_some() {
        s.push_str("_robot");
    }
    s
}

/// A chain written into a scene text: errors that the scene's validation finds on its lines
/// (from `first_line` on) are about the URDF, so [`Imported::relocate`] names the URDF link.
struct Imported {
    chain: UrdfChain,
    /// The URDF file as named in errors.
    file: String,
    /// The first line of the scene text that the chain was written into.
    first_line: usize,
}

impl Imported {
    /// `e` located at the URDF element it is about, if the scene's validation found it on the
    /// chain's generated lines: `links[i]…` at model link i's `<link>`, anything else at the
    /// robot. Errors on the user's own lines are returned as they are.
    fn relocate(&self, e: SpecError) -> SpecError {
        let SpecError::At {
            line,
            path,
            message,
            ..
        } = &e
        else {
            return e;
        };
        if *line < self.first_line {
            return e;
        }
        let link = path
            .strip_prefix("links[")
            .and_then(|r| r.split_once(']'))
            .and_then(|(i, rest)| Some((i.parse::<usize>().ok()?, rest)));
        let (line, column, element, attribute, message) = match link {
            Some((i, rest)) if i < self.chain.link_positions.len() => {
                let (line, column) = self.chain.link_positions[i];
                (
                    line,
                    column,
                    "link",
                    rest.trim_start_matches('.').to_string(),
                    format!(
                        "link moved by joint {:?} ({path} of the imported chain): {message}",
                        self.chain.joint_names[i]
                    ),
                )
            }
            _ if path.starts_with("base") => (
                1,
                1,
                "robot",
                path.clone(),
                format!(
                    "the placement of base link {:?} ({path} of the imported chain, with the \
                     scene's [base] if it has one): {message}",
                    self.chain.base_link
                ),
            ),
            _ => (1, 1, "robot", path.clone(), message.clone()),
        };
        SpecError::Urdf(Box::new(crate::error::UrdfError {
            file: self.file.clone(),
            line,
            column,
            element: element.to_string(),
            attribute,
            message,
        }))
    }
}

/// The scene text of a URDF file alone: its chain (with the base link's pose in the root as
/// `[base]`, the root being the world), gravity [`URDF_GRAVITY`], the kernels
/// [`URDF_KERNELS`], no ball.
pub fn urdf_scene_text(urdf: &str, file: &str, choice: &ChainChoice) -> Result<String, SpecError> {
    urdf_scene(urdf, file, choice).map(|(text, _)| text)
}

/// The command-line error (exit status 2) of the ends of `u` that `choice` gave by flag
/// (`--base`/`--tip`), located at the first one's flag and naming every one; `None` when no
/// unknown end came from the command line (a scene's key named it).
fn flag_error(u: &UnknownLink, choice: &ChainChoice) -> Option<SpecError> {
    let given = |end: ChainEnd| match end {
        ChainEnd::Base => choice.base.is_some(),
        ChainEnd::Tip => choice.tip.is_some(),
    };
    let mut flagged = u.unknown.iter().filter(|(end, _)| given(*end));
    let (first, name) = flagged.next()?;
    let mut message = format!("{name:?} is not a link of the robot");
    for (end, name) in flagged {
        let _ = write!(message, ", nor is {} {name:?}", end.flag());
    }
    let _ = write!(message, " (links: {:?})", u.links);
    Some(SpecError::At {
        kind: SpecErrorKind::ChainChoice,
        file: u.file.clone(),
        line: 1,
        column: 1,
        path: first.flag().to_string(),
        message,
    })
}

fn urdf_scene(
    urdf: &str,
    file: &str,
    choice: &ChainChoice,
) -> Result<(String, Imported), SpecError> {
    let chain = read_chain(
        urdf,
        file,
        choice.base.as_deref(),
        choice.tip.as_deref(),
        None,
    )
    .map_err(|e| match e {
        SpecError::UnknownLink(u) => flag_error(&u, choice).unwrap_or(SpecError::UnknownLink(u)),
        e => e,
    })?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Made from the URDF file {:?}: robot {:?}, chain {:?} -> {:?}, joints {:?}.",
        provenance(Path::new(file)),
        chain.robot,
        chain.base_link,
        chain.tip_link,
        chain.joint_names
    );
    let _ = writeln!(out, "name = {}", toml_string(&identifier(&chain.robot)));
    let _ = writeln!(out, "gravity = {}", vec3(URDF_GRAVITY));
    let kernels: Vec<String> = URDF_KERNELS.iter().map(|k| format!("{k:?}")).collect();
    let _ = writeln!(out, "kernels = [{}]", kernels.join(", "));
    out.push_str(&chain_toml(&chain));
    let imported = Imported {
        chain,
        file: file.to_string(),
        first_line: 1,
    };
    Ok((out, imported))
}

/// A TOML scene text with its `urdf`, `base_link` and `tip_link` keys resolved: the keys become
/// comments (lines keep their numbers, so errors in the user's part point at the user's
/// lines), gravity defaults to [`URDF_GRAVITY`], and the chain is appended. The scene's
/// `[base]` places the URDF's root link in the world; when the base link is not at the root's
/// frame ([`UrdfChain::base`]), the chain's base transform is that `[base]` followed by the
/// base link's pose in the root, written as one `[base]` table after the user's (checked
/// first, at its own lines, then turned into comments). `dir` is the scene file's directory
/// (the URDF path is relative to it); `choice` (command-line `--base`/`--tip`) overrides the
/// scene's links. A text without `urdf` is returned unchanged, and then `choice` must be
/// empty.
pub fn expand_toml(
    text: &str,
    origin: &str,
    dir: &Path,
    choice: &ChainChoice,
) -> Result<String, SpecError> {
    expand(text, origin, dir, choice).map(|(text, _)| text)
}

/// [`expand_toml`], with the chain it wrote in (`None` for a text without `urdf`).
fn expand(
    text: &str,
    origin: &str,
    dir: &Path,
    choice: &ChainChoice,
) -> Result<(String, Option<Imported>), SpecError> {
    let Ok(tree) = toml::de::DeTable::parse(text) else {
        // Syntax errors are reported, located, by the scene parser.
        return Ok((text.to_string(), None));
    };
    let ix = crate::error::SourceIndex::new(text, origin, Some(tree.get_ref()));
    let table = tree.get_ref();
    let mut keys: Vec<(&str, String, std::ops::Range<usize>)> = Vec::new();
    for (k, v) in table.iter() {
        let name = k.get_ref().as_ref();
        if !matches!(
            name,
            "urdf" | "base_link" | "tip_link" | "nonphysical_inertia"
        ) {
            continue;
        }
        let toml::de::DeValue::String(s) = v.get_ref() else {
            return Err(ix.at(
                SpecErrorKind::WrongType,
                name,
                format!("`{name}` must be a string"),
            ));
        };
        keys.push((
            match name {
                "urdf" => "urdf",
                "base_link" => "base_link",
                "tip_link" => "tip_link",
                _ => "nonphysical_inertia",
            },
            s.to_string(),
            k.span().start..v.span().end,
        ));
    }
    let get = |n: &str| keys.iter().find(|k| k.0 == n).map(|k| k.1.clone());
    let Some(urdf) = get("urdf") else {
        if let Some((n, ..)) = keys.first() {
            let what = if *n == "nonphysical_inertia" {
                "whose inertias it keeps; a scene's own link takes the key in its \
                 [[links]] table"
            } else {
                "the URDF file it names a link of"
            };
            return Err(ix.invalid(n, format!("`{n}` at the top level needs `urdf` ({what})")));
        }
        if choice.base.is_some() || choice.tip.is_some() {
            return Err(SpecError::At {
                kind: SpecErrorKind::ChainChoice,
                file: origin.to_string(),
                line: 1,
                column: 1,
                path: "urdf".to_string(),
                message: "--base/--tip choose the chain of a URDF; this scene is not a URDF \
                          and names none (no `urdf` key)"
                    .to_string(),
            });
        }
        return Ok((text.to_string(), None));
    };
    for (key, what) in [("links", "its links"), ("tool", "its tool (the tip link)")] {
        if table.iter().any(|(k, _)| k.get_ref().as_ref() == key) {
            return Err(ix.invalid(
                key,
                format!("a scene with `urdf` takes {what} from the URDF; remove `{key}`"),
            ));
        }
    }
    let chain_choice = ChainChoice {
        base: choice.base.clone().or(get("base_link")),
        tip: choice.tip.clone().or(get("tip_link")),
    };
    let path = dir.join(&urdf);
    let file = path.display().to_string();
    let urdf_text = crate::read_input_text(&path).map_err(|e| {
        ix.invalid(
            "urdf",
            format!("cannot read the URDF file {file} (relative to the scene file): {e}"),
        )
    })?;
    // A link named wrongly is the mistake of whoever named it: the command line's flag,
    // which overrides the scene's key, or else the key.
    let chain = read_chain(
        &urdf_text,
        &file,
        chain_choice.base.as_deref(),
        chain_choice.tip.as_deref(),
        get("nonphysical_inertia").as_deref(),
    )
    .map_err(|e| match e {
        // The command line's mistake first (exit status 2), then the scene's key.
        SpecError::UnknownLink(u) => flag_error(&u, choice).unwrap_or_else(|| {
            let (end, name) = &u.unknown[0];
            ix.invalid(
                end.key(),
                format!(
                    "{name:?} is not a link of the URDF {file} (links: {:?})",
                    u.links
                ),
            )
        }),
        e => e,
    })?;
    let has_gravity = table.iter().any(|(k, _)| k.get_ref().as_ref() == "gravity");
    // A base link away from the root's frame: the chain's base transform is the scene's own
    // `[base]` (the root in the world) then the base link in the root, written as one `[base]`
    // in place of the user's, whose lines become comments.
    let user_base = table.iter().find(|(k, _)| k.get_ref().as_ref() == "base");
    let mut hidden: Vec<(std::ops::Range<usize>, bool)> = keys
        .iter()
        .map(|(n, _, span)| (span.clone(), *n == "urdf" && !has_gravity))
        .collect();
    let base = match (&chain.base, user_base) {
        (None, _) => None,
        (Some(own), None) => Some((own.clone(), placement_note(&chain))),
        (Some(own), Some((k, v))) => {
            let user = scene_base(text, &ix)?;
            let mut spans = Vec::new();
            subtree_spans(k, v, &mut spans);
            hidden.extend(spans.into_iter().map(|r| (r, false)));
            let pose = |t: &TransformSpec| (t.rotation_matrix(), t.translation());
            Some((
                spec(compose(&pose(&user), &pose(own))),
                format!(
                    "# The scene's [base] above (root link {:?} in the world), then link {:?} \
                     where the joints from the root put it (moving joints at q = 0).",
                    chain.root_link, chain.base_link
                ),
            ))
        }
    };
    // Whole lines, in text order, overlapping ones merged (a dotted `base.translation` key
    // and its table share a line).
    let mut lines: Vec<(std::ops::Range<usize>, bool)> = Vec::new();
    hidden.sort_by_key(|h| h.0.start);
    for (span, gravity) in hidden {
        let start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
        let end = text[span.end..]
            .find('\n')
            .map_or(text.len(), |i| span.end + i);
        match lines.last_mut() {
            Some((r, g)) if start <= r.end => {
                r.end = r.end.max(end);
                *g |= gravity;
            }
            _ => lines.push((start..end, gravity)),
        }
    }
    let mut out = String::with_capacity(text.len() + 4096);
    let mut last = 0;
    for (range, gravity) in lines {
        out.push_str(&text[last..range.start]);
        if gravity {
            out.push_str(&format!("gravity = {} ", vec3(URDF_GRAVITY)));
        }
        for (i, line) in text[range.clone()].split('\n').enumerate() {
            if i > 0 {
                out.push('\n');
            }
            out.push_str("# ");
            out.push_str(line);
        }
        last = range.end;
    }
    out.push_str(&text[last..]);
    let first_line = out.lines().count() + 1;
    let _ = writeln!(
        out,
        "\n# Imported from {:?}: robot {:?}, chain {:?} -> {:?}, joints {:?}.",
        provenance(&path),
        chain.robot,
        chain.base_link,
        chain.tip_link,
        chain.joint_names
    );
    out.push_str(&chain_tables(
        &chain,
        base.as_ref().map(|(t, note)| (t, note.clone())),
    ));
    let imported = Imported {
        chain,
        file,
        first_line,
    };
    Ok((out, Some(imported)))
}

/// The `[base]` of a TOML scene text (identity when absent), read and checked on its own,
/// with errors at the user's lines: the scene text that is validated holds the composed one.
fn scene_base(text: &str, ix: &crate::error::SourceIndex<'_>) -> Result<TransformSpec, SpecError> {
    #[derive(serde::Deserialize)]
    struct BaseOnly {
        #[serde(default)]
        base: TransformSpec,
    }
    let b: BaseOnly = toml::from_str(text).map_err(|e| ix.locate_toml_error(&e, false))?;
    crate::validate::check_transform(ix, "base", &b.base)?;
    Ok(b.base)
}

/// The spans of key `k` with value `v` and of everything under it: a table's header (or
/// dotted key) and every key and value of its body, which need not follow it in the text.
fn subtree_spans(
    k: &toml::Spanned<toml::de::DeString<'_>>,
    v: &toml::Spanned<toml::de::DeValue<'_>>,
    out: &mut Vec<std::ops::Range<usize>>,
) {
    let (ks, vs) = (k.span(), v.span());
    out.push(ks.start.min(vs.start)..ks.end.max(vs.end));
    if let toml::de::DeValue::Table(t) = v.get_ref() {
        for (k, v) in t.iter() {
            subtree_spans(k, v, out);
        }
    }
}

/// The URDF file a TOML scene text names in its `urdf` key, resolved against `dir` (the scene
/// file's directory); `None` if the text names none or does not parse (the scene parser
/// reports that). For build scripts, which must tell Cargo every file they read.
pub fn urdf_path(text: &str, dir: &Path) -> Option<std::path::PathBuf> {
    let tree = toml::de::DeTable::parse(text).ok()?;
    let (_, v) = tree
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == "urdf")?;
    match v.get_ref() {
        toml::de::DeValue::String(s) => Some(dir.join(s.as_ref())),
        _ => None,
    }
}

impl Scene {
    /// Reads a scene file — TOML (its `urdf`, if any, resolved next to it) or a URDF (`.urdf`,
    /// or any file whose text starts with `<`) — and
    /// returns the scene with its self-contained text (see [`expand_toml`]). Errors name the
    /// file as given (or the URDF file), the line and the field or element.
    pub fn load_with_text(
        path: impl AsRef<Path>,
        choice: &ChainChoice,
    ) -> Result<(Scene, String), SpecError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let raw = read(path)?;
        let (text, imported) = if is_urdf(path, &raw) {
            let (text, imported) = urdf_scene(&raw, &file, choice)?;
            (text, Some(imported))
        } else {
            let dir = path.parent().unwrap_or(Path::new(""));
            expand(&raw, &file, dir, choice)?
        };
        let scene = Scene::from_toml_str(&text, &file).map_err(|e| match &imported {
            Some(im) => im.relocate(e),
            None => e,
        })?;
        Ok((scene, text))
    }
}

use crate::urdf::{M3, compose, mat_mul as mul, mat_vec as apply};

fn transpose(a: M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn rot_x(a: f64) -> M3 {
    let (s, c) = libm::sincos(a);
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn rot_z(a: f64) -> M3 {
    let (s, c) = libm::sincos(a);
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn spec(p: (M3, [f64; 3])) -> TransformSpec {
    TransformSpec {
        translation: Some(p.1),
        rotation: Some(crate::RotationSpec::Matrix(p.0)),
    }
}

impl Scene {
    /// The DH readers of the kinematics front end: the same robot with every link in
    /// placement form (`origin` + `axis` = z). Modified DH, A_i = R_x(α) T_x(a) R_z(θ) T_z(d):
    /// origin R_x(α) T_x(a) R_z(offset) T_z(d), link frames unchanged. Standard DH,
    /// A_i = R_z(θ) T_z(d) T_x(a) R_x(α): the joint motion comes first, so joint i's origin is
    /// row i − 1's tail T_x(a) R_x(α) then R_z(offset_i) T_z(d_i); link i's frame becomes joint
    /// i's frame, so its COG and inertia are moved by T_x(a_i) R_x(α_i), and the last tail goes
    /// into the tool. A scene already in placement form is returned as it is. Runtime
    /// parameters naming DH constants are dropped (placement origins are baked).
    pub fn placement_form(&self) -> Scene {
        let mut out = self.clone();
        if self.is_placement() {
            return out;
        }
        let id = (IDENTITY, [0.0; 3]);
        let mut tail = id;
        for l in &mut out.links {
            let offset = l.offset.map_or(0.0, |o| o.radians());
            let head = compose(&(rot_z(offset), [0.0; 3]), &(IDENTITY, [0.0, 0.0, l.d]));
            let own = compose(
                &(IDENTITY, [l.a, 0.0, 0.0]),
                &(rot_x(l.alpha.radians()), [0.0; 3]),
            );
            let origin = match self.dh {
                crate::DhConvention::Standard => {
                    let o = compose(&tail, &head);
                    tail = own;
                    // COG and inertia from DH frame i into joint frame i.
                    let c = apply(&own.0, l.com);
                    l.com = [0, 1, 2].map(|k| c[k] + own.1[k]);
                    let i = mul(&mul(&own.0, &l.inertia_matrix()), &transpose(own.0));
                    l.inertia = crate::InertiaSpec::Full(i);
                    o
                }
                crate::DhConvention::Modified => compose(&own, &head),
            };
            l.origin = Some(spec(origin));
            l.axis = Some([0.0, 0.0, 1.0]);
            (l.a, l.d, l.offset) = (0.0, 0.0, None);
            l.alpha = crate::Angle::Radians(0.0);
        }
        let tool = (self.tool_rotation(), self.tool_translation());
        let tool = compose(&tail, &tool);
        out.tool = (tool != id).then(|| spec(tool));
        let known = out.constants();
        out.runtime_parameters
            .retain(|p| known.iter().any(|(n, _)| n == p));
        out
    }
}
