//! Scenes with holonomic constraints (`constraints = [...]`) through the binary: the built-in
//! constrained scenes stay on their constraints and conserve energy, the Cartesian double
//! pendulum is the zoo's double pendulum in its angles, the trajectory carries the
//! multipliers on request, initial data off the constraints is projected with a warning, a
//! step too large for Newton's method is a failed run, and the help and the guide list every
//! constrained method of the library.

use crate::common;
use common::*;

use serde_json::Value;
use svi::method::constrained::ConstrainedMethod;

/// `svi run SCENE ARGS --json`, which must succeed.
fn constrained(scene: &str, args: &[&str]) -> Value {
    let mut all = vec!["run", scene, "--json"];
    all.extend(args);
    json(&all)
}

/// A scene's constraint diagnostics: |g| and |G q̇| over the run.
fn on_constraints(summary: &Value) -> (f64, f64) {
    (
        number(summary, "constraint_error_max"),
        number(summary, "velocity_constraint_error_max"),
    )
}

#[test]
fn the_built_in_constrained_scenes_stay_on_their_constraints_and_keep_energy() {
    // (scene, constraints, largest energy error accepted: measured 4.2e-4 (RATTLE at
    // h = 0.01 over T = 100: the oscillation of the modified energy, no drift), 1.8e-14 and
    // 2.6e-7).
    for (scene, count, energy) in [
        ("spherical-pendulum", 1, 5e-4),
        ("double-pendulum-cartesian", 2, 1e-12),
        ("four-bar-linkage", 3, 1e-6),
    ] {
        let summary = constrained(scene, &[]);
        let (g, rate) = on_constraints(&summary);
        let energy_error = number(&summary, "energy_error_max");
        println!("{scene}: |g| {g:.1e}, |G q'| {rate:.1e}, energy error {energy_error:.2e}");
        assert_eq!(summary["status"], "ok", "{scene}");
        assert_eq!(summary["model"], "text", "{scene}");
        assert_eq!(summary["constraints"].as_array().unwrap().len(), count);
        assert!(g <= 1e-12 && rate <= 1e-12, "{scene}: {g:e}, {rate:e}");
        assert!(energy_error <= energy, "{scene}: {energy_error:e}");
        assert_eq!(summary["warnings"], serde_json::json!([]), "{scene}");
        assert!(number(&summary, "initial_q_moved") < 1e-15, "{scene}");
    }
    // Rotations about the vertical respect the sphere: their momentum is kept to round-off.
    let spherical = constrained("spherical-pendulum", &[]);
    assert!(number(&spherical, "momentum_error_max") <= 1e-13);
}

#[test]
fn the_four_bar_linkages_crank_turns_full_circles() {
    let scratch = Scratch::new("four-bar");
    let out = scratch.join("four-bar.csv");
    let out = out.to_str().unwrap();
    constrained("four-bar-linkage", &["--out", out, "--every", "10"]);
    let rows = parse_csv(&std::fs::read_to_string(out).unwrap());
    let mut turned = 0.0;
    let angle = |row: &std::collections::HashMap<String, String>| {
        cell(row, "q_yb").atan2(cell(row, "q_xb"))
    };
    for pair in rows.windows(2) {
        let step = angle(&pair[1]) - angle(&pair[0]);
        turned +=
            (step + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    }
    let turns = turned / std::f64::consts::TAU;
    println!("four-bar linkage: the crank turned {turns:.2} times in 20 s");
    assert!(turns > 20.0, "{turns}");
}

#[test]
fn the_cartesian_double_pendulum_is_the_zoo_double_pendulum_in_its_angles() {
    // The reference: the zoo model in its angles, SVI with 13 points at h = 0.01 (converged).
    let zoo = json(&[
        "run",
        "double-pendulum",
        "--method",
        "svi:13",
        "--h",
        "0.01",
        "--t-end",
        "10",
        "--json",
    ]);
    let angles = vector(&zoo, "q");
    let (x1, y1) = (angles[0].sin(), -angles[0].cos());
    let expected = [x1, y1, x1 + angles[1].sin(), y1 - angles[1].cos()];
    let cartesian = constrained("double-pendulum-cartesian", &[]);
    assert_eq!(cartesian["method"], "rattle-kahan-li8");
    let q = vector(&cartesian, "q");
    let error = q
        .iter()
        .zip(expected)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("double-pendulum-cartesian against the zoo's angles at T = 10: {error:.1e}");
    // Measured: 6.3e-15 (kahan-li8 RATTLE, h = 0.0025).
    assert!(error <= 1e-12, "{error:e}");
}

#[test]
fn the_trajectory_has_the_multipliers_on_request() {
    let scratch = Scratch::new("multipliers");
    let plain = scratch.join("plain.csv");
    let with = scratch.join("with.csv");
    let plain = plain.to_str().unwrap();
    let with = with.to_str().unwrap();
    let args = ["--t-end", "1", "--every", "25"];
    let summary = constrained(
        "double-pendulum-cartesian",
        &[&args[..], &["--out", plain]].concat(),
    );
    assert_eq!(summary["trajectory"]["rows"], 17);
    constrained(
        "double-pendulum-cartesian",
        &[&args[..], &["--out", with, "--multipliers"]].concat(),
    );
    let plain = std::fs::read_to_string(plain).unwrap();
    let with = std::fs::read_to_string(with).unwrap();
    assert_eq!(
        plain.lines().next().unwrap(),
        "t,q_x1,q_y1,q_x2,q_y2,v_x1,v_y1,v_x2,v_y2,p_x1,p_y1,p_x2,p_y2,energy"
    );
    assert_eq!(
        with.lines().next().unwrap(),
        format!("{},lambda_1,lambda_2", plain.lines().next().unwrap())
    );
    // The same rows, with two more columns: the rods' tensions (nonzero after the start).
    for (a, b) in plain.lines().zip(with.lines()).skip(1) {
        assert!(b.starts_with(a), "{a} / {b}");
    }
    let rows = parse_csv(&with);
    assert!(rows[1..].iter().all(|row| cell(row, "lambda_1") != 0.0));
    // --multipliers=false is the default; --multipliers without --out is refused.
    bad_input(
        &["run", "double-pendulum-cartesian"],
        &["--multipliers"],
        "--multipliers (output.multipliers): adds the multipliers to the trajectory",
    );
    bad_input(
        &["run", "kepler"],
        &["--multipliers", "--out", "x.csv"],
        "this scene has none",
    );
}

/// The spherical pendulum as a scene file, with `constraints` and `[run]` lines.
fn sphere(constraints: &str, run: &str) -> String {
    format!(
        "lagrangian = \"0.5*(vx^2 + vy^2 + vz^2) - 9.81*z\"\ncoordinates = [\"x\", \"y\", \
         \"z\"]\nconstraints = {constraints}\n[parameters]\nl = 1.0\n[initial]\nq = \
         [0.7173560908995228, 0.0, -0.6967067093471654]\nv = [0.0, 2.0, 0.0]\n[run]\n{run}\n"
    )
}

#[test]
fn initial_data_off_the_constraints_is_projected_with_a_warning() {
    // The sphere of radius 1.001: q0 is 1e-3 inside it (|g| = 2e-3), and its velocity has a
    // radial part that the projection removes.
    let file = scene_file(
        "projected",
        &sphere("[\"x^2 + y^2 + z^2 - 1.002001\"]", "h = 0.01\nt_end = 1.0")
            .replace("v = [0.0, 2.0, 0.0]", "v = [0.1, 2.0, 0.0]"),
    );
    let output = svi(&["run", &file.path, "--json"]);
    assert_eq!(output.status.code(), Some(0));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("warning: the initial state is off the constraints, so it was projected"),
        "{stderr}"
    );
    let summary: Value = serde_json::from_slice(&output.stdout).unwrap();
    let moved = number(&summary, "initial_q_moved");
    assert!((moved - 1e-3).abs() < 1e-9, "{moved}");
    assert!(number(&summary, "initial_p_moved") > 0.01);
    assert_eq!(summary["warnings"][0]["kind"], "projection");
    assert!(number(&summary, "constraint_error_max") <= 1e-12);
    // --strict makes the warning an error.
    let strict = svi(&["run", &file.path, "--strict"]);
    assert_eq!(strict.status.code(), Some(1));
}

#[test]
fn a_step_newton_cannot_take_is_a_failed_run_with_its_last_good_state() {
    let output = svi(&[
        "run",
        "spherical-pendulum",
        "--h",
        "100",
        "--t-end",
        "1000",
        "--json",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let summary: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(summary["status"], "failed");
    assert_eq!(summary["error"]["kind"], "non_convergence");
    assert_eq!(summary["error"]["step"], 0);
    assert_eq!(summary["steps"], 0);
    assert_eq!(summary["constraint_error_max"], Value::Null);
    assert_eq!(vector(&summary, "q")[1], 0.0);
}

#[test]
fn a_scene_and_its_method_must_agree_about_constraints() {
    let names = ConstrainedMethod::names().join(", ");
    let stderr = bad_input(
        &["run", "spherical-pendulum"],
        &["--method", "verlet"],
        &names,
    );
    assert!(
        stderr.contains("verlet integrates without constraints"),
        "{stderr}"
    );
    let stderr = bad_input(
        &["run", "kepler"],
        &["--method", "rattle"],
        "svi, svi-newton",
    );
    assert!(
        stderr.contains("rattle is a constrained method"),
        "{stderr}"
    );
    // An unknown name lists both kinds.
    bad_input(&["run", "kepler"], &["--method", "shake"], &names);
    // svi:P/Q out of range is neither kind: the error names the number, with or without
    // constraints (it said "svi:1/4 is a constrained method" on kepler).
    for scene in ["kepler", "spherical-pendulum"] {
        let stderr = bad_input(
            &["run", scene],
            &["--method", "svi:1/4"],
            "invalid points: svi:1/4 needs at least 2 nodes",
        );
        assert!(!stderr.contains("constrained method"), "{stderr}");
    }
    // Every constrained method runs a constrained scene, with its order.
    for name in ConstrainedMethod::names() {
        let summary = constrained("spherical-pendulum", &["--method", &name, "--t-end", "1"]);
        let order = ConstrainedMethod::named(&name).unwrap().order();
        assert_eq!(summary["method"], name.as_str());
        assert_eq!(summary["order"], order);
    }
}

#[test]
fn the_help_and_the_guide_list_every_constrained_method() {
    let help = svi(&["run", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    let guide = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/guide/src/constraints.md"
    ))
    .unwrap();
    for name in ConstrainedMethod::names() {
        assert!(
            help.contains(&format!("  {name} ")),
            "svi run --help: {name}"
        );
        assert!(
            guide.contains(&format!("| `{name}` |")),
            "the guide's table: {name}"
        );
    }
}

#[test]
fn a_constrained_scene_run_allocates_nothing_per_step_beyond_the_integrators_own() {
    use nalgebra::DVector;
    use svi::method::constrained::{ConstrainedIntegrator, Rattle};
    use svi::model::text::{TextLagrangian, TextModel, TextSpec};
    use svi_experiments::{Control, Scene};
    let scratch = Scratch::new("constrained-allocations");
    // The allocations per step of the library's RATTLE on the scene's model, with an observer
    // that does nothing: the difference between 1000 and 100 steps, over 900.
    let spec = TextSpec {
        lagrangian: "0.5*m*(vx^2 + vy^2 + vz^2) - m*g*z".into(),
        coordinates: vec!["x".into(), "y".into(), "z".into()],
        parameters: vec![("m".into(), 1.0), ("g".into(), 9.81), ("l".into(), 1.0)],
        constraints: vec!["x^2 + y^2 + z^2 - l^2".into()],
        ..TextSpec::default()
    };
    let model = TextModel::new(&spec).unwrap();
    let constraints = model.constraints();
    let model = TextLagrangian::<svi::Dyn, false, false, true>::new(model).unwrap();
    let integrator = ConstrainedIntegrator::new(model, constraints, Rattle::default()).unwrap();
    let q0 = DVector::from_vec(vec![0.7173560908995228, 0.0, -0.6967067093471654]);
    let p0 = DVector::from_vec(vec![0.0, 2.0, 0.0]);
    let library = |steps: usize| {
        let before = crate::allocations::count();
        integrator.run(0.0, &q0, &p0, 0.01, steps, |_| {}).unwrap();
        crate::allocations::count() - before
    };
    let per_step = (library(1000) - library(100)) as f64 / 900.0;
    // The same from a scene run: its observer's energy, momentum and trajectory rows (to a
    // file, with the multipliers) add nothing per step.
    let scene_run = |t_end: f64, out: Option<&str>| {
        let mut scene = Scene::load("spherical-pendulum").unwrap();
        scene.run.t_end = Some(t_end);
        scene.output.trajectory = out.map(|name| scratch.join(name));
        scene.output.multipliers = out.map(|_| true);
        let before = crate::allocations::count();
        let summary = scene.run(Control::QUIET).unwrap();
        let count = crate::allocations::count() - before;
        assert_eq!(summary.steps, (t_end * 100.0).round() as usize);
        count
    };
    println!("RATTLE on the text model: {per_step} allocations per step (the library's)");
    for out in [None, Some("trajectory.csv")] {
        let extra = scene_run(100.0, out) as f64 - scene_run(1.0, out) as f64 - 9900.0 * per_step;
        println!("a scene run, trajectory {out:?}: {extra} allocations more over 9900 steps");
        // A file's writes may allocate now and then (its buffer), never per step.
        assert!(extra <= 4.0, "{out:?}: {extra}");
    }
}

#[test]
fn a_constrained_scene_reads_the_registrys_names_as_the_constrained_methods() {
    // (method, order, symmetric, energy error bound at h = 0.01 to T = 100)
    let cases = [
        ("symplectic-euler", 1, false, 5e-2),
        ("midpoint", 2, true, 1e-3),
        ("trapezoid", 2, true, 1e-3),
        ("svi:6/5", 8, true, 1e-10),
    ];
    for (method, order, symmetric, bound) in cases {
        let summary = constrained("spherical-pendulum", &["--method", method]);
        assert_eq!(summary["method"], method);
        assert_eq!(summary["order"], order, "{method}");
        assert_eq!(summary["symmetric"], symmetric, "{method}");
        let (g, rate) = on_constraints(&summary);
        assert!(g <= 1e-12 && rate <= 1e-12, "{method}: {g:e} {rate:e}");
        let energy = summary["energy_error_max"].as_f64().unwrap();
        assert!(energy <= bound, "{method}: energy error {energy:e}");
        assert!(summary["evaluations"].as_u64().unwrap() > 0, "{method}");
        assert!(summary["factorizations"].as_u64().unwrap() > 0, "{method}");
    }
}
