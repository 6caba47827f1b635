//! Output files of a ball-and-finger run ([`RunReport::write_dir`]): `trajectory.csv` /
//! `trajectory.json` (t, mode, kind, q, q̇, ω, τ, λ, λ_n, h (eq. 4), σ (eq. 18), ‖Δv‖ (eq. 13),
//! n·v_c (eq. 36), E (eq. 22), drift per sample), `events.csv` / `events.json` and
//! `summary.json`, each written atomically.

use super::report::mode_name;
use super::{EventInfo, RunReport, RunSummary, SampleInfo};
use crate::SimError;
use crate::trajectory::{SampleKind, SimOutput, write_atomic};
use bf_model::Mode;
use serde::Serialize;
use std::path::Path;

/// Column names with their units for a finger with `n` joints; the state components are named
/// as in `solution.json` (q1.., qd1.., omega_x..) and by [`state_names`] in `trajectory.json`.
fn traj_header(n: usize) -> Vec<String> {
    let mut h: Vec<String> = ["t [s]", "mode", "kind"].map(String::from).to_vec();
    h.extend((1..=n).map(|i| format!("q{i} [rad]")));
    h.extend((1..=n).map(|i| format!("qd{i} [rad/s]")));
    h.extend(["omega_x [rad/s]", "omega_y [rad/s]", "omega_z [rad/s]"].map(String::from));
    h.extend((1..=n).map(|i| format!("tau{i} [N m]")));
    h.extend(
        [
            "lambda_x [N]",
            "lambda_y [N]",
            "lambda_z [N]",
            "lambda_n [N]",
            "h [m]",
            "sigma [N]",
            "dv [m/s]",
            "hdot [m/s]",
            "energy [J]",
            "drift [m]",
        ]
        .map(String::from),
    );
    h
}

/// Names of the components of the state x in `trajectory.json` (q1.., qd1.., omega_x..).
fn state_names(n: usize) -> Vec<String> {
    let mut v: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
    v.extend((1..=n).map(|i| format!("qd{i}")));
    v.extend(["omega_x", "omega_y", "omega_z"].map(String::from));
    v
}

fn csv_err(what: &'static str) -> impl Fn(csv::Error) -> SimError {
    move |e| SimError::Serialize {
        what,
        source: e.into(),
    }
}

fn f(v: f64) -> String {
    format!("{v:?}")
}

fn info_fields<const N: usize>(s: &SampleInfo<N>) -> Vec<String> {
    let mut r: Vec<String> = s.tau.iter().chain(&s.lambda).map(|&v| f(v)).collect();
    r.extend(
        [
            s.lambda_n,
            s.h,
            s.sigma,
            s.slip_speed,
            s.normal_velocity,
            s.energy,
        ]
        .map(f),
    );
    r
}

#[derive(Serialize)]
struct TrajectoryJson<'a, const N: usize> {
    state_names: Vec<String>,
    units: [(&'static str, &'static str); 4],
    t: &'a [f64],
    mode: &'a [Mode],
    kind: &'a [SampleKind],
    x: &'a [Vec<f64>],
    drift: &'a [Option<f64>],
    derived: &'a [SampleInfo<N>],
}

#[derive(Serialize)]
struct EventsJson<'a, const N: usize> {
    events: &'a [EventInfo<N>],
}

impl<const N: usize> RunReport<N> {
    /// Writes `trajectory.csv` / `trajectory.json` (t, mode, kind, q, q̇, ω, τ, λ, λ_n, h, σ,
    /// ‖Δv‖ (`dv`), n·v_c (`hdot`), E, drift per sample), `events.csv` / `events.json`
    /// (time, kind, guard, modes, pre/post state and derived quantities) and `summary.json`
    /// into `dir` (created if missing), each atomically. `error` (a failed run) is added to
    /// the summary.
    pub fn write_dir(
        &self,
        dir: &Path,
        out: &SimOutput<Mode>,
        error: Option<&str>,
    ) -> Result<(), SimError> {
        std::fs::create_dir_all(dir)
            .map_err(|e| bf_output::FileError::new("cannot create directory", dir, e))?;
        let tr = &out.trajectory;
        let traj_header = traj_header(N);
        // Trajectory CSV.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&traj_header)
            .map_err(csv_err("trajectory CSV"))?;
        for i in 0..tr.len() {
            let mut rec = vec![
                f(tr.t[i]),
                mode_name(tr.mode[i]).to_string(),
                kind_name(tr.kind[i]).to_string(),
            ];
            rec.extend(tr.x[i].iter().map(|&v| f(v)));
            rec.extend(info_fields(&self.samples[i]));
            rec.push(tr.drift[i].map(f).unwrap_or_default());
            w.write_record(&rec).map_err(csv_err("trajectory CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "trajectory CSV",
            source: e.into(),
        })?;
        write_atomic(&dir.join("trajectory.csv"), &bytes)?;
        let tj = TrajectoryJson {
            state_names: state_names(N),
            units: [
                ("t", "s"),
                ("x", "rad (q), rad/s (qd, omega)"),
                ("drift", "m"),
                ("derived", "as the columns of trajectory.csv"),
            ],
            t: &tr.t,
            mode: &tr.mode,
            kind: &tr.kind,
            x: &tr.x,
            drift: &tr.drift,
            derived: &self.samples,
        };
        write_atomic(&dir.join("trajectory.json"), &json("trajectory JSON", &tj)?)?;
        // Events.
        let mut w = csv::Writer::from_writer(Vec::new());
        let mut header: Vec<String> = [
            "t [s]",
            "kind",
            "guard",
            "mode_before",
            "mode_after",
            "chained",
            "zeno_fallback",
        ]
        .map(String::from)
        .to_vec();
        for side in ["pre", "post"] {
            // The state and the derived quantities: every column but t, mode, kind and drift.
            for c in &traj_header[3..traj_header.len() - 1] {
                header.push(format!("{side}_{c}"));
            }
        }
        w.write_record(&header).map_err(csv_err("event CSV"))?;
        for e in &self.events {
            let mut rec = vec![
                f(e.t),
                e.kind.to_string(),
                e.guard.to_string(),
                mode_name(e.mode_before).to_string(),
                e.mode_after.map_or("terminate", mode_name).to_string(),
                e.chained.to_string(),
                e.zeno_fallback.to_string(),
            ];
            rec.extend(e.x_pre.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.pre));
            rec.extend(e.x_post.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.post));
            w.write_record(&rec).map_err(csv_err("event CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "event CSV",
            source: e.into(),
        })?;
        write_atomic(&dir.join("events.csv"), &bytes)?;
        write_atomic(
            &dir.join("events.json"),
            &json(
                "events JSON",
                &EventsJson {
                    events: &self.events,
                },
            )?,
        )?;
        #[derive(Serialize)]
        struct SummaryJson<'a> {
            #[serde(flatten)]
            summary: &'a RunSummary,
            error: Option<&'a str>,
        }
        write_atomic(
            &dir.join("summary.json"),
            &json(
                "summary JSON",
                &SummaryJson {
                    summary: &self.summary,
                    error,
                },
            )?,
        )
    }
}

/// The sample kind as written in every file: its serde name, as in the JSON files.
fn kind_name(k: SampleKind) -> &'static str {
    match k {
        SampleKind::Initial => "Initial",
        SampleKind::Step => "Step",
        SampleKind::Grid => "Grid",
        SampleKind::EventPre => "EventPre",
        SampleKind::EventPost => "EventPost",
    }
}

fn json<T: Serialize>(what: &'static str, v: &T) -> Result<Vec<u8>, SimError> {
    serde_json::to_vec_pretty(v).map_err(|e| SimError::Serialize {
        what,
        source: e.into(),
    })
}
