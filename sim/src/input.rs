//! Joint-torque inputs τ(t, q, q̇) for the finger (the τ of eq. 24/44).
//!
//! * [`TorqueSeries`]: open-loop torques from a time series (e.g. the optimiser's solution,
//!   Sect. 6.2 "open-loop simulation"), piecewise linear in t, held constant outside the data.
//! * [`PdController`]: τᵢ = kpᵢ (targetᵢ − qᵢ) − kdᵢ q̇ᵢ.
//! * [`TrackingPd`]: feed-forward torques plus joint-space PD tracking of a reference
//!   trajectory, τ = τ*(t) + K_p (q*(t) − q) + K_d (q̇*(t) − q̇), inside given time windows
//!   (the stabilised open loop the paper's Sect. 7 points to).
//!
//! File formats (also in sim/README.md):
//! * CSV with header `t,tau1,...,tauN` (each name optionally followed by a unit in brackets,
//!   `t [s],tau1 [N m]`), one row per time, strictly increasing t, finite values.
//! * JSON `{ "t": [t0, t1, ...], "tau": [[tau1, ..., tauN] at t0, [..] at t1, ...] }`.

use crate::SimError;
use bf_model::Mode;
use bf_output::FileError;
use std::path::Path;

/// A source of joint torques.
///
/// The ball-and-finger system ([`crate::ball_finger::BallFinger`]) calls [`Input::tau_in_mode`]
/// and reports what a real controller measures through [`Input::observe`]; its report takes the
/// state just before an event with [`Input::tau_before`]. They default to the plain law
/// τ(t, q, q̇) and to ignoring the measurements, so an input that only implements
/// [`Input::tau`] runs exactly as before (bit for bit). Feedback laws that switch with the
/// contact (bf-control's hybrid controller) override them.
pub trait Input {
    /// Number of torques N (= number of joints).
    fn dim(&self) -> usize;
    /// Writes τ(t, q, q̇) into `out` (length N).
    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError>;
    /// Writes τ into `out` knowing the plant's contact mode and the ball's ω (what a controller
    /// with contact sensing and a ball encoder measures). Called in every right-hand side and
    /// guard evaluation, and for the per-sample report after the run, so it must be a function
    /// of its arguments and of what [`Input::observe`] recorded up to time `t`. Default:
    /// [`Input::tau`].
    fn tau_in_mode(
        &self,
        mode: Mode,
        t: f64,
        q: &[f64],
        qd: &[f64],
        omega: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        let _ = (mode, omega);
        self.tau(t, q, qd, out)
    }
    /// τ as it drove the plant up to time `t`: the limit from the left, with only what
    /// [`Input::observe`] recorded before `t` (an input whose memory changes at an observation
    /// has two values at its time; [`Input::tau_in_mode`] gives the one after it). The
    /// per-sample report evaluates the state just before an event with it: that sample only ends
    /// a step, since the step after the event starts from the state after the reset, so its τ,
    /// forces and power are those the step ended with. Default: [`Input::tau_in_mode`] (an
    /// input that ignores the measurements has one value).
    fn tau_before(
        &self,
        mode: Mode,
        t: f64,
        q: &[f64],
        qd: &[f64],
        omega: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        self.tau_in_mode(mode, t, q, qd, omega, out)
    }
    /// Whether [`Input::observe`] wants the measured contact force after every accepted step
    /// (it costs one contact-force evaluation per step). Default: no.
    fn wants_force(&self) -> bool {
        false
    }
    /// A measurement of the plant: an accepted step's end or a mode transition. Called in time
    /// order, never for rejected trial steps. Default: ignored.
    fn observe(&self, m: &Measurement<'_>) {
        let _ = m;
    }
}

/// What the plant reports to an [`Input`] ([`Input::observe`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement<'a> {
    /// Time (s).
    pub t: f64,
    /// The mode after the step or transition.
    pub mode: Mode,
    /// The mode before a transition; `None` for the end of an accepted step.
    pub from: Option<Mode>,
    /// The state x = (q, q̇, ω) (after the reset, for a transition).
    pub x: &'a [f64],
    /// The contact force λ on the finger (N, world axes) at the end of an accepted contact
    /// step, when [`Input::wants_force`]; `None` otherwise.
    pub lambda: Option<[f64; 3]>,
}

/// Piecewise-linear torque time series with clamped ends.
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueSeries {
    t: Vec<f64>,
    /// Row-major: tau[k * n + i] = τᵢ(t_k).
    tau: Vec<f64>,
    n: usize,
}

fn parse_err(path: &Path, line: Option<usize>, msg: impl Into<String>) -> SimError {
    SimError::Parse {
        path: path.to_path_buf(),
        line,
        msg: msg.into(),
    }
}

impl TorqueSeries {
    /// Builds a series from times and torque rows (errors name the data `<memory>`).
    /// Requires ≥ 1 sample, strictly increasing finite times, and N ≥ 1 finite torques per row.
    pub fn new(t: Vec<f64>, tau: Vec<Vec<f64>>) -> Result<Self, SimError> {
        Self::from_rows(Path::new("<memory>"), t, tau, None)
    }

    fn from_rows(
        path: &Path,
        t: Vec<f64>,
        rows: Vec<Vec<f64>>,
        lines: Option<&[usize]>,
    ) -> Result<Self, SimError> {
        let line = |k: usize| lines.map(|l| l[k]);
        if t.is_empty() {
            return Err(parse_err(path, None, "no samples"));
        }
        if t.len() != rows.len() {
            return Err(parse_err(
                path,
                None,
                format!("{} times but {} torque rows", t.len(), rows.len()),
            ));
        }
        let n = rows[0].len();
        if n == 0 {
            return Err(parse_err(path, line(0), "no torque columns"));
        }
        let mut flat = Vec::with_capacity(n * rows.len());
        for (k, row) in rows.iter().enumerate() {
            if row.len() != n {
                return Err(parse_err(
                    path,
                    line(k),
                    format!(
                        "sample {k} has {} torques and sample 0 has {n}: every sample needs \
                         one torque per joint",
                        row.len()
                    ),
                ));
            }
            if !t[k].is_finite() {
                return Err(parse_err(
                    path,
                    line(k),
                    format!("sample {k}: t is not finite"),
                ));
            }
            if let Some(i) = row.iter().position(|v| !v.is_finite()) {
                return Err(parse_err(
                    path,
                    line(k),
                    format!("sample {k}: tau{} is not finite", i + 1),
                ));
            }
            if k > 0 && t[k] <= t[k - 1] {
                return Err(parse_err(
                    path,
                    line(k),
                    format!(
                        "time not strictly increasing: t[{k}] = {} after t[{}] = {}",
                        t[k],
                        k - 1,
                        t[k - 1]
                    ),
                ));
            }
            flat.extend_from_slice(row);
        }
        Ok(TorqueSeries { t, tau: flat, n })
    }

    /// Reads a CSV file with header `t,tau1,...,tauN`.
    pub fn from_csv_path(path: &Path) -> Result<Self, SimError> {
        let text =
            bf_scene::read_input_text(path).map_err(|e| FileError::new("cannot read", path, e))?;
        Self::from_csv_str(&text, path)
    }

    /// Parses CSV text; `path` is used in error messages only.
    pub fn from_csv_str(text: &str, path: &Path) -> Result<Self, SimError> {
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let header = rdr
            .headers()
            .map_err(|e| parse_err(path, Some(1), format!("cannot read header: {e}")))?
            .clone();
        // A unit in brackets may follow each name (`t [s]`, `tau1 [N m]`, as `optimize` writes).
        let cols: Vec<&str> = header
            .iter()
            .map(|c| match c.split_once('[') {
                Some((name, unit)) if unit.ends_with(']') => name.trim_end(),
                _ => c,
            })
            .collect();
        if cols.len() < 2 || cols[0] != "t" {
            return Err(parse_err(
                path,
                Some(1),
                format!("header must be `t,tau1,...,tauN`, got `{}`", cols.join(",")),
            ));
        }
        for (i, c) in cols.iter().enumerate().skip(1) {
            if *c != format!("tau{i}") {
                return Err(parse_err(
                    path,
                    Some(1),
                    format!("header column {} must be `tau{i}`, got `{c}`", i + 1),
                ));
            }
        }
        let n = cols.len() - 1;
        let mut t = Vec::new();
        let mut rows = Vec::new();
        let mut lines = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map(|p| p.line() as usize);
                parse_err(path, line, e.to_string())
            })?;
            let line = rec.position().map_or(0, |p| p.line() as usize);
            if rec.iter().all(str::is_empty) {
                continue;
            }
            if rec.len() != n + 1 {
                return Err(parse_err(
                    path,
                    Some(line),
                    format!("{} columns, header has {}", rec.len(), n + 1),
                ));
            }
            let mut vals = Vec::with_capacity(n + 1);
            for (i, field) in rec.iter().enumerate() {
                let v: f64 = field.parse().map_err(|_| {
                    parse_err(
                        path,
                        Some(line),
                        format!("column `{}`: `{field}` is not a number", cols[i]),
                    )
                })?;
                if !v.is_finite() {
                    return Err(parse_err(
                        path,
                        Some(line),
                        format!("column `{}`: value {v} is not finite", cols[i]),
                    ));
                }
                vals.push(v);
            }
            t.push(vals[0]);
            rows.push(vals[1..].to_vec());
            lines.push(line);
        }
        Self::from_rows(path, t, rows, Some(&lines))
    }

    /// Reads a JSON file `{ "t": [...], "tau": [[...], ...] }`.
    pub fn from_json_path(path: &Path) -> Result<Self, SimError> {
        let text =
            bf_scene::read_input_text(path).map_err(|e| FileError::new("cannot read", path, e))?;
        Self::from_json_str(&text, path)
    }

    /// Parses JSON text; `path` is used in error messages only.
    pub fn from_json_str(text: &str, path: &Path) -> Result<Self, SimError> {
        #[derive(serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Raw {
            t: Vec<f64>,
            tau: Vec<Vec<f64>>,
        }
        let raw: Raw = serde_json::from_str(text)
            .map_err(|e| parse_err(path, Some(e.line()), format!("invalid JSON: {e}")))?;
        Self::from_rows(path, raw.t, raw.tau, None)
    }

    /// Loads CSV or JSON by file extension (`.json` → JSON, anything else → CSV).
    pub fn from_path(path: &Path) -> Result<Self, SimError> {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("json") => Self::from_json_path(path),
            _ => Self::from_csv_path(path),
        }
    }

    /// Writes the series as CSV in the documented format (atomically).
    pub fn write_csv(&self, path: &Path) -> Result<(), SimError> {
        let mut s = String::from("t");
        for i in 1..=self.n {
            s.push_str(&format!(",tau{i}"));
        }
        s.push('\n');
        for (k, t) in self.t.iter().enumerate() {
            s.push_str(&format!("{t:?}"));
            for v in &self.tau[k * self.n..(k + 1) * self.n] {
                s.push_str(&format!(",{v:?}"));
            }
            s.push('\n');
        }
        crate::trajectory::write_atomic(path, s.as_bytes())
    }

    /// Sample times.
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// Interpolated torques at `t` (clamped outside [t₀, t_last]).
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        self.eval_each(t, |i, v| out[i] = v);
    }

    /// Calls `f(i, τᵢ(t))` for every column `i` of the interpolated value at `t` (clamped
    /// outside [t₀, t_last]), so that callers combining several series need no buffer.
    pub fn eval_each(&self, t: f64, mut f: impl FnMut(usize, f64)) {
        let n = self.n;
        let last = self.t.len() - 1;
        let row = |k: usize| &self.tau[k * n..(k + 1) * n];
        if t.is_nan() || t <= self.t[0] {
            row(0).iter().enumerate().for_each(|(i, &v)| f(i, v));
            return;
        }
        if t >= self.t[last] {
            row(last).iter().enumerate().for_each(|(i, &v)| f(i, v));
            return;
        }
        // First index with t_k > t; t lies in [t_{k-1}, t_k).
        let k = self.t.partition_point(|&tk| tk <= t);
        let (ta, tb) = (self.t[k - 1], self.t[k]);
        let w = (t - ta) / (tb - ta);
        let (ra, rb) = (row(k - 1), row(k));
        for i in 0..n {
            f(i, ra[i] + w * (rb[i] - ra[i]));
        }
    }
}

impl Input for TorqueSeries {
    fn dim(&self) -> usize {
        self.n
    }
    fn tau(&self, t: f64, _q: &[f64], _qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        if out.len() != self.n {
            return Err(SimError::DimensionMismatch {
                what: "torque output",
                expected: self.n,
                found: out.len(),
            });
        }
        self.eval(t, out);
        Ok(())
    }
}

/// Joint-space PD controller τᵢ = kpᵢ (targetᵢ − qᵢ) − kdᵢ q̇ᵢ (N m, rad, rad/s).
#[derive(Debug, Clone, PartialEq)]
pub struct PdController {
    /// Proportional gains (N m / rad).
    pub kp: Vec<f64>,
    /// Derivative gains (N m s / rad).
    pub kd: Vec<f64>,
    /// Target joint angles (rad).
    pub target: Vec<f64>,
}

impl PdController {
    /// Builds a controller; all three vectors must have the same length and finite entries.
    pub fn new(kp: Vec<f64>, kd: Vec<f64>, target: Vec<f64>) -> Result<Self, SimError> {
        let n = kp.len();
        for (name, v) in [("kd", &kd), ("target", &target)] {
            if v.len() != n {
                return Err(SimError::InvalidSetting {
                    name,
                    msg: format!("length {} differs from kp length {n}", v.len()),
                });
            }
        }
        if kp.iter().chain(&kd).chain(&target).any(|v| !v.is_finite()) {
            return Err(SimError::InvalidSetting {
                name: "PdController",
                msg: "gains and target must be finite".into(),
            });
        }
        Ok(PdController { kp, kd, target })
    }
}

impl Input for PdController {
    fn dim(&self) -> usize {
        self.kp.len()
    }
    fn tau(&self, _t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        let n = self.kp.len();
        check_lengths(
            n,
            q,
            qd,
            out,
            &[("kd", self.kd.len()), ("target", self.target.len())],
        )?;
        for i in 0..n {
            out[i] = self.kp[i] * (self.target[i] - q[i]) - self.kd[i] * qd[i];
        }
        Ok(())
    }
}

/// Errors unless q, q̇, the torque output and then every `(what, len)` of `extra` have length
/// `n` (the joint count of an input law); the first mismatch is named.
fn check_lengths(
    n: usize,
    q: &[f64],
    qd: &[f64],
    out: &[f64],
    extra: &[(&'static str, usize)],
) -> Result<(), SimError> {
    let io = [
        ("q", q.len()),
        ("qd", qd.len()),
        ("torque output", out.len()),
    ];
    for &(what, len) in io.iter().chain(extra) {
        if len != n {
            return Err(SimError::DimensionMismatch {
                what,
                expected: n,
                found: len,
            });
        }
    }
    Ok(())
}

/// Feed-forward torques with joint-space PD tracking of a reference trajectory:
/// τᵢ = τ*ᵢ(t) + kpᵢ (q*ᵢ(t) − qᵢ) + kdᵢ (q̇*ᵢ(t) − q̇ᵢ) (N m, rad, rad/s) while t lies in one
/// of the feedback windows, τ*(t) outside them. τ*, q* and q̇* are piecewise-linear series
/// ([`TorqueSeries`] used as a generic series: one column per joint). With all gains zero the
/// torques are τ*(t) exactly, the pure open loop.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackingPd {
    feedforward: TorqueSeries,
    q_ref: TorqueSeries,
    qd_ref: TorqueSeries,
    kp: Vec<f64>,
    kd: Vec<f64>,
    windows: Vec<(f64, f64)>,
    feedback: bool,
}

impl TrackingPd {
    /// Builds the input: feed-forward torques τ*(t), reference angles q*(t) and rates q̇*(t)
    /// (same number of columns N), gains kp (N m/rad) and kd (N m s/rad) of length N (finite,
    /// non-negative), and the windows [t_a, t_b) in which the feedback acts (t_a ≤ t_b).
    pub fn new(
        feedforward: TorqueSeries,
        q_ref: TorqueSeries,
        qd_ref: TorqueSeries,
        kp: Vec<f64>,
        kd: Vec<f64>,
        windows: Vec<(f64, f64)>,
    ) -> Result<Self, SimError> {
        let n = feedforward.dim();
        for (name, len) in [
            ("q_ref", q_ref.dim()),
            ("qd_ref", qd_ref.dim()),
            ("kp", kp.len()),
            ("kd", kd.len()),
        ] {
            if len != n {
                return Err(SimError::InvalidSetting {
                    name,
                    msg: format!("length {len} differs from the {n} feed-forward torques"),
                });
            }
        }
        if let Some(g) = kp
            .iter()
            .chain(&kd)
            .find(|g| !(g.is_finite() && **g >= 0.0))
        {
            return Err(SimError::InvalidSetting {
                name: "TrackingPd gains",
                msg: format!("{g} is not a finite non-negative gain"),
            });
        }
        if let Some(w) = windows
            .iter()
            .find(|(a, b)| !(a.is_finite() && b.is_finite() && a <= b))
        {
            return Err(SimError::InvalidSetting {
                name: "TrackingPd windows",
                msg: format!("[{}, {}) is not a finite interval", w.0, w.1),
            });
        }
        let feedback = kp.iter().chain(&kd).any(|&g| g != 0.0);
        Ok(TrackingPd {
            feedforward,
            q_ref,
            qd_ref,
            kp,
            kd,
            windows,
            feedback,
        })
    }

    /// Whether the feedback acts at time `t` (some gain non-zero and `t` in a window).
    pub fn feedback_at(&self, t: f64) -> bool {
        self.feedback && self.windows.iter().any(|&(a, b)| a <= t && t < b)
    }
}

impl Input for TrackingPd {
    fn dim(&self) -> usize {
        self.kp.len()
    }
    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        check_lengths(self.kp.len(), q, qd, out, &[])?;
        self.feedforward.eval(t, out);
        if self.feedback_at(t) {
            // Two passes without a buffer: this runs in every right-hand side of the integrator.
            self.q_ref
                .eval_each(t, |i, qr| out[i] += self.kp[i] * (qr - q[i]));
            self.qd_ref
                .eval_each(t, |i, qdr| out[i] += self.kd[i] * (qdr - qd[i]));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_linear_and_clamped() {
        let s = TorqueSeries::new(
            vec![0.0, 1.0, 3.0],
            vec![vec![0.0, 1.0], vec![2.0, 1.0], vec![-2.0, 5.0]],
        )
        .unwrap();
        let mut o = [0.0; 2];
        s.eval(0.5, &mut o);
        assert_eq!(o, [1.0, 1.0]);
        s.eval(2.0, &mut o);
        assert_eq!(o, [0.0, 3.0]);
        s.eval(-1.0, &mut o);
        assert_eq!(o, [0.0, 1.0]);
        s.eval(10.0, &mut o);
        assert_eq!(o, [-2.0, 5.0]);
        s.eval(1.0, &mut o);
        assert_eq!(o, [2.0, 1.0]);
    }

    #[test]
    fn csv_and_json_agree() {
        let csv = "t,tau1,tau2\n0,1,2\n0.5,3,4\n2,5,-6\n";
        let json = r#"{"t":[0,0.5,2],"tau":[[1,2],[3,4],[5,-6]]}"#;
        let a = TorqueSeries::from_csv_str(csv, Path::new("a.csv")).unwrap();
        let b = TorqueSeries::from_json_str(json, Path::new("a.json")).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.dim(), 2);
    }

    fn csv_error(text: &str) -> (Option<usize>, String) {
        match TorqueSeries::from_csv_str(text, Path::new("bad.csv")) {
            Err(SimError::Parse { line, msg, path }) => {
                assert_eq!(path, Path::new("bad.csv"));
                (line, msg)
            }
            other => panic!("expected parse error, got {other:?}"),
        }
    }

    #[test]
    fn malformed_csv_errors_name_the_line() {
        for (text, line, needle) in [
            ("t,tau1\n0,1\n1,2\n0.5,3\n", 4, "not strictly increasing"),
            ("t,tau1,tau2\n0,1,2\n1,2\n", 3, "columns"),
            ("t,tau1\n0,1\n1,NaN\n", 3, "not finite"),
            ("t,tau1\n0,abc\n", 2, "not a number"),
            ("time,tau1\n0,1\n", 1, "header"),
        ] {
            let (l, m) = csv_error(text);
            assert_eq!(l, Some(line), "{text:?}");
            assert!(m.contains(needle), "{m}");
        }
        let (_, m) = csv_error("t,tau1\n");
        assert!(m.contains("no samples"), "{m}");
    }

    #[test]
    fn malformed_json_errors() {
        for (text, needle) in [
            (
                r#"{"t":[0,1],"tau":[[1],[2,3]]}"#,
                "sample 1 has 2 torques and sample 0 has 1",
            ),
            (r#"{"t":[0,1,2],"tau":[[1],[2]]}"#, "3 times but 2"),
            (r#"{"t":[1,0],"tau":[[1],[2]]}"#, "not strictly increasing"),
            (r#"{"t":[0,1],"tau":[[1],[null]]}"#, "invalid JSON"),
            (r#"{"t":[0,1]"#, "invalid JSON"),
        ] {
            match TorqueSeries::from_json_str(text, Path::new("x.json")) {
                Err(e @ SimError::Parse { .. }) => {
                    let s = e.to_string();
                    assert!(s.contains(needle) && s.contains("x.json"), "{s}");
                }
                other => panic!("{text}: expected parse error, got {other:?}"),
            }
        }
    }

    #[test]
    fn missing_file_is_io_error_with_path() {
        let p = Path::new("/nonexistent/dir/torques.csv");
        match TorqueSeries::from_path(p) {
            Err(e @ SimError::Io { .. }) => assert!(e.to_string().contains("torques.csv")),
            other => panic!("expected Io error, got {other:?}"),
        }
    }

    #[test]
    fn csv_roundtrip_through_file() {
        let s =
            TorqueSeries::new(vec![0.0, 0.1, 0.3], vec![vec![0.1, -0.2, 1.0 / 3.0]; 3]).unwrap();
        let dir = std::env::temp_dir().join(format!("bf-sim-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("tau.csv");
        s.write_csv(&p).unwrap();
        let r = TorqueSeries::from_path(&p).unwrap();
        assert_eq!(s, r);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pd_controller_law_and_dimension_errors() {
        let pd = PdController::new(vec![2.0, 3.0], vec![0.5, 1.0], vec![1.0, -1.0]).unwrap();
        let mut o = [0.0; 2];
        pd.tau(0.0, &[0.5, 0.0], &[1.0, -2.0], &mut o).unwrap();
        // τ = kp (target − q) − kd q̇ = [2·0.5 − 0.5·1, 3·(−1) − 1·(−2)].
        assert_eq!(o, [0.5, -1.0]);
        assert!(pd.tau(0.0, &[0.0], &[0.0, 0.0], &mut o).is_err());
        assert!(PdController::new(vec![1.0], vec![1.0, 2.0], vec![0.0]).is_err());
        assert!(PdController::new(vec![f64::NAN], vec![1.0], vec![0.0]).is_err());
    }

    #[test]
    fn tracking_pd_law_windows_and_errors() {
        let series =
            |v: [f64; 2]| TorqueSeries::new(vec![0.0, 2.0], vec![vec![v[0]], vec![v[1]]]).unwrap();
        // τ* = t, q* = 1 + t, q̇* = 1 on [0, 2], gains kp, kd, feedback window w.
        let tracking = |kp: f64, kd: f64, w: (f64, f64)| {
            TrackingPd::new(
                series([0.0, 2.0]),
                series([1.0, 3.0]),
                series([1.0, 1.0]),
                vec![kp],
                vec![kd],
                vec![w],
            )
        };
        let pd = tracking(4.0, 0.5, (0.5, 1.0)).unwrap();
        let mut o = [0.0];
        pd.tau(0.75, &[1.0], &[3.0], &mut o).unwrap();
        // 0.75 + 4 (1.75 − 1) + 0.5 (1 − 3) = 0.75 + 3 − 1.
        assert_eq!(o, [2.75]);
        pd.tau(1.0, &[1.0], &[3.0], &mut o).unwrap();
        assert_eq!(o, [1.0], "window end is open");
        pd.tau(0.25, &[1.0], &[3.0], &mut o).unwrap();
        assert_eq!(o, [0.25]);
        // Zero gains: the feed-forward series exactly, inside the window too.
        let zero = tracking(0.0, 0.0, (0.0, 2.0)).unwrap();
        assert!(!zero.feedback_at(0.75));
        zero.tau(0.75, &[-7.0], &[9.0], &mut o).unwrap();
        assert_eq!(o, [0.75]);
        assert!(pd.tau(0.75, &[1.0, 2.0], &[3.0], &mut o).is_err());
        let bad = |kp: f64, w: (f64, f64)| tracking(kp, 0.0, w);
        assert!(bad(-1.0, (0.0, 1.0)).is_err());
        assert!(bad(f64::NAN, (0.0, 1.0)).is_err());
        assert!(bad(1.0, (1.0, 0.0)).is_err());
        assert!(bad(1.0, (0.0, 1.0)).is_ok());
    }
}
