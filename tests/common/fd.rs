//! Random points for the finite-difference checks of assembled ball–finger NLPs.
#![allow(dead_code)] // not every test file that includes `common` checks derivatives

use bf_optim::ipm::Nlp;
use bf_optim::ocp::Transcription;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A point near the initial guess of `nlp` (every variable moved by up to ±0.3, phase
/// durations in [0.5, 1.5], the second cost parameter in [1, 2], where the problems' terms
/// are all well defined) and multipliers in [−1, 1] for every constraint.
pub fn random_point(nlp: &Transcription, rng: &mut ChaCha8Rng) -> (Vec<f64>, Vec<f64>) {
    let m = nlp.num_constraints();
    let mut x = nlp.initial().to_vec();
    for v in x.iter_mut() {
        *v += rng.random_range(-0.3..0.3);
    }
    for l in &nlp.phases {
        x[l.t] = rng.random_range(0.5..1.5);
    }
    x[nlp.c0 + 1] = rng.random_range(1.0..2.0);
    let lam = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
    (x, lam)
}
