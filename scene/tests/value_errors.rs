//! Scene files that parse but break a semantic rule: masses, inertias (symmetric positive
//! definite), kernel and cost lists, runtime parameters, names, friction, ball, joint limits,
//! rotations, contact kinds, the contact link and angle strings; each error names the line, key path and value.

mod common;

use bf_scene::{Angle, KNOWN_KERNELS, RotationSpec, Scene, SpecErrorKind};
use common::*;
use std::f64::consts::PI;

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

/// A body whose principal moments are each finite but overflow when summed (the trace M(q)
/// adds up) is refused itself, not the other bodies that look negligible beside its infinite
/// trace.
#[test]
fn an_inertia_whose_trace_overflows_is_named() {
    let new = "inertia = [1e308, 1e308, 1e308]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, new);
    let line = line_no(&text, new, 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].inertia",
        "overflow f64 when summed",
    );
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
    // All zero (a point mass): said in words, not as minors of I / 0, which are NaN.
    let new = "inertia = [0.0, 0.0, 0.0]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, new);
    let line = line_no(&text, new, 0);
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[0].inertia",
        "inertia must be positive definite (it is zero: a point mass has no rotational inertia)",
    );
    assert!(!shown.contains("NaN"), "{shown}");
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
fn the_contact_link_turns_about_a_revolute_joint_and_has_a_length() {
    // The last link's `a = 1.0` (the second such line) and its joint.
    let new = "a = 1.0\njoint = \"prismatic\"";
    let text = edit("a = 1.0", 1, new);
    let line = line_no(&text, "joint = \"prismatic\"", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "links[1].joint",
        "revolute last joint",
    );
    for a in ["a = 0.0", "a = -0.5"] {
        let text = edit("a = 1.0", 1, a);
        let line = line_no(&text, a, 0);
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line,
            "links[1].a",
            "length a > 0",
        );
    }
    // A prismatic joint elsewhere, or a zero-length last link of an arm without a ball, is fine.
    let text = edit("a = 1.0", 0, "a = 1.0\njoint = \"prismatic\"");
    assert!(Scene::from_toml_str(&text, FILE).is_ok());
    let arm = edit("a = 1.0", 1, "a = 0.0");
    let arm = arm[..arm.find("[ball]").unwrap()].replace(", \"contact\"]", "]");
    if let Err(e) = Scene::from_toml_str(&arm, FILE) {
        panic!("{e}");
    }
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

/// ε of the saturation sqrt(x² + ε²) (eq. 59) from `MIN_SMOOTH_EPS` to `MAX_SMOOTH_EPS`: the
/// square of the largest (plus any squared distance up to 1e100 m) stays finite, and that of
/// the smallest a normal number, so the derivative x / sqrt(x² + ε²) is defined at x = 0; beyond
/// them, and at 0, the file is refused, with the range the constants give.
#[test]
fn smooth_eps_keeps_its_square_finite_and_normal() {
    let (min, max) = (bf_scene::MIN_SMOOTH_EPS, bf_scene::MAX_SMOOTH_EPS);
    assert!((max * max + 1e200).sqrt().is_finite());
    assert!(!((1e5 * max) * (1e5 * max)).is_finite());
    assert!((min * min).is_normal());
    assert!(!((1e-5 * min) * (1e-5 * min)).is_normal());
    let slope_at_zero = |eps: f64| 0.0 / (eps * eps).sqrt();
    assert!(slope_at_zero(min).is_finite() && slope_at_zero(1e-170).is_nan());
    assert!(bf_scene::smooth_eps_out_of_range(2.0 * max).is_some());
    assert!(bf_scene::smooth_eps_out_of_range(0.5 * min).is_some());
    assert_eq!(bf_scene::smooth_eps_out_of_range(max), None);
    assert_eq!(bf_scene::smooth_eps_out_of_range(min), None);
    let range = format!("[{min:e}, {max:e}]");
    assert!(bf_scene::SMOOTH_EPS_RANGE.contains(&range), "{range}");
    for bad in ["1e200", "0.0", "-0.01", "1e-320"] {
        let new = format!("smooth_eps = {bad}");
        let text = edit("smooth_eps = 0.01", 0, &new);
        let line = line_no(&text, &new, 0);
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line,
            "contact.smooth_eps",
            &range,
        );
    }
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

/// [`BASE`] with a `[tool]` table of the given body appended.
fn with_tool(body: &str) -> String {
    format!("{BASE}\n[tool]\n{body}\n")
}

#[test]
fn the_contact_segment_must_run_along_the_tip_frames_x_axis_to_the_last_joint() {
    // Without a tool the segment is the last link: start (-a_n, 0, 0), l = a_n.
    let s = Scene::from_toml_str(BASE, FILE).unwrap();
    assert_eq!(s.contact_segment_start(), Some([-1.0, 0.0, 0.0]));
    assert_eq!(s.contact_segment_length(), Some(Ok(1.0)));
    // A tool that turns the tip frame about z and lifts it: the tip frame's x axis no longer
    // runs along the last link, so the segment p_e - l e_x would not be the link.
    let text =
        with_tool("translation = [0.0, 0.0, 0.3]\nrotation = { axis = \"z\", angle = \"pi/2\" }");
    let line = line_no(&text, "[tool]", 0);
    let shown = expect_err(&text, SpecErrorKind::Invalid, line, "tool", "(-l, 0, 0)");
    assert!(shown.contains("[0.0, 1.0, -0.3]"), "{shown}");
    // Moved sideways off the link's line: refused too.
    let text = with_tool("translation = [0.1, 0.01, 0.0]");
    let line = line_no(&text, "[tool]", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "tool",
        "tip frame's x axis",
    );
    // Extending the finger along x lengthens the segment; a tool that only turns the frame
    // about x leaves it as it is; with tip contact there is no segment to check.
    let s = Scene::from_toml_str(&with_tool("translation = [0.1, 0.0, 0.0]"), FILE).unwrap();
    assert_eq!(s.contact_segment_length(), Some(Ok(1.1)));
    let s = Scene::from_toml_str(
        &with_tool("rotation = { axis = \"x\", angle = \"pi/3\" }"),
        FILE,
    )
    .unwrap();
    assert_eq!(s.contact_segment_length(), Some(Ok(1.0)));
    let tip = with_tool("rotation = { axis = \"z\", angle = \"pi/2\" }")
        .replace("kind = \"segment\"", "kind = \"tip\"");
    assert!(Scene::from_toml_str(&tip, FILE).is_ok());
}

#[test]
fn segment_contact_on_modified_dh_is_refused_at_the_contact_kind() {
    let text = BASE.replace(
        "name = \"test_scene\"",
        "name = \"test_scene\"\ndh = \"modified\"",
    );
    let line = line_no(&text, "kind = \"segment\"", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "contact.kind",
        "modified DH table does not hold",
    );
    assert!(Scene::from_toml_str(&text.replace("\"segment\"", "\"tip\""), FILE).is_ok());
}

#[test]
fn a_baked_segment_length_cannot_be_a_runtime_parameter() {
    let runtime = |text: &str, names: &str| {
        text.replace(
            "gravity = [0.0, 0.0, -9.81]",
            &format!("gravity = [0.0, 0.0, -9.81]\nruntime_parameters = [{names}]"),
        )
    };
    // Without a tool l is link2.a itself, which may stay a runtime parameter.
    let s = Scene::from_toml_str(&runtime(BASE, "\"link2.a\""), FILE).unwrap();
    assert!(s.is_runtime("link2.a"));
    // With a tool the kernels bake l = a_2 + 0.1 in.
    let text = runtime(
        &with_tool("translation = [0.1, 0.0, 0.0]"),
        "\"ball.radius\", \"link2.a\"",
    );
    let line = line_no(
        &text,
        "runtime_parameters = [\"ball.radius\", \"link2.a\"]",
        0,
    );
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "runtime_parameters[1]",
        "bake the segment's length in (l = 1.1 m",
    );
    assert!(shown.contains("\"link2.a\""), "{shown}");
    // A tool translation places the tip, whatever the tool.
    let text = runtime(
        &with_tool("translation = [0.0, 0.0, 0.0]"),
        "\"tool.translation.x\"",
    );
    let line = line_no(&text, "runtime_parameters = [\"tool.translation.x\"]", 0);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line,
        "runtime_parameters[0]",
        "places the tip",
    );
    // Neither matters for tip contact, nor does link1.a.
    assert!(Scene::from_toml_str(&text.replace("\"segment\"", "\"tip\""), FILE).is_ok());
    let text = runtime(&with_tool("translation = [0.1, 0.0, 0.0]"), "\"link1.a\"");
    assert!(Scene::from_toml_str(&text, FILE).is_ok());
    // Scenes built in code are checked alike.
    let mut s = Scene::from_toml_str(&with_tool("translation = [0.1, 0.0, 0.0]"), FILE).unwrap();
    s.runtime_parameters.push("link2.a".into());
    assert_eq!(
        s.validate("code").unwrap_err().path(),
        Some("runtime_parameters[0]")
    );
}

#[test]
fn a_prismatic_joints_limits_are_plain_lengths() {
    let prismatic = BASE.replacen("a = 1.0\n", "joint = \"prismatic\"\na = 1.0\n", 1);
    for (old, new, key) in [
        ("q_min = -1.0", "q_min = \"-90deg\"", "links[0].q_min"),
        ("q_max = 1.0", "q_max = \"pi/2\"", "links[0].q_max"),
        ("q_min = -1.0", "q_min = '-pi'", "links[0].q_min"),
    ] {
        let text = prismatic.replacen(old, new, 1);
        let line = line_no(&text, new, 0);
        expect_err(
            &text,
            SpecErrorKind::WrongType,
            line,
            key,
            "length in metres",
        );
    }
    // Plain numbers are metres; a revolute joint still takes angles.
    let s = Scene::from_toml_str(
        &prismatic.replacen("q_min = -1.0", "q_min = -0.25", 1),
        FILE,
    )
    .unwrap();
    assert_eq!(
        (s.links[0].q_min, s.links[0].q_max),
        (Some(-0.25), Some(1.0))
    );
    let s = Scene::from_toml_str(&edit("q_min = -1.0", 0, "q_min = \"-90deg\""), FILE).unwrap();
    assert_eq!(s.links[0].q_min, Some(-PI / 2.0));
}

#[test]
fn scene_names_the_generated_crate_takes_are_refused() {
    for (bad, needle) in [
        ("ocp", "optimal-control node kernels"),
        ("registry", "registry"),
        ("modules", "modules.rs"),
        ("ocp_kernels", "ocp_kernels.rs"),
        ("SceneKernels", "type"),
        ("NodeKernel", "type"),
        ("paper_f32", "variant module of the `paper` scene"),
        ("paper_runtime", "variant module"),
        ("std", "standard library"),
        ("core", "core library"),
        ("alloc", "alloc library"),
    ] {
        let new = format!("name = \"{bad}\"");
        let text = edit("name = \"test_scene\"", 0, &new);
        let shown = expect_err(&text, SpecErrorKind::Invalid, 1, "name", needle);
        assert!(
            shown.contains("clashes with the generated crate"),
            "{shown}"
        );
    }
    // The crate's functions and statics do not clash with a module; nor do near misses.
    for good in ["scene", "scene_toml", "paper_f64", "ocp2", "Registry"] {
        let text = edit("name = \"test_scene\"", 0, &format!("name = \"{good}\""));
        assert!(Scene::from_toml_str(&text, FILE).is_ok(), "{good}");
    }
}

/// The reserved names are those `bf-generated` defines: every module and type at the root of
/// its `src/lib.rs`, every file its build script writes to `OUT_DIR` by a fixed name, and
/// every variant module it emits for `paper`. A new one added there without reserving it here
/// fails this test.
#[test]
fn reserved_scene_names_cover_what_the_generated_crate_defines() {
    let dir = format!("{}/../generated", env!("CARGO_MANIFEST_DIR"));
    let lib = std::fs::read_to_string(format!("{dir}/src/lib.rs")).unwrap();
    let build = std::fs::read_to_string(format!("{dir}/build.rs")).unwrap();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut defined = Vec::new();
    for line in lib.lines() {
        for kw in [
            "pub mod ",
            "mod ",
            "pub struct ",
            "pub type ",
            "pub enum ",
            "pub trait ",
        ] {
            if let Some(rest) = line.strip_prefix(kw) {
                defined.push(ident(rest));
            }
        }
    }
    for (i, _) in build.match_indices("out.join(\"") {
        let rest = &build[i + "out.join(\"".len()..];
        let file = ident(rest);
        if rest[file.len()..].starts_with(".rs\"") {
            defined.push(file);
        }
    }
    for (i, _) in build.match_indices("named(\"") {
        defined.push(format!("paper_{}", ident(&build[i + "named(\"".len()..])));
    }
    for want in [
        "ocp",
        "registry",
        "modules",
        "ocp_kernels",
        "SceneKernels",
        "paper_fma",
    ] {
        assert!(
            defined.iter().any(|d| d == want),
            "{want} not found in {defined:?}"
        );
    }
    for d in &defined {
        assert!(
            bf_scene::reserved_scene_name(d).is_some(),
            "bf-generated defines `{d}`, which scene names may still take"
        );
    }
}

#[test]
fn a_dh_convention_on_placement_links_is_refused() {
    let placement = "name = \"p\"\ndh = \"modified\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n\n[[links]]\naxis = [0.0, 0.0, 1.0]\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n";
    for dh in ["dh = \"modified\"", "dh = \"standard\""] {
        let text = placement.replace("dh = \"modified\"", dh);
        let err = Scene::from_toml_str(&text, "p.toml").unwrap_err();
        assert_eq!((err.path(), err.line()), (Some("dh"), Some(2)), "{err}");
        assert!(err.to_string().contains("placement form"), "{err}");
    }
    let text = placement.replace("dh = \"modified\"\n", "");
    assert!(Scene::from_toml_str(&text, "p.toml").is_ok());
}

/// A DH angle beyond ±2²⁰ rad, where the kernels' sine and cosine are defined, is refused at
/// its line (as a runtime parameter it would make every kernel output NaN).
#[test]
fn dh_angles_stay_within_the_kernels_range() {
    for new in ["alpha = 2e6", "alpha = -1.1e6"] {
        let text = edit("alpha = 0.0", 0, new);
        let line = line_no(&text, new, 0);
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line,
            "links[1].alpha",
            "beyond ±2²⁰",
        );
    }
    // Within it, any angle is taken.
    let text = edit("alpha = 0.0", 0, "alpha = 1e6");
    assert!(Scene::from_toml_str(&text, "paper.toml").is_ok());
}
