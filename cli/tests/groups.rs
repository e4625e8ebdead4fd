//! `svi run` on the models on Lie groups other than SO(3) (SE(3), SO(3) × S¹, SO(3)⁸): JSON
//! summaries with their conservation diagnostics, the exact solution of the falling body and
//! the method's order against it, the CSV trajectory, scene files and bad input. References:
//! the exact solution (Euler's top and a parabola), the Noether momenta of the declared
//! generators, the group defect 0, and the agreement of the full and reduced forms on the
//! G-invariant satellite.

use crate::common;
use common::*;

#[test]
fn falling_body_matches_its_exact_solution_and_keeps_its_momenta() {
    let summary = json(&["run", "falling-body", "--json"]);
    assert_eq!(summary["kind"], "lie_group");
    assert_eq!(summary["model"], "falling-body");
    assert_eq!(summary["method"], "lie-svi");
    assert_eq!(summary["steps"], 1000);
    assert_eq!(
        summary["momentum_names"],
        serde_json::json!(["L_z", "p_x", "p_y"])
    );
    // Round-off of momenta that grow to 250 (the spatial momentum about the origin of a body
    // 467 m below it), against their initial size 5.
    assert!(
        number(&summary, "momentum_error_relative") <= 1e-12,
        "{summary}"
    );
    assert!(number(&summary, "group_defect_max") <= 1e-14, "{summary}");
    assert!(number(&summary, "energy_error_max") <= 1e-6, "{summary}");
    let last = number(&summary, "solution_error_final");
    assert!(last <= 1e-6, "{summary}");
    assert!(number(&summary, "solution_error_max") >= last);
    assert_eq!(vector(&summary, "g").len(), 12);
    // Four points (order 6) against three (order 4) at the same step.
    let finer = json(&["run", "falling-body", "--json", "--method", "lie-svi:4"]);
    let ratio = last / number(&finer, "solution_error_final");
    assert!(ratio > 30.0, "{ratio}");
}

#[test]
fn dual_spin_satellite_full_and_reduced_forms_agree() {
    let full = json(&["run", "dual-spin", "--json", "--t-end", "5"]);
    let reduced = json(&[
        "run",
        "dual-spin",
        "--json",
        "--t-end",
        "5",
        "--form",
        "reduced",
    ]);
    assert_eq!(reduced["form"], "reduced");
    for summary in [&full, &reduced] {
        assert!(
            number(summary, "momentum_error_relative") <= 1e-14,
            "{summary}"
        );
        assert!(number(summary, "group_defect_max") <= 1e-14, "{summary}");
    }
    let (a, b) = (vector(&full, "g"), vector(&reduced, "g"));
    let distance = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(distance < 1e-11, "{distance:e}");
    // The rotor's momentum p = J(Ω₃ + φ̇) = 0.5 (0.1 + 5) is the last body momentum.
    assert!((vector(&full, "momentum")[3] - 2.55).abs() < 1e-13);
}

#[test]
fn chain_trajectory_has_entries_velocities_momenta_and_defect() {
    let scratch = Scratch::new("chain");
    let path = scratch.join("chain.csv");
    let summary = json(&[
        "run",
        "spherical-chain",
        "--json",
        "--t-end",
        "0.1",
        "--every",
        "10",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert!(
        number(&summary, "momentum_error_relative") <= 1e-14,
        "{summary}"
    );
    assert_eq!(summary["trajectory"]["rows"], 6);
    let text = std::fs::read_to_string(&path).unwrap();
    let rows = parse_csv(&text);
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(header.len(), 1 + 72 + 24 + 24 + 2);
    assert_eq!(header[..2], ["t", "g_1"]);
    assert_eq!(header[73], "xi_1");
    assert_eq!(header[97], "mu_1");
    assert_eq!(header[121..], ["energy", "defect"]);
    assert_eq!(rows.len(), 6);
    let first = cell(&rows[0], "energy");
    for row in &rows {
        assert!(cell(row, "defect") < 1e-14);
        assert!((cell(row, "energy") - first).abs() < 1e-3 * first.abs());
        // No spin about the links: Ω₃ of every link stays zero.
        assert!(cell(row, "xi_3").abs() < 1e-12 && cell(row, "xi_24").abs() < 1e-12);
    }
}

#[test]
fn a_scene_file_gives_the_initial_state_on_the_group() {
    // g₀ = exp(log) with no turn: the identity rotation at the origin moved by v = (0, 0, 5);
    // thrown straight up with no spin, the body rises and falls back: x₃(1) = 5 − g₀/2.
    let scene = scene_file(
        "group-scene",
        "model = \"falling-body\"\n[initial]\nlog = [0, 0, 0, 0, 0, 0]\n\
         xi = [0, 0, 0, 0, 0, 5]\n[run]\nt_end = 1.0\n",
    );
    let summary = json(&["run", &scene.path, "--json"]);
    let g = vector(&summary, "g");
    assert!((g[11] - (5.0 - 0.5 * 9.81)).abs() < 1e-12, "{g:?}");
}

#[test]
fn bad_input_on_a_group_is_a_typed_error() {
    let cases: [(&str, &str); 6] = [
        (
            "[initial]\nlog = [0.1, 0.2]\n",
            "initial.log: 2 components; need 6",
        ),
        (
            "[initial]\ng = [1, 0, 0, 0, 1, 0, 0, 0, 1.1, 0, 0, 0]\n",
            "initial configuration: not in SE(3)",
        ),
        (
            "[initial]\nxi = [1, 0, 0, 0, 0, 0]\nmomentum = [1, 0, 0, 0, 0, 0]\n",
            "both xi and momentum",
        ),
        (
            "[initial]\nq = [1, 0]\n",
            "initial.q: the model 'falling-body' lives on a Lie group",
        ),
        ("[initial]\nomega = [1, 0, 0]\n", "initial.omega"),
        (
            "[initial]\nxi = [1, 0, nan, 0, 0, 0]\n",
            "NaN is not finite",
        ),
    ];
    for (text, needle) in cases {
        let scene = scene_file("group-bad", &format!("model = \"falling-body\"\n{text}"));
        bad_input(&["run", &scene.path], &[], needle);
    }
    bad_input(
        &["run", "dual-spin"],
        &["--diagnostics", "solution"],
        "no exact solution",
    );
    bad_input(
        &["run", "falling-body"],
        &["--form", "reduced"],
        "needs a G-invariant Lagrangian",
    );
    bad_input(
        &["run", "spherical-chain"],
        &["--method", "svi"],
        "models on Lie groups",
    );
    bad_input(&["run", "dual-spin"], &["--param", "j=4"], "below i3");
    bad_input(
        &["ensemble", "falling-body"],
        &["--initial", "q.0=1,2"],
        "lives on a Lie group",
    );
}

#[test]
fn an_ensemble_on_a_group_tabulates_the_final_states() {
    // Every mass falls alike (the mass scales the translation's Lagrangian): both members end
    // in the same configuration, which the table gives entry by entry.
    let scratch = Scratch::new("group-ensemble");
    let path = scratch.join("table.csv");
    let summary = json(&[
        "ensemble",
        "falling-body",
        "--param",
        "m=1,2",
        "--t-end",
        "1",
        "--json",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert_eq!(
        (summary["members"].as_u64(), summary["ok"].as_u64()),
        (Some(2), Some(2))
    );
    let rows = parse_csv(&std::fs::read_to_string(&path).unwrap());
    assert_eq!(rows.len(), 2);
    // The linear momenta (μ₄, μ₅, μ₆) scale with the mass, the angular ones do not.
    for column in ["g_1", "g_12", "xi_6", "momentum_1", "momentum_4"] {
        let (light, heavy) = (cell(&rows[0], column), cell(&rows[1], column));
        let scale = if column == "momentum_4" { 2.0 } else { 1.0 };
        assert!(
            (heavy - scale * light).abs() < 1e-8,
            "{column}: {light} {heavy}"
        );
    }
    assert!(cell(&rows[1], "group_defect_max") < 1e-14);
    assert!(cell(&rows[1], "solution_error_final") < 1e-8);
}
