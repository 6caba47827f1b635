//! URDF import errors: each names the file, the line (and column) of the offending element, the
//! element and the attribute; and the TOML side of `urdf = ...` scenes (placement-form links,
//! the keys that conflict with an imported chain, line numbers kept for the user's part).

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

use bf_scene::{ChainChoice, Scene, SpecError, read_urdf_chain};

const FILE: &str = "robot.urdf";

/// A two-joint arm; `{J2}` is replaced by the second joint's element.
const ARM: &str = r#"<robot name="arm">
  <link name="base"/>
  <link name="l1">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="l2">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/></joint>
  {J2}
</robot>
"#;

const J2: &str = r#"<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>"#;

fn arm(j2: &str) -> String {
    ARM.replace("{J2}", j2)
}

/// The error of reading `text`, checked to be a URDF error at `line` on `element`/`attribute`
/// whose message contains `needle`.
fn expect(
    text: &str,
    tip: Option<&str>,
    line: usize,
    element: &str,
    attribute: &str,
    needle: &str,
) {
    let err = read_urdf_chain(text, FILE, None, tip, None).unwrap_err();
    let shown = err.to_string();
    match &err {
        SpecError::Urdf(u) => {
            let (file, l, e, a, message) = (&u.file, &u.line, &u.element, &u.attribute, &u.message);
            assert_eq!(file, FILE, "{shown}");
            assert_eq!(*l, line, "{shown}");
            assert_eq!((e.as_str(), a.as_str()), (element, attribute), "{shown}");
            assert!(message.contains(needle), "{shown} lacks {needle:?}");
            assert!(shown.starts_with(&format!("{FILE}:{line}:")), "{shown}");
        }
        other => panic!("not a URDF error: {other}"),
    }
}

#[test]
fn the_valid_arm_reads() {
    let c = read_urdf_chain(&arm(J2), FILE, None, None, None).unwrap();
    assert_eq!(c.joint_names, ["j1", "j2"]);
    assert_eq!(
        c.links[1].origin.as_ref().unwrap().translation,
        Some([1.0, 0.0, 0.0])
    );
    assert_eq!(c.links[1].com, [0.5, 0.0, 0.0]);
}

#[test]
fn a_moving_link_without_inertial() {
    let text = arm(J2).replace(
        r#"<inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#,
        "",
    );
    expect(
        &text,
        None,
        6,
        "link",
        "inertial",
        "link \"l2\" (moved by joint \"j2\") has no <inertial>",
    );
}

#[test]
fn an_inertial_without_mass_and_a_bad_mass() {
    let text = arm(J2).replacen(r#"<mass value="1"/>"#, "", 1);
    expect(&text, None, 4, "inertial", "mass", "no <mass>");
    let text = arm(J2).replacen(r#"<mass value="1"/>"#, r#"<mass value="-2"/>"#, 1);
    expect(&text, None, 4, "mass", "value", "mass must be > 0 (got -2)");
}

/// A second `<inertial>` of a link or `<axis>` of a joint is refused at its own line: taking
/// the first silently would drop what the author meant (a duplicated `<inertial>` changed M).
#[test]
fn a_second_element_where_the_urdf_allows_one_is_refused() {
    let inertial = r#"<inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#;
    let text = arm(J2).replacen(inertial, &format!("{inertial}\n    {inertial}"), 1);
    assert_ne!(text, arm(J2));
    expect(
        &text,
        None,
        8,
        "inertial",
        "",
        "<link> has a second <inertial>",
    );
    let text = arm(&J2.replace(
        r#"<axis xyz="0 0 1"/>"#,
        "<axis xyz=\"0 0 1\"/>\n<axis xyz=\"1 0 0\"/>",
    ));
    expect(&text, None, 11, "axis", "", "<joint> has a second <axis>");
}

#[test]
fn unknown_and_unsupported_joint_types() {
    expect(
        &arm(&J2.replace("revolute", "hinge")),
        None,
        10,
        "joint",
        "type",
        "unknown joint type \"hinge\"",
    );
    expect(
        &arm(&J2.replace("revolute", "floating")),
        None,
        10,
        "joint",
        "type",
        "not supported",
    );
}

#[test]
fn bad_numbers_name_the_attribute_and_the_value() {
    expect(
        &arm(&J2.replace("xyz=\"1 0 0\"", "xyz=\"1 zero 0\"")),
        None,
        10,
        "origin",
        "xyz",
        "\"zero\" is not a finite number",
    );
    expect(
        &arm(&J2.replace("xyz=\"1 0 0\"", "xyz=\"1 0\"")),
        None,
        10,
        "origin",
        "xyz",
        "expected 3 number(s)",
    );
    expect(
        &arm(&J2.replace("xyz=\"1 0 0\"", "xyz=\"1 0 nan\"")),
        None,
        10,
        "origin",
        "xyz",
        "not a finite number",
    );
    // Exactly zero (of either sign) has no direction; NaN and inf are no numbers to take one
    // from.
    for (axis, needle) in [
        ("0 0 0", "must not be zero"),
        ("-0 0 -0", "must not be zero"),
        ("0 NaN 1", "\"NaN\" is not a finite number"),
        ("0 inf 1", "\"inf\" is not a finite number"),
    ] {
        expect(
            &arm(&J2.replace("0 0 1", axis)),
            None,
            10,
            "axis",
            "xyz",
            needle,
        );
    }
}

/// The URDF text of the arm with the second joint's axis `xyz`, read into a scene: the axis it
/// got, after the scene's own validation (which wants a unit axis) accepted it.
fn imported_axis(xyz: &str) -> [f64; 3] {
    let text = arm(&J2.replace("0 0 1", xyz));
    let toml = bf_scene::urdf_scene_text(&text, FILE, &ChainChoice::default())
        .unwrap_or_else(|e| panic!("{xyz}: {e}"));
    let scene = Scene::from_toml_str(&toml, FILE).unwrap_or_else(|e| panic!("{xyz}: {e}"));
    scene.links[1].axis.unwrap()
}

/// A joint's name is a label: any characters the URDF's XML holds reach the scene as they are,
/// through the scene text the import writes (combining marks, no-break and zero-width spaces,
/// quotes and backslashes once made a TOML syntax error of a valid URDF).
#[test]
fn a_joint_name_of_any_characters_reaches_the_scene_as_it_is() {
    for (xml, name) in [
        ("coude&#x301;", "coude\u{301}"),
        ("j&#xA0;2", "j\u{a0}2"),
        ("j&#xAD;2&#x200B;", "j\u{ad}2\u{200b}"),
        (
            "say &quot;hi&quot; \\ back\\slash",
            "say \"hi\" \\ back\\slash",
        ),
        ("Ellenbogen ÄÖÜ 肘", "Ellenbogen ÄÖÜ 肘"),
    ] {
        let text = arm(&J2.replace("name=\"j2\"", &format!("name=\"{xml}\"")));
        let toml = bf_scene::urdf_scene_text(&text, FILE, &ChainChoice::default())
            .unwrap_or_else(|e| panic!("{name:?}: {e}"));
        let scene = Scene::from_toml_str(&toml, FILE).unwrap_or_else(|e| panic!("{name:?}: {e}"));
        assert_eq!(scene.links[1].name.as_deref(), Some(name), "{toml}");
    }
}

/// Any finite non-zero axis has a direction (urdfdom normalises it too): neither huge
/// components, whose squares overflow, nor tiny ones, whose squares underflow, lose it, and no
/// length cut-off refuses a short one.
#[test]
fn an_axis_of_any_finite_non_zero_length_gives_its_direction() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for (xyz, want) in [
        ("1e200 1e200 0", [h, h, 0.0]),
        ("1e155 0 0", [1.0, 0.0, 0.0]),
        ("1.7e308 -1.7e308 0", [h, -h, 0.0]),
        ("0 0 1e-10", [0.0, 0.0, 1.0]),
        ("0 0 -1e-170", [0.0, 0.0, -1.0]),
        ("0 1e-200 1e-200", [0.0, h, h]),
        ("5e-324 0 0", [1.0, 0.0, 0.0]),
        ("0 1e-5 1e-5", [0.0, h, h]),
        ("0 0 -3", [0.0, 0.0, -1.0]),
    ] {
        let a = imported_axis(xyz);
        for k in 0..3 {
            assert!(
                (a[k] - want[k]).abs() <= 2e-16,
                "{xyz}: got {a:?}, want {want:?}"
            );
        }
    }
    // Exactly as the URDF reader gives it, before the scene's text: a unit vector.
    let c = read_urdf_chain(
        &arm(&J2.replace("0 0 1", "3e-300 4e-300 0")),
        FILE,
        None,
        None,
        None,
    )
    .unwrap();
    let a = c.links[1].axis.unwrap();
    assert!(
        (a[0] - 0.6).abs() <= 1e-16 && (a[1] - 0.8).abs() <= 1e-16,
        "{a:?}"
    );
}

/// A zero inertia tensor on a link of positive mass is refused in words, at the `<inertia>`
/// the user wrote: the link's own, or that of the link fixed to it that brings the mass.
#[test]
fn a_zero_inertia_with_a_positive_mass_is_named_as_such() {
    let text = arm_with_l2_inertia("0", "0", "0");
    expect(
        &text,
        None,
        7,
        "inertia",
        "",
        "link \"l2\", moved by joint \"j2\": the inertia is zero while the mass is 1 kg > 0",
    );
    let err = read_urdf_chain(&text, FILE, None, None, None).unwrap_err();
    assert!(!err.to_string().contains("NaN"), "{err}");
    // l2 carries nothing itself; its mass, a point, comes from the link fixed to it.
    let point = r#"<inertial><mass value="2"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>"#;
    let text = arm(&format!(
        "{J2}\n  <link name=\"l2b\">\n    {point}\n  </link>\n  <joint name=\"f\" type=\"fixed\"><parent link=\"l2\"/><child link=\"l2b\"/></joint>"
    ))
    .replace(L2_INERTIAL, "");
    expect(
        &text,
        None,
        12,
        "inertia",
        "",
        "link \"l2\", moved by joint \"j2\": the inertia is zero while the mass is 2 kg > 0 \
         (the <inertia> of link \"l2b\", fixed to it)",
    );
    // A point mass lumped into a link with a rotational inertia of its own is a body.
    let text = arm(&format!(
        "{J2}\n  <link name=\"l2b\">{point}</link>\n  <joint name=\"f\" type=\"fixed\"><parent link=\"l2\"/><child link=\"l2b\"/><origin xyz=\"0.5 0 0\"/></joint>"
    ));
    let c = read_urdf_chain(&text, FILE, None, None, None).unwrap();
    assert_eq!((c.links[1].mass, c.links[1].com), (3.0, [0.5, 0.0, 0.0]));
}

/// Two finite inertias can add up to more than f64 holds: the lumped tensor's inf is named, not
/// hidden behind the NaN minors of I / inf.
#[test]
fn a_lumped_inertia_that_overflows_is_named_as_such() {
    let huge = r#"<inertial><mass value="1"/><inertia ixx="1e308" ixy="0" ixz="0" iyy="1e308" iyz="0" izz="1e308"/></inertial>"#;
    let text = with_fixed_link(
        &arm_with_l2_inertia("1e308", "1e308", "1e308"),
        "l2",
        "l2b",
        huge,
    );
    expect(
        &text,
        None,
        6,
        "link",
        "inertial",
        "link \"l2\" (with the links fixed to it), moved by joint \"j2\": inertia must be \
         positive definite and finite (an entry is inf)",
    );
}

/// `<inertial>` of the second link in `ARM`.
const L2_INERTIAL: &str = r#"<inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#;

/// A dummy link's `<inertial>` as published URDFs write it: mass 0, a zero inertia, and an
/// origin that must not move any COG.
const DUMMY: &str = r#"<inertial><origin xyz="0.3 0.1 0" rpy="0 1 0"/><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>"#;

/// The arm with a link `name` fixed to `parent` (0.2 m along x) whose body is `inertial`.
fn with_fixed_link(text: &str, parent: &str, name: &str, inertial: &str) -> String {
    text.replace(
        "</robot>",
        &format!(
            "  <link name=\"{name}\">{inertial}</link>\n  <joint name=\"fix_{name}\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"{name}\"/><origin xyz=\"0.2 0 0\"/></joint>\n</robot>"
        ),
    )
}

/// A link whose `<inertial>` has mass 0 and a zero inertia reads exactly as one without
/// `<inertial>`, wherever it is: fixed to the base (dropped), lumped into a moving link, or
/// moved itself with the mass of a link fixed to it; and a moving one with no mass in front
/// is refused as a link without `<inertial>` is.
#[test]
fn a_massless_dummy_link_reads_as_one_without_inertial() {
    let read = |t: &str| read_urdf_chain(t, FILE, None, None, None);
    let same = |with_dummy: &str, without: &str| {
        assert_ne!(with_dummy, without);
        let (a, b) = (read(with_dummy).unwrap(), read(without).unwrap());
        assert_eq!(a, b);
        // The dummy's origin moved no COG and its zero mass added none.
        assert_eq!((a.links[1].mass, a.links[1].com), (1.0, [0.5, 0.0, 0.0]));
        // The scene's own validation takes it too.
        let toml = bf_scene::urdf_scene_text(with_dummy, FILE, &ChainChoice::default()).unwrap();
        Scene::from_toml_str(&toml, FILE).unwrap();
    };
    // On the base: dropped.
    let base = arm(J2).replace(
        "<link name=\"base\"/>",
        &format!("<link name=\"base\">{DUMMY}</link>"),
    );
    same(&base, &arm(J2));
    // A root fixed to the base: dropped with it.
    let mounted = |inertial: &str| {
        arm(J2).replace(
            "</robot>",
            &format!(
                "  <link name=\"world\">{inertial}</link>\n  <joint name=\"mount\" type=\"fixed\"><parent link=\"world\"/><child link=\"base\"/><origin xyz=\"0 0 0.4\"/></joint>\n</robot>"
            ),
        )
    };
    same(&mounted(DUMMY), &mounted(""));
    // Lumped into the moving link l2 (the tip then is the dummy, hence the tool).
    same(
        &with_fixed_link(&arm(J2), "l2", "flange", DUMMY),
        &with_fixed_link(&arm(J2), "l2", "flange", ""),
    );
    // Moved by j2, with its mass from the link fixed to it: l2's body moved to "l2b", 0.2 m
    // out, so its inertial origin goes 0.2 m back.
    let moved_body = L2_INERTIAL.replace("0.5 0 0", "0.3 0 0");
    let moving =
        |l2: &str| with_fixed_link(&arm(J2), "l2", "l2b", &moved_body).replace(L2_INERTIAL, l2);
    same(&moving(DUMMY), &moving(""));
    // Moved by j2, with nothing fixed to it: no mass, as without <inertial>.
    expect(
        &arm(J2).replace(L2_INERTIAL, DUMMY),
        None,
        6,
        "link",
        "inertial",
        "link \"l2\" (moved by joint \"j2\") has mass 0 (a massless <inertial>, as none), nor \
         has any link fixed to it: a moving link needs a mass",
    );
}

/// Mass 0 with an inertia is no dummy but a contradiction: refused at the `<mass>`.
#[test]
fn a_zero_mass_with_an_inertia_is_refused() {
    for (mass, entry) in [("0", r#"ixx="0.1""#), ("-0", r#"iyz="1e-300""#)] {
        let inertial = DUMMY
            .replace(r#"value="0""#, &format!(r#"value="{mass}""#))
            .replace(&format!("{}=\"0\"", &entry[..3]), entry);
        assert_ne!(inertial, DUMMY);
        expect(
            &with_fixed_link(&arm(J2), "base", "pedestal", &inertial),
            None,
            11,
            "mass",
            "value",
            "link \"pedestal\": mass is 0 but its <inertia> is not zero; give the mass, or zero \
             the inertia too for a massless link (as one without <inertial>)",
        );
    }
}

#[test]
fn a_link_not_on_any_chain() {
    // A second tree under `base`'s sibling root is refused as a second root; a tip that is
    // not below the base is not on any chain.
    let text = arm(J2).replace(
        "<link name=\"base\"/>",
        "<link name=\"base\"/>\n  <link name=\"stray\"/>",
    );
    expect(&text, None, 3, "link", "name", "form 2 trees");
    let err = read_urdf_chain(&arm(J2), FILE, Some("l2"), Some("l1"), None).unwrap_err();
    assert!(
        err.to_string()
            .contains("link \"l1\" is not on any chain from base link \"l2\""),
        "{err}"
    );
    let err = read_urdf_chain(&arm(J2), FILE, None, Some("nope"), None).unwrap_err();
    assert!(
        err.to_string()
            .contains("tip link \"nope\" is not a link of the robot"),
        "{err}"
    );
}

#[test]
fn a_joint_name_used_twice_is_refused() {
    // The second joint named like the first: the line of the second.
    let twice = J2.replace("name=\"j2\"", "name=\"j1\"");
    expect(
        &arm(&twice),
        None,
        10,
        "joint",
        "name",
        "joint \"j1\" is defined twice",
    );
}

#[test]
fn loops_are_refused() {
    // l2 → l1 closes the loop l1 → l2 → l1 (l1 then has two parents).
    let closing = format!(
        "{J2}\n  <joint name=\"back\" type=\"fixed\"><parent link=\"l2\"/><child link=\"l1\"/></joint>"
    );
    expect(&arm(&closing), None, 11, "joint", "child", "closed loop");
    // A cycle with one parent each: base is then no root, and the cycle is found.
    let text = arm(J2).replace(
        "<joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/>",
        "<joint name=\"j1\" type=\"revolute\"><parent link=\"l2\"/>",
    );
    let err = read_urdf_chain(&text, FILE, None, None, None).unwrap_err();
    assert!(err.to_string().contains("the joints form a loop"), "{err}");
}

#[test]
fn malformed_xml_and_a_wrong_root() {
    let err = read_urdf_chain(
        "<robot name=\"x\">\n<link name=\"a\">\n</robot>",
        FILE,
        None,
        None,
        None,
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("robot.urdf:3:"), "{err}");
    assert!(err.to_string().contains("not well-formed XML"), "{err}");
    let err = read_urdf_chain("<sdf/>", FILE, None, None, None).unwrap_err();
    assert!(
        err.to_string().contains("the root element must be <robot>"),
        "{err}"
    );
}

#[test]
fn fixed_only_chains_have_no_joint() {
    let text = arm(&J2.replace("revolute", "fixed")).replace(
        "<joint name=\"j1\" type=\"revolute\"",
        "<joint name=\"j1\" type=\"fixed\"",
    );
    expect(
        &text,
        None,
        6,
        "link",
        "name",
        "has no revolute, continuous or prismatic joint",
    );
}

fn tmpdir(name: &str) -> TempDir {
    TempDir::fresh(
        std::env::temp_dir().join(format!("bf-scene-urdf-{name}-{}", std::process::id())),
    )
}

/// A link name that is no link of the URDF is blamed on whoever gave it: the command line's
/// `--base`/`--tip` (a `ChainChoice` error, which the program exits on with status 2, naming
/// the flag), or the scene's `base_link`/`tip_link` key at its own line. Both used to be the
/// URDF's `<robot>` element, with neither the flag nor the key named.
#[test]
fn an_unknown_chain_link_names_the_flag_or_the_key_that_gave_it() {
    let dir = tmpdir("unknown-link");
    std::fs::write(dir.join("arm.urdf"), arm(J2)).unwrap();
    let tip = |t: &str| ChainChoice {
        base: None,
        tip: Some(t.to_string()),
    };
    let err = bf_scene::urdf_scene_text(&arm(J2), FILE, &tip("nope")).unwrap_err();
    assert_eq!(
        err.kind(),
        Some(bf_scene::SpecErrorKind::ChainChoice),
        "{err}"
    );
    assert_eq!(err.path(), Some("--tip"), "{err}");
    assert!(err.to_string().contains("\"nope\" is not a link"), "{err}");
    let base = ChainChoice {
        base: Some("nope".to_string()),
        tip: None,
    };
    let err = bf_scene::urdf_scene_text(&arm(J2), FILE, &base).unwrap_err();
    assert_eq!(err.path(), Some("--base"), "{err}");
    assert!(bf_scene::urdf_scene_text(&arm(J2), FILE, &tip("l2")).is_ok());

    let path = dir.join("arm.toml");
    std::fs::write(
        &path,
        "name = \"arm2\"\nurdf = \"arm.urdf\"\ntip_link = \"zzz\"\nkernels = [\"mass_matrix\"]\n",
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert_eq!(err.kind(), Some(bf_scene::SpecErrorKind::Invalid), "{err}");
    assert_eq!(
        (err.path(), err.line()),
        (Some("tip_link"), Some(3)),
        "{err}"
    );
    // The command line's choice overrides the key, and is the one blamed.
    let err = Scene::load_with_text(&path, &tip("nope")).unwrap_err();
    assert_eq!(err.path(), Some("--tip"), "{err}");
    if let Err(e) = Scene::load_with_text(&path, &tip("l2")) {
        panic!("{e}");
    }
    // The command line's mistake is reported before the file's: before a broken joint of the
    // URDF, and before a wrong key of the scene at the other end.
    let broken = arm(&J2.replace(r#"<parent link="l1"/>"#, r#"<parent link="nowhere"/>"#));
    let err = bf_scene::urdf_scene_text(&broken, FILE, &tip("nope")).unwrap_err();
    assert_eq!(err.path(), Some("--tip"), "{err}");
    let keyed = dir.join("keyed.toml");
    std::fs::write(
        &keyed,
        "name = \"arm3\"\nurdf = \"arm.urdf\"\nbase_link = \"zzz\"\nkernels = [\"mass_matrix\"]\n",
    )
    .unwrap();
    let err = Scene::load_with_text(&keyed, &tip("nope")).unwrap_err();
    assert_eq!(err.path(), Some("--tip"), "{err}");
    // Both flags wrong: the first is where the error is, and both are named.
    let both = ChainChoice {
        base: Some("nob".to_string()),
        tip: Some("not".to_string()),
    };
    let err = bf_scene::urdf_scene_text(&arm(J2), FILE, &both).unwrap_err();
    assert_eq!(err.path(), Some("--base"), "{err}");
    assert!(err.to_string().contains("nor is --tip \"not\""), "{err}");
    let Err(SpecError::UnknownLink(u)) =
        read_urdf_chain(&arm(J2), FILE, Some("nob"), Some("not"), None)
    else {
        panic!("two unknown ends must be an UnknownLink error");
    };
    assert_eq!(u.unknown.len(), 2);
    assert!(
        u.to_string()
            .contains("base link \"nob\" and tip link \"not\" are not links"),
        "{u}"
    );
    // Read directly, the error says which end and lists the links, at the URDF's <robot>.
    let Err(SpecError::UnknownLink(u)) = read_urdf_chain(&arm(J2), FILE, Some("zzz"), None, None)
    else {
        panic!("an unknown base must be an UnknownLink error");
    };
    assert_eq!(u.unknown, [(bf_scene::ChainEnd::Base, "zzz".to_string())]);
    assert!(u.links.iter().any(|l| l == "l2"), "{u}");
    assert!(u.to_string().contains("base link \"zzz\""), "{u}");
}

#[test]
fn a_toml_scene_takes_its_robot_from_a_urdf_next_to_it() {
    let dir = tmpdir("toml");
    std::fs::write(dir.join("arm.urdf"), arm(J2)).unwrap();
    let scene_text = "name = \"arm2\"\nurdf = \"arm.urdf\"\ntip_link = \"l2\"\nkernels = [\"mass_matrix\"]\n\n[friction]\nmu_s = -1.0\nmu_k = 0.5\n";
    let path = dir.join("arm.toml");
    // An error in the user's part keeps its own line (7), although keys became comments.
    std::fs::write(&path, scene_text).unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert_eq!(err.line(), Some(7), "{err}");
    assert_eq!(err.path(), Some("friction.mu_s"), "{err}");
    std::fs::write(&path, scene_text.replace("-1.0", "0.6")).unwrap();
    let (scene, text) = Scene::load_with_text(&path, &ChainChoice::default()).unwrap();
    assert_eq!(scene.nq(), 2);
    assert_eq!(scene.gravity, [0.0, 0.0, -9.81], "default gravity");
    // The text is self-contained: it parses again without the URDF.
    assert_eq!(Scene::from_toml_str(&text, "again").unwrap(), scene);
    // Keys an imported chain cannot share.
    std::fs::write(
        &path,
        format!("{scene_text}\n[tool]\ntranslation = [0.0, 0.0, 1.0]\n"),
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert!(
        err.to_string()
            .contains("takes its tool (the tip link) from the URDF"),
        "{err}"
    );
    std::fs::write(
        &path,
        "name = \"x\"\nbase_link = \"l1\"\ngravity = [0.0, 0.0, -9.81]\nkernels = []\n",
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert!(
        err.to_string()
            .contains("`base_link` at the top level needs `urdf`"),
        "{err}"
    );
    // A URDF that is not there is an I/O error naming it.
    std::fs::write(&path, scene_text.replace("arm.urdf", "missing.urdf")).unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert!(err.to_string().contains("missing.urdf"), "{err}");
}

/// The second link's inertia replaced by the diagonal `ixx`, `iyy`, `izz`.
fn arm_with_l2_inertia(ixx: &str, iyy: &str, izz: &str) -> String {
    arm(J2).replacen(
        r#"<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <joint"#,
        &format!(
            r#"<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>
  </link>
  <joint"#
        ),
        1,
    )
}

#[test]
fn an_inertia_no_rigid_body_has_names_the_urdf_link() {
    // 0.3 > 0.1 + 0.1: the triangle inequality of the principal moments fails.
    let text = arm_with_l2_inertia("0.1", "0.1", "0.3");
    assert_ne!(text, arm(J2));
    expect(
        &text,
        None,
        6,
        "link",
        "inertial",
        "link \"l2\", moved by joint \"j2\": principal moments",
    );
    let err = read_urdf_chain(&text, FILE, None, None, None).unwrap_err();
    assert!(err.to_string().contains("`nonphysical_inertia"), "{err}");
    // The scene's source keeps the published values, on the violating link only.
    let c = read_urdf_chain(&text, FILE, None, None, Some("vendor data sheet")).unwrap();
    assert_eq!(c.links[0].nonphysical_inertia, None);
    assert_eq!(
        c.links[1].nonphysical_inertia.as_deref(),
        Some("vendor data sheet")
    );
    assert_eq!(c.links[1].inertia_matrix()[2][2], 0.3);
}

#[test]
fn a_scene_keeps_a_urdfs_nonphysical_inertia_by_naming_its_source() {
    let dir = tmpdir("nonphysical");
    std::fs::write(
        dir.join("arm.urdf"),
        arm_with_l2_inertia("0.1", "0.1", "0.3"),
    )
    .unwrap();
    let path = dir.join("arm.toml");
    let scene_text = "name = \"arm2\"\nurdf = \"arm.urdf\"\nkernels = [\"mass_matrix\"]\n";
    std::fs::write(&path, scene_text).unwrap();
    let err = Scene::load(&path).unwrap_err();
    let shown = err.to_string();
    assert!(shown.contains("arm.urdf:6:"), "the URDF's line: {shown}");
    std::fs::write(
        &path,
        format!("{scene_text}nonphysical_inertia = \"vendor data sheet\"\n"),
    )
    .unwrap();
    let (scene, text) = Scene::load_with_text(&path, &ChainChoice::default()).unwrap();
    assert_eq!(scene.nq(), 2);
    // Its warning names the URDF's joint: `links[1]` is no table of the user's scene file.
    let w = scene.warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("links[1].inertia (`j2`): ") && w[0].contains("vendor data sheet"),
        "{w:?}"
    );
    // The mark travels with the self-contained text.
    assert_eq!(Scene::from_toml_str(&text, "again").unwrap(), scene);
    // Without `urdf` the top-level key has nothing to apply to.
    std::fs::write(
        &path,
        "name = \"x\"\nnonphysical_inertia = \"s\"\ngravity = [0.0, 0.0, -9.81]\nkernels = []\n",
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert!(
        err.to_string()
            .contains("`nonphysical_inertia` at the top level needs `urdf`"),
        "{err}"
    );
}

/// A value the scene's validation refuses on an imported link (here the relative mass floor,
/// which the URDF reader does not check) is reported at the URDF's `<link>` element, on the
/// URDF's own line, for a `.urdf` given directly and for a scene that names it: not on a line
/// of the scene text generated from it.
#[test]
fn validation_errors_on_imported_links_name_the_urdf_link() {
    let dir = tmpdir("relocated");
    // Blank lines first, so that the URDF's lines differ from the generated text's.
    let text = format!(
        "{}{}",
        "\n".repeat(40),
        arm(J2).replacen(r#"<mass value="1"/>"#, r#"<mass value="1e300"/>"#, 1)
    );
    let l2_line = text
        .lines()
        .position(|l| l.contains(r#"<link name="l2">"#))
        .unwrap()
        + 1;
    let urdf = dir.join("arm.urdf");
    std::fs::write(&urdf, &text).unwrap();
    let scene = dir.join("arm.toml");
    std::fs::write(
        &scene,
        "name = \"arm2\"\nurdf = \"arm.urdf\"\nkernels = [\"mass_matrix\"]\n",
    )
    .unwrap();
    for path in [&urdf, &scene] {
        let err = Scene::load(path).unwrap_err();
        let SpecError::Urdf(u) = &err else {
            panic!("not located in the URDF: {err}");
        };
        assert!(u.file.ends_with("arm.urdf"), "{err}");
        assert_eq!(u.line, l2_line, "{err}");
        assert_eq!((u.element.as_str(), u.attribute.as_str()), ("link", "mass"));
        assert!(
            u.message.contains("joint \"j2\"") && u.message.contains("below 1e-12"),
            "{err}"
        );
    }
    // The user's own lines keep their location.
    std::fs::write(
        &scene,
        "name = \"arm2\"\nurdf = \"arm.urdf\"\nkernels = [\"mass_matrix\"]\n[ball]\nradius = -1.0\ncenter = [0.0, 0.0, 0.0]\nmass = 1.0\n",
    )
    .unwrap();
    let err = Scene::load(&scene).unwrap_err();
    assert_eq!(err.path(), Some("ball.radius"), "{err}");
}

#[test]
fn placement_links_in_toml_are_checked() {
    let base = "name = \"p\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n\n[[links]]\naxis = [0.0, 0.0, 1.0]\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n";
    assert!(Scene::from_toml_str(base, "p.toml").unwrap().is_placement());
    let err = Scene::from_toml_str(
        &base.replace("[0.0, 0.0, 1.0]", "[0.0, 0.0, 2.0]"),
        "p.toml",
    )
    .unwrap_err();
    assert!(err.to_string().contains("unit vector"), "{err}");
    assert_eq!(err.line(), Some(6));
    let err = Scene::from_toml_str(&base.replace("mass = 1.0", "mass = 1.0\na = 0.3"), "p.toml")
        .unwrap_err();
    assert_eq!(err.path(), Some("links[0].a"), "{err}");
    let mixed = format!(
        "{base}\n[[links]]\na = 1.0\nalpha = 0.0\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n"
    );
    let err = Scene::from_toml_str(&mixed, "p.toml").unwrap_err();
    assert_eq!(err.path(), Some("links[1].axis"), "{err}");
    assert!(err.to_string().contains("missing field `axis`"), "{err}");
    // A placement link after DH rows.
    let dh_first = format!(
        "name = \"m\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n\n[[links]]\na = 1.0\nalpha = 0.0\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n{}",
        &base[base.find("[[links]]").unwrap()..]
    );
    let err = Scene::from_toml_str(&dh_first, "m.toml").unwrap_err();
    assert!(err.to_string().contains("one form for all links"), "{err}");
    // A placement link with an origin but no axis is missing its axis, not "a DH row".
    let origin_only = format!(
        "{base}\n[[links]]\norigin = {{ translation = [1.0, 0.0, 0.0] }}\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n"
    );
    let err = Scene::from_toml_str(&origin_only, "p.toml").unwrap_err();
    assert_eq!(err.path(), Some("links[1].axis"), "{err}");
    // A DH row still needs a and alpha.
    let dh = "name = \"d\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n\n[[links]]\nalpha = 0.0\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n";
    let err = Scene::from_toml_str(dh, "d.toml").unwrap_err();
    assert_eq!(err.path(), Some("links[0].a"), "{err}");
    assert!(err.to_string().contains("missing field `a`"), "{err}");
}

/// The scene text of a URDF (alone, or named by a TOML scene) does not depend on how the path to
/// it was spelt: the provenance comment names the URDF by its file name only, so the same files
/// give the same text, and the same generated code, from any working directory.
#[test]
fn a_scene_text_names_its_urdf_by_the_file_name_alone() {
    let dir = tmpdir("provenance");
    let sub = dir.join("robots");
    std::fs::create_dir_all(&sub).unwrap();
    std::fs::write(sub.join("arm.urdf"), arm(J2)).unwrap();
    std::fs::write(
        sub.join("arm.toml"),
        "name = \"arm2\"\nurdf = \"arm.urdf\"\ntip_link = \"l2\"\nkernels = [\"mass_matrix\"]\n",
    )
    .unwrap();
    let roundabout = dir.join("robots").join("..").join("robots");
    for file in ["arm.urdf", "arm.toml"] {
        let choice = ChainChoice::default();
        let (_, a) = Scene::load_with_text(sub.join(file), &choice).unwrap();
        let (_, b) = Scene::load_with_text(roundabout.join(file), &choice).unwrap();
        assert_eq!(a, b, "{file}");
        assert!(a.contains("\"arm.urdf\""), "{a}");
        assert!(!a.contains(&*dir.to_string_lossy()), "{a}");
    }
    // Errors still name the path as given, to find the file.
    std::fs::write(
        sub.join("bad.urdf"),
        arm(J2).replace("value=\"1\"", "value=\"-1\""),
    )
    .unwrap();
    let err = Scene::load(roundabout.join("bad.urdf")).unwrap_err();
    assert!(err.to_string().contains("/../robots/bad.urdf"), "{err}");
}

/// `dh` has no meaning for a chain read from a URDF (placement form); the generated text of an
/// import carries no `dh`, so only the user's own key is refused, on the user's line.
#[test]
fn a_dh_convention_beside_a_urdf_is_refused() {
    let dir = tmpdir("dh");
    std::fs::write(dir.join("arm.urdf"), arm(J2)).unwrap();
    let path = dir.join("arm.toml");
    let scene =
        "name = \"arm2\"\nurdf = \"arm.urdf\"\ntip_link = \"l2\"\nkernels = [\"mass_matrix\"]\n";
    std::fs::write(&path, format!("{scene}dh = \"standard\"\n")).unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert_eq!((err.path(), err.line()), (Some("dh"), Some(5)), "{err}");
    assert!(err.to_string().contains("urdf"), "{err}");
    std::fs::write(&path, scene).unwrap();
    let (_, text) = Scene::load_with_text(&path, &ChainChoice::default()).unwrap();
    assert!(!text.contains("dh ="), "{text}");
    assert!(Scene::load(dir.join("arm.urdf")).is_ok());
}

/// A robot whose name a scene may not take gets `_robot` appended, as a keyword does.
#[test]
fn a_urdf_robot_named_like_a_generated_item_is_renamed() {
    for (robot, name) in [
        ("registry", "registry_robot"),
        ("std", "std_robot"),
        ("fn", "fn_robot"),
    ] {
        let text = arm(J2).replace("<robot name=\"arm\">", &format!("<robot name=\"{robot}\">"));
        let toml = bf_scene::urdf_scene_text(
            &text,
            FILE,
            &ChainChoice {
                base: None,
                tip: Some("l2".into()),
            },
        )
        .unwrap();
        let scene = Scene::from_toml_str(&toml, FILE).unwrap();
        assert_eq!(scene.name, name);
    }
}

/// A placement axis written with a few digits is the unit vector meant: accepted within 1e-6
/// of unit length and normalised when read; zero, non-finite and clearly non-unit axes are
/// refused at the key.
#[test]
fn a_placement_axis_is_normalised_when_read() {
    let base = "name = \"p\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n\n[[links]]\naxis = [0.0, 0.0, 1.0]\nmass = 1.0\ncom = [0.0, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n";
    let s = Scene::from_toml_str(
        &base.replace("[0.0, 0.0, 1.0]", "[0.0, 0.70710678, 0.70710678]"),
        "p.toml",
    )
    .unwrap();
    let a = s.links[0].axis.unwrap();
    let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((norm - 1.0).abs() < 4e-16, "{a:?}: norm {norm}");
    assert_eq!(a[1], a[2]);
    assert!(
        (a[1] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15,
        "{a:?}"
    );
    // A unit axis is kept bit for bit.
    let s = Scene::from_toml_str(base, "p.toml").unwrap();
    assert_eq!(s.links[0].axis, Some([0.0, 0.0, 1.0]));
    for bad in [
        "[0.0, 0.0, 1.00001]",
        "[0.0, 0.7071, 0.7071]",
        "[0.0, 0.0, 0.0]",
        "[0.0, 0.0, nan]",
    ] {
        let err =
            Scene::from_toml_str(&base.replace("[0.0, 0.0, 1.0]", bad), "p.toml").unwrap_err();
        assert_eq!(err.line(), Some(6), "{bad}: {err}");
        assert!(
            err.path().is_some_and(|p| p.starts_with("links[0].axis")),
            "{bad}: {err}"
        );
    }
    // A scene built in code is used as it is: its axis must be unit to 1e-9.
    let mut s = Scene::from_toml_str(base, "p.toml").unwrap();
    s.links[0].axis = Some([0.0, 0.6, 0.800_000_1]);
    assert_eq!(
        s.validate("code").unwrap_err().path(),
        Some("links[0].axis")
    );
}

/// A URDF saved under another extension (`.xml`, as some exporters write it) is read as a URDF:
/// a text that starts with `<` is no TOML document. It gives the scene the `.urdf` gives.
#[test]
fn a_urdf_under_another_extension_is_read_as_one() {
    let dir = tmpdir("xml");
    let text = format!("<?xml version=\"1.0\"?>\n{}", arm(J2));
    let (urdf, xml) = (dir.join("robot.urdf"), dir.join("robot.xml"));
    std::fs::write(&urdf, &text).unwrap();
    std::fs::write(&xml, &text).unwrap();
    let (a, _) = Scene::load_with_text(&urdf, &ChainChoice::default()).unwrap();
    let (b, _) = Scene::load_with_text(&xml, &ChainChoice::default()).unwrap();
    assert_eq!(a.links, b.links);
    assert_eq!(a.name, b.name);
}

/// Well-formed documents that exporters write are read like the plain one: a document type
/// declaration, and another tool's elements of URDF's names in their own namespace (ignored,
/// as unknown elements are); the robot's own namespace, default or prefixed, is URDF's.
#[test]
fn doctypes_and_foreign_namespaces_are_read() {
    let plain = read_urdf_chain(&arm(J2), FILE, None, None, None).unwrap();
    let doctype = format!("<?xml version=\"1.0\"?>\n<!DOCTYPE robot>\n{}", arm(J2));
    let foreign = arm(J2).replace(
        "<robot name=\"arm\">",
        "<robot name=\"arm\" xmlns:gz=\"http://gazebosim.org\">\n  <gz:link name=\"ghost\"/>\n  \
         <gz:joint name=\"gj\" type=\"fixed\"><parent link=\"l2\"/><child link=\"ghost\"/></gz:joint>",
    );
    let defaulted = arm(J2).replace(
        "<robot name=\"arm\">",
        "<robot name=\"arm\" xmlns=\"http://www.ros.org\">",
    );
    // Every element prefixed with the robot's own namespace, closing tags included.
    let prefixed = {
        let mut t = arm(J2);
        for tag in [
            "robot", "link", "joint", "inertial", "mass", "inertia", "origin", "parent", "child",
            "axis",
        ] {
            t = t
                .replace(&format!("<{tag} "), &format!("<urdf:{tag} "))
                .replace(&format!("<{tag}>"), &format!("<urdf:{tag}>"))
                .replace(&format!("</{tag}>"), &format!("</urdf:{tag}>"));
        }
        t.replacen(
            "<urdf:robot ",
            "<urdf:robot xmlns:urdf=\"http://www.ros.org\" ",
            1,
        )
    };
    assert!(prefixed.contains("<urdf:inertia ") && prefixed.contains("</urdf:link>"));
    for text in [doctype, foreign, defaulted, prefixed] {
        let chain = read_urdf_chain(&text, FILE, None, None, None).unwrap();
        assert_eq!(chain.joint_names, plain.joint_names, "{text}");
        assert_eq!(chain.tip_link, plain.tip_link, "{text}");
    }
}
