//! `svi run` and `svi bench` on the pseudospectral scenes (issue 19, §5.8): the Schrödinger
//! packet and the NLS soliton with their norm and errors, the space-time CSV and picture, the
//! work–precision bench of the Galerkin SVI against Strang, and bad input with exit status 2.

use crate::common;

use common::{Scratch, bad_input, json, number, scene_file, svi};

#[test]
fn the_pseudospectral_scenes_run_with_norm_error_and_ffts() {
    // Errors at the scenes' defaults, measured once: the linear-in-time packet 4.3e-4 (order
    // 2, h = 1e-3), the soliton with svi:4 (order 6, h = 0.05) 3.9e-12, Strang (h = 1e-3)
    // 9.2e-7; the norm is kept to round-off by all three.
    for (arguments, method, largest_error) in [
        (vec!["schrodinger-packet"], "midpoint", 1e-3),
        (vec!["nls-soliton"], "svi:4/3", 1e-10),
        (vec!["nls-soliton-strang", "--t-end", "2"], "strang", 1e-6),
    ] {
        let mut args = vec!["run"];
        args.extend(&arguments);
        args.push("--json");
        let summary = json(&args);
        assert_eq!(summary["status"], "ok", "{summary}");
        assert_eq!(summary["method"], method);
        let error = number(&summary, "error_max");
        assert!(error > 0.0 && error < largest_error, "{summary}");
        assert!(number(&summary, "norm_error_max") < 1e-13, "{summary}");
        assert!(number(&summary, "ffts") > 0.0);
    }
    // --method on the command line: the seed's scheme on the soliton, order 2.
    let summary = json(&[
        "run",
        "nls-soliton",
        "--method",
        "midpoint",
        "--h",
        "0.01",
        "--t-end",
        "1",
        "--json",
    ]);
    assert_eq!(summary["order"], 2);
    assert!(number(&summary, "error_max") < 1e-4, "{summary}");
}

#[test]
fn the_field_is_written_as_t_x_abs_re_im_rows_and_drawn() {
    let scratch = Scratch::new("soliton-plot");
    let (csv, svg) = (scratch.join("soliton.csv"), scratch.join("soliton.svg"));
    let summary = json(&[
        "run",
        "nls-soliton",
        "--param",
        "points=128",
        "--t-end",
        "1",
        "--h",
        "0.1",
        "--out",
        csv.to_str().unwrap(),
        "--every",
        "5",
        "--plot",
        svg.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(summary["trajectory"]["rows"], 3 * 128);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,x,abs,re,im"));
    let rows: Vec<Vec<f64>> = lines
        .map(|line| line.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    // At x = 0, t = 0 (node 64 of [−40, 40) with 128 nodes) ψ = η = 1.
    assert_eq!(rows[64][..2], [0.0, 0.0]);
    assert!((rows[64][2] - 1.0).abs() < 1e-15 && (rows[64][3] - 1.0).abs() < 1e-15);
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg") && picture.contains("nls-soliton: |ψ| from"));
}

#[test]
fn bad_pseudospectral_input_is_exit_status_two() {
    let run = ["run"];
    bad_input(
        &run,
        &["nls-soliton", "--param", "points=511"],
        "even number",
    );
    bad_input(&run, &["nls-soliton", "--param", "points=2"], "modes");
    bad_input(&run, &["nls-soliton", "--h", "0"], "h");
    bad_input(&run, &["nls-soliton", "--h", "2"], "convergence limit");
    bad_input(&run, &["nls-soliton", "--param", "eta=nan"], "eta");
    bad_input(
        &run,
        &["nls-soliton", "--indicators", "megno"],
        "--indicators: 'nls-soliton' is a pseudospectral scene: it takes",
    );
    bad_input(
        &run,
        &["nls-soliton", "--method", "verlet"],
        "pseudospectral scene takes",
    );
    bad_input(
        &run,
        &["nls-soliton", "--method", "svi:4/4"],
        "Gauss points",
    );
    bad_input(
        &run,
        &["schrodinger-packet", "--adapt", "step"],
        "pseudospectral scene",
    );
    let file = scene_file(
        "spectral-unknown",
        "model = \"nls-soliton\"\n[mesh]\nquadrature = \"midpoint\"\n",
    );
    bad_input(&run, &[&file.path], "quadrature");
}

#[test]
fn the_bench_compares_the_galerkin_svi_with_strang() {
    let scratch = Scratch::new("spectral-bench");
    let dir = scratch.join("out");
    let output = svi(&[
        "bench",
        "nls-soliton",
        "--methods",
        "svi:4,strang",
        "--t-end",
        "1",
        "--steps",
        "8,16,32",
        "--batches",
        "1",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{output:?}");
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.starts_with("method,steps,h,error,seconds,ffts,norm_error_max\n"),
        "{text}"
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("svi:4/3,")).count(),
        3
    );
    assert_eq!(text.lines().filter(|l| l.starts_with("strang,")).count(), 3);
    assert!(text.contains("time to error 1e-8"), "{text}");
    let picture = std::fs::read_to_string(dir.join("nls-soliton.svg")).unwrap();
    assert!(picture.contains("error against FFTs"));
    assert!(
        picture.contains("error 1e-8"),
        "the crossing error is drawn"
    );
    bad_input(
        &["bench"],
        &["nls-soliton", "--methods", "rk4"],
        "pseudospectral scene takes",
    );
}
