//! Speculative factorization on a second thread (decision record 0036): while the IPM factors
//! `K(δ_w, δ_c)` for the inertia test (Wächter & Biegler 2006, Sect. 3.1, Algorithm IC), a
//! [`Speculator`] factors on another core the matrix the inertia correction would factor next
//! if this one were rejected (the same matrix with δ_w grown by κ_w⁺), with a copy of the
//! solver ([`SparseLdlt::duplicate`]: the same options and symbolic analysis). When the
//! correction then asks for exactly that matrix (bit for bit the same values), the finished
//! factor is taken instead of factoring again; otherwise it is dropped. A factorization is a
//! deterministic function of the analysis and the values, so the factor taken is the one the
//! solver would have computed: the path of a solve is the same with and without speculation,
//! on any number of cores; only the wall time changes.
//!
//! The second thread is the speculator's own (started at its first job, ended when the
//! speculator is dropped), not a pool's. Speculation pays only where a core is idle: two
//! factorizations at once on a machine whose cores are busy take as long as one after the
//! other (each gets half a core), and the factors of accepted trials (about two thirds) are
//! then work taken from the solve itself. So a solve inside a parallel multi-start (rayon
//! workers that already keep every core busy) does not speculate at all
//! ([`Speculator::worthwhile`]), and otherwise no job is started while the calling thread
//! has recently waited for a core ([`Speculator::idle_core`]: Linux's run-queue delay of the
//! thread, above [`MAX_RUN_QUEUE_WAIT`] of the wall time).

use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{FactorizationFailure, Inertia, SparseLdlt};

/// Smallest factorization work (multiply–adds, [`SparseLdlt::factor_flops`]) worth a second
/// thread: about 0.1 ms of factoring, a few times the cost of handing a job over and back.
pub const MIN_SPECULATION_FLOPS: f64 = 2e5;

/// Share of the wall time the calling thread waited for a core (smoothed over the intervals
/// between factorizations) above which no speculative job is started: the cores are busy.
pub const MAX_RUN_QUEUE_WAIT: f64 = 0.1;

/// A job for the second thread: the solver copy to factor with and the matrix values.
struct Job {
    solver: SparseLdlt,
    values: Vec<f64>,
}

/// A finished job: the solver holding the factor, the values factored, the factorization's
/// outcome and how long it took.
struct Done {
    solver: SparseLdlt,
    values: Vec<f64>,
    result: Result<Inertia, FactorizationFailure>,
    elapsed: Duration,
}

/// Where the solver copy is.
enum Spare {
    /// Not made yet (or dropped because the options changed).
    None,
    /// Idle, with the values buffer of its last job (reused).
    Idle(SparseLdlt, Vec<f64>),
    /// On the second thread, factoring a copy of these values.
    Busy(Vec<f64>),
    /// Back from the second thread.
    Ready(Done),
}

/// A second thread that factors predicted KKT matrices with a copy of the IPM's solver
/// (module docs).
pub struct Speculator {
    spare: Spare,
    jobs: Option<Sender<Job>>,
    done: Option<Receiver<Done>>,
    thread: Option<JoinHandle<()>>,
    /// Time the second thread spent factoring (jobs received back so far).
    busy: Duration,
    /// Whether the calling thread waits for a core.
    cores: CoreWatch,
}

impl Default for Speculator {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for Speculator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Speculator")
            .field("running", &self.thread.is_some())
            .field("busy", &self.busy)
            .finish()
    }
}

impl Speculator {
    /// A speculator without a thread yet.
    pub fn new() -> Self {
        Self {
            spare: Spare::None,
            jobs: None,
            done: None,
            thread: None,
            busy: Duration::ZERO,
            cores: CoreWatch::default(),
        }
    }

    /// Whether a core looks idle from the calling thread: the share of the wall time since
    /// the last call that it spent waiting for a core (Linux `/proc/thread-self/schedstat`,
    /// its second field), halved with each call and averaged with the new share, is below
    /// `MAX_RUN_QUEUE_WAIT`. Without that file (other systems): always.
    pub fn idle_core(&mut self) -> bool {
        self.cores.idle_core()
    }

    /// Time the second thread spent factoring in the jobs that came back since the last call
    /// (a finished job is collected first).
    pub fn take_busy(&mut self) -> Duration {
        self.poll();
        std::mem::take(&mut self.busy)
    }

    /// Whether speculation can pay for `solver` (analysed) on this thread: at least two
    /// cores, a factorization of at least [`MIN_SPECULATION_FLOPS`], the calling thread
    /// not a worker of a rayon pool that already has a thread per core (a parallel multi-start,
    /// whose other workers keep the other cores busy), and a factorization that does not
    /// already share its work with the second core ([`SparseLdlt::shares_factorization`]:
    /// both at once leave three threads spinning on two cores, decision record 0090).
    pub fn worthwhile(solver: &SparseLdlt) -> bool {
        let cores = cores();
        let pool_uses_every_core =
            rayon::current_thread_index().is_some() && rayon::current_num_threads() >= cores;
        cores >= 2
            && !pool_uses_every_core
            && !solver.shares_factorization()
            && solver.factor_flops() >= MIN_SPECULATION_FLOPS
    }

    /// Collects a finished job without waiting.
    fn poll(&mut self) {
        if let Spare::Busy(_) = self.spare
            && let Some(rx) = &self.done
        {
            match rx.try_recv() {
                Ok(done) => {
                    self.busy += done.elapsed;
                    self.spare = Spare::Ready(done);
                }
                Err(TryRecvError::Empty) => {}
                // The thread is gone (it panicked): speculate no more.
                Err(TryRecvError::Disconnected) => self.stop(),
            }
        }
    }

    /// Waits for the job in flight.
    fn wait(&mut self) {
        if let Spare::Busy(_) = self.spare {
            match self.done.as_ref().map(Receiver::recv) {
                Some(Ok(done)) => {
                    self.busy += done.elapsed;
                    self.spare = Spare::Ready(done);
                }
                _ => self.stop(),
            }
        }
    }

    /// Ends the thread (speculation off from here on).
    fn stop(&mut self) {
        self.spare = Spare::None;
        self.jobs = None;
        self.done = None;
        if let Some(t) = self.thread.take() {
            // A panic of the second thread lost only a speculative factor.
            let _ = t.join();
        }
    }

    /// Starts factoring `values` (a matrix with `solver`'s pattern) on the second thread with
    /// a copy of `solver`, unless the copy is still busy with an earlier job (then nothing is
    /// started: the caller factors as it would without speculation). Returns whether a job
    /// started. `fill` writes the values into the buffer it is given (resized to the
    /// pattern's length), so the caller's matrix need not be copied twice.
    pub fn start(&mut self, solver: &SparseLdlt, fill: impl FnOnce(&mut Vec<f64>)) -> bool {
        self.poll();
        let (copy, mut buffer) = match std::mem::replace(&mut self.spare, Spare::None) {
            busy @ Spare::Busy(_) => {
                self.spare = busy;
                return false;
            }
            Spare::Idle(s, b) if s.options() == solver.options() => (s, b),
            Spare::Ready(d) if d.solver.options() == solver.options() => (d.solver, d.values),
            // No copy yet, or one of other options (the solve switched its ordering).
            _ => match solver.duplicate() {
                Some(s) => (s, Vec::new()),
                None => return false,
            },
        };
        if self.thread.is_none() && !self.spawn() {
            return false;
        }
        fill(&mut buffer);
        let pending = buffer.clone();
        let sent = self.jobs.as_ref().is_some_and(|tx| {
            tx.send(Job {
                solver: copy,
                values: buffer,
            })
            .is_ok()
        });
        if sent {
            self.spare = Spare::Busy(pending);
        } else {
            self.stop();
        }
        sent
    }

    /// If the last job factored exactly `values` (bit for bit) with `solver`'s options: waits
    /// for it if it is still running, swaps the solver copy holding its factor into `solver`
    /// (the caller's solver becomes the idle copy) and returns the factorization's outcome
    /// and the time spent waiting. `None` for other values or options (the job is then
    /// dropped when the next one starts).
    pub fn take(
        &mut self,
        solver: &mut SparseLdlt,
        values: &[f64],
    ) -> Option<(Result<Inertia, FactorizationFailure>, Duration)> {
        let matches = |v: &[f64]| {
            v.len() == values.len()
                && v.iter()
                    .zip(values)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
        };
        let waited = Instant::now();
        match &self.spare {
            Spare::Busy(pending) if matches(pending) => self.wait(),
            Spare::Ready(done) if matches(&done.values) => {}
            _ => return None,
        }
        let waited = waited.elapsed();
        match std::mem::replace(&mut self.spare, Spare::None) {
            Spare::Ready(mut done) if done.solver.options() == solver.options() => {
                std::mem::swap(solver, &mut done.solver);
                self.spare = Spare::Idle(done.solver, done.values);
                Some((done.result, waited))
            }
            other => {
                self.spare = other;
                None
            }
        }
    }

    /// Starts the second thread.
    fn spawn(&mut self) -> bool {
        let (job_tx, job_rx) = channel::<Job>();
        let (done_tx, done_rx) = channel::<Done>();
        let thread = std::thread::Builder::new()
            .name("kkt-speculation".into())
            .spawn(move || {
                for Job { mut solver, values } in job_rx {
                    let t = Instant::now();
                    let result = solver.factor_on_one_thread(&values);
                    let done = Done {
                        solver,
                        values,
                        result,
                        elapsed: t.elapsed(),
                    };
                    if done_tx.send(done).is_err() {
                        break;
                    }
                }
            });
        match thread {
            Ok(t) => {
                self.thread = Some(t);
                self.jobs = Some(job_tx);
                self.done = Some(done_rx);
                true
            }
            Err(_) => false,
        }
    }
}

impl Drop for Speculator {
    fn drop(&mut self) {
        // Closing the job channel ends the thread's loop after its current job.
        self.stop();
    }
}

/// The cores this process may use, read once: both uses of the second core ask before every
/// factorization, and on Linux the count comes from cgroup files.
pub(super) fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, usize::from))
}

/// Whether the calling thread waits for a core, from the run-queue delay Linux records for
/// it, smoothed over the intervals between the calls: what both uses of the second core
/// (speculation here, the shared factorization of `supernodal`) ask before they start.
#[derive(Debug, Default, Clone)]
pub(super) struct CoreWatch {
    /// The calling thread's run-queue delay (ns) when last asked, and when.
    last_wait: Option<(Instant, f64)>,
    /// Smoothed share of the wall time the calling thread waited for a core.
    waiting: f64,
}

impl CoreWatch {
    /// Whether no other thread on the machine is ready to run besides the caller: the
    /// runnable count of Linux `/proc/loadavg` (its fourth field, `runnable/total`) below the
    /// number of cores. Without that file: always.
    pub(super) fn machine_idle() -> bool {
        let cores = cores();
        std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|s| {
                let field = s.split_whitespace().nth(3)?;
                field.split('/').next()?.parse::<usize>().ok()
            })
            .is_none_or(|runnable| runnable < cores)
    }

    /// [`Speculator::idle_core`], for either use of the second core.
    pub(super) fn idle_core(&mut self) -> bool {
        let Some(wait) = std::fs::read_to_string("/proc/thread-self/schedstat")
            .ok()
            .and_then(|s| s.split_whitespace().nth(1)?.parse::<f64>().ok())
        else {
            return true;
        };
        let now = Instant::now();
        if let Some((then, before)) = self.last_wait {
            let wall = now.duration_since(then).as_secs_f64() * 1e9;
            if wall > 0.0 {
                let share = ((wait - before) / wall).clamp(0.0, 1.0);
                self.waiting = 0.5 * (self.waiting + share);
            }
        }
        self.last_wait = Some((now, wait));
        self.waiting < MAX_RUN_QUEUE_WAIT
    }
}
