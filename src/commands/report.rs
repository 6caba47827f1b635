//! `ball-finger report <which> [--out DIR] [--quick]`: stand-alone reports. Writes
//! `DIR/<which>.md` and the figures under `DIR/figures/` as one output set (DIR, by default
//! `out/report/<which>`, is checked before the work and replaced as a whole at the end).
//!
//! `strategies` flags unverified rows, and ratios against an unverified or failed cold start,
//! in the table and on stdout: they are measurements of the strategies. A row whose solve
//! errored leaves the comparison incomplete: the set is marked FAILED and the command exits 1.

use crate::errors::bail_usage;
use crate::paper::report::strategies;
use anyhow::{Result, bail};
use bf_output::{DirSpec, Outcome, OutputDir};
use std::path::PathBuf;

use crate::cli::ReportArgs;

/// Names of the reports `report` knows.
pub const REPORTS: &[&str] = &["speed-accuracy", "strategies"];

/// The command an output set of the report `which` records in its manifest
/// (`report strategies`), which [`OutputDir::create`] compares with the directory it replaces.
pub fn output_command(which: &str) -> String {
    format!("report {which}")
}

/// Runs the report named by `a.which`.
pub fn run(a: &ReportArgs) -> Result<()> {
    if !REPORTS.contains(&a.which.as_str()) {
        bail_usage!(
            "unknown report `{}`; known reports: {}",
            a.which,
            REPORTS.join(", ")
        );
    }
    let target = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/report").join(&a.which));
    let md_name = format!("{}.md", a.which);
    // The manifest names the report, not only the command: one report's set is not another's,
    // so `report speed-accuracy` refuses a directory `report strategies` wrote.
    let command = output_command(&a.which);
    let mut out = OutputDir::create(
        &target,
        &DirSpec {
            option: "--out",
            command: &command,
        },
        &[],
    )?;
    // CI logs (stderr not a terminal) get a line every 5 s while the report runs.
    let hb = crate::progress::Heartbeat::start(&format!("report {}", a.which));
    hb.stage(if a.quick {
        "running (--quick)"
    } else {
        "running"
    });
    // Lines the reader must not miss (rows that errored or are unverified), printed after the
    // report is written; `failure` marks the set FAILED and the command exits 1.
    let mut flagged: Vec<String> = Vec::new();
    let mut failure: Option<String> = None;
    let md = match a.which.as_str() {
        "speed-accuracy" => {
            crate::paper::speed_accuracy::speed_accuracy(out.path(), a.quick, None)?
        }
        _ => {
            let pb = super::optimize::iteration_spinner("strategies");
            pb.enable_steady_tick(std::time::Duration::from_millis(120));
            pb.set_message("solving ...");
            let rows = crate::paper::report::strategies_report(a.quick, &|r| {
                let line = format!(
                    "{} {}: {} phi {:.4e} in {:.1} s, {}",
                    r.problem,
                    r.label(),
                    r.status,
                    r.objective,
                    r.seconds,
                    r.verdict()
                );
                hb.line(&line);
                pb.println(line);
            })?;
            pb.finish_and_clear();
            flagged = strategies::flags(&rows);
            failure = strategies::failures(&rows);
            strategies::markdown(&rows)
        }
    };
    let head = match &failure {
        Some(f) => format!("**FAILED**: {f}\n\n"),
        None => String::new(),
    };
    let text = format!("# ball-finger: {} report\n\n{head}{md}", a.which);
    out.write(&md_name, text.as_bytes())?;
    out.commit(match &failure {
        Some(f) => Outcome::Failed(f),
        None => Outcome::Success,
    })?;
    hb.stage("done");
    drop(hb);
    for f in &flagged {
        crate::outln!("flagged: {f}")?;
    }
    crate::outln!("wrote {}", target.join(&md_name).display())?;
    match failure {
        Some(f) => bail!("{f}"),
        None => Ok(()),
    }
}
