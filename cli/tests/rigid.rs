//! `svi run` on the rigid-body scenes (Lie-group variational integrator on SO(3)): JSON
//! summaries with the conservation diagnostics, the CSV trajectory, scene files, overrides
//! and error messages. References: conservation laws (spatial angular momentum of the free
//! body, vertical angular momentum of the tops, ‖RᵀR − I‖ = 0) and the agreement of the
//! full and reduced forms on the free body.

use crate::common;
use common::*;

#[test]
fn rigid_body_scene_conserves_momentum_and_orthogonality() {
    let summary = json(&["run", "rigid-body", "--json"]);
    assert_eq!(summary["model"], "rigid-body");
    assert_eq!(summary["method"], "lie-svi");
    assert_eq!(summary["form"], "reduced");
    assert_eq!(summary["order"], 4);
    assert_eq!(summary["symplectic"], true);
    assert_eq!(summary["steps"], 2000);
    assert!(
        number(&summary, "orthogonality_error_max") <= 1e-13,
        "{summary}"
    );
    assert!(
        number(&summary, "momentum_error_relative") <= 1e-12,
        "{summary}"
    );
    assert!(number(&summary, "momentum_error_max") <= 1e-12, "{summary}");
    assert!(
        number(&summary, "invariant_error_max") <= 1e-12,
        "{summary}"
    );
    assert!(number(&summary, "energy_error_max") <= 1e-8, "{summary}");
    // Default state: Ω₀ = (1, 0.5, −0.4), I = diag(1, 2, 3), R₀ = I: π = (1, 1, −1.2).
    let spatial = vector(&summary, "spatial_momentum");
    for (x, y) in spatial.iter().zip([1.0, 1.0, -1.2]) {
        assert!((x - y).abs() <= 1e-12, "{spatial:?}");
    }
    let q = vector(&summary, "quaternion");
    assert!((q.iter().map(|c| c * c).sum::<f64>() - 1.0).abs() < 1e-14);
}

#[test]
fn full_and_reduced_forms_agree_on_the_free_body() {
    let full = json(&[
        "run",
        "rigid-body",
        "--json",
        "--form",
        "full",
        "--t-end",
        "10",
    ]);
    let reduced = json(&[
        "run",
        "rigid-body",
        "--json",
        "--form",
        "reduced",
        "--t-end",
        "10",
    ]);
    assert_eq!(full["form"], "full");
    assert_eq!(reduced["form"], "reduced");
    for key in ["attitude", "momentum", "omega"] {
        for (a, b) in vector(&full, key).iter().zip(vector(&reduced, key)) {
            assert!((a - b).abs() <= 1e-12, "{key}: {a} vs {b}");
        }
    }
}

#[test]
fn heavy_top_and_pendulum_conserve_vertical_momentum() {
    for scene in ["heavy-top", "pendulum-3d"] {
        let summary = json(&["run", scene, "--json", "--t-end", "5"]);
        assert_eq!(summary["form"], "full");
        assert_eq!(summary["steps"], 500);
        assert_eq!(summary["momentum_names"][0], "vertical angular momentum");
        assert!(
            number(&summary, "momentum_error_relative") <= 1e-12,
            "{summary}"
        );
        assert!(
            number(&summary, "orthogonality_error_max") <= 1e-13,
            "{summary}"
        );
        assert!(number(&summary, "energy_error_max") <= 1e-6, "{summary}");
    }
    // Higher order through the overrides.
    let summary = json(&[
        "run",
        "heavy-top",
        "--json",
        "--t-end",
        "1",
        "--points",
        "4",
        "--quadrature",
        "4",
    ]);
    assert_eq!(summary["order"], 6);
    assert_eq!(summary["quadrature"], 4);
}

#[test]
fn trajectory_csv_has_quaternion_matrix_and_omega() {
    let scratch = Scratch::new("trajectory");
    let path = scratch.join("top.csv");
    let summary = json(&[
        "run",
        "heavy-top",
        "--json",
        "--t-end",
        "1",
        "--every",
        "10",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert_eq!(summary["trajectory"]["rows"], 11);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..5], ["t", "qw", "qx", "qy", "qz"]);
    assert_eq!(header.len(), 22);
    let rows: Vec<Vec<f64>> = lines
        .map(|line| line.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 11);
    let first_energy = rows[0][20];
    for row in &rows {
        let norm: f64 = row[1..5].iter().map(|c| c * c).sum();
        assert!((norm - 1.0).abs() < 1e-14);
        assert!(row[21] < 1e-13);
        assert!((row[20] - first_energy).abs() < 1e-6);
        // Spin Ω₃ = 10 of the symmetric top is constant.
        assert!((row[16] - 10.0).abs() < 1e-12);
    }
    assert!((rows[10][0] - 1.0).abs() < 1e-15);
}

#[test]
fn scene_files_with_a_rigid_model_run() {
    let scratch = Scratch::new("scene");
    let path = scratch.join("top.toml");
    std::fs::write(
        &path,
        r#"model = "heavy-top"
[parameters]
l = 0.3
[initial]
quaternion = [1.0, 0.0, 0.0, 0.0]
momentum = [0.2, 0.0, 4.0]
[method]
points = 2
quadrature = 1
[run]
h = 0.02
t_end = 2.0
"#,
    )
    .unwrap();
    let summary = json(&["run", path.to_str().unwrap(), "--json"]);
    assert_eq!(summary["model"], "heavy-top");
    assert_eq!(summary["parameters"]["l"], 0.3);
    assert_eq!(summary["order"], 2);
    assert_eq!(summary["steps"], 100);
    assert!(
        number(&summary, "momentum_error_relative") <= 1e-12,
        "{summary}"
    );
    // Body momentum Π₃ = 4 with I₃ = 0.5: spin Ω₃ = 8 throughout.
    assert!((vector(&summary, "omega")[2] - 8.0).abs() < 1e-12);
}

#[test]
fn bad_rigid_scenes_fail_with_messages() {
    let stderr = failure(&["run", "heavy-top", "--form", "reduced"]);
    assert!(stderr.contains("G-invariant"), "{stderr}");
    let stderr = failure(&["run", "heavy-top", "--method", "svi"]);
    assert!(stderr.contains("lie-svi"), "{stderr}");
    let stderr = failure(&["run", "heavy-top", "--form", "sideways"]);
    assert!(stderr.contains("sideways"), "{stderr}");
    let stderr = failure(&["run", "heavy-top", "--points", "1"]);
    assert!(stderr.contains("points"), "{stderr}");
    let stderr = failure(&["run", "heavy-top", "--h", "0"]);
    assert!(stderr.contains("h"), "{stderr}");
    let stderr = failure(&["run", "heavy-top", "--param", "m=-1"]);
    assert!(stderr.contains("m"), "{stderr}");
    let stderr = failure(&["run", "kepler", "--form", "full"]);
    assert!(stderr.contains("scenes on Lie groups only"), "{stderr}");
    let scratch = Scratch::new("bad");
    let path = scratch.join("bad.toml");
    std::fs::write(
        &path,
        "model = \"pendulum-3d\"\n[initial]\nquaternion = [1.0, 1.0, 0.0, 0.0]\n",
    )
    .unwrap();
    let stderr = failure(&["run", path.to_str().unwrap()]);
    assert!(stderr.contains("quaternion"), "{stderr}");
    std::fs::write(
        &path,
        "model = \"pendulum-3d\"\n[initial]\nomega = [1.0, 2.0]\n",
    )
    .unwrap();
    let stderr = failure(&["run", path.to_str().unwrap()]);
    assert!(stderr.contains("omega"), "{stderr}");
}

#[test]
fn list_shows_the_rigid_scenes_models_and_groups() {
    let output = svi(&["list"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    for name in ["rigid-body", "heavy-top", "pendulum-3d"] {
        assert!(text.matches(name).count() >= 2, "{name} missing:\n{text}");
    }
    // The registered Lie groups, with their dimension and stored size.
    assert!(
        text.contains("Lie groups for models written in Rust"),
        "{text}"
    );
    for (name, shape) in [("SE(3)", "N = 6, E = 12"), ("SO(3)^8", "N = 24, E = 72")] {
        assert!(
            text.lines()
                .any(|line| line.trim_start().starts_with(name) && line.contains(shape)),
            "{name}: {text}"
        );
    }
    // The text summary prints the orthogonality diagnostic.
    let output = svi(&["run", "pendulum-3d", "--t-end", "0.5"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("|R^T R - I|"), "{text}");
    assert!(text.contains("vertical angular momentum"), "{text}");
}

#[test]
fn rigid_scenes_take_the_method_grammar() {
    let base = ["run", "rigid-body", "--json", "--t-end", "2"];
    let run = |extra: &[&str]| {
        let mut all = base.to_vec();
        all.extend_from_slice(extra);
        json(&all)
    };
    // The built-in scene: lie-svi, 3/3, reduced form.
    let scene = run(&[]);
    for (extra, form) in [
        (&["--method", "lie-svi-reduced"][..], "reduced"),
        (&["--method", "lie-svi-reduced:3"], "reduced"),
        (&["--method", "lie-svi:3/3", "--form", "reduced"], "reduced"),
        (&["--method", "lie-svi:3/3"], "reduced"),
        (&["--method", "lie-svi", "--form", "full"], "full"),
    ] {
        let summary = run(extra);
        assert_eq!(summary["method"], "lie-svi", "{extra:?}");
        assert_eq!(summary["form"], form, "{extra:?}");
        assert_eq!(
            (&summary["points"], &summary["quadrature"]),
            (&3.into(), &3.into())
        );
        for (a, b) in vector(&summary, "momentum")
            .iter()
            .zip(vector(&scene, "momentum"))
        {
            assert!((a - b).abs() <= 1e-12, "{extra:?}: {a} vs {b}");
        }
    }
    let summary = run(&["--method", "lie-svi:3/2"]);
    assert_eq!(
        (&summary["points"], &summary["quadrature"]),
        (&3.into(), &2.into())
    );
    assert_eq!(summary["order"], 4);
    let summary = run(&["--method", "lie-svi:4", "--quadrature", "4"]);
    assert_eq!(summary["order"], 6);

    let scratch = Scratch::new("grammar");
    let path = scratch.join("body.toml");
    let write = |method: &str| {
        std::fs::write(
            &path,
            format!("model = \"rigid-body\"\n[method]\n{method}\n[run]\nh = 0.05\nt_end = 1\n"),
        )
        .unwrap();
    };
    write("name = \"lie-svi-reduced:4\"");
    let summary = json(&["run", path.to_str().unwrap(), "--json"]);
    assert_eq!(
        (&summary["form"], &summary["points"]),
        (&"reduced".into(), &4.into())
    );
    write("name = \"lie-svi\"\npoints = 4\nquadrature = 4\nform = \"reduced\"");
    let summary = json(&["run", path.to_str().unwrap(), "--json"]);
    assert_eq!(
        (&summary["form"], &summary["order"]),
        (&"reduced".into(), &6.into())
    );

    for (method, needle) in [
        ("name = \"svi:7/6\"", "'svi:7/6' integrates models on ℝᴺ"),
        ("name = \"lie-svi-reduced\"\nform = \"full\"", "contradicts"),
        ("name = \"lie-svi:1\"", "1 CGL points"),
    ] {
        write(method);
        let stderr = failure(&["run", path.to_str().unwrap()]);
        assert!(stderr.contains(needle), "{method}: {stderr}");
    }
    for (extra, needle) in [
        (
            &["--method", "verlet"][..],
            "'verlet' integrates models on ℝᴺ",
        ),
        (
            &["--method", "lie-svi-reduced", "--form", "full"],
            "contradicts",
        ),
        (&["--method", "lie-svi:3/3/3"], "lie-svi:3/3/3"),
    ] {
        let mut all = vec!["run", "heavy-top"];
        all.extend_from_slice(extra);
        let stderr = failure(&all);
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
    }
}

#[test]
fn rigid_scenes_take_adaptivity_output_times_and_failure_handling() {
    // Step doubling on SO(3): every accepted step keeps the momenta and R orthogonal.
    let summary = json(&[
        "run",
        "rigid-body",
        "--adapt",
        "step",
        "--tol",
        "1e-8",
        "--json",
    ]);
    assert_eq!(summary["adapt"], "step");
    assert_eq!(number(&summary, "tol"), 1e-8);
    let adaptivity = &summary["adaptivity"];
    let accepted = adaptivity["accepted"].as_u64().unwrap();
    assert!(accepted > 0, "{summary}");
    // Step doubling takes three method steps per trial (two of h, one of 2h).
    assert!(
        summary["steps"].as_u64().unwrap() >= accepted * 3 / 2,
        "{summary}"
    );
    assert_eq!(number(&summary, "t_end"), 100.0);
    assert!(number(adaptivity, "min_step") > 0.0, "{summary}");
    for (field, bound) in [
        ("momentum_error_relative", 1e-12),
        ("orthogonality_error_max", 1e-13),
    ] {
        assert!(number(&summary, field) <= bound, "{field}: {summary}");
    }
    assert!(summary["outputs"].is_null());

    // Output times, read off the step curve R_k exp(ξ(τ)) of the Lie-group integrator.
    let summary = json(&["run", "heavy-top", "--output-times", "0.5,1.25", "--json"]);
    let outputs = summary["outputs"].as_array().unwrap();
    let times: Vec<f64> = outputs.iter().map(|o| number(o, "t")).collect();
    assert_eq!(times, [0.5, 1.25]);
    for output in outputs {
        let q = vector(output, "quaternion");
        assert!(
            (q.iter().map(|c| c * c).sum::<f64>() - 1.0).abs() < 1e-13,
            "{output}"
        );
        // Spin Ω₃ = 10 of the symmetric top is constant.
        assert!((vector(output, "omega")[2] - 10.0).abs() < 1e-9, "{output}");
    }
    assert_eq!(summary["adaptivity"]["outputs"], 2);
    assert_eq!(summary["steps"], 2000);

    // Degree adaptivity chooses the points of each step.
    let summary = json(&[
        "run",
        "heavy-top",
        "--t-end",
        "2",
        "--adapt",
        "degree",
        "--tol",
        "1e-10",
        "--json",
    ]);
    assert_eq!(summary["adapt"], "degree");
    assert!(
        !summary["adaptivity"]["points_used"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert!(
        number(&summary, "momentum_error_relative") <= 1e-12,
        "{summary}"
    );

    // Recovery and a divergence limit: a plain run's numbers, with the retries counted.
    let plain = json(&["run", "heavy-top", "--t-end", "1", "--json"]);
    assert!(plain.get("retries").is_none() && plain.get("adaptivity").is_none());
    let guarded = json(&[
        "run",
        "heavy-top",
        "--t-end",
        "1",
        "--recovery",
        "halve-step",
        "--divergence-limit",
        "100",
        "--json",
    ]);
    assert_eq!(guarded["retries"], 0);
    assert_eq!(guarded["quaternion"], plain["quaternion"]);
    // Π₃ = I₃ Ω₃ = 5 exceeds a limit of 1 in the first step: a run failure (status 1).
    let output = svi(&["run", "heavy-top", "--divergence-limit", "1"]);
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("the run failed after 0 steps; last good state at t = 0: quaternion = ")
            && stderr.contains("state diverged at step 0"),
        "{stderr}"
    );
}

#[test]
fn options_a_rigid_scene_cannot_use_exit_with_status_2() {
    for (args, needle) in [
        (&["--tol", "1e-8"][..], "--tol (run.tol)"),
        (
            &[
                "--adapt",
                "step",
                "--tol",
                "1e-8",
                "--recovery",
                "halve-step",
            ],
            "--recovery (run.recovery)",
        ),
        (&["--adapt", "step", "--tol", "1e-8", "--h", "0.1"], "--h: "),
        (&["--every", "2"], "no trajectory file"),
        (&["--diagnostics", "none,energy"], "--diagnostics"),
        (&["--diagnostics", "solution"], "has no exact solution"),
        (&["--param", "bogus=1"], "bogus"),
        (&["--method", "verlet"], "'verlet' integrates models on ℝᴺ"),
    ] {
        bad_input(&["run", "heavy-top"], args, needle);
    }
    let scene = scene_file(
        "cross",
        "model = \"heavy-top\"\n[initial]\nq = [1.0, 0.0, 0.0]\n",
    );
    bad_input(
        &["run", &scene.path],
        &[],
        "initial.q: applies to scenes on ℝᴺ",
    );
}
