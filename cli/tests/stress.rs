//! Stress scenes, failure reporting and `svi stress`. Hostile input to the command line is
//! `hostile.rs`.

use crate::common;
use common::*;

use svi_experiments::{Control, Scene};

#[test]
fn every_stress_scene_parses_and_a_short_run_of_each_succeeds() {
    for name in [
        "stiff-spring-pendulum",
        "stiff-spring-pendulum-coarse",
        "stiff-spring-pendulum-multiscale",
        "kepler-long",
        "kepler-e0.9",
        "kepler-e0.99",
        "kepler-recovery",
        "double-pendulum-chaotic",
    ] {
        let mut scene = Scene::builtin(name).unwrap().unwrap();
        let h = scene.run.h.unwrap();
        scene.run.t_end = Some(50.0 * h);
        let summary = scene
            .run(Control::QUIET)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(summary.steps, 50, "{name}");
        // kepler-recovery is coarse on purpose (h = 0.11 at e = 0.95: 0.33 after 50 steps).
        let bound = if name == "kepler-recovery" { 0.5 } else { 1e-2 };
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
        stderr.contains("the run failed after 26 steps; last good state at t = 2.86"),
        "{stderr}"
    );
    assert!(
        stderr.contains("nonlinear solve did not converge at step 26 (t = 2.86"),
        "{stderr}"
    );
    // Header, the initial point and the 26 good steps.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 28);
    assert!(text.lines().last().unwrap().starts_with("2.86,"));
    // With recovery the same scene completes.
    let output = svi(&["run", "kepler-recovery", "--json"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(summary["steps"].as_u64(), Some(1819));
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
    let (dir, csv) = stress(
        "stress",
        &[
            "--cases",
            "oscillator,kepler-long",
            "--methods",
            "verlet,svi:6,sc:6,dop853",
            "--steps",
            "20000",
        ],
    );
    for file in ["stress.md", "stress.csv", "windows.csv", "drift.svg"] {
        assert!(dir.0.join(file).exists(), "{file}");
    }
    let (header, rows) = table(&csv);
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
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
fn svi_stress_runs_the_adaptive_modes_reparametrised_bounded_and_step_doubling_drifting() {
    let (_dir, csv) = stress(
        "stress-adaptive",
        &[
            "--cases",
            "kepler-long",
            "--methods",
            "svi:6@sundman:1,svi:6@step",
            "--steps",
            "20000",
            "--bisections",
            "1",
            "--tolerance",
            "1e-8",
        ],
    );
    let (header, rows) = table(&csv);
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
    assert_eq!(rows.len(), 2);
    let value = |r: &Vec<&str>, name: &str| r[column(name)].parse::<f64>().unwrap();
    // Time-reparametrised SVI is symplectic in τ: no drift over the horizon 20000 · 0.2 (the
    // energy error stays at round-off, 8e-14 of 0.5), with a step limit in Δτ found by the
    // search (Δτ = 1.7 on this machine).
    let reparam = &rows[0];
    assert_eq!(reparam[1], "svi:6@sundman:1");
    assert_ne!(reparam[column("verdict")], "drifts", "{reparam:?}");
    assert!(value(reparam, "max_error") < 1e-12, "{reparam:?}");
    assert!(value(reparam, "bounded_h") >= 0.2, "{reparam:?}");
    // Step doubling has no step limit, and its energy error drifts.
    let doubling = &rows[1];
    assert_eq!(doubling[1], "svi:6@step");
    assert_eq!(doubling[column("bounded_h")], "", "{doubling:?}");
    assert_eq!(doubling[column("verdict")], "drifts", "{doubling:?}");
    // --bisections needs a method with a step limit, --tolerance one that takes it.
    for (args, option) in [
        (
            vec!["--methods", "svi:6@step", "--bisections", "2"],
            "--bisections",
        ),
        (
            vec!["--methods", "svi:6@sundman:1", "--tolerance", "1e-8"],
            "--tolerance",
        ),
    ] {
        let output = svi(&[&["stress", "--cases", "kepler-long"], &args[..]].concat());
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(option), "{args:?}: {stderr}");
    }
}

#[test]
fn svi_stress_rejects_unknown_cases_and_too_few_steps() {
    for args in [
        vec!["stress", "--cases", "nope"],
        vec!["stress", "--cases", "oscillator", "--steps", "10"],
        vec!["stress", "--methods", "rk45"],
        vec!["stress", "--cases", "oscillator", "--tolerance", "-1"],
    ] {
        let output = svi(&args);
        assert!(!output.status.success(), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"));
    }
}

/// `svi stress ARGS --out-dir` a scratch directory named `name` (the run must succeed): the
/// directory and its stress.csv.
fn stress(name: &str, args: &[&str]) -> (Scratch, String) {
    let dir = Scratch::new(name);
    let out = ["--out-dir", dir.0.to_str().unwrap()];
    let output = svi(&[&["stress"], args, &out[..]].concat());
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = std::fs::read_to_string(dir.0.join("stress.csv")).unwrap();
    (dir, csv)
}

/// The header and rows of a CSV text whose cells hold no commas.
fn table(csv: &str) -> (Vec<&str>, Vec<Vec<&str>>) {
    let mut lines = csv.lines();
    let header = lines.next().unwrap().split(',').collect();
    (header, lines.map(|l| l.split(',').collect()).collect())
}
