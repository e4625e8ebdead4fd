//! `svi ensemble` end to end: every member's row is the `svi run` of that member's scene,
//! digit for digit (the reference is the single run of the binary, an independent process);
//! the table does not depend on the thread count; a failed member is recorded and never stops
//! the others; bad input names its option with exit status 2; the plots are written.

use crate::common;
use common::*;

use std::collections::HashMap;

/// The member table of `svi ensemble ARGS --out FILE`: (exit status, header, rows by column).
fn table(args: &[&str], scratch: &Scratch, file: &str) -> (i32, Vec<HashMap<String, String>>) {
    let path = scratch.join(file);
    let mut all: Vec<&str> = vec!["ensemble"];
    all.extend(args);
    let path_text = path.to_str().unwrap().to_owned();
    all.extend(["--out", &path_text]);
    let output = svi_within(&all, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}: {stderr}"));
    (output.status.code().unwrap(), parse_csv(&text))
}

/// `svi run ARGS --json`: its stdout as text.
fn run_text(args: &[&str]) -> String {
    let output = svi(args);
    assert!(output.status.success(), "{output:?}");
    String::from_utf8(output.stdout).unwrap()
}

/// Every field of the ℝᴺ summary that has a column, compared exactly with the row.
fn assert_row_is_the_run(row: &HashMap<String, String>, text: &str) {
    let run: serde_json::Value = serde_json::from_str(text).unwrap();
    let names: Vec<String> = run["coordinates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_owned())
        .collect();
    for field in ["q", "v", "p"] {
        for (i, x) in raw(text, field).into_iter().enumerate() {
            assert_eq!(cell(row, &format!("{field}_{}", names[i])), x, "{field}");
        }
    }
    for field in [
        "t_end",
        "energy_initial",
        "energy_final",
        "energy_error_max",
        "energy_scale",
    ] {
        assert_eq!(cell(row, field), raw(text, field)[0], "{field}");
    }
    for field in ["steps", "iterations", "evaluations"] {
        assert_eq!(row[field], run[field].to_string(), "{field}");
    }
}

#[test]
fn every_member_is_the_single_run_of_its_parameters_and_a_failure_stops_none() {
    let scratch = Scratch::new("ensemble-members");
    let (status, rows) = table(
        &["kepler", "--param", "e=0.1:0.7:4,1.2", "--t-end", "20"],
        &scratch,
        "kepler.csv",
    );
    // One member failed: exit status 1, with every member in the table.
    assert_eq!(status, 1);
    assert_eq!(rows.len(), 5);
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row["member"], i.to_string());
    }
    for row in &rows[..4] {
        assert_eq!(row["status"], "ok");
        let e = &row["e"];
        let run = run_text(&[
            "run",
            "kepler",
            "--param",
            &format!("e={e}"),
            "--t-end",
            "20",
            "--diagnostics",
            "energy",
            "--json",
        ]);
        assert_row_is_the_run(row, &run);
    }
    assert_eq!(cell(&rows[1], "e"), 0.1 + 0.6 / 3.0);
    let failed = &rows[4];
    assert_eq!(failed["e"], "1.2");
    assert_eq!(failed["status"], "invalid_parameter");
    assert_eq!(failed["q_q1"], "");
    assert!(failed["error"].contains("outside [0, 1)"), "{failed:?}");
}

#[test]
fn initial_grids_set_components_of_the_default_state() {
    let scratch = Scratch::new("ensemble-initial");
    let (status, rows) = table(
        &[
            "double-pendulum",
            "--initial",
            "q.alpha1=-1:1:3",
            "--initial",
            "v.1=0,0.5",
            "--t-end",
            "0.5",
        ],
        &scratch,
        "initial.csv",
    );
    assert_eq!(status, 0);
    assert_eq!(rows.len(), 6);
    // Member 3: alpha1 = 0 (second value, first axis slowest), v2 = 0.5.
    let row = &rows[3];
    assert_eq!((cell(row, "q.alpha1"), cell(row, "v.1")), (0.0, 0.5));
    // The same state written into a scene file (alpha2 = 0.5 and v1 = 0 are the defaults).
    let scene = scene_file(
        "ensemble-initial-scene",
        "model = \"double-pendulum\"\n[initial]\nq = [0.0, 0.5]\nv = [0.0, 0.5]\n[method]\nname = \"svi\"\npoints = 6\n",
    );
    let run = run_text(&[
        "run",
        &scene.path,
        "--t-end",
        "0.5",
        "--diagnostics",
        "energy",
        "--json",
    ]);
    assert_row_is_the_run(row, &run);
}

#[test]
fn the_table_is_the_same_on_one_thread_and_two_and_draws_repeat_with_the_seed() {
    let scratch = Scratch::new("ensemble-threads");
    let args = |threads: &'static str, seed: &'static str| {
        vec![
            "kepler",
            "--param",
            "e=0:0.8",
            "--random",
            "40",
            "--seed",
            seed,
            "--t-end",
            "10",
            "--threads",
            threads,
        ]
    };
    let read = |file: &str| std::fs::read_to_string(scratch.join(file)).unwrap();
    assert_eq!(table(&args("1", "7"), &scratch, "one.csv").0, 0);
    assert_eq!(table(&args("2", "7"), &scratch, "two.csv").0, 0);
    assert_eq!(table(&args("0", "8"), &scratch, "other.csv").0, 0);
    assert_eq!(read("one.csv"), read("two.csv"));
    assert_ne!(read("one.csv"), read("other.csv"));
    let rows = parse_csv(&read("one.csv"));
    assert_eq!(rows.len(), 40);
    assert!(rows.iter().all(|row| (0.0..=0.8).contains(&cell(row, "e"))));
}

#[test]
fn the_json_summary_counts_members_by_status() {
    let output = svi(&[
        "ensemble",
        "kepler",
        "--param",
        "e=0.2,0.4,1.5",
        "--t-end",
        "2",
        "--json",
        "--threads",
        "2",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let summary: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(summary["members"], 3);
    assert_eq!(summary["ok"], 2);
    assert_eq!(summary["failed"], 1);
    assert_eq!(summary["failures"]["invalid_parameter"], 1);
    assert_eq!(summary["threads"], 2);
    assert_eq!(summary["varied"], serde_json::json!(["e"]));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("1 of 3 members failed (invalid_parameter: 1)"),
        "{stderr}"
    );
    // Without --out and --json the table goes to stdout.
    let output = svi(&["ensemble", "kepler", "--param", "e=0.2,0.4", "--t-end", "2"]);
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    assert_eq!(parse_csv(&text).len(), 2);
}

#[test]
fn bad_ensembles_name_their_option_with_exit_status_2() {
    let ensemble = ["ensemble", "kepler", "--t-end", "1"];
    for (args, needle) in [
        (vec!["--param", "e=0.1:0.9:0"], "COUNT is 0"),
        (vec!["--param", "e=0.9:0.1:3"], "exceeds HI"),
        (vec!["--param", "e=0.1:nan:3"], "not a finite number"),
        (vec!["--param", "x=0.1:0.9:3"], "no parameter 'x'"),
        (vec!["--param", "e=0.1:0.9"], "only --random draws"),
        (vec!["--initial", "q.q9=0:1:2"], "no coordinate 'q9'"),
        (vec!["--initial", "z.q1=0:1:2"], "unknown field 'z'"),
        (
            vec!["--param", "e=0:1:3", "--threads", "100000"],
            "--threads",
        ),
        (vec!["--param", "e=0:1:3", "--threads", "-1"], "--threads"),
        (vec!["--param", "e=0:1:3", "--seed", "3"], "--seed"),
        (vec!["--param", "e=0:1", "--random", "0"], "--random"),
        (
            vec![
                "--param",
                "e=0:1:3",
                "--plot",
                "x.gif",
                "--plot-value",
                "q_q1",
            ],
            "--plot",
        ),
        (vec!["--param", "e=0:1:3", "--h", "-1"], "h"),
    ] {
        bad_input(&ensemble, &args, needle);
    }
}

#[test]
fn plots_draw_a_sweep_and_a_heat_map() {
    let scratch = Scratch::new("ensemble-plots");
    let svg = scratch.join("sweep.svg");
    let output = svi(&[
        "ensemble",
        "kepler",
        "--param",
        "e=0:0.8:9",
        "--t-end",
        "20",
        "--out",
        scratch.join("sweep.csv").to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
        "--plot-value",
        "energy_error_max",
    ]);
    assert!(output.status.success(), "{output:?}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("energy_error_max"));
    let png = scratch.join("map.png");
    let output = svi(&[
        "ensemble",
        "double-pendulum",
        "--initial",
        "q.alpha1=-3:3:4",
        "--initial",
        "q.alpha2=-3:3:5",
        "--t-end",
        "0.2",
        "--json",
        "--plot",
        png.to_str().unwrap(),
        "--plot-value",
        "q_alpha2",
        "--plot-cyclic",
    ]);
    assert!(output.status.success(), "{output:?}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // 400 / 5 = 80 pixels per cell: 320 × 400.
    assert_eq!(&bytes[16..24], &[0, 0, 1, 64, 0, 0, 1, 144]);
    let missing = svi(&[
        "ensemble",
        "kepler",
        "--param",
        "e=0:0.8:3",
        "--t-end",
        "1",
        "--json",
        "--plot",
        scratch.join("none.svg").to_str().unwrap(),
        "--plot-value",
        "nothing",
    ]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no column 'nothing'"));
}

/// `--max-steps` bounds every member: an adaptive member that needs more steps is a row with
/// status `too_many_steps` (and `steps` at the budget); the others run.
#[test]
fn the_step_budget_bounds_every_member() {
    let scratch = Scratch::new("ensemble-budget");
    let (status, rows) = table(
        &[
            "kepler",
            "--param",
            "e=0.1,0.95",
            "--adapt",
            "step",
            "--tol",
            "1e-10",
            "--t-end",
            "20",
            "--max-steps",
            "300",
        ],
        &scratch,
        "budget.csv",
    );
    assert_eq!(status, 1);
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["status"], "ok", "{:?}", rows[0]);
    assert!(cell(&rows[0], "steps") <= 300.0);
    assert_eq!(rows[1]["status"], "too_many_steps", "{:?}", rows[1]);
    assert_eq!(cell(&rows[1], "steps"), 300.0);
}

/// Chains (zoo and text) and Lagrangians written as text run as ensembles: a chain's row has
/// its scalars and no column per site, each row is the single run of that member; an initial
/// component of a chain is refused naming the reason, and a text model's is set by name.
#[test]
fn chains_and_text_models_run_as_ensembles() {
    let scratch = Scratch::new("ensemble-chains");
    // The zoo chain and the same chain written as text.
    for scene in ["fput", "fput-text"] {
        let args = [
            scene,
            "--param",
            "n=16",
            "--param",
            "beta=0.5,1",
            "--t-end",
            "5",
        ];
        let (status, rows) = table(&args, &scratch, &format!("{scene}.csv"));
        assert_eq!(status, 0, "{rows:?}");
        assert_eq!(rows.len(), 2);
        for row in &rows {
            assert_eq!(row["status"], "ok");
            assert!(
                !row.keys().any(|column| column.starts_with("q_")),
                "{row:?}"
            );
            let beta = format!("beta={}", row["beta"]);
            let run = run_text(&[
                "run",
                scene,
                "--param",
                "n=16",
                "--param",
                &beta,
                "--t-end",
                "5",
                "--diagnostics",
                "energy",
                "--json",
            ]);
            for field in ["energy_initial", "energy_error_max"] {
                assert_eq!(cell(row, field), raw(&run, field)[0], "{field}");
            }
            // SVI 6/12 keeps the chain's energy to round-off.
            assert!(cell(row, "energy_error_max") <= 1e-12 * cell(row, "energy_initial"));
        }
        // A stiffer spring stores more energy in the same displacement.
        assert!(cell(&rows[1], "energy_initial") > cell(&rows[0], "energy_initial"));
    }
    bad_input(
        &["ensemble", "fput", "--param", "n=16"],
        &["--initial", "q.q1=0:1:2"],
        "site by site",
    );
    let (status, rows) = table(
        &["kepler-text", "--initial", "q.x=0.5,0.6", "--t-end", "10"],
        &scratch,
        "kepler-text.csv",
    );
    assert_eq!(status, 0, "{rows:?}");
    // The first member starts from the scene's own state: it is the scene's run.
    let run = run_text(&["run", "kepler-text", "--t-end", "10", "--json"]);
    assert_eq!(cell(&rows[0], "q_x"), raw(&run, "q")[0]);
    assert_eq!(cell(&rows[0], "q_y"), raw(&run, "q")[1]);
    assert_ne!(cell(&rows[1], "q_x"), cell(&rows[0], "q_x"));
}
