//! A test's temporary directory that removes itself: shared by the helpers of the root crate's
//! tests (`tests/common/cli.rs`) and of bf-plot's (`plot/tests/common/mod.rs`).
#![allow(dead_code)] // each including test file uses its own subset

use std::path::{Path, PathBuf};

/// A fresh, empty directory ([`TempDir::fresh`]), a [`Path`] by dereference. Dropped, it
/// removes the directory and its contents, unless the thread is panicking: a failed test's
/// outputs stay for inspection.
pub struct TempDir(PathBuf);

impl TempDir {
    /// The directory `path`, emptied (or created) now.
    pub fn fresh(path: PathBuf) -> Self {
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).unwrap();
        TempDir(path)
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
