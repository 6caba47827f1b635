//! Progress of a long `ball-finger simulate` run on stderr.

use anyhow::{Result, anyhow};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal as _;
use std::time::Duration;

/// Progress of a long run on stderr: an indicatif bar on a terminal, otherwise a line every
/// [`Progress::LINE_EVERY`]. Nothing for runs shorter than [`Progress::AFTER`].
pub(super) struct Progress {
    bar: Option<ProgressBar>,
    t0: f64,
    t_end: f64,
    last_line: Option<Duration>,
}

impl Progress {
    const AFTER: Duration = Duration::from_secs(1);
    const LINE_EVERY: Duration = Duration::from_secs(10);

    pub(super) fn new(t0: f64, t_end: f64) -> Result<Self> {
        let bar = if std::io::stderr().is_terminal() {
            let pb = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden());
            pb.set_style(
                ProgressStyle::with_template(
                    "simulate {bar:40} t = {msg} s ({elapsed}, eta {eta})",
                )
                .map_err(|e| anyhow!("progress bar template: {e}"))?,
            );
            Some(pb)
        } else {
            None
        };
        Ok(Progress {
            bar,
            t0,
            t_end,
            last_line: None,
        })
    }

    pub(super) fn update(&mut self, elapsed: Duration, t: f64, steps: usize, samples: usize) {
        if elapsed < Self::AFTER {
            return;
        }
        let share = (t - self.t0) / (self.t_end - self.t0);
        match &self.bar {
            Some(pb) => {
                if pb.is_hidden() {
                    pb.set_draw_target(ProgressDrawTarget::stderr());
                }
                pb.set_position((1000.0 * share) as u64);
                pb.set_message(format!("{t:.3}"));
            }
            None => {
                if self
                    .last_line
                    .is_none_or(|last| elapsed >= last + Self::LINE_EVERY)
                {
                    self.last_line = Some(elapsed);
                    crate::errln!(
                        "simulate: t = {t:.4} s of {} s ({:.1} %), {steps} steps, {samples} \
                         samples, {:.0} s elapsed",
                        self.t_end,
                        100.0 * share,
                        elapsed.as_secs_f64()
                    );
                }
            }
        }
    }

    pub(super) fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}
