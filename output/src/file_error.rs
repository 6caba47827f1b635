//! [`FileError`]: a failed operation on one file, shared by the crates' error enums (bf-sim,
//! bf-plot, the study layer) so that they all report file failures alike: the message names
//! the operation and the path, and the `io::Error` is the [`source`](Error::source), never
//! repeated in the message (an error chain then states the operating system's reason once).

use std::error::Error;
use std::fmt;
use std::io;
use std::path::PathBuf;

/// A file operation that failed: `"{op} {path}"`, with the `io::Error` as its source.
#[derive(Debug)]
pub struct FileError {
    /// What was attempted, as the message starts (`cannot read`, `cannot write`, ...).
    pub op: &'static str,
    /// The file or directory.
    pub path: PathBuf,
    /// Why.
    pub source: io::Error,
}

impl FileError {
    /// The error of `op` on `path`; for `map_err(|e| FileError::new("cannot read", path, e))`.
    pub fn new(op: &'static str, path: impl Into<PathBuf>, source: io::Error) -> Self {
        FileError {
            op,
            path: path.into(),
            source,
        }
    }
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.op, self.path.display())
    }
}

impl Error for FileError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        Some(&self.source)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_operation_and_path_and_keeps_the_reason_as_source() {
        let io = io::Error::from(io::ErrorKind::PermissionDenied);
        let reason = io.to_string();
        let e = FileError::new("cannot write", "out/run.json", io);
        assert_eq!(e.to_string(), "cannot write out/run.json");
        assert_eq!(e.source().map(|s| s.to_string()), Some(reason));
    }
}
