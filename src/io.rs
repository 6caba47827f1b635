//! Small I/O helpers for the CLI: atomic file writes (so an interrupted or failed run never
//! leaves a half-written output file) and parsing of numeric command-line lists.

use anyhow::{Context, Result, bail};
use std::path::Path;

/// Write `contents` to `path` atomically: write a sibling temporary file, then rename it over
/// the target. Creates the parent directory if needed.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(dir) = dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    let file_name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = path.with_file_name(format!(
        ".{}.{}.tmp",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, contents).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| {
        let _ = std::fs::remove_file(&tmp);
        format!("cannot move {} to {}", tmp.display(), path.display())
    })?;
    Ok(())
}

/// Parse a comma-separated list of finite numbers given for the option `name`
/// (e.g. `--q 0.1,0.2,0.3`), checking the expected length when one is given.
pub fn parse_list(name: &str, text: &str, expected_len: Option<usize>) -> Result<Vec<f64>> {
    let mut values = Vec::new();
    for (i, item) in text.split(',').enumerate() {
        let item = item.trim();
        let v: f64 = item
            .parse()
            .with_context(|| format!("{name}: element {} ({item:?}) is not a number", i + 1))?;
        if !v.is_finite() {
            bail!(
                "{name}: element {} is {v}; only finite values are allowed",
                i + 1
            );
        }
        values.push(v);
    }
    if let Some(n) = expected_len
        && values.len() != n
    {
        bail!(
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
    }

    #[test]
    fn write_atomic_replaces_content_and_leaves_no_temp_file() {
        let dir = std::env::temp_dir().join(format!("bf-io-test-{}", std::process::id()));
        let path = dir.join("sub/out.txt");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let leftovers: Vec<_> = std::fs::read_dir(path.parent().unwrap())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
