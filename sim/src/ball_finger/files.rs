//! Output files of a ball-and-finger run ([`RunReport::write_dir`]): `trajectory.csv` /
//! `trajectory.json` (t, mode, kind, q, q̇, ω, τ, λ, λ_n, h (eq. 4), σ (eq. 18), ‖Δv‖ (eq. 13),
//! n·v_c (eq. 36), E (eq. 22), drift per sample), `events.csv` / `events.json` and
//! `summary.json`, each written atomically.

use super::{EventInfo, RunReport, RunSummary, SampleInfo};
use crate::SimError;
use crate::trajectory::{SampleKind, SimOutput, write_atomic};
use bf_model::Mode;
use serde::Serialize;
use std::path::Path;

const TRAJ_HEADER: [&str; 25] = [
    "t", "mode", "kind", "q1", "q2", "q3", "qd1", "qd2", "qd3", "omega1", "omega2", "omega3",
    "tau1", "tau2", "tau3", "lambda1", "lambda2", "lambda3", "lambda_n", "h", "sigma", "dv",
    "hdot", "energy", "drift",
];

fn csv_err(what: &'static str) -> impl Fn(csv::Error) -> SimError {
    move |e| SimError::Serialize {
        what,
        msg: e.to_string(),
    }
}

fn f(v: f64) -> String {
    format!("{v:?}")
}

fn info_fields(s: &SampleInfo) -> Vec<String> {
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
struct TrajectoryJson<'a> {
    t: &'a [f64],
    mode: &'a [Mode],
    kind: &'a [SampleKind],
    x: &'a [Vec<f64>],
    drift: &'a [Option<f64>],
    derived: &'a [SampleInfo],
}

#[derive(Serialize)]
struct EventsJson<'a> {
    events: &'a [EventInfo],
}

impl RunReport {
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
        // Trajectory CSV.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(TRAJ_HEADER)
            .map_err(csv_err("trajectory CSV"))?;
        for i in 0..tr.len() {
            let mut rec = vec![
                f(tr.t[i]),
                format!("{:?}", tr.mode[i]),
                format!("{:?}", tr.kind[i]),
            ];
            rec.extend(tr.x[i].iter().map(|&v| f(v)));
            rec.extend(info_fields(&self.samples[i]));
            rec.push(tr.drift[i].map(f).unwrap_or_default());
            w.write_record(&rec).map_err(csv_err("trajectory CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "trajectory CSV",
            msg: e.to_string(),
        })?;
        write_atomic(&dir.join("trajectory.csv"), &bytes)?;
        let tj = TrajectoryJson {
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
        let mut header: Vec<String> =
            ["t", "kind", "guard", "mode_before", "mode_after", "chained"]
                .map(String::from)
                .to_vec();
        for side in ["pre", "post"] {
            for c in &TRAJ_HEADER[3..24] {
                header.push(format!("{side}_{c}"));
            }
        }
        w.write_record(&header).map_err(csv_err("event CSV"))?;
        for e in &self.events {
            let mut rec = vec![
                f(e.t),
                e.kind.to_string(),
                e.guard.to_string(),
                format!("{:?}", e.mode_before),
                e.mode_after
                    .map_or_else(|| "Terminate".to_string(), |m| format!("{m:?}")),
                e.chained.to_string(),
            ];
            rec.extend(e.x_pre.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.pre));
            rec.extend(e.x_post.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.post));
            w.write_record(&rec).map_err(csv_err("event CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "event CSV",
            msg: e.to_string(),
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

fn json<T: Serialize>(what: &'static str, v: &T) -> Result<Vec<u8>, SimError> {
    serde_json::to_vec_pretty(v).map_err(|e| SimError::Serialize {
        what,
        msg: e.to_string(),
    })
}
