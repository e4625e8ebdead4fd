//! Lagrangians written as text in scene files, end to end through the `svi` binary: the
//! built-in `kepler-text` scene against the built-in `kepler` (the same orbit from the zoo
//! model: the reference), parameters, diagnostics, and errors that name the column.

use crate::common;
use common::*;

/// A text scene: the Kepler problem as in `experiments/scenes/kepler-text.toml`, with `extra` lines
/// at the top level and a horizon of 20.
fn kepler_scene(lagrangian: &str, extra: &str) -> String {
    format!(
        "lagrangian = \"{lagrangian}\"\ncoordinates = [\"x\", \"y\"]\n{extra}\n\
         [parameters]\nmu = 1.0\n[initial]\nq = [0.5, 0.0]\nv = [0.0, 1.7320508075688772]\n\
         [run]\nh = 0.2\nt_end = 20.0\n"
    )
}

#[test]
fn kepler_from_text_matches_the_builtin_kepler_scene() {
    let text = json(&["run", "kepler-text", "--json"]);
    let zoo = json(&["run", "kepler", "--json"]);
    assert_eq!(text["model"], "text");
    assert_eq!(text["coordinates"], serde_json::json!(["x", "y"]));
    assert_eq!(text["parameters"], serde_json::json!({ "mu": 1.0 }));
    assert_eq!(number(&text, "steps"), 10_000.0);
    for (a, b) in vector(&text, "q").iter().zip(vector(&zoo, "q")) {
        assert!((a - b).abs() < 1e-10, "{a} against {b}");
    }
    // The same diagnostics as the zoo model: bounded energy error, the angular momentum of
    // the generator ["-y", "x"] to round-off; no exact solution to measure against.
    let energy = number(&text, "energy_error_max");
    assert!(energy < 1e-9 && (energy - number(&zoo, "energy_error_max")).abs() < 1e-12);
    assert!(number(&text, "momentum_error_max") < 1e-12, "{text}");
    assert!(text["solution_error_max"].is_null());
    assert_eq!(text["status"], "ok");
}

#[test]
fn parameters_of_a_text_model_are_overridden_by_flag() {
    let scene = scene_file(
        "text-param",
        &kepler_scene("0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)", ""),
    );
    let one = json(&["run", &scene.path, "--json"]);
    let two = json(&["run", &scene.path, "--json", "--param", "mu=2"]);
    assert_eq!(two["parameters"], serde_json::json!({ "mu": 2.0 }));
    // E = |v|²/2 − μ/|q|: 1.5 − 2 and 1.5 − 4.
    assert!((number(&one, "energy_initial") + 0.5).abs() < 1e-15);
    assert!((number(&two, "energy_initial") + 2.5).abs() < 1e-15);
    bad_input(
        &["run", &scene.path],
        &["--param", "m=2"],
        "not a parameter of the text model (parameters: mu)",
    );
    // Without symmetries there is no momentum to measure, and asking for it is an error.
    assert!(one["momentum_error_max"].is_null());
    bad_input(
        &["run", &scene.path],
        &["--diagnostics", "momentum"],
        "no Noether momentum",
    );
}

#[test]
fn a_forced_time_dependent_text_model_runs_with_every_method() {
    let text = "lagrangian = \"(vq^2 - q^2)/2 + q*cos(t)\"\ncoordinates = [\"q\"]\n\
                forces = [\"-0.1*vq\"]\n[initial]\nq = [1.0]\nv = [0.0]\n\
                [run]\nh = 0.05\nt_end = 10.0\n";
    let scene = scene_file("text-forced", text);
    let reference = json(&["run", &scene.path, "--json", "--method", "svi:9"]);
    let q = vector(&reference, "q")[0];
    for method in ["sc", "midpoint", "verlet", "trapezoid"] {
        let summary = json(&["run", &scene.path, "--json", "--method", method]);
        let error = (vector(&summary, "q")[0] - q).abs();
        assert!(error < 1e-2, "{method}: {error:e}");
    }
}

#[test]
fn a_syntax_error_names_the_column() {
    let scene = scene_file(
        "text-syntax",
        &kepler_scene("0.5*(vx^2 + vy^2 + 1/sqrt(x^2 + y^2)", ""),
    );
    let message = bad_input(&["run", &scene.path], &[], "at column 5 of lagrangian");
    assert!(message.contains("unbalanced '('"), "{message}");
    let scene = scene_file("text-symbol", &kepler_scene("0.5*(vx^2 + vz^2)", ""));
    bad_input(
        &["run", &scene.path],
        &[],
        "unknown symbol 'vz' at column 13 of lagrangian (known: x, y, vx, vy, t, mu)",
    );
    let scene = scene_file(
        "text-force",
        &kepler_scene("0.5*(vx^2 + vy^2)", "forces = [\"-vx\", \"-vy*\"]"),
    );
    bad_input(&["run", &scene.path], &[], "at column 5 of forces[1]");
    // As JSON: the error object, of kind invalid_input.
    let output = svi(&["run", &scene.path, "--json"]);
    assert_eq!(output.status.code(), Some(2));
    let error: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(error["error"]["kind"], "invalid_input");
    assert!(
        error["error"]["message"]
            .as_str()
            .unwrap()
            .contains("column 5")
    );
}

#[test]
fn what_a_text_scene_must_give_is_named() {
    let kepler = "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)";
    for (text, needle) in [
        (
            kepler_scene(kepler, "model = \"kepler\""),
            "both model = \"kepler\" and lagrangian",
        ),
        (
            kepler_scene(kepler, "").replace("q = [0.5, 0.0]\n", ""),
            "initial.q is needed",
        ),
        (
            kepler_scene(kepler, "").replace("t_end = 20.0\n", ""),
            "run.t_end is needed",
        ),
        (
            kepler_scene(kepler, "").replace(
                "coordinates = [\"x\", \"y\"]",
                "coordinates = [\"x\", \"x\"]",
            ),
            "invalid coordinate name 'x': given twice",
        ),
        (
            kepler_scene(kepler, "").replace(
                "coordinates = [\"x\", \"y\"]",
                "coordinates = [\"x\", \"sin\"]",
            ),
            "invalid coordinate name 'sin': it is a function",
        ),
        (
            kepler_scene(kepler, "").replace("mu = 1.0", "mu = nan"),
            "parameter 'mu' = NaN is not a finite number",
        ),
        (
            kepler_scene(kepler, "symmetries = [[\"-y\"]]"),
            "symmetries[0] has 1 expressions, but the model has 2 coordinates",
        ),
        (
            "model = \"kepler\"\ncoordinates = [\"x\"]\n".into(),
            "coordinates: belongs to a Lagrangian written as text",
        ),
        ("[run]\nh = 0.1\n".into(), "the scene names no model"),
    ] {
        let scene = scene_file("text-needs", &text);
        bad_input(&["run", &scene.path], &[], needle);
    }
}

/// Two planar oscillators of unit frequency coupled by a spring of stiffness k = 1/2, in four
/// coordinates (x1, y1, x2, y2), with the rotation about the origin as a symmetry: the sums
/// x1 + x2, y1 + y2 oscillate at frequency 1, the differences at √(1 + 2k) = √2.
const COUPLED: &str = "lagrangian = \"0.5*(vx1^2 + vy1^2 + vx2^2 + vy2^2) \
    - 0.5*(x1^2 + y1^2 + x2^2 + y2^2) - 0.5*k*((x1 - x2)^2 + (y1 - y2)^2)\"\n\
    coordinates = [\"x1\", \"y1\", \"x2\", \"y2\"]\n\
    symmetries = [[\"-y1\", \"x1\", \"-y2\", \"x2\"]]\n\
    [parameters]\nk = 0.5\n\
    [initial]\nq = [1.0, 0.0, 0.0, 0.5]\nv = [0.0, 1.0, 0.0, 0.0]\n\
    [run]\nh = 0.05\nt_end = 10.0\n";

/// The exact (x1, y1, x2, y2) of [`COUPLED`] at time t, from its normal modes.
fn coupled_exact(t: f64) -> [f64; 4] {
    let w = 2f64.sqrt();
    let (sum_x, difference_x) = (t.cos(), (w * t).cos());
    let sum_y = 0.5 * t.cos() + t.sin();
    let difference_y = -0.5 * (w * t).cos() + (w * t).sin() / w;
    [
        0.5 * (sum_x + difference_x),
        0.5 * (sum_y + difference_y),
        0.5 * (sum_x - difference_x),
        0.5 * (sum_y - difference_y),
    ]
}

#[test]
fn a_text_model_of_four_coordinates_runs() {
    let scene = scene_file("text-coupled", COUPLED);
    let summary = json(&["run", &scene.path, "--json"]);
    assert_eq!(summary["status"], "ok", "{summary}");
    assert_eq!(summary["model"], "text");
    assert_eq!(
        summary["coordinates"],
        serde_json::json!(["x1", "y1", "x2", "y2"])
    );
    assert_eq!(number(&summary, "steps"), 200.0);
    // E = |v|²/2 + |q|²/2 + k|q1 − q2|²/2 at t0: 1/2 + 5/8 + 5/16.
    assert!(
        (number(&summary, "energy_initial") - 1.4375).abs() < 1e-14,
        "{summary}"
    );
    let energy = number(&summary, "energy_error_max");
    assert!(
        energy.is_finite() && energy < 1e-12,
        "energy error {energy:e}"
    );
    assert!(number(&summary, "momentum_error_max") < 1e-12, "{summary}");
    let q = vector(&summary, "q");
    assert_eq!(q.len(), 4);
    for (i, (found, exact)) in q.iter().zip(coupled_exact(10.0)).enumerate() {
        assert!(
            (found - exact).abs() < 1e-10,
            "q[{i}] = {found} against {exact}"
        );
    }
    // Every family of methods runs the model of run-time dimension, and stays near the orbit.
    for method in ["sc", "midpoint", "verlet", "trapezoid", "svi@step"] {
        let (method, adapt) = method.split_once('@').unwrap_or((method, ""));
        let mut args = vec!["run", &scene.path, "--json", "--method", method];
        if !adapt.is_empty() {
            args.extend(["--adapt", adapt]);
        }
        let summary = json(&args);
        assert_eq!(summary["status"], "ok", "{method}: {summary}");
        let energy = number(&summary, "energy_error_max");
        assert!(
            energy.is_finite() && energy < 1e-2,
            "{method}: energy error {energy:e}"
        );
    }
}

#[test]
fn fput_written_as_one_line_of_text_runs_as_the_zoo_chain() {
    // The built-in fput-text scene against the built-in fput (the reference: the same chain
    // in Rust) at n = 1000, ten steps of svi's fixed point and of verlet.
    for method in ["svi", "verlet"] {
        let run = |scene: &str| {
            json(&[
                "run", scene, "--json", "--param", "n=1000", "--t-end", "1", "--method", method,
            ])
        };
        let (text, zoo) = (run("fput-text"), run("fput"));
        assert_eq!(text["model"], "text");
        assert_eq!(text["status"], "ok", "{text}");
        assert_eq!(text["steps"], 10);
        assert_eq!(text["parameters"]["n"], 1000.0);
        let (q, reference) = (vector(&text, "q"), vector(&zoo, "q"));
        assert_eq!(q.len(), 1000);
        for (a, b) in q.iter().zip(&reference) {
            assert!((a - b).abs() < 1e-13, "{method}: {a} against {b}");
        }
        let energy = number(&text, "energy_initial");
        assert!((energy - number(&zoo, "energy_initial")).abs() < 1e-13);
        assert!(number(&text, "energy_error_max") < 1e-12, "{text}");
    }
}

#[test]
fn a_periodic_chain_of_two_families_runs_from_per_site_expressions() {
    // Two families on a ring, coupled on each site: x and y harmonic chains with a cross
    // spring; started at rest in the lowest ring mode of x, energy E = Σ (k/2)(Δx)².
    let text = "lagrangian = \"sum(i, 1, n, (vx[i]^2 + vy[i]^2)/2 - k/2*(x[i+1]-x[i])^2 \
                - k/2*(y[i+1]-y[i])^2 - c/2*(x[i]-y[i])^2)\"\n\
                coordinates = [\"x[1..n]\", \"y[1..n]\"]\nboundary = \"periodic\"\n\
                [parameters]\nn = 50\nk = 1.0\nc = 0.0\n\
                [initial]\nq = [\"cos(2*pi*i/n)\", \"0\"]\nv = [\"0\", \"0\"]\n\
                [method]\nname = \"verlet\"\n[run]\nh = 0.05\nt_end = 5.0\n";
    let scene = scene_file("text-ring", text);
    let summary = json(&["run", &scene.path, "--json"]);
    assert_eq!(summary["status"], "ok", "{summary}");
    let q = vector(&summary, "q");
    assert_eq!(q.len(), 100);
    // With c = 0 each x mode is a harmonic oscillator of frequency ω = 2 sin(π/n):
    // x_i(t) = cos(ωt) cos(2πi/n), y = 0 (Verlet's phase error is O(h²ω³t)).
    let omega = 2.0 * (std::f64::consts::PI / 50.0).sin();
    for i in 0..50 {
        let exact =
            (omega * 5.0).cos() * (2.0 * std::f64::consts::PI * (i + 1) as f64 / 50.0).cos();
        assert!(
            (q[2 * i] - exact).abs() < 1e-4,
            "x[{}]: {} {exact}",
            i + 1,
            q[2 * i]
        );
        assert_eq!(q[2 * i + 1], 0.0);
    }
    assert!(number(&summary, "energy_error_max") < 1e-5, "{summary}");
}

#[test]
fn misused_indices_and_chain_options_are_bad_input_naming_them() {
    let chain = |lagrangian: &str, extra: &str| {
        format!(
            "lagrangian = \"{lagrangian}\"\ncoordinates = [\"q[1..n]\"]\n{extra}\n\
             [parameters]\nn = 8\n[initial]\nq = \"sin(i)\"\nv = \"0\"\n\
             [run]\nh = 0.1\nt_end = 1.0\n"
        )
    };
    let kinetic = "sum(i, 1, n, vq[i]^2/2)";
    for (name, lagrangian, needle) in [
        (
            "text-index",
            "sum(i, 1, n, vq[2*i]^2/2)".to_string(),
            "indexing error at column 17 of lagrangian ('2*i')",
        ),
        (
            "text-nested",
            "sum(i, 1, n, vq[i]^2 + sum(j, 1, n, q[j]))".to_string(),
            "column 24 of lagrangian ('sum'): a sum inside a sum",
        ),
        (
            "text-outside",
            format!("{kinetic} - q[i]^2"),
            "column 29 of lagrangian ('i')",
        ),
        (
            "text-wide",
            format!("{kinetic} - sum(i, 1, n, q[i]*q[i+4])"),
            "reads 5 coordinates",
        ),
    ] {
        let scene = scene_file(name, &chain(&lagrangian, ""));
        bad_input(&["run", &scene.path], &[], needle);
    }
    let scene = scene_file(
        "text-chain",
        &chain(&format!("{kinetic} - sum(i, 1, n, q[i]^2)"), ""),
    );
    bad_input(
        &["run", &scene.path],
        &["--param", "n=2.5"],
        "not a whole number",
    );
    bad_input(&["run", &scene.path], &["--method", "lie-svi"], "lie-svi");
    let periodic = scene_file(
        "text-boundary",
        &kepler_scene(
            "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)",
            "boundary = \"periodic\"",
        ),
    );
    bad_input(&["run", &periodic.path], &[], "boundary");
    let expression = scene_file(
        "text-expression",
        &kepler_scene("0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)", "")
            .replace("q = [0.5, 0.0]", "q = \"i\""),
    );
    bad_input(&["run", &expression.path], &[], "initial.q");
    let unknown = scene_file(
        "text-initial",
        &chain(&format!("{kinetic} - sum(i, 1, n, q[i]^2)"), "")
            .replace("q = \"sin(i)\"", "q = \"sin(j)\""),
    );
    bad_input(
        &["run", &unknown.path],
        &[],
        "unknown symbol 'j' at column 5 of initial.q",
    );
}

/// Kepler written as a text Hamiltonian (the built-in `kepler-h-text`) ends where the zoo's
/// `kepler-h` (run by the Hamiltonian SVI) and `kepler` (run by SVI) end, the same orbit from
/// models written in Rust: the reference. Measured at T = 2000 (10 000 steps of 7/6): 1.5e-11.
#[test]
fn kepler_from_a_text_hamiltonian_matches_the_zoo_scenes() {
    for (zoo, method) in [("kepler-h", "svi-h:7/6"), ("kepler", "svi:7/6")] {
        let text = json(&["run", "kepler-h-text", "--json", "--method", method]);
        let reference = json(&["run", zoo, "--json", "--method", method]);
        assert_eq!(text["model"], "text");
        assert_eq!(text["status"], "ok");
        for field in ["q", "p"] {
            for (a, b) in vector(&text, field).iter().zip(vector(&reference, field)) {
                assert!((a - b).abs() < 5e-11, "{method} {field}: {a} against {b}");
            }
        }
        // The angular momentum of the generator ["-y", "x"], J1 = x py − y px, to round-off.
        assert!(number(&text, "momentum_error_max") < 1e-12, "{text}");
        assert!(number(&text, "energy_error_max") < 2e-11, "{text}");
    }
}

/// A charged particle in a uniform magnetic field B, H = |p − A(q)|²/2 with A = B(−y, x)/2:
/// not separable. From q = (1, 0), p = (0, −B/2) the exact motion is the gyration
/// q(t) = (cos Bt, −sin Bt) (the reference). SVI on either side is exact to round-off; the
/// implicit midpoint rule has its phase error, (Bh)³/12 a step (0.017 over 200 steps), and
/// conserves the quadratic H to round-off.
#[test]
fn a_non_separable_text_hamiltonian_gyrates_as_the_exact_solution() {
    let text = "hamiltonian = \"((px + B*y/2)^2 + (py - B*x/2)^2)/2\"\n\
                coordinates = [\"x\", \"y\"]\n[parameters]\nB = 2.0\n\
                [initial]\nq = [1.0, 0.0]\np = [0.0, -1.0]\n[run]\nh = 0.05\nt_end = 10.0\n";
    let scene = scene_file("text-magnetic", text);
    let exact = [20f64.cos(), -20f64.sin()];
    for (method, tolerance) in [
        ("svi-h", 1e-13),
        ("svi", 1e-13),
        ("midpoint-h", 0.02),
        ("verlet-h", 0.005),
    ] {
        let summary = json(&["run", &scene.path, "--json", "--method", method]);
        let error = vector(&summary, "q")
            .iter()
            .zip(exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error < tolerance, "{method}: {error:e}");
        assert!(
            number(&summary, "energy_error_max") < 1e-14,
            "{method}: {summary}"
        );
    }
}

#[test]
fn a_text_hamiltonian_names_what_is_wrong() {
    let scene = |hamiltonian: &str, extra: &str| {
        format!(
            "hamiltonian = \"{hamiltonian}\"\ncoordinates = [\"x\", \"y\"]\n{extra}\n\
             [parameters]\nmu = 1.0\n[initial]\nq = [0.5, 0.0]\np = [0.0, 1.7320508075688772]\n\
             [run]\nh = 0.2\nt_end = 2.0\n"
        )
    };
    let kepler = "0.5*(px^2 + py^2) - mu/sqrt(x^2 + y^2)";
    for (name, text, needle) in [
        (
            "text-h-symbol",
            scene("0.5*(px^2 + pz^2)", ""),
            "unknown symbol 'pz' at column 13 of hamiltonian (known: x, y, px, py, t, mu)",
        ),
        (
            "text-h-velocity",
            scene("0.5*(vx^2 + py^2)", ""),
            "'vx' at column 6 of hamiltonian is a velocity, but a Hamiltonian is a function of \
             the momenta: write px",
        ),
        (
            "text-h-force-velocity",
            scene(kepler, "forces = [\"-vx\", \"-py\"]"),
            "'vx' at column 2 of forces[0] is a velocity",
        ),
        (
            "text-h-both",
            scene(kepler, "lagrangian = \"0.5*(vx^2 + vy^2)\""),
            "the scene gives both lagrangian and hamiltonian: give one of them",
        ),
        (
            "text-h-model",
            scene(kepler, "model = \"kepler\""),
            "both model = \"kepler\" and lagrangian or hamiltonian",
        ),
        (
            "text-h-constraints",
            scene(kepler, "constraints = [\"x^2 + y^2 - 1\"]"),
            "constraints is not supported here",
        ),
    ] {
        let file = scene_file(name, &text);
        bad_input(&["run", &file.path], &[], needle);
    }
    // A non-finite H at the initial state stops the run before its first step, as a
    // non-finite L does: a failed run (exit status 1), naming H.
    let file = scene_file(
        "text-h-singular",
        &scene(kepler, "").replace("q = [0.5, 0.0]", "q = [0.0, 0.0]"),
    );
    for method in ["svi-h", "svi"] {
        let output = svi(&["run", &file.path, "--method", method]);
        assert_eq!(output.status.code(), Some(1), "{method}");
        let message = String::from_utf8_lossy(&output.stderr);
        assert!(
            message.contains("non-finite Hamiltonian H or its gradient at the initial state"),
            "{message}"
        );
    }
}
