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
