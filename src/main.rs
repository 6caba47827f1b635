//! `ball-finger` command-line interface: parses arguments, dispatches to
//! [`ball_finger::commands`], and turns errors into a message on stderr and exit code 1
//! (2 for usage errors, as clap does).

use ball_finger::cli::{Cli, Command};
use ball_finger::commands;
use clap::Parser;

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Generate(a) => commands::generate::run(&a),
        Command::Eval(a) => commands::eval::run(&a),
        Command::Simulate(a) => commands::simulate::run(&a),
        Command::Optimize(a) => commands::optimize::run(&a),
        Command::Paper(a) => commands::paper::run(&a),
        Command::Report(a) => commands::report::run(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
