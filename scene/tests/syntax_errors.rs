//! Scene files that do not parse: every error names the file, the right line and column and
//! the key path (`FILE:LINE:COLUMN: PATH: message`) — syntax, unknown and missing keys, wrong
//! types and shapes, non-finite numbers, unreadable files.

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

mod common;

use bf_scene::{Scene, SpecError, SpecErrorKind};
use common::*;

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
fn io_error_names_the_file() {
    let err = Scene::load("/nonexistent/dir/scene.toml").unwrap_err();
    assert!(matches!(err, SpecError::Io { .. }));
    assert!(
        err.to_string().starts_with("/nonexistent/dir/scene.toml: "),
        "{err}"
    );
    // The reason is in the message itself, which a build script prints alone
    // (`panic!("{e}")`), and not also a source, so that a printed chain states it once.
    let shown = err.to_string();
    assert!(shown.contains("No such file"), "{shown}");
    assert!(std::error::Error::source(&err).is_none(), "{err:?}");
}

#[test]
fn load_reports_the_path_in_errors() {
    let dir =
        TempDir::fresh(std::env::temp_dir().join(format!("bf_spec_test_{}", std::process::id())));
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
