//! The rows of the extremes study and their markdown table: every probe reports a number with
//! an error estimate, a clear (typed) error, or a failure. A number that is NaN or infinite
//! becomes a failure, and so does an error other than the one the probe documents at that
//! extreme.

use std::time::Instant;

use bf_model::ModelError;

/// Result of one probe row.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// A finite number and an estimate of its error (or of the error it measures).
    Number {
        /// The measured value.
        value: f64,
        /// Error estimate of `value` (same unit), or the error bound the value is compared with.
        error_estimate: f64,
    },
    /// The code under test refused the input with a typed, explanatory error (the expected
    /// behaviour at this extreme).
    ClearError {
        /// The error's message.
        message: String,
    },
    /// NaN appeared, or an error that is not the documented one: a failure of the probe.
    Failed {
        /// What went wrong.
        message: String,
    },
}

/// One row of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtremesRow {
    /// Probe group, e.g. `"kernel accuracy"`.
    pub case: String,
    /// The extreme parameter value, e.g. `"|q| = 1e6 rad"`.
    pub parameter: String,
    /// What `outcome` is, e.g. `"rel. error of M vs double-double"`.
    pub quantity: String,
    /// Number, clear error or failure.
    pub outcome: Outcome,
    /// Wall-clock seconds spent on the probe this row belongs to (shared by its rows).
    pub seconds: f64,
}

/// All rows of [`run_extremes`](super::run_extremes).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExtremesReport {
    /// The rows, in probe order.
    pub rows: Vec<ExtremesRow>,
    /// Whether the quick variant (10 s horizon) was run.
    pub quick: bool,
    /// Total wall-clock seconds.
    pub seconds: f64,
}

impl ExtremesReport {
    /// The rows whose outcome is [`Outcome::Failed`].
    pub fn failures(&self) -> Vec<&ExtremesRow> {
        self.rows
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Failed { .. }))
            .collect()
    }

    /// The report section as a markdown table (failures, if any, announced first).
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "### Stability at the extremes ({} variant, {:.1} s)\n\n",
            if self.quick { "quick" } else { "full" },
            self.seconds
        ));
        let fails = self.failures();
        if fails.is_empty() {
            s.push_str(
                "All probes returned a finite number or a clear error (no NaN, no hang).\n\n",
            );
        } else {
            s.push_str(&format!("**{} PROBE(S) FAILED:**\n\n", fails.len()));
            for f in fails {
                if let Outcome::Failed { message } = &f.outcome {
                    s.push_str(&format!(
                        "- **FAILED** {} / {} / {}: {}\n",
                        f.case, f.parameter, f.quantity, message
                    ));
                }
            }
            s.push('\n');
        }
        s.push_str("| case | parameter | quantity | outcome | error estimate | time (s) |\n");
        s.push_str("|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let (out, err) = match &r.outcome {
                Outcome::Number {
                    value,
                    error_estimate,
                } => (fmt_num(*value), fmt_num(*error_estimate)),
                Outcome::ClearError { message } => (
                    format!("error: {}", message.replace('|', "\\|")),
                    "—".into(),
                ),
                Outcome::Failed { message } => (
                    format!("**FAILED: {}**", message.replace('|', "\\|")),
                    "—".into(),
                ),
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {:.3} |\n",
                r.case.replace('|', "\\|"),
                r.parameter.replace('|', "\\|"),
                r.quantity.replace('|', "\\|"),
                out,
                err,
                r.seconds
            ));
        }
        s
    }
}

fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e-2 && v.abs() < 1e4 {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

/// Rows of one probe, with the probe's time filled in afterwards.
pub(super) struct Rows {
    case: &'static str,
    rows: Vec<ExtremesRow>,
}

impl Rows {
    pub(super) fn new(case: &'static str) -> Self {
        Rows {
            case,
            rows: Vec::new(),
        }
    }
    /// A number row; NaN/inf in `value` or `err` turns it into a failure.
    pub(super) fn num(
        &mut self,
        parameter: impl Into<String>,
        quantity: impl Into<String>,
        value: f64,
        err: f64,
    ) {
        let outcome = if value.is_finite() && err.is_finite() {
            Outcome::Number {
                value,
                error_estimate: err,
            }
        } else {
            Outcome::Failed {
                message: format!("non-finite result: value {value}, error estimate {err}"),
            }
        };
        self.push(parameter, quantity, outcome);
    }
    pub(super) fn push(
        &mut self,
        parameter: impl Into<String>,
        quantity: impl Into<String>,
        outcome: Outcome,
    ) {
        self.rows.push(ExtremesRow {
            case: self.case.to_string(),
            parameter: parameter.into(),
            quantity: quantity.into(),
            outcome,
            seconds: 0.0,
        });
    }
    pub(super) fn fail(&mut self, parameter: impl Into<String>, message: impl Into<String>) {
        self.push(
            parameter,
            "probe",
            Outcome::Failed {
                message: message.into(),
            },
        );
    }
    pub(super) fn finish(mut self, start: Instant, out: &mut Vec<ExtremesRow>) {
        let dt = start.elapsed().as_secs_f64();
        for r in &mut self.rows {
            r.seconds = dt;
        }
        out.extend(self.rows);
    }
}

/// The outcome of a model error: a clear error if it is the one the probe expects at this
/// extreme, otherwise a failure.
pub(super) fn model_err_outcome(e: &ModelError, expected: fn(&ModelError) -> bool) -> Outcome {
    if expected(e) {
        Outcome::ClearError {
            message: e.to_string(),
        }
    } else {
        Outcome::Failed {
            message: format!("unexpected error: {e}"),
        }
    }
}
