//! `svi run --sensitivity`: the Jacobians of a run in its JSON summary, against central
//! differences of whole runs of the binary (`--param`, `[initial]`), the start's own
//! derivatives (the identity, and Kepler's pericentre as a function of e), and bad input.

use crate::common;
use common::*;
use serde_json::Value;

/// The final state (q, then v) of `svi run` with `args` and the JSON summary.
fn final_state(args: &[&str]) -> Vec<f64> {
    let summary = json(args);
    let mut out = vector(&summary, "q");
    out.extend(vector(&summary, "v"));
    out
}

/// The Jacobian of the last output, row by row.
fn last_jacobian(summary: &Value) -> Vec<Vec<f64>> {
    let outputs = summary["sensitivity"]["outputs"].as_array().unwrap();
    let last = outputs.last().unwrap();
    last["jacobian"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn kepler_sensitivity_to_e_and_q0_matches_differences_of_whole_runs() {
    let run = [
        "run", "kepler", "--json", "--h", "0.05", "--t-end", "3", "--method", "svi:5",
    ];
    let mut args = run.to_vec();
    args.extend(["--sensitivity", "e,q0"]);
    let summary = json(&args);
    let block = &summary["sensitivity"];
    assert_eq!(block["columns"], serde_json::json!(["e", "q0_q1", "q0_q2"]));
    assert_eq!(
        block["rows"],
        serde_json::json!(["q_q1", "q_q2", "v_q1", "v_q2"])
    );
    let outputs = block["outputs"].as_array().unwrap();
    assert_eq!(outputs.len(), 2, "the start and the end");
    // At the start: ∂q₀/∂e = (−1, 0) (the pericentre 1 − e), ∂q₀/∂q₀ = I.
    let start = &outputs[0]["jacobian"];
    assert_eq!(start[0], serde_json::json!([-1.0, 1.0, 0.0]));
    assert_eq!(start[1], serde_json::json!([0.0, 0.0, 1.0]));
    // ∂v₀/∂e = (0, d/de √((1 + e)/(1 − e))) = (0, 1/((1 − e)² √((1 + e)/(1 − e)))) at e = ½.
    let dv = 1.0 / (0.25 * 3.0_f64.sqrt());
    assert!(
        (start[3][0].as_f64().unwrap() - dv).abs() < 1e-14,
        "{start}"
    );
    // The end against central differences in e (the start moves with it) ...
    let jacobian = last_jacobian(&summary);
    let delta = 1e-5;
    let (mut plus, mut minus) = (run.to_vec(), run.to_vec());
    let (e_plus, e_minus) = (format!("e={}", 0.5 + delta), format!("e={}", 0.5 - delta));
    plus.extend(["--param", &e_plus]);
    minus.extend(["--param", &e_minus]);
    let (up, down) = (final_state(&plus), final_state(&minus));
    for row in 0..4 {
        let difference = (up[row] - down[row]) / (2.0 * delta);
        assert!(
            (jacobian[row][0] - difference).abs() <= 1e-7 * difference.abs().max(1.0),
            "∂{row}/∂e: {} against {difference}",
            jacobian[row][0]
        );
    }
    // ... and in q0₂, from a scene whose start is given (e then does not move it).
    let scene = |q2: f64| {
        scene_file(
            &format!("sensitivity-kepler-{}", q2.to_bits()),
            &format!(
                "model = \"kepler\"\n[initial]\nq = [0.5, {q2}]\nv = [0.0, 1.7320508075688772]\n"
            ),
        )
    };
    let given = scene(0.0);
    let mut args = vec![given.path.as_str()];
    args.extend(&run[2..]);
    args.extend(["--sensitivity", "q0,e"]);
    let summary = json(&[&["run"], args.as_slice()].concat());
    let jacobian = last_jacobian(&summary);
    let (up_scene, down_scene) = (scene(delta), scene(-delta));
    let state = |file: &SceneFile| {
        let mut args = vec!["run", file.path.as_str()];
        args.extend(&run[2..]);
        final_state(&args)
    };
    let (up, down) = (state(&up_scene), state(&down_scene));
    for row in 0..4 {
        let difference = (up[row] - down[row]) / (2.0 * delta);
        assert!(
            (jacobian[row][1] - difference).abs() <= 1e-7 * difference.abs().max(1.0),
            "∂{row}/∂q0_q2: {} against {difference}",
            jacobian[row][1]
        );
        // e chooses nothing of a given start and does not enter L.
        assert_eq!(jacobian[row][2], 0.0);
    }
}

#[test]
fn damped_pendulum_sensitivities_are_reported_every_k_steps() {
    let summary = json(&[
        "run",
        "damped-pendulum",
        "--json",
        "--t-end",
        "2",
        "--sensitivity",
        "q0,v0,l,c",
        "--sensitivity-every",
        "5",
    ]);
    let block = &summary["sensitivity"];
    assert_eq!(
        block["columns"],
        serde_json::json!(["q0_theta", "v0_theta", "l", "c"])
    );
    let outputs = block["outputs"].as_array().unwrap();
    // 20 steps of 0.1: the start and steps 5, 10, 15, 20.
    let times: Vec<f64> = outputs.iter().map(|o| o["t"].as_f64().unwrap()).collect();
    assert_eq!(times.len(), 5, "{times:?}");
    assert!((times[2] - 1.0).abs() < 1e-12, "{times:?}");
    // The last output is the summary's final state (the derivatives' run solves the same
    // steps by Newton's method, the scene's by a fixed point: round-off apart).
    let last = outputs.last().unwrap();
    let (a, b) = (
        last["q"][0].as_f64().unwrap(),
        summary["q"][0].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-13, "{a} against {b}");
    // Friction slows the pendulum: from θ₀ = 1 at rest, more friction leaves it further
    // from the bottom at t = 2 (it has not yet swung through).
    let jacobian = last_jacobian(&summary);
    assert!(
        jacobian[0][3] > 0.0 && jacobian[0][3].is_finite(),
        "{jacobian:?}"
    );
}

#[test]
fn sensitivity_bad_input_is_refused_naming_it() {
    let run = ["run", "--t-end", "1"];
    bad_input(&run, &["kepler", "--sensitivity", "mass"], "'mass'");
    bad_input(
        &run,
        &["pendulum", "--sensitivity", "q0"],
        "kepler, damped-pendulum",
    );
    bad_input(
        &run,
        &["kepler", "--sensitivity", "e", "--adapt", "step"],
        "--adapt",
    );
    bad_input(
        &run,
        &["kepler", "--sensitivity", "e", "--output-times", "0.5"],
        "--output-times",
    );
    bad_input(
        &run,
        &["kepler", "--sensitivity-every", "3"],
        "--sensitivity",
    );
    bad_input(
        &run,
        &["kepler", "--sensitivity", "e", "--sensitivity-every", "0"],
        "0 steps",
    );
    bad_input(&run, &["kepler", "--sensitivity", "p0"], "name v0");
    bad_input(&run, &["kepler", "--sensitivity", "e,e"], "named twice");
    // A model written as text is named as one (it said "model '' has no parameters").
    bad_input(
        &run,
        &["kepler-text", "--sensitivity", "q0"],
        "a model written as text has no parameters that can be differentiated",
    );
}
