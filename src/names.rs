//! The names user output gives enum values (modes, solver statuses, guesses, integrators):
//! the same text as their serde name in the JSON files, so a mode is `stick` in the report,
//! the CSV files and the JSON alike, and no Rust `Debug` text (`Some(Slip)`,
//! `Rk4 { h: 0.01 }`) reaches a user.

use bf_sim::Method;
use serde::Serialize;

/// The serde name of a unit enum value (e.g. `Mode::Stick` → `stick`,
/// `Status::Solved` → `Solved`); for anything that is not serialised as a string, its JSON
/// text.
pub fn name<T: Serialize>(v: &T) -> String {
    match serde_json::to_value(v) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(e) => format!("<unnamed: {e}>"),
    }
}

/// The names of a list of enum values, comma-separated.
pub fn names<T: Serialize>(v: &[T]) -> String {
    v.iter().map(name).collect::<Vec<_>>().join(", ")
}

/// `before → after` of a transition; `end` when the reset terminated the run.
pub fn transition<T: Serialize>(before: &T, after: Option<&T>) -> String {
    format!(
        "{} → {}",
        name(before),
        after.map_or("end".to_string(), name)
    )
}

/// An integrator with its settings: `dopri5`, `rk4 (h = 0.01 s)`.
pub fn method(m: &Method) -> String {
    match m {
        Method::Dopri5 => "dopri5".to_string(),
        Method::Rk4 { h } => format!("rk4 (h = {h} s)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bf_model::Mode;
    use bf_optim::ipm::Status;

    #[test]
    fn names_are_the_json_names_without_debug_text() {
        assert_eq!(name(&Mode::Stick), "stick");
        assert_eq!(name(&Status::MaxIterations), "MaxIterations");
        assert_eq!(transition(&Mode::Free, Some(&Mode::Slip)), "free → slip");
        assert_eq!(transition(&Mode::Stick, None), "stick → end");
        let rk = method(&Method::Rk4 { h: 0.01 });
        assert_eq!(rk, "rk4 (h = 0.01 s)");
        // JSON of the same values: the text above is what a reader finds in the files.
        assert_eq!(serde_json::to_string(&Mode::Stick).unwrap(), "\"stick\"");
        for s in [method(&Method::Dopri5), rk] {
            assert!(!s.contains("{ ") && !s.contains("Some("), "{s}");
        }
    }
}
