//! The hostile suite, round 3 (issue #34): the surfaces round 2 (`hostile.rs`) did not cover
//! — Lagrangians written as text, `svi ensemble`, `svi scale`, output paths (existing files,
//! planted links, FIFOs, devices, collisions), standard output that cannot be written, and
//! `--json` as one object always.
//!
//! In process, through the parsers and checks the binary uses, nothing may panic; a rejection
//! is a message with no number printed in full; a run that succeeds reports finite numbers or
//! warns. The binary's cases run in a scratch directory with a timeout each ([`HANG`]): they
//! end with status 0, 1 or 2, never a panic; `--json` prints exactly one JSON object whose
//! status agrees with the exit status; a planted link's target, an existing output that a
//! rejected command names, a FIFO and the scene file are never written; no temporary file is
//! left behind.
//!
//! Case counts come from [`cases`] (`SVI_HOSTILE_CASES=K` multiplies them).

use crate::common;
use common::*;

use clap::Parser;
use proptest::prelude::*;
use proptest::sample::select;
use serde_json::Value;
use svi_experiments::ensemble::{Ensemble, EnsembleArgs};
use svi_experiments::scale::{MAX_ESTIMATED_SECONDS, ScaleArgs};
use svi_experiments::{Control, Scene};

use crate::hostile_support;
use hostile_support::*;

// ---- Lagrangians written as text -------------------------------------------------------

/// A token of the text grammar, biased towards the hostile: huge and negative integer
/// powers, numbers at the edge of the floats, every function, names that are not there.
fn token() -> BoxedStrategy<String> {
    prop_oneof![
        4 => select(vec![
            "x", "y", "vx", "vy", "t", "k", "+", "-", "*", "/", "^", "(", ")", "(", ")", ",",
            "0.5*vx^2", "0.5*vy^2", "0.5*(vx^2+vy^2)", "-x^2", "sin(x)", "cos(y)", "exp(x)",
            "ln(x)", "sqrt(x^2+y^2)", "atan2(y,x)", "1/x", "abs(x)", "pi", "e",
        ])
        .prop_map(String::from),
        2 => select(vec![
            "^2147483647", "^-2147483647", "^99999", "^1001", "^1000", "^-1000000", "^4294967297",
            "^1e300", "^0.5", "^-0.5", "1e308", "1e-308", "5e-324", "0", "1e999", "z", "vz",
            "tanh(", "atan2(x)", "log(", "^^", "**",
        ])
        .prop_map(String::from),
        1 => (-3i32..3000).prop_map(|n| format!("^{n}")),
    ]
    .boxed()
}

/// A term of a Lagrangian: mostly a valid one (some with huge powers, singular points,
/// overflowing constants), sometimes a soup of tokens.
fn term() -> BoxedStrategy<String> {
    prop_oneof![
        6 => select(vec![
            "k*x^2", "0.5*(x^2+y^2)", "sin(x)*y", "cos(x-y)", "x^4", "x*y", "exp(x)", "1/x",
            "1/sqrt(x^2+y^2)", "ln(x)", "atan2(y, x)", "x^99999", "y^2147483647", "x^-99999",
            "1e308*x^2", "x^1e300", "tanh(y)^2", "abs(x)", "k*t*x", "vx*y", "vx*vy",
            "sqrt(1 - vx^2 - vy^2)", "exp(vx)", "vx^4",
        ])
        .prop_map(String::from),
        1 => proptest::collection::vec(token(), 1..6).prop_map(|tokens| tokens.concat()),
    ]
    .boxed()
}

/// A text model's scene: a kinetic part (mostly) and terms, one to four coordinates (from a
/// pool with odd and doubled names; mostly x and y), maybe forces and symmetries, an initial
/// state (mostly of the right length), a step and a horizon.
fn text_scene() -> impl Strategy<Value = String> {
    let expression = (
        prop_oneof![
            6 => Just("0.5*(vx^2+vy^2)".to_string()),
            1 => Just("-sqrt(1 - vx^2 - vy^2)".to_string()),
            1 => Just(String::new()),
        ],
        proptest::collection::vec((select(vec![" - ", " + ", " * "]), term()), 1..4),
    )
        .prop_map(|(kinetic, terms)| {
            let mut text = kinetic;
            for (operator, term) in terms {
                text.push_str(operator);
                text.push_str(&term);
            }
            text
        });
    let coordinates = prop_oneof![
        8 => Just(r#"["x", "y"]"#.to_string()),
        1 => Just(r#"["x"]"#.to_string()),
        1 => Just(r#"["x", "y", "z", "w"]"#.to_string()),
        1 => select(vec![r#"["x", "x"]"#, r#"["vx", "x"]"#, r#"["sin"]"#, "[]", r#"["t"]"#])
            .prop_map(String::from),
    ];
    let pair = || {
        prop_oneof![
            4 => proptest::collection::vec(-1.0f64..1.0, 2..3).prop_map(|v| format!("{v:?}")),
            1 => mostly(proptest::collection::vec(-2.0f64..2.0, 0..4).prop_map(|v| format!("{v:?}"))),
        ]
    };
    (
        expression,
        coordinates,
        proptest::option::of(select(vec![
            r#"forces = ["-0.1*vx", "-0.1*vy"]"#,
            r#"forces = ["vx^99999", "0"]"#,
            r#"forces = ["1"]"#,
            r#"symmetries = [["-y", "x"]]"#,
            r#"symmetries = [["1", "0"]]"#,
            r#"symmetries = [["y"]]"#,
        ])),
        mostly((0.0f64..3.0).prop_map(|k| format!("{k:?}"))),
        (pair(), pair()),
        (
            mostly((0.001f64..0.5).prop_map(|h| format!("{h:?}"))),
            mostly((0.0f64..5.0).prop_map(|t| format!("{t:?}"))),
        ),
    )
        .prop_map(
            |(lagrangian, coordinates, extra, k, (q, v), (h, t_end))| {
                let mut text = format!(
                    "lagrangian = \"{lagrangian}\"\ncoordinates = {coordinates}\n"
                );
                if let Some(line) = extra {
                    text.push_str(line);
                    text.push('\n');
                }
                text.push_str(&format!(
                    "[parameters]\nk = {k}\n[initial]\nq = {q}\nv = {v}\n[run]\nh = {h}\nt_end = {t_end}\n"
                ));
                text
            },
        )
}

/// The outcomes of a text scene.
const TEXT_OUTCOMES: [&str; 4] = ["rejected", "failed", "ran", "too long to run here"];

/// Parse a text scene and run it when short: never a panic, a message or finite numbers.
fn text_case(text: &str) -> Result<usize, TestCaseError> {
    let args = [text.to_string()];
    let mut scene = match Scene::from_toml(text, "a hostile text scene") {
        Ok(scene) => scene,
        Err(error) => {
            check_error(&error, &args)?;
            return Ok(0);
        }
    };
    let h = scene.run.h.unwrap_or(0.1);
    let span = scene.run.t_end.unwrap_or(0.0) - scene.initial.t0.unwrap_or(0.0);
    // Long (or NaN-long) runs are skipped: the binary cases run them with a timeout.
    let steps = span / h;
    if steps.is_nan() || steps > 2000.0 {
        return Ok(3);
    }
    scene.run.max_steps = Some(20_000);
    match scene.run(Control::QUIET) {
        Ok(summary) => {
            check_summary(&summary, text)?;
            Ok(2)
        }
        Err(error) => {
            check_error(&error, &args)?;
            Ok(1)
        }
    }
}

#[test]
fn hostile_text_lagrangians_never_panic() {
    let counts = run_counting(
        "text Lagrangians",
        1500,
        &TEXT_OUTCOMES,
        text_scene(),
        |text| text_case(&text),
    );
    assert!(counts[0] > 0 && counts[2] > 0, "{counts:?}");
}

// ---- svi ensemble ------------------------------------------------------------------------

/// `svi ensemble`'s arguments, parsed as the binary parses them.
#[derive(Debug, Parser)]
struct EnsembleCli {
    #[command(flatten)]
    args: EnsembleArgs,
}

/// An axis SPEC: grids, lists, ranges and hostile ones (huge counts, non-numbers, reversed,
/// overflowing).
fn spec() -> BoxedStrategy<String> {
    prop_oneof![
        8 => select(vec![
            "0.1:0.5:3", "0.2,0.4", "0:0.9", "0.3", "0:1:1", "0:0.5:2,0.7", "-3:3:4",
        ])
        .prop_map(String::from),
        2 => select(vec![
            "0:1:0", "0:1:100000000000", "0:1:1000001", "0:0.5:1000000,0:0.5:1000000", "1:0:3",
            "nan", "inf", "-1e308:1e308:3", "1e308:1.7976931348623157e308", "", ",", ":", "::",
            "0:1:2.5", "0:1:-1", "a,b", "0:1:18446744073709551616",
        ])
        .prop_map(String::from),
        1 => (hostile_number(), hostile_number()).prop_map(|(a, b)| format!("{a}:{b}")),
    ]
    .boxed()
}

/// Mostly one of `valid`, sometimes a hostile number.
fn mostly_valid(valid: &[&'static str]) -> BoxedStrategy<String> {
    prop_oneof![
        6 => select(valid.to_vec()).prop_map(String::from),
        1 => hostile_number(),
    ]
    .boxed()
}

/// `svi ensemble` arguments: a scene, axes (the same name twice, a coordinate by name and
/// by index, unknown names), draws, threads and shared run options, hostile numbers among
/// them.
fn ensemble_arguments() -> impl Strategy<Value = Vec<String>> {
    let scene = select(vec![
        "kepler",
        "double-pendulum",
        "pendulum",
        "oscillator",
        "rigid-body",
        "fput",
        "wave",
        "kepler-text",
        "nosuch",
    ]);
    let parameter = (select(vec!["e", "g", "m1", "sigma", "nosuch", "n"]), spec())
        .prop_map(|(name, spec)| vec!["--param".to_string(), format!("{name}={spec}")]);
    let initial = (
        select(vec![
            "q.alpha1", "q.0", "v.alpha2", "p.1", "q.q1", "q.theta", "x.0", "q.9", "q.",
        ]),
        spec(),
    )
        .prop_map(|(name, spec)| vec!["--initial".to_string(), format!("{name}={spec}")]);
    (
        scene,
        proptest::collection::vec(prop_oneof![parameter, initial], 0..3),
        proptest::option::weighted(0.2, mostly_valid(&["3", "5"])),
        flag("--seed", mostly_valid(&["0", "7"])),
        flag("--threads", mostly_valid(&["1", "2"])),
        flag("--h", mostly_valid(&["0.1", "0.05"])),
        flag("--t-end", mostly_valid(&["0.5", "1"])),
        flag("--max-steps", mostly_valid(&["100", "1000"])),
        proptest::option::of(select(vec!["step", "degree", "reparam", "sem", "none"])),
    )
        .prop_map(
            |(scene, axes, random, seed, threads, h, t_end, max_steps, adapt)| {
                let mut all = vec![scene.to_string()];
                all.extend(axes.into_iter().flatten());
                if let Some(count) = random {
                    all.extend(["--random".to_string(), count]);
                }
                for extra in [seed, threads, h, t_end, max_steps] {
                    all.extend(extra);
                }
                if let Some(adapt) = adapt {
                    all.extend(["--adapt".to_string(), adapt.to_string()]);
                }
                all
            },
        )
}

/// The outcomes of an ensemble's arguments.
const ENSEMBLE_OUTCOMES: [&str; 4] = [
    "rejected by clap",
    "rejected by the checks",
    "too many members to run here",
    "ran",
];

/// Parse and expand an ensemble as `svi ensemble` does, and run it when small (each member
/// shortened): never a panic; one outcome per member, in order; a member that is `ok` reports
/// finite numbers.
fn ensemble_case(args: &[String]) -> Result<usize, TestCaseError> {
    let parsed = match EnsembleCli::try_parse_from(
        std::iter::once("ensemble").chain(args.iter().map(String::as_str)),
    ) {
        Ok(parsed) => parsed.args,
        Err(error) => {
            check_message(&error.to_string(), args)?;
            return Ok(0);
        }
    };
    let random = parsed
        .random
        .map(|count| svi_experiments::scene::ensemble::Random {
            count,
            seed: parsed.seed.unwrap_or(0),
        });
    let built = Scene::load(parsed.scene.as_deref().unwrap_or("kepler"))
        .and_then(|scene| Ensemble::new(scene, &parsed.overrides(), parsed.axes(), random));
    let mut ensemble = match built {
        Ok(ensemble) => ensemble,
        Err(error) => {
            check_error(&error, args)?;
            return Ok(1);
        }
    };
    let count = ensemble.members.len();
    prop_assert!((1..=svi_experiments::scene::ensemble::MAX_MEMBERS).contains(&count));
    if count > 8 {
        return Ok(2);
    }
    // Short members: at most 2 time units and a step budget.
    let run = &mut ensemble.scene.run;
    let t0 = ensemble.scene.initial.t0.unwrap_or(0.0);
    if !run.t_end.is_some_and(|t| t - t0 <= 2.0) {
        run.t_end = Some(t0 + 2.0);
    }
    run.max_steps = Some(run.max_steps.map_or(20_000, |steps| steps.min(20_000)));
    let outcomes = match ensemble.run(0..count, 1, &|| {}, None) {
        Ok(outcomes) => outcomes,
        Err(error) => {
            check_error(&error, args)?;
            return Ok(1);
        }
    };
    prop_assert_eq!(outcomes.len(), count);
    for outcome in &outcomes {
        if let Some(error) = &outcome.error {
            prop_assert_ne!(error.kind, "panic", "{:?}: {}", args, error.message);
            check_message(&error.message, args)?;
        } else if let Some(summary) = &outcome.summary {
            check_summary(summary, &format!("{args:?}"))?;
        }
    }
    let table = ensemble.table(0, &outcomes);
    prop_assert_eq!(table.rows.len(), count);
    Ok(3)
}

#[test]
fn hostile_ensembles_never_panic_and_keep_every_member() {
    let counts = run_counting(
        "svi ensemble arguments",
        600,
        &ENSEMBLE_OUTCOMES,
        ensemble_arguments(),
        |args| ensemble_case(&args),
    );
    assert!(counts[1] > 0 && counts[3] > 0, "{counts:?}");
}

// ---- svi scale ---------------------------------------------------------------------------

/// `svi scale`'s arguments, parsed as the binary parses them.
#[derive(Debug, Parser)]
struct ScaleCli {
    #[command(flatten)]
    args: ScaleArgs,
}

/// Hostile `svi scale` arguments; checked (never run): what passes is within every cap and
/// estimated under the hour.
#[test]
fn hostile_numbers_in_svi_scale_are_checked_first() {
    let arguments = (
        flag(
            "--sizes",
            prop_oneof![
                1 => Mode::InProcess.number_or(&["10", "1000", "1000000"]),
                1 => select(vec!["10,20,30", "1000000,1000000", "", ",", "10,,10"])
                    .prop_map(String::from),
            ]
            .boxed(),
        ),
        flag("--steps", Mode::InProcess.number_or(&["1", "1048576"])),
        flag("--batches", Mode::InProcess.number_or(&["1", "100"])),
        flag("--min-run", Mode::InProcess.number_or(&["0", "60", "0.2"])),
    )
        .prop_map(|(a, b, c, d)| [a, b, c, d].concat());
    let counts = run_counting(
        "svi scale arguments",
        1500,
        &["rejected by clap", "rejected by the check", "accepted"],
        arguments,
        |args| {
            let parsed = match ScaleCli::try_parse_from(
                std::iter::once("scale").chain(args.iter().map(String::as_str)),
            ) {
                Ok(parsed) => parsed.args,
                Err(error) => {
                    check_message(&error.to_string(), &args)?;
                    return Ok(0);
                }
            };
            match parsed.check() {
                Err(error) => {
                    check_error(&error, &args)?;
                    Ok(1)
                }
                Ok(()) => {
                    prop_assert!(parsed.min_run.is_finite() && parsed.min_run >= 0.0);
                    prop_assert!(parsed.estimated_seconds() <= MAX_ESTIMATED_SECONDS);
                    Ok(2)
                }
            }
        },
    );
    assert!(counts[1] > 0 && counts[2] > 0, "{counts:?}");
}

// ---- the binary: outputs, standard output, --json ------------------------------------------

/// What sits at an output's name before the command runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Existing {
    /// Nothing.
    Nothing,
    /// A regular file with the text [`PRECIOUS`].
    File,
    /// A symbolic link to the victim file outside the directory.
    Link,
    /// A FIFO.
    Fifo,
    /// A directory.
    Directory,
}

/// The text of every file a case must not lose.
const PRECIOUS: &str = "precious\n";

/// A command of the binary with its outputs: the arguments, with `OUT` and `PLOT` standing
/// for the output names, and whether stdout goes to /dev/full.
#[derive(Debug, Clone)]
struct OutputCase {
    args: Vec<String>,
    out: Existing,
    plot: Existing,
    full_stdout: bool,
}

/// A command that writes files, a second output that may collide with the first, a bad
/// option now and then, and stdout to a full device now and then.
fn output_case() -> impl Strategy<Value = OutputCase> {
    let command = select(vec![
        "run oscillator --t-end 3 --out OUT",
        "run oscillator --t-end 3 --out OUT --plot PLOT",
        "run oscillator --t-end 3 --out OUT --plot OUT",
        "run oscillator --t-end 3 --json --out OUT --plot PLOT",
        "run scene.toml --out OUT",
        "run scene.toml --out scene.toml",
        "run scene.toml --json --out OUT --plot scene.toml",
        "run oscillator --t-end 3 --out OUT --h -1",
        "run oscillator --t-end 3 --json --out OUT --h nan",
        "run oscillator --t-end 3 --out OUT.svg",
        "run oscillator --t-end 3 --out OUT --plot PLOT.png",
        "run fput --param n=16 --t-end 1 --out OUT --plot PLOT",
        "run wave --t-end 0.2 --out OUT --plot PLOT",
        "run nls-soliton --t-end 0.1 --param points=32 --out OUT",
        "ensemble kepler --param e=0.1,0.5 --t-end 1 --out OUT",
        "ensemble kepler --param e=0.1,0.5 --t-end 1 --json --out OUT --plot PLOT.svg",
        "ensemble kepler --param e=0.1,0.5 --t-end 1 --out OUT --plot OUT",
        "ensemble kepler --param e=0.1,0.5 --t-end 1 --json --out OUT --threads nan",
        "ensemble kepler --param e=0.1,0.5 --param g=1 --json --out OUT",
        "stability --samples 20 --out-dir OUT",
        "stability --z 0.5",
        "bench --methods verlet --steps 10 --batches 1 --min-batch 0 --t-end 10 --out-dir OUT",
        "list",
        "run --json --method nosuch",
        "ensemble --json --param e=0:1:1000000000000,0.3",
    ]);
    let existing = select(vec![
        Existing::Nothing,
        Existing::Nothing,
        Existing::Nothing,
        Existing::File,
        Existing::File,
        Existing::Link,
        Existing::Fifo,
        Existing::Directory,
    ]);
    (
        command,
        existing.clone(),
        existing,
        proptest::bool::weighted(0.2),
    )
        .prop_map(|(command, out, plot, full_stdout)| OutputCase {
            args: command.split(' ').map(String::from).collect(),
            out,
            plot,
            full_stdout,
        })
}

/// Put `existing` at `path`, pointing a link at `victim`.
fn plant(path: &std::path::Path, existing: Existing, victim: &std::path::Path) {
    match existing {
        Existing::Nothing => {}
        Existing::File => std::fs::write(path, PRECIOUS).unwrap(),
        Existing::Link => std::os::unix::fs::symlink(victim, path).unwrap(),
        Existing::Fifo => {
            let made = std::process::Command::new("mkfifo").arg(path).status();
            assert!(made.is_ok_and(|status| status.success()), "mkfifo");
        }
        Existing::Directory => std::fs::create_dir(path).unwrap(),
    }
}

/// Run one output case in a fresh directory: the binary ends in time with 0, 1 or 2 and no
/// panic; the victim of a planted link, the scene file and a FIFO are as they were; an
/// existing file is whole (the old text, or a complete new output); no temporary is left;
/// `--json` is one object whose status agrees with the exit status; a full stdout is an
/// error, not a panic.
fn output_run(case: &OutputCase) -> Result<usize, TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let victim_dir = tempfile::tempdir().unwrap();
    let victim = victim_dir.path().join("victim.txt");
    std::fs::write(&victim, PRECIOUS).unwrap();
    let scene = dir.path().join("scene.toml");
    let scene_text = "model = \"oscillator\"\n[run]\nt_end = 3.0\n";
    std::fs::write(&scene, scene_text).unwrap();
    let out = dir.path().join("OUT");
    let plot = dir.path().join("PLOT");
    plant(&out, case.out, &victim);
    let plot_existing = if case.args.iter().any(|arg| arg == "PLOT") {
        plant(&plot, case.plot, &victim);
        case.plot
    } else {
        Existing::Nothing
    };
    let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
    let output = if case.full_stdout {
        svi_to_full_stdout(dir.path(), &args)
    } else {
        svi_within_in(Some(dir.path()), &args, HANG).map_err(TestCaseError::fail)?
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    let code = output.status.code();
    prop_assert!(!stderr.contains("panicked"), "{:?}: {}", case, stderr);
    prop_assert!(
        matches!(code, Some(0..=2)),
        "{:?}: {:?} {}",
        case,
        code,
        stderr
    );
    prop_assert_eq!(
        std::fs::read_to_string(&victim).unwrap(),
        PRECIOUS,
        "{:?}",
        case
    );
    prop_assert_eq!(
        std::fs::read_to_string(&scene).unwrap(),
        scene_text,
        "{:?}",
        case
    );
    for (path, existing) in [(&out, case.out), (&plot, plot_existing)] {
        let kind = std::fs::symlink_metadata(path).map(|m| m.file_type());
        match existing {
            Existing::Fifo => {
                use std::os::unix::fs::FileTypeExt;
                prop_assert!(
                    kind.is_ok_and(|k| k.is_fifo()),
                    "{:?}: a FIFO replaced",
                    case
                );
            }
            Existing::Link => prop_assert!(
                kind.is_ok_and(|k| k.is_symlink()),
                "{:?}: a planted link replaced (it is refused, never written through)",
                case
            ),
            Existing::File if code == Some(2) => prop_assert_eq!(
                std::fs::read_to_string(path).unwrap_or_default(),
                PRECIOUS,
                "{:?}: bad input truncated an existing output",
                case
            ),
            _ => {}
        }
    }
    let leftovers: Vec<String> = walk(dir.path())
        .into_iter()
        .filter(|name| name.contains(".svi-"))
        .collect();
    prop_assert!(leftovers.is_empty(), "{:?}: left {:?}", case, leftovers);
    if case.full_stdout {
        // Every command prints (a summary, a table, regions): a full stdout is an error.
        prop_assert_ne!(code, Some(0), "{:?}: a full stdout went unreported", case);
    } else if args.contains(&"--json") {
        let text = String::from_utf8_lossy(&output.stdout);
        let mut objects = serde_json::Deserializer::from_str(&text).into_iter::<Value>();
        let first = objects.next();
        prop_assert!(objects.next().is_none(), "{:?}: more than one object", case);
        let object = first
            .and_then(Result::ok)
            .ok_or_else(|| TestCaseError::fail(format!("{case:?}: no JSON object: {text}")))?;
        let ok = match args[0] {
            "ensemble" => object["failed"] == 0,
            _ => object["status"] == "ok",
        };
        prop_assert_eq!(ok, code == Some(0), "{:?}: {}", case, object);
    }
    Ok(code.unwrap_or(1) as usize)
}

/// Every file name under `dir`, recursively.
fn walk(dir: &std::path::Path) -> Vec<String> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        names.push(path.display().to_string());
        if entry.file_type().is_ok_and(|kind| kind.is_dir()) {
            names.extend(walk(&path));
        }
    }
    names
}

/// Run the binary in `dir` with stdout on /dev/full (killed after [`HANG`]).
fn svi_to_full_stdout(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_svi"))
        .current_dir(dir)
        .args(args)
        .stdin(std::process::Stdio::null())
        .stdout(full)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("svi starts");
    let start = std::time::Instant::now();
    loop {
        if child.try_wait().ok().flatten().is_some() {
            break;
        }
        if start.elapsed() > HANG {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.wait_with_output().expect("svi ends")
}

#[test]
fn outputs_never_follow_links_clobber_or_block_and_json_is_one_object() {
    let counts = run_counting(
        "output paths, stdout and --json",
        120,
        &["exit 0", "exit 1", "exit 2"],
        output_case(),
        |case| output_run(&case),
    );
    assert!(counts[0] > 0 && counts[2] > 0, "{counts:?}");
}

// ---- scenes with holonomic constraints through the binary ---------------------------------

/// `svi run` of a built-in constrained scene with hostile flags (steps Newton cannot take,
/// non-finite and degenerate parameters, mismatched methods, the options a constrained run
/// refuses, --multipliers with and without a file), always with `--json`.
fn constrained_arguments() -> impl Strategy<Value = Vec<String>> {
    let scene = select(vec![
        "spherical-pendulum",
        "double-pendulum-cartesian",
        "four-bar-linkage",
    ]);
    let flags = proptest::collection::vec(
        select(vec![
            vec!["--h", "100"],
            vec!["--h", "1"],
            vec!["--h", "nan"],
            vec!["--h", "1e-300"],
            vec!["--t-end", "0.5"],
            vec!["--t-end", "1e300"],
            vec!["--param", "l=0"],
            vec!["--param", "l=nan"],
            vec!["--param", "d1=1e300"],
            vec!["--param", "r1=2"],
            vec!["--param", "r2=0.1"],
            vec!["--param", "g=-inf"],
            vec!["--param", "nosuch=1"],
            vec!["--method", "rattle-kahan-li8"],
            vec!["--method", "verlet"],
            vec!["--method", "rattle:3"],
            vec!["--adapt", "step"],
            vec!["--output-times", "0.5"],
            vec!["--diagnostics", "solution"],
            vec!["--diagnostics", "none"],
            vec!["--multipliers"],
            vec!["--multipliers=false"],
            vec!["--multipliers=maybe"],
            vec!["--out", "out.csv"],
            vec!["--every", "7"],
            vec!["--max-steps", "5"],
            vec!["--strict"],
        ]),
        0..4,
    );
    (scene, flags).prop_map(|(scene, flags)| {
        let mut args: Vec<String> = vec!["run".into(), scene.into()];
        args.extend(flags.into_iter().flatten().map(String::from));
        // Short runs: at most a second of simulated time unless the flags say otherwise.
        if !args.iter().any(|arg| arg == "--t-end") {
            args.extend(["--t-end".into(), "1".into()]);
        }
        args.push("--json".into());
        args
    })
}

/// Run the binary on a constrained scene's hostile command line in `dir`: status 0, 1 or 2,
/// no panic, one JSON object whose status agrees with the exit status, finite numbers when
/// it succeeds.
fn constrained_case(dir: &std::path::Path, args: &[String]) -> Result<usize, TestCaseError> {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let output = svi_within_in(Some(dir), &args, HANG).map_err(TestCaseError::fail)?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    let code = output.status.code();
    prop_assert!(!stderr.contains("panicked"), "{:?}: {}", args, stderr);
    prop_assert!(
        matches!(code, Some(0..=2)),
        "{:?}: {:?} {}",
        args,
        code,
        stderr
    );
    let text = String::from_utf8_lossy(&output.stdout);
    prop_assert_eq!(text.lines().count(), 1, "{:?}: {}", args, text);
    let object: Value = serde_json::from_str(&text)
        .map_err(|error| TestCaseError::fail(format!("{args:?}: {error}: {text}")))?;
    prop_assert_eq!(
        object["status"] == "ok",
        code == Some(0),
        "{:?}: {}",
        args,
        object
    );
    if code == Some(0) {
        check_summary_json(&object, &format!("{args:?}"))?;
        prop_assert!(
            object["constraint_error_max"]
                .as_f64()
                .is_some_and(|g| g <= 1e-9)
        );
    }
    if code == Some(1) && object["kind"] == "ode" {
        // A run that failed after it started says why, never a silent status.
        prop_assert!(
            object["error"]["kind"].is_string(),
            "{:?}: {}",
            args,
            object
        );
    }
    Ok(code.unwrap_or(1) as usize)
}

#[test]
fn hostile_flags_on_constrained_scenes_end_in_one_json_object_and_a_status() {
    let dir = Scratch::new("hostile-constrained");
    let counts = run_counting(
        "constrained scenes through the binary",
        60,
        &["exit 0", "exit 1", "exit 2"],
        constrained_arguments(),
        |args| constrained_case(&dir.0, &args),
    );
    assert!(counts[0] > 0 && counts[2] > 0, "{counts:?}");
}
