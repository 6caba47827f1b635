//! [`Simulator::apply_reset`]: the event step of the hybrid loop (paper Sect. 3.2, Fig. 3).
//!
//! `apply_reset` runs the reset map, logs the event, applies the Zeno guard (more than
//! `zeno_max_events` events within `zeno_window`: the system's [`HybridSystem::zeno_fallback`]
//! may end the cascade, which is then recorded as a [`SimWarning`]; without a fallback the run
//! stops with [`SimError::Zeno`]), and checks whether the new mode has a directional guard
//! already beyond its zero (then the next `step()` reports that event at the same instant: a
//! chained transition, bounded by `max_chained_events`).

use super::{Simulator, StopReason, mode_name};
use crate::trajectory::{EventRecord, SampleKind, SimWarning};
use crate::{HybridSystem, SimError, Transition};

impl<S: HybridSystem + ?Sized> Simulator<'_, S> {
    /// Applies the reset of the pending event (the state must be at the event time, which
    /// `step()` guarantees): runs the reset map, logs the event, enforces the Zeno and chain
    /// limits, and enters the new mode. No-op if no event is pending.
    pub fn apply_reset(&mut self) -> Result<(), SimError> {
        let Some(p) = self.pending.take() else {
            return Ok(());
        };
        let t = self.t;
        let mode_before = self.mode;
        let x_pre = self.x.clone();
        let tr = self.sys.reset(self.mode, p.guard, t, &mut self.x)?;
        if self.x.iter().any(|v| !v.is_finite()) {
            return Err(self.non_finite(&format!(
                "state after reset of guard `{}`",
                self.guards[p.guard].name
            )));
        }
        self.stats.events += 1;
        self.chain = match self.last_event_t {
            Some(tl) if (t - tl).abs() <= 2.0 * self.set.event_tol => self.chain + 1,
            _ => 1,
        };
        self.last_event_t = Some(t);
        self.recent_events
            .push_back((t, self.guards[p.guard].name, mode_before));
        while self
            .recent_events
            .front()
            .is_some_and(|&(tf, _, _)| tf < t - self.set.zeno_window)
        {
            self.recent_events.pop_front();
        }
        let mut zeno_fallback = false;
        let mut mode_after = match tr {
            Transition::To(m) => Some(m),
            Transition::Terminate => None,
        };
        if self.recent_events.len() > self.set.zeno_max_events {
            let count = self.recent_events.len();
            let fallback = match mode_after {
                Some(m) => {
                    let recent: Vec<(&'static str, S::Mode)> =
                        self.recent_events.iter().map(|&(_, g, m)| (g, m)).collect();
                    self.sys.zeno_fallback(m, t, &mut self.x, &recent)?
                }
                None => None,
            };
            let Some((m, message)) = fallback else {
                return Err(SimError::Zeno {
                    t,
                    mode: mode_name(&mode_before),
                    count,
                });
            };
            if self.x.iter().any(|v| !v.is_finite()) {
                return Err(self.non_finite("state after the Zeno fallback"));
            }
            mode_after = Some(m);
            zeno_fallback = true;
            self.stats.zeno_fallbacks += 1;
            self.warnings.push(SimWarning {
                t,
                kind: "zeno_fallback",
                message: format!(
                    "{count} events within {} s: {message}",
                    self.set.zeno_window
                ),
            });
            self.recent_events.clear();
        }
        self.events.push(EventRecord {
            t,
            guard: self.guards[p.guard].name,
            guard_index: p.guard,
            mode_before,
            mode_after,
            x_pre,
            x_post: self.x.clone(),
            chained: p.chained,
            zeno_fallback,
        });
        if self.chain > self.set.max_chained_events {
            return Err(SimError::ChainLimit {
                t,
                mode: mode_name(&self.mode),
                count: self.chain,
            });
        }
        self.f_valid = false;
        match mode_after {
            None => {
                self.traj
                    .push(t, &self.x, self.mode, SampleKind::EventPost, None);
                self.finished = Some(StopReason::Terminated);
            }
            Some(m) => {
                self.mode = m;
                self.traj
                    .push(t, &self.x, self.mode, SampleKind::EventPost, None);
                self.sys.check_valid(self.mode, t, &self.x)?;
                self.enter_mode(true)?;
            }
        }
        Ok(())
    }
}
