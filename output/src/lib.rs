//! Output files that a reader never sees half-written, and output directories that a reader
//! never sees mixed from two runs.
//!
//! * [`write_atomic`] writes one file: the bytes go to a uniquely named sibling temporary file
//!   (`.NAME.PID-N.tmp`), which is then renamed over the target. Device files (`/dev/null`,
//!   `/dev/stdout`, `/dev/full`) are written in place, as a shell redirection would.
//! * [`OutputDir`] is a run's whole output directory. The run writes into a uniquely named
//!   sibling staging directory (`.NAME.staging-PID-N`, created exclusively, so two runs into
//!   one directory never share it); [`OutputDir::commit`] adds a manifest
//!   ([`MANIFEST`]: command, status, error, file list) and, for a run that did not succeed, a
//!   [`FAILED`] marker holding the error, and then moves the staging directory into place as a
//!   whole. On Linux this is one atomic `renameat2(RENAME_EXCHANGE)` with the previous
//!   directory, which is removed afterwards. Where the exchange is not available (another OS, a
//!   file system without it) the previous directory is renamed to a backup name, the new one
//!   into place, and the backup removed: in the short window between the two renames a reader
//!   finds no directory, never a mixture.
//! * [`FileError`] is the error of one failed file operation, for the error enums of the
//!   crates that write files themselves.
//! * A run that dies before its commit leaves its staging directory behind, never a changed
//!   target. The next [`OutputDir::create`] on the same target removes staging and backup
//!   directories whose process no longer exists (on systems with `/proc`).
//! * Replacing a directory as a whole deletes what was in it, so [`OutputDir::create`] accepts
//!   an existing target only if it is empty or carries a manifest of the same command; anything
//!   else (a source tree, a home directory, a file, another command's output, a directory that
//!   merely holds a file of the command's name, such as a stored `solution.json`) is refused
//!   before the run starts, and so is a target that holds one of the run's inputs.
//! * A fault can be injected at the n-th write ([`OutputDir::inject_fault_at_write`]), so tests
//!   can show that a run stopped between two writes leaves the previous directory untouched.

use std::fmt;
use std::fs;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

mod file_error;
pub use file_error::FileError;

/// Name of the manifest every committed output directory holds.
pub const MANIFEST: &str = ".ball-finger.json";

/// Name of the marker file of a run that did not succeed (its content is the error).
pub const FAILED: &str = "FAILED";

/// Process-wide counter that makes temporary names unique within one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn next_id() -> u64 {
    COUNTER.fetch_add(1, Ordering::Relaxed)
}

/// An output path could not be checked, created, written or moved into place. The message
/// names the path and includes the operating system's reason (so the error has no separate
/// `source`, which would print the reason twice in an error chain).
#[derive(Debug)]
pub struct OutputError {
    message: String,
    kind: Option<io::ErrorKind>,
}

impl OutputError {
    fn io(what: &str, path: &Path, e: &io::Error) -> Self {
        OutputError {
            message: format!("{what} {}: {e}", path.display()),
            kind: Some(e.kind()),
        }
    }

    fn invalid(message: String) -> Self {
        OutputError {
            message,
            kind: None,
        }
    }

    /// The kind of the underlying I/O error, if there was one (e.g. to tell a full disk
    /// from a refused target).
    pub fn kind(&self) -> Option<io::ErrorKind> {
        self.kind
    }
}

impl fmt::Display for OutputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for OutputError {}

/// Writes `bytes` to `path` atomically: a uniquely named sibling temporary file is written,
/// flushed to disk and renamed over `path`. The parent directory is created if needed. A device
/// or other non-regular file (`/dev/null`, `/dev/full`) is written in place instead, so such
/// targets are never replaced. Errors name the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let dir = parent_of(path);
    fs::create_dir_all(&dir).map_err(|e| {
        // "File exists" alone does not say which: name the file in the way.
        let in_the_way = dir.ancestors().find(|a| a.is_file());
        match in_the_way {
            Some(file) => OutputError::io(
                "cannot create directory",
                &dir,
                &std::io::Error::other(format!("{} is a file, not a directory", file.display())),
            ),
            None => OutputError::io("cannot create directory", &dir, &e),
        }
    })?;
    replace_file(path, bytes).map_err(|e| OutputError::io("cannot write", path, &e))
}

/// [`write_atomic`] for libraries with their own error type: the same steps, except that the
/// parent directory must exist, with the plain `io::Error` (the caller names `path`).
pub fn replace_file(path: &Path, bytes: &[u8]) -> io::Result<()> {
    match fs::metadata(path) {
        Ok(m) if m.is_dir() => {
            return Err(io::Error::new(
                io::ErrorKind::IsADirectory,
                "it is a directory",
            ));
        }
        Ok(m) if !m.is_file() => {
            let mut f = fs::OpenOptions::new().write(true).open(path)?;
            f.write_all(bytes)?;
            return f.flush();
        }
        _ => {}
    }
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
    let tmp = parent_of(path).join(format!(
        ".{}.{}-{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        next_id()
    ));
    let written = fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    if let Err(e) = written.and_then(|()| fs::rename(&tmp, path)) {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    Ok(())
}

/// The directory holding `path` (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// What a command's output directory looks like, for the checks of [`OutputDir::create`].
#[derive(Debug, Clone, Copy)]
pub struct DirSpec<'a> {
    /// The command-line option that named the directory (`--out`), for error messages.
    pub option: &'a str,
    /// The command writing it, recorded in the manifest: a directory is replaced only by the
    /// command that wrote it. With the subcommand where that chooses what the set holds
    /// (`report strategies`).
    pub command: &'a str,
}

/// How a run ended, recorded by [`OutputDir::commit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome<'a> {
    /// The run succeeded.
    Success,
    /// The run did not succeed; the text (the error) goes into the manifest and the
    /// [`FAILED`] marker.
    Failed(&'a str),
}

/// A run's output directory under construction: files are written into a private staging
/// directory (see [`OutputDir::path`]) and become visible at the target, all together, on
/// [`OutputDir::commit`]. Dropping it without a commit removes the staging directory and
/// leaves the target as it was.
#[derive(Debug)]
pub struct OutputDir {
    target: PathBuf,
    staging: PathBuf,
    command: String,
    writes: usize,
    fault_at: Option<usize>,
    done: bool,
}

impl OutputDir {
    /// Checks `target` and creates the staging directory next to it. Fails, naming
    /// `spec.option` and the path, when the target exists and is not a directory, is a
    /// directory this command did not write, holds one of `inputs` (the files and directories
    /// the run reads: the target is replaced as a whole, so they would be lost), or when its
    /// parent cannot be created or written. Call it before the run's work.
    pub fn create(
        target: &Path,
        spec: &DirSpec<'_>,
        inputs: &[PathBuf],
    ) -> Result<OutputDir, OutputError> {
        let opt = spec.option;
        let name = target
            .file_name()
            .ok_or_else(|| {
                OutputError::invalid(format!(
                    "{opt} {}: does not name a directory that could be replaced (give a \
                     directory name such as out/{})",
                    target.display(),
                    spec.command.replace(' ', "-")
                ))
            })?
            .to_string_lossy()
            .into_owned();
        check_target(target, spec)?;
        refuse_inputs(target, spec.option, inputs)?;
        let parent = parent_of(target);
        fs::create_dir_all(&parent).map_err(|e| {
            OutputError::io(&format!("{opt}: cannot create the directory"), &parent, &e)
        })?;
        remove_stale(&parent, &name);
        let pid = std::process::id();
        let staging = loop {
            let candidate = parent.join(format!(".{name}.staging-{pid}-{}", next_id()));
            match fs::create_dir(&candidate) {
                Ok(()) => break candidate,
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    return Err(OutputError::io(
                        &format!("{opt} {}: cannot create a directory in", target.display()),
                        &parent,
                        &e,
                    ));
                }
            }
        };
        Ok(OutputDir {
            target: target.to_path_buf(),
            staging,
            command: spec.command.to_string(),
            writes: 0,
            fault_at: None,
            done: false,
        })
    }

    /// The staging directory: write the run's files here (directly, with [`OutputDir::write`],
    /// or through a library writer given a path from [`OutputDir::file`]).
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The directory the files will be moved to by [`OutputDir::commit`].
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// `text` (e.g. a library's error message about a file it wrote into [`OutputDir::path`])
    /// with the staging directory replaced by the target, so messages name the files the user
    /// asked for.
    pub fn rename_in(&self, text: &str) -> String {
        text.replace(
            &self.staging.display().to_string(),
            &self.target.display().to_string(),
        )
    }

    /// Makes the `n`-th write (1-based, counting [`OutputDir::file`], [`OutputDir::write`] and
    /// the marker and manifest of [`OutputDir::commit`]) fail with an injected error, as if the
    /// process had stopped right before it. For tests.
    pub fn inject_fault_at_write(&mut self, n: usize) {
        self.fault_at = Some(n);
    }

    /// Announces a write of `name` (a path relative to the directory; `/` separates
    /// subdirectories, which are created) and returns the staging path to write it to. Each call
    /// counts as one write for [`OutputDir::inject_fault_at_write`].
    pub fn file(&mut self, name: &str) -> Result<PathBuf, OutputError> {
        self.writes += 1;
        let path = self.staging.join(name);
        if self.fault_at == Some(self.writes) {
            return Err(OutputError::invalid(format!(
                "cannot write {}: injected fault at write {}",
                self.target.join(name).display(),
                self.writes
            )));
        }
        if let Some(dir) = path.parent() {
            fs::create_dir_all(dir).map_err(|e| {
                OutputError::io("cannot create directory", &self.target.join(name), &e)
            })?;
        }
        Ok(path)
    }

    /// Writes `bytes` to `name` inside the directory; the error names the file at its final
    /// place.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let path = self.file(name)?;
        fs::write(&path, bytes)
            .map_err(|e| OutputError::io("cannot write", &self.target.join(name), &e))
    }

    /// Records how the run ended (the manifest, and the [`FAILED`] marker for a failed run),
    /// then moves the directory into place as a whole, replacing the previous one.
    pub fn commit(mut self, outcome: Outcome<'_>) -> Result<(), OutputError> {
        let error = match outcome {
            Outcome::Success => None,
            Outcome::Failed(msg) => {
                self.write(FAILED, format!("{msg}\n").as_bytes())?;
                Some(msg)
            }
        };
        let mut files = Vec::new();
        list_files(&self.staging, "", &mut files)
            .map_err(|e| OutputError::io("cannot list", &self.staging, &e))?;
        files.push(MANIFEST.to_string());
        files.sort();
        let manifest = manifest_json(&self.command, error, &files);
        self.write(MANIFEST, manifest.as_bytes())?;
        swap_into_place(&self.staging, &self.target)?;
        self.done = true;
        Ok(())
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.done {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// Refuses an output `target` named by `option` (a directory that [`OutputDir`] replaces as a
/// whole, or a file that [`write_atomic`] replaces) that is one of `inputs` or holds one:
/// writing it would delete what the run reads. Paths are compared after resolving links and
/// relative parts; a target that does not exist yet replaces nothing.
pub fn refuse_inputs(target: &Path, option: &str, inputs: &[PathBuf]) -> Result<(), OutputError> {
    let Ok(canonical_target) = fs::canonicalize(target) else {
        return Ok(());
    };
    for input in inputs {
        if let Ok(canonical) = fs::canonicalize(input)
            && canonical.starts_with(&canonical_target)
        {
            let (relation, kind) = if canonical_target.is_dir() {
                ("holds", "directory")
            } else {
                ("is", "file")
            };
            return Err(OutputError::invalid(format!(
                "{option} {}: {relation} {}, an input of this run; the output {kind} is \
                 replaced as a whole, so give another {kind}",
                canonical_target.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// The command named by the manifest text `manifest` (`None` if it names none).
fn manifest_command(manifest: &str) -> Option<String> {
    let rest = manifest.split_once("\"command\"")?.1.trim_start();
    let rest = rest.strip_prefix(':')?.trim_start().strip_prefix('"')?;
    let mut command = String::new();
    let mut chars = rest.chars();
    while let Some(c) = chars.next() {
        match c {
            '"' => return Some(command),
            '\\' => command.push(chars.next()?),
            c => command.push(c),
        }
    }
    None
}

/// Refuses a target that is not a directory, or a directory that is neither empty nor an
/// earlier output of the command.
fn check_target(target: &Path, spec: &DirSpec<'_>) -> Result<(), OutputError> {
    let opt = spec.option;
    let meta = match fs::symlink_metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => {
            return Err(OutputError::io(
                &format!("{opt}: cannot inspect"),
                target,
                &e,
            ));
        }
    };
    if meta.file_type().is_symlink() {
        return Err(OutputError::invalid(format!(
            "{opt} {}: is a symbolic link; the output directory is replaced as a whole, so give \
             the directory itself",
            target.display()
        )));
    }
    if !meta.is_dir() {
        return Err(OutputError::invalid(format!(
            "{opt} {}: exists and is not a directory",
            target.display()
        )));
    }
    let mut entries = fs::read_dir(target)
        .map_err(|e| OutputError::io(&format!("{opt}: cannot read"), target, &e))?;
    let empty = entries.next().is_none();
    let manifest = target.join(MANIFEST);
    if manifest.is_file() {
        let text = fs::read_to_string(&manifest)
            .map_err(|e| OutputError::io(&format!("{opt}: cannot read"), &manifest, &e))?;
        return match manifest_command(&text) {
            Some(c) if c == spec.command => Ok(()),
            other => Err(OutputError::invalid(format!(
                "{opt} {}: the directory holds the output of {}, not of `{}`; the output \
                 directory is replaced as a whole, so give a new or empty directory, or one \
                 written by `{}`",
                target.display(),
                other.map_or_else(
                    || format!("an unknown command (its {MANIFEST} names none)"),
                    |c| format!("`{c}`")
                ),
                spec.command,
                spec.command
            ))),
        };
    }
    if empty {
        Ok(())
    } else {
        Err(OutputError::invalid(format!(
            "{opt} {}: the directory exists and was not written by `{}` (it has no {MANIFEST}); \
             the output directory is replaced as a whole, so give a new or empty directory",
            target.display(),
            spec.command
        )))
    }
}

/// Removes staging and backup directories of `name` left in `parent` by processes that no
/// longer exist (killed runs). Only where `/proc` tells which processes exist.
fn remove_stale(parent: &Path, name: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    let own = std::process::id().to_string();
    for e in entries.flatten() {
        let file_name = e.file_name();
        let file_name = file_name.to_string_lossy();
        let rest = [".staging-", ".old-"].iter().find_map(|kind| {
            file_name
                .strip_prefix('.')
                .and_then(|s| s.strip_prefix(name))
                .and_then(|s| s.strip_prefix(kind))
        });
        let Some(pid) = rest.and_then(|r| r.split('-').next()) else {
            continue;
        };
        if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) || pid == own {
            continue;
        }
        if !proc.join(pid).exists() {
            let _ = fs::remove_dir_all(e.path());
        }
    }
}

/// Moves `staging` to `target`, replacing a previous directory there as a whole.
fn swap_into_place(staging: &Path, target: &Path) -> Result<(), OutputError> {
    let moved =
        |e: &io::Error| OutputError::io("cannot move the new output into place at", target, e);
    match fs::symlink_metadata(target) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => match fs::rename(staging, target) {
            Ok(()) => return Ok(()),
            // Created meanwhile by someone else: replace it like an existing one.
            Err(_) if target.is_dir() => {}
            Err(e) => return Err(moved(&e)),
        },
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(OutputError::invalid(format!(
                "cannot move the new output into place at {}: it is no longer a directory",
                target.display()
            )));
        }
        Err(e) => return Err(OutputError::io("cannot inspect", target, &e)),
    }
    #[cfg(target_os = "linux")]
    if exchange(staging, target).is_ok() {
        // `staging` now holds the previous output.
        let _ = fs::remove_dir_all(staging);
        return Ok(());
    }
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let backup =
        parent_of(target).join(format!(".{name}.old-{}-{}", std::process::id(), next_id()));
    fs::rename(target, &backup).map_err(|e| moved(&e))?;
    if let Err(e) = fs::rename(staging, target) {
        let _ = fs::rename(&backup, target);
        return Err(moved(&e));
    }
    let _ = fs::remove_dir_all(&backup);
    Ok(())
}

/// Atomically exchanges two directory entries (Linux ≥ 3.15; not every file system supports it).
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(io::Error::from)
}

/// Relative paths (with `/`) of every file below `dir`.
fn list_files(dir: &Path, prefix: &str, out: &mut Vec<String>) -> io::Result<()> {
    for e in fs::read_dir(dir)? {
        let e = e?;
        let name = format!("{prefix}{}", e.file_name().to_string_lossy());
        if e.file_type()?.is_dir() {
            list_files(&e.path(), &format!("{name}/"), out)?;
        } else {
            out.push(name);
        }
    }
    Ok(())
}

/// The manifest as JSON (written by hand: this crate has no dependencies besides `rustix`).
fn manifest_json(command: &str, error: Option<&str>, files: &[String]) -> String {
    let mut s = String::from("{\n");
    s.push_str(&format!("  \"command\": {},\n", json_string(command)));
    let status = if error.is_some() { "failed" } else { "success" };
    s.push_str(&format!("  \"status\": \"{status}\",\n"));
    match error {
        Some(e) => s.push_str(&format!("  \"error\": {},\n", json_string(e))),
        None => s.push_str("  \"error\": null,\n"),
    }
    s.push_str("  \"files\": [");
    for (i, f) in files.iter().enumerate() {
        s.push_str(if i == 0 { "\n    " } else { ",\n    " });
        s.push_str(&json_string(f));
    }
    s.push_str("\n  ]\n}\n");
    s
}

fn json_string(text: &str) -> String {
    let mut s = String::with_capacity(text.len() + 2);
    s.push('"');
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\r' => s.push_str("\\r"),
            '\t' => s.push_str("\\t"),
            c if (c as u32) < 0x20 => s.push_str(&format!("\\u{:04x}", c as u32)),
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: DirSpec<'static> = DirSpec {
        option: "--out",
        command: "test",
    };

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("bf-output-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn run(target: &Path, files: &[(&str, &str)], fault: Option<usize>) -> Result<(), OutputError> {
        let mut out = OutputDir::create(target, &SPEC, &[])?;
        if let Some(n) = fault {
            out.inject_fault_at_write(n);
        }
        for (name, text) in files {
            out.write(name, text.as_bytes())?;
        }
        out.commit(Outcome::Success)
    }

    #[test]
    fn write_atomic_replaces_content_and_leaves_no_temp_file() {
        let dir = scratch("file");
        let path = dir.join("sub/out.txt");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        assert_eq!(names(&dir.join("sub")), ["out.txt"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn write_atomic_under_a_file_names_the_file_in_the_way() {
        let dir = scratch("under-a-file");
        let file = dir.join("afile");
        fs::write(&file, "kept").unwrap();
        let e = write_atomic(&file.join("sub/out.txt"), b"x").unwrap_err();
        let shown = format!("{} is a file, not a directory", file.display());
        assert!(e.to_string().contains(&shown), "{e}");
        assert_eq!(fs::read_to_string(&file).unwrap(), "kept");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn write_atomic_to_a_full_device_names_it() {
        let e = write_atomic(Path::new("/dev/full"), b"x").unwrap_err();
        assert_eq!(e.kind(), Some(io::ErrorKind::StorageFull), "{e}");
        assert!(e.to_string().contains("/dev/full"), "{e}");
    }

    #[test]
    fn a_new_set_replaces_the_old_one_as_a_whole() {
        let dir = scratch("replace");
        let target = dir.join("out");
        run(&target, &[("a.txt", "1"), ("sub/b.txt", "1")], None).unwrap();
        run(&target, &[("a.txt", "2"), ("c.txt", "2")], None).unwrap();
        // b.txt of the first run is gone: nothing of it is mixed into the second set.
        assert_eq!(names(&target), [MANIFEST, "a.txt", "c.txt"]);
        assert_eq!(fs::read_to_string(target.join("a.txt")).unwrap(), "2");
        let m = fs::read_to_string(target.join(MANIFEST)).unwrap();
        assert!(m.contains("\"status\": \"success\""), "{m}");
        assert!(m.contains("\"c.txt\"") && !m.contains("b.txt"), "{m}");
        assert_eq!(names(&dir), ["out"], "no staging or backup directory left");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_run_stopped_between_two_writes_leaves_the_previous_set() {
        let dir = scratch("fault");
        let target = dir.join("out");
        run(&target, &[("a.txt", "old"), ("b.txt", "old")], None).unwrap();
        let e = run(&target, &[("a.txt", "new"), ("b.txt", "new")], Some(2)).unwrap_err();
        assert!(e.to_string().contains("b.txt"), "{e}");
        assert_eq!(fs::read_to_string(target.join("a.txt")).unwrap(), "old");
        assert_eq!(fs::read_to_string(target.join("b.txt")).unwrap(), "old");
        assert_eq!(names(&dir), ["out"], "no staging directory left");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failed_run_is_marked() {
        let dir = scratch("failed");
        let target = dir.join("out");
        let mut out = OutputDir::create(&target, &SPEC, &[]).unwrap();
        out.write("x.csv", b"t\n").unwrap();
        out.commit(Outcome::Failed("solver stopped: \"max iter\""))
            .unwrap();
        assert_eq!(
            fs::read_to_string(target.join(FAILED)).unwrap(),
            "solver stopped: \"max iter\"\n"
        );
        let m = fs::read_to_string(target.join(MANIFEST)).unwrap();
        assert!(m.contains("\"status\": \"failed\""), "{m}");
        assert!(
            m.contains(r#""error": "solver stopped: \"max iter\"""#),
            "{m}"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn concurrent_runs_get_distinct_staging_directories() {
        let dir = scratch("twice");
        let target = dir.join("out");
        let a = OutputDir::create(&target, &SPEC, &[]).unwrap();
        let b = OutputDir::create(&target, &SPEC, &[]).unwrap();
        assert_ne!(a.path(), b.path());
        drop(a);
        drop(b);
        assert!(names(&dir).is_empty(), "{:?}", names(&dir));
        let c = OutputDir::create(&target, &SPEC, &[]).unwrap();
        let msg = format!(
            "I/O error on {}: disk full",
            c.path().join("x.csv").display()
        );
        assert_eq!(
            c.rename_in(&msg),
            format!("I/O error on {}: disk full", target.join("x.csv").display())
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn foreign_targets_are_refused_before_any_work() {
        let dir = scratch("refuse");
        let file = dir.join("file.txt");
        fs::write(&file, "x").unwrap();
        let e = OutputDir::create(&file, &SPEC, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--out") && e.contains("not a directory"), "{e}");
        let e = OutputDir::create(&file.join("sub"), &SPEC, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--out") && e.contains("file.txt"), "{e}");
        let foreign = dir.join("src");
        fs::create_dir_all(&foreign).unwrap();
        fs::write(foreign.join("main.rs"), "fn main() {}").unwrap();
        let e = OutputDir::create(&foreign, &SPEC, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("was not written by `test`"), "{e}");
        assert!(OutputDir::create(Path::new(".."), &SPEC, &[]).is_err());
        // A file of the command's name does not make a directory its output: the notes
        // beside it would be lost.
        let stored = dir.join("stored");
        fs::create_dir_all(stored.join("sub")).unwrap();
        fs::write(stored.join("summary.json"), "{}").unwrap();
        fs::write(stored.join("sub/notes.txt"), "keep").unwrap();
        let e = run(&stored, &[("summary.json", "{\"new\":1}")], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("has no .ball-finger.json"), "{e}");
        assert_eq!(
            fs::read_to_string(stored.join("sub/notes.txt")).unwrap(),
            "keep"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn another_commands_output_and_a_runs_own_inputs_are_refused() {
        let dir = scratch("others");
        let target = dir.join("out");
        run(&target, &[("solution.json", "{}")], None).unwrap();
        let other = DirSpec {
            command: "other",
            ..SPEC
        };
        let e = OutputDir::create(&target, &other, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("output of `test`, not of `other`"), "{e}");
        assert_eq!(names(&target), [MANIFEST, "solution.json"]);
        // The same command may replace its own output, unless the run reads from it.
        let input = target.join("solution.json");
        let e = OutputDir::create(&target, &SPEC, std::slice::from_ref(&input))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("an input of this run") && e.contains("solution.json"),
            "{e}"
        );
        let e = OutputDir::create(&target, &SPEC, std::slice::from_ref(&target))
            .unwrap_err()
            .to_string();
        assert!(e.contains("an input of this run"), "{e}");
        let elsewhere = dir.join("in.json");
        fs::write(&elsewhere, "{}").unwrap();
        drop(OutputDir::create(&target, &SPEC, std::slice::from_ref(&elsewhere)).unwrap());
        // A manifest that names no command is nobody's.
        fs::write(target.join(MANIFEST), "{}").unwrap();
        let e = OutputDir::create(&target, &SPEC, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("names none"), "{e}");
        assert_eq!(
            manifest_command("{\n  \"command\": \"a \\\"b\\\"\",\n}").as_deref(),
            Some("a \"b\"")
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn exchange_swaps_two_directories() {
        let dir = scratch("exchange");
        let (a, b) = (dir.join("a"), dir.join("b"));
        fs::create_dir_all(&a).unwrap();
        fs::create_dir_all(&b).unwrap();
        fs::write(a.join("x"), "a").unwrap();
        fs::write(b.join("x"), "b").unwrap();
        exchange(&a, &b).unwrap();
        assert_eq!(fs::read_to_string(a.join("x")).unwrap(), "b");
        assert_eq!(fs::read_to_string(b.join("x")).unwrap(), "a");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn staging_directories_of_dead_processes_are_removed() {
        let dir = scratch("stale");
        // Process ids above the kernel's limit (2^22) never exist.
        let stale = dir.join(".out.staging-4999999-0");
        fs::create_dir_all(stale.join("sub")).unwrap();
        run(&dir.join("out"), &[("a.txt", "1")], None).unwrap();
        assert_eq!(names(&dir), ["out"]);
        fs::remove_dir_all(&dir).unwrap();
    }
}
