//! The rows of the extremes study, their markdown summary (one line per probe: its worst case,
//! arithmetic errors also in units of roundoff u, with ⚑ where an error measure exceeds its flag
//! bound: [`ROUNDOFF_FLAG`] u for arithmetic, the stated tolerance otherwise) and the full table as CSV: every probe
//! reports a number with an error estimate, a clear (typed) error, or a failure. A number that is NaN or infinite
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

    /// (rows whose error measure exceeds its flag bound, rows that are error measures).
    pub fn flag_counts(&self) -> (usize, usize) {
        let measures = self
            .rows
            .iter()
            .filter(|r| is_error_measure(&r.quantity))
            .count();
        let exceeded = self.rows.iter().filter(|r| exceeds(r).is_some()).count();
        (exceeded, measures)
    }

    /// The report section: failures (if any) first, then one line per probe with its worst
    /// case, a flag where an error measure exceeds its bound, and what the "error estimate"
    /// column means. The full table is [`ExtremesReport::to_csv`] (written beside the report as
    /// [`CSV_NAME`]).
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
                        f.case,
                        f.parameter,
                        f.quantity,
                        crate::names::tidy(message)
                    ));
                }
            }
            s.push('\n');
        }
        s.push_str(ESTIMATE_MEANING);
        s.push_str(&format!(
            " One line per probe: its worst case (the error measure furthest above its bound, \
             else the first failure, else the first clear error, else its first row); the \
             full table of {} rows is `{CSV_NAME}`.\n\n",
            self.rows.len()
        ));
        let (exceeded, measures) = self.flag_counts();
        s.push_str(&format!(
            "⚑ {exceeded} of {measures} error measures exceed their flag bound ({ROUNDOFF_FLAG} u \
             for arithmetic, the stated tolerance otherwise; ⚑ ×k: outcome = k × flag bound; \
             per probe in the last column, each row in the CSV's `exceeds_bound_by`).\n\n"
        ));
        s.push_str("| case | worst case: parameter | quantity | outcome | error estimate | rows (clear errors, ⚑ over bound) · time (s) |\n");
        s.push_str("|---|---|---|---|---|---|\n");
        for case in self.cases() {
            let rows: Vec<&ExtremesRow> = self.rows.iter().filter(|r| r.case == case).collect();
            let Some(worst) = worst_row(&rows) else {
                continue;
            };
            let (out, err) = cells(worst);
            let clear = rows
                .iter()
                .filter(|r| matches!(r.outcome, Outcome::ClearError { .. }))
                .count();
            let over = rows.iter().filter(|r| exceeds(r).is_some()).count();
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} ({clear}, {over}) · {:.3} |\n",
                esc(&case),
                esc(&worst.parameter),
                esc(&worst.quantity),
                out,
                err,
                rows.len(),
                worst.seconds
            ));
        }
        s
    }

    /// The probe names in order of first appearance.
    pub fn cases(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for r in &self.rows {
            if !v.contains(&r.case) {
                v.push(r.case.clone());
            }
        }
        v
    }

    /// Every row as CSV (RFC 4180 quoting), with units in the header: `value` and
    /// `error_estimate` carry the unit named in `quantity` (1 for relative measures).
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "case,parameter,quantity,outcome,value [unit of quantity],\
             error_estimate [unit of quantity],error_measure,exceeds_bound_by [1],message,time [s]\n",
        );
        for r in &self.rows {
            let (kind, value, est, message) = match &r.outcome {
                Outcome::Number {
                    value,
                    error_estimate,
                } => (
                    "number",
                    format!("{value:e}"),
                    format!("{error_estimate:e}"),
                    String::new(),
                ),
                Outcome::ClearError { message } => {
                    ("clear error", String::new(), String::new(), message.clone())
                }
                Outcome::Failed { message } => {
                    ("failed", String::new(), String::new(), message.clone())
                }
            };
            let line = [
                csv_field(&r.case),
                csv_field(&r.parameter),
                csv_field(&r.quantity),
                kind.to_string(),
                value,
                est,
                is_error_measure(&r.quantity).to_string(),
                exceeds(r).map_or(String::new(), |f| format!("{f:e}")),
                csv_field(&message),
                format!("{}", r.seconds),
            ];
            s.push_str(&line.join(","));
            s.push('\n');
        }
        s
    }
}

/// File name of the full table beside the report.
pub const CSV_NAME: &str = "extremes.csv";

/// The one-sentence meaning of the "error estimate" column.
pub const ESTIMATE_MEANING: &str = "\"Error estimate\": for a row that measures an error \
    (relative error, deviation, residual, energy drift) it is the scale the error is judged \
    on: for floating-point arithmetic the f64 machine epsilon 2.2e-16 = 2 u, with the outcome \
    also given in units of the unit roundoff u = 2⁻⁵³ ≈ 1.1e-16 and ⚑ only above 64 u (a few \
    roundings in each of the dozens of operations of a kernel stay below it); for a simulation \
    the integrator's rtol, with ⚑ above it. For any other row it estimates the outcome's own \
    error.";

/// The unit roundoff of f64, u = 2⁻⁵³ (half the machine epsilon).
pub const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// An arithmetic error measure is flagged above this many units of roundoff: errors of a few
/// u are what rounding in a kernel of dozens of operations gives, not a defect.
pub const ROUNDOFF_FLAG: f64 = 64.0;

/// Whether row `r` is judged on the floating-point scale (its bound is the machine epsilon),
/// rather than on a tolerance such as an integrator's rtol.
fn on_roundoff_scale(r: &ExtremesRow) -> bool {
    matches!(r.outcome, Outcome::Number { error_estimate, .. } if error_estimate == f64::EPSILON)
}

/// The bound above which an error measure is flagged: [`ROUNDOFF_FLAG`] u on the roundoff
/// scale, the stated bound otherwise.
fn flag_bound(r: &ExtremesRow) -> Option<f64> {
    match r.outcome {
        Outcome::Number { error_estimate, .. }
            if is_error_measure(&r.quantity) && error_estimate > 0.0 =>
        {
            Some(if on_roundoff_scale(r) {
                ROUNDOFF_FLAG * UNIT_ROUNDOFF
            } else {
                error_estimate
            })
        }
        _ => None,
    }
}

/// Whether `quantity` names an error measure (compared with a bound) rather than a value.
pub fn is_error_measure(quantity: &str) -> bool {
    let q = quantity.trim_start();
    [
        "rel. err",
        "err.",
        "rel. dev",
        "max dev",
        "max |ΔE|",
        "|λ − λ",
    ]
    .iter()
    .any(|p| q.starts_with(p))
        || q.contains("residual")
}

/// outcome / flag bound when `r` is an error measure above its flag bound ([`ROUNDOFF_FLAG`] u
/// for arithmetic errors, the stated bound otherwise).
pub fn exceeds(r: &ExtremesRow) -> Option<f64> {
    match (r.outcome.clone(), flag_bound(r)) {
        (Outcome::Number { value, .. }, Some(b)) if value > b => Some(value / b),
        _ => None,
    }
}

fn worst_row<'a>(rows: &[&'a ExtremesRow]) -> Option<&'a ExtremesRow> {
    let ratio = |r: &ExtremesRow| match (&r.outcome, flag_bound(r)) {
        (Outcome::Number { value, .. }, Some(b)) => Some(value / b),
        _ => None,
    };
    rows.iter()
        .copied()
        .find(|r| matches!(r.outcome, Outcome::Failed { .. }))
        .or_else(|| {
            rows.iter()
                .copied()
                .filter_map(|r| ratio(r).map(|x| (r, x)))
                .fold(None::<(&ExtremesRow, f64)>, |m, (r, x)| match m {
                    Some((_, y)) if y >= x => m,
                    _ => Some((r, x)),
                })
                .map(|(r, _)| r)
        })
        .or_else(|| {
            rows.iter()
                .copied()
                .find(|r| matches!(r.outcome, Outcome::ClearError { .. }))
        })
        .or_else(|| rows.first().copied())
}

fn cells(r: &ExtremesRow) -> (String, String) {
    match &r.outcome {
        Outcome::Number {
            value,
            error_estimate,
        } => {
            let flag = exceeds(r).map_or(String::new(), |f| format!(" ⚑ ×{f:.1e}"));
            let units = if on_roundoff_scale(r) && is_error_measure(&r.quantity) {
                format!(" ({} u)", fmt_units(value / UNIT_ROUNDOFF))
            } else {
                String::new()
            };
            (
                format!("{}{units}{flag}", fmt_num(*value)),
                fmt_num(*error_estimate),
            )
        }
        // The table cell rounds the lower layers' full-precision numbers; the CSV keeps them.
        Outcome::ClearError { message } => (
            format!("error: {}", esc(&crate::names::tidy(message))),
            "—".into(),
        ),
        Outcome::Failed { message } => (
            format!("**FAILED: {}**", esc(&crate::names::tidy(message))),
            "—".into(),
        ),
    }
}

/// A multiple of u: one decimal below 100, else two significant digits in scientific form.
fn fmt_units(k: f64) -> String {
    if k < 100.0 {
        format!("{k:.1}")
    } else {
        format!("{k:.1e}")
    }
}

fn esc(s: &str) -> String {
    s.replace('|', "\\|")
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn row(case: &str, quantity: &str, value: f64, err: f64) -> ExtremesRow {
        ExtremesRow {
            case: case.into(),
            parameter: format!("|q| = {value}"),
            quantity: quantity.into(),
            outcome: Outcome::Number {
                value,
                error_estimate: err,
            },
            seconds: 0.5,
        }
    }

    fn report() -> ExtremesReport {
        ExtremesReport {
            rows: vec![
                row("kernels", "rel. err. M", 1e-16, f64::EPSILON),
                row("kernels", "rel. err. M", 4e-10, f64::EPSILON),
                row("kernels", "rel. err. g", 1e-15, f64::EPSILON),
                row("painlevé", "threshold μ_k*", 0.9, 1e-12),
                ExtremesRow {
                    case: "painlevé".into(),
                    parameter: "μ_k = 2, \"big\"".into(),
                    quantity: "slip".into(),
                    outcome: Outcome::ClearError {
                        message: "no consistent normal force".into(),
                    },
                    seconds: 0.5,
                },
            ],
            quick: true,
            seconds: 1.0,
        }
    }

    #[test]
    fn flags_exactly_the_error_measures_above_their_bound() {
        let r = report();
        let flagged: Vec<f64> = r.rows.iter().filter_map(exceeds).collect();
        // Only 4e-10 (3.6e6 u) exceeds 64 u; 1e-15 is 9 u of roundoff, not a defect; a value
        // that is not an error measure (μ_k* = 0.9 with its own error 1e-12) is never flagged.
        assert_eq!(flagged.len(), 1);
        let u = f64::EPSILON / 2.0;
        assert!((flagged[0] - 4e-10 / (64.0 * u)).abs() < 1.0);
        let md = r.to_markdown();
        assert!(md.contains("⚑ 1 of 3 error measures"), "{md}");
        // The worst case of "kernels" is the 4e-10 row, in units of u and flagged.
        let line = md.lines().find(|l| l.starts_with("| kernels")).unwrap();
        assert!(line.contains("4.000e-10 (3.6e6 u) ⚑ ×5.6e4"), "{line}");
        assert!(line.contains("3 (0, 1)"), "{line}");
        // Just above and below the flag bound.
        let mut r2 = report();
        r2.rows = vec![
            row("k", "rel. err. M", 63.0 * u, f64::EPSILON),
            row("k", "rel. err. M", 65.0 * u, f64::EPSILON),
            // On a tolerance scale (rtol 1e-8) the bound itself is the flag bound.
            row("k", "max |ΔE| (J)", 2e-8, 1e-8),
        ];
        let f: Vec<f64> = r2.rows.iter().filter_map(exceeds).collect();
        assert_eq!(f.len(), 2, "{f:?}");
        assert!((f[0] - 65.0 / 64.0).abs() < 1e-12 && (f[1] - 2.0).abs() < 1e-12);
        let line = md.lines().find(|l| l.starts_with("| painlevé")).unwrap();
        assert!(line.contains("error: no consistent"), "{line}");
        assert!(md.contains(ESTIMATE_MEANING));
    }

    /// A clear error's full-precision numbers are rounded in the table cell and kept whole in
    /// the CSV.
    #[test]
    fn error_cells_round_full_precision_numbers() {
        let mut r = report();
        r.rows[4].outcome = Outcome::ClearError {
            message: "Painlevé paradox (Inconsistent): slip normal inverse mass \
                      -5.459312364956617e-1 <= 0"
                .into(),
        };
        let md = r.to_markdown();
        let line = md.lines().find(|l| l.starts_with("| painlevé")).unwrap();
        assert!(
            line.contains("slip normal inverse mass -5.45931e-1 <= 0"),
            "{line}"
        );
        assert!(r.to_csv().contains("-5.459312364956617e-1"));
    }

    #[test]
    fn csv_has_every_row_with_units_and_quoting() {
        let csv = report().to_csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 1 + 5);
        assert!(lines[0].contains("time [s]") && lines[0].contains("value [unit of quantity]"));
        let cols = lines[0].split(',').count();
        assert_eq!(lines[1].split(',').count(), cols);
        assert!(lines[2].contains(",true,5.6"), "{}", lines[2]);
        assert!(
            lines[5].contains("\"μ_k = 2, \"\"big\"\"\""),
            "{}",
            lines[5]
        );
    }
}
