//! The `svi` binary end to end: built-in scenes, overrides, JSON summary, CSV trajectory,
//! and error messages. References: the oscillator's exact solution q(t) = sin t (q0 = 0,
//! p0 = 1, σ = 1) and the Kepler orbit's energy −1/2 and angular momentum √(1 − e²) (the
//! default state is the pericentre of an orbit with semi-major axis 1).

use crate::common;
use common::*;

const REQUIRED: [&str; 16] = [
    "model",
    "method",
    "h",
    "steps",
    "t_end",
    "q",
    "v",
    "p",
    "energy_error_max",
    "momentum_error_max",
    "solution_error_max",
    "solution_error_final",
    "iterations",
    "seconds",
    "evaluations",
    "factorizations",
];

#[test]
fn oscillator_svi_is_spectrally_accurate() {
    let summary = json(&["run", "oscillator", "--json"]);
    for field in REQUIRED {
        assert!(summary.get(field).is_some(), "missing {field}: {summary}");
    }
    assert_eq!(summary["model"], "oscillator");
    assert_eq!(summary["method"], "svi");
    assert_eq!(summary["points"], 9);
    assert_eq!(summary["quadrature"], 18);
    assert_eq!(summary["parameters"]["sigma"], 1.0);
    assert_eq!(summary["steps"], 100);
    assert_eq!(number(&summary, "h"), 1.0);
    assert_eq!(number(&summary, "t0"), 0.0);
    assert_eq!(number(&summary, "t_end"), 100.0);
    assert!(summary["momentum_error_max"].is_null(), "no symmetry");
    let energy = number(&summary, "energy_error_max");
    let solution = number(&summary, "solution_error_final");
    assert!(energy < 1e-12, "energy error {energy:e}");
    assert!(solution < 1e-10, "solution error {solution:e}");
    let q = vector(&summary, "q");
    let p = vector(&summary, "p");
    assert!((q[0] - 100f64.sin()).abs() < 1e-10);
    assert!((p[0] - 100f64.cos()).abs() < 1e-10);
    assert!(summary["iterations"].as_u64().unwrap() >= 100);
    assert!(number(&summary, "seconds") >= 0.0);
}

#[test]
fn oscillator_sc_runs_with_velocity_coordinates() {
    let summary = json(&["run", "oscillator", "--method", "sc", "--json"]);
    for field in REQUIRED {
        assert!(summary.get(field).is_some(), "missing {field}: {summary}");
    }
    assert_eq!(summary["method"], "sc");
    assert_eq!(summary["points"], 9);
    assert!(summary["quadrature"].is_null());
    assert_eq!(summary["symplectic"], false);
    assert_eq!(summary["steps"], 100);
    assert!(summary["momentum_error_max"].is_null());
    let energy = number(&summary, "energy_error_max");
    let solution = number(&summary, "solution_error_final");
    assert!(energy.is_finite() && solution.is_finite());
    // SC drifts, but 9 CGL points at h = 1 are still far below 1e-3 over 100 periods/2π.
    assert!(energy < 1e-3 && solution < 1e-3, "{energy:e} {solution:e}");
}

#[test]
fn short_kepler_run_conserves_angular_momentum() {
    let summary = json(&["run", "kepler", "--t-end", "20", "--json"]);
    assert_eq!(summary["model"], "kepler");
    assert_eq!(summary["steps"], 100);
    assert_eq!(summary["points"], 6);
    assert_eq!(summary["quadrature"], 12);
    assert_eq!(number(&summary, "h"), 0.2);
    let momentum = number(&summary, "momentum_error_max");
    assert!(momentum < 1e-12, "momentum error {momentum:e}");
    let solution = number(&summary, "solution_error_final");
    assert!(solution < 1e-6, "solution error {solution:e}");
    assert!(number(&summary, "energy_error_max") < 1e-9);
}

#[test]
fn the_default_scene_is_kepler_with_svi() {
    let summary = json(&["run", "--t-end", "2", "--json"]);
    assert_eq!(summary["model"], "kepler");
    assert_eq!(summary["method"], "svi");
    assert_eq!(summary["parameters"]["e"], 0.5);
    assert_eq!(summary["steps"], 10);
}

#[test]
fn overrides_reach_the_run() {
    let summary = json(&[
        "run",
        "kepler",
        "--param",
        "e=0.9",
        "--h",
        "0.05",
        "--t-end",
        "10",
        "--points",
        "5",
        "--quadrature",
        "7",
        "--json",
    ]);
    assert_eq!(number(&summary, "h"), 0.05);
    assert_eq!(number(&summary, "t_end"), 10.0);
    assert_eq!(summary["points"], 5);
    assert_eq!(summary["quadrature"], 7);
    assert_eq!(summary["steps"], 200);
    assert_eq!(summary["parameters"]["e"], 0.9);
    // Pericentre of the e = 0.9 orbit: q0 = (0.1, 0), E = −1/2, M = √(1 − e²); E is the
    // difference of two terms near 10, so it is exact to a few of their ulps (2e-15).
    let energy = number(&summary, "energy_initial");
    assert!((energy + 0.5).abs() <= 8e-15, "{energy:e}");
    let (q, v, p) = (
        vector(&summary, "q"),
        vector(&summary, "v"),
        vector(&summary, "p"),
    );
    let energy = 0.5 * (v[0] * v[0] + v[1] * v[1]) - 1.0 / q[0].hypot(q[1]);
    // h = 0.05 is coarse at the e = 0.9 pericentre (r = 0.1): the energy error is
    // truncation, 8.1e-4 here, 4.7e-6 at h = 0.025 (order 8), not drift.
    assert!((energy + 0.5).abs() < 2e-3, "final energy {energy}");
    assert!((energy - number(&summary, "energy_final")).abs() < 1e-12);
    assert!(number(&summary, "energy_error_max") < 2e-3);
    let angular = q[0] * p[1] - q[1] * p[0];
    assert!(
        (angular - (1.0f64 - 0.81).sqrt()).abs() < 1e-12,
        "M = {angular}"
    );
    assert!(
        (p[0] - v[0]).abs() < 1e-12 && (p[1] - v[1]).abs() < 1e-12,
        "p = v"
    );
}

#[test]
fn diagnostics_can_be_switched_off() {
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "2",
        "--diagnostics",
        "energy",
        "--json",
    ]);
    assert!(summary["energy_error_max"].is_number());
    assert!(summary["momentum_error_max"].is_null());
    assert!(summary["solution_error_max"].is_null());
}

#[test]
fn trajectory_csv_has_the_header_and_every_kth_step() {
    let dir = Scratch::new("csv");
    let path = dir.join("oscillator.csv");
    let path_text = path.to_str().unwrap();
    let summary = json(&[
        "run",
        "oscillator",
        "--out",
        path_text,
        "--every",
        "10",
        "--json",
    ]);
    assert_eq!(summary["trajectory"]["rows"], 11);
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "t,q_q,v_q,p_q,energy");
    assert_eq!(lines.len(), 1 + 100 / 10 + 1);
    let row = |i: usize| -> Vec<f64> { lines[i].split(',').map(|x| x.parse().unwrap()).collect() };
    assert_eq!(row(1), [0.0, 0.0, 1.0, 1.0, 0.5]);
    for i in 1..lines.len() {
        let values = row(i);
        let t = 10.0 * (i - 1) as f64;
        assert_eq!(values[0], t);
        assert!((values[1] - t.sin()).abs() < 1e-10, "row {i}: {values:?}");
        assert!((values[4] - 0.5).abs() < 1e-12, "row {i}: {values:?}");
    }
    assert_eq!(row(lines.len() - 1)[1], vector(&summary, "q")[0]);
}

#[test]
fn a_trajectory_ends_with_the_last_point_when_steps_are_not_a_multiple_of_every() {
    let dir = Scratch::new("csv-tail");
    let path = dir.join("kepler.csv");
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "2.2",
        "--every",
        "5",
        "--out",
        path.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["steps"], 11);
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "t,q_q1,q_q2,v_q1,v_q2,p_q1,p_q2,energy");
    let times: Vec<f64> = lines[1..]
        .iter()
        .map(|line| line.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(times, [0.0, 1.0, 2.0, 2.2]);
}

#[test]
fn a_scene_file_sets_everything() {
    let dir = Scratch::new("file");
    let csv = dir.join("out.csv");
    let text = format!(
        "model = \"pendulum\"\n\
         [parameters]\ng = 2.0\n\
         [initial]\nt0 = 1.0\nq = [0.5]\nv = [0.0]\n\
         [method]\nname = \"sc\"\npoints = 7\n\
         [run]\nh = 0.25\nt_end = 6.0\n\
         [output]\nevery = 4\ntrajectory = \"{}\"\ndiagnostics = [\"energy\", \"solution\"]\n",
        csv.display()
    );
    let scene = scene_file("file-scene", &text);
    let summary = json(&["run", &scene.path, "--json"]);
    assert_eq!(summary["model"], "pendulum");
    assert_eq!(summary["method"], "sc");
    assert_eq!(summary["points"], 7);
    assert_eq!(summary["parameters"]["g"], 2.0);
    assert_eq!(number(&summary, "t0"), 1.0);
    assert_eq!(summary["steps"], 20);
    assert!(number(&summary, "solution_error_max") < 1e-6);
    assert_eq!(summary["trajectory"]["rows"], 6);
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 7);
}

#[test]
fn the_human_summary_is_a_short_aligned_block() {
    let output = svi(&["run", "oscillator"]);
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    for label in [
        "model",
        "method",
        "step h",
        "time",
        "wall time",
        "work",
        "final q",
        "final v",
        "final p",
        "energy error",
        "momentum error",
        "solution error",
    ] {
        assert!(
            text.lines()
                .any(|line| line.starts_with(label) && line.len() > 16),
            "{label}: {text}"
        );
    }
    assert!(
        text.contains("svi, 9 CGL points, 18 Gauss points; order 16"),
        "{text}"
    );
    assert!(text.contains("momentum error  n/a"), "{text}");
}

#[test]
fn list_names_scenes_and_models() {
    let output = svi(&["list"]);
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    for name in [
        "oscillator",
        "kepler",
        "pendulum",
        "spring-pendulum",
        "double-pendulum",
    ] {
        assert!(text.contains(name), "{name}: {text}");
    }
    assert!(text.contains("e = 0.5"), "{text}");
    // Every name stands apart from its description, the longest included.
    for name in svi_models::LOCAL_MODEL_NAMES
        .iter()
        .chain(svi_models::MODEL_NAMES)
    {
        assert!(text.contains(&format!("  {name} ")), "{name}: {text}");
    }
}

#[test]
fn plain_svi_prints_help() {
    let output = svi(&[]);
    let text = String::from_utf8_lossy(&output.stderr).into_owned()
        + &String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("Usage"), "{text}");
    assert!(text.contains("run"), "{text}");
}

#[test]
fn unknown_scenes_and_models_are_named() {
    let stderr = failure(&["run", "keppler"]);
    assert!(
        stderr.contains("'keppler'") && stderr.contains("oscillator, kepler"),
        "{stderr}"
    );
    let missing = std::env::temp_dir().join("svi-cli-no-such-dir/scene.toml");
    let stderr = failure(&["run", missing.to_str().unwrap()]);
    assert!(stderr.contains("cannot read scene file"), "{stderr}");
    let scene = scene_file("unknown-model", "model = \"kepler3\"\n");
    let stderr = failure(&["run", &scene.path]);
    assert!(stderr.contains("unknown model 'kepler3'"), "{stderr}");
    assert!(stderr.contains("double-pendulum"), "{stderr}");
}

#[test]
fn malformed_toml_names_the_line() {
    let scene = scene_file(
        "malformed",
        "model = \"kepler\"\n[run]\nh = 0.1\nt_end = \n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(stderr.contains("cannot parse scene"), "{stderr}");
    assert!(stderr.contains("line 4"), "{stderr}");
    let scene = scene_file("unknown-field", "model = \"kepler\"\nsteps = 3\n");
    let stderr = failure(&["run", &scene.path]);
    assert!(
        stderr.contains("line 2") && stderr.contains("steps"),
        "{stderr}"
    );
}

#[test]
fn invalid_step_horizon_and_options_are_rejected() {
    for (args, needle) in [
        // The library prints numbers with `{:?}` (1e-300, never 300 digits; issue #14).
        (&["--h", "0"][..], "invalid h: 0.0 must be positive"),
        (&["--h", "-1"], "invalid h: -1.0 must be positive"),
        (&["--h", "nan"], "invalid h"),
        (&["--points", "1"], "invalid points"),
        (&["--quadrature", "0"], "invalid quadrature"),
        (
            &["--t-end", "0"],
            "invalid t_end: the horizon 0.0 is not after the start 0.0",
        ),
        (&["--every", "0", "--out", "x.csv"], "invalid every"),
        (&["--every", "3"], "no trajectory file"),
        (
            &["--method", "sc", "--quadrature", "7"],
            "quadrature is an option of svi",
        ),
    ] {
        let mut all = vec!["run", "oscillator"];
        all.extend_from_slice(args);
        let stderr = failure(&all);
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}

#[test]
fn invalid_parameters_are_rejected() {
    let stderr = failure(&["run", "kepler", "--param", "e=1.5"]);
    assert!(
        stderr.contains("invalid e") && stderr.contains("[0, 1)"),
        "{stderr}"
    );
    let stderr = failure(&["run", "kepler", "--param", "bogus=1"]);
    assert!(
        stderr.contains("invalid bogus") && stderr.contains("known: e"),
        "{stderr}"
    );
    let stderr = failure(&["run", "kepler", "--param", "e"]);
    assert!(stderr.contains("malformed parameter 'e'"), "{stderr}");
    let stderr = failure(&["run", "kepler", "--param", "e=x"]);
    assert!(stderr.contains("'x' is not a number"), "{stderr}");
    let stderr = failure(&["run", "kepler", "--method", "rk45"]);
    assert!(stderr.contains("rk45"), "{stderr}");
}

#[test]
fn invalid_initial_states_are_rejected() {
    let scene = scene_file("dimension", "model = \"kepler\"\n[initial]\nq = [1.0]\n");
    let stderr = failure(&["run", &scene.path]);
    assert!(
        stderr.contains("initial.q has 1 components, but model 'kepler' has dimension 2"),
        "{stderr}"
    );
    let scene = scene_file(
        "nan",
        "model = \"oscillator\"\n[initial]\nq = [nan]\np = [1.0]\n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(
        stderr.contains("initial position[0]") && stderr.contains("NaN"),
        "{stderr}"
    );
    let scene = scene_file(
        "both",
        "model = \"oscillator\"\n[initial]\nq = [0.0]\nv = [1.0]\np = [1.0]\n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(stderr.contains("both v and p"), "{stderr}");
}

#[test]
fn classic_methods_are_selected_by_flag() {
    // The paper's oscillator scene at h = 0.1 (T = 10): q(t) = sin t.
    for (method, order, bound) in [
        ("symplectic-euler", 1, 0.1),
        ("symplectic-euler-adjoint", 1, 0.1),
        ("midpoint", 2, 1e-2),
        ("verlet", 2, 1e-2),
        ("trapezoid", 2, 1e-2),
    ] {
        let summary = json(&[
            "run",
            "oscillator",
            "--method",
            method,
            "--h",
            "0.1",
            "--t-end",
            "10",
            "--json",
        ]);
        for field in REQUIRED {
            assert!(summary.get(field).is_some(), "missing {field}: {summary}");
        }
        assert_eq!(summary["method"], method);
        assert!(summary["points"].is_null(), "{summary}");
        assert!(summary["quadrature"].is_null(), "{summary}");
        assert_eq!(summary["order"], order);
        assert_eq!(summary["symplectic"], true);
        assert_eq!(summary["steps"], 100);
        let solution = number(&summary, "solution_error_final");
        assert!(solution < bound, "{method}: {solution:e}");
        let q = vector(&summary, "q");
        assert!((q[0] - 10f64.sin()).abs() < bound, "{method}: {q:?}");
    }
    // Störmer–Verlet is explicit on the (constant-mass) oscillator.
    let summary = json(&["run", "oscillator", "--method", "verlet", "--json"]);
    assert_eq!(summary["iterations"], 0);
    assert_eq!(summary["evaluations"], 101);
    assert_eq!(summary["factorizations"], 0);
}

#[test]
fn the_simplified_newton_method_factorises_less_often_than_it_steps() {
    // The double pendulum's mass matrix depends on the angle between the arms: `svi` solves
    // its stage equations by the simplified Newton method, `svi-newton` factorises the
    // exact Jacobian at every iteration. 2000 steps of h = 0.01 (measured: 686
    // factorisations against 4000); the final states agree to round-off.
    let kept = json(&["run", "double-pendulum", "--method", "svi", "--json"]);
    let exact = json(&["run", "double-pendulum", "--method", "svi-newton", "--json"]);
    assert_eq!(kept["steps"], 2000);
    let factorizations = kept["factorizations"].as_u64().unwrap();
    assert!(2 * factorizations < 2000, "{factorizations} factorisations");
    assert_eq!(exact["factorizations"], exact["iterations"]);
    let (q, q_exact) = (vector(&kept, "q"), vector(&exact, "q"));
    for (a, b) in q.iter().zip(&q_exact) {
        assert!((a - b).abs() <= 1e-11, "{q:?} {q_exact:?}");
    }
}

#[test]
fn a_scene_file_selects_a_classic_method() {
    let scene = scene_file(
        "midpoint",
        "model = \"pendulum\"\n[method]\nname = \"midpoint\"\npoints = 7\n\
         [run]\nh = 0.05\nt_end = 5\n",
    );
    let summary = json(&["run", &scene.path, "--json"]);
    assert_eq!(summary["method"], "midpoint");
    // `points` in a scene is ignored by a method without CGL points.
    assert!(summary["points"].is_null());
    assert_eq!(summary["steps"], 100);
    assert!(number(&summary, "solution_error_final") < 1e-3);
    assert!(number(&summary, "energy_error_max") < 1e-3);
}

#[test]
fn the_damped_oscillator_scene_reports_the_solution_error() {
    let summary = json(&["run", "damped-oscillator", "--json"]);
    assert_eq!(summary["model"], "damped-oscillator");
    assert_eq!(summary["parameters"]["zeta"], 0.1);
    assert_eq!(summary["steps"], 500);
    assert!(number(&summary, "solution_error_final") < 1e-12);
    // The friction removes the energy: E(50) ≈ E(0) e^{−5}.
    let (initial, last) = (
        number(&summary, "energy_initial"),
        number(&summary, "energy_final"),
    );
    assert_eq!(initial, 0.5);
    assert!(last < 0.01 * initial && last > 0.0, "{last}");
    for method in ["verlet", "midpoint", "sc", "symplectic-euler"] {
        let summary = json(&["run", "damped-oscillator", "--method", method, "--json"]);
        let solution = number(&summary, "solution_error_final");
        assert!(solution < 0.05, "{method}: {solution:e}");
    }
    // Over-damped by a parameter.
    let summary = json(&[
        "run",
        "damped-oscillator",
        "--param",
        "zeta=2",
        "--method",
        "trapezoid",
        "--json",
    ]);
    assert!(number(&summary, "solution_error_final") < 1e-3);
    for scene in ["damped-pendulum", "driven-oscillator"] {
        let summary = json(&["run", scene, "--t-end", "10", "--json"]);
        assert_eq!(summary["model"], scene);
    }
}

#[test]
fn classic_methods_reject_spectral_options() {
    let stderr = failure(&["run", "oscillator", "--method", "verlet", "--points", "4"]);
    assert!(
        stderr.contains(
            "points is an option of svi, svi-newton, svi-h, sc, sc-h and multiscale, not of verlet"
        ),
        "{stderr}"
    );
    let stderr = failure(&["run", "kepler", "--method", "midpoint", "--quadrature", "4"]);
    assert!(
        stderr.contains("quadrature is an option of svi, svi-newton and svi-h, not of midpoint"),
        "{stderr}"
    );
    let stderr = failure(&["run", "kepler", "--method", "leapfrog"]);
    assert!(stderr.contains("verlet"), "{stderr}");
    let text = String::from_utf8(svi(&["list"]).stdout).unwrap();
    for name in ["damped-oscillator", "damped-pendulum", "driven-oscillator"] {
        assert!(text.contains(name), "{name}: {text}");
    }
}

#[test]
fn output_times_report_dense_states_at_those_times() {
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "10",
        "--h",
        "0.1",
        "--points",
        "7",
        "--quadrature",
        "6",
        "--output-times",
        "0.05,3.33,9.99,10",
        "--json",
    ]);
    let outputs = summary["outputs"].as_array().unwrap();
    let times: Vec<f64> = outputs.iter().map(|o| number(o, "t")).collect();
    assert_eq!(times, [0.05, 3.33, 9.99, 10.0]);
    // Every state read off a step polynomial lies on the orbit: energy −1/2.
    for output in outputs {
        let v = vector(output, "v");
        let q = vector(output, "q");
        let energy = 0.5 * (v[0] * v[0] + v[1] * v[1]) - 1.0 / q[0].hypot(q[1]);
        assert!((energy + 0.5).abs() < 1e-7, "{output}");
    }
    assert_eq!(vector(&summary, "q"), vector(&outputs[3], "q"));
    assert_eq!(number(&summary, "steps"), 100.0);
    assert!(number(&summary, "solution_error_final") < 1e-8);
}

#[test]
fn degree_adaptivity_meets_the_tolerance_with_varying_points() {
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "62.83",
        "--h",
        "0.5",
        "--points",
        "5",
        "--quadrature",
        "4",
        "--adapt",
        "degree",
        "--tol",
        "1e-9",
        "--json",
    ]);
    assert_eq!(summary["adapt"], "degree");
    assert!(number(&summary, "solution_error_final") < 1e-8, "{summary}");
    let used = summary["adaptivity"]["points_used"].as_array().unwrap();
    assert!(used.len() >= 3, "{summary}");
}

#[test]
fn step_adaptivity_takes_small_steps_only_at_the_close_approach() {
    let summary = json(&[
        "run", "kepler", "--param", "e=0.9", "--t-end", "25.13", "--adapt", "step", "--tol",
        "1e-10", "--json",
    ]);
    assert!(number(&summary, "solution_error_final") < 1e-8, "{summary}");
    let adaptivity = &summary["adaptivity"];
    assert!(number(adaptivity, "max_step") > 20.0 * number(adaptivity, "min_step"));
    // Step doubling conserves the angular momentum step by step.
    assert!(number(&summary, "momentum_error_max") < 1e-13);
}

#[test]
fn bad_tolerances_and_output_times_are_rejected() {
    for (args, message) in [
        (&["--adapt", "step", "--tol", "0"][..], "invalid tol"),
        (&["--adapt", "step", "--tol", "nan"][..], "invalid tol"),
        (
            &["--adapt", "degree", "--tol", "1e-20"][..],
            "double precision",
        ),
        (&["--output-times", "1,0.5"][..], "increase strictly"),
        (&["--output-times", "0.5,3000"][..], "outside the span"),
        (
            &["--adapt", "degree", "--tol", "1e-6", "--method", "verlet"][..],
            "no polynomial degree",
        ),
        (&["--adapt", "sometimes"][..], "invalid value"),
    ] {
        let mut all = vec!["run", "kepler"];
        all.extend_from_slice(args);
        let stderr = failure(&all);
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
}

#[test]
fn bench_measures_given_step_counts_and_tolerances() {
    let dir = Scratch::new("bench-steps");
    let out = dir.0.to_str().unwrap();
    let common = [
        "bench",
        "oscillator",
        "--t-end",
        "10",
        "--batches",
        "1",
        "--min-batch",
        "0",
        "--out-dir",
        out,
    ];
    let args: Vec<&str> = common
        .iter()
        .copied()
        .chain([
            "--methods",
            "svi:3/2,dop853",
            "--steps",
            "20,40",
            "--tolerances",
            "1e-8",
        ])
        .collect();
    let output = svi(&args);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("oscillator.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let firsts: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        firsts,
        [("svi:3/2", "2e1"), ("svi:3/2", "4e1"), ("dop853", "1e-8")]
    );
    // Order 4: doubling the steps divides the final error by about 16.
    let error = |row: &Vec<&str>| row[4].parse::<f64>().unwrap();
    let ratio = error(&rows[0]) / error(&rows[1]);
    assert!(ratio > 12.0 && ratio < 20.0, "{ratio}");

    for bad in [["--steps", "0"], ["--tolerances", "0"], ["--steps", "x"]] {
        let args: Vec<&str> = common.iter().copied().chain(bad).collect();
        failure(&args);
    }
}

/// The rows of the one CSV file `svi bench ARGS --out-dir DIR` wrote (columns as in
/// `bench_measures_given_step_counts_and_tolerances`).
fn bench_rows(name: &str, args: &[&str]) -> Vec<Vec<String>> {
    let dir = Scratch::new(name);
    let out = dir.0.to_str().unwrap();
    let mut all = vec!["bench"];
    all.extend_from_slice(args);
    all.extend(["--batches", "1", "--min-batch", "0", "--out-dir", out]);
    let output = svi(&all);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let csv = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .find(|path| path.extension().is_some_and(|e| e == "csv"))
        .unwrap_or_else(|| panic!("no CSV: {stderr}"));
    std::fs::read_to_string(csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

/// Chains and Lagrangians written as text are measured against the resolved reference run:
/// their fixed-step methods reach their orders, and Kepler written as text has the zoo
/// model's errors (the reference run against the exact solution); a peer is refused.
#[test]
fn bench_measures_chains_and_text_models_against_the_reference_run() {
    let error = |row: &Vec<String>| row[4].parse::<f64>().unwrap();
    let steps = [
        "--methods",
        "svi:3/2",
        "--steps",
        "100,200",
        "--t-end",
        "20",
    ];
    let text = bench_rows("bench-text", &[&["kepler-text"][..], &steps].concat());
    let zoo = bench_rows("bench-zoo", &[&["kepler"][..], &steps].concat());
    assert_eq!(text.len(), 2);
    for (a, b) in text.iter().zip(&zoo) {
        assert!(
            (error(a) / error(b) - 1.0).abs() < 1e-3,
            "{a:?} against {b:?}"
        );
    }
    let ratio = error(&text[0]) / error(&text[1]);
    assert!(ratio > 12.0 && ratio < 20.0, "order 4: {ratio}");
    let chain = bench_rows(
        "bench-chain",
        &[
            "fput",
            "--param",
            "n=16",
            "--param",
            "beta=0.5",
            "--t-end",
            "5",
            "--methods",
            "verlet",
            "--steps",
            "50,100",
        ],
    );
    let ratio = error(&chain[0]) / error(&chain[1]);
    assert!(ratio > 3.5 && ratio < 4.5, "order 2: {ratio}");
    bad_input(
        &["bench", "fput"],
        &["--methods", "dop853"],
        "needs a model of fixed size",
    );
}

#[test]
fn one_method_grammar_on_the_command_line_and_in_scenes() {
    // `--method svi:7/6` is `--method svi --points 7 --quadrature 6`, and the scene's
    // `name = "svi:7/6"` is `name = "svi"` with `points = 7` and `quadrature = 6`.
    let args = ["run", "kepler", "--t-end", "4", "--json"];
    let run = |extra: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(extra);
        json(&all)
    };
    let written = run(&["--method", "svi:7/6"]);
    let sugar = run(&["--method", "svi", "--points", "7", "--quadrature", "6"]);
    let scene_points = scene_file(
        "svi-7-6",
        "model = \"kepler\"\n[parameters]\ne = 0.5\n[method]\nname = \"svi\"\npoints = 7\n\
         quadrature = 6\n[run]\nh = 0.2\nt_end = 4\n",
    );
    let in_file = json(&["run", &scene_points.path, "--json"]);
    let scene_name = scene_file(
        "svi-7-6-name",
        "model = \"kepler\"\n[parameters]\ne = 0.5\n[method]\nname = \"svi:7/6\"\n\
         [run]\nh = 0.2\nt_end = 4\n",
    );
    let in_name = json(&["run", &scene_name.path, "--json"]);
    for summary in [&written, &sugar, &in_file, &in_name] {
        // The JSON keeps the method's name; the options are their own fields.
        assert_eq!(summary["method"], "svi", "{summary}");
        assert_eq!(summary["points"], 7, "{summary}");
        assert_eq!(summary["quadrature"], 6, "{summary}");
        assert_eq!(summary["order"], 12, "{summary}");
        assert_eq!(summary["q"], written["q"], "{summary}");
    }
    // Flags apply on top of the written method; the scene's points give way to it.
    let summary = run(&["--method", "svi:7/6", "--points", "5"]);
    assert_eq!(
        (&summary["points"], &summary["quadrature"]),
        (&5.into(), &6.into())
    );
    let summary = run(&["--method", "sc:9"]);
    assert_eq!(
        (&summary["points"], &summary["order"]),
        (&9.into(), &8.into())
    );
    // The scene's points carry over to a method written without them.
    let summary = json(&[
        "run",
        "oscillator",
        "--method",
        "svi",
        "--t-end",
        "2",
        "--json",
    ]);
    assert_eq!(
        (&summary["points"], &summary["quadrature"]),
        (&9.into(), &18.into())
    );

    for (extra, needle) in [
        (&["--method", "midpoint:3"][..], "midpoint takes no options"),
        (&["--method", "sc:9/4"], "no Gauss points"),
        (&["--method", "svi:x"], "'svi:x'"),
        (&["--method", "svi:1"], "1 CGL points"),
        (
            &["--method", "lie-svi"],
            "'lie-svi' integrates models on Lie groups, not models on ℝᴺ",
        ),
        (&["--method", "lie-svi", "--points", "3"], "'lie-svi'"),
        (
            &["--method", "verlet", "--points", "3"],
            "--points is an option of svi, svi-newton, svi-h, sc, sc-h and multiscale, not of verlet",
        ),
    ] {
        let mut all = vec!["run", "kepler"];
        all.extend_from_slice(extra);
        let stderr = failure(&all);
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
    }
    let scene = scene_file(
        "lie-svi-on-kepler",
        "model = \"kepler\"\n[method]\nname = \"lie-svi:3/3\"\n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(
        stderr.contains("'lie-svi:3/3' integrates models on Lie groups"),
        "{stderr}"
    );
    let scene = scene_file(
        "bad-name",
        "model = \"kepler\"\n[method]\nname = \"svi:6/\"\n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(
        stderr.contains("'svi:6/'") && stderr.contains("line 3"),
        "{stderr}"
    );
}

#[test]
fn stability_and_bench_take_the_same_grammar() {
    let output = svi(&["stability", "--method", "svi:7/6", "--z", "1,2"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = String::from_utf8(output.stdout).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    for (method, needle) in [("lie-svi", "'lie-svi'"), ("rk45", "unknown method 'rk45'")] {
        let stderr = failure(&["stability", "--method", method, "--z", "1"]);
        assert!(stderr.contains(needle), "{stderr}");
    }

    let dir = Scratch::new("bench-grammar");
    let out = dir.0.to_str().unwrap();
    let output = svi(&[
        "bench",
        "kepler",
        "--methods",
        "svi:7/6,sc:9,verlet",
        "--steps",
        "2000",
        "--batches",
        "1",
        "--min-batch",
        "0",
        "--t-end",
        "20",
        "--out-dir",
        out,
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("kepler.csv")).unwrap();
    let methods: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap())
        .collect();
    assert_eq!(methods, ["svi:7/6", "sc:9", "verlet"]);
    for (methods, needle) in [
        ("svi:7/6,rk45", "unknown method 'rk45'"),
        ("midpoint:3", "midpoint takes no options"),
        ("lie-svi", "'lie-svi' integrates models on Lie groups"),
    ] {
        let stderr = failure(&[
            "bench",
            "kepler",
            "--methods",
            methods,
            "--steps",
            "10",
            "--out-dir",
            out,
        ]);
        assert!(stderr.contains(needle), "{methods}: {stderr}");
    }
    let stderr = failure(&["bench", "kepler", "--methods", "rk45", "--out-dir", out]);
    assert!(stderr.contains("dop853, dopri5"), "{stderr}");
}

#[test]
fn diagnostics_none_computes_no_diagnostic() {
    let vector = [
        "energy_error_max",
        "momentum_error_max",
        "solution_error_max",
    ];
    let rigid = [
        "energy_error_max",
        "momentum_error_max",
        "momentum_error_relative",
        "invariant_error_max",
        "orthogonality_error_max",
    ];
    for (scene, fields) in [("kepler", &vector[..]), ("rigid-body", &rigid[..])] {
        let args = [
            "run",
            scene,
            "--t-end",
            "20",
            "--diagnostics",
            "none",
            "--json",
        ];
        let summary = json(&args);
        for field in fields {
            assert!(summary[field].is_null(), "{scene} {field}: {summary}");
        }
    }
    // The final state is measured once, not per step.
    let args = [
        "run",
        "rigid-body",
        "--t-end",
        "5",
        "--diagnostics",
        "none",
        "--json",
    ];
    assert!(number(&json(&args), "orthogonality_error_final") <= 1e-13);
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "20",
        "--diagnostics",
        "none",
        "--json",
    ]);
    // The same run: the same final state and work as with every diagnostic.
    let all = json(&["run", "kepler", "--t-end", "20", "--json"]);
    for field in ["q", "p", "steps", "iterations", "evaluations"] {
        assert_eq!(summary[field], all[field], "{field}");
    }
    let scene = scene_file(
        "no-diagnostics",
        "model = \"oscillator\"\n[output]\ndiagnostics = [\"none\"]\n",
    );
    let summary = json(&["run", &scene.path, "--json"]);
    assert!(summary["energy_error_max"].is_null(), "{summary}");
    let stderr = failure(&["run", "kepler", "--diagnostics", "energy,none"]);
    assert!(stderr.contains("--diagnostics"), "{stderr}");
}

#[test]
fn options_the_scene_cannot_use_are_errors_with_status_2() {
    for (args, needle) in [
        (&["--tol", "1e-9"][..], "--tol (run.tol)"),
        (
            &["--adapt", "degree", "--tol", "1e-6", "--method", "verlet"],
            "--adapt degree (run.adapt): method verlet has no polynomial degree",
        ),
        (
            &[
                "--adapt",
                "step",
                "--tol",
                "1e-9",
                "--recovery",
                "halve-step",
            ],
            "--recovery (run.recovery)",
        ),
        (&["--adapt", "step", "--tol", "1e-9", "--h", "0.1"], "--h: "),
        (
            &["--output-times", "1", "--out", "x.csv", "--every", "2"],
            "--every (output.every)",
        ),
        (
            &["--form", "full"],
            "--form: applies to scenes on Lie groups only",
        ),
        (
            &["--method", "verlet", "--points", "4"],
            "--points is an option",
        ),
        (&["--param", "bogus=1"], "invalid bogus"),
        (&["--h", "0"], "invalid h"),
        (&["--diagnostics", "entropy"], "invalid value 'entropy'"),
    ] {
        let mut all = vec!["run", "kepler"];
        all.extend_from_slice(args);
        let stderr = failure(&all);
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert_eq!(svi(&all).status.code(), Some(2), "{args:?}: {stderr}");
    }
    for name in ["keppler", "kepler.toml"] {
        assert_eq!(svi(&["run", name]).status.code(), Some(2), "{name}");
    }
    let scene = scene_file(
        "tol-without-adapt",
        "model = \"kepler\"\n[run]\ntol = 1e-9\n",
    );
    let stderr = failure(&["run", &scene.path]);
    assert!(stderr.contains("--tol (run.tol)"), "{stderr}");
    // A run that starts and fails exits with status 1.
    let output = svi(&["run", "kepler-recovery", "--recovery", "none"]);
    assert_eq!(output.status.code(), Some(1));
}

#[test]
fn the_help_states_the_exit_statuses_and_diagnostics_none() {
    let text = String::from_utf8(svi(&["--help"]).stdout).unwrap();
    assert!(text.contains("Exit status: 0"), "{text}");
    assert!(text.contains("2 for bad input"), "{text}");
    let text = String::from_utf8(svi(&["run", "--help"]).stdout).unwrap();
    assert!(
        text.contains("none computes no per-step diagnostic"),
        "{text}"
    );
}

/// Issue #18's scene: the stiff spring pendulum (spring period 0.063) by the multiscale VI at
/// h = 0.31, about five spring periods per step. Reference: the same scene resolved by SVI
/// 6/5 at h = 5e-4 (126 steps per spring period). The slow angle at T = 10 agrees to 1e-6 (the
/// issue asks 1e-3; measured 8e-9), and the energy error over T = 1000 (3226 steps) is no
/// larger than over the first T = 10 to within 10 % (bounded: no drift; measured 1 %).
#[test]
fn the_multiscale_scene_steps_over_five_spring_periods_with_the_slow_angle_right() {
    let resolved = json(&[
        "run",
        "stiff-spring-pendulum",
        "--t-end",
        "10",
        "--h",
        "5e-4",
        "--json",
    ]);
    let coarse = json(&[
        "run",
        "stiff-spring-pendulum-multiscale",
        "--t-end",
        "10",
        "--json",
    ]);
    assert_eq!(coarse["method"], "multiscale");
    assert_eq!(coarse["h"], 0.31);
    let angle = |summary: &serde_json::Value| vector(summary, "q")[1];
    assert!(
        (angle(&coarse) - angle(&resolved)).abs() < 1e-6,
        "θ {} against {}",
        angle(&coarse),
        angle(&resolved)
    );
    let long = json(&["run", "stiff-spring-pendulum-multiscale", "--json"]);
    assert_eq!(long["steps"], 3226);
    let (short_error, long_error) = (
        number(&coarse, "energy_error_max"),
        number(&long, "energy_error_max"),
    );
    assert!(short_error < 1e-7 * number(&coarse, "energy_scale"));
    assert!(
        long_error <= 1.1 * short_error,
        "{long_error:e} after T = 1000 against {short_error:e}"
    );
}

#[test]
fn reparam_takes_fixed_steps_in_tau_and_follows_the_exact_orbit() {
    // Ten periods of Kepler e = 0.9 (the exact orbit by Kepler's equation), g = |q|.
    let summary = json(&[
        "run",
        "kepler",
        "--param",
        "e=0.9",
        "--t-end",
        "62.83",
        "--adapt",
        "reparam",
        "--monitor",
        "sundman:1",
        "--h",
        "0.1",
        "--points",
        "7",
        "--quadrature",
        "6",
        "--json",
    ]);
    assert_eq!(summary["adapt"], "reparam");
    assert_eq!(summary["monitor"], "sundman:1");
    assert!(summary["tol"].is_null(), "{summary}");
    assert_eq!(number(&summary, "t_end"), 62.83);
    assert!(
        number(&summary, "solution_error_final") < 1e-10,
        "{summary}"
    );
    assert!(number(&summary, "energy_error_max") < 1e-11, "{summary}");
    assert!(number(&summary, "momentum_error_max") < 1e-12, "{summary}");
    // dt = |q| dτ: steps of 0.1 · 0.1 at pericentre, 0.1 · 1.9 at apocentre.
    let adaptivity = &summary["adaptivity"];
    assert!(number(adaptivity, "max_step") > 15.0 * number(adaptivity, "min_step"));
    // The same from a scene file.
    let scene = scene_file(
        "reparam",
        "model = \"kepler\"\n[parameters]\ne = 0.9\n[method]\nname = \"svi:7/6\"\n\
         [run]\nh = 0.1\nt_end = 62.83\nadapt = \"reparam\"\nmonitor = \"sundman:1\"\n",
    );
    let from_scene = json(&["run", &scene.path, "--json"]);
    assert_eq!(from_scene["q"], summary["q"]);
}

#[test]
fn the_potential_monitor_with_a_composition_is_explicit_and_keeps_the_orbit() {
    // Kepler e = 0.9 over 318 orbits (#17): Kahan–Li 8 on the logarithmic Hamiltonian,
    // measured 6.7e-10 with the energy and angular momentum at round-off and no Newton.
    let summary = json(&[
        "run",
        "kepler",
        "--param",
        "e=0.9",
        "--t-end",
        "2000",
        "--adapt",
        "reparam",
        "--monitor",
        "potential",
        "--method",
        "kahan-li8",
        "--h",
        "0.2",
        "--json",
    ]);
    assert_eq!(summary["monitor"], "potential");
    assert_eq!(summary["method"], "kahan-li8");
    assert_eq!(summary["order"], 8);
    assert!(number(&summary, "solution_error_final") < 1e-9, "{summary}");
    assert!(number(&summary, "energy_error_max") < 1e-12, "{summary}");
    assert!(number(&summary, "momentum_error_max") < 1e-13, "{summary}");
    assert_eq!(number(&summary, "iterations"), 0.0);
    // 17 gradients per τ-step (the last step's size found by Newton adds a few steps).
    let (steps, evaluations) = (number(&summary, "steps"), number(&summary, "evaluations"));
    assert!(evaluations < 17.0 * (steps + 10.0), "{summary}");
    // A potential that is not below zero: a typed error naming U.
    bad_input(
        &["run", "oscillator"],
        &[
            "--adapt",
            "reparam",
            "--monitor",
            "potential",
            "--method",
            "verlet",
        ],
        "U(q)",
    );
}

#[test]
fn reparam_options_that_do_not_apply_are_bad_input() {
    for (scene, args, needle) in [
        (
            "kepler",
            &["--adapt", "reparam", "--monitor", "sundman:x"][..],
            "monitor",
        ),
        (
            "kepler",
            &["--adapt", "reparam", "--monitor", "r^2"][..],
            "unknown monitor",
        ),
        (
            "kepler",
            &["--monitor", "sundman:1"][..],
            "--monitor (run.monitor)",
        ),
        (
            "kepler",
            &["--adapt", "reparam", "--tol", "1e-9"][..],
            "--tol (run.tol)",
        ),
        (
            "rigid-body",
            &["--adapt", "reparam"][..],
            "--adapt reparam (run.adapt)",
        ),
        ("damped-oscillator", &["--adapt", "reparam"][..], "unforced"),
        ("driven-oscillator", &["--adapt", "reparam"][..], "unforced"),
    ] {
        bad_input(&["run", scene], args, needle);
    }
}

#[test]
fn sem_fits_each_step_to_discrete_energy_conservation() {
    // Ten periods of Kepler e = 0.5 by the midpoint SEM integrator (svi 2 points, 1 Gauss
    // point) from h₀ = 0.01: the steps follow the orbit (measured 2.8e-3 … 5.1e-2 in 2231
    // steps, no fallback), the energy error stays that of the midpoint rule (measured
    // 1.5e-5 at the end) and the angular momentum is conserved.
    let summary = json(&[
        "run",
        "kepler",
        "--param",
        "e=0.5",
        "--t-end",
        "62.83",
        "--adapt",
        "sem",
        "--h",
        "0.01",
        "--points",
        "2",
        "--quadrature",
        "1",
        "--json",
    ]);
    assert_eq!(summary["adapt"], "sem");
    assert!(summary["tol"].is_null(), "{summary}");
    assert_eq!(number(&summary, "t_end"), 62.83);
    let adaptivity = &summary["adaptivity"];
    assert_eq!(adaptivity["unmet"], 0, "{summary}");
    assert!(
        number(adaptivity, "max_step") > 10.0 * number(adaptivity, "min_step"),
        "{summary}"
    );
    assert!(number(&summary, "energy_error_max") < 1e-3, "{summary}");
    assert!(number(&summary, "momentum_error_max") < 1e-12, "{summary}");
}

#[test]
fn sem_options_that_do_not_apply_are_bad_input() {
    for (scene, args, needle) in [
        (
            "kepler",
            &["--adapt", "sem", "--tol", "1e-9"][..],
            "--tol (run.tol)",
        ),
        (
            "kepler",
            &["--adapt", "sem", "--method", "verlet"][..],
            "--adapt sem (run.adapt)",
        ),
        (
            "rigid-body",
            &["--adapt", "sem"][..],
            "--adapt sem (run.adapt)",
        ),
        ("fput", &["--adapt", "sem"][..], "--adapt sem (run.adapt)"),
        ("driven-oscillator", &["--adapt", "sem"][..], "sem"),
    ] {
        bad_input(&["run", scene], args, needle);
    }
}
