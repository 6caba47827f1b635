//! One re-plan at a lift-off (`track --replan`, paper::replan) by criterion: the transient
//! period from a measured lift-off state back to the optimum's, warm-started primal-dual from
//! the re-plan problem's own solution at the optimum's lift-off state (what every re-plan after
//! the set-up starts from), on the default optima of `periodic-qc` (`optimize --starts 4`,
//! period 0.62 s: budget 62 ms) and `periodic-cot-human` (the default search, period 10 s:
//! budget 1 s). Two states: the optimum's own lift-off state (the re-plan's floor: it is the
//! optimum) and a perturbed one (joint rates ×1.02, ball ω ×0.97). Iterations and status of
//! each case are printed once.
//!
//! Quick run: `cargo bench --bench replan -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::process::Command;

use ball_finger::paper::replan::{REPLAN_MAX_ITER, replan_problem, solve_replan};
use ball_finger::pipeline::{OcpSolution, SolutionIo};
use criterion::{Criterion, criterion_group, criterion_main};

/// The optimum of `optimize --problem NAME ARGS…` run by the command-line program.
fn optimum(problem: &str, args: &[&str]) -> Option<OcpSolution> {
    let dir =
        std::env::temp_dir().join(format!("bf-bench-replan-{problem}-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_ball-finger"))
        .args(["optimize", "--problem", problem, "--out"])
        .arg(&dir)
        .args(args)
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!("{problem}: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    let sol = OcpSolution::read_json(&dir.join("solution.json")).ok();
    std::fs::remove_dir_all(&dir).ok();
    sol
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("replan");
    group.sample_size(10);
    for (problem, args) in [
        ("periodic-qc", &["--starts", "4"][..]),
        ("periodic-cot-human", &[][..]),
    ] {
        let Some(sol) = optimum(problem, args) else {
            continue;
        };
        let Ok((mut p, rotated, x_lo)) = replan_problem(&sol, REPLAN_MAX_ITER) else {
            eprintln!("{problem}: cannot build the re-plan");
            continue;
        };
        let own = match solve_replan(&mut p, &rotated, &x_lo) {
            Ok(s) if s.status.is_success() => s,
            other => {
                eprintln!(
                    "{problem}: the set-up solve failed: {:?}",
                    other.map(|s| s.status)
                );
                continue;
            }
        };
        let mut perturbed = x_lo.clone();
        perturbed[3..6].iter_mut().for_each(|v| *v *= 1.02);
        perturbed[6..9].iter_mut().for_each(|v| *v *= 0.97);
        for (label, x) in [("optimum_state", &x_lo), ("perturbed", &perturbed)] {
            match solve_replan(&mut p, &own, x) {
                Ok(s) => println!(
                    "{problem}/{label}: {:?}, {} iterations, {:.1} ms (period {:.3} s)",
                    s.status,
                    s.iterations,
                    s.solve_seconds * 1e3,
                    sol.period
                ),
                Err(e) => println!("{problem}/{label}: {e}"),
            }
            group.bench_function(format!("{problem}/{label}"), |b| {
                b.iter(|| black_box(solve_replan(&mut p, &own, x).map(|s| s.objective).ok()))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
