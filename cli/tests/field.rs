//! `svi run` on the field scenes (issue 19): the built-in scenes with their diagnostics, the
//! field CSV, field scene files, and bad input with exit status 2.

use crate::common;

use common::{Scratch, bad_input, json, number, scene_file, svi};

#[test]
fn the_built_in_field_scenes_run_with_their_diagnostics() {
    // Errors against the exact solutions at the scenes' meshes (Δx = 0.1 for the kinks and
    // the breather, 2π/128 for the wave), measured once: second-order schemes on these
    // meshes give errors of about 10⁻³–10⁻¹, and the conservation laws hold to round-off.
    for (scene, largest_error) in [
        ("wave", 3e-3),
        ("sine-gordon-kink", 2e-2),
        ("sine-gordon-breather", 0.3),
        ("phi4-kink", 5e-3),
    ] {
        let summary = json(&["run", scene, "--json"]);
        assert_eq!(summary["status"], "ok", "{scene}: {summary}");
        assert_eq!(summary["model"], scene);
        assert_eq!(summary["explicit"], true);
        let error = number(&summary, "error_max");
        assert!(error > 0.0 && error < largest_error, "{scene}: {summary}");
        assert!(
            number(&summary, "multisymplectic_residual_max") < 1e-13,
            "{scene}: {summary}"
        );
        let energy = number(&summary, "energy_initial");
        assert!(
            number(&summary, "energy_error_max") < 2e-3 * energy,
            "{scene}: {summary}"
        );
    }
}

#[test]
fn the_midpoint_scheme_runs_by_newton_from_a_scene_file() {
    let file = scene_file(
        "field-midpoint",
        "model = \"phi4-kink\"\n[mesh]\npoints = 201\nquadrature = \"midpoint\"\n[run]\nh = 0.2\nt_end = 4.0\n",
    );
    let summary = json(&["run", &file.path, "--json"]);
    assert_eq!(summary["explicit"], false);
    assert_eq!(summary["quadrature"], "midpoint");
    assert_eq!(summary["levels"], 20);
    assert!(number(&summary, "newton_iterations") >= 20.0);
    assert!(number(&summary, "error_max") < 1e-2, "{summary}");
    assert!(number(&summary, "multisymplectic_residual_max") < 1e-13);
}

#[test]
fn the_field_is_written_as_t_x_u_rows() {
    let dir = Scratch::new("field-csv");
    let path = dir.join("wave.csv");
    let path = path.to_str().unwrap();
    // 64 nodes, levels 0, 4, 8, 12, 16 of 16: five levels of 64 rows.
    let summary = json(&[
        "run",
        "wave",
        "--param",
        "points=64",
        "--h",
        "0.04908738521234052",
        "--t-end",
        "0.7853981633974483",
        "--out",
        path,
        "--every",
        "4",
        "--json",
    ]);
    assert_eq!(summary["trajectory"]["rows"], 5 * 64);
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,x,u"));
    let rows: Vec<Vec<f64>> = lines
        .map(|line| line.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 5 * 64);
    // The first row is u(0, 0) = exp(sin 0) = 1; the last is the last node at the end.
    assert_eq!(rows[0], vec![0.0, 0.0, 1.0]);
    let last = &rows[rows.len() - 1];
    assert!((last[0] - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    assert!((last[1] - 63.0 * 2.0 * std::f64::consts::PI / 64.0).abs() < 1e-12);
}

#[test]
fn bad_field_input_is_exit_status_two() {
    let run = ["run"];
    bad_input(&run, &["wave", "--param", "points=1"], "points");
    bad_input(&run, &["wave", "--h", "0.06"], "stability limit");
    bad_input(&run, &["wave", "--h", "-1"], "h");
    bad_input(&run, &["wave", "--t-end", "0"], "t_end");
    bad_input(&run, &["wave", "--t-end", "1e12"], "more than");
    bad_input(&run, &["sine-gordon-kink", "--param", "speed=1.5"], "speed");
    bad_input(&run, &["phi4-kink", "--adapt", "step"], "field scene");
    // The flags of the chaos indicators, sensitivities, events and sections are refused too,
    // by name (the field scenes ran without them, exit 0).
    for flags in [
        &["--indicators", "megno"][..],
        &["--sensitivity", "q0"],
        &["--sensitivity-every", "2"],
        &["--event", "u"],
        &["--section", "u=0"],
        &["--events-out", "events.csv"],
        &["--multipliers"],
    ] {
        let stderr = bad_input(
            &run,
            &[&["sine-gordon-kink"][..], flags].concat(),
            "field scene",
        );
        assert!(
            stderr.starts_with(&format!("error: {}: ", flags[0])),
            "{stderr}"
        );
    }
    bad_input(&run, &["wave", "--param", "mass=1"], "mass");
    // The commands that run ODE scenes name a field scene as one (they said "no built-in
    // scene or scene file named 'wave'").
    for (command, says) in [
        (&["bench", "wave"][..], "is a field scene"),
        (&["ensemble", "sine-gordon-kink"], "is a field scene"),
        (
            &["compare", "wave", "--methods", "svi"],
            "which only `svi run` runs",
        ),
        (
            &["ensemble", "nls-soliton"],
            "is a pseudospectral scene, which only `svi run` and `svi bench` run",
        ),
    ] {
        let stderr = bad_input(command, &[], says);
        assert!(!stderr.contains("no built-in scene"), "{stderr}");
    }
    let file = scene_file("field-unknown", "model = \"wave\"\n[mesh]\nspacing = 0.1\n");
    bad_input(&run, &[&file.path], "spacing");
}

#[test]
fn an_unwritable_field_file_is_exit_status_one() {
    let output = svi(&["run", "wave", "--out", "/nonexistent-dir/wave.csv"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("cannot write"));
}

#[test]
fn list_shows_the_field_scenes_and_run_prints_a_text_summary() {
    let text = String::from_utf8(svi(&["list"]).stdout).unwrap();
    let fields = text
        .split("Field scenes in 1 + 1 dimensions")
        .nth(1)
        .expect("a group of its own");
    for name in [
        "wave",
        "sine-gordon-kink",
        "sine-gordon-breather",
        "phi4-kink",
        "sine-gordon-kink-fast",
        "phi4-kink-moving-mesh",
        "sine-gordon-kink-antikink",
    ] {
        assert!(fields.contains(name), "{name} missing:\n{text}");
    }
    let output = svi(&["run", "phi4-kink", "--t-end", "1"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("multisymplectic residual:"), "{text}");
    assert!(text.contains("0 to 1 in 20 levels"), "{text}");
}

#[test]
fn plot_draws_the_field_over_space_and_time_and_needs_the_trajectory_file() {
    let scratch = Scratch::new("breather-plot");
    let (csv, svg) = (scratch.join("breather.csv"), scratch.join("breather.svg"));
    let summary = json(&[
        "run",
        "sine-gordon-breather",
        "--t-end",
        "10",
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["status"], "ok");
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg"));
    assert!(picture.contains("sine-gordon-breather: u from"));
    // One filled cell per sampled node and level: at most 160 × 120, at least a few thousand.
    let cells = picture.matches("<rect").count();
    assert!((2_000..=160 * 121 + 10).contains(&cells), "{cells} cells");
    bad_input(
        &["run", "sine-gordon-breather"],
        &["--plot", svg.to_str().unwrap()],
        "--plot",
    );
}

#[test]
fn a_moving_mesh_scene_runs_the_r_adaptive_integrator_and_fails_as_a_run() {
    let scratch = Scratch::new("moving-mesh");
    let csv = scratch.join("kink.csv");
    // The kink at v = 0.99 to t = 2 on 61 moving nodes: error 0.0708, measured.
    let summary = json(&[
        "run",
        "sine-gordon-kink-fast",
        "--param",
        "points=61",
        "--t-end",
        "2",
        "--out",
        csv.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["method"], "r-adaptive");
    assert_eq!(summary["monitor"], "arc-length");
    assert!(summary["dx"].is_null(), "{summary}");
    assert!(number(&summary, "smallest_width") > 0.0);
    assert!(number(&summary, "solution_error_max") < 0.09, "{summary}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("t,x,u,node\n"), "{text}");
    assert_eq!(text.lines().count(), 1 + 61 * 41);
    // Each level's nodes in order, from −20 to 20, strictly increasing: the node paths.
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|line| line.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    for level in rows.chunks(61) {
        assert!(level.iter().all(|row| row[0] == level[0][0]), "{level:?}");
        assert!(level.iter().enumerate().all(|(i, row)| row[3] == i as f64));
        assert_eq!((level[0][1], level[60][1]), (-20.0, 20.0));
        assert!(
            level.windows(2).all(|pair| pair[1][1] > pair[0][1]),
            "{level:?}"
        );
    }
    // Keys of a moving mesh on a uniform one, β with the arc length: bad input.
    let run = ["run"];
    bad_input(
        &run,
        &["sine-gordon-kink", "--param", "smoothing=1"],
        "smoothing",
    );
    bad_input(
        &run,
        &["sine-gordon-kink-fast", "--param", "monitor_curvature=1"],
        "monitor_curvature",
    );
    bad_input(
        &run,
        &["sine-gordon-kink-fast", "--param", "smoothing=-1"],
        "smoothing",
    );
    // Steps far too long for the fast kink (h = 2: it moves 14 times its width in one step):
    // the run fails after it started, exit status 1.
    let output = svi(&[
        "run",
        "sine-gordon-kink-fast",
        "--param",
        "points=41",
        "--h",
        "2",
        "--json",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let failure: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(failure["status"], "failed");
    let kind = failure["error"]["kind"].as_str().unwrap();
    assert!(
        ["mesh_fold", "non_convergence"].contains(&kind),
        "{failure}"
    );
    assert!(failure["error"]["step"].is_number(), "{failure}");
}
