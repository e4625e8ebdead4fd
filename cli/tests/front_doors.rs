//! The front doors of one scene give the same numbers: `svi run SCENE --json`, `svi ensemble
//! SCENE` (one member: the scene itself, or a grid whose one member has the scene's values)
//! and `svi bench SCENE --methods METHOD --steps N` (the scene's method at the scene's step:
//! N = (t_end − t0)/h) run the same computation — same method, step, horizon, initial state,
//! recovery — and report it bit for bit: final state, steps, energy and momentum errors,
//! evaluations, iterations and (where the model has an exact solution) the final error. Only
//! wall times differ. (The Python package's door, `svi.run`/`svi.solve`/`svi.ensemble`/
//! `svi.bench`, is held to the same numbers by `python/tests/test_front_doors.py`.)
//!
//! What each door reports of a run, and so what is compared:
//!
//! - `svi run --json`: everything (state, errors, counts, `solution_error_final` against the
//!   exact solution where there is one).
//! - `svi ensemble`: a row per member with the run's state, energies, `energy_error_max`,
//!   `momentum_error_max`, `solution_error_max`, `iterations`, `evaluations`, `retries`
//!   (no column per coordinate on a chain); no `solution_error_final`.
//! - `svi bench`: per point `h`, `steps`, `final_error`, `energy_error_max`,
//!   `momentum_error_max`, `evaluations`, `iterations` and the wall time, not the state. Its
//!   `final_error` is ‖q(t_end) − q_exact(t_end)‖, the run's `solution_error_final`, for a
//!   model with an exact solution; for a chain it is measured against bench's own resolved
//!   reference run (svi:7/6 at the scene's step, halved until two runs agree to 10⁻¹¹), which
//!   [`reference_of_a_chain`] recomputes with `svi run` to check the same number.

use crate::common;
use common::*;

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::DVector;

/// `svi run SCENE ARGS --json`: its text (numbers read exactly with [`raw`]) and its JSON.
fn run(scene: &str, args: &[&str]) -> (String, serde_json::Value) {
    let mut all = vec!["run", scene];
    all.extend_from_slice(args);
    all.push("--json");
    let output = svi_within(&all, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "svi {all:?}: {text} {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let value = serde_json::from_str(&text).unwrap();
    (text, value)
}

/// The one row of `svi ensemble SCENE ARGS` (the member table printed on stdout).
fn ensemble_row(scene: &str, args: &[&str]) -> HashMap<String, String> {
    let mut all = vec!["ensemble", scene, "--threads", "1"];
    all.extend_from_slice(args);
    let output = svi_within(&all, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "svi {all:?}: {stdout} {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut rows = parse_csv(&stdout);
    assert_eq!(rows.len(), 1, "one member: {stdout}");
    let row = rows.remove(0);
    assert_eq!(row["status"], "ok", "{stdout}");
    row
}

/// The one record of `svi bench SCENE --methods METHOD --steps N ARGS` (one timing run).
fn bench_record(scene: &str, method: &str, steps: &str, args: &[&str]) -> HashMap<String, String> {
    // Tests run side by side in one process: a directory of its own for each bench.
    static BENCHES: AtomicUsize = AtomicUsize::new(0);
    let index = BENCHES.fetch_add(1, Ordering::Relaxed);
    let dir = Scratch::new(&format!("front-doors-bench-{index}"));
    let out = dir.0.to_str().unwrap().to_owned();
    let mut all = vec![
        "bench",
        scene,
        "--methods",
        method,
        "--batches",
        "1",
        "--min-batch",
        "0",
        "--out-dir",
        &out,
    ];
    // A step count, or for step doubling (METHOD@step) a tolerance.
    if method.ends_with("@step") {
        all.extend(["--tolerances", steps]);
    } else {
        all.extend(["--steps", steps]);
    }
    all.extend_from_slice(args);
    let output = svi_within(&all, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "svi {all:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut rows = parse_csv(&stdout);
    assert_eq!(rows.len(), 1, "one point: {stdout}");
    rows.remove(0)
}

/// The number `key` of a run, or `None` where it is null.
fn optional(text: &str, value: &serde_json::Value, key: &str) -> Option<f64> {
    assert!(value.get(key).is_some(), "no {key} in {text}");
    (!value[key].is_null()).then(|| raw(text, key)[0])
}

/// A cell of a table, `None` where it is empty.
fn optional_cell(row: &HashMap<String, String>, column: &str) -> Option<f64> {
    (!row[column].is_empty()).then(|| cell(row, column))
}

/// The ensemble's row is the run, field by field, bit for bit (`None` of the run is an empty
/// cell).
fn assert_row_is_the_run(row: &HashMap<String, String>, text: &str, run: &serde_json::Value) {
    if let Some(names) = run["coordinates"].as_array() {
        for field in ["q", "v", "p"] {
            for (name, x) in names.iter().zip(raw(text, field)) {
                let column = format!("{field}_{}", name.as_str().unwrap());
                assert_eq!(cell(row, &column), x, "{column}");
            }
        }
    }
    for field in [
        "t_end",
        "energy_initial",
        "energy_final",
        "energy_error_max",
        "energy_scale",
        "momentum_error_max",
        "solution_error_max",
    ] {
        assert_eq!(
            optional_cell(row, field),
            optional(text, run, field),
            "{field}"
        );
    }
    for field in ["steps", "iterations", "evaluations", "retries"] {
        assert_eq!(row[field], run[field].to_string(), "{field}");
    }
}

/// Bench's record is the run: the step, the steps taken, the energy and momentum errors, the
/// evaluations and iterations, and (`final_error`: the run's error against the exact
/// solution, or the caller's value) the final error.
fn assert_record_is_the_run(
    record: &HashMap<String, String>,
    text: &str,
    run: &serde_json::Value,
    final_error: Option<f64>,
) {
    for field in ["steps", "evaluations", "iterations"] {
        assert_eq!(record[field], run[field].to_string(), "{field}");
    }
    // Step doubling has no step (its parameter is the tolerance).
    if let Some(h) = optional_cell(record, "h") {
        assert_eq!(Some(h), optional(text, run, "h"), "h");
    }
    assert_eq!(
        optional_cell(record, "energy_error_max"),
        optional(text, run, "energy_error_max"),
        "energy_error_max"
    );
    // A model without symmetries: an empty cell in bench, null (or absent, on a chain) in
    // the run.
    let momentum = run
        .get("momentum_error_max")
        .and_then(|_| optional(text, run, "momentum_error_max"));
    assert_eq!(
        optional_cell(record, "momentum_error_max"),
        momentum,
        "momentum_error_max"
    );
    let final_error = final_error.or_else(|| optional(text, run, "solution_error_final"));
    assert_eq!(
        Some(cell(record, "final_error")),
        final_error,
        "final_error"
    );
}

/// Kepler (e = 0.5) by the scene's SVI 6/12 at h = 0.2 over 100 steps, with its Noether
/// momentum and exact solution: the run, the ensemble of the scene alone and of a grid whose
/// one member is the scene's e, and bench at 100 steps give the same numbers.
#[test]
fn kepler_by_svi_is_the_same_run_through_every_door() {
    let horizon = ["--t-end", "20"];
    let diagnostics = ["--diagnostics", "energy,momentum,solution"];
    let (text, value) = run("kepler", &[&horizon[..], &diagnostics].concat());
    assert_eq!(
        (value["method"].as_str(), value["points"].as_u64()),
        (Some("svi"), Some(6))
    );
    assert_eq!(
        (value["h"].as_f64(), value["steps"].as_u64()),
        (Some(0.2), Some(100))
    );
    assert!(!value["momentum_error_max"].is_null());
    for grid in [&[][..], &["--param", "e=0.5"]] {
        let row = ensemble_row("kepler", &[&horizon[..], &diagnostics, grid].concat());
        assert_row_is_the_run(&row, &text, &value);
    }
    let record = bench_record("kepler", "svi:6/12", "100", &horizon);
    assert_eq!(cell(&record, "h"), 0.2);
    assert_record_is_the_run(&record, &text, &value, None);
}

/// The harmonic oscillator's scene starts from a momentum (q0, p0) = (0, 1); bench starts
/// its runs from the velocity the Legendre map gives. By spectral collocation (sc:9, another
/// method than the scene's) at h = 1 over 20 steps, every door gives the same numbers.
#[test]
fn the_oscillator_by_collocation_from_a_momentum_is_the_same_run_through_every_door() {
    let args = ["--method", "sc:9", "--t-end", "20"];
    let diagnostics = ["--diagnostics", "energy,solution"];
    let (text, value) = run("oscillator", &[&args[..], &diagnostics].concat());
    assert_eq!(value["method"].as_str(), Some("sc"));
    assert_eq!(value["steps"].as_u64(), Some(20));
    let row = ensemble_row("oscillator", &[&args[..], &diagnostics].concat());
    assert_row_is_the_run(&row, &text, &value);
    let record = bench_record("oscillator", "sc:9", "20", &["--t-end", "20"]);
    assert_eq!(cell(&record, "h"), 1.0);
    assert_record_is_the_run(&record, &text, &value, None);
}

/// Kepler at e = 0.95 with the coarse h = 0.11 (the `kepler-recovery` scene): two solves fail
/// and are retried as half steps under the scene's `recovery = "halve-step"`. Bench runs the
/// scene's recovery too (it used to run without it, and its runs failed at step 26 where `svi
/// run` of the same scene succeeds).
#[test]
fn a_scene_with_recovery_is_the_same_run_through_every_door() {
    let args = ["--t-end", "11", "--diagnostics", "energy,momentum"];
    let (text, value) = run("kepler-recovery", &args);
    assert_eq!(value["steps"].as_u64(), Some(100));
    assert!(
        value["retries"].as_u64().unwrap() > 0,
        "the scene retries steps: {text}"
    );
    let row = ensemble_row("kepler-recovery", &args);
    assert_row_is_the_run(&row, &text, &value);
    let record = bench_record("kepler-recovery", "svi:6/12", "100", &args[..2]);
    assert_eq!(cell(&record, "h"), 0.11);
    assert_record_is_the_run(&record, &text, &value, None);
}

/// The adaptive modes have their bench rows: fixed steps Δτ in computational time
/// (`--adapt reparam --monitor sundman:1 --h 0.25` is `svi:9/8@sundman:1` at 80 τ-steps
/// over 20) and step doubling (`--adapt step --tol 1e-8` is `svi:7/6@step` at tolerance
/// 1e-8) give the numbers of the run.
#[test]
fn the_adaptive_modes_of_bench_are_the_runs() {
    let horizon = ["--t-end", "20"];
    let diagnostics = ["--diagnostics", "energy,momentum"];
    let reparam = [
        "--method",
        "svi:9/8",
        "--adapt",
        "reparam",
        "--monitor",
        "sundman:1",
        "--h",
        "0.25",
    ];
    let args = [&horizon[..], &reparam, &diagnostics].concat();
    let (text, value) = run("kepler", &args);
    let record = bench_record("kepler", "svi:9/8@sundman:1", "80", &horizon);
    assert_record_is_the_run(&record, &text, &value, None);
    let row = ensemble_row("kepler", &args);
    assert_row_is_the_run(&row, &text, &value);

    let doubling = ["--method", "svi:7/6", "--adapt", "step", "--tol", "1e-8"];
    let (text, value) = run("kepler", &[&horizon[..], &doubling].concat());
    let record = bench_record("kepler", "svi:7/6@step", "1e-8", &horizon);
    assert_record_is_the_run(&record, &text, &value, None);
}

/// The final position of bench's reference run for a chain, recomputed with `svi run`: SVI
/// 7/6 at the scene's step `h`, then at h/2, h/4, … until two runs agree to 10⁻¹¹ relative
/// (bench/scene_runs.rs).
fn reference_of_a_chain(scene: &str, h: f64, args: &[&str]) -> DVector<f64> {
    let final_q = |h: f64| {
        let step = h.to_string();
        let (text, _) = run(
            scene,
            &[
                args,
                &["--method", "svi:7/6", "--h", &step, "--diagnostics", "none"],
            ]
            .concat(),
        );
        DVector::from_vec(raw(&text, "q"))
    };
    let (mut h, mut coarse) = (h, final_q(h));
    for _ in 0..4 {
        let fine = final_q(0.5 * h);
        if (&coarse - &fine).amax() <= 1e-11 * fine.amax().max(1.0) {
            return fine;
        }
        (h, coarse) = (0.5 * h, fine);
    }
    panic!("the reference runs of {scene} do not agree down to h = {h}");
}

/// A chain of run-time size (FPUT, n = 32) by the scene's SVI 6/12 at h = 0.1 over 50 steps,
/// and by Störmer–Verlet: run, ensemble (the scene alone, and a grid whose one member is the
/// scene's n) and bench agree; bench's final error is the distance of the run's final state
/// from the reference run.
#[test]
fn a_chain_is_the_same_run_through_every_door() {
    let horizon = ["--t-end", "5"];
    let diagnostics = ["--diagnostics", "energy"];
    let reference = reference_of_a_chain("fput", 0.1, &horizon);
    for (method, label) in [(None, "svi:6/12"), (Some("verlet"), "verlet")] {
        let method_args: Vec<&str> = method.map(|m| vec!["--method", m]).unwrap_or_default();
        let args = [&horizon[..], &method_args, &diagnostics].concat();
        let (text, value) = run("fput", &args);
        assert_eq!(value["steps"].as_u64(), Some(50), "{label}");
        for grid in [&[][..], &["--param", "n=32"]] {
            let row = ensemble_row("fput", &[&args[..], grid].concat());
            assert_row_is_the_run(&row, &text, &value);
            assert_eq!(
                optional_cell(&row, "invariant_error_max"),
                optional(&text, &value, "invariant_error_max"),
                "{label}"
            );
        }
        let record = bench_record("fput", label, "50", &horizon);
        let final_error = (DVector::from_vec(raw(&text, "q")) - &reference).norm();
        assert_record_is_the_run(&record, &text, &value, Some(final_error));
    }
}
