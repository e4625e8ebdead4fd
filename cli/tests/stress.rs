//! Stress scenes, failure reporting, `svi stress`, and hostile input to the command line:
//! scene files (TOML strings, random and mutated), command-line arguments (parsed as `svi
//! run` parses them) and the binary itself. Nothing may panic or hang; every rejection is an
//! error message.
//!
//! Case counts are set per test for a short CI run (about 7 000 inputs in all);
//! `SVI_HOSTILE_CASES=N` multiplies them by N.

mod common;
use common::*;

use clap::Parser;
use proptest::prelude::*;
use svi_cli::bench::BenchMethod;
use svi_cli::{Overrides, Scene, SceneError, parse_parameter};

#[path = "../../tests/common/hostile_cases.rs"]
mod hostile_cases;
use hostile_cases::cases;

#[test]
fn every_stress_scene_parses_and_a_short_run_of_each_succeeds() {
    for name in [
        "stiff-spring-pendulum",
        "stiff-spring-pendulum-coarse",
        "kepler-long",
        "kepler-e0.9",
        "kepler-e0.99",
        "kepler-recovery",
        "double-pendulum-chaotic",
    ] {
        let mut scene = Scene::builtin(name).unwrap().unwrap();
        let h = scene.run.h.unwrap();
        scene.run.t_end = Some(50.0 * h);
        let summary = scene.run(false).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(summary.steps, 50, "{name}");
        // kepler-recovery is coarse on purpose (h = 0.08 at e = 0.95: 0.13 after 50 steps).
        let bound = if name == "kepler-recovery" { 0.2 } else { 1e-2 };
        assert!(
            summary.energy_error_max.unwrap() < bound,
            "{name}: {summary:?}"
        );
    }
}

#[test]
fn a_failed_run_reports_the_last_good_state_and_keeps_its_trajectory() {
    let dir = Scratch::new("failure");
    let csv = dir.0.join("trajectory.csv");
    let output = svi(&[
        "run",
        "kepler-recovery",
        "--recovery",
        "none",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("the run failed after 55 steps; last good state at t = 4.4"),
        "{stderr}"
    );
    assert!(
        stderr.contains("nonlinear solve did not converge at step 55 (t = 4.4"),
        "{stderr}"
    );
    // Header, the initial point and the 55 good steps.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 57);
    assert!(text.lines().last().unwrap().starts_with("4.4,"));
    // With recovery the same scene completes.
    let output = svi(&["run", "kepler-recovery", "--json"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(summary["steps"].as_u64(), Some(2500));
    assert!(summary["retries"].as_u64().unwrap() >= 1);
}

#[test]
fn beyond_the_stability_limit_the_run_stops_with_a_divergence_error() {
    let output = svi(&["run", "oscillator-beyond-stability"]);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("state diverged at step 23 (t = 48.3"),
        "{stderr}"
    );
    assert!(stderr.contains("exceeds the limit 1e6"), "{stderr}");
    // Below the limit, h = 1.9, the same scene runs to the end with |q| ≤ 1.
    let output = svi(&["run", "oscillator-beyond-stability", "--h", "1.9", "--json"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert!(summary["q"][0].as_f64().unwrap().abs() <= 1.0);
}

#[test]
fn svi_stress_measures_the_verlet_limit_and_the_kepler_drift() {
    let dir = Scratch::new("stress");
    let output = svi(&[
        "stress",
        "--cases",
        "oscillator,kepler-long",
        "--methods",
        "verlet,svi:6,sc:6,dop853",
        "--steps",
        "20000",
        "--out-dir",
        dir.0.to_str().unwrap(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    for file in ["stress.md", "stress.csv", "windows.csv", "drift.svg"] {
        assert!(dir.0.join(file).exists(), "{file}");
    }
    let csv = std::fs::read_to_string(dir.0.join("stress.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 8);
    let row = |scene: &str, method: &str| {
        rows.iter()
            .find(|r| r[0] == scene && r[1] == method)
            .unwrap_or_else(|| panic!("{scene} {method}"))
    };
    let value = |r: &Vec<&str>, name: &str| r[column(name)].parse::<f64>().unwrap();
    // Störmer–Verlet on q̈ = −q: linearly stable exactly for h < 2.
    let verlet = row("oscillator", "verlet");
    let (bounded, beyond) = (value(verlet, "bounded_h"), value(verlet, "bounded_beyond"));
    assert!(
        bounded < 2.0 && beyond >= 2.0 && beyond / bounded < 1.01,
        "{verlet:?}"
    );
    assert!(verlet[column("bounded_failure")].contains("state diverges"));
    // Kepler e = 0.5: svi bounded, sc and dop853 drift.
    let svi_row = row("kepler-long", "svi:6");
    assert_eq!(svi_row[column("verdict")], "bounded");
    assert!(value(svi_row, "drift").abs() < value(svi_row, "amplitude"));
    for method in ["sc:6", "dop853"] {
        let r = row("kepler-long", method);
        assert_eq!(r[column("verdict")], "drifts", "{method}");
        assert!(
            value(r, "drift").abs() > 10.0 * value(r, "amplitude"),
            "{method}"
        );
    }
    let markdown = std::fs::read_to_string(dir.0.join("stress.md")).unwrap();
    assert_eq!(markdown.lines().count(), 2 + 8);
    let windows = std::fs::read_to_string(dir.0.join("windows.csv")).unwrap();
    assert!(windows.lines().count() > 8 * 100);
}

#[test]
fn svi_stress_rejects_unknown_cases_and_too_few_steps() {
    for args in [
        vec!["stress", "--cases", "nope"],
        vec!["stress", "--cases", "oscillator", "--steps", "10"],
        vec!["stress", "--methods", "rk4"],
        vec!["stress", "--cases", "oscillator", "--tolerance", "-1"],
    ] {
        let output = svi(&args);
        assert!(!output.status.success(), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"));
    }
}

// ---- hostile input ------------------------------------------------------------------------

/// A TOML value: numbers of every kind (including nan and inf), strings, arrays, garbage.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-1e3f64..1e3).prop_map(|x| format!("{x:?}")),
        2 => (-400i32..400).prop_map(|e| format!("1e{e}")),
        1 => proptest::sample::select(vec![
            "nan", "inf", "-inf", "+inf", "0", "-0", "0.0", "-1", "1e309", "-1e309", "5e-324",
            "18446744073709551616", "-9223372036854775809", "\"6\"", "true", "[]", "[1.0]",
            "[1.0, 2.0, 3.0]", "{}", "\"\"", "0x10", "1_000", "--1", "1..2",
        ]).prop_map(String::from),
        1 => (0i64..100).prop_map(|x| x.to_string()),
        1 => "[a-z\\[\\]\"=.,0-9 -]{0,10}",
    ]
}

/// Mostly a valid value from `valid`, sometimes a hostile one.
fn mostly(valid: impl Strategy<Value = String> + 'static) -> BoxedStrategy<String> {
    prop_oneof![4 => valid, 1 => toml_value()].boxed()
}

/// Mostly nothing, sometimes a few entries.
fn few<T: Clone + std::fmt::Debug + 'static>(
    entry: impl Strategy<Value = T> + 'static,
) -> BoxedStrategy<Vec<T>> {
    prop_oneof![2 => Just(Vec::new()), 1 => proptest::collection::vec(entry, 1..3)].boxed()
}

/// A scene: the fields of the format, each mostly valid, some hostile, some misspelt.
fn scene_text() -> impl Strategy<Value = String> {
    let model = prop_oneof![
        6 => proptest::sample::select(svi_models::MODEL_NAMES.to_vec()).prop_map(String::from),
        1 => "[a-z-]{0,12}",
    ];
    let method = prop_oneof![
        6 => proptest::sample::select(
            svi::method::registry::METHODS
                .iter()
                .filter(|entry| entry.space == svi::method::registry::SpaceKind::Vector)
                .map(|entry| entry.name)
                .collect::<Vec<_>>()
        ).prop_map(String::from),
        1 => proptest::sample::select(vec![
            "svi:4/3", "svi:5", "sc:4", "svi:1", "sc:3/2", "verlet:2", "lie-svi",
        ]).prop_map(String::from),
        1 => "[a-z-]{0,12}",
    ];
    let parameter = proptest::sample::select(vec![
        "e",
        "sigma",
        "m",
        "g",
        "k",
        "l",
        "m1",
        "m2",
        "d1",
        "d2",
        "c",
        "zeta",
        "drive",
        "amplitude",
        "x",
    ]);
    let small = |low: f64, high: f64| (low..high).prop_map(|x| format!("{x:?}"));
    (
        model,
        few((parameter, mostly(small(0.0, 0.95)))),
        few((
            proptest::sample::select(vec!["t0", "q", "v", "p"]),
            mostly(proptest::collection::vec(-2.0f64..2.0, 0..4).prop_map(|v| format!("{v:?}"))),
        )),
        (
            method,
            proptest::option::of(mostly((2usize..9).prop_map(|p| p.to_string()))),
            proptest::option::of(mostly((1usize..12).prop_map(|m| m.to_string()))),
        ),
        (mostly(small(0.001, 0.5)), mostly(small(0.0, 5.0))),
        few((
            proptest::sample::select(vec![
                "recovery", "max_halvings", "divergence_limit", "horizon",
            ]),
            prop_oneof![
                1 => toml_value(),
                1 => proptest::sample::select(vec!["\"none\"", "\"halve-step\"", "\"halve\"", "3", "1e3"])
                    .prop_map(String::from),
            ],
        )),
        proptest::option::of(proptest::sample::select(vec![
            "diagnostics = [\"energy\"]",
            "diagnostics = [\"entropy\"]",
            "every = 3",
            "diagnostics = []",
        ])),
    )
        .prop_map(|(model, parameters, initial, (method, points, quadrature), (h, t_end), run, output)| {
            let mut text = format!("model = \"{model}\"\n[parameters]\n");
            for (name, value) in parameters {
                text.push_str(&format!("{name} = {value}\n"));
            }
            text.push_str("[initial]\n");
            for (name, value) in initial {
                text.push_str(&format!("{name} = {value}\n"));
            }
            text.push_str(&format!("[method]\nname = \"{method}\"\n"));
            if let Some(points) = points {
                text.push_str(&format!("points = {points}\n"));
            }
            if let Some(quadrature) = quadrature {
                text.push_str(&format!("quadrature = {quadrature}\n"));
            }
            text.push_str(&format!("[run]\nh = {h}\nt_end = {t_end}\n"));
            for (name, value) in run {
                text.push_str(&format!("{name} = {value}\n"));
            }
            if let Some(line) = output {
                text.push_str(&format!("[output]\n{line}\n"));
            }
            text
        })
}

/// Largest number of steps a hostile scene may take in a test (larger ones are only
/// parsed and checked, not run).
const MAX_TEST_STEPS: f64 = 2000.0;

/// How far a hostile scene got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    /// Rejected by the parser or the checks.
    Rejected,
    /// A valid scene, too long to run in a test.
    Parsed,
    /// Run (to the end or to a reported failure).
    Ran,
}

/// Parse `text`; if it is a valid scene, run it when it is short. Never panics.
fn parse_and_maybe_run(text: &str) -> Result<Outcome, TestCaseError> {
    let scene = match Scene::from_toml(text, "hostile scene") {
        Ok(scene) => scene,
        Err(error) => {
            prop_assert!(!error.to_string().is_empty());
            return Ok(Outcome::Rejected);
        }
    };
    prop_assert!(scene.output.trajectory.is_none());
    let h = scene.run.h.unwrap_or(0.2);
    let span = scene.run.t_end.unwrap_or(20.0) - scene.initial.t0.unwrap_or(0.0);
    let short = span / h <= MAX_TEST_STEPS
        && scene.points().unwrap_or(0) <= 16
        && scene.quadrature().unwrap_or(0) <= 32
        && scene.run.max_halvings.unwrap_or(0) <= 6
        && scene.run.h.is_some()
        && scene.run.t_end.is_some();
    if !short {
        return Ok(Outcome::Parsed);
    }
    {
        match scene.run(false) {
            Ok(summary) => {
                prop_assert!(summary.steps as f64 <= MAX_TEST_STEPS + 1.0);
                prop_assert!(summary.state.configuration().iter().all(|x| x.is_finite()));
            }
            Err(error) => {
                let message = error.to_string();
                prop_assert!(!message.is_empty());
                if let SceneError::RunFailed { partial, .. } = &error {
                    prop_assert!(
                        partial.state.configuration().iter().all(|x| x.is_finite()),
                        "{}",
                        message
                    );
                }
            }
        }
    }
    Ok(Outcome::Ran)
}

#[test]
fn structured_hostile_scenes_never_panic() {
    let config = cases(3000);
    let total = config.cases as usize;
    let counts = std::cell::RefCell::new([0usize; 3]);
    proptest::test_runner::TestRunner::new(config)
        .run(&scene_text(), |text| {
            let outcome = parse_and_maybe_run(&text)?;
            counts.borrow_mut()[outcome as usize] += 1;
            Ok(())
        })
        .unwrap();
    // The generator reaches every path: rejections, valid scenes, runs.
    let [rejected, parsed, ran] = counts.into_inner();
    eprintln!("hostile scenes: {rejected} rejected, {parsed} valid but long, {ran} run");
    assert_eq!(rejected + parsed + ran, total);
    assert!(rejected > total / 10, "{rejected} of {total} rejected");
    assert!(ran > total / 10, "{ran} of {total} run");
}

proptest! {
    #![proptest_config(cases(3000))]

    #[test]
    fn arbitrary_text_is_never_a_panic(text in prop_oneof![
        1 => ".{0,200}",
        1 => "[a-z_\\[\\]\"=.,0-9 \n-]{0,200}",
    ]) {
        parse_and_maybe_run(&text)?;
    }
}

/// `svi run`'s arguments: an optional scene and the overrides.
#[derive(Debug, Parser)]
struct RunArguments {
    scene: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
}

/// A command-line token: a flag, a value, or garbage.
fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => proptest::sample::select(vec![
            "--method", "--points", "--quadrature", "--h", "--t-end", "--param", "--every",
            "--diagnostics", "--recovery", "--divergence-limit", "--json", "--bogus", "-h",
        ]).prop_map(String::from),
        3 => toml_value(),
        1 => proptest::sample::select(vec![
            "svi", "sc", "verlet", "midpoint", "svi:7/6", "lie-svi", "midpoint:3", "e=0.9", "e=1", "e=nan", "=1", "e=", "sigma=inf",
            "k=-1", "energy,momentum", "halve-step", "none", "kepler", "oscillator",
        ]).prop_map(String::from),
        1 => ".{0,8}",
    ]
}

proptest! {
    #![proptest_config(cases(1000))]

    #[test]
    fn hostile_run_arguments_never_panic(tokens in proptest::collection::vec(token(), 0..8)) {
        let args = std::iter::once("run".to_string()).chain(tokens);
        let Ok(parsed) = RunArguments::try_parse_from(args) else { return Ok(()) };
        let name = parsed.scene.as_deref().unwrap_or("kepler");
        let Ok(mut scene) = Scene::load(name) else { return Ok(()) };
        if scene.apply(&parsed.overrides).is_err() || scene.output.trajectory.is_some() {
            return Ok(());
        }
        // Keep the run short whatever the arguments asked for.
        let h = *scene.run.h.get_or_insert(0.01);
        if h.is_finite() && h > 0.0 {
            scene.run.t_end = Some(scene.initial.t0.unwrap_or(0.0) + 200.0 * h);
        }
        if scene.points().unwrap_or(0) > 16 || scene.quadrature().unwrap_or(0) > 32 {
            return Ok(());
        }
        if let Err(error) = scene.run(false) {
            prop_assert!(!error.to_string().is_empty());
        }
    }

    #[test]
    fn method_specifications_and_parameters_parse_or_fail_cleanly(text in ".{0,16}") {
        if let Ok(spec) = text.parse::<BenchMethod>() {
            prop_assert_eq!(spec.to_string().parse::<BenchMethod>().ok(), Some(spec));
        }
        if let Err(error) = text.parse::<svi::MethodSpec>() {
            prop_assert!(error.to_string().starts_with("invalid method: "), "{}", error);
        }
        match parse_parameter(&text) {
            Ok((name, value)) => {
                prop_assert!(!name.is_empty());
                prop_assert!(!value.is_nan() || text.to_lowercase().contains("nan"));
            }
            Err(error) => prop_assert!(error.to_string().starts_with("malformed parameter")),
        }
    }
}

proptest! {
    #![proptest_config(cases(60))]

    /// The binary itself: exit status 0, 1 (error) or 2 (usage), never a panic.
    #[test]
    fn the_binary_never_panics(tokens in proptest::collection::vec(token(), 0..6)) {
        let mut args = vec!["run".to_string(), "oscillator".to_string()];
        // Arguments cannot hold NUL bytes (an OS rule, not svi's).
        args.extend(tokens.into_iter().filter(|t| !t.contains('\0')));
        // A short run whatever the tokens say (a repeated --h or --t-end is a usage error).
        args.extend(["--h", "0.5", "--t-end", "2"].map(String::from));
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let output = svi(&refs);
        let stderr = String::from_utf8_lossy(&output.stderr);
        prop_assert!(!stderr.contains("panicked"), "{:?}: {}", args, stderr);
        let code = output.status.code();
        prop_assert!(matches!(code, Some(0..=2)), "{:?}: {:?} {}", args, code, stderr);
    }
}
