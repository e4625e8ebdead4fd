//! Limits, messages and ignored options on the command line (issue #14): no input makes
//! `svi` read, run or allocate without bound (item 2), a message says what is wrong with the
//! value the user gave and names the option (item 8), and no option is accepted and then
//! ignored (item 10). Each test names the item it checks; each failed before the fix.

use crate::common;
use common::*;

use svi_experiments::scene::limits::{
    MAX_BATCH_SECONDS, MAX_BATCHES, MAX_BISECTIONS, MAX_DRIFT_STEPS, MAX_RUN_SECONDS, MAX_SAMPLES,
    MAX_SCENE_BYTES, MAX_STEPS, MIN_PEER_TOLERANCE,
};

/// Issue #14, item 2: `svi run /dev/urandom` read without bound (1.6 GB in 6 s). A scene is
/// read only from a regular file of at most 1 MiB; anything else is an error naming it.
#[test]
fn scene_files_are_read_only_from_small_regular_files() {
    let dir = Scratch::new("limits-files");
    let huge = dir.join("huge.toml");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(MAX_SCENE_BYTES + 1)
        .unwrap();
    let fifo = dir.join("fifo.toml");
    let fifo_made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|status| status.success());
    let mut cases = vec![
        ("/dev/urandom".to_string(), "it is a character device"),
        ("/dev/zero".to_string(), "it is a character device"),
        (dir.0.display().to_string(), "it is a directory"),
        (
            huge.display().to_string(),
            "it is larger than 1048576 bytes (1 MiB)",
        ),
    ];
    if fifo_made {
        cases.push((fifo.display().to_string(), "it is a FIFO"));
    }
    for (path, needle) in &cases {
        for command in [&["run"][..], &["bench"]] {
            let stderr = bad_input(command, &[path], needle);
            assert!(
                stderr.contains(&format!("'{path}' is not a scene file")),
                "{stderr}"
            );
        }
    }
}

/// Issue #14, item 2: `svi bench --min-batch nan` and `inf` never ended, `svi stability
/// --samples 1e9` grew memory without bound, step counts were not capped. Every time budget
/// and count is checked against its cap before anything runs.
#[test]
fn time_budgets_and_counts_are_checked_before_anything_runs() {
    let dir = Scratch::new("limits-budgets");
    let out = dir.0.to_str().unwrap();
    let too_many_samples = (MAX_SAMPLES + 1).to_string();
    let too_many_steps = (MAX_STEPS + 1).to_string();
    let too_many_drift_steps = (MAX_DRIFT_STEPS + 1).to_string();
    let too_many_batches = (MAX_BATCHES + 1).to_string();
    let too_many_bisections = (MAX_BISECTIONS + 1).to_string();
    let too_long_batch = (MAX_BATCH_SECONDS + 1.0).to_string();
    let too_long_run = (MAX_RUN_SECONDS + 1.0).to_string();
    for (args, needle) in [
        (
            &["bench", "--min-batch", "nan"][..],
            "invalid --min-batch: NaN s",
        ),
        (
            &["bench", "--min-batch", "inf"],
            "invalid --min-batch: inf s",
        ),
        (&["bench", "--min-batch", "-1"], "invalid --min-batch: -1 s"),
        (&["bench", "--min-batch", &too_long_batch], "at most 60 s"),
        (&["bench", "--max-run", "inf"], "invalid --max-run: inf s"),
        (&["bench", "--max-run", "0"], "above 0 s, at most 3600 s"),
        (&["bench", "--max-run", &too_long_run], "invalid --max-run"),
        (
            &["bench", "--batches", &too_many_batches],
            "invalid --batches: 101 timing batches; need 1 to 100",
        ),
        (
            &["bench", "--steps", &too_many_steps],
            "invalid --steps: 100000001 steps; need 1 to 100000000",
        ),
        (
            &["stability", "--samples", &too_many_samples],
            "invalid --samples: 100001 grid points; need 2 to 100000",
        ),
        (
            &["stress", "--steps", &too_many_drift_steps],
            "invalid --steps: 10000001 steps; need 200 to 10000000",
        ),
        (
            &["stress", "--bisections", &too_many_bisections],
            "invalid --bisections: 51 bisections; need 0 to 50",
        ),
        // DOP853 at a tolerance of 1e-300 took steps until memory ran out (24 GB).
        (
            &["stress", "--methods", "dop853", "--tolerance", "1e-300"],
            "invalid --tolerance: 1e-300; need a finite tolerance of at least 1e-20",
        ),
        (
            &["bench", "--methods", "dop853", "--tolerances", "1e-8,1e-21"],
            "invalid --tolerances: 1e-21; need a finite tolerance of at least 1e-20",
        ),
    ] {
        bad_input(args, &["--out-dir", out], needle);
    }
}

/// Issue #14, item 2: every cap is stated once (`svi_experiments::scene::limits`), in the option's
/// help and in the guide's chapter "Limits" (`docs/guide/src/limits.md`).
#[test]
fn every_cap_is_in_the_help_and_the_guide() {
    let help = |command: &str| String::from_utf8(svi(&[command, "--help"]).stdout).unwrap();
    for (command, text) in [
        ("stability", format!("2 to {MAX_SAMPLES}")),
        ("bench", format!("1 to {MAX_BATCHES}")),
        ("bench", format!("at most {MAX_BATCH_SECONDS}")),
        ("bench", format!("at most {MAX_RUN_SECONDS}")),
        ("bench", format!("1 to {MAX_STEPS}")),
        ("stress", format!("200 to {MAX_DRIFT_STEPS}")),
        ("stress", format!("0 to {MAX_BISECTIONS}")),
        ("stress", format!("at least {MIN_PEER_TOLERANCE:e}")),
        ("bench", format!("at least {MIN_PEER_TOLERANCE:e}")),
    ] {
        assert!(
            help(command).contains(&text),
            "svi {command} --help: {text}"
        );
    }
    let limits = include_str!("../../docs/guide/src/limits.md")
        .strip_prefix("# Limits\n")
        .expect("the guide's chapter on limits");
    for cap in [
        "1 MiB",
        "10⁵ grid points",
        "100 timing batches",
        "60 s",
        "3600 s",
        "10⁸ steps",
        "10⁷ steps",
        "50 bisections",
        "1e-20",
    ] {
        assert!(limits.contains(cap), "the guide's Limits: {cap}\n{limits}");
    }
}

/// Issue #14, item 8: misleading messages. Each says what is wrong with the value given, in
/// the option's name, with numbers short enough to read.
#[test]
fn messages_say_what_is_wrong_and_name_the_option() {
    let dir = Scratch::new("limits-messages");
    let out = dir.0.to_str().unwrap();
    // The stress cases are their own list, not "no scene 'kepler'".
    let stderr = bad_input(
        &["stress", "--cases", "kepler"],
        &["--out-dir", out],
        "'kepler' is not a stress case of svi stress (stress cases: oscillator, kepler-long,",
    );
    assert!(!stderr.contains("no built-in scene"), "{stderr}");
    // The bench horizon is checked first, naming --t-end (not the exact solution, h or a
    // non-finite state).
    for (t_end, needle) in [
        ("nan", "invalid --t-end (run.t_end): NaN is not finite"),
        (
            "0",
            "invalid --t-end (run.t_end): the horizon 0.0 is not after the start 0.0",
        ),
        ("-1", "invalid --t-end (run.t_end): the horizon -1.0"),
        (
            "1e300",
            "invalid --t-end (run.t_end): the span from 0 to 1e300 needs more than 100000000 \
             steps of the model's step 0.2",
        ),
    ] {
        bad_input(&["bench", "--t-end", t_end], &["--out-dir", out], needle);
    }
    // Kepler started at the origin: its force and momentum are singular there.
    let origin = scene_file("origin", "model = \"kepler\"\n[initial]\nq = [0.0, 0.0]\n");
    let stderr = failure(&["run", &origin.path]);
    assert!(
        stderr.contains("non-finite momentum ∂L/∂q̇ of the model from the given initial state"),
        "{stderr}"
    );
    // Negative numbers are values, and the error is about the value.
    for (args, needle) in [
        (
            &["run", "--points", "-1"][..],
            "invalid value '-1' for '--points <N>'",
        ),
        (
            &["run", "--quadrature", "-2"],
            "invalid value '-2' for '--quadrature",
        ),
        (&["run", "--every", "-1"], "invalid value '-1' for '--every"),
        (
            &["run", "--divergence-limit", "-1"],
            "invalid divergence_limit: -1.0 must be positive",
        ),
        (
            &["bench", "--batches", "-1"],
            "invalid value '-1' for '--batches",
        ),
        (
            &["bench", "--steps", "-10"],
            "invalid value '-10' for '--steps",
        ),
        (&["bench", "--target", "-1"], "invalid --target: -1"),
        (
            &["stability", "--samples", "-1"],
            "invalid value '-1' for '--samples",
        ),
        (
            &["stability", "--z-max", "-1"],
            "invalid z_max: -1.0 must be positive",
        ),
        (
            &["stress", "--steps", "-1"],
            "invalid value '-1' for '--steps",
        ),
        (
            &["stress", "--bisections", "-1"],
            "invalid value '-1' for '--bisections",
        ),
        (&["stress", "--tolerance", "-1"], "invalid --tolerance: -1"),
    ] {
        let stderr = bad_input(args, &[], needle);
        assert!(!stderr.contains("unexpected argument"), "{stderr}");
    }
    // Numbers print short: 1e300, never 300 digits.
    for (args, needle) in [
        (
            &["run", "kepler", "--param", "e=1e300"][..],
            "invalid e: 1e300",
        ),
        (
            &["run", "kepler", "--param", "e=-1e-300"],
            "invalid e: -1e-300",
        ),
        (
            &["run", "kepler", "--output-times", "0.5,1e300"],
            "time 1e300 (entry 1)",
        ),
        (&["run", "kepler", "--h", "-1e300"], "invalid h: -1e300"),
        (
            &["run", "kepler", "--divergence-limit", "-1e-300"],
            "-1e-300",
        ),
        (&["stability", "--z", "-1e300"], "-1e300"),
    ] {
        let stderr = bad_input(args, &[], needle);
        assert!(!has_long_number(&stderr), "{stderr}");
    }
    let output = svi(&[
        "stability",
        "--z-max",
        "1e300",
        "--samples",
        "3",
        "--out-dir",
        out,
    ]);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(!has_long_number(&text), "{text}");
    // Lists of scenes and models include the rigid bodies.
    let unknown = scene_file("unknown-model", "model = \"top\"\n");
    bad_input(
        &["run", &unknown.path],
        &[],
        "rigid bodies: rigid-body, heavy-top, pendulum-3d",
    );
    bad_input(
        &["bench", "rigid-body"],
        &["--out-dir", out],
        "'rigid-body' is a rigid body on SO(3)",
    );
}

/// Issue #14, item 10: options accepted and then ignored. Each is an error (exit status 2)
/// that names it.
#[test]
fn options_that_would_be_ignored_are_errors() {
    let dir = Scratch::new("limits-ignored");
    let out = dir.0.to_str().unwrap();
    for (args, needle) in [
        (
            &["stability", "--figures", "--method", "svi:3"][..],
            "'--figures' cannot be used with '--method <METHOD>'",
        ),
        (
            &["stability", "--figures", "--z", "1"],
            "'--figures' cannot be used with '--z <Z>'",
        ),
        (
            &["stability", "--z", "1", "--samples", "5"],
            "'--z <Z>' cannot be used with '--samples <SAMPLES>'",
        ),
        (
            &["stability", "--z", "1", "--z-max", "5"],
            "'--z <Z>' cannot be used with '--z-max <Z_MAX>'",
        ),
        (
            &["stability", "--z", "1", "--out-dir", out],
            "'--z <Z>' cannot be used with '--out-dir <OUT_DIR>'",
        ),
        (&["bench", "--batches", "0"], "invalid --batches: 0"),
        (&["bench", "--target", "nan"], "invalid --target: NaN"),
        (&["bench", "--max-run", "nan"], "invalid --max-run: NaN"),
        (
            &["bench", "--methods", ","],
            "invalid --methods: no method given",
        ),
        (
            &["bench", "--methods", "svi:3/2", "--tolerances", "1e-8"],
            "--tolerances: sets the tolerances of dop853, dopri5 and radau5",
        ),
        (
            &["bench", "--methods", "dop853", "--steps", "10"],
            "--steps: sets the step counts of the library's methods",
        ),
        (
            &[
                "bench",
                "--methods",
                "svi:3/2",
                "--steps",
                "10",
                "--target",
                "1e-3",
            ],
            "--target: ends a sweep",
        ),
        (
            &[
                "bench",
                "--methods",
                "dop853",
                "--tolerances",
                "1e-8",
                "--max-run",
                "1",
            ],
            "--max-run: ends a sweep",
        ),
        (
            &["stress", "--methods", "dop853", "--bisections", "3"],
            "--bisections: refines the step limits",
        ),
        (
            &["stress", "--methods", "svi:6", "--tolerance", "1e-8"],
            "--tolerance: sets the tolerance of dop853 and METHOD@step",
        ),
        (
            &["run", "pendulum", "--diagnostics", "momentum"],
            "--diagnostics momentum (output.diagnostics): the model 'pendulum' has no symmetry",
        ),
        (
            &["run", "double-pendulum", "--diagnostics", "energy,solution"],
            "--diagnostics solution (output.diagnostics): the model 'double-pendulum' has no \
             exact solution",
        ),
    ] {
        let mut all = args.to_vec();
        if !args.contains(&"--out-dir") && args[0] != "run" && !args.contains(&"--z") {
            all.extend(["--out-dir", out]);
        }
        bad_input(&all, &[], needle);
    }
    // Where they apply, the same options run.
    let output = svi(&[
        "bench",
        "oscillator",
        "--methods",
        "svi:3/2,dop853",
        "--steps",
        "10",
        "--tolerances",
        "1e-6",
        "--batches",
        "1",
        "--min-batch",
        "0",
        "--t-end",
        "5",
        "--out-dir",
        out,
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// An adaptive run had no step budget: `svi run double-pendulum --param g=2897664167324477573
/// --adapt step --tol 1e-9` (a fuzzed case: the pendulum's period is 10⁻⁹) ran for hours.
/// `--max-steps` (`run.max_steps`, default and cap 10⁹) ends it with `too_many_steps` and the
/// run so far (exit status 1); a fixed grid that needs more is rejected before it starts.
#[test]
fn a_run_takes_at_most_its_step_budget() {
    let args = [
        "run",
        "double-pendulum",
        "--param",
        "g=2897664167324477573",
        "--adapt",
        "step",
        "--tol",
        "1e-9",
        "--max-steps",
        "3000",
        "--json",
    ];
    let output = svi_within(&args, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    assert_eq!(output.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["status"], "failed");
    assert_eq!(report["error"]["kind"], "too_many_steps");
    assert_eq!(report["error"]["step"], 3000);
    let t = number(&report["error"], "t");
    assert!(t > 0.0 && t < 1e-3, "stopped at t = {t}");
    // A fixed grid of 1000 steps against budgets of 999 and 1000.
    let grid = |budget| {
        [
            "kepler",
            "--h",
            "0.01",
            "--t-end",
            "10",
            "--max-steps",
            budget,
        ]
    };
    bad_input(&["run"], &grid("999"), "max_steps");
    let exact: Vec<&str> = std::iter::once("run").chain(grid("1000")).collect();
    assert!(svi(&exact).status.success());
    for bad in ["0", "1000000001"] {
        bad_input(&["run"], &["kepler", "--max-steps", bad], "--max-steps");
    }
    bad_input(&["run"], &["kepler", "--max-steps", "-1"], "--max-steps");
}
