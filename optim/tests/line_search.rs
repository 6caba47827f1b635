//! Ipopt's filter reset heuristic on the Hock–Schittkowski suite, each problem with its
//! objective as given and multiplied by 1e8 and 1e12 (`Settings::filter_reset_trigger`,
//! `max_filter_resets`): with and without it every run ends with the same status and optimum,
//! and with a trigger of one blocked line search (instead of Ipopt's five) the resets happen
//! often, so the comparison exercises them.

mod hs;

use bf_optim::ipm::LineSearchSettings;
use bf_optim::ipm::Settings;
use hs::{assert_same_results, sweep_scaled_objectives as sweep};

#[test]
fn filter_resets_keep_every_result() {
    let without = sweep(&Settings {
        line_search: LineSearchSettings {
            max_filter_resets: 0,
            ..Default::default()
        },
        ..Settings::default()
    });
    let eager = sweep(&Settings {
        line_search: LineSearchSettings {
            filter_reset_trigger: 1,
            ..Default::default()
        },
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
