//! Events, Poincaré sections and chaos indicators through the binary: Kepler's pericentres at
//! 2πk from `--event`, a terminal event that ends the run with status ok, the Hénon–Heiles
//! section's points on their surface, the same numbers from a scene file's `[[events]]`,
//! MEGNO and the Lyapunov spectrum of the chaotic and a regular orbit, the ensemble's section
//! picture and indicator columns, and bad input as typed errors.

use crate::common;
use common::*;

use std::f64::consts::TAU;

#[test]
fn kepler_pericentres_are_events_at_two_pi_k() {
    let summary = json(&[
        "run",
        "kepler",
        "--t-end",
        "40",
        "--event",
        "pericentre: q1*vq1 + q2*vq2 @up",
        "--json",
    ]);
    let events = summary["events"].as_array().unwrap();
    assert_eq!(events.len(), 6);
    for (k, event) in events.iter().enumerate() {
        assert_eq!(event["name"], "pericentre");
        let t = number(event, "t");
        // SVI 6 points at h = 0.2: the run's phase error, growing to 1e-8 at t = 8π.
        assert!((t - TAU * (k + 1) as f64).abs() < 3e-8, "{k}: {t}");
        let q = vector(event, "q");
        assert!((q[0] - 0.5).abs() < 1e-9 && q[1].abs() < 1e-7, "{q:?}");
    }
    assert_eq!(summary["terminal_event"], serde_json::Value::Null);
    assert!(number(&summary, "t_end") == 40.0);
}

#[test]
fn a_terminal_event_ends_the_run_with_status_ok_and_names_itself() {
    let scene = scene_file(
        "terminal-event",
        r#"
model = "kepler"
[run]
h = 0.05
t_end = 100.0
[[events]]
name = "apocentre"
g = "q1*vq1 + q2*vq2"
direction = "down"
terminal = true
"#,
    );
    let output = svi(&["run", &scene.path, "--json"]);
    assert_eq!(output.status.code(), Some(0));
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(summary["status"], "ok");
    assert_eq!(summary["terminal_event"], "apocentre");
    let t = number(&summary, "t_end");
    assert!((t - TAU / 2.0).abs() < 1e-9, "{t}");
    // The state is the apocentre's: (−1.5, 0) at rest in r.
    let q = vector(&summary, "q");
    assert!((q[0] + 1.5).abs() < 1e-9 && q[1].abs() < 1e-8, "{q:?}");
    let text = String::from_utf8(svi(&["run", &scene.path]).stdout).unwrap();
    assert!(
        text.contains("ended by") && text.contains("terminal event apocentre"),
        "{text}"
    );
}

#[test]
fn the_henon_heiles_section_lies_on_its_surface_and_is_drawn() {
    let scratch = Scratch::new("section");
    let (csv, svg) = (scratch.join("section.csv"), scratch.join("section.svg"));
    let summary = json(&[
        "run",
        "henon-heiles",
        "--section",
        "x=0,vx>0",
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
        "--json",
    ]);
    let section = &summary["section"];
    assert_eq!(section["surface"], "x=0,vx>0");
    assert_eq!(section["axes"], serde_json::json!(["q_y", "v_y"]));
    let rows = parse_csv(&std::fs::read_to_string(&csv).unwrap());
    assert_eq!(rows.len() as f64, number(section, "points"));
    // About one crossing per 6.7 time units over T = 2000.
    assert!(rows.len() > 250, "{}", rows.len());
    for row in &rows {
        assert!(cell(row, "q_x").abs() < 1e-12, "{row:?}");
        assert!(cell(row, "v_x") > 0.0);
        assert!((cell(row, "energy") - 0.125).abs() < 1e-12);
    }
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(
        picture.matches("<circle").count(),
        rows.len() + 1,
        "points and legend"
    );
    // Positional names mean the same section.
    let same = json(&["run", "henon-heiles", "--section", "q1=0,v1>0", "--json"]);
    assert_eq!(same["section"]["points"], section["points"]);
}

#[test]
fn indicators_tell_the_chaotic_orbit_from_a_regular_one() {
    let chaotic = json(&[
        "run",
        "henon-heiles",
        "--indicators",
        "megno,spectrum,lyapunov,sali,gali",
        "--json",
    ]);
    let spectrum = vector(&chaotic, "lyapunov");
    assert_eq!(spectrum.len(), 4);
    let sum: f64 = spectrum.iter().sum();
    assert!(sum.abs() < 1e-10, "{sum:e}");
    assert!(spectrum[0] > 0.03, "{spectrum:?}");
    assert!((spectrum[0] + spectrum[3]).abs() < 1e-2, "{spectrum:?}");
    // ⟨Y⟩ ≈ λt/2 on a chaotic orbit (T = 2000).
    assert!(number(&chaotic, "megno") > 20.0);
    assert!(number(&chaotic, "sali") < 1e-8);
    assert!(number(&chaotic, "gali") < 1e-8);
    // The tangent run is the plain run: the same final state and the same work of the
    // steps' solves.
    let plain = json(&["run", "henon-heiles", "--json"]);
    assert_eq!(chaotic["q"], plain["q"]);
    for work in ["iterations", "evaluations"] {
        assert!(number(&plain, work) > 0.0);
        assert_eq!(chaotic[work], plain[work], "{work}");
    }
    let regular = json(&[
        "run",
        "henon-heiles",
        "--param",
        "energy=0.08333333333333333",
        "--param",
        "y0=0",
        "--indicators",
        "megno,sali,gali",
        "--json",
    ]);
    assert!((number(&regular, "megno") - 2.0).abs() < 0.1, "{regular}");
    assert!(number(&regular, "sali") > 1e-3);
    assert!(number(&regular, "gali") > 1e-3);
}

#[test]
fn an_ensemble_draws_its_members_sections_and_tabulates_indicators() {
    let scratch = Scratch::new("ensemble-section");
    let (table, svg) = (scratch.join("members.csv"), scratch.join("section.svg"));
    let output = svi(&[
        "ensemble",
        "henon-heiles",
        "--param",
        "y0=-0.3:0.5:5",
        "--section",
        "x=0,vx>0",
        "--t-end",
        "300",
        "--out",
        table.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let rows = parse_csv(&std::fs::read_to_string(&table).unwrap());
    let points: f64 = rows.iter().map(|row| cell(row, "section_points")).sum();
    let picture = std::fs::read_to_string(&svg).unwrap();
    // Every point, and the legend's five markers.
    assert_eq!(picture.matches("<circle").count() as f64, points + 5.0);
    let output = svi(&[
        "ensemble",
        "henon-heiles",
        "--param",
        "y0=-0.2,0",
        "--param",
        "energy=0.125,0.08333333333333333",
        "--indicators",
        "megno",
        "--t-end",
        "500",
    ]);
    let rows = parse_csv(&String::from_utf8(output.stdout).unwrap());
    let megno: Vec<f64> = rows.iter().map(|row| cell(row, "megno")).collect();
    // (−0.2, 1/8) chaotic, (0, 1/12) regular.
    assert!(megno[0] > 5.0 && (megno[3] - 2.0).abs() < 0.2, "{megno:?}");
}

#[test]
fn bad_events_sections_and_indicators_are_typed_errors() {
    let run = ["run", "henon-heiles"];
    bad_input(&run, &["--section", "z=0"], "'z'");
    bad_input(&run, &["--section", "q3=0,v3>0"], "'q3'");
    bad_input(&run, &["--section", "vx=0"], "is a velocity");
    bad_input(&run, &["--section", "x"], "no surface");
    bad_input(&run, &["--event", "x + w"], "unknown symbol 'w'");
    bad_input(&run, &["--event", "e: x @sideways"], "@sideways");
    bad_input(
        &run,
        &["--indicators", "megno", "--adapt", "step"],
        "fixed steps",
    );
    bad_input(
        &run,
        &["--indicators", "megno", "--section", "x=0"],
        "--indicators",
    );
    bad_input(
        &run,
        &["--section", "x=0", "--output-times", "1"],
        "--output-times",
    );
    bad_input(
        &["run", "rigid-body"],
        &["--indicators", "megno"],
        "rigid-body",
    );
    bad_input(&["run", "rigid-body"], &["--event", "t - 1"], "rigid-body");
    // A chain: its coordinates have no names (it said "rigid-body scenes have none").
    for flags in [["--event", "t - 1"], ["--section", "q1=0"]] {
        let stderr = bad_input(&["run", "fput"], &flags, "a chain of any size");
        assert!(!stderr.contains("rigid-body"), "{stderr}");
    }
    bad_input(
        &["run", "spherical-pendulum"],
        &["--event", "t - 1"],
        "constrained",
    );
    // A function that is not finite is a failed run naming the event (exit status 1).
    let output = svi(&["run", "henon-heiles", "--event", "bad: 1/(t - t)", "--json"]);
    assert_eq!(output.status.code(), Some(1));
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert!(
        summary["error"]["message"]
            .as_str()
            .unwrap()
            .contains("event 'bad'"),
        "{summary}"
    );
}

#[test]
fn the_events_file_holds_every_event_and_a_failed_run_keeps_its_events() {
    let scratch = Scratch::new("events-out");
    let path = scratch.join("events.csv");
    let file = path.to_str().unwrap();
    // Kepler e = 0.5 from its pericentre (period 2π): apocentres (y falling through 0) at
    // π, 3π, 5π and pericentres at 2π, 4π, 6π, in time order in the file.
    let summary = json(&[
        "run",
        "kepler",
        "--method",
        "svi:9/8",
        "--t-end",
        "20",
        "--event",
        "peri: q1*vq1 + q2*vq2 @up",
        "--event",
        "q2 @down",
        "--events-out",
        file,
        "--json",
    ]);
    let rows = parse_csv(&std::fs::read_to_string(&path).unwrap());
    assert_eq!(rows.len(), 6);
    let events = summary["events"].as_array().unwrap();
    for (k, (row, event)) in rows.iter().zip(events).enumerate() {
        let name = if k % 2 == 0 { "event2" } else { "peri" };
        assert_eq!(row["event"], name);
        assert_eq!(event["name"], name);
        // The file's numbers are the summary's (serde_json's parser may be off in the last
        // digit).
        let same = |a: f64, b: f64| (a - b).abs() <= 2.0 * f64::EPSILON * a.abs();
        assert!(same(cell(row, "t"), number(event, "t")));
        assert!(same(cell(row, "q_q1"), vector(event, "q")[0]));
        assert!(same(cell(row, "p_q2"), vector(event, "p")[1]));
        assert!(
            (cell(row, "t") - TAU / 2.0 * (k + 1) as f64).abs() < 1e-9,
            "{row:?}"
        );
    }
    // An event that turns NaN after t = 5 fails the run (status 1); the apocentre at π and the
    // zero of the failing function at t = 5 were located first, and are kept in the summary
    // and the file.
    let output = svi(&[
        "run",
        "kepler",
        "--t-end",
        "20",
        "--event",
        "q2 @down",
        "--event",
        "late: sqrt(5 - t)",
        "--events-out",
        file,
        "--json",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let events = summary["events"].as_array().unwrap();
    let names: Vec<&str> = events.iter().map(|e| e["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["event1", "late"]);
    assert!((number(&events[0], "t") - TAU / 2.0).abs() < 1e-8);
    let rows = parse_csv(&std::fs::read_to_string(&path).unwrap());
    assert_eq!(rows.len(), 2);
    assert!((cell(&rows[1], "t") - number(&events[1], "t")).abs() < 1e-15);
    // The file needs events, is CSV and is no other output's file.
    let run = ["run", "kepler"];
    bad_input(&run, &["--events-out", file], "give --event");
    bad_input(
        &run,
        &["--event", "q2", "--events-out", "events.svg"],
        "not a picture",
    );
    bad_input(
        &run,
        &["--event", "q2", "--events-out", file, "--out", file],
        "writes the same file",
    );
}
