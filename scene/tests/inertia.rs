//! Inertias: positive definiteness does not depend on the unit; principal moments that violate
//! the triangle inequality are refused unless the table names a published source, and then
//! reported by `Scene::warnings` (as is μ_k > μ_s); the shipped scenes' warnings.

mod common;

use bf_scene::{Scene, SpecErrorKind};
use common::*;

/// `text` with the inertias of [`BASE`]'s other bodies (the links' tensors as written there, and
/// the ball's default) replaced by `v` times unit tensors: all bodies at one scale, as a
/// consistent unit system has them (a lone 1e-300 body is refused by the scale floor).
fn bodies_at(text: &str, v: &str) -> String {
    let diag = format!("inertia = [{v}, {v}, {v}]");
    text.replace("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", &diag)
        .replace(
            "inertia = [[1.0e-3, 0.0, 0.0], [0.0, 2.0e-3, 0.0], [0.0, 0.0, 2.0e-3]]",
            &diag,
        )
        .replace(
            "[ball]\nradius = 1.0\ncenter = [0.0, 0.0, 0.0]\nmass = 0.02",
            &format!("[ball]\nradius = 1.0\ncenter = [0.0, 0.0, 0.0]\nmass = 0.02\n{diag}"),
        )
}

#[test]
fn a_body_negligible_next_to_the_others_is_refused_naming_the_value() {
    // A link of 1e-300 kg (or 1e-300 kg m²) beside 0.02 kg links: the error names the value.
    let text = edit("mass = 0.02", 1, "mass = 1.0e-300");
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, "mass = 1.0e-300", 0),
        "links[1].mass",
        "1e-300",
    );
    assert!(shown.contains("2e-2"), "{shown}");
    // The largest body is named: its value may be the wrong one.
    let text = edit("mass = 0.02", 0, "mass = 1.0e300");
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, "mass = 0.02", 0),
        "links[1].mass",
        "links[0]: 1e300",
    );
    assert!(shown.contains("2e-2"), "{shown}");
    let tiny = "inertia = [1.0e-300, 1.0e-300, 1.0e-300]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, tiny);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, tiny, 0),
        "links[0].inertia",
        "3e-300",
    );
    // Every body at 1e-300 (one consistent, if odd, unit) is accepted: the floor is relative.
    let text = bodies_at(BASE, "1.0e-300").replace("mass = 0.02", "mass = 1.0e-300");
    Scene::from_toml_str(&text, FILE).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn positive_definiteness_does_not_depend_on_the_unit() {
    // Minors of diag(1e-300, …) underflow to 0 and of diag(1e300, …) overflow; both are valid.
    for v in ["1.0e-300", "1.0e300", "5.0e-320"] {
        let new = format!("inertia = [{v}, {v}, {v}]");
        let text = bodies_at(&edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, &new), v);
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
fn impossible_inertias_are_rejected_naming_key_and_values() {
    // Izz > Ixx + Iyy: violates the triangle inequality (a diagonal link inertia).
    let new = "inertia = [1.0e-3, 1.0e-3, 2.5e-3]";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, new);
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, new, 0),
        "links[0].inertia",
        "triangle inequality",
    );
    assert!(
        shown.contains("2.5e-3 > 1e-3 + 1e-3") && shown.contains("nonphysical_inertia"),
        "{shown}"
    );
    // The same moments rotated into a full tensor (principal axes not the link axes).
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
    let text = edit(old, 0, &full);
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, &full, 0),
        "links[1].inertia",
        "triangle inequality",
    );
    // A thin plate (equality) is physical, up to rounding of the decimal input, at any scale.
    for k in [1.0e-3, 1.0e-300, 1.0e300] {
        let plate = format!(
            "inertia = [[{:e}, 0.0, 0.0], [0.0, {:e}, 0.0], [0.0, 0.0, {:e}]]",
            k,
            2.0 * k,
            3.0 * k
        );
        let scene =
            Scene::from_toml_str(&bodies_at(&edit(old, 0, &plate), &format!("{k:e}")), FILE)
                .unwrap_or_else(|e| panic!("{plate}: {e}"));
        assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    }
    // A violation by a relative 1e-6 is refused at every scale: the tolerance is scale-free.
    for k in [1.0e-3, 1.0e-300, 1.0e300] {
        let bad = format!(
            "inertia = [{:e}, {:e}, {:e}]",
            k,
            2.0 * k,
            3.0 * k * (1.0 + 1e-6)
        );
        let text = bodies_at(
            &edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, &bad),
            &format!("{k:e}"),
        );
        expect_err(
            &text,
            SpecErrorKind::Invalid,
            line_no(&text, &bad, 0),
            "links[0].inertia",
            "triangle inequality",
        );
    }
    // Ball inertia.
    let text = edit("mass = 0.02", 2, "mass = 0.02\ninertia = [1.0, 1.0, 2.5]");
    let shown = expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, "inertia = [1.0, 1.0, 2.5]", 0),
        "ball.inertia",
        "triangle inequality",
    );
    assert!(shown.contains("2.5e0 > 1e0 + 1e0"), "{shown}");
}

#[test]
fn published_nonphysical_inertias_need_a_source_and_give_a_warning() {
    assert!(
        Scene::from_toml_str(BASE, FILE)
            .unwrap()
            .warnings()
            .is_empty()
    );
    let with_source =
        "inertia = [1.0e-3, 1.0e-3, 2.5e-3]\nnonphysical_inertia = \"Doe 1999, Table 2\"";
    let text = edit("inertia = [1.0e-3, 2.0e-3, 2.0e-3]", 0, with_source);
    let w = Scene::from_toml_str(&text, FILE).unwrap().warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("links[0].inertia: ")
            && w[0].contains("triangle")
            && w[0].contains("2.5e-3")
            && w[0].contains("Doe 1999, Table 2"),
        "{w:?}"
    );
    let text = edit(
        "mass = 0.02",
        2,
        "mass = 0.02\ninertia = [1.0, 1.0, 2.5]\nnonphysical_inertia = \"a test\"",
    );
    let w = Scene::from_toml_str(&text, FILE).unwrap().warnings();
    assert!(
        w.len() == 1 && w[0].starts_with("ball.inertia: ") && w[0].contains("a test"),
        "{w:?}"
    );
    // The source must be named.
    let empty = "nonphysical_inertia = \" \"";
    let text = edit(
        "inertia = [1.0e-3, 2.0e-3, 2.0e-3]",
        0,
        &format!("inertia = [1.0e-3, 1.0e-3, 2.5e-3]\n{empty}"),
    );
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, empty, 0),
        "links[0].nonphysical_inertia",
        "source",
    );
    // The key on a physical inertia (here the default ball inertia) is refused: it cannot go stale.
    let stale = "nonphysical_inertia = \"a test\"";
    let text = edit("mass = 0.02", 2, &format!("mass = 0.02\n{stale}"));
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, stale, 0),
        "ball.nonphysical_inertia",
        "satisfies the triangle inequality",
    );
}

#[test]
fn kinetic_friction_above_static_friction_is_a_warning() {
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
            // Armstrong's link 3 (0.086 > 0.0125 + 0.066), kept with its source.
            assert_eq!(w.len(), 1, "{w:?}");
            assert!(
                w[0].starts_with("links[2].inertia")
                    && w[0].contains("8.6e-2 > 1.25e-2 + 6.6e-2")
                    && w[0].contains("Armstrong"),
                "{w:?}"
            );
        } else {
            assert!(w.is_empty(), "{name}: {w:?}");
        }
    }
    // Without its source the published link 3 is refused.
    let path = format!("{}/../scenes/puma560.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let stripped: String = text
        .lines()
        .filter(|l| !l.starts_with("nonphysical_inertia"))
        .collect::<Vec<_>>()
        .join("\n");
    let err = Scene::from_toml_str(&stripped, "puma560.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("links[2].inertia") && err.contains("8.6e-2 > 1.25e-2 + 6.6e-2"),
        "{err}"
    );
}

#[test]
fn a_ball_whose_inertia_overflows_names_its_radius() {
    // (2/5) m r² of a 1e300 m ball is not a number f64 holds: the radius is named, not the
    // triangle inequality of an inertia the file never gave.
    let text = edit("radius = 1.0", 0, "radius = 1.0e300");
    expect_err(
        &text,
        SpecErrorKind::Invalid,
        line_no(&text, "radius = 1.0e300", 0),
        "ball.radius",
        "not a finite number > 0",
    );
}
