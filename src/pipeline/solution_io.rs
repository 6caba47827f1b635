//! Reading and writing solutions: `solution.json` ([`SolutionIo::write_json`],
//! [`SolutionIo::read_json`]), `solution-internals.json` beside it, and `torques.csv`
//! ([`SolutionIo::write_torques_csv`], the format `simulate --torques` reads), each written
//! atomically.
//!
//! `solution.json` (schema [`SCHEMA_VERSION`]) describes itself: `schema_version`, `units` of
//! every quantity, `state_names` (q1..qn, qd1..qdn, omega_x, omega_y, omega_z), the solver
//! `status`, `verified` and, in the re-integration record `verification`, the block
//! {defect, tolerance, verified} ([`verified_block`]), mode names
//! in lowercase as in the simulator's files, and the trajectory at the collocation points
//! (`nodes`) and on a dense grid (`dense`) as one named column per component. What only warm
//! starts need (the raw collocation data, the primal-dual point, static parameters, solver
//! timings in seconds and counters) is in `solution-internals.json`, which
//! [`SolutionIo::read_json`] reads too. Files without `schema_version` (the format before
//! schema 2: the whole record in one file) are still read.

use std::path::Path;

use anyhow::Context;
use serde_json::{Map, Value, json};

use bf_output::FileError;
use bf_problem::{OcpSolution, PhaseMode};

use super::error::PipelineError;

/// Version of the `solution.json` layout written by [`SolutionIo::write_json`].
pub const SCHEMA_VERSION: u64 = 2;

/// File name of the internals beside `solution.json` ([`internals_file`] of it).
pub const INTERNALS_FILE: &str = "solution-internals.json";

/// File name of the internals of the solution file `path`: its stem with `-internals.json`
/// (`solution.json` → [`INTERNALS_FILE`], `candidate-0003.json` →
/// `candidate-0003-internals.json`), so every solution file in a directory has its own and no
/// write of one solution replaces another's warm-start data.
pub fn internals_file(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map_or_else(|| "solution".into(), |s| s.to_string_lossy().into_owned());
    format!("{stem}-internals.json")
}

/// Fields of [`OcpSolution`] that go to [`INTERNALS_FILE`].
const INTERNAL_FIELDS: [&str; 5] = ["raw", "nlp_warm", "params", "timing", "counters"];

fn io_err(path: &Path, e: impl std::fmt::Display) -> PipelineError {
    PipelineError::SolutionFile {
        path: path.into(),
        reason: e.to_string(),
    }
}

/// Writes one solution file (ball or arm) through the workspace's one atomic writer
/// ([`bf_output::replace_file`]), so a failed or interrupted write never leaves a truncated
/// `solution.json` / `torques.csv` behind.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), PipelineError> {
    bf_output::replace_file(path, bytes).map_err(|e| FileError::new("cannot write", path, e).into())
}

/// File input and output of an [`OcpSolution`].
pub trait SolutionIo: Sized {
    /// Writes `solution.json` and, beside it, [`INTERNALS_FILE`].
    fn write_json(&self, path: &Path) -> Result<(), PipelineError>;
    /// Reads a solution written by [`SolutionIo::write_json`] (or a file of the format before
    /// schema 2).
    fn read_json(path: &Path) -> Result<Self, PipelineError>;
    /// Writes [`OcpSolution::torques_csv`] to `path`.
    fn write_torques_csv(&self, path: &Path) -> Result<(), PipelineError>;
}

/// The state component names of an `nq`-joint finger: q1..qn, qd1..qdn, omega_x..omega_z.
pub fn state_names(nq: usize) -> Vec<String> {
    let mut v: Vec<String> = (1..=nq).map(|i| format!("q{i}")).collect();
    v.extend((1..=nq).map(|i| format!("qd{i}")));
    v.extend(["omega_x", "omega_y", "omega_z"].map(String::from));
    v
}

/// Component names and units of one trajectory table (`nodes`, `dense`), in column order.
fn sample_columns(nq: usize) -> Vec<(String, &'static str)> {
    let mut v = vec![("t".to_string(), "s"), ("phase".to_string(), "1")];
    v.extend((1..=nq).map(|i| (format!("q{i}"), "rad")));
    v.extend((1..=nq).map(|i| (format!("qd{i}"), "rad/s")));
    v.extend(["omega_x", "omega_y", "omega_z"].map(|n| (n.to_string(), "rad/s")));
    v.extend((1..=nq).map(|i| (format!("tau{i}"), "N m")));
    v.extend(["lambda_x", "lambda_y", "lambda_z"].map(|n| (n.to_string(), "N")));
    v.extend([
        ("h".to_string(), "m"),
        ("sigma".to_string(), "N"),
        ("alpha".to_string(), "m"),
    ]);
    v
}

/// Units of every quantity in `solution.json`.
fn units(nq: usize) -> Value {
    let mut m = Map::new();
    for (k, u) in [
        (
            "objective",
            "cost of the problem (c1, or c1/c2 for the periodic problems)",
        ),
        ("c1", "cost state c1"),
        ("c2", "s (cost state c2)"),
        ("phase_durations", "s"),
        ("period", "s"),
        ("mean_omega", "rad/s"),
        ("impulse", "N s"),
        ("solve_seconds", "s"),
        ("constraint_violation", "scaled NLP units"),
        ("dual_infeasibility", "scaled NLP units"),
        ("epsilon", "m"),
        ("verification.defect", "state units (rad, rad/s)"),
        ("verification.*.seconds", "s"),
    ] {
        m.insert(k.into(), Value::from(u));
    }
    for (c, u) in sample_columns(nq) {
        m.insert(format!("nodes.{c}, dense.{c}"), Value::from(u));
    }
    Value::Object(m)
}

fn columns(samples: &Value, nq: usize) -> Value {
    let mut m = Map::new();
    let get = |k: &str| {
        samples
            .get(k)
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default()
    };
    m.insert("t".into(), Value::Array(get("t")));
    m.insert("phase".into(), Value::Array(get("phase")));
    let split = |key: &str, names: &[String], m: &mut Map<String, Value>| {
        let rows = get(key);
        for (j, n) in names.iter().enumerate() {
            let col: Vec<Value> = rows
                .iter()
                .map(|r| r.get(j).cloned().unwrap_or(Value::Null))
                .collect();
            m.insert(n.clone(), Value::Array(col));
        }
    };
    let idx = |p: &str| (1..=nq).map(|i| format!("{p}{i}")).collect::<Vec<_>>();
    let xyz = |p: &str| ["x", "y", "z"].map(|a| format!("{p}_{a}")).to_vec();
    split("q", &idx("q"), &mut m);
    split("qd", &idx("qd"), &mut m);
    split("omega", &xyz("omega"), &mut m);
    split("tau", &idx("tau"), &mut m);
    split("lambda", &xyz("lambda"), &mut m);
    for k in ["h", "sigma", "alpha"] {
        m.insert(k.into(), Value::Array(get(k)));
    }
    Value::Object(m)
}

/// The trajectory table `cols` (one named column per component) as rows per quantity. Every
/// column holds one entry per sample of `t`: an edited column of another length is an error
/// that names it (rows are built by index, so a shorter one would index past its end).
fn uncolumns(cols: &Value, table: &str, nq: usize, path: &Path) -> Result<Value, PipelineError> {
    let column = |k: &str| -> Result<Vec<Value>, PipelineError> {
        cols.get(k)
            .and_then(Value::as_array)
            .cloned()
            .ok_or_else(|| io_err(path, format!("trajectory column `{table}.{k}` missing")))
    };
    let t = column("t")?;
    let n = t.len();
    let get = |k: &str| -> Result<Vec<Value>, PipelineError> {
        let c = column(k)?;
        if c.len() != n {
            return Err(io_err(
                path,
                format!(
                    "trajectory column `{table}.{k}` has {} samples, `{table}.t` {n}: every \
                     column holds one entry per sample",
                    c.len()
                ),
            ));
        }
        Ok(c)
    };
    let join = |names: Vec<String>| -> Result<Value, PipelineError> {
        let cs: Vec<Vec<Value>> = names.iter().map(|n| get(n)).collect::<Result<_, _>>()?;
        Ok(Value::Array(
            (0..n)
                .map(|i| Value::Array(cs.iter().map(|c| c[i].clone()).collect()))
                .collect(),
        ))
    };
    let idx = |p: &str| (1..=nq).map(|i| format!("{p}{i}")).collect::<Vec<_>>();
    let xyz = |p: &str| ["x", "y", "z"].map(|a| format!("{p}_{a}")).to_vec();
    let mut m = Map::new();
    m.insert("t".into(), Value::Array(t.clone()));
    m.insert("phase".into(), Value::Array(get("phase")?));
    m.insert("q".into(), join(idx("q"))?);
    m.insert("qd".into(), join(idx("qd"))?);
    m.insert("omega".into(), join(xyz("omega"))?);
    m.insert("tau".into(), join(idx("tau"))?);
    m.insert("lambda".into(), join(xyz("lambda"))?);
    for k in ["h", "sigma", "alpha"] {
        m.insert(k.into(), Value::Array(get(k)?));
    }
    Ok(Value::Object(m))
}

/// Durations `{secs, nanos}` → seconds.
fn timing_seconds(timing: &Value) -> Value {
    let mut m = Map::new();
    if let Some(o) = timing.as_object() {
        for (k, v) in o {
            let s = v.get("secs").and_then(Value::as_f64).unwrap_or(0.0)
                + v.get("nanos").and_then(Value::as_f64).unwrap_or(0.0) * 1e-9;
            m.insert(k.clone(), Value::from(s));
        }
    }
    Value::Object(m)
}

/// Seconds → durations `{secs, nanos}` (the solver's own record).
fn timing_durations(seconds: &Value) -> Value {
    let mut m = Map::new();
    if let Some(o) = seconds.as_object() {
        for (k, v) in o {
            let d = std::time::Duration::from_secs_f64(v.as_f64().unwrap_or(0.0).max(0.0));
            m.insert(
                k.clone(),
                json!({"secs": d.as_secs(), "nanos": d.subsec_nanos()}),
            );
        }
    }
    Value::Object(m)
}

/// The verification block {defect, tolerance, verified} of a re-integrated solution: its
/// largest end-of-phase state error, [`super::verify::VERIFIED_DEFECT`], and whether the
/// solution is verified ([`super::verify::is_verified`]); None without a re-integration.
pub fn verified_block(sol: &OcpSolution) -> Option<Value> {
    sol.verification.as_ref().map(|v| {
        json!({
            "defect": v.max_defect,
            "tolerance": super::verify::VERIFIED_DEFECT,
            "verified": super::verify::is_verified(sol),
        })
    })
}

/// The two documents written for `sol`: `solution.json` and the internals.
pub fn documents(
    sol: &OcpSolution,
    internals_name: &str,
) -> Result<(Value, Value), serde_json::Error> {
    let Value::Object(mut all) = serde_json::to_value(sol)? else {
        return Ok((Value::Null, Value::Null));
    };
    let nq = sol.nodes.q.first().map_or(3, Vec::len);
    let mut internals = Map::new();
    internals.insert("schema_version".into(), Value::from(SCHEMA_VERSION));
    internals.insert("problem".into(), Value::from(sol.problem.clone()));
    for k in INTERNAL_FIELDS {
        let v = all.remove(k).unwrap_or(Value::Null);
        if k == "timing" {
            internals.insert("timing_seconds".into(), timing_seconds(&v));
        } else {
            internals.insert(k.into(), v);
        }
    }
    let mut public = Map::new();
    public.insert("schema_version".into(), Value::from(SCHEMA_VERSION));
    public.insert("internals".into(), Value::from(internals_name));
    public.insert("problem".into(), Value::from(sol.problem.clone()));
    public.insert(
        "status".into(),
        Value::from(crate::names::name(&sol.status)),
    );
    public.insert(
        "verified".into(),
        Value::from(super::verify::is_verified(sol)),
    );
    public.insert("units".into(), units(nq));
    public.insert("state_names".into(), json!(state_names(nq)));
    all.remove("status");
    all.remove("problem");
    if let (Some(Value::Object(v)), Some(Value::Object(b))) =
        (all.get_mut("verification"), verified_block(sol))
    {
        v.extend(b);
    }
    all.insert(
        "modes".into(),
        json!(
            sol.modes
                .iter()
                .map(|m| crate::names::name(m).to_lowercase())
                .collect::<Vec<_>>()
        ),
    );
    all.insert(
        "mean_omega".into(),
        json!({"omega_x": sol.mean_omega[0], "omega_y": sol.mean_omega[1], "omega_z": sol.mean_omega[2]}),
    );
    all.insert(
        "nlp_size".into(),
        json!({"variables": sol.nlp_size.0, "constraints": sol.nlp_size.1}),
    );
    for k in ["nodes", "dense"] {
        let v = all.remove(k).unwrap_or(Value::Null);
        all.insert(k.into(), columns(&v, nq));
    }
    public.extend(all);
    Ok((Value::Object(public), Value::Object(internals)))
}

/// Rebuilds the record from the two documents of schema 2.
fn from_documents(
    public: &Value,
    internals: &Value,
    path: &Path,
) -> Result<OcpSolution, PipelineError> {
    let Value::Object(p) = public else {
        return Err(io_err(path, "not a JSON object"));
    };
    // Derived from `verification` when read, but a reader of the file alone takes it as said.
    if let Some(v) = p.get("verified").filter(|v| !v.is_boolean()) {
        return Err(io_err(
            path,
            format!("`verified` is {v}, not true or false"),
        ));
    }
    let mut all = p.clone();
    let nq = p
        .get("state_names")
        .and_then(Value::as_array)
        .map_or(3, |v| v.len().saturating_sub(3) / 2);
    for k in [
        "schema_version",
        "internals",
        "units",
        "state_names",
        "verified",
    ] {
        all.remove(k);
    }
    let modes: Vec<Value> = p
        .get("modes")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default()
        .into_iter()
        .map(|m| match m.as_str() {
            // The record's mode names are capitalised (Free, Stick).
            Some(s) => {
                let mut c = s.chars();
                Value::from(
                    c.next()
                        .map_or(String::new(), |f| f.to_uppercase().chain(c).collect()),
                )
            }
            None => m,
        })
        .collect();
    all.insert("modes".into(), Value::Array(modes));
    if let Some(w) = p.get("mean_omega") {
        all.insert(
            "mean_omega".into(),
            json!([w.get("omega_x"), w.get("omega_y"), w.get("omega_z")]),
        );
    }
    if let Some(n) = p.get("nlp_size") {
        all.insert(
            "nlp_size".into(),
            json!([n.get("variables"), n.get("constraints")]),
        );
    }
    for k in ["nodes", "dense"] {
        let cols = p.get(k).cloned().unwrap_or(Value::Null);
        all.insert(k.into(), uncolumns(&cols, k, nq, path)?);
    }
    for k in INTERNAL_FIELDS {
        let v = if k == "timing" {
            timing_durations(internals.get("timing_seconds").unwrap_or(&Value::Null))
        } else {
            internals.get(k).cloned().unwrap_or(Value::Null)
        };
        all.insert(k.into(), v);
    }
    serde_json::from_value(Value::Object(all)).map_err(|e| io_err(path, e))
}

/// Errors naming both files unless the internals `internals` (read from `ipath`) belong to
/// the solution `sol` read from `path`: the same problem and one phase of raw collocation
/// data per phase of the solution (a warm start interpolates phase by phase).
fn check_internals_belong(
    sol: &OcpSolution,
    internals: &Value,
    path: &Path,
    ipath: &Path,
) -> Result<(), PipelineError> {
    let theirs = internals.get("problem").and_then(Value::as_str);
    if theirs != Some(sol.problem.as_str()) {
        return Err(io_err(
            ipath,
            format!(
                "its `problem` is {}, {}'s is `{}`: the internals belong to another \
                 solution",
                theirs.map_or("missing".to_string(), |t| format!("`{t}`")),
                path.display(),
                sol.problem
            ),
        ));
    }
    for (i, raw) in sol.raw.iter().enumerate() {
        raw.check_shape()
            .map_err(|m| io_err(ipath, format!("raw[{i}]: {m}")))?;
    }
    if sol.raw.len() != sol.modes.len() {
        return Err(io_err(
            ipath,
            format!(
                "it has {} phases of raw collocation data, {} has {} phases: the internals \
                 belong to another solution",
                sol.raw.len(),
                path.display(),
                sol.modes.len()
            ),
        ));
    }
    // A node's algebraic variables are q̈ and ω̇, and λ after them in a stick phase
    // (bf-problem's node layout): a mode edited in `solution.json` would time a contact phase
    // as a flight, or the reverse, when the plan is replayed. Only a width that is the other
    // mode's is blamed on `modes`; any other misfit is the collocation data's, which a warm
    // start checks against the problem.
    let Some(nq) = sol.nodes.q.first().map(Vec::len) else {
        return Ok(());
    };
    for (i, (raw, mode)) in sol.raw.iter().zip(&sol.modes).enumerate() {
        let Some(a) = raw.a.first() else {
            continue;
        };
        let stick = matches!(mode, PhaseMode::Stick);
        let other = nq + 3 + if stick { 0 } else { 3 };
        if a.len() == other {
            return Err(io_err(
                path,
                format!(
                    "`modes[{i}]` is `{}`, but its collocation data (raw[{i}] of {}) hold {} \
                     algebraic values per node, a {} phase's",
                    crate::names::name(mode),
                    ipath.display(),
                    a.len(),
                    if stick { "free" } else { "stick" }
                ),
            ));
        }
    }
    Ok(())
}

/// The internals file of the solution file `path` with document `v`: the name its
/// `internals` field gives, beside it ([`internals_file`] of `path` if the field is absent).
/// Errors naming the field unless that is a plain file name: `optimize` writes the internals
/// beside their solution, and a name with a directory in it would read whatever file it
/// points to as one.
pub fn internals_path(path: &Path, v: &Value) -> Result<std::path::PathBuf, PipelineError> {
    let Some(field) = v.get("internals") else {
        return Ok(path.with_file_name(internals_file(path)));
    };
    let plain = field.as_str().filter(|name| {
        let mut parts = Path::new(name).components();
        matches!(
            (parts.next(), parts.next()),
            (Some(std::path::Component::Normal(n)), None) if n == std::ffi::OsStr::new(name)
        )
    });
    match plain {
        Some(name) => Ok(path.with_file_name(name)),
        None => Err(io_err(
            path,
            format!(
                "its `internals` ({field}) is not the name of a file beside it, as `optimize` \
                 writes it (e.g. \"solution-internals.json\")"
            ),
        )),
    }
}

/// A solution from the text of its two documents (`solution.json` as `public`, the internals
/// it names as `internals`), named `path` and `ipath` in errors: [`SolutionIo::read_json`] for
/// documents held elsewhere (e.g. compiled into the program), the same checks included.
pub fn read_documents(
    public: &str,
    internals: &str,
    path: &Path,
    ipath: &Path,
) -> Result<OcpSolution, PipelineError> {
    from_texts(public, path, |_| {
        Ok((internals.to_string(), ipath.to_path_buf()))
    })
}

/// The solution of the `solution.json` text `s` (named `path` in errors): before schema 2 the
/// record itself; of schema 2 with its internals, whose text and path `internals` gives for
/// the parsed document.
fn from_texts(
    s: &str,
    path: &Path,
    internals: impl FnOnce(&Value) -> Result<(String, std::path::PathBuf), PipelineError>,
) -> Result<OcpSolution, PipelineError> {
    let v: Value = crate::io::json_value(s).map_err(|e| io_err(path, e))?;
    check_schema_version(&v, path)?;
    check_range(&v, path)?;
    if v.get("schema_version").is_none() {
        let sol = serde_json::from_value(v).map_err(|e| io_err(path, e))?;
        check_recorded(&sol, path)?;
        return Ok(sol);
    }
    let (text, ipath) = internals(&v)?;
    let internals: Value = crate::io::json_value(&text).map_err(|e| io_err(&ipath, e))?;
    check_schema_version(&internals, &ipath)?;
    check_range(&internals, &ipath)?;
    check_internal_fields(&internals, &ipath)?;
    let sol = from_documents(&v, &internals, path)?;
    check_phases(&sol, path)?;
    check_recorded(&sol, path)?;
    check_internals_belong(&sol, &internals, path, &ipath)?;
    Ok(sol)
}

/// Largest magnitude of any number in a solution's files: values beyond it are not a solution
/// of these problems (angles, velocities, torques, durations, multipliers) and overflow the
/// solver's products when the file comes back as a warm start.
pub const MAX_SOLUTION_VALUE: f64 = 1e12;

/// The first number of the document `v` that is NaN or beyond [`MAX_SOLUTION_VALUE`] in
/// magnitude, with its field path (`nodes.q1[3]`).
pub fn out_of_range(v: &Value) -> Option<(String, f64)> {
    fn walk(v: &Value, at: &mut String) -> Option<(String, f64)> {
        match v {
            Value::Number(n) => n
                .as_f64()
                .filter(|x| x.is_nan() || x.abs() > MAX_SOLUTION_VALUE)
                .map(|x| (at.clone(), x)),
            Value::Array(a) => a.iter().enumerate().find_map(|(i, x)| {
                let len = at.len();
                at.push_str(&format!("[{i}]"));
                let r = walk(x, at);
                at.truncate(len);
                r
            }),
            Value::Object(o) => o.iter().find_map(|(k, x)| {
                let len = at.len();
                if !at.is_empty() {
                    at.push('.');
                }
                at.push_str(k);
                let r = walk(x, at);
                at.truncate(len);
                r
            }),
            _ => None,
        }
    }
    walk(v, &mut String::new())
}

/// Errors naming `path`, the field and the value at [`out_of_range`]'s first find.
fn check_range(v: &Value, path: &Path) -> Result<(), PipelineError> {
    match out_of_range(v) {
        None => Ok(()),
        Some((field, x)) => Err(io_err(
            path,
            format!("`{field}` = {x:e} is out of range (|value| ≤ {MAX_SOLUTION_VALUE:e})"),
        )),
    }
}

/// [`super::solve::check_recorded_problem`] of `sol`, the error naming `path`.
fn check_recorded(sol: &OcpSolution, path: &Path) -> Result<(), PipelineError> {
    super::solve::check_recorded_problem(sol).map_err(|why| io_err(path, why))
}

/// Errors naming `path` unless the fields of the `solution.json` document `v` agree among
/// themselves (the checks of [`SolutionIo::read_json`] that need no internals: phases, durations,
/// period, the trajectory tables' columns and times). For a reader that uses the public
/// document alone, as `simulate --init` does: it replays a plan by its period and first node,
/// so a file whose own fields disagree is refused there as everywhere.
pub fn check_public_fields(v: &Value, path: &Path) -> Result<(), PipelineError> {
    check_schema_version(v, path)?;
    check_range(v, path)?;
    let sol: OcpSolution = if v.get("schema_version").is_none() {
        serde_json::from_value(v.clone()).map_err(|e| io_err(path, e))?
    } else {
        // Internals without data, in the form the writer gives them.
        let timing = serde_json::to_value(bf_optim::ipm::Timing::default());
        let counters = serde_json::to_value(bf_optim::ipm::Counters::default());
        let (timing, counters) = (
            timing.map_err(|e| io_err(path, e))?,
            counters.map_err(|e| io_err(path, e))?,
        );
        let empty = json!({"raw": [], "params": [], "nlp_warm": null, "counters": counters,
            "timing_seconds": timing_seconds(&timing)});
        from_documents(v, &empty, path)?
    };
    check_phases(&sol, path)?;
    check_recorded(&sol, path)
}

/// Errors naming the internals file `ipath` and the field unless its collocation data,
/// parameters and NLP point read as their types: the two documents are read as one, and a
/// field missing from the internals would otherwise be blamed on `solution.json`.
fn check_internal_fields(internals: &Value, ipath: &Path) -> Result<(), PipelineError> {
    fn check<T: serde::de::DeserializeOwned>(
        internals: &Value,
        key: &str,
        ipath: &Path,
    ) -> Result<(), PipelineError> {
        let v = internals.get(key).cloned().unwrap_or(Value::Null);
        serde_json::from_value::<T>(v)
            .map(drop)
            .map_err(|e| io_err(ipath, format!("`{key}`: {e}")))
    }
    check::<Vec<bf_optim::ocp::PhaseTrajectory>>(internals, "raw", ipath)?;
    check::<Vec<f64>>(internals, "params", ipath)?;
    check::<Option<bf_optim::ipm::WarmStart>>(internals, "nlp_warm", ipath)
}

/// Errors naming `path` unless the solution's own fields agree: at least one phase, one
/// positive duration per mode, a period that is their sum, and trajectory tables of times
/// that do not decrease within the phases. Checked before the internals, so an edited `modes`
/// is blamed on the field and not on the internals it no longer matches.
fn check_phases(sol: &OcpSolution, path: &Path) -> Result<(), PipelineError> {
    if sol.modes.is_empty() {
        return Err(io_err(
            path,
            "`modes` is empty: a solution has at least one phase",
        ));
    }
    if sol.phase_durations.len() != sol.modes.len() {
        return Err(io_err(
            path,
            format!(
                "`modes` lists {} phases and `phase_durations` {}: one duration per phase",
                sol.modes.len(),
                sol.phase_durations.len()
            ),
        ));
    }
    if let Some((i, d)) = sol
        .phase_durations
        .iter()
        .enumerate()
        .find(|(_, d)| !(d.is_finite() && **d > 0.0))
    {
        return Err(io_err(
            path,
            format!("`phase_durations[{i}]` is {d}: a phase lasts a finite positive time"),
        ));
    }
    // `track` and `simulate --init` time the plan by `period`, the verification and a warm
    // start by the durations: an edit of one without the other would replay another plan.
    let sum: f64 = sol.phase_durations.iter().sum();
    if (sol.period - sum).abs() > 1e-9 * sum {
        return Err(io_err(
            path,
            format!(
                "`period` is {} s but `phase_durations` add up to {sum} s: the period is the \
                 sum of the phases' durations",
                sol.period
            ),
        ));
    }
    for (name, samples) in [("nodes", &sol.nodes), ("dense", &sol.dense)] {
        check_samples(samples, sol.modes.len())
            .map_err(|m| io_err(path, format!("`{name}`: {m}")))?;
    }
    Ok(())
}

/// Why a trajectory table of a solution of `phases` phases does not fit, if it does not: times
/// that decrease, or phase indices beyond `phases` (the columns' lengths are checked where the
/// table is read, in `uncolumns`).
fn check_samples(s: &bf_problem::Samples, phases: usize) -> Result<(), String> {
    let n = s.t.len();
    if let Some(k) = (1..n).find(|&k| s.t[k].partial_cmp(&s.t[k - 1]).is_none_or(|o| o.is_lt())) {
        return Err(format!(
            "`t[{k}]` = {} comes before `t[{}]` = {}: times do not decrease",
            s.t[k],
            k - 1,
            s.t[k - 1]
        ));
    }
    if let Some(k) = s.phase.iter().position(|&p| p >= phases) {
        return Err(format!(
            "`phase[{k}]` is {}, but the solution has {phases} phases (numbered from 0)",
            s.phase[k]
        ));
    }
    Ok(())
}

/// Refuses a solution document `v` (of the file `path`) whose `schema_version` this program
/// does not read: a newer schema may mean other things by the same fields.
pub fn check_schema_version(v: &Value, path: &Path) -> Result<(), PipelineError> {
    match v.get("schema_version").map(|x| (x, x.as_u64())) {
        // Only schema 2 names an internals file: without its version it would be read as the
        // older one-file record, and blamed for the fields that went to the internals.
        None if v.get("internals").is_some() => Err(io_err(
            path,
            format!(
                "`schema_version` is missing (a file that names its `internals` is of schema {SCHEMA_VERSION})"
            ),
        )),
        None | Some((_, Some(SCHEMA_VERSION))) => Ok(()),
        Some((x, _)) => Err(io_err(
            path,
            format!(
                "schema_version {x} is not one this program reads (it reads {SCHEMA_VERSION} \
                 and files without schema_version)"
            ),
        )),
    }
}

impl SolutionIo for OcpSolution {
    fn write_json(&self, path: &Path) -> Result<(), PipelineError> {
        let name = internals_file(path);
        let (public, internals) = documents(self, &name).map_err(|e| io_err(path, e))?;
        let ipath = path.with_file_name(&name);
        let s = serde_json::to_string_pretty(&internals).map_err(|e| io_err(&ipath, e))?;
        write_file(&ipath, s.as_bytes())?;
        let s = serde_json::to_string_pretty(&public).map_err(|e| io_err(path, e))?;
        write_file(path, s.as_bytes())
    }

    fn read_json(path: &Path) -> Result<OcpSolution, PipelineError> {
        let s = bf_codegen::spec::read_input_text(path)
            .map_err(|e| FileError::new("cannot read", path, e))?;
        from_texts(&s, path, |v| {
            let ipath = internals_path(path, v)?;
            let text = bf_codegen::spec::read_input_text(&ipath).map_err(|e| {
                io_err(
                    &ipath,
                    format!("cannot read the internals of {} ({e})", path.display()),
                )
            })?;
            Ok((text, ipath))
        })
    }

    fn write_torques_csv(&self, path: &Path) -> Result<(), PipelineError> {
        write_file(path, torques_csv(self).as_bytes())
    }
}

/// Samples per phase of `torques.csv`: with linear interpolation between them (as `simulate
/// --torques` reads it), the torques of a replay then differ from the collocation polynomials
/// by far less than the verification tolerance (the 100 dense samples per phase leave
/// state errors of order 1e-4 in a replay).
pub const TORQUE_SAMPLES_PER_PHASE: usize = 1000;

/// Torque limits of the scene the solution was computed on: the scene it records
/// (`scene_toml` with its `scene_params`, a user's file as much as a compiled one); for a file
/// that records none (written before), the built-in scene its verification or its problem
/// names. `None` where neither is known.
fn tau_max_of(sol: &OcpSolution) -> Option<Vec<f64>> {
    // A joint without a limit is unbounded (as the problem poses it).
    use bf_problem::arm::torque_limits;
    if let Some(scene) = super::solve::recorded_scene(sol).ok()? {
        return Some(torque_limits(&scene));
    }
    let scene = match &sol.verification {
        Some(v) => v.scene.clone(),
        None => sol
            .problem
            .parse::<bf_problem::Problem>()
            .ok()?
            .scene()
            .to_string(),
    };
    let text = bf_generated::scene_toml(&scene)?;
    let spec = bf_codegen::Scene::from_toml_str(text, &scene).ok()?;
    Some(torque_limits(&spec))
}

/// `torques.csv`: `t [s],tau1 [N m],…`, [`TORQUE_SAMPLES_PER_PHASE`] samples per phase of the
/// collocation polynomials clamped to the torque limits (the interpolant the verification
/// re-integrates), strictly increasing in t; the dense samples
/// ([`OcpSolution::torques_csv`]) when the raw data or the limits are not available.
pub fn torques_csv(sol: &OcpSolution) -> String {
    let nq = sol.dense.tau.first().map_or(0, Vec::len);
    let tau_max = match tau_max_of(sol) {
        Some(m) if m.len() == nq && !sol.raw.is_empty() => m,
        _ => return sol.torques_csv(),
    };
    let mut s = String::from("t [s]");
    for i in 1..=nq {
        s.push_str(&format!(",tau{i} [N m]"));
    }
    s.push('\n');
    let mut last = f64::NEG_INFINITY;
    let n = TORQUE_SAMPLES_PER_PHASE;
    for tr in &sol.raw {
        for k in 0..=n {
            let tau = -1.0 + 2.0 * k as f64 / n as f64;
            let t = tr.time(tau);
            if t <= last || !t.is_finite() {
                continue;
            }
            last = t;
            s.push_str(&format!("{t:?}"));
            for (u, m) in tr.u_at(tau).iter().zip(&tau_max) {
                s.push_str(&format!(",{:?}", u.clamp(-m, *m)));
            }
            s.push('\n');
        }
    }
    s
}

/// An initial state read from a solution file: q (rad), q̇ (rad/s), ω (rad/s), mode name.
pub type InitialState = (Vec<f64>, Vec<f64>, [f64; 3], String);

/// The initial state (q, q̇, ω) and mode of a solution file (`solution.json` of either schema),
/// for `simulate --init`: the first collocation node, the first phase's mode in lowercase.
pub fn initial_state_of(v: &Value) -> Option<InitialState> {
    let nodes = v.get("nodes")?;
    let num = |x: &Value| x.as_f64();
    let first = |k: &str| nodes.get(k)?.as_array()?.first().and_then(num);
    let (q, qd, w) = if v.get("schema_version").is_some() {
        let names = v.get("state_names")?.as_array()?;
        let nq = names.len().checked_sub(3)? / 2;
        let q: Option<Vec<f64>> = (1..=nq).map(|i| first(&format!("q{i}"))).collect();
        let qd: Option<Vec<f64>> = (1..=nq).map(|i| first(&format!("qd{i}"))).collect();
        let w = [first("omega_x")?, first("omega_y")?, first("omega_z")?];
        (q?, qd?, w)
    } else {
        let row = |k: &str| -> Option<Vec<f64>> {
            nodes
                .get(k)?
                .as_array()?
                .first()?
                .as_array()?
                .iter()
                .map(num)
                .collect()
        };
        let w = row("omega")?;
        (row("q")?, row("qd")?, [*w.first()?, *w.get(1)?, *w.get(2)?])
    };
    let mode = v
        .get("modes")?
        .as_array()?
        .first()?
        .as_str()?
        .to_lowercase();
    Some((q, qd, w, mode))
}

/// Writes `solution.json`, its internals and `torques.csv` into `dir` (created if needed).
pub fn write_solution(sol: &OcpSolution, dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    sol.write_json(&dir.join("solution.json"))?;
    sol.write_torques_csv(&dir.join("torques.csv"))?;
    Ok(())
}
