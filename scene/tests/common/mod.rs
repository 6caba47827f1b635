//! Shared helpers of the scene-file tests: a small valid scene with every section ([`BASE`]),
//! one-line edits of it, and the check that an edit fails at the right line and key path.
#![allow(dead_code)] // each test file uses its own subset

use bf_scene::{Angle, Scene, SpecError, SpecErrorKind};

pub const FILE: &str = "bad.toml";

/// A small valid scene with every section; the error tests edit one line of it.
pub const BASE: &str = r#"name = "test_scene"
kernels = ["mass_matrix", "gravity", "contact"]
gravity = [0.0, 0.0, -9.81]

[base]
translation = [2.0, 0.0, 0.0]
rotation = { axis = "y", angle = "-pi/2" }

[[links]]
a = 1.0
alpha = "pi/2"
mass = 0.02
com = [-0.5, 0.0, 0.0]
inertia = [1.0e-3, 2.0e-3, 2.0e-3]
q_min = -1.0
q_max = 1.0

[[links]]
a = 1.0
alpha = 0.0
mass = 0.02
com = [-0.5, 0.0, 0.0]
inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]

[ball]
radius = 1.0
center = [0.0, 0.0, 0.0]
mass = 0.02

[friction]
mu_s = 0.8
mu_k = 0.6
mu_v = 0.001
socket_damping = 0.004

[contact]
kind = "segment"
smooth_eps = 0.01
"#;

/// 1-based number of the `nth` (0-based) line of `text` equal to `line` (trimmed).
pub fn line_no(text: &str, line: &str, nth: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == line)
        .nth(nth)
        .map(|(i, _)| i + 1)
        .unwrap_or_else(|| panic!("line {line:?} (#{nth}) not in text"))
}

/// Replaces the `nth` line equal to `old` by `new` (which may span several lines or be empty).
pub fn edit(old: &str, nth: usize, new: &str) -> String {
    let target = line_no(BASE, old, nth);
    BASE.lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == target { new } else { l })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Asserts that `text` fails with `kind` at `line`, field `path`, and that the message contains
/// `needle`. Returns the error's display string.
pub fn expect_err(
    text: &str,
    kind: SpecErrorKind,
    line: usize,
    path: &str,
    needle: &str,
) -> String {
    let err = match Scene::from_toml_str(text, FILE) {
        Ok(s) => panic!("expected an error at {path}, got a scene: {s:?}"),
        Err(e) => e,
    };
    let shown = err.to_string();
    match &err {
        SpecError::At {
            kind: k,
            file,
            line: l,
            column,
            path: p,
            message,
        } => {
            assert_eq!(file, FILE, "{shown}");
            assert_eq!(*l, line, "wrong line: {shown}");
            assert!(*column >= 1, "{shown}");
            assert_eq!(p, path, "wrong path: {shown}");
            assert_eq!(*k, kind, "wrong kind: {shown}");
            assert!(
                message.contains(needle),
                "message lacks {needle:?}: {shown}"
            );
            assert!(
                shown.starts_with(&format!("{FILE}:{line}:{column}: {path}: ")),
                "bad format: {shown}"
            );
        }
        SpecError::Io { .. } => panic!("unexpected I/O error {shown}"),
        SpecError::Urdf(_) | SpecError::UnknownLink(_) => panic!("unexpected URDF error {shown}"),
    }
    shown
}

/// Loads the shipped scene `scenes/<name>.toml`.
pub fn scene(name: &str) -> Scene {
    let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The exact angle `num/den · π`.
pub fn pm(num: i64, den: i64) -> Angle {
    Angle::PiMultiple { num, den }
}
