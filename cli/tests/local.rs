//! `svi run` on the chains of runtime dimension (`fput`, `toda`; issue #16): the JSON carries
//! vectors of the model's n, a bad size is bad input naming `n`, every method of ℝᴺ runs a
//! chain and the options a chain cannot use are bad input naming them, the trajectory holds t, the energy and the
//! model's observables. References: the FPUT chain started in its lowest mode, whose energy
//! is ¼ (n + 1) ω₁² A² with ω₁ = 2 sin(π/(2(n + 1))) (the cubic springs add Σ r³ = 0 for
//! that shape) and all in mode 1; the Toda lattice's Lax traces, conserved exactly.

use crate::common;
use common::*;

/// The energy of the FPUT chain of n particles in its lowest mode of amplitude 1.
fn fput_mode_one_energy(n: usize) -> f64 {
    let omega = 2.0 * (std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin();
    0.25 * (n + 1) as f64 * omega * omega
}

#[test]
fn fput_of_a_thousand_particles_reports_every_coordinate() {
    let summary = json(&["run", "fput", "--param", "n=1000", "--t-end", "1", "--json"]);
    assert_eq!(summary["model"], "fput");
    assert_eq!(summary["parameters"]["n"], 1000.0);
    assert_eq!(summary["method"], "svi");
    assert_eq!(summary["steps"], 10);
    assert_eq!(summary["status"], "ok");
    // The coordinates of a chain are numbered, not named.
    assert!(summary.get("coordinates").is_none(), "{summary}");
    let (q, v, p) = (
        vector(&summary, "q"),
        vector(&summary, "v"),
        vector(&summary, "p"),
    );
    assert_eq!((q.len(), v.len(), p.len()), (1000, 1000, 1000));
    // Unit masses: p = q̇ exactly (q̇ = M⁻¹p).
    assert_eq!(v, p);
    // After t = 1 the lowest mode (period 2000) has barely moved: q ≈ sin(πi/1001).
    for (i, x) in q.iter().enumerate() {
        let start = (std::f64::consts::PI * (i + 1) as f64 / 1001.0).sin();
        assert!((x - start).abs() < 1e-4, "{i}: {x} {start}");
    }
    let energy = fput_mode_one_energy(1000);
    assert!(
        (number(&summary, "energy_initial") - energy).abs() < 1e-14,
        "{summary}"
    );
    assert!(number(&summary, "energy_error_max") < 1e-15, "{summary}");
    // Nothing to measure but the energy: the fields of ℝᴺ are there, null.
    for field in [
        "momentum_error_max",
        "solution_error_max",
        "solution_error_final",
        "invariant_error_max",
    ] {
        assert!(summary[field].is_null(), "{field}: {summary}");
    }
    assert_eq!(summary["invariant_names"], serde_json::json!([]));
}

#[test]
fn a_size_that_is_not_a_positive_whole_number_is_bad_input_naming_n() {
    for value in ["n=0", "n=-3", "n=2.5", "n=1e300"] {
        let stderr = bad_input(&["run", "fput"], &["--param", value], "invalid n");
        assert!(stderr.contains("must be a whole number"), "{stderr}");
    }
    bad_input(
        &["run", "fput"],
        &["--param", "n=nan"],
        "invalid n: NaN is not finite",
    );
    // Toda needs two particles (one spring would close on itself).
    bad_input(&["run", "toda"], &["--param", "n=1"], "invalid n");
    // --json: one object with the error, still exit status 2.
    let output = svi(&["run", "fput", "--param", "n=0", "--json"]);
    assert_eq!(output.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["status"], "failed");
    assert_eq!(report["error"]["kind"], "invalid_parameter");
    assert!(
        report["error"]["message"]
            .as_str()
            .unwrap()
            .starts_with("invalid n:"),
        "{report}"
    );
}

#[test]
fn options_a_chain_cannot_use_are_bad_input_naming_them() {
    bad_input(&["run", "fput"], &["--method", "lie-svi"], "lie-svi");
    bad_input(
        &["run", "fput"],
        &["--adapt", "degree", "--tol", "1e-9", "--method", "verlet"],
        "--adapt degree",
    );
    bad_input(
        &["run", "fput"],
        &["--diagnostics", "momentum"],
        "--diagnostics momentum",
    );
    bad_input(
        &["run", "toda"],
        &["--diagnostics", "energy,solution"],
        "--diagnostics solution",
    );
    bad_input(&["run", "fput"], &["--form", "full"], "--form");
    bad_input(&["run", "fput"], &["--every", "3"], "output.every");
    bad_input(&["run", "fput"], &["--param", "gamma=1"], "gamma");
    bad_input(
        &["bench", "fput"],
        &["--methods", "radau5"],
        "needs a model of fixed size",
    );
    bad_input(
        &["ensemble", "toda"],
        &["--initial", "q.q1=0,1"],
        "site by site",
    );
}

#[test]
fn a_scene_file_gives_the_initial_state_of_its_size() {
    let file = scene_file(
        "chain.toml",
        "model = \"fput\"\n[parameters]\nn = 3\nalpha = 0.0\n\
         [initial]\nq = [0.0, 0.0, 0.0]\nv = [1.0, 0.0, -1.0]\n\
         [method]\nname = \"verlet\"\n[run]\nh = 0.01\nt_end = 1.0\n",
    );
    let summary = json(&["run", &file.path, "--json"]);
    assert_eq!(summary["method"], "verlet");
    assert_eq!(vector(&summary, "q").len(), 3);
    // α = 0: a harmonic chain; q̇ = (1, 0, −1) is mode 2 (q = (a, 0, −a), ω₂ = √2), so
    // q₁(t) = sin(√2 t)/√2 and q₂ = 0 (Störmer–Verlet at h = 0.01: error O(h²)).
    let q = vector(&summary, "q");
    let exact = 2f64.sqrt().sin() / 2f64.sqrt();
    assert!((q[0] - exact).abs() < 1e-4, "{q:?} {exact}");
    assert!(q[1].abs() < 1e-15 && (q[0] + q[2]).abs() < 1e-15, "{q:?}");
    assert!((number(&summary, "energy_initial") - 1.0).abs() < 1e-15);
    // The length is the chain's n, after the scene's and the command line's parameters.
    let stderr = bad_input(&["run", &file.path], &["--param", "n=4"], "initial.q");
    assert!(
        stderr.contains("3 components") && stderr.contains("4"),
        "{stderr}"
    );
}

#[test]
fn toda_conserves_its_lax_traces() {
    let summary = json(&["run", "toda", "--json"]);
    assert_eq!(summary["model"], "toda");
    assert_eq!(summary["steps"], 10_000);
    assert_eq!(
        summary["invariant_names"],
        serde_json::json!(["trace_lax_1", "trace_lax_2", "trace_lax_3", "trace_lax_4"])
    );
    let invariants = number(&summary, "invariant_error_max");
    assert!(invariants < 1e-12, "{summary}");
    assert!(number(&summary, "energy_error_max") < 1e-12, "{summary}");
    // The sine profile has no net momentum: tr 𝕃 = Σp stays 0.
    let p = vector(&summary, "p");
    assert_eq!(p.len(), 16);
    assert!(p.iter().sum::<f64>().abs() < 1e-12, "{p:?}");
    // Störmer–Verlet keeps them near, not to rounding.
    let verlet = json(&["run", "toda", "--method", "verlet", "--json"]);
    let error = number(&verlet, "invariant_error_max");
    assert!(error > 1e-4 && error < 0.1, "{verlet}");
    // No diagnostics: none measured.
    let none = json(&[
        "run",
        "toda",
        "--t-end",
        "1",
        "--diagnostics",
        "none",
        "--json",
    ]);
    assert!(none["invariant_error_max"].is_null() && none["energy_error_max"].is_null());
}

#[test]
fn the_fput_trajectory_holds_the_energy_and_the_mode_energies() {
    let scratch = Scratch::new("fput");
    let path = scratch.join("fput.csv");
    let summary = json(&[
        "run",
        "fput",
        "--t-end",
        "100",
        "--every",
        "100",
        "--out",
        path.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["trajectory"]["rows"], 11);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "t", "energy", "mode_1", "mode_2", "mode_3", "mode_4", "mode_5", "mode_6", "mode_7",
            "mode_8"
        ]
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|line| line.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 11);
    let energy = fput_mode_one_energy(32);
    // Everything in mode 1 at the start.
    assert!((rows[0][1] - energy).abs() < 1e-15, "{:?}", rows[0]);
    assert!((rows[0][2] - energy).abs() < 1e-15, "{:?}", rows[0]);
    assert!(
        rows[0][3..].iter().all(|e| e.abs() < 1e-30),
        "{:?}",
        rows[0]
    );
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], 10.0 * k as f64);
        assert!((row[1] - energy).abs() < 1e-15, "{row:?}");
        // The harmonic mode energies hold all but the cubic springs' share of it, and
        // mode 1 most of it this early (period 66).
        let modes: f64 = row[2..].iter().sum();
        assert!((modes - energy).abs() < 0.02 * energy, "{row:?}");
        assert!(row[2] > 0.9 * energy, "{row:?}");
    }
    // By t = 100 energy has reached modes 2 and 3 (α couples mode 1 to the even modes,
    // and those on).
    assert!(
        rows[10][3] > 1e-4 * energy && rows[10][4] > 1e-6 * energy,
        "{:?}",
        rows[10]
    );
    // A short chain writes the modes it has.
    let short = scratch.join("short.csv");
    json(&[
        "run",
        "fput",
        "--param",
        "n=3",
        "--t-end",
        "1",
        "--out",
        short.to_str().unwrap(),
        "--json",
    ]);
    let text = std::fs::read_to_string(&short).unwrap();
    assert_eq!(text.lines().next(), Some("t,energy,mode_1,mode_2,mode_3"));
    assert_eq!(text.lines().count(), 12);
}

#[test]
fn chains_take_output_times_step_and_degree_adaptivity_recovery_and_strictness() {
    // Output times inside steps: cubic Hermite between the step's ends; against a run whose
    // grid holds the time (h = 0.05), to O(h⁴).
    let inside = json(&[
        "run",
        "fput",
        "--t-end",
        "5",
        "--output-times",
        "2.55,5",
        "--json",
    ]);
    let grid = json(&[
        "run",
        "fput",
        "--t-end",
        "5",
        "--h",
        "0.05",
        "--output-times",
        "2.55,5",
        "--json",
    ]);
    let outputs = inside["outputs"].as_array().unwrap();
    assert_eq!(outputs.len(), 2);
    assert_eq!(outputs[0]["t"], 2.55);
    let (a, b) = (vector(&outputs[0], "q"), vector(&grid["outputs"][0], "q"));
    assert_eq!(a.len(), 32);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9, "{x} {y}");
    }
    // Step doubling chooses its own steps and meets the tolerance on this smooth run.
    let adaptive = json(&[
        "run", "toda", "--t-end", "10", "--adapt", "step", "--tol", "1e-8", "--json",
    ]);
    assert_eq!(adaptive["adapt"], "step");
    assert!(adaptive["adaptivity"]["accepted"].as_u64().unwrap() > 0);
    assert!(
        number(&adaptive, "invariant_error_max") < 1e-8,
        "{adaptive}"
    );
    // Degree adaptivity chooses the points of each step, by sparse Newton on a chain whose
    // mass matrix depends on q̇.
    let degree = json(&[
        "run",
        "relativistic-chain",
        "--t-end",
        "5",
        "--h",
        "0.5",
        "--points",
        "4",
        "--quadrature",
        "3",
        "--adapt",
        "degree",
        "--tol",
        "1e-10",
        "--json",
    ]);
    assert_eq!(degree["adapt"], "degree");
    let used = degree["adaptivity"]["points_used"].as_array().unwrap();
    assert!(used.len() >= 2, "{degree}");
    let error = number(&degree, "energy_error_max") / number(&degree, "energy_initial");
    assert!(error < 1e-10, "{degree}");
    // Recovery and the divergence limit are run options like any other.
    let guarded = json(&[
        "run",
        "fput",
        "--t-end",
        "10",
        "--recovery",
        "halve-step",
        "--divergence-limit",
        "10",
        "--strict",
        "--json",
    ]);
    assert_eq!(guarded["retries"], 0);
    assert_eq!(guarded["status"], "ok");
    assert!(guarded["warnings"].as_array().unwrap().is_empty());
    // A divergence limit below the chain's extent stops the run (exit status 1).
    let output = svi(&[
        "run",
        "fput",
        "--t-end",
        "10",
        "--divergence-limit",
        "0.5",
        "--json",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["error"]["kind"], "diverged");
    assert_eq!(vector(&report, "q").len(), 32);
}

#[test]
fn the_relativistic_chain_runs_by_sparse_newton_below_the_speed_of_light() {
    let summary = json(&["run", "relativistic-chain", "--t-end", "10", "--json"]);
    assert_eq!(summary["model"], "relativistic-chain");
    assert_eq!(summary["steps"], 100);
    // E = Σ m c² γᵢ at rest positions, γᵢ = 1/√(1 − (0.8 sin(πi/33))²).
    let energy: f64 = (1..=32)
        .map(|i| {
            let speed = 0.8 * (std::f64::consts::PI * f64::from(i) / 33.0).sin();
            1.0 / (1.0 - speed * speed).sqrt()
        })
        .sum();
    assert!(
        (number(&summary, "energy_initial") - energy).abs() < 1e-12,
        "{summary} {energy}"
    );
    assert!(number(&summary, "energy_error_max") < 1e-12, "{summary}");
    let v = vector(&summary, "v");
    assert_eq!(v.len(), 32);
    assert!(v.iter().all(|x| x.abs() < 1.0), "{v:?}");
}

/// Every implicit method of ℝᴺ runs a chain whose mass matrix depends on q̇ (sparse Newton on
/// its equations: SC's collocation equations, the segment rules', Verlet's implicit
/// trapezoid), and keeps its relative energy error within the method's over 20 steps of
/// h = 0.1.
#[test]
fn every_implicit_method_runs_the_relativistic_chain() {
    // Measured: 4.8e-14, 1.8e-12, 2.7e-9 (trapezoid and Verlet), 5.9e-5 and 3.5e-16.
    for (method, tolerance) in [
        ("sc", 1e-12),
        ("midpoint", 1e-10),
        ("trapezoid", 1e-7),
        ("symplectic-euler", 1e-3),
        ("verlet", 1e-7),
        ("svi-newton", 1e-13),
    ] {
        let summary = json(&[
            "run",
            "relativistic-chain",
            "--param",
            "n=64",
            "--method",
            method,
            "--t-end",
            "2",
            "--json",
        ]);
        assert_eq!(summary["method"], method);
        assert_eq!(summary["steps"], 20, "{method}");
        let error = number(&summary, "energy_error_max") / number(&summary, "energy_initial");
        assert!(error < tolerance, "{method}: {error:e}");
        assert!(
            vector(&summary, "v").iter().all(|x| x.abs() < 1.0),
            "{method}"
        );
    }
}

#[test]
fn list_shows_the_chains_and_their_observables() {
    let output = svi(&["list"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    let chains = text
        .split("Chains and lattices of any size n")
        .nth(1)
        .expect("a group of its own");
    for name in ["fput", "toda", "relativistic-chain"] {
        assert!(chains.matches(name).count() >= 2, "{name} missing:\n{text}");
    }
    assert!(
        chains.contains("mode_8") && chains.contains("trace_lax_4"),
        "{text}"
    );
    // The text summary of a long chain shows the ends of its vectors.
    let output = svi(&["run", "fput", "--param", "n=100", "--t-end", "0.5"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("(100 components)"), "{text}");
    assert!(text.lines().all(|line| line.len() < 400), "{text}");
}

#[test]
fn plot_draws_the_trajectory_columns_and_needs_the_trajectory_file() {
    let scratch = Scratch::new("fput-plot");
    let (csv, svg) = (scratch.join("fput.csv"), scratch.join("fput.svg"));
    let summary = json(&[
        "run",
        "fput",
        "--t-end",
        "100",
        "--every",
        "10",
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["status"], "ok");
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg"), "{}", &picture[..80]);
    // One legend entry per column but t, and the title names scene and method.
    for label in ["energy", "mode_1", "mode_8", "fput (svi)"] {
        assert!(picture.contains(label), "{label} missing");
    }
    // Without a trajectory file there is nothing to draw: bad input naming --plot.
    bad_input(
        &["run", "fput"],
        &["--plot", svg.to_str().unwrap()],
        "--plot",
    );
}

/// `svi list`'s "methods at any n" of a chain are the methods that run it beyond the size of
/// dense matrices: on the FPUT chain (constant mass) and the relativistic chain (a kinetic
/// energy that is not quadratic) at n = 6000 (a dense 2n × 2n matrix is past the limit),
/// each listed method takes a step, and every other method on ℝⁿ of the registry is refused
/// naming the dense matrix it would hold.
#[test]
fn the_methods_listed_for_any_size_are_the_ones_that_run_any_size() {
    let output = svi(&["list"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    for model in ["fput", "relativistic-chain"] {
        let line = text
            .lines()
            .find(|line| line.split_whitespace().next() == Some(model) && line.contains("; h = "))
            .unwrap_or_else(|| panic!("no model line for {model}:\n{text}"));
        let listed: Vec<&str> = line
            .split("methods at any n: ")
            .nth(1)
            .unwrap_or_else(|| panic!("no methods in {line}"))
            .split(", ")
            .collect();
        assert!(
            listed.contains(&"verlet") && listed.contains(&"svi-newton"),
            "{line}"
        );
        for entry in svi::method::registry::METHODS
            .iter()
            .filter(|entry| entry.space == svi::method::registry::SpaceKind::Vector)
        {
            let args = [
                "run", model, "--param", "n=6000", "--t-end", "0.1", "--method", entry.name,
            ];
            let output = svi(&args);
            let stderr = String::from_utf8_lossy(&output.stderr);
            if listed.contains(&entry.name) {
                assert!(output.status.success(), "{args:?}: {stderr}");
            } else {
                assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
                assert!(stderr.contains("would hold a dense"), "{args:?}: {stderr}");
            }
        }
    }
}
