//! Each solver setting's default is written once, beside its field (the `settings!` macro of
//! `optim/src/ipm/settings.rs` makes the field's doc line "Default: `…`." and the `Default`
//! impl from the same expression). This checks what the macro cannot: that the list covers
//! every serialized field once, that the literal defaults the docs show are the values
//! `Default` gives, and that no field's prose repeats a default by hand (a second copy that
//! could drift).

use bf_optim::ipm::Settings;
use std::collections::BTreeSet;

#[test]
fn every_field_has_one_default_and_the_docs_show_its_value() {
    let json = serde_json::to_value(Settings::default()).unwrap();
    let object = json.as_object().unwrap();
    let defaults: Vec<(&str, &str)> = Settings::GROUPS
        .iter()
        .flat_map(|(_, fields)| fields.iter().copied())
        .collect();
    let listed: BTreeSet<&str> = defaults.iter().map(|(f, _)| *f).collect();
    assert_eq!(listed.len(), defaults.len(), "a field listed twice");
    let serialized: BTreeSet<&str> = object.keys().map(String::as_str).collect();
    assert_eq!(listed, serialized);
    let mut literals = 0;
    for (field, text) in &defaults {
        // The documented text of every plain number or boolean is the value `Default` has.
        let value = &object[*field];
        if let Ok(x) = text.parse::<f64>() {
            let got = value.as_f64().unwrap();
            assert_eq!(got, x, "{field}: docs say {text}, Default gives {got}");
            literals += 1;
        } else if let Ok(b) = text.parse::<bool>() {
            assert_eq!(value.as_bool(), Some(b), "{field}");
            literals += 1;
        }
    }
    assert!(literals > 50, "only {literals} literal defaults checked");
    // Expressions (enum variants, 1/3, ε^{3/4}) evaluate to what `Default` holds.
    let d = Settings::default();
    assert_eq!(d.recovery.perturb_dec_fact, 1.0 / 3.0);
    assert_eq!(d.barrier.slack_move, libm::pow(f64::EPSILON, 0.75));
}

#[test]
fn no_default_is_written_twice_in_the_source() {
    let source = include_str!("../src/ipm/settings.rs");
    let start = source
        .find("settings! {")
        .expect("the first settings! invocation");
    for (k, line) in source[start..].lines().enumerate() {
        let lower = line.to_lowercase();
        assert!(
            !lower.contains("(default:") && !lower.contains("default: "),
            "settings.rs: a default written by hand in a field's docs (line {k} after the first macro call): {line}"
        );
    }
}

/// The groups are a view of the code, not of the files: settings serialize flat, as they did
/// before the grouping, so a file written by an older version reads into the same values, and
/// the fields of the experimental group are none of the other groups'.
#[test]
fn grouped_settings_serialize_flat_and_old_flat_files_read() {
    let mut s = Settings::default();
    s.termination.tol = 1e-7;
    s.scaling.method = bf_optim::ipm::ScalingMethod::None;
    s.experimental.residual_ratio_with_solution = true;
    let json = serde_json::to_value(&s).unwrap();
    let object = json.as_object().unwrap();
    assert!(object.values().all(|v| !v.is_object()), "a nested group");
    assert_eq!(object["tol"], 1e-7);
    assert_eq!(object["scaling"], "None");
    // A flat file as older versions wrote it.
    let old: Settings = serde_json::from_str(
        r#"{"tol": 1e-7, "scaling": "None", "residual_ratio_with_solution": true}"#,
    )
    .unwrap();
    assert_eq!(old, s);
    // Each field belongs to one group.
    let mut seen = BTreeSet::new();
    for (group, fields) in Settings::GROUPS {
        for (field, _) in *fields {
            assert!(seen.insert(*field), "{field} in {group} and another group");
        }
    }
}
