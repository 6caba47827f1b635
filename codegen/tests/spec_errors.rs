//! Scene-specification tests (`bf_codegen::spec`): every class of bad input must produce an
//! error naming the file, the right line and the field path; the four shipped scenes must load
//! with the values of the paper (Sect. 2.1, Table 1, Sect. 6), docs/parameters.md and the cited robot
//! data, written here independently of the scene files; exact angle parsing.

use bf_codegen::spec::{Angle, KNOWN_KERNELS, RotationSpec, Scene, SpecError, SpecErrorKind};
use nalgebra::{Matrix3, Matrix4, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

const FILE: &str = "bad.toml";

/// A small valid scene with every section; the error tests edit one line of it.
const BASE: &str = r#"name = "test_scene"
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
fn line_no(text: &str, line: &str, nth: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == line)
        .nth(nth)
        .map(|(i, _)| i + 1)
        .unwrap_or_else(|| panic!("line {line:?} (#{nth}) not in text"))
}

/// Replaces the `nth` line equal to `old` by `new` (which may span several lines or be empty).
fn edit(old: &str, nth: usize, new: &str) -> String {
    let target = line_no(BASE, old, nth);
    BASE.lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == target { new } else { l })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Asserts that `text` fails with `kind` at `line`, field `path`, and that the message contains
/// `needle`. Returns the error's display string.
fn expect_err(text: &str, kind: SpecErrorKind, line: usize, path: &str, needle: &str) -> String {
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
    }
    shown
}

#[test]
fn base_scene_is_valid() {
    let s = Scene::from_toml_str(BASE, FILE).expect("BASE must be valid");
    assert_eq!(s.nq(), 2);
    // The full-matrix and diagonal inertia forms describe the same tensor here.
    assert_eq!(s.link_inertia(1), s.link_inertia(0));
    assert_eq!(
        s.link_inertia(0),
        [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]
    );
}

#[test]
fn display_format_is_file_line_column_path_message() {
    let text = edit("mass = 0.02", 1, "mass = -0.02");
    let line = line_no(&text, "mass = -0.02", 0);
    let shown = expect_err(&text, SpecErrorKind::Invalid, line, "links[1].mass", "> 0");
    assert_eq!(
        shown,
        format!("{FILE}:{line}:1: links[1].mass: must be > 0 (got -0.02)")
    );
}

#[test]
fn toml_syntax_error() {
    let text = edit("mass = 0.02", 0, "mass = 0.02 0.03");
    let line = line_no(&text, "mass = 0.02 0.03", 0);
    expect_err(
        &text,
        SpecErrorKind::Syntax,
        line,
        "links[0].mass",
        "TOML syntax error",
    );
    // A broken table header.
    let text = edit("[ball]", 0, "[ball");
    let line = line_no(&text, "[ball", 0);
    expect_err(
        &text,
        SpecErrorKind::Syntax,
        line,
        "ball",
        "TOML syntax error",
    );
    // A duplicate key is a syntax error in TOML.
    let text = edit("radius = 1.0", 0, "radius = 1.0\nradius = 2.0");
    let line = line_no(&text, "radius = 2.0", 0);
    expect_err(
        &text,
        SpecErrorKind::Syntax,
        line,
        "ball.radius",
        "duplicate",
    );
}

#[test]
fn unknown_keys_are_rejected_everywhere() {
    let text = edit(
        "gravity = [0.0, 0.0, -9.81]",
        0,
        "gravity = [0.0, 0.0, -9.81]\ncolour = 3",
    );
    let line = line_no(&text, "colour = 3", 0);
    expect_err(
        &text,
        SpecErrorKind::UnknownField,
        line,
        "colour",
        "unknown field `colour`",
    );

    let text = edit("mass = 0.02", 1, "mass = 0.02\nmasss = 0.03");
    let line = line_no(&text, "masss = 0.03", 0);
    expect_err(
        &text,
        SpecErrorKind::UnknownField,
        line,
        "links[1].masss",
        "unknown field",
    );

    let text = edit("radius = 1.0", 0, "radius = 1.0\ndensity = 3.0");
    let line = line_no(&text, "density = 3.0", 0);
    expect_err(
        &text,
        SpecErrorKind::UnknownField,
        line,
        "ball.density",
        "unknown field",
    );

    let text = edit(
        "rotation = { axis = \"y\", angle = \"-pi/2\" }",
        0,
        "rotation = { axis = \"y\", angle = \"-pi/2\", turns = 1 }",
    );
    let line = line_no(&text, "[base]", 0) + 2;
    expect_err(
        &text,
        SpecErrorKind::UnknownField,
        line,
        "base.rotation",
        "unknown field `turns`",
    );
}

#[test]
fn missing_fields_name_the_table_and_key() {
    // links[1] without a mass: reported at its [[links]] header.
    let text = edit("mass = 0.02", 1, "");
    let line = line_no(&text, "[[links]]", 1);
    expect_err(
        &text,
        SpecErrorKind::MissingField,
        line,
        "links[1].mass",
        "missing field `mass`",
    );

    let text = edit("radius = 1.0", 0, "");
    let line = line_no(&text, "[ball]", 0);
    expect_err(
        &text,
        SpecErrorKind::MissingField,
        line,
        "ball.radius",
        "missing field",
    );

    let text = edit("gravity = [0.0, 0.0, -9.81]", 0, "");
    let err = Scene::from_toml_str(&text, FILE).unwrap_err();
    assert_eq!(err.path(), Some("gravity"), "{err}");
    assert_eq!(err.kind(), Some(SpecErrorKind::MissingField), "{err}");
    assert!(err.to_string().starts_with("bad.toml:"), "{err}");

    let text = edit(
        "rotation = { axis = \"y\", angle = \"-pi/2\" }",
        0,
        "rotation = { axis = \"y\" }",
    );
    let line = line_no(&text, "rotation = { axis = \"y\" }", 0);
    expect_err(
        &text,
        SpecErrorKind::MissingField,
        line,
        "base.rotation.angle",
        "missing field",
    );
}

#[test]
fn wrong_types_and_shapes() {
    let text = edit("mass = 0.02", 0, "mass = \"heavy\"");
    let line = line_no(&text, "mass = \"heavy\"", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "links[0].mass",
        "invalid type",
    );

    let text = edit("com = [-0.5, 0.0, 0.0]", 0, "com = [-0.5, 0.0]");
    let line = line_no(&text, "com = [-0.5, 0.0]", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "links[0].com",
        "invalid length 2",
    );

    // A fourth component must not be silently dropped.
    let text = edit(
        "gravity = [0.0, 0.0, -9.81]",
        0,
        "gravity = [0.0, 0.0, -9.81, 1.0]",
    );
    let line = line_no(&text, "gravity = [0.0, 0.0, -9.81, 1.0]", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "gravity",
        "invalid length 4",
    );

    let text = edit(
        "inertia = [1.0e-3, 2.0e-3, 2.0e-3]",
        0,
        "inertia = [1.0e-3, 2.0e-3]",
    );
    let line = line_no(&text, "inertia = [1.0e-3, 2.0e-3]", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "links[0].inertia",
        "inertia must be",
    );

    let text = edit(
        "name = \"test_scene\"",
        0,
        "name = \"test_scene\"\ndh = \"sideways\"",
    );
    let line = line_no(&text, "dh = \"sideways\"", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "dh",
        "unknown variant",
    );

    let text = edit(
        "rotation = { axis = \"y\", angle = \"-pi/2\" }",
        0,
        "rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 0.0]]",
    );
    let line = line_no(&text, "[base]", 0) + 2;
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "base.rotation[2]",
        "invalid length 4",
    );
}

#[test]
fn non_finite_numbers_are_rejected() {
    for (old, nth, new, path) in [
        ("mass = 0.02", 1, "mass = nan", "links[1].mass"),
        (
            "gravity = [0.0, 0.0, -9.81]",
            0,
            "gravity = [0.0, 0.0, -inf]",
            "gravity[2]",
        ),
        ("mu_k = 0.6", 0, "mu_k = inf", "friction.mu_k"),
        ("a = 1.0", 0, "a = +inf", "links[0].a"),
        ("q_max = 1.0", 0, "q_max = nan", "links[0].q_max"),
        (
            "center = [0.0, 0.0, 0.0]",
            0,
            "center = [0.0, nan, 0.0]",
            "ball.center[1]",
        ),
        (
            "inertia = [1.0e-3, 2.0e-3, 2.0e-3]",
            0,
            "inertia = [1.0e-3, inf, 2.0e-3]",
            "links[0].inertia[1]",
        ),
        (
            "translation = [2.0, 0.0, 0.0]",
            0,
            "translation = [nan, 0.0, 0.0]",
            "base.translation[0]",
        ),
        (
            "smooth_eps = 0.01",
            0,
            "smooth_eps = nan",
            "contact.smooth_eps",
        ),
    ] {
        let text = edit(old, nth, new);
        let line = line_no(&text, new, 0);
        expect_err(&text, SpecErrorKind::Invalid, line, path, "finite");
    }
    // An angle that is NaN.
    let text = edit("alpha = 0.0", 0, "alpha = nan");
    let line = line_no(&text, "alpha = nan", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[1].alpha",
        "finite",
    );
    // A literal that overflows f64.
    let text = edit("mu_s = 0.8", 0, "mu_s = 1e400");
    let line = line_no(&text, "mu_s = 1e400", 0);
    let err = Scene::from_toml_str(&text, FILE).unwrap_err();
    assert_eq!(
        (err.line(), err.path()),
        (Some(line), Some("friction.mu_s")),
        "{err}"
    );
}

#[test]
fn masses_must_be_positive() {
    for (new, nth, path) in [
        ("mass = -0.02", 1, "links[1].mass"),
        ("mass = 0.0", 0, "links[0].mass"),
        ("mass = 0", 2, "ball.mass"),
    ] {
        let text = edit("mass = 0.02", nth, new);
        let line = line_no(&text, new, 0);
        expect_err(&text, SpecErrorKind::Invalid, line, path, "must be > 0");
    }
}

#[test]
fn inertia_must_be_symmetric_positive_definite() {
    // Negative principal moment.
    let new = "inertia = [1.0e-3, -2.0e-3, 2.0e-3]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].inertia",
        "positive definite",
    );
    // Zero moment (semi-definite).
    let new = "inertia = [1.0e-3, 0.0, 2.0e-3]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].inertia",
        "positive definite",
    );
    // Positive diagonal but indefinite: the product of inertia is too large.
    let new = "inertia = [[1.0e-3, 3.0e-3, 0.0], [3.0e-3, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]";
    let old = "inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]";
    let text = edit(old, 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[1].inertia",
        "positive definite",
    );
    // Asymmetric.
    let new = "inertia = [[1.0e-3, 1.0e-4, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]";
    let text = edit(old, 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[1].inertia",
        "symmetric",
    );
    // Ball inertia too.
    let new = "mass = 0.02\ninertia = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]";
    let text = edit("mass = 0.02", 2, new);
    let line = line_no(
        &text,
        "inertia = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]",
        0,
    );
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "ball.inertia",
        "positive definite",
    );
    // A valid explicit ball inertia overrides the solid-sphere default.
    let text = edit("mass = 0.02", 2, "mass = 0.02\ninertia = [1.0, 2.0, 2.5]");
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(s.ball_inertia().unwrap()[2][2], 2.5);
}

#[test]
fn zero_links_is_an_error() {
    let links_start = line_no(BASE, "[[links]]", 0);
    let ball = line_no(BASE, "[ball]", 0);
    let text: String = BASE
        .lines()
        .enumerate()
        .filter(|(i, _)| i + 1 < links_start || i + 1 >= ball)
        .map(|(_, l)| format!("{l}\n"))
        .collect::<String>()
        .replace("name = \"test_scene\"", "name = \"test_scene\"\nlinks = []");
    let line = line_no(&text, "links = []", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links",
        "at least one link",
    );
}

#[test]
fn kernel_list_is_checked() {
    let new = "kernels = [\"mass_matrix\", \"gravity\", \"jacobian_of_doom\"]";
    let text = edit(
        "kernels = [\"mass_matrix\", \"gravity\", \"contact\"]",
        0,
        new,
    );
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "kernels[2]",
        "unknown kernel",
    );

    let new = "kernels = [\"gravity\", \"gravity\"]";
    let text = edit(
        "kernels = [\"mass_matrix\", \"gravity\", \"contact\"]",
        0,
        new,
    );
    expect_err(&text, SpecErrorKind::Invalid, line, "kernels[1]", "twice");

    // Every known kernel is accepted in a scene with ball and contact.
    let all = KNOWN_KERNELS
        .iter()
        .map(|k| format!("\"{k}\""))
        .collect::<Vec<_>>()
        .join(", ");
    let text = edit(
        "kernels = [\"mass_matrix\", \"gravity\", \"contact\"]",
        0,
        &format!("kernels = [{all}]"),
    );
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(s.kernels.len(), KNOWN_KERNELS.len());
}

#[test]
fn ocp_kernel_costs_are_checked() {
    let old = "kernels = [\"mass_matrix\", \"gravity\", \"contact\"]";
    let with = |list: &str| edit(old, 0, &format!("{old}\nocp_kernels = {list}"));
    let s = Scene::from_toml_str(&with("[\"qc\", \"cot\"]"), FILE).unwrap();
    assert_eq!(
        s.ocp_kernels,
        Some(vec!["qc".to_string(), "cot".to_string()])
    );
    let text = with("[\"qc\", \"fastest\"]");
    let ocp_line = |t: &str| {
        t.lines()
            .position(|l| l.starts_with("ocp_kernels"))
            .unwrap()
            + 1
    };
    let line = ocp_line(&text);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "ocp_kernels[1]",
        "unknown cost kind",
    );
    let text = with("[\"cot\", \"cot\"]");
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "ocp_kernels[1]",
        "twice",
    );
    // Without a ball the node functions do not exist.
    let no_ball = {
        let t = with("[\"qc\"]");
        let start = t.find("[ball]").unwrap();
        t[..start].to_string()
    };
    let line = ocp_line(&no_ball);
    expect_err(
        &no_ball.replace(", \"contact\"", ""),
        SpecErrorKind::Invalid,
        line,
        "ocp_kernels[0]",
        "[ball] and a [contact]",
    );
}

#[test]
fn contact_kernels_need_ball_and_contact() {
    // Remove [ball] .. end (ball, friction, contact).
    let ball = line_no(BASE, "[ball]", 0);
    let text: String = BASE
        .lines()
        .take(ball - 1)
        .map(|l| format!("{l}\n"))
        .collect();
    let line = line_no(
        &text,
        "kernels = [\"mass_matrix\", \"gravity\", \"contact\"]",
        0,
    );
    expect_err(&text, SpecErrorKind::Invalid, line, "kernels[2]", "[ball]");

    // A ball but no [contact]: contact_smooth still rejected.
    let contact = line_no(BASE, "[contact]", 0);
    let text: String = BASE
        .lines()
        .take(contact - 1)
        .map(|l| format!("{l}\n"))
        .collect::<String>()
        .replace("\"contact\"]", "\"contact_smooth\"]");
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "kernels[2]",
        "[contact]",
    );

    // A [contact] section without a [ball].
    let text: String = BASE
        .lines()
        .enumerate()
        .filter(|(i, _)| !(ball - 1..ball + 3).contains(i))
        .map(|(_, l)| format!("{l}\n"))
        .collect::<String>()
        .replace("\"contact\"]", "\"gravity\"]");
    let text = text.replace(
        "kernels = [\"mass_matrix\", \"gravity\", \"gravity\"]",
        "kernels = [\"gravity\"]",
    );
    let line = line_no(&text, "[contact]", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "contact",
        "needs a [ball]",
    );
}

#[test]
fn runtime_parameters_must_name_registry_constants() {
    let new = "runtime_parameters = [\"ball.radius\", \"link3.mass\"]";
    let text = edit(
        "name = \"test_scene\"",
        0,
        &format!("name = \"test_scene\"\n{new}"),
    );
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "runtime_parameters[1]",
        "link3.mass",
    );

    let new = "runtime_parameters = [\"link2.mass\", \"link2.mass\"]";
    let text = edit(
        "name = \"test_scene\"",
        0,
        &format!("name = \"test_scene\"\n{new}"),
    );
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "runtime_parameters[1]",
        "twice",
    );

    let new = "runtime_parameters = [\"link1.inertia.yx\"]";
    let text = edit(
        "name = \"test_scene\"",
        0,
        &format!("name = \"test_scene\"\n{new}"),
    );
    let line = line_no(&text, new, 0);
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "runtime_parameters[0]",
        "unknown",
    );
    assert!(
        shown.contains("link1.inertia.xy"),
        "should suggest similar names: {shown}"
    );

    let new = "runtime_parameters = [\"ball.radius\", \"link2.inertia.xz\", \"gravity.z\"]";
    let text = edit(
        "name = \"test_scene\"",
        0,
        &format!("name = \"test_scene\"\n{new}"),
    );
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(
        s.runtime_parameter_values(),
        vec![
            ("ball.radius".to_string(), 1.0),
            ("link2.inertia.xz".to_string(), 0.0),
            ("gravity.z".to_string(), -9.81)
        ]
    );
    assert!(s.is_runtime("gravity.z") && !s.is_runtime("gravity.x"));
}

#[test]
fn scene_name_must_be_a_rust_identifier() {
    for bad in ["2fast", "my-scene", "fn", "self", "", "_", "naïve", "a b"] {
        let new = format!("name = \"{bad}\"");
        let text = edit("name = \"test_scene\"", 0, &new);
        expect_err(&text, SpecErrorKind::Invalid, 1, "name", "identifier");
    }
    for good in ["paper", "_x", "Scene2", "iiwa7"] {
        let text = edit("name = \"test_scene\"", 0, &format!("name = \"{good}\""));
        assert!(Scene::from_toml_str(&text, FILE).is_ok(), "{good}");
    }
}

#[test]
fn friction_coefficients_must_be_finite_and_nonnegative() {
    for (old, new, path) in [
        ("mu_s = 0.8", "mu_s = -0.1", "friction.mu_s"),
        ("mu_k = 0.6", "mu_k = -0.6", "friction.mu_k"),
        ("mu_v = 0.001", "mu_v = -1e-9", "friction.mu_v"),
        (
            "socket_damping = 0.004",
            "socket_damping = -0.004",
            "friction.socket_damping",
        ),
    ] {
        let text = edit(old, 0, new);
        let line = line_no(&text, new, 0);
        expect_err(&text, SpecErrorKind::Invalid, line, path, ">= 0");
    }
    // mu_k > mu_s is physically odd but allowed; zero friction is allowed.
    let text = edit("mu_k = 0.6", 0, "mu_k = 0.9");
    assert_eq!(
        Scene::from_toml_str(&text, FILE)
            .unwrap()
            .friction
            .unwrap()
            .mu_k,
        0.9
    );
    let text = edit("mu_s = 0.8", 0, "mu_s = 0");
    assert_eq!(
        Scene::from_toml_str(&text, FILE)
            .unwrap()
            .friction
            .unwrap()
            .mu_s,
        0.0
    );
}

#[test]
fn ball_radius_must_be_positive() {
    for new in ["radius = 0.0", "radius = -1.0"] {
        let text = edit("radius = 1.0", 0, new);
        let line = line_no(&text, new, 0);
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line,
            "ball.radius",
            "must be > 0",
        );
    }
}

#[test]
fn joint_limits_must_be_ordered() {
    let text = edit("q_min = -1.0", 0, "q_min = 1.5");
    let line = line_no(&text, "q_min = 1.5", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].q_min",
        "q_min must be <= q_max",
    );
    // Angle strings are accepted for limits and converted to radians.
    let text = edit("q_min = -1.0", 0, "q_min = \"-45deg\"");
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(s.links[0].q_min, Some(-PI / 4.0));
    let text = edit("q_max = 1.0", 0, "q_max = \"-90 deg\"");
    let line = line_no(&text, "q_min = -1.0", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].q_min",
        "q_max",
    );
}

#[test]
fn base_rotation_matrix_must_be_a_rotation() {
    let old = "rotation = { axis = \"y\", angle = \"-pi/2\" }";
    let rot_line = line_no(BASE, old, 0);
    // Not orthonormal (scaled).
    let text = edit(
        old,
        0,
        "rotation = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
    );
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        rot_line,
        "base.rotation",
        "orthonormal",
    );
    // Not orthogonal rows.
    let text = edit(
        old,
        0,
        "rotation = [[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
    );
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        rot_line,
        "base.rotation",
        "orthonormal",
    );
    // A reflection.
    let text = edit(
        old,
        0,
        "rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]",
    );
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        rot_line,
        "base.rotation",
        "determinant",
    );
    // Bad axis name.
    let text = edit(old, 0, "rotation = { axis = \"w\", angle = \"pi\" }");
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        rot_line,
        "base.rotation.axis",
        "axis",
    );
    // The matrix form of R_y(-pi/2) equals the exact axis form (docs/parameters.md).
    let text = edit(
        old,
        0,
        "rotation = [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]",
    );
    let m = Scene::from_toml_str(&text, FILE).unwrap();
    let a = Scene::from_toml_str(BASE, FILE).unwrap();
    assert_eq!(m.base_rotation(), a.base_rotation());
    assert!(matches!(m.base.rotation, Some(RotationSpec::Matrix(_))));
}

#[test]
fn contact_kind_must_be_segment_or_tip() {
    let text = edit("kind = \"segment\"", 0, "kind = \"edge\"");
    let line = line_no(&text, "kind = \"edge\"", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "contact.kind",
        "\"segment\" or \"tip\"",
    );
    let text = edit("kind = \"segment\"", 0, "kind = \"tip\"");
    assert_eq!(
        Scene::from_toml_str(&text, FILE)
            .unwrap()
            .contact
            .unwrap()
            .kind,
        "tip"
    );
    // The default kind is "segment" and the default eps 0.01 (eq. 59).
    let text = edit("kind = \"segment\"", 0, "").replace("smooth_eps = 0.01", "");
    let c = Scene::from_toml_str(&text, FILE).unwrap().contact.unwrap();
    assert_eq!((c.kind.as_str(), c.smooth_eps), ("segment", 0.01));
}

#[test]
fn bad_angle_strings_name_the_field() {
    for bad in [
        "pi/x", "1.5", "pi/0", "2*pie", "", "90 rad", "pi/2.5", "1e3deg",
    ] {
        let new = format!("alpha = \"{bad}\"");
        let text = edit("alpha = \"pi/2\"", 0, &new);
        let line = line_no(&text, &new, 0);
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line,
            "links[0].alpha",
            "invalid angle",
        );
    }
}

#[test]
fn io_error_names_the_file() {
    let err = Scene::load("/nonexistent/dir/scene.toml").unwrap_err();
    assert!(matches!(err, SpecError::Io { .. }));
    assert!(
        err.to_string().starts_with("/nonexistent/dir/scene.toml: "),
        "{err}"
    );
}

#[test]
fn load_reports_the_path_in_errors() {
    let dir = std::env::temp_dir().join(format!("bf_spec_test_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("foo.toml");
    std::fs::write(&path, edit("mass = 0.02", 1, "mass = -0.02")).unwrap();
    let err = Scene::load(&path).unwrap_err();
    let line = line_no(&edit("mass = 0.02", 1, "mass = -0.02"), "mass = -0.02", 0);
    assert_eq!(
        err.to_string(),
        format!(
            "{}:{line}:1: links[1].mass: must be > 0 (got -0.02)",
            path.display()
        )
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

// ------------------------------------------------------------------------------------------
// Angle parsing
// ------------------------------------------------------------------------------------------

fn pm(num: i64, den: i64) -> Angle {
    Angle::PiMultiple { num, den }
}

#[test]
fn angle_strings_parse_exactly() {
    for (s, want) in [
        ("pi/2", pm(1, 2)),
        ("-pi/2", pm(-1, 2)),
        ("3*pi/4", pm(3, 4)),
        ("3pi/4", pm(3, 4)),
        ("3 * pi / 4", pm(3, 4)),
        ("pi", pm(1, 1)),
        ("-pi", pm(-1, 1)),
        ("+pi/3", pm(1, 3)),
        ("PI/6", pm(1, 6)),
        ("π/2", pm(1, 2)),
        ("2*pi/4", pm(1, 2)),
        ("0.5*pi", pm(1, 2)),
        ("0*pi", pm(0, 1)),
        ("0", pm(0, 1)),
        ("-0", pm(0, 1)),
        ("0.0", pm(0, 1)),
        ("90deg", pm(1, 2)),
        ("-90 deg", pm(-1, 2)),
        ("180deg", pm(1, 1)),
        ("360deg", pm(2, 1)),
        ("1deg", pm(1, 180)),
        ("22.5deg", pm(1, 8)),
        ("-45 degrees", pm(-1, 4)),
        ("100deg", pm(5, 9)),
        ("90°", pm(1, 2)),
    ] {
        assert_eq!(Angle::parse_str(s), Ok(want), "{s}");
    }
    for bad in [
        "", "1.5", "pi/0", "pi/x", "pie", "x deg", "pi/2.5", "1e3deg", "pi/-2", "--pi", "pi pi",
        "deg", "2 pi 3",
    ] {
        let e = Angle::parse_str(bad).unwrap_err();
        assert!(e.contains("invalid angle"), "{bad}: {e}");
    }
}

#[test]
fn angle_numbers_are_radians_and_exact_multiples_evaluate_correctly() {
    #[derive(serde::Deserialize)]
    struct W {
        a: Angle,
    }
    let w: W = toml::from_str("a = 1.5").unwrap();
    assert_eq!(w.a, Angle::Radians(1.5));
    let w: W = toml::from_str("a = -2").unwrap();
    assert_eq!(w.a, Angle::Radians(-2.0));
    let w: W = toml::from_str("a = \"-3*pi/4\"").unwrap();
    assert_eq!(w.a, pm(-3, 4));

    assert_eq!(pm(1, 2).radians(), PI / 2.0);
    assert_eq!(pm(-1, 1).radians(), -PI);
    assert!((pm(-3, 4).radians() + 0.75 * PI).abs() < 1e-15);
    assert_eq!(Angle::Radians(0.3).radians(), 0.3);
    // Exact cos/sin at quarter turns (no 6e-17 residue), f64 values elsewhere.
    assert_eq!(pm(1, 2).cos_sin(), (0.0, 1.0));
    assert_eq!(pm(-1, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(1, 1).cos_sin(), (-1.0, 0.0));
    assert_eq!(pm(3, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(-5, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(4, 1).cos_sin(), (1.0, 0.0));
    let (c, s) = pm(1, 3).cos_sin();
    assert!((c - 0.5).abs() < 1e-15 && (s - 3f64.sqrt() / 2.0).abs() < 1e-15);
    assert_eq!(Angle::pi_multiple(6, -8), Some(pm(-3, 4)));
    assert_eq!(Angle::pi_multiple(1, 0), None);
}

#[test]
fn random_degree_and_pi_fraction_strings_round_trip() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..2000 {
        let k: i64 = rng.random_range(-100_000..100_000);
        let Ok(Angle::PiMultiple { num, den }) = Angle::parse_str(&format!("{k}deg")) else {
            panic!("{k}deg");
        };
        // num/den = k/180 exactly, in lowest terms, den > 0.
        assert_eq!(num * 180, k * den, "{k}deg");
        assert!(den > 0 && gcd(num, den) == 1);
        let (n, d): (i64, i64) = (rng.random_range(-50..50), rng.random_range(1..50));
        let a = Angle::parse_str(&format!("{n}*pi/{d}")).unwrap();
        assert!(
            (a.radians() - n as f64 * PI / d as f64).abs() <= 1e-13,
            "{n}*pi/{d}"
        );
        let Angle::PiMultiple { num, den } = a else {
            panic!()
        };
        assert_eq!(num * d, n * den);
    }
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

// ------------------------------------------------------------------------------------------
// The shipped scene files
// ------------------------------------------------------------------------------------------

fn scene(name: &str) -> Scene {
    let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Standard DH forward kinematics written here independently of the crate
/// (A_i = Rz(theta) Tz(d) Tx(a) Rx(alpha), docs/parameters.md): world frames 1..n.
fn dh_frames(base: Matrix4<f64>, table: &[(f64, f64, f64)], q: &[f64]) -> Vec<Matrix4<f64>> {
    let mut t = base;
    let mut out = Vec::new();
    for (&(a, alpha, d), &qi) in table.iter().zip(q) {
        let rz = Matrix4::new_rotation(Vector3::z() * qi);
        let tz = Matrix4::new_translation(&Vector3::new(0.0, 0.0, d));
        let tx = Matrix4::new_translation(&Vector3::new(a, 0.0, 0.0));
        let rx = Matrix4::new_rotation(Vector3::x() * alpha);
        t = t * rz * tz * tx * rx;
        out.push(t);
    }
    out
}

fn table(s: &Scene) -> Vec<(f64, f64, f64)> {
    s.links
        .iter()
        .map(|l| (l.a, l.alpha.radians(), l.d))
        .collect()
}

fn homogeneous(r: [[f64; 3]; 3], p: [f64; 3]) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    for i in 0..3 {
        for j in 0..3 {
            t[(i, j)] = r[i][j];
        }
        t[(i, 3)] = p[i];
    }
    t
}

fn assert_finger_common(s: &Scene) {
    // docs/parameters.md, written out independently of the scene file.
    assert_eq!(s.nq(), 3);
    assert_eq!(s.dh, bf_codegen::spec::DhConvention::Standard);
    assert_eq!(s.gravity, [0.0, 0.0, -9.81]);
    assert_eq!(s.base_translation(), [2.0, 0.0, 0.0]);
    assert_eq!(
        s.base_rotation(),
        [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        "R_y(-pi/2) must be exact"
    );
    let alphas = [pm(1, 2), pm(0, 1), pm(0, 1)];
    for (i, l) in s.links.iter().enumerate() {
        assert_eq!(l.a, 1.0);
        assert_eq!(l.d, 0.0);
        assert_eq!(l.alpha, alphas[i], "alpha_{} must be exact", i + 1);
        assert!(l.offset.is_none_or(|o| o.radians() == 0.0));
        assert_eq!(l.mass, 0.02);
        assert_eq!(l.com, [-0.5, 0.0, 0.0]);
        assert_eq!(
            s.link_inertia(i),
            [
                [1.0677e-3, 0.0, 0.0],
                [0.0, 2.3177e-3, 0.0],
                [0.0, 0.0, 2.0833e-3]
            ]
        );
        assert_eq!(l.tau_max, Some(1.0));
    }
    let b = s.ball.as_ref().unwrap();
    assert_eq!((b.radius, b.center, b.mass), (1.0, [0.0; 3], 0.02));
    let ib = s.ball_inertia().unwrap();
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { 0.4 * 0.02 * 1.0 } else { 0.0 };
            assert!((ib[i][j] - want).abs() < 1e-18, "I_b = 0.008 * 1");
        }
    }
    let f = s.friction.as_ref().unwrap();
    assert_eq!(
        (f.mu_s, f.mu_k, f.mu_v, f.socket_damping),
        (0.8, 0.6, 0.001, 0.004)
    );
    let c = s.contact.as_ref().unwrap();
    assert_eq!((c.kind.as_str(), c.smooth_eps), ("segment", 0.01));
    let mut k = s.kernels.clone();
    k.sort();
    // The inverse-dynamics family is emitted for every scene without being listed.
    let mut all: Vec<String> = KNOWN_KERNELS
        .iter()
        .filter(|k| !bf_codegen::kernels::ROBOT_KERNELS.contains(k))
        .map(|s| s.to_string())
        .collect();
    all.sort();
    assert_eq!(k, all, "the finger scenes emit every kernel");

    // Geometry: at q = 0 the finger stands upright from o_f = (2r, 0, 0): frame i at
    // (2, 0, i) with e_x3 = +z (docs/parameters.md: base R_y(-pi/2), links along x_i).
    let base = homogeneous(s.base_rotation(), s.base_translation());
    let frames = dh_frames(base, &table(s), &[0.0; 3]);
    for (i, f) in frames.iter().enumerate() {
        let p = f.fixed_view::<3, 1>(0, 3);
        assert!(
            (p - Vector3::new(2.0, 0.0, (i + 1) as f64)).norm() < 1e-12,
            "frame {}",
            i + 1
        );
    }
    let ex3 = frames[2].fixed_view::<3, 1>(0, 0);
    assert!((ex3 - Vector3::z()).norm() < 1e-12);
    // Positive q2 bends the finger towards the ball at the origin (needed for human.toml's
    // q2 >= 0 to mean flexion towards the ball).
    let bent = dh_frames(base, &table(s), &[0.0, 0.3, 0.0]);
    assert!(bent[2][(0, 3)] < 2.0);
}

#[test]
fn paper_scene_matches_params_md() {
    let s = scene("paper");
    assert_eq!(s.name, "paper");
    assert_finger_common(&s);
    assert!(
        s.runtime_parameters.is_empty(),
        "paper scene is fully baked"
    );
    assert!(
        s.links
            .iter()
            .all(|l| l.q_min.is_none() && l.q_max.is_none())
    );
}

#[test]
fn human_scene_differs_only_in_limits_runtime_parameters_and_ocp_kernels() {
    let s = scene("human");
    assert_eq!(s.name, "human");
    assert_finger_common(&s);
    // Paper Sect. 6: q_i >= 0 for i in {2, 3}; upper limits 90 and 100 degrees.
    assert_eq!((s.links[0].q_min, s.links[0].q_max), (None, None));
    assert_eq!(s.links[1].q_min, Some(0.0));
    assert_eq!(s.links[2].q_min, Some(0.0));
    assert!((s.links[1].q_max.unwrap() - 90.0 * PI / 180.0).abs() < 1e-15);
    assert!((s.links[2].q_max.unwrap() - 100.0 * PI / 180.0).abs() < 1e-15);
    assert_eq!(
        s.runtime_parameter_values(),
        vec![
            ("ball.radius".to_string(), 1.0),
            ("link3.mass".to_string(), 0.02)
        ]
    );
    // Only the COT objective's optimal-control node kernels (periodic-cot-human).
    assert_eq!(s.ocp_kernels, Some(vec!["cot".to_string()]));
    // Apart from these, identical to the paper scene.
    let mut p = scene("paper");
    p.name = s.name.clone();
    p.description = s.description.clone();
    p.runtime_parameters = s.runtime_parameters.clone();
    p.ocp_kernels = s.ocp_kernels.clone();
    for i in 1..3 {
        p.links[i].q_min = s.links[i].q_min;
        p.links[i].q_max = s.links[i].q_max;
    }
    assert_eq!(p, s);
}

#[test]
fn puma560_scene_matches_corke_rtb() {
    let s = scene("puma560");
    assert_eq!(s.nq(), 6);
    assert!(s.ball.is_none() && s.contact.is_none());
    assert!(!s.wants("contact") && !s.wants("contact_smooth"));
    assert!(s.wants("mass_matrix") && s.wants("gravity") && s.wants("cqd_g_rnea"));
    // mdl_puma560.m (standard DH): (a, alpha, d), written independently.
    let want = [
        (0.0, PI / 2.0, 0.0),
        (0.4318, 0.0, 0.0),
        (0.0203, -PI / 2.0, 0.15005),
        (0.0, PI / 2.0, 0.4318),
        (0.0, -PI / 2.0, 0.0),
        (0.0, 0.0, 0.0),
    ];
    for (l, w) in s.links.iter().zip(want) {
        assert_eq!((l.a, l.alpha.radians(), l.d), w);
        assert!(matches!(l.alpha, Angle::PiMultiple { .. }), "alpha exact");
    }
    let masses: Vec<f64> = s.links[1..].iter().map(|l| l.mass).collect();
    assert_eq!(masses, [17.4, 4.8, 0.82, 0.34, 0.09]);
    assert_eq!(s.links[1].com, [-0.3638, 0.006, 0.2275]);
    assert_eq!(s.links[2].com, [-0.0203, -0.0141, 0.070]);
    assert_eq!(s.links[5].com, [0.0, 0.0, 0.032]);
    assert_eq!(s.link_inertia(1)[2][2], 0.539);
    assert_eq!(s.link_inertia(2)[1][1], 0.086);
    // Link 1: only I_yy = 0.35 matters; its COG is on the fixed joint-1 axis.
    assert_eq!(s.link_inertia(0)[1][1], 0.35);
    assert_eq!(s.links[0].com, [0.0; 3]);
    let deg = PI / 180.0;
    let lim = [
        (-160.0, 160.0),
        (-45.0, 225.0),
        (-225.0, 45.0),
        (-110.0, 170.0),
        (-100.0, 100.0),
        (-266.0, 266.0),
    ];
    for (l, (lo, hi)) in s.links.iter().zip(lim) {
        assert!((l.q_min.unwrap() - lo * deg).abs() < 1e-14);
        assert!((l.q_max.unwrap() - hi * deg).abs() < 1e-14);
    }
    // z0 (joint 1) coincides with y1: the property that makes m1, I1xx, I1zz irrelevant.
    let f = dh_frames(
        Matrix4::identity(),
        &table(&s),
        &[0.7, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    let y1 = f[0].fixed_view::<3, 1>(0, 1);
    assert!((y1 - Vector3::z()).norm() < 1e-12);
    assert!(f[0].fixed_view::<3, 1>(0, 3).norm() < 1e-12);
}

/// URDF rotation from roll-pitch-yaw: Rz(yaw) Ry(pitch) Rx(roll).
fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    *(nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), y)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), p)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), r))
    .matrix()
}

#[test]
fn iiwa7_scene_reproduces_the_iiwa_stack_urdf() {
    let s = scene("iiwa7");
    assert_eq!(s.nq(), 7);
    assert!(s.ball.is_none() && s.contact.is_none());
    let d: Vec<f64> = s.links.iter().map(|l| l.d).collect();
    assert_eq!(d, [0.34, 0.0, 0.4, 0.0, 0.4, 0.0, 0.126]);
    assert!(s.links.iter().all(|l| l.a == 0.0));
    let taus: Vec<f64> = s.links.iter().map(|l| l.tau_max.unwrap()).collect();
    assert_eq!(taus, [176.0, 176.0, 110.0, 110.0, 110.0, 40.0, 40.0]);
    let total: f64 = s.links.iter().map(|l| l.mass).sum();
    assert!((total - 17.5).abs() < 1e-12);

    // iiwa_stack iiwa7.xacro: joint origins (xyz, rpy), axes z; inertials in link frames.
    let h = PI / 2.0;
    let joints = [
        ([0.0, 0.0, 0.15], [0.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.19], [h, 0.0, PI]),
        ([0.0, 0.21, 0.0], [h, 0.0, PI]),
        ([0.0, 0.0, 0.19], [h, 0.0, 0.0]),
        ([0.0, 0.21, 0.0], [-h, PI, 0.0]),
        ([0.0, 0.0607, 0.19], [h, 0.0, 0.0]),
        ([0.0, 0.081, 0.0607], [-h, PI, 0.0]),
    ];
    let inertials = [
        (4.0, [0.0, -0.03, 0.12], [0.1, 0.09, 0.02]),
        (4.0, [0.0003, 0.059, 0.042], [0.05, 0.018, 0.044]),
        (3.0, [0.0, 0.03, 0.13], [0.08, 0.075, 0.01]),
        (2.7, [0.0, 0.067, 0.034], [0.03, 0.01, 0.029]),
        (1.7, [0.0001, 0.021, 0.076], [0.02, 0.018, 0.005]),
        (1.8, [0.0, 0.0006, 0.0004], [0.005, 0.0036, 0.0047]),
        (0.3, [0.0, 0.0, 0.02], [0.001, 0.001, 0.001]),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..20 {
        let q: Vec<f64> = (0..7).map(|_| rng.random_range(-3.0..3.0)).collect();
        let dh = dh_frames(
            homogeneous(s.base_rotation(), s.base_translation()),
            &table(&s),
            &q,
        );
        let mut t = Matrix4::<f64>::identity();
        for i in 0..7 {
            let (xyz, r) = joints[i];
            let mut j = Matrix4::identity();
            j.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&rpy(r[0], r[1], r[2]));
            j[(0, 3)] = xyz[0];
            j[(1, 3)] = xyz[1];
            j[(2, 3)] = xyz[2];
            t = t * j * Matrix4::new_rotation(Vector3::z() * q[i]);
            // Same joint axis and direction (q has KUKA's sign).
            let zu = t.fixed_view::<3, 1>(0, 2).into_owned();
            let zd = if i == 0 {
                Vector3::z()
            } else {
                dh[i - 1].fixed_view::<3, 1>(0, 2).into_owned()
            };
            assert!((zu - zd).norm() < 1e-9, "joint {} axis", i + 1);
            // World COG and world inertia of link i+1 agree.
            let (m, c, diag) = inertials[i];
            assert_eq!(s.links[i].mass, m);
            let cu = t.transform_point(&nalgebra::Point3::from(Vector3::from(c)));
            let cd = dh[i].transform_point(&nalgebra::Point3::from(Vector3::from(s.links[i].com)));
            assert!((cu - cd).norm() < 1e-9, "link {} COG", i + 1);
            let ru = t.fixed_view::<3, 3>(0, 0).into_owned();
            let rd = dh[i].fixed_view::<3, 3>(0, 0).into_owned();
            let iu = ru * Matrix3::from_diagonal(&Vector3::from(diag)) * ru.transpose();
            let li = s.link_inertia(i);
            let id = rd * Matrix3::from_fn(|r, k| li[r][k]) * rd.transpose();
            assert!((iu - id).norm() < 1e-9, "link {} inertia", i + 1);
        }
        // The flange (DH frame 7) is 0.045 m past the URDF link_7 frame along its z axis.
        let flange = t * Matrix4::new_translation(&Vector3::new(0.0, 0.0, 0.045));
        assert!((flange.fixed_view::<3, 1>(0, 3) - dh[6].fixed_view::<3, 1>(0, 3)).norm() < 1e-9);
    }
}

#[test]
fn constant_registry_has_fixed_order_and_matches_fields() {
    let s = scene("paper");
    let c = s.constants();
    let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        &names[..12],
        [
            "gravity.x",
            "gravity.y",
            "gravity.z",
            "base.translation.x",
            "base.translation.y",
            "base.translation.z",
            "link1.a",
            "link1.alpha",
            "link1.d",
            "link1.offset",
            "link1.mass",
            "link1.com.x",
        ]
    );
    // 3 gravity + 3 base + 14 per link (a, alpha, d, offset, mass, 3 com, 6 inertia)
    // + 11 ball (radius, 3 centre, mass, 6 inertia) + 4 friction.
    assert_eq!(c.len(), 6 + 14 * 3 + 11 + 4);
    let mut sorted = names.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), names.len(), "names are unique");
    let get = |n: &str| s.constant(n).unwrap_or_else(|| panic!("{n}"));
    assert_eq!(get("link2.inertia.yy"), 2.3177e-3);
    assert_eq!(get("link3.inertia.xz"), 0.0);
    assert_eq!(get("link1.alpha"), PI / 2.0);
    assert_eq!(get("link3.com.x"), -0.5);
    assert_eq!(get("base.translation.x"), 2.0);
    assert_eq!(get("ball.radius"), 1.0);
    assert!((get("ball.inertia.zz") - 0.008).abs() < 1e-18);
    assert_eq!(get("friction.socket_damping"), 0.004);
    assert_eq!(s.constant("link4.mass"), None);
    assert_eq!(
        s.constant("tool.translation.x"),
        None,
        "no tool in the paper scene"
    );
    // Arms without ball or friction have only the kinematic/inertial constants.
    let p = scene("iiwa7");
    assert_eq!(p.constants().len(), 6 + 14 * 7);
    assert_eq!(p.constant("link7.d"), Some(0.126));
}

#[test]
fn tool_transform_is_in_the_registry() {
    let text = format!(
        "{BASE}\n[tool]\ntranslation = [0.0, 0.0, 0.1]\nrotation = {{ axis = \"z\", angle = \"pi\" }}\n"
    );
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(s.tool_translation(), [0.0, 0.0, 0.1]);
    assert_eq!(
        s.tool_rotation(),
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert_eq!(s.constant("tool.translation.z"), Some(0.1));
    let text = format!("{BASE}\n[tool]\ntranslation = [0.0, 0.0]\n");
    let line = line_no(&text, "translation = [0.0, 0.0]", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "tool.translation",
        "invalid length 2",
    );
}

#[test]
fn validate_checks_scenes_built_in_code() {
    let mut s = Scene::from_toml_str(BASE, FILE).unwrap();
    assert!(s.validate("code").is_ok());
    s.links[0].mass = -1.0;
    let e = s.validate("code").unwrap_err();
    assert_eq!(
        e.to_string(),
        "code:1:1: links[0].mass: must be > 0 (got -1)"
    );
    s.links[0].mass = 1.0;
    s.links[1].alpha = Angle::PiMultiple { num: 1, den: 0 };
    assert_eq!(
        s.validate("code").unwrap_err().path(),
        Some("links[1].alpha")
    );
    s.links[1].alpha = "pi/2".parse().unwrap();
    s.kernels.push("contact".into());
    assert_eq!(s.validate("code").unwrap_err().path(), Some("kernels[3]"));
}

#[test]
fn positive_definiteness_does_not_depend_on_the_unit() {
    // Minors of diag(1e-300, …) underflow to 0 and of diag(1e300, …) overflow; both are valid.
    for v in ["1.0e-300", "1.0e300", "5.0e-320"] {
        let new = format!("inertia = [{v}, {v}, {v}]");
        let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, &new);
        let s = Scene::from_toml_str(&text, FILE).unwrap_or_else(|e| panic!("{new}: {e}"));
        assert!(s.warnings().is_empty(), "{new}: {:?}", s.warnings());
    }
    // A tiny but indefinite tensor is still rejected, with the unit-free minors in the message.
    let new =
        "inertia = [[1.0e-300, 3.0e-300, 0.0], [3.0e-300, 2.0e-300, 0.0], [0.0, 0.0, 2.0e-300]]";
    let old = "inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]";
    let text = edit(old, 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[1].inertia",
        "positive definite",
    );
}

#[test]
fn impossible_inertias_and_friction_are_warned_about() {
    assert!(
        Scene::from_toml_str(BASE, FILE)
            .unwrap()
            .warnings()
            .is_empty()
    );
    // Izz > Ixx + Iyy: violates the triangle inequality (a diagonal link inertia).
    let text = edit(
        "inertia = [1.0e-3, 2.0e-3, 2.0e-3]",
        0,
        "inertia = [1.0e-3, 1.0e-3, 2.5e-3]",
    );
    let w = Scene::from_toml_str(&text, FILE).unwrap().warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("links[0].inertia: ")
            && w[0].contains("triangle")
            && w[0].contains("2.5e-3"),
        "{w:?}"
    );
    // The same moments rotated into a full tensor (principal axes not the link axes), and a
    // thin plate (equality, allowed up to rounding of the decimal input).
    let (c, s) = (0.6f64, 0.8f64);
    let (a, b) = (1.0e-3, 2.5e-3);
    let full = format!(
        "inertia = [[{}, {}, 0.0], [{}, {}, 0.0], [0.0, 0.0, 1.0e-3]]",
        a * c * c + b * s * s,
        (a - b) * c * s,
        (a - b) * c * s,
        a * s * s + b * c * c
    );
    let old = "inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]";
    let w = Scene::from_toml_str(&edit(old, 0, &full), FILE)
        .unwrap()
        .warnings();
    assert!(
        w.len() == 1 && w[0].starts_with("links[1].inertia: "),
        "{w:?}"
    );
    let plate = "inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 3.0e-3]]";
    let scene = Scene::from_toml_str(&edit(old, 0, plate), FILE).unwrap();
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    // Ball inertia.
    let text = edit("mass = 0.02", 2, "mass = 0.02\ninertia = [1.0, 1.0, 2.5]");
    let w = Scene::from_toml_str(&text, FILE).unwrap().warnings();
    assert!(w.len() == 1 && w[0].starts_with("ball.inertia: "), "{w:?}");
    // Kinetic friction above static friction: a warning naming both values, not an error.
    let text = edit("mu_k = 0.6", 0, "mu_k = 0.9");
    let w = Scene::from_toml_str(&text, FILE).unwrap().warnings();
    assert_eq!(
        w,
        ["friction.mu_k = 0.9 > friction.mu_s = 0.8: kinetic friction above static friction"]
    );
}

#[test]
fn shipped_scenes_warn_only_about_published_puma_data() {
    for name in ["paper", "human", "iiwa7", "puma560"] {
        let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let w = Scene::load(&path).unwrap().warnings();
        if name == "puma560" {
            // Link 1's placeholder moments (only Iyy enters the dynamics) and Armstrong's link 3
            // (0.086 > 0.066 + 0.0125).
            assert_eq!(w.len(), 2, "{w:?}");
            assert!(w[0].starts_with("links[0].inertia") && w[1].starts_with("links[2].inertia"));
        } else {
            assert!(w.is_empty(), "{name}: {w:?}");
        }
    }
}

#[test]
fn overflowing_scene_values_are_refused_by_generate_and_eval() {
    let text = edit("a = 1.0", 0, "a = 1.0e308");
    let scene = Scene::from_toml_str(&text, FILE).unwrap();
    let err = bf_codegen::generate(&scene, &text).unwrap_err().to_string();
    assert!(
        err.contains("non-finite") && err.contains("link1.a = 1e308"),
        "{err}"
    );
    let err = bf_codegen::eval_all(&scene, &[0.1, 0.2], &[0.0, 0.0], [0.0; 3], 0.01)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("not finite") && err.contains("link1.a = 1e308"),
        "{err}"
    );
    // A huge velocity: C q̇ overflows; the quantity is named.
    let scene = Scene::from_toml_str(BASE, FILE).unwrap();
    let err = bf_codegen::eval_all(&scene, &[0.1, 0.2], &[1e200, 1e200], [0.0; 3], 0.01)
        .unwrap_err()
        .to_string();
    assert!(err.contains("Cqd is not finite"), "{err}");
}
