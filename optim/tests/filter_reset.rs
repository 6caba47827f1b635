//! Ipopt's filter reset heuristic (`Settings::filter_reset_trigger`, `max_filter_resets`) on
//! the Hock–Schittkowski suite, each problem with its objective as given and multiplied by 1e8
//! and 1e12: with and without the heuristic every run ends with the same status and optimum,
//! and with a trigger of one blocked line search (instead of Ipopt's five) the resets happen
//! often, so the comparison exercises them.

mod hs;

use bf_optim::ipm::{Settings, Solution, solve};
use hs::Transformed;

fn sweep(settings: &Settings) -> Vec<(&'static str, f64, Solution)> {
    let mut out = Vec::new();
    for (i, name) in hs::all().iter().map(|p| p.name).enumerate() {
        for obj in [1.0, 1e8, 1e12] {
            let p = hs::all().into_iter().nth(i).unwrap();
            let t = Transformed {
                obj,
                con: 1.0,
                scaling: None,
                ..Transformed::new(p)
            };
            out.push((name, obj, solve(&t, settings).unwrap()));
        }
    }
    out
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
    let mut resets = 0;
    for ((name, obj, a), (_, _, b)) in without.iter().zip(&eager) {
        assert_eq!(a.counters.filter_resets, 0, "{name} × {obj:e}");
        assert_eq!(b.status, a.status, "{name} × {obj:e}: {b:?}");
        let scale = a.objective.abs().max(*obj);
        assert!(
            (b.objective - a.objective).abs() <= 1e-6 * scale,
            "{name} × {obj:e}: objective {} with resets, {} without",
            b.objective,
            a.objective
        );
        resets += b.counters.filter_resets;
    }
    assert!(resets > 0, "no filter reset happened");
}
