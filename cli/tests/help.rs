//! Every subcommand's `--help` and `-h` are plain text: no rustdoc link syntax ("[`Svi`]")
//! leaked from doc comments, and each option states its default at most once.

use crate::common;
use common::*;

/// The subcommands of `svi`, and the top level.
const COMMANDS: [&[&str]; 9] = [
    &[],
    &["run"],
    &["list"],
    &["bench"],
    &["compare"],
    &["stability"],
    &["stress"],
    &["ensemble"],
    &["scale"],
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
        (&["compare"], "--methods"),
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

/// The text between `start` and `end` in the block of `option` of `svi ARGS --help`.
fn stated(args: &[&str], option: &str, start: &str, end: &str) -> String {
    let text = help(args, "--help");
    let block = blocks(&text)
        .into_iter()
        .find(|block| block.trim_start().starts_with(option))
        .unwrap_or_else(|| panic!("svi {args:?}: no {option}:\n{text}"));
    let from = block
        .find(start)
        .unwrap_or_else(|| panic!("svi {args:?} {option}: no '{start}' in\n{block}"))
        + start.len();
    let rest = &block[from..];
    rest[..rest.find(end).unwrap_or(rest.len())]
        .trim()
        .to_string()
}

/// Issue #34, item 8: every default and cap a help text states is what the binary does —
/// read off the help text, then observed in a run (or a rejection one past the cap).
#[test]
fn help_texts_state_the_defaults_and_caps_the_binary_has() {
    // svi run: the diagnostics measured without --diagnostics are exactly those stated.
    let defaults = stated(&["run"], "--diagnostics", "[default: ", "]");
    let summary = json(&["run", "kepler", "--t-end", "1", "--json"]);
    for (diagnostic, field) in [
        ("energy", "energy_error_max"),
        ("momentum", "momentum_error_max"),
        ("solution", "solution_error_max"),
    ] {
        let measured = !summary[field].is_null();
        let listed = defaults.split(',').any(|name| name == diagnostic);
        assert_eq!(
            measured, listed,
            "{diagnostic}: stated {defaults}, {summary}"
        );
    }
    // svi ensemble: its own default, a column measured or empty.
    let defaults = stated(&["ensemble"], "--diagnostics", "[default: ", "]");
    let output = svi(&["ensemble", "kepler", "--param", "e=0.5", "--t-end", "1"]);
    assert!(output.status.success());
    let table = String::from_utf8(output.stdout).unwrap();
    let mut lines = table.lines();
    let columns: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    for (diagnostic, column) in [
        ("energy", "energy_error_max"),
        ("momentum", "momentum_error_max"),
    ] {
        let index = columns.iter().position(|c| *c == column).unwrap();
        let listed = defaults.split(',').any(|name| name == diagnostic);
        assert_eq!(
            !row[index].is_empty(),
            listed,
            "{diagnostic}: stated {defaults}"
        );
    }
    // --tol and --monitor: the defaults a run reports.
    let tol: f64 = stated(&["run"], "--tol", "[default: ", "]")
        .parse()
        .unwrap();
    let adaptive = json(&["run", "kepler", "--t-end", "1", "--adapt", "step", "--json"]);
    assert_eq!(number(&adaptive, "tol"), tol);
    let monitor = stated(&["run"], "--monitor", "[default: ", "]");
    let reparam = json(&[
        "run", "kepler", "--t-end", "1", "--adapt", "reparam", "--json",
    ]);
    assert_eq!(reparam["monitor"], monitor.as_str());
    // --max-steps: the cap is accepted, one more is not, and the cap is the default (a
    // fixed grid of more steps is rejected without the flag).
    let cap: usize = stated(&["run"], "--max-steps", "1 to ", " ")
        .parse()
        .unwrap();
    assert_eq!(
        stated(&["run"], "--max-steps", "[default: ", "]"),
        cap.to_string()
    );
    let beyond = (cap + 1).to_string();
    bad_input(&["run", "--max-steps", &beyond], &[], "--max-steps");
    let (cap_text, h) = (cap.to_string(), (2.0 / cap as f64).to_string());
    let more = format!("more than {:e} steps", cap as f64);
    bad_input(
        &["run", "oscillator", "--t-end", "4", "--h", &h],
        &[],
        &more,
    );
    let summary = json(&["run", "--max-steps", &cap_text, "--t-end", "1", "--json"]);
    assert_eq!(summary["status"], "ok");
    // svi ensemble takes every adaptivity svi run takes.
    for command in ["run", "ensemble"] {
        let short = help(&[command], "-h");
        let line: String = short
            .lines()
            .skip_while(|line| !line.trim_start().starts_with("--adapt"))
            .take(2)
            .collect();
        assert!(
            line.contains("[possible values: none, step, degree, reparam, sem]"),
            "svi {command} -h: {line}"
        );
    }
    // svi scale: each stated cap is accepted by its check, and one more is not.
    use svi_experiments::scale::ScaleArgs;
    let cheap = ScaleArgs {
        sizes: vec![10],
        steps: 1,
        batches: 1,
        min_run: 0.0,
        out_dir: String::new(),
    };
    let size: usize = stated(&["scale"], "--sizes", " to ", " ").parse().unwrap();
    let steps: usize = stated(&["scale"], "--steps", "(1 to ", ")")
        .parse()
        .unwrap();
    let batches: usize = stated(&["scale"], "--batches", "(1 to ", ")")
        .parse()
        .unwrap();
    let min_run: f64 = stated(&["scale"], "--min-run", "(0 to ", ")")
        .parse()
        .unwrap();
    for (at_cap, beyond) in [
        (
            ScaleArgs {
                sizes: vec![size],
                ..cheap.clone()
            },
            ScaleArgs {
                sizes: vec![size + 1],
                ..cheap.clone()
            },
        ),
        (
            ScaleArgs {
                steps,
                ..cheap.clone()
            },
            ScaleArgs {
                steps: steps + 1,
                ..cheap.clone()
            },
        ),
        (
            ScaleArgs {
                batches,
                ..cheap.clone()
            },
            ScaleArgs {
                batches: batches + 1,
                ..cheap.clone()
            },
        ),
        (
            ScaleArgs {
                min_run,
                ..cheap.clone()
            },
            ScaleArgs {
                min_run: min_run * 1.01,
                ..cheap.clone()
            },
        ),
    ] {
        assert!(at_cap.check().is_ok(), "{at_cap:?}: {:?}", at_cap.check());
        assert!(beyond.check().is_err(), "{beyond:?}");
    }
    for bad in ["nan", "-1", "inf"] {
        bad_input(&["scale", "--min-run", bad], &[], "--min-run");
    }
}

/// The models and parameters `svi run --help` states for `--sensitivity` are those the binary
/// differentiates: each stated parameter of each stated model gives its column, and a model
/// not stated is refused.
#[test]
fn sensitivity_help_lists_the_models_the_binary_differentiates() {
    let stated = stated(
        &["run"],
        "--sensitivity",
        "models and their parameters: ",
        ")",
    );
    let stated = stated.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut models = Vec::new();
    for entry in stated.split("; ") {
        let (model, parameters) = entry
            .split_once(": ")
            .unwrap_or_else(|| panic!("'{entry}' is not MODEL: PARAMETERS"));
        for parameter in parameters.split(", ") {
            let args = ["run", model, "--t-end", "0.2", "--sensitivity", parameter];
            let summary = json(&[&args[..], &["--json"]].concat());
            assert_eq!(summary["sensitivity"]["columns"][0], parameter, "{args:?}");
        }
        models.push(model);
    }
    assert_eq!(models, svi_models::PARAMETRIC_MODEL_NAMES);
    bad_input(
        &["run"],
        &["pendulum", "--sensitivity", "q0"],
        "models that do: kepler",
    );
}
