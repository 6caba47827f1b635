//! Watching the solver work: any problem of the Hock–Schittkowski suite that the solver is
//! tested on (`optim/tests/hs/`, transcribed from Hock & Schittkowski 1981 with the published
//! starting points and optima), solved with the iteration log printed.
//!
//! The log has one line per interior-point iteration, in Ipopt's columns: the objective, the
//! primal and dual infeasibilities, log₁₀ μ, the step's norm, log₁₀ of the Hessian
//! regularization δ_w that the inertia correction needed, the two step lengths and the line
//! search's trials; an `r` after the count marks a restoration iteration. Print level 2 adds
//! the restoration phase's details, 3 the inertia corrections and rejected steps. Reading it
//! on a small problem is the quickest way to see what each part of `ipm::core` does; HS013,
//! whose optimum fails the constraint qualification, is the suite's hard case.
//!
//! Run it: `cargo run --release -p bf-optim --example hs_log -- HS013`; `--adaptive` selects
//! the adaptive barrier update (default: monotone), `--print-level N` the detail (default 2).
//! Without a name it solves HS071; an unknown name lists the problems there are.

#[path = "../tests/hs/mod.rs"]
mod hs;

use bf_optim::ipm::{BarrierSettings, MuStrategy, OutputSettings, Settings, Solution, solve};

/// Solves the suite's problem `name` with the barrier update `mu_strategy` and the log detail
/// `print_level`; the problem's published optimum f* and the solution, or a message naming
/// the problem that does not exist (or the solver's error).
pub fn run(
    name: &str,
    mu_strategy: MuStrategy,
    print_level: u8,
) -> Result<(f64, Solution), String> {
    let problems = hs::all();
    let Some(p) = problems.iter().find(|p| p.name.eq_ignore_ascii_case(name)) else {
        let names: Vec<&str> = problems.iter().map(|p| p.name).collect();
        return Err(format!(
            "no Hock–Schittkowski problem named {name:?}; there are: {}",
            names.join(" ")
        ));
    };
    let settings = Settings {
        output: OutputSettings { print_level },
        barrier: BarrierSettings {
            mu_strategy,
            ..Default::default()
        },
        ..Settings::default()
    };
    let sol = solve(p, &settings).map_err(|e| format!("{}: {e}", p.name))?;
    Ok((p.fstar, sol))
}

/// The command line: `[NAME] [--adaptive] [--print-level N]`.
#[allow(dead_code)] // unused where `tests/examples.rs` includes this file as a module
fn main() -> std::process::ExitCode {
    let mut name = "HS071".to_string();
    let mut strategy = MuStrategy::Monotone;
    let mut print_level = 2u8;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--adaptive" => strategy = MuStrategy::Adaptive,
            "--print-level" => match args.next().map(|v| v.parse::<u8>()) {
                Some(Ok(level)) => print_level = level,
                _ => {
                    eprintln!("error: --print-level takes a number 0–255");
                    return std::process::ExitCode::from(2);
                }
            },
            "-h" | "--help" => {
                println!("usage: hs_log [NAME] [--adaptive] [--print-level N]");
                return std::process::ExitCode::SUCCESS;
            }
            other if other.starts_with('-') => {
                eprintln!(
                    "error: unknown option {other}; usage: hs_log [NAME] [--adaptive] [--print-level N]"
                );
                return std::process::ExitCode::from(2);
            }
            other => name = other.to_string(),
        }
    }
    match run(&name, strategy, print_level) {
        Ok((fstar, sol)) => {
            println!(
                "{name}: {:?} after {} iterations, f = {:.10e} (published f* = {fstar:.10e}), x = {:?}",
                sol.status, sol.iterations, sol.objective, sol.x
            );
            if sol.status.is_success() {
                std::process::ExitCode::SUCCESS
            } else {
                std::process::ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
