//! `svi compare`: one scene once per method — the outer Solar System of Hairer, Lubich &
//! Wanner's Fig. I.2.4 over a short horizon (100 or 200 steps of 10 days), its table, JSON and
//! picture; a method list with a bad item; a method that fails as it runs; and the scene run
//! by `svi run`.

use crate::common;
use common::*;

use serde_json::Value;

/// The bodies of the outer Solar System, as its coordinates name them.
const BODIES: [&str; 6] = ["sun", "jupiter", "saturn", "uranus", "neptune", "pluto"];

/// `svi ARGS`, expected to end within [`HANG`] with exit status `code`; its stdout and stderr.
fn svi_status(args: &[&str], code: i32) -> (String, String) {
    let output = svi_within(args, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(code), "svi {args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "svi {args:?}: {stderr}");
    (stdout, stderr)
}

/// The row of `method` in a comparison's JSON.
fn row<'a>(comparison: &'a Value, method: &str) -> &'a Value {
    comparison["methods"]
        .as_array()
        .unwrap()
        .iter()
        .find(|row| row["method"] == method)
        .unwrap_or_else(|| panic!("no row of {method}: {comparison}"))
}

#[test]
fn the_outer_solar_system_compares_methods_in_a_table_and_as_json() {
    let (text, _) = svi_status(
        &[
            "compare",
            "outer-solar-system",
            "--methods",
            "explicit-euler,verlet",
            "--t-end",
            "1000",
        ],
        0,
    );
    for needle in [
        "scene outer-solar-system: nbody (G = 0.000295912208286), h = 10, t0 = 0",
        "max |E-E0|",
        "final |E-E0|",
        "max momentum error",
    ] {
        assert!(text.contains(needle), "{needle}:\n{text}");
    }
    for method in ["explicit-euler", "verlet"] {
        let line = text
            .lines()
            .find(|line| line.starts_with(&format!("{method} ")))
            .unwrap_or_else(|| panic!("no row of {method}:\n{text}"));
        assert!(line.contains(" ok ") && line.contains(" 100 "), "{line}");
    }

    // Implicit Euler takes some 13 ms a step on the 18 coordinates (its Newton Jacobian is
    // the acceleration's, by scalar sweeps): 100 steps.
    let methods = "explicit-euler,implicit-euler,symplectic-euler,verlet";
    let args = [
        "compare",
        "outer-solar-system",
        "--methods",
        methods,
        "--t-end",
        "1000",
        "--json",
    ];
    let comparison: Value = serde_json::from_str(&svi_status(&args, 0).0).unwrap();
    assert_eq!(comparison["status"], "ok");
    assert_eq!(comparison["model"], "nbody");
    assert_eq!(comparison["h"], 10.0);
    assert_eq!(comparison["parameters"]["G"], 2.95912208286e-4);
    assert_eq!(comparison["methods"].as_array().unwrap().len(), 4);
    for method in methods.split(',') {
        let row = row(&comparison, method);
        assert_eq!(row["status"], "ok", "{row}");
        assert_eq!(row["steps"], 100, "{row}");
        assert_eq!(row["t_end"], 1000.0, "{row}");
        for field in [
            "seconds",
            "energy_initial",
            "energy_final",
            "energy_error_max",
            "energy_error_final",
            "momentum_error_max",
        ] {
            assert!(number(row, field).is_finite(), "{method} {field}: {row}");
        }
        assert!(
            number(row, "energy_error_final") <= number(row, "energy_error_max"),
            "{row}"
        );
    }
    // Explicit Euler gains energy at every step and changes the angular momentum (by
    // h² Σ mᵢ q̇ᵢ × q̈ᵢ a step); Störmer–Verlet's energy error stays small, and it keeps the
    // Noether momenta to round-off (of order 1e-5 and 1e-4 here).
    let (euler, verlet) = (
        row(&comparison, "explicit-euler"),
        row(&comparison, "verlet"),
    );
    let energy = number(euler, "energy_initial").abs();
    assert!(
        number(euler, "energy_error_max") > 100.0 * number(verlet, "energy_error_max"),
        "{euler}\n{verlet}"
    );
    assert!(
        number(verlet, "energy_error_max") < 1e-4 * energy,
        "{verlet}"
    );
    assert!(number(verlet, "momentum_error_max") < 1e-15, "{verlet}");
    assert!(number(euler, "momentum_error_max") > 1e-8, "{euler}");
}

#[test]
fn the_picture_has_an_orbit_per_body_and_method_and_the_energy_errors() {
    let dir = Scratch::new("compare-plot");
    let plot = dir.join("solar-system.svg");
    let plot = plot.to_str().unwrap();
    let (text, _) = svi_status(
        &[
            "compare",
            "outer-solar-system",
            "--methods",
            "explicit-euler,verlet",
            "--t-end",
            "2000",
            "--plot",
            plot,
        ],
        0,
    );
    assert!(text.contains(&format!("picture: {plot}")), "{text}");
    let svg = std::fs::read_to_string(plot).unwrap();
    assert!(svg.starts_with("<svg"), "{svg}");
    // plotters writes each legend entry as a text element of its own: one per body in each
    // method's panel, one per method in the energy panel (and the method in its panel's
    // title).
    let labels = |label: &str| svg.matches(&format!(">\n{label}\n<")).count();
    for body in BODIES {
        assert_eq!(labels(body), 2, "{body}");
    }
    assert_eq!(labels("explicit-euler"), 2);
    assert_eq!(labels("verlet"), 2);
    assert_eq!(labels("energy error"), 1);
}

#[test]
fn a_bad_method_list_is_bad_input_naming_the_method() {
    for (methods, needle) in [
        ("verlet,rk45", "rk45"),
        ("verlet,lie-svi", "lie-svi"),
        ("verlet,svi:1", "svi:1"),
    ] {
        bad_input(
            &["compare", "outer-solar-system"],
            &["--methods", methods, "--t-end", "100"],
            needle,
        );
    }
    bad_input(
        &["compare", "outer-solar-system"],
        &["--t-end", "100"],
        "--methods",
    );
    bad_input(
        &["compare", "outer-solar-system"],
        &["--methods", "verlet", "--param", "G=-1"],
        "G",
    );
    bad_input(
        &["compare", "outer-solar-system"],
        &["--methods", "verlet", "--plot", "orbits.png"],
        ".svg",
    );
    // With --json, bad input is the one failure object of `svi run --json`: an option the
    // scene rejects, and a value the model rejects as every method starts.
    for bad in [["--h", "-1"], ["--param", "G=-1"]] {
        let (stdout, _) = svi_status(
            &[
                &["compare", "outer-solar-system", "--methods", "verlet,svi"],
                &bad[..],
                &["--json"],
            ]
            .concat(),
            2,
        );
        let failure: Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(failure["status"], "failed");
        assert_eq!(failure["error"]["kind"], "invalid_parameter", "{failure}");
        assert!(failure.get("methods").is_none(), "{failure}");
    }
}

#[test]
fn a_method_that_fails_has_its_row_say_so_and_the_others_still_run() {
    // Störmer–Verlet at h = 2.1 is beyond its stability limit h = 2 on the oscillator and
    // passes the scene's divergence limit after some 20 steps; implicit Euler damps.
    let args = [
        "compare",
        "oscillator-beyond-stability",
        "--methods",
        "verlet,implicit-euler",
        "--t-end",
        "100",
    ];
    let (stdout, stderr) = svi_status(&[&args[..], &["--json"]].concat(), 1);
    assert!(
        stderr.contains("1 of 2 methods failed: verlet (diverged)"),
        "{stderr}"
    );
    let comparison: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(comparison["status"], "failed");
    let verlet = row(&comparison, "verlet");
    assert_eq!(verlet["status"], "failed");
    assert_eq!(verlet["error"]["kind"], "diverged", "{verlet}");
    assert!(number(verlet, "t_end") < 100.0, "{verlet}");
    let euler = row(&comparison, "implicit-euler");
    assert_eq!(euler["status"], "ok");
    assert_eq!(euler["t_end"], 100.0);
    let (text, _) = svi_status(&args, 1);
    assert!(text.contains("verlet failed: "), "{text}");
}

#[test]
fn every_kind_of_scene_compares() {
    let dir = Scratch::new("compare-kinds");
    for (scene, methods, t_end, curve) in [
        ("kepler", "svi,verlet", "10", "q1"),
        ("kepler-text", "svi,rk4", "10", "x"),
        ("fput", "svi,verlet", "1", "mode_1"),
        ("rigid-body", "lie-svi,lie-svi-reduced", "1", "qw"),
    ] {
        let plot = dir.join(&format!("{scene}.svg"));
        let plot = plot.to_str().unwrap();
        let (stdout, _) = svi_status(
            &[
                "compare",
                scene,
                "--methods",
                methods,
                "--t-end",
                t_end,
                "--plot",
                plot,
                "--json",
            ],
            0,
        );
        let comparison: Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(comparison["status"], "ok", "{scene}: {comparison}");
        for method in methods.split(',') {
            assert!(number(row(&comparison, method), "energy_error_max").is_finite());
        }
        // A curve of each configuration coordinate against t in each method's panel.
        let svg = std::fs::read_to_string(plot).unwrap();
        assert_eq!(svg.matches(&format!(">\n{curve}\n<")).count(), 2, "{scene}");
    }
}

#[test]
fn the_outer_solar_system_runs_as_a_scene() {
    let summary = json(&["run", "outer-solar-system", "--t-end", "1000", "--json"]);
    assert_eq!(summary["model"], "nbody");
    assert_eq!(summary["method"], "verlet");
    assert_eq!(summary["steps"], 100);
    assert_eq!(vector(&summary, "q").len(), 18);
    let coordinates = summary["coordinates"].as_array().unwrap();
    assert_eq!(coordinates[3], "jupiter_x");
    assert_eq!(coordinates[17], "pluto_z");
    assert!(number(&summary, "energy_error_max") < 1e-9, "{summary}");
    assert!(number(&summary, "momentum_error_max") < 1e-15, "{summary}");
    // Listed with its parameter.
    let output = svi(&["list"]);
    let list = String::from_utf8(output.stdout).unwrap();
    assert!(list.contains("outer-solar-system"), "{list}");
    let line = list
        .lines()
        .find(|line| line.trim_start().starts_with("nbody "))
        .unwrap_or_else(|| panic!("{list}"));
    assert!(line.contains("G = 0.000295912208286"), "{line}");
    assert!(line.contains("6 Noether momenta"), "{line}");
}
