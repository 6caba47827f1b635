//! `Simulator`: the step-to-event loop over a [`HybridSystem`] (paper Sect. 3.2, Fig. 3).
//!
//! Detailed API (in the style of diffsol's step-by-step solver):
//! ```text
//! let mut sim = Simulator::new(&sys, settings, mode0, t0, &x0, t_end)?;
//! loop {
//!     match sim.step()? {
//!         StopReason::Step => {}
//!         StopReason::RootFound { .. } => sim.apply_reset()?,   // state is already at the root
//!         StopReason::TEndReached | StopReason::Terminated => break,
//!     }
//! }
//! let out = sim.finish();
//! ```
//! ([`Simulator::advance`] is one turn of that loop) or simply [`simulate`] /
//! [`Simulator::run`], which return the partial trajectory inside a
//! [`SimFailure`] when the run fails.
//!
//! Each accepted step is followed by guard scanning on its dense output ([`crate::events`]);
//! if an event is found the state is moved back to the event time (`state_mut_back` in diffsol's
//! terms), a pre-event sample is recorded, and `step()` returns `RootFound`. `apply_reset` runs
//! the reset map, logs the event, applies the Zeno guard (more than `zeno_max_events` events
//! within `zeno_window`: the system's [`HybridSystem::zeno_fallback`] may end the cascade, which
//! is then recorded as a [`SimWarning`]; without a fallback the run stops with
//! [`SimError::Zeno`]), and checks whether the new mode has a
//! directional guard already beyond its zero (then the next `step()` reports that event at the
//! same instant: a chained transition, bounded by `max_chained_events`).
//!
//! Files: the step loop here; the event step [`Simulator::apply_reset`] in `reset.rs`;
//! [`SimFailure`] and [`simulate`] in `failure.rs`.

mod failure;
mod reset;

pub use failure::{SimFailure, simulate, simulate_until};

use crate::events::{GuardProbe, beyond_triggered, scan_guard};
use crate::integrator::{
    FAC_MAX, FAC_MIN, PI_BETA, PI_SAFE, StepBuffers, dopri5_step, error_norm, initial_step,
    rk4_step,
};
use crate::trajectory::{EventRecord, SampleKind, SimOutput, SimStats, SimWarning, Trajectory};
use crate::{Guard, HybridSystem, Method, SimError, SimSettings};
use std::collections::VecDeque;
use std::fmt::Debug;

/// What one call of [`Simulator::step`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// An integration step was accepted without events.
    Step,
    /// A guard fired at `t`; the state has been moved to the event time (pre-reset). Call
    /// [`Simulator::apply_reset`] (or `step()` again, which applies it first).
    RootFound {
        /// Event time (s).
        t: f64,
        /// Guard index in the current mode.
        guard: usize,
        /// Guard name.
        name: &'static str,
    },
    /// `t_end` was reached.
    TEndReached,
    /// A reset returned [`Transition::Terminate`](crate::Transition::Terminate).
    Terminated,
}

/// Earliest event (guard index, time) of a step, if any, and the guard masks at its end.
type Located = (Option<(usize, f64)>, Vec<bool>);

/// Outcome of [`Simulator::check_trial`].
struct Found {
    /// Earliest event (guard index, time) on the step, if any.
    event: Option<(usize, f64)>,
    /// Guard masks at the step end.
    mask: Vec<bool>,
    /// Drift removed by the projection of the step end (no event only).
    drift: Option<f64>,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    guard: usize,
    reported: bool,
    chained: bool,
}

/// The hybrid simulator state machine. See the module docs for the loop.
///
/// `S` may be a trait object (`dyn HybridSystem<Mode = M>`): callers that run many system
/// types (every joint count of a finger) pass them that way, so one compiled copy of the
/// simulator serves them all.
pub struct Simulator<'s, S: HybridSystem + ?Sized> {
    sys: &'s S,
    set: SimSettings,
    t_start: f64,
    t_end: f64,
    t: f64,
    x: Vec<f64>,
    mode: S::Mode,
    f: Vec<f64>,
    f_valid: bool,
    h: f64,
    err_old: f64,
    last_rejected: bool,
    guards: Vec<Guard>,
    gval: Vec<f64>,
    masked: Vec<bool>,
    pending: Option<Pending>,
    buf: StepBuffers,
    traj: Trajectory<S::Mode>,
    events: Vec<EventRecord<S::Mode>>,
    stats: SimStats,
    recent_events: VecDeque<(f64, &'static str, S::Mode)>,
    warnings: Vec<SimWarning>,
    chain: usize,
    last_event_t: Option<f64>,
    next_grid: u64,
    finished: Option<StopReason>,
    steps_attempted: usize,
    last_drift: Option<f64>,
    domain_creep: usize,
}

fn mode_name<M: Debug>(m: &M) -> String {
    format!("{m:?}")
}

impl<'s, S: HybridSystem + ?Sized> Simulator<'s, S> {
    /// Sets up a run of `sys` from (`t0`, `x0`) in `mode0` until `t_end`. Validates the
    /// settings, the dimensions, finiteness of `x0` and `t_end > t0`, evaluates the guards of
    /// `mode0` (a directional guard already beyond its zero fires at the first `step()`).
    pub fn new(
        sys: &'s S,
        settings: SimSettings,
        mode0: S::Mode,
        t0: f64,
        x0: &[f64],
        t_end: f64,
    ) -> Result<Self, SimError> {
        settings.validate()?;
        let n = sys.dim();
        if x0.len() != n {
            return Err(SimError::DimensionMismatch {
                what: "initial state",
                expected: n,
                found: x0.len(),
            });
        }
        if !t0.is_finite() || !t_end.is_finite() || t_end <= t0 {
            return Err(SimError::InvalidSetting {
                name: "t_end",
                msg: format!("need finite t_end > t0, got t0 = {t0}, t_end = {t_end}"),
            });
        }
        if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFinite {
                what: format!("initial state component {i}"),
                t: t0,
                mode: mode_name(&mode0),
            });
        }
        let mut sim = Simulator {
            sys,
            t_start: t0,
            t_end,
            t: t0,
            x: x0.to_vec(),
            mode: mode0,
            f: vec![0.0; n],
            f_valid: false,
            h: 0.0,
            err_old: 1e-4,
            last_rejected: false,
            guards: Vec::new(),
            gval: Vec::new(),
            masked: Vec::new(),
            pending: None,
            buf: StepBuffers::new(n),
            traj: Trajectory::default(),
            events: Vec::new(),
            stats: SimStats::default(),
            recent_events: VecDeque::new(),
            warnings: Vec::new(),
            chain: 0,
            last_event_t: None,
            next_grid: 0,
            finished: None,
            steps_attempted: 0,
            last_drift: None,
            domain_creep: 0,
            set: settings,
        };
        sim.sys.check_valid(sim.mode, t0, &sim.x)?;
        sim.traj
            .push(t0, &sim.x, sim.mode, SampleKind::Initial, None);
        if sim.set.output_dt.is_some() {
            sim.traj.push(t0, &sim.x, sim.mode, SampleKind::Grid, None);
            sim.next_grid = 1;
        }
        sim.enter_mode(false)?;
        sim.h = match (sim.set.method, sim.set.h_init) {
            (Method::Rk4 { h }, _) => h,
            (Method::Dopri5, Some(h)) => h.min(sim.set.h_max),
            (Method::Dopri5, None) => {
                sim.ensure_f()?;
                sim.stats.rhs_evals += 1;
                initial_step(
                    sys,
                    sim.mode,
                    t0,
                    &sim.x,
                    &sim.f,
                    sim.set.rtol,
                    sim.set.atol,
                    sim.set.h_max,
                )?
            }
        };
        Ok(sim)
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// Current mode.
    pub fn mode(&self) -> S::Mode {
        self.mode
    }

    /// Trajectory recorded so far.
    pub fn trajectory(&self) -> &Trajectory<S::Mode> {
        &self.traj
    }

    /// Event log so far.
    pub fn events(&self) -> &[EventRecord<S::Mode>] {
        &self.events
    }

    /// Warnings so far (Zeno fallbacks).
    pub fn warnings(&self) -> &[SimWarning] {
        &self.warnings
    }

    /// Counters so far.
    pub fn stats(&self) -> SimStats {
        self.stats
    }

    fn ensure_f(&mut self) -> Result<(), SimError> {
        if !self.f_valid {
            self.sys.rhs(self.mode, self.t, &self.x, &mut self.f)?;
            self.stats.rhs_evals += 1;
            if self.f.iter().any(|v| !v.is_finite()) {
                return Err(self.non_finite("vector field"));
            }
            self.f_valid = true;
        }
        Ok(())
    }

    fn non_finite(&self, what: &str) -> SimError {
        SimError::NonFinite {
            what: what.to_string(),
            t: self.t,
            mode: mode_name(&self.mode),
        }
    }

    /// (Re)loads the guards of the current mode at the current state, masks those on their
    /// surface, and schedules an immediate event for a directional guard beyond its zero.
    fn enter_mode(&mut self, chained: bool) -> Result<(), SimError> {
        self.guards = self.sys.guards(self.mode);
        let m = self.guards.len();
        self.gval.resize(m, 0.0);
        self.sys
            .guard_values(self.mode, self.t, &self.x, &mut self.gval)?;
        self.stats.guard_evals += 1;
        if let Some(j) = self.gval.iter().position(|v| !v.is_finite()) {
            return Err(self.non_finite(&format!("guard `{}`", self.guards[j].name)));
        }
        let tol = self.set.guard_zero_tol;
        self.masked = self.gval.iter().map(|v| v.abs() <= tol).collect();
        let imm = (0..m).find(|&j| beyond_triggered(self.guards[j].direction, self.gval[j], tol));
        self.pending = imm.map(|guard| Pending {
            guard,
            reported: false,
            chained,
        });
        Ok(())
    }

    /// Advances the simulation by one accepted step, or up to the next event, or reports the
    /// end. A pending event from the previous call is applied first.
    ///
    /// A trial step is rejected and retried shorter when its error test fails, a stage is not
    /// finite, or the system raises [`SimError::OutsideDomain`] at a stage, at a guard sample of
    /// the dense output, or at the projected end state (`project` / `check_valid`): the state
    /// must stay inside the mode's domain over the whole step (e.g. |h| within the contact band
    /// in a contact mode), and a shorter step keeps it there unless the trajectory itself runs
    /// into the boundary (see `SimSettings::max_domain_creep`).
    pub fn step(&mut self) -> Result<StopReason, SimError> {
        if let Some(r) = self.finished {
            return Ok(r);
        }
        if let Some(p) = self.pending {
            if !p.reported {
                self.pending = Some(Pending {
                    reported: true,
                    ..p
                });
                return Ok(StopReason::RootFound {
                    t: self.t,
                    guard: p.guard,
                    name: self.guards[p.guard].name,
                });
            }
            self.apply_reset()?;
            return self.step();
        }
        let remaining = self.t_end - self.t;
        if remaining <= 0.0 {
            self.finished = Some(StopReason::TEndReached);
            return Ok(StopReason::TEndReached);
        }
        self.ensure_f()?;
        let fixed = matches!(self.set.method, Method::Rk4 { .. });
        let mut h = self.h.min(self.set.h_max);
        if let Method::Rk4 { h: hf } = self.set.method {
            h = hf;
        }
        // Stretch/shrink the last step onto t_end instead of leaving a sliver.
        let mut last = false;
        if self.t + 1.01 * h >= self.t_end {
            h = remaining;
            last = true;
        }
        self.sys.fixed_step(fixed.then_some(h));
        let mut domain_rejected = false;
        loop {
            self.steps_attempted += 1;
            if self.steps_attempted > self.set.max_steps {
                return Err(SimError::MaxSteps {
                    t: self.t,
                    max_steps: self.set.max_steps,
                    mode: mode_name(&self.mode),
                });
            }
            let (err, mut cause) = match self.trial(h, fixed) {
                Ok(err) => (err, None),
                Err(e) if e.is_step_rejectable() => (f64::INFINITY, Some(e)),
                Err(e) => return Err(e),
            };
            if err <= 1.0 {
                let t1 = if last { self.t_end } else { self.t + h };
                match self.check_trial(t1) {
                    Ok(found) => {
                        if !fixed {
                            let expo1 = 0.2 - PI_BETA * 0.75;
                            let fac11 = libm::pow(err.max(1e-300), expo1);
                            let fac = (fac11 / libm::pow(self.err_old, PI_BETA) / PI_SAFE)
                                .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                            let mut h_new = h / fac;
                            if self.last_rejected {
                                h_new = h_new.min(h);
                            }
                            self.err_old = err.max(1e-4);
                            self.last_rejected = false;
                            self.h = h_new.min(self.set.h_max);
                        }
                        self.stats.accepted_steps += 1;
                        self.domain_creep = if domain_rejected {
                            self.domain_creep + 1
                        } else {
                            0
                        };
                        return self.commit(t1, found);
                    }
                    Err((e, _)) if e.is_step_rejectable() => cause = Some(e),
                    Err((e, at_end)) => {
                        if at_end {
                            // The step end itself is invalid: stop there (the trajectory keeps
                            // the last valid sample), as for any failure after a step.
                            self.emit_grid(t1);
                            self.t = t1;
                            std::mem::swap(&mut self.x, &mut self.buf.x1);
                            self.f_valid = false;
                        }
                        return Err(e);
                    }
                }
            }
            self.stats.rejected_steps += 1;
            self.last_rejected = true;
            last = false;
            h = if err.is_finite() && cause.is_none() {
                let fac11 = libm::pow(err, 0.2 - PI_BETA * 0.75);
                h / (fac11 / PI_SAFE).min(1.0 / FAC_MIN)
            } else {
                0.25 * h
            };
            if h < self.set.h_min {
                return Err(match cause {
                    Some(e) => e,
                    None if err.is_finite() => SimError::StepSizeTooSmall {
                        t: self.t,
                        h,
                        mode: mode_name(&self.mode),
                    },
                    None => self.non_finite(
                        "step (its stages blew up at every step down to h_min: the dynamics \
                         are too stiff for this step and tolerance)",
                    ),
                });
            }
            if let Some(e) = cause {
                if self.domain_creep >= self.set.max_domain_creep {
                    return Err(e);
                }
                self.stats.domain_rejections += 1;
                domain_rejected = true;
            }
        }
    }

    /// One Runge–Kutta trial of length `h` from the current state into `self.buf`; returns the
    /// error norm (0 for fixed steps, ∞ when a stage or the end state is not finite, or blew up
    /// where the system could not evaluate it).
    fn trial(&mut self, h: f64, fixed: bool) -> Result<f64, SimError> {
        if fixed {
            self.stats.rhs_evals += 4;
            rk4_step(
                self.sys,
                self.mode,
                self.t,
                &self.x,
                &self.f,
                h,
                &mut self.buf,
            )?;
        } else {
            self.stats.rhs_evals += 6;
            dopri5_step(
                self.sys,
                self.mode,
                self.t,
                &self.x,
                &self.f,
                h,
                &mut self.buf,
            )?;
        }
        let finite = self
            .buf
            .x1
            .iter()
            .chain(&self.buf.f1)
            .all(|v| v.is_finite());
        Ok(if !finite {
            f64::INFINITY
        } else if fixed {
            0.0
        } else {
            error_norm(
                &self.buf.err,
                &self.x,
                &self.buf.x1,
                self.set.rtol,
                self.set.atol,
            )
        })
    }

    /// Checks a trial step that passed the error test: locates the earliest event on its
    /// dense output; without an event, projects the end state (`self.buf.x1`, in place) and
    /// checks its validity. Nothing of the simulator's state is committed here, so an error
    /// leaves the step retryable.
    ///
    /// Errors carry whether they concern the (projected) step end rather than the step itself.
    fn check_trial(&mut self, t1: f64) -> Result<Found, (SimError, bool)> {
        let (event, mask) = self.locate(t1).map_err(|e| (e, false))?;
        if event.is_some() {
            return Ok(Found {
                event,
                mask,
                drift: None,
            });
        }
        let at_end = |e| (e, true);
        let drift = self
            .sys
            .project(self.mode, t1, &mut self.buf.x1)
            .map_err(at_end)?;
        if self.buf.x1.iter().any(|v| !v.is_finite()) {
            return Err(at_end(SimError::NonFinite {
                what: "state after projection".to_string(),
                t: t1,
                mode: mode_name(&self.mode),
            }));
        }
        self.sys
            .check_valid(self.mode, t1, &self.buf.x1)
            .map_err(at_end)?;
        Ok(Found { event, mask, drift })
    }

    /// Commits an accepted and checked step ending at `t1`: moves to the event time (and
    /// reports the root) or to the (projected) step end.
    fn commit(&mut self, t1: f64, found: Found) -> Result<StopReason, SimError> {
        match found.event {
            Some((guard, te)) => {
                let mut xe = vec![0.0; self.x.len()];
                if te > self.t {
                    self.buf.dense.eval(te, &mut xe);
                } else {
                    xe.copy_from_slice(&self.x);
                }
                self.emit_grid(te);
                self.t = te;
                self.x = xe;
                self.f_valid = false;
                self.traj
                    .push(self.t, &self.x, self.mode, SampleKind::EventPre, None);
                self.pending = Some(Pending {
                    guard,
                    reported: true,
                    chained: false,
                });
                Ok(StopReason::RootFound {
                    t: te,
                    guard,
                    name: self.guards[guard].name,
                })
            }
            None => {
                self.masked = found.mask;
                self.emit_grid(t1);
                self.t = t1;
                std::mem::swap(&mut self.x, &mut self.buf.x1);
                std::mem::swap(&mut self.f, &mut self.buf.f1);
                self.f_valid = true;
                self.last_drift = found.drift;
                if let Some(d) = self.last_drift {
                    self.stats.max_drift = self.stats.max_drift.max(d.abs());
                    // The projection moved x off the FSAL point.
                    self.f_valid = false;
                }
                if self.set.record_steps {
                    self.traj.push(
                        self.t,
                        &self.x,
                        self.mode,
                        SampleKind::Step,
                        self.last_drift,
                    );
                }
                // Guard values at the new step start (after projection).
                self.sys
                    .guard_values(self.mode, self.t, &self.x, &mut self.gval)?;
                self.stats.guard_evals += 1;
                if self.t >= self.t_end {
                    self.finished = Some(StopReason::TEndReached);
                    return Ok(StopReason::TEndReached);
                }
                Ok(StopReason::Step)
            }
        }
    }

    /// Scans every guard over the step just accepted (dense output in `self.buf.dense`) and
    /// returns the earliest event (guard index, time) and the guard masks at the step end (to
    /// be committed when the step is taken without an event).
    fn locate(&mut self, t1: f64) -> Result<Located, SimError> {
        let m = self.guards.len();
        if m == 0 {
            return Ok((None, Vec::new()));
        }
        let kk = self.set.event_subdivisions;
        let t0 = self.t;
        let ts: Vec<f64> = (0..=kk)
            .map(|k| {
                if k == kk {
                    t1
                } else {
                    t0 + (t1 - t0) * k as f64 / kk as f64
                }
            })
            .collect();
        let mut probe = GuardProbe {
            sys: self.sys,
            mode: self.mode,
            dense: &self.buf.dense,
            x: vec![0.0; self.x.len()],
            g: vec![0.0; m],
            evals: 0,
        };
        // vals[j][k] = g_j(ts[k])
        let mut vals = vec![vec![0.0; kk + 1]; m];
        for j in 0..m {
            vals[j][0] = self.gval[j];
        }
        let mut gk = vec![0.0; m];
        for k in 1..=kk {
            probe.dense.eval(ts[k], &mut probe.x);
            self.sys.guard_values(self.mode, ts[k], &probe.x, &mut gk)?;
            probe.evals += 1;
            for j in 0..m {
                if !gk[j].is_finite() {
                    return Err(SimError::NonFinite {
                        what: format!("guard `{}`", self.guards[j].name),
                        t: ts[k],
                        mode: mode_name(&self.mode),
                    });
                }
                vals[j][k] = gk[j];
            }
        }
        let mut best: Option<(usize, f64)> = None;
        let mut new_mask = self.masked.clone();
        for j in 0..m {
            let scan = scan_guard(
                &mut probe,
                j,
                &self.guards[j],
                self.masked[j],
                &ts,
                &vals[j],
                self.set.event_tol,
                self.set.guard_zero_tol,
            )?;
            new_mask[j] = scan.still_masked;
            if let Some(te) = scan.t_event
                && best.is_none_or(|(_, tb)| te < tb)
            {
                best = Some((j, te));
            }
        }
        self.stats.guard_evals += probe.evals;
        Ok((best, new_mask))
    }

    /// Records uniform-grid samples in (previous grid time, `t_upto`] from the current dense
    /// output.
    fn emit_grid(&mut self, t_upto: f64) {
        let Some(dt) = self.set.output_dt else {
            return;
        };
        let mut xg = vec![0.0; self.x.len()];
        loop {
            let tg = self.t_start + self.next_grid as f64 * dt;
            if tg > t_upto || tg > self.t_end {
                break;
            }
            self.buf.dense.eval(tg, &mut xg);
            self.traj.push(tg, &xg, self.mode, SampleKind::Grid, None);
            self.next_grid += 1;
        }
    }

    /// Consumes the simulator and returns what was computed.
    pub fn finish(self) -> SimOutput<S::Mode> {
        SimOutput {
            terminated: self.finished == Some(StopReason::Terminated),
            trajectory: self.traj,
            events: self.events,
            stats: self.stats,
            t_final: self.t,
            mode_final: self.mode,
            warnings: self.warnings,
        }
    }

    /// One turn of the run loop: [`Simulator::step`], then [`Simulator::apply_reset`] when the
    /// step ended at an event. `Ok(true)` while the run goes on, `Ok(false)` once it has ended
    /// (`t_end` reached or the system terminated it).
    pub fn advance(&mut self) -> Result<bool, SimError> {
        match self.step()? {
            StopReason::Step => Ok(true),
            StopReason::RootFound { .. } => self.apply_reset().map(|()| true),
            StopReason::TEndReached | StopReason::Terminated => Ok(false),
        }
    }

    /// Runs to `t_end` (or termination). On failure, returns the error together with the
    /// partial trajectory and event log up to the last accepted point.
    pub fn run(self) -> Result<SimOutput<S::Mode>, Box<SimFailure<S::Mode>>> {
        self.run_until(|_| false)
    }

    /// [`Simulator::run`], ended early where `until` says so: it is asked after every turn of
    /// the loop ([`Simulator::advance`]: an accepted step, or one ending at an event with its
    /// reset applied) and `true` ends the run there, without error. Every step before is the
    /// one [`Simulator::run`] takes, so the output is a prefix of the whole run's.
    pub fn run_until(
        mut self,
        mut until: impl FnMut(&Self) -> bool,
    ) -> Result<SimOutput<S::Mode>, Box<SimFailure<S::Mode>>> {
        loop {
            match self.advance() {
                Ok(true) if until(&self) => break,
                Ok(true) => {}
                Ok(false) => break,
                Err(error) => {
                    let (t, mode) = (self.t, self.mode);
                    return Err(Box::new(SimFailure {
                        error,
                        t,
                        mode: Some(mode),
                        partial: self.finish(),
                    }));
                }
            }
        }
        Ok(self.finish())
    }
}
