//! `ball-finger` command-line interface: parses arguments, dispatches to
//! [`ball_finger::commands`], and turns errors into a message on stderr and exit code 1 (2 for
//! a wrong command line: clap's own refusals and the commands'
//! [`ball_finger::errors::UsageError`]s). A closed output pipe
//! (`ball-finger eval … | head -c 10`) ends the program quietly with status 141, the status a
//! shell reports for a Unix tool stopped by SIGPIPE.

use ball_finger::cli::{Cli, Command};
use ball_finger::commands;
use clap::Parser;

/// Exit status of a wrong command line, clap's: for the arguments clap rejects and for the
/// [`ball_finger::errors::UsageError`]s of the commands.
const EXIT_USAGE: i32 = 2;

/// Exit status of a process stopped by SIGPIPE (128 + 13), as shells report it.
const EXIT_BROKEN_PIPE: i32 = 141;

fn main() {
    let cli = Cli::parse();
    if let Some(nodes) = cli.max_graph_nodes {
        bf_codegen::graph::set_node_limit(nodes as usize);
    }
    let result = match cli.command {
        Command::Generate(a) => commands::generate::run(&a),
        Command::Eval(a) => commands::eval::run(&a),
        Command::Bench(a) => commands::bench::run(&a),
        Command::Simulate(a) => commands::simulate::run(&a),
        Command::Optimize(a) => commands::optimize::run(&a),
        Command::Paper(a) => commands::paper::run(&a),
        Command::Report(a) => commands::report::run(&a),
        Command::Verify(a) => commands::verify::run(&a),
        Command::Track(a) => commands::track::run(&a),
    };
    if let Err(e) = result {
        if ball_finger::errors::is_broken_pipe(&e) {
            std::process::exit(EXIT_BROKEN_PIPE);
        }
        let usage = ball_finger::errors::is_usage(&e);
        let hint = if usage {
            "\nFor more information, try '--help'.\n"
        } else {
            ""
        };
        // A failing stderr leaves nothing else to report to; the exit status still says it.
        let _ = std::io::Write::write_all(
            &mut std::io::stderr(),
            format!("error: {}\n{hint}", ball_finger::errors::render(&e)).as_bytes(),
        );
        std::process::exit(if usage { EXIT_USAGE } else { 1 });
    }
}
