//! Progress of the long commands (`paper`, `report`) for logs: when stderr is not a terminal
//! (CI), the terminal progress bars are hidden, so a [`Heartbeat`] prints one line when the
//! stage changes and one every [`HEARTBEAT`] while a stage runs. On a terminal it prints
//! nothing (the bars show the progress), like `optimize`'s line mode.

use std::io::IsTerminal;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Interval of the heartbeat lines.
pub const HEARTBEAT: Duration = Duration::from_secs(5);

/// Whether progress goes to the log as lines (stderr is not a terminal).
pub fn line_mode() -> bool {
    !std::io::stderr().is_terminal()
}

/// Prints `<label>: <stage> (<elapsed> s)` to stderr on every stage change and every
/// [`HEARTBEAT`], in line mode only; stops when dropped.
pub struct Heartbeat {
    stage: Arc<Mutex<(String, Instant)>>,
    stop: Option<Sender<()>>,
    thread: Option<JoinHandle<()>>,
    label: String,
    start: Instant,
    lines: bool,
}

impl Heartbeat {
    /// Starts the heartbeat of command `label` (lines only when [`line_mode`]).
    pub fn start(label: &str) -> Self {
        Self::with(label, line_mode(), HEARTBEAT)
    }

    /// Starts a heartbeat that prints lines if `lines`, every `every`.
    pub fn with(label: &str, lines: bool, every: Duration) -> Self {
        let start = Instant::now();
        let stage = Arc::new(Mutex::new((String::from("starting"), start)));
        let (stop, thread) = if lines {
            let (tx, rx) = mpsc::channel::<()>();
            let st = Arc::clone(&stage);
            let label = label.to_string();
            let h = std::thread::spawn(move || {
                while let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(every) {
                    let (name, since) = st
                        .lock()
                        .map(|g| g.clone())
                        .unwrap_or_else(|e| e.into_inner().clone());
                    crate::errln!(
                        "{label}: {name} ... {:.0} s in this stage, {:.0} s in all",
                        since.elapsed().as_secs_f64(),
                        start.elapsed().as_secs_f64()
                    );
                }
            });
            (Some(tx), Some(h))
        } else {
            (None, None)
        };
        Heartbeat {
            stage,
            stop,
            thread,
            label: label.to_string(),
            start,
            lines,
        }
    }

    /// Enters a new stage (printed at once in line mode).
    pub fn stage(&self, name: &str) {
        if let Ok(mut g) = self.stage.lock() {
            *g = (name.to_string(), Instant::now());
        }
        if self.lines {
            crate::errln!(
                "{}: {name} (at {:.1} s)",
                self.label,
                self.start.elapsed().as_secs_f64()
            );
        }
    }

    /// Prints one progress line within the current stage (line mode only).
    pub fn line(&self, text: &str) {
        if self.lines {
            crate::errln!("{}: {text}", self.label);
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(h) = self.thread.take() {
            let _ = h.join();
        }
    }
}
