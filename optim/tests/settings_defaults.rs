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
    let listed: BTreeSet<&str> = Settings::DEFAULTS.iter().map(|(f, _)| *f).collect();
    assert_eq!(
        listed.len(),
        Settings::DEFAULTS.len(),
        "a field listed twice"
    );
    let serialized: BTreeSet<&str> = object.keys().map(String::as_str).collect();
    assert_eq!(listed, serialized);
    let mut literals = 0;
    for (field, text) in Settings::DEFAULTS {
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
    assert_eq!(d.perturb_dec_fact, 1.0 / 3.0);
    assert_eq!(d.slack_move, f64::EPSILON.powf(0.75));
}

#[test]
fn no_default_is_written_twice_in_the_source() {
    let source = include_str!("../src/ipm/settings.rs");
    let start = source
        .find("settings! {")
        .expect("the settings! invocation");
    for (k, line) in source[start..].lines().enumerate() {
        let lower = line.to_lowercase();
        assert!(
            !lower.contains("(default:") && !lower.contains("default: "),
            "settings.rs: a default written by hand in a field's docs (line {k} of the macro call): {line}"
        );
    }
}
