//! The line-search heuristics of Ipopt on the Hock–Schittkowski suite, each problem with its
//! objective as given and multiplied by 1e8 and 1e12:
//!
//! * the watchdog (`Settings::watchdog_shortened_iter_trigger`): without unchecked steps
//!   (`watchdog_trial_iter_max` = 0) and without second-order corrections, a watchdog only
//!   re-tests the full step against the iterate it was started at and returns there to
//!   backtrack from half the step: exactly the regular line search, so every iterate must agree
//!   bit for bit with the run without the watchdog; under stress (a watchdog after every
//!   shortened step, up to 3 unchecked full steps each, returns to iterates several steps back),
//!   every problem must still end with the status and objective of the run without it: a
//!   return that restored a multiplier, slack or derivative of another iterate, or a full step
//!   judged against the wrong reference, would show as another status or optimum;
//! * the filter reset (`Settings::filter_reset_trigger`, `max_filter_resets`): with and without
//!   it every run ends with the same status and optimum, and with a trigger of one blocked line
//!   search (instead of Ipopt's five) the resets happen often, so the comparison exercises them.

mod hs;

use bf_optim::ipm::Settings;
use hs::{assert_same_results, sweep_scaled_objectives as sweep};

#[test]
fn a_watchdog_without_unchecked_steps_is_the_regular_line_search() {
    let plain = Settings {
        max_soc: 0,
        ..Settings::default()
    };
    let watched = Settings {
        watchdog_shortened_iter_trigger: 1,
        watchdog_trial_iter_max: 0,
        ..plain.clone()
    };
    let (a, b) = (sweep(&plain), sweep(&watched));
    let mut returns = 0;
    for ((name, obj, p), (_, _, w)) in a.iter().zip(&b) {
        assert_eq!(p.counters.watchdogs, 0);
        assert_eq!(
            (w.status, w.iterations, &w.x),
            (p.status, p.iterations, &p.x),
            "{name} × {obj:e}"
        );
        returns += w.counters.watchdog_returns;
    }
    assert!(returns > 0, "no watchdog returned");
}

#[test]
fn watchdogs_after_every_shortened_step_keep_every_result() {
    let plain = sweep(&Settings::default());
    let stressed = sweep(&Settings {
        watchdog_shortened_iter_trigger: 1,
        ..Settings::default()
    });
    assert_same_results(&plain, &stressed, "with watchdogs");
    let watchdogs: usize = stressed.iter().map(|(_, _, w)| w.counters.watchdogs).sum();
    let returns: usize = stressed
        .iter()
        .map(|(_, _, w)| w.counters.watchdog_returns)
        .sum();
    // The stress reaches both outcomes: watchdogs whose full steps succeed and returns.
    assert!(
        returns > 0 && watchdogs > returns,
        "{watchdogs} watchdogs, {returns} returns"
    );
}

#[test]
fn filter_resets_keep_every_result() {
    let without = sweep(&Settings {
        max_filter_resets: 0,
        ..Settings::default()
    });
    let eager = sweep(&Settings {
        filter_reset_trigger: 1,
        ..Settings::default()
    });
    assert!(
        without
            .iter()
            .all(|(_, _, a)| a.counters.filter_resets == 0)
    );
    assert_same_results(&without, &eager, "with resets");
    let resets: usize = eager.iter().map(|(_, _, b)| b.counters.filter_resets).sum();
    assert!(resets > 0, "no filter reset happened");
}
