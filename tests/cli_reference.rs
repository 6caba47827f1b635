//! `docs/cli.md`, the command-line reference, is the text the parser writes
//! (`markdown_reference` below, from clap's description of `ball_finger::cli::Cli`): every
//! command and option is documented, with its current help, default and choices. `BF_OVERWRITE_CLI_DOC=1 cargo test --release --test
//! cli_reference` rewrites the file after an intended change of the command line.

use clap::CommandFactory as _;

const PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cli.md");

#[test]
fn the_reference_is_the_parsers_text() {
    let text = markdown_reference();
    if std::env::var("BF_OVERWRITE_CLI_DOC").as_deref() == Ok("1") {
        std::fs::write(PATH, &text).unwrap();
    }
    let stored = std::fs::read_to_string(PATH).unwrap_or_default();
    assert!(
        stored == text,
        "docs/cli.md differs from the command line's own text; if the change is intended, \
         rerun with BF_OVERWRITE_CLI_DOC=1"
    );
}

/// Every option and positional argument of every command has an entry line of its own in its
/// command's section (a line `- \`--name …\``, `- \`-x, --name …\`` or `- \`<NAME>…\``),
/// checked on the parser, independently of how the reference is written: a mention in another
/// option's help does not count.
#[test]
fn every_option_of_every_command_has_its_entry() {
    let text = std::fs::read_to_string(PATH).unwrap_or_default();
    let cli = ball_finger::cli::Cli::command();
    let mut checked = 0;
    let mut walk: Vec<(String, clap::Command)> = cli
        .get_subcommands()
        .map(|c| (c.get_name().to_string(), c.clone()))
        .collect();
    while let Some((path, cmd)) = walk.pop() {
        if path == "help" {
            continue;
        }
        let heading = format!("## `{path}`\n");
        let start = text
            .find(&heading)
            .unwrap_or_else(|| panic!("no section for `{path}`"));
        let rest = &text[start + heading.len()..];
        let section = &rest[..rest.find("\n## ").unwrap_or(rest.len())];
        let entries: Vec<&str> = section
            .lines()
            .filter_map(|l| l.strip_prefix("- `"))
            .collect();
        for a in cmd.get_arguments().filter(|a| !a.is_global_set()) {
            let has = |head: &str| {
                entries.iter().any(|e| {
                    e.strip_prefix(head)
                        .is_some_and(|r| r.starts_with([' ', '`', '.']))
                })
            };
            let found = match (a.get_long(), a.get_short()) {
                (Some("help"), _) => continue,
                (Some(long), Some(short)) => has(&format!("-{short}, --{long}")),
                (Some(long), None) => has(&format!("--{long}")),
                (None, _) => {
                    let name = a
                        .get_value_names()
                        .and_then(|v| v.first().map(ToString::to_string))
                        .unwrap_or_else(|| a.get_id().as_str().to_uppercase());
                    has(&format!("<{name}>"))
                }
            };
            assert!(found, "`{path}`: {} has no entry line", a.get_id());
            checked += 1;
        }
        walk.extend(
            cmd.get_subcommands()
                .map(|c| (format!("{path} {}", c.get_name()), c.clone())),
        );
    }
    assert!(checked > 100, "only {checked} arguments checked");
    assert!(
        text.contains("\n- `--max-graph-nodes <NODES>`"),
        "the global option"
    );
    assert!(text.contains("\n- `-V, --version`"), "the version flag");
}

/// The options whose default is stated in their help (they are `Option`s, so that a value
/// given equal to the default still counts as given) state the value the program uses.
#[test]
fn stated_defaults_are_the_programs() {
    let text = markdown_reference();
    // A command's own section: another command's option of the same name is not checked.
    let section = |command: &str| -> &str {
        let start = text
            .find(&format!("## `{command}`\n"))
            .unwrap_or_else(|| panic!("{command}'s section"));
        let rest = &text[start + 1..];
        &rest[..rest.find("\n## ").unwrap_or(rest.len())]
    };
    let entry = |command: &str, option: &str| -> &str {
        let section = section(command);
        let start = section
            .find(&format!("\n- `{option} "))
            .unwrap_or_else(|| panic!("no entry for {command} {option}"));
        let rest = &section[start + 1..];
        &rest[..rest.find('\n').unwrap_or(rest.len())]
    };
    for (command, option, default) in [
        (
            "optimize",
            "--elements",
            ball_finger::cli::DEFAULT_ELEMENTS.to_string(),
        ),
        (
            "optimize",
            "--refine-rounds",
            ball_finger::cli::DEFAULT_REFINE_ROUNDS.to_string(),
        ),
        ("optimize", "--min-stick", bf_problem::MIN_STICK.to_string()),
        (
            "optimize",
            "--cone-margin",
            bf_problem::ProblemSettings::default()
                .cone_margin
                .to_string(),
        ),
        (
            "simulate",
            "--rtol",
            format!("{:e}", ball_finger::cli::DEFAULT_RTOL),
        ),
        (
            "simulate",
            "--step",
            ball_finger::cli::DEFAULT_STEP.to_string(),
        ),
        (
            "simulate",
            "--h-max",
            ball_finger::cli::DEFAULT_H_MAX.to_string(),
        ),
        (
            "simulate",
            "--impact-law",
            ball_finger::cli::DEFAULT_IMPACT_LAW.to_string(),
        ),
        (
            "simulate",
            "--mode0",
            ball_finger::cli::DEFAULT_MODE0.to_string(),
        ),
    ] {
        let entry = entry(command, option);
        assert!(
            entry.contains(&format!("[default: {default}]"))
                || entry.contains(&format!("[default: {default};")),
            "{command} {option}: {entry}"
        );
    }
}

/// The command-line reference, `docs/cli.md`, written from the parser itself: every command,
/// its usage and every option with its help, default and choices. A test holds the file equal
/// to this text, so an option cannot be added, renamed or reworded without its reference.
fn markdown_reference() -> String {
    use std::fmt::Write as _;
    let mut cli = ball_finger::cli::Cli::command();
    cli.build();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Command-line reference\n\n\
         Written from the program's own argument parser (`cargo test --release --test \
         cli_reference` checks that this file is current; `BF_OVERWRITE_CLI_DOC=1` with the same \
         command rewrites it). The same text, with line breaks, is each command's `--help`. \
         Exit statuses: 0 success, 1 a failed or unverified run or a refused input, 2 a wrong \
         command line (README, \"Commands\").\n"
    );
    let global: Vec<&clap::Arg> = cli.get_arguments().filter(|a| a.is_global_set()).collect();
    if !global.is_empty() {
        let _ = writeln!(out, "## Options of every command\n");
        for a in &global {
            arg_entry(&mut out, a);
        }
        out.push('\n');
    }
    let own: Vec<&clap::Arg> = cli
        .get_arguments()
        .filter(|a| !a.is_global_set() && a.get_id() != "help")
        .collect();
    if !own.is_empty() {
        let _ = writeln!(out, "## `ball-finger` without a command\n");
        for a in &own {
            arg_entry(&mut out, a);
        }
        out.push('\n');
    }
    for sub in cli.get_subcommands() {
        command_section(&mut out, sub, &["ball-finger"]);
    }
    out
}

fn command_section(out: &mut String, cmd: &clap::Command, parents: &[&str]) {
    use std::fmt::Write as _;
    if cmd.is_hide_set() || cmd.get_name() == "help" {
        return;
    }
    let mut path = parents.to_vec();
    path.push(cmd.get_name());
    let _ = writeln!(out, "## `{}`\n", path[1..].join(" "));
    if let Some(about) = cmd.get_long_about().or(cmd.get_about()) {
        let _ = writeln!(out, "{}\n", paragraphs(&about.to_string(), "\n\n"));
    }
    let usage = cmd
        .clone()
        .bin_name(path.join(" "))
        .render_usage()
        .to_string();
    let usage = usage.trim_start_matches("Usage:").trim();
    let _ = writeln!(out, "```text\n{usage}\n```\n");
    let args: Vec<&clap::Arg> = cmd
        .get_arguments()
        .filter(|a| !a.is_hide_set() && !a.is_global_set() && a.get_id() != "help")
        .collect();
    for a in &args {
        arg_entry(out, a);
    }
    if !args.is_empty() {
        out.push('\n');
    }
    for sub in cmd.get_subcommands() {
        command_section(out, sub, &path);
    }
}

fn arg_entry(out: &mut String, a: &clap::Arg) {
    use std::fmt::Write as _;
    let values: Vec<String> = a
        .get_value_names()
        .map(|v| v.iter().map(|n| format!("<{n}>")).collect())
        .unwrap_or_default();
    let takes_value = a.get_action().takes_values();
    // A value that may repeat (`<DIRS>...`) is shown as clap's usage shows it.
    let repeats = a.get_num_args().is_some_and(|n| n.max_values() > 1);
    let values: Vec<String> = match (repeats, values.split_last()) {
        (true, Some((last, rest))) => rest.iter().cloned().chain([format!("{last}...")]).collect(),
        _ => values,
    };
    let name = match (a.get_long(), a.get_short()) {
        (Some(l), Some(s)) => format!("-{s}, --{l}"),
        (Some(l), None) => format!("--{l}"),
        (None, Some(s)) => format!("-{s}"),
        (None, None) => String::new(),
    };
    let label = match (name.is_empty(), takes_value) {
        (true, _) => values.join(" "),
        (false, true) if !values.is_empty() => format!("{name} {}", values.join(" ")),
        (false, true) => format!("{name} <{}>", a.get_id().as_str().to_uppercase()),
        (false, false) => name,
    };
    let help = a
        .get_long_help()
        .or(a.get_help())
        .map(|h| paragraphs(&h.to_string(), " "))
        .unwrap_or_default();
    let mut extra = Vec::new();
    // A float default as clap prints it (`0.00000001`) reads better as the help writes it.
    let defaults: Vec<String> = a
        .get_default_values()
        .iter()
        .map(|v| {
            let text = v.to_string_lossy();
            match text.parse::<f64>() {
                Ok(x) if text.contains('.') => ball_finger::cli::shown(x),
                _ => text.into_owned(),
            }
        })
        .collect();
    if takes_value && !defaults.is_empty() && !help.contains("[default:") {
        extra.push(format!("default: `{}`", defaults.join(",")));
    }
    let choices: Vec<String> = a
        .get_possible_values()
        .iter()
        .filter(|p| !p.is_hide_set())
        .map(|p| format!("`{}`", p.get_name()))
        .collect();
    if takes_value && !choices.is_empty() {
        extra.push(format!("one of {}", choices.join(", ")));
    }
    if a.is_required_set() {
        extra.push("required".to_string());
    }
    let extra = if extra.is_empty() {
        String::new()
    } else {
        format!(" ({})", extra.join("; "))
    };
    let _ = writeln!(out, "- `{label}`: {help}{extra}");
}

/// A help text with the lines of each paragraph joined, the paragraphs joined by `between`
/// (a blank line for a command's text, a space inside a list item).
fn paragraphs(text: &str, between: &str) -> String {
    text.trim()
        .split("\n\n")
        .map(|p| p.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect::<Vec<_>>()
        .join(between)
}
