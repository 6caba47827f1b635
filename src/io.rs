//! Small I/O helpers for the CLI: output files and directories (re-exported from `bf-output`:
//! a single file is replaced atomically, a run's output directory as a whole), standard output
//! that reports write errors instead of panicking, and parsing of numeric command-line lists.

use crate::errors::bail_usage;
use anyhow::{Context, Result};
use std::io::Write as _;

pub use bf_output::{DirSpec, Outcome, OutputDir, write_atomic};

/// Writes `text` to standard output and flushes it. A closed pipe or a full disk is an error
/// (naming standard output) that `main` turns into an exit status, never a panic.
pub fn print_out(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("cannot write to standard output")
}

/// `println!` that returns an error instead of panicking when standard output cannot be
/// written (see [`print_out`]).
#[macro_export]
macro_rules! outln {
    () => { $crate::io::print_out("\n") };
    ($($arg:tt)*) => { $crate::io::print_out(&format!("{}\n", format_args!($($arg)*))) };
}

/// `eprintln!` that drops what a standard error that cannot be written (closed, or on a full
/// device) does not take, instead of panicking: a lost note must not take the command's
/// result on standard output, its files and its exit status with it.
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// Parse a comma-separated list of finite numbers given for the option `name`
/// (e.g. `--q 0.1,0.2,0.3`), checking the expected length when one is given; a bad list is a
/// [`crate::errors::UsageError`].
pub fn parse_list(name: &str, text: &str, expected_len: Option<usize>) -> Result<Vec<f64>> {
    let mut values = Vec::new();
    for (i, item) in text.split(',').enumerate() {
        let item = item.trim();
        let v: f64 = item.parse().map_err(|_| {
            crate::errors::usage(format!(
                "{name}: element {} ({item:?}) is not a number",
                i + 1
            ))
        })?;
        if !v.is_finite() {
            bail_usage!(
                "{name}: element {} is {v}; only finite values are allowed",
                i + 1
            );
        }
        values.push(v);
    }
    if let Some(n) = expected_len
        && values.len() != n
    {
        bail_usage!(
            "{name}: expected {n} comma-separated values, got {}",
            values.len()
        );
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_list_rejects_nan_wrong_length_and_garbage() {
        assert_eq!(
            parse_list("--q", "1, 2,3.5", Some(3)).unwrap(),
            vec![1.0, 2.0, 3.5]
        );
        let e = parse_list("--q", "1,NaN,3", Some(3))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--q") && e.contains("element 2"), "{e}");
        let e = parse_list("--q", "1,2", Some(3)).unwrap_err().to_string();
        assert!(e.contains("expected 3"), "{e}");
        let e = parse_list("--qd", "1,x", None).unwrap_err().to_string();
        assert!(e.contains("--qd") && e.contains("\"x\""), "{e}");
        // Every refusal is a wrong command line (exit status 2).
        for (text, n) in [("1,NaN,3", Some(3)), ("1,2", Some(3)), ("1,x", None)] {
            let e = parse_list("--q", text, n).unwrap_err();
            assert!(crate::errors::is_usage(&e), "{text}: {e}");
        }
    }
}

/// Parses a JSON document that a user gives (a state file, a solution, its internals) into a
/// `serde_json::Value`, refusing an object that gives a key twice: `Value` would keep the last
/// one without a word, while the typed readers (`--torques`) and the TOML scenes refuse it.
/// The error names the key, with serde_json's line and column.
pub fn json_value(text: &str) -> serde_json::Result<serde_json::Value> {
    serde_json::from_str::<StrictJson>(text).map(|v| v.0)
}

/// A JSON value read with duplicate keys refused ([`json_value`]).
struct StrictJson(serde_json::Value);

impl<'de> serde::Deserialize<'de> for StrictJson {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(StrictVisitor)
    }
}

struct StrictVisitor;

impl<'de> serde::de::Visitor<'de> for StrictVisitor {
    type Value = StrictJson;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(v.into()))
    }

    fn visit_i64<E>(self, v: i64) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(v.into()))
    }

    fn visit_u64<E>(self, v: u64) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(v.into()))
    }

    fn visit_f64<E>(self, v: f64) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(v.into()))
    }

    fn visit_str<E>(self, v: &str) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(v.into()))
    }

    fn visit_unit<E>(self) -> std::result::Result<StrictJson, E> {
        Ok(StrictJson(serde_json::Value::Null))
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(
        self,
        mut seq: A,
    ) -> std::result::Result<StrictJson, A::Error> {
        let mut items = Vec::new();
        while let Some(StrictJson(v)) = seq.next_element()? {
            items.push(v);
        }
        Ok(StrictJson(serde_json::Value::Array(items)))
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<StrictJson, A::Error> {
        let mut object = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(serde::de::Error::custom(format!(
                    "the key `{key}` is given twice in one object"
                )));
            }
            let StrictJson(v) = map.next_value()?;
            object.insert(key, v);
        }
        Ok(StrictJson(serde_json::Value::Object(object)))
    }
}

#[cfg(test)]
mod json_tests {
    use super::json_value;

    /// The strict reader gives serde_json's own value (numbers bit for bit) and refuses a key
    /// given twice, at any depth, naming it.
    #[test]
    fn a_key_given_twice_is_refused_and_the_rest_reads_as_serde_json() {
        let text = r#"{"q":[0.1,-2.5e-300,3],"n":{"a":null,"b":true,"c":"x"},"k":18446744073709551615,"i":-7}"#;
        let strict = json_value(text).unwrap();
        let plain: serde_json::Value = serde_json::from_str(text).unwrap();
        assert_eq!(strict, plain);
        for bad in [r#"{"q":[1],"q":[2]}"#, r#"{"n":{"a":1,"a":1}}"#] {
            let e = json_value(bad).unwrap_err().to_string();
            assert!(e.contains("given twice") && e.contains("line 1"), "{e}");
        }
    }
}
