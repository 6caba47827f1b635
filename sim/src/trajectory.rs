//! Simulation output: sampled trajectory (t, x, mode), event log, statistics, and writers.
//!
//! Files are written atomically: the content goes to `<path>.tmp` in the same directory, which
//! is then renamed onto `path`, so a reader never sees a half-written file.
//!
//! CSV trajectory columns: `t,mode,kind,drift,x0,...,x{n-1}` (drift empty when the mode has no
//! projection). CSV event log columns: `t,guard,guard_index,mode_before,mode_after,pre0..,post0..`.
//! JSON: `{ "trajectory": {...}, "events": [...], "stats": {...}, "t_final", "mode_final",
//! "terminated", "warnings": [...], "error" }`
//! with modes written by their `Debug` name.

use crate::SimError;
use bf_output::FileError;
use serde::Serialize;
use std::fmt::Debug;
use std::path::Path;

/// Why a sample was recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum SampleKind {
    /// The initial state.
    Initial,
    /// End of an accepted integration step.
    Step,
    /// A point of the uniform output grid (`SimSettings::output_dt`), from dense output.
    Grid,
    /// State just before a transition (mode before the event).
    EventPre,
    /// State just after the reset (mode after the event).
    EventPost,
}

/// Sampled hybrid trajectory, in nondecreasing time order (an event contributes two samples at
/// the same time: pre and post).
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory<M> {
    /// Sample times (s).
    pub t: Vec<f64>,
    /// States x at the sample times.
    pub x: Vec<Vec<f64>>,
    /// Mode at each sample.
    pub mode: Vec<M>,
    /// Why each sample was taken.
    pub kind: Vec<SampleKind>,
    /// Constraint drift removed by `HybridSystem::project` at that sample (`None` if none).
    pub drift: Vec<Option<f64>>,
}

impl<M> Default for Trajectory<M> {
    fn default() -> Self {
        Trajectory {
            t: Vec::new(),
            x: Vec::new(),
            mode: Vec::new(),
            kind: Vec::new(),
            drift: Vec::new(),
        }
    }
}

impl<M> Trajectory<M> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Indices of the samples of one kind.
    pub fn indices_of(&self, kind: SampleKind) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.kind[i] == kind).collect()
    }
}

impl<M: Copy> Trajectory<M> {
    pub(crate) fn push(
        &mut self,
        t: f64,
        x: &[f64],
        mode: M,
        kind: SampleKind,
        drift: Option<f64>,
    ) {
        self.t.push(t);
        self.x.push(x.to_vec());
        self.mode.push(mode);
        self.kind.push(kind);
        self.drift.push(drift);
    }
}

impl<M: Debug> Trajectory<M> {
    /// Writes the trajectory as CSV (see the module docs for the columns).
    pub fn write_csv(&self, path: &Path) -> Result<(), SimError> {
        let n = self.x.first().map_or(0, Vec::len);
        let mut w = csv::Writer::from_writer(Vec::new());
        let mut header = vec![
            "t".to_string(),
            "mode".into(),
            "kind".into(),
            "drift".into(),
        ];
        header.extend((0..n).map(|i| format!("x{i}")));
        let ser = |e: csv::Error| SimError::Serialize {
            what: "trajectory CSV",
            source: e.into(),
        };
        w.write_record(&header).map_err(ser)?;
        for i in 0..self.len() {
            let mut rec = vec![
                fmt_f64(self.t[i]),
                format!("{:?}", self.mode[i]),
                format!("{:?}", self.kind[i]),
                self.drift[i].map(fmt_f64).unwrap_or_default(),
            ];
            rec.extend(self.x[i].iter().map(|&v| fmt_f64(v)));
            w.write_record(&rec).map_err(ser)?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "trajectory CSV",
            source: e.into(),
        })?;
        write_atomic(path, &bytes)
    }
}

/// Round-trip exact decimal form of a float (Rust's shortest representation).
fn fmt_f64(v: f64) -> String {
    format!("{v:?}")
}

/// One transition in the event log.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRecord<M> {
    /// Event time (s).
    pub t: f64,
    /// Name of the guard that fired.
    pub guard: &'static str,
    /// Index of that guard in `HybridSystem::guards(mode_before)`.
    pub guard_index: usize,
    /// Mode before the transition.
    pub mode_before: M,
    /// Mode after the transition (`None` if the reset terminated the run).
    pub mode_after: Option<M>,
    /// State before the reset.
    pub x_pre: Vec<f64>,
    /// State after the reset.
    pub x_post: Vec<f64>,
    /// Whether the event fired immediately after a previous reset at the same instant (a chained
    /// transition) rather than from a located crossing.
    pub chained: bool,
    /// Whether the Zeno fallback replaced the transition the guard asked for (`mode_after` is
    /// then the fallback's mode, e.g. a stick held where σ asked for slip).
    pub zeno_fallback: bool,
}

/// Counters of one run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SimStats {
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected steps (error test failed, non-finite stage, or a state outside the mode's
    /// domain).
    pub rejected_steps: usize,
    /// Of the rejected steps, those rejected because a stage, a guard sample or the projected
    /// end state lay outside the mode's domain ([`crate::SimError::is_step_rejectable`]).
    pub domain_rejections: usize,
    /// Vector-field evaluations.
    pub rhs_evals: usize,
    /// Guard evaluations (each evaluates all guards of the mode).
    pub guard_evals: usize,
    /// Events (transitions) applied.
    pub events: usize,
    /// Largest drift reported by `HybridSystem::project` (0 if never).
    pub max_drift: f64,
    /// Zeno cascades ended by the system's fallback (`HybridSystem::zeno_fallback`).
    pub zeno_fallbacks: usize,
}

/// Successful result of a run.
#[derive(Debug, Clone)]
pub struct SimOutput<M> {
    /// Sampled trajectory.
    pub trajectory: Trajectory<M>,
    /// Event log, in time order.
    pub events: Vec<EventRecord<M>>,
    /// Counters.
    pub stats: SimStats,
    /// Time reached (t_end, or the time of a terminating reset).
    pub t_final: f64,
    /// Mode at `t_final`.
    pub mode_final: M,
    /// Whether a reset terminated the run before `t_end`.
    pub terminated: bool,
    /// Conditions that did not stop the run but qualify its result (Zeno fallbacks).
    pub warnings: Vec<SimWarning>,
}

/// A condition met during a run that did not stop it but qualifies its result (a documented
/// fallback was used, an invariant was exceeded, ...).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimWarning {
    /// Time (s) at which it occurred.
    pub t: f64,
    /// Machine-readable kind, e.g. `"zeno_fallback"`.
    pub kind: &'static str,
    /// One-line explanation.
    pub message: String,
}

#[derive(Serialize)]
struct TrajJson<'a> {
    t: &'a [f64],
    x: &'a [Vec<f64>],
    mode: Vec<String>,
    kind: &'a [SampleKind],
    drift: &'a [Option<f64>],
}

#[derive(Serialize)]
struct EventJson<'a> {
    t: f64,
    guard: &'a str,
    guard_index: usize,
    mode_before: String,
    mode_after: Option<String>,
    x_pre: &'a [f64],
    x_post: &'a [f64],
    chained: bool,
}

#[derive(Serialize)]
struct OutputJson<'a> {
    trajectory: TrajJson<'a>,
    events: Vec<EventJson<'a>>,
    stats: SimStats,
    t_final: f64,
    mode_final: String,
    terminated: bool,
    warnings: &'a [SimWarning],
    error: Option<String>,
}

pub(crate) fn output_json<M: Debug>(
    traj: &Trajectory<M>,
    events: &[EventRecord<M>],
    stats: SimStats,
    t_final: f64,
    mode_final: &M,
    terminated: bool,
    warnings: &[SimWarning],
    error: Option<String>,
) -> Result<Vec<u8>, SimError> {
    let j = OutputJson {
        trajectory: TrajJson {
            t: &traj.t,
            x: &traj.x,
            mode: traj.mode.iter().map(|m| format!("{m:?}")).collect(),
            kind: &traj.kind,
            drift: &traj.drift,
        },
        events: events
            .iter()
            .map(|e| EventJson {
                t: e.t,
                guard: e.guard,
                guard_index: e.guard_index,
                mode_before: format!("{:?}", e.mode_before),
                mode_after: e.mode_after.as_ref().map(|m| format!("{m:?}")),
                x_pre: &e.x_pre,
                x_post: &e.x_post,
                chained: e.chained,
            })
            .collect(),
        stats,
        t_final,
        mode_final: format!("{mode_final:?}"),
        terminated,
        warnings,
        error,
    };
    serde_json::to_vec_pretty(&j).map_err(|e| SimError::Serialize {
        what: "simulation JSON",
        source: e.into(),
    })
}

pub(crate) fn events_csv<M: Debug>(events: &[EventRecord<M>]) -> Result<Vec<u8>, SimError> {
    let n = events.first().map_or(0, |e| e.x_pre.len());
    let ser = |e: csv::Error| SimError::Serialize {
        what: "event CSV",
        source: e.into(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec![
        "t".to_string(),
        "guard".into(),
        "guard_index".into(),
        "mode_before".into(),
        "mode_after".into(),
        "chained".into(),
        "zeno_fallback".into(),
    ];
    header.extend((0..n).map(|i| format!("pre{i}")));
    header.extend((0..n).map(|i| format!("post{i}")));
    w.write_record(&header).map_err(ser)?;
    for e in events {
        let mut rec = vec![
            fmt_f64(e.t),
            e.guard.to_string(),
            e.guard_index.to_string(),
            format!("{:?}", e.mode_before),
            e.mode_after
                .as_ref()
                .map(|m| format!("{m:?}"))
                .unwrap_or_else(|| "Terminate".into()),
            e.chained.to_string(),
            e.zeno_fallback.to_string(),
        ];
        rec.extend(e.x_pre.iter().map(|&v| fmt_f64(v)));
        rec.extend(e.x_post.iter().map(|&v| fmt_f64(v)));
        w.write_record(&rec).map_err(ser)?;
    }
    w.into_inner().map_err(|e| SimError::Serialize {
        what: "event CSV",
        source: e.into(),
    })
}

impl<M: Debug> SimOutput<M> {
    /// Writes trajectory, events and statistics as one JSON document.
    pub fn write_json(&self, path: &Path) -> Result<(), SimError> {
        let bytes = output_json(
            &self.trajectory,
            &self.events,
            self.stats,
            self.t_final,
            &self.mode_final,
            self.terminated,
            &self.warnings,
            None,
        )?;
        write_atomic(path, &bytes)
    }

    /// Writes the event log as CSV.
    pub fn write_events_csv(&self, path: &Path) -> Result<(), SimError> {
        write_atomic(path, &events_csv(&self.events)?)
    }
}

/// Writes `bytes` to `path` atomically (a uniquely named sibling temporary file, flushed to
/// disk and renamed onto `path`; the workspace's one helper, `bf_output::replace_file`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SimError> {
    bf_output::replace_file(path, bytes).map_err(|e| FileError::new("cannot write", path, e).into())
}

/// `x` as a message shows a number a user gave or a run reached: plainly between 1e-3 and 1e6,
/// in exponent form outside (`{}` of a `--t-end 1e-300` would print 300 digits).
pub fn shown(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
