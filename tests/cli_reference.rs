//! `docs/cli.md`, the command-line reference, is the text the parser writes
//! (`ball_finger::cli::markdown_reference`): every command and option is documented, with its
//! current help, default and choices. `BF_OVERWRITE_CLI_DOC=1 cargo test --release --test
//! cli_reference` rewrites the file after an intended change of the command line.

use clap::CommandFactory as _;

const PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cli.md");

#[test]
fn the_reference_is_the_parsers_text() {
    let text = ball_finger::cli::markdown_reference();
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
    let text = ball_finger::cli::markdown_reference();
    // `optimize`'s own section: another command's option of the same name is not checked.
    let section = {
        let start = text.find("## `optimize`\n").expect("optimize's section");
        let rest = &text[start + 1..];
        &rest[..rest.find("\n## ").unwrap_or(rest.len())]
    };
    let entry = |option: &str| -> &str {
        let start = section
            .find(&format!("\n- `{option} "))
            .unwrap_or_else(|| panic!("no entry for {option}"));
        let rest = &section[start + 1..];
        &rest[..rest.find('\n').unwrap_or(rest.len())]
    };
    for (option, default) in [
        ("--elements", ball_finger::cli::DEFAULT_ELEMENTS.to_string()),
        (
            "--refine-rounds",
            ball_finger::cli::DEFAULT_REFINE_ROUNDS.to_string(),
        ),
        ("--min-stick", bf_problem::MIN_STICK.to_string()),
        (
            "--cone-margin",
            bf_problem::ProblemSettings::default()
                .cone_margin
                .to_string(),
        ),
    ] {
        assert!(
            entry(option).contains(&format!("[default: {default}]")),
            "{option}: {}",
            entry(option)
        );
    }
}
