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

/// Every long option of every command is named in its command's section (checked on the
/// parser, independently of how the reference is written).
#[test]
fn every_option_of_every_command_is_in_its_section() {
    let text = ball_finger::cli::markdown_reference();
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
        for a in cmd.get_arguments() {
            if let Some(long) = a.get_long()
                && long != "help"
                && !a.is_global_set()
            {
                let named = ["`", ", "].iter().any(|before| {
                    [" ", "`"]
                        .iter()
                        .any(|after| section.contains(&format!("{before}--{long}{after}")))
                });
                assert!(named, "`{path}`: --{long} is not in its section");
                checked += 1;
            }
        }
        walk.extend(
            cmd.get_subcommands()
                .map(|c| (format!("{path} {}", c.get_name()), c.clone())),
        );
    }
    assert!(checked > 100, "only {checked} options checked");
    assert!(
        text.contains("`--max-graph-nodes <NODES>`"),
        "the global option"
    );
}
