//! Reading and writing solutions: `solution.json` ([`SolutionIo::write_json`],
//! [`SolutionIo::read_json`]) and `torques.csv` ([`SolutionIo::write_torques_csv`], the format
//! `simulate --torques` reads), each written atomically.

use std::path::Path;

use anyhow::Context;

use bf_output::FileError;
use bf_problem::OcpSolution;

use super::error::StudyError;

/// Through the workspace's one atomic writer ([`bf_output::replace_file`]), so a failed or
/// interrupted write never leaves a truncated `solution.json` / `torques.csv` behind.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StudyError> {
    bf_output::replace_file(path, bytes).map_err(|e| FileError::new("cannot write", path, e).into())
}

/// File input and output of an [`OcpSolution`].
pub trait SolutionIo: Sized {
    /// Writes `solution.json`.
    fn write_json(&self, path: &Path) -> Result<(), StudyError>;
    /// Reads a solution written by [`SolutionIo::write_json`].
    fn read_json(path: &Path) -> Result<Self, StudyError>;
    /// Writes [`OcpSolution::torques_csv`] to `path`.
    fn write_torques_csv(&self, path: &Path) -> Result<(), StudyError>;
}

impl SolutionIo for OcpSolution {
    fn write_json(&self, path: &Path) -> Result<(), StudyError> {
        let s = serde_json::to_string_pretty(self).map_err(|source| StudyError::Json {
            op: "cannot serialise the solution for",
            path: path.into(),
            source,
        })?;
        write_atomic(path, s.as_bytes())
    }

    fn read_json(path: &Path) -> Result<OcpSolution, StudyError> {
        let s =
            std::fs::read_to_string(path).map_err(|e| FileError::new("cannot read", path, e))?;
        serde_json::from_str(&s).map_err(|source| StudyError::Json {
            op: "cannot parse",
            path: path.into(),
            source,
        })
    }

    fn write_torques_csv(&self, path: &Path) -> Result<(), StudyError> {
        write_atomic(path, self.torques_csv().as_bytes())
    }
}

/// Writes `solution.json` and `torques.csv` into `dir` (created if needed).
pub fn write_solution(sol: &OcpSolution, dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    sol.write_json(&dir.join("solution.json"))?;
    sol.write_torques_csv(&dir.join("torques.csv"))?;
    Ok(())
}
