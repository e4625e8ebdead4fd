//! Every subcommand's `--help` and `-h` are plain text: no rustdoc link syntax ("[`Svi`]")
//! leaked from doc comments, and each option states its default at most once.

mod common;
use common::*;

/// The subcommands of `svi`, and the top level.
const COMMANDS: [&[&str]; 6] = [
    &[],
    &["run"],
    &["list"],
    &["bench"],
    &["stability"],
    &["stress"],
];

/// The help text of `svi ARGS FLAG`.
fn help(args: &[&str], flag: &str) -> String {
    let mut all = args.to_vec();
    all.push(flag);
    let output = svi(&all);
    assert!(output.status.success(), "svi {all:?}");
    String::from_utf8(output.stdout).unwrap()
}

/// The help text split into one block per option or argument (a block starts at a line
/// that begins, after indentation, with `-` or `[`/`<` of a positional argument).
fn blocks(text: &str) -> Vec<String> {
    let mut blocks: Vec<String> = Vec::new();
    for line in text.lines() {
        let trimmed = line.trim_start();
        let starts = line.starts_with("  ")
            && !line.starts_with("        ")
            && (trimmed.starts_with('-') || trimmed.starts_with('[') || trimmed.starts_with('<'));
        if starts || blocks.is_empty() {
            blocks.push(String::new());
        }
        if let Some(block) = blocks.last_mut() {
            block.push_str(line);
            block.push('\n');
        }
    }
    blocks
}

#[test]
fn help_texts_have_no_rustdoc_links_and_no_doubled_defaults() {
    for args in COMMANDS {
        for flag in ["--help", "-h"] {
            let text = help(args, flag);
            assert!(!text.contains("[`"), "svi {args:?} {flag}:\n{text}");
            assert!(!text.contains("`]"), "svi {args:?} {flag}:\n{text}");
            for block in blocks(&text) {
                assert!(
                    block.matches("[default:").count() <= 1,
                    "svi {args:?} {flag}, doubled default:\n{block}"
                );
            }
        }
    }
}

#[test]
fn every_method_option_lists_the_registry() {
    for (args, option) in [
        (&["run"][..], "--method"),
        (&["stability"], "--method"),
        (&["bench"], "--methods"),
        (&["stress"], "--methods"),
    ] {
        let text = help(args, "--help");
        let block = blocks(&text)
            .into_iter()
            .find(|block| block.trim_start().starts_with(option))
            .unwrap_or_else(|| panic!("svi {args:?}: no {option}:\n{text}"));
        for entry in svi::method::registry::METHODS {
            assert!(
                block.contains(&entry.grammar()) && block.contains(entry.summary),
                "svi {args:?} {option}: {} missing:\n{block}",
                entry.name
            );
        }
    }
    // The stability default is stated once, by clap.
    let text = help(&["stability"], "--help");
    assert_eq!(text.matches("[default: svi:5/4]").count(), 1, "{text}");
}
