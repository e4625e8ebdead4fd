//! The commands called in-process, through the library's API: runs of scenes, work–precision
//! sweeps, stability analyses, scaling measurements and gradients that need every model and
//! method.
//!
//! These tests were unit tests of the modules they test. Here they link the library as CI
//! builds it once, instead of a second, test-mode copy of every model × method
//! monomorphisation (about six minutes of a two-core CI build).

/// A built-in scene.
fn scene(name: &str) -> svi_experiments::Scene {
    svi_experiments::Scene::builtin(name)
        .expect("built-in")
        .expect("parses")
}

/// A method written `name`, `name:P` or `name:P/M`.
fn method(text: &str) -> svi::method::registry::MethodSpec {
    text.parse().expect("a method")
}

mod run {
    use super::{method, scene};
    use svi_experiments::scene::overrides::RunFlags;
    use svi_experiments::{Control, Diagnostic, Overrides, Parameters, Scene, SceneError};

    #[test]
    fn classic_methods_have_neither_points_nor_quadrature() {
        for name in [
            "symplectic-euler",
            "symplectic-euler-adjoint",
            "midpoint",
            "verlet",
            "trapezoid",
        ] {
            let kind = method(name);
            assert_eq!(kind.name(), name);
            assert!(!kind.entry().takes_points());
            // The scene's `points = 9` is ignored, a `--points` flag is an error.
            let mut scene = scene("oscillator");
            scene
                .apply(&Overrides {
                    run: RunFlags {
                        method: Some(kind.into()),
                        ..RunFlags::default()
                    },
                    ..Overrides::default()
                })
                .unwrap();
            assert_eq!((scene.points(), scene.quadrature()), (None, None));
            let error = scene
                .apply(&Overrides {
                    run: RunFlags {
                        points: Some(4),
                        ..RunFlags::default()
                    },
                    ..Overrides::default()
                })
                .unwrap_err();
            assert_eq!(
                error.to_string(),
                format!(
                    "--points is an option of svi, svi-newton, svi-h, sc, sc-h and multiscale, not of {}",
                    kind.name()
                )
            );
            let summary = scene.run(Control::QUIET).unwrap();
            assert_eq!(summary.method, kind.name());
            assert_eq!((summary.points, summary.quadrature), (None, None));
            assert!(summary.symplectic && summary.order <= 2);
            // h = 1 on the oscillator: first- and second-order methods are coarse (the phase
            // is lost) but stable, with bounded energy error.
            assert!(summary.energy_error_max.unwrap() <= 0.5, "{kind}");
            assert!(
                summary.conservation.solution_error_final().unwrap() < 2.0,
                "{kind}"
            );
        }
    }

    #[test]
    fn the_damped_oscillator_scene_reports_its_solution_error() {
        let mut scene = scene("damped-oscillator");
        assert_eq!(scene.parameters["zeta"], 0.1);
        assert_eq!((scene.run.h, scene.run.t_end), (Some(0.1), Some(50.0)));
        // By default only the error at the end; the largest over the run when asked for.
        let summary = scene.run(Control::QUIET).unwrap();
        assert_eq!(summary.conservation.solution_error_max(), None);
        let last = summary.conservation.solution_error_final().unwrap();
        assert!(last < 1e-12, "{last:e}");
        scene.output.diagnostics = Some(vec![Diagnostic::Solution]);
        let summary = scene.run(Control::QUIET).unwrap();
        assert_eq!(summary.steps, 500);
        let max = summary.conservation.solution_error_max().unwrap();
        assert!(max < 1e-12 && max >= last, "{max:e} {last:e}");
        assert_eq!(summary.conservation.solution_error_final(), Some(last));
        // E(50) = E(0) e^{−5}-ish: the friction removed almost all the energy.
        assert!(summary.energy_final < 0.01 * summary.energy_initial);
        let mut verlet = scene.clone();
        verlet.method.name = Some(method("verlet").into());
        let summary = verlet.run(Control::QUIET).unwrap();
        // Second order: 1.6e-3 at h = 0.1.
        let error = summary.conservation.solution_error_max().unwrap();
        assert!(error > 1e-3 && error < 2e-3, "{error:e}");
        assert_eq!(summary.evaluations, 501);
    }

    #[test]
    fn wrong_dimension_names_field_and_sizes() {
        let text = "model = \"kepler\"\n[initial]\nq = [1, 0, 0]\n";
        let error = Scene::from_toml(text, "t")
            .unwrap()
            .run(Control::QUIET)
            .unwrap_err();
        assert!(matches!(
            &error,
            SceneError::Dimension {
                field: "q",
                expected: 2,
                found: 3,
                ..
            }
        ));
        assert_eq!(
            error.to_string(),
            "initial.q has 3 components, but model 'kepler' has dimension 2"
        );
        let text = "model = \"oscillator\"\n[initial]\np = []\n";
        let error = Scene::from_toml(text, "t")
            .unwrap()
            .run(Control::QUIET)
            .unwrap_err();
        assert!(matches!(
            error,
            SceneError::Dimension {
                field: "p",
                expected: 1,
                found: 0,
                ..
            }
        ));
    }

    #[test]
    fn an_unknown_model_lists_the_known_ones() {
        let error = Scene::from_toml("model = \"kepler3\"\n", "t")
            .unwrap()
            .run(Control::QUIET)
            .unwrap_err();
        assert!(matches!(error, SceneError::UnknownModel(_)));
        assert!(error.to_string().contains("known: oscillator, pendulum"));
    }

    #[test]
    fn a_run_that_asks_for_nothing_reports_no_errors() {
        let mut scene = scene("oscillator");
        scene.output.diagnostics = Some(vec![]);
        let summary = scene.run(Control::QUIET).unwrap();
        assert_eq!(summary.steps, 100);
        assert_eq!(summary.energy_error_max, None);
        assert_eq!(summary.conservation.momentum_error_max(), None);
        assert_eq!(summary.conservation.solution_error_max(), None);
        // q(100) = sin(100) for q0 = 0, p0 = 1.
        assert!(
            (summary.state.configuration()[0] - 100f64.sin()).abs() < 1e-10,
            "{:?}",
            summary.state.configuration()
        );
    }

    #[test]
    fn the_summary_reports_the_initial_and_final_energy() {
        let mut scene = scene("kepler");
        scene.run.t_end = Some(2.0);
        let summary = scene.run(Control::QUIET).unwrap();
        assert_eq!(summary.steps, 10);
        assert!((summary.energy_initial + 0.5).abs() < 1e-15);
        assert!(
            (summary.energy_final + 0.5).abs() < 1e-9,
            "{}",
            summary.energy_final
        );
        assert_eq!(
            summary.parameters,
            Parameters(vec![("e", 0.5), ("phase", 0.0)])
        );
        assert_eq!(summary.coordinates, Some(vec!["q1".into(), "q2".into()]));
        assert!(summary.to_string().contains("kepler (e = 0.5, phase = 0)"));
    }
}

mod bench {
    use svi_experiments::bench::peers::RADAU5_TOLERANCE_FLOOR;
    use svi_experiments::bench::*;
    use svi_experiments::{Scene, SceneError};

    /// (method, parameter) of every record, in order.
    fn labels(records: &[Record]) -> Vec<(&str, f64)> {
        records
            .iter()
            .map(|r| (r.method.as_str(), r.parameter))
            .collect()
    }

    #[test]
    fn a_short_sweep_converges_at_the_methods_order() {
        // Oscillator to t = 10: errors must fall by about 10× per point and the times and
        // counts must be positive; the exact solution is the reference.
        let mut scene = Scene::builtin("oscillator").unwrap().unwrap();
        scene.run.t_end = Some(10.0);
        let options = BenchOptions {
            methods: vec!["svi:3/2".parse().unwrap(), BenchMethod::Dop853],
            target: Some(1e-9),
            max_run: Some(1.0),
            batches: 1,
            min_batch: 0.0,
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        let svi: Vec<&Record> = records.iter().filter(|r| r.method == "svi:3/2").collect();
        assert!(svi.len() >= 3, "{records:?}");
        assert!(svi.last().unwrap().final_error < 1e-9);
        // The sweep starts at the fewest steps (to within 1/16) with an error below 3e-2: one
        // sixteenth fewer steps of an order-4 method would be at most 1.3× less accurate.
        assert!(
            (3e-2 / 1.3..=3e-2).contains(&svi[0].final_error),
            "{:?}",
            svi[0]
        );
        for pair in svi.windows(2) {
            let ratio = pair[0].final_error / pair[1].final_error;
            assert!(ratio > 3.0 && ratio < 40.0, "{pair:?}");
            assert!(pair[1].evaluations > pair[0].evaluations);
        }
        let dop: Vec<&Record> = records.iter().filter(|r| r.method == "dop853").collect();
        assert!(dop.len() >= 3 && dop.iter().all(|r| r.seconds > 0.0 && r.evaluations > 0));
        assert!(dop.iter().any(|r| r.final_error < 1e-8), "{dop:?}");
        let csv = to_csv(&records);
        assert_eq!(csv.lines().count(), records.len() + 1);
        assert!(csv.starts_with("method,parameter,h,steps,final_error"));
    }

    #[test]
    fn given_step_counts_and_tolerances_are_measured_exactly() {
        // svi:3/2 has order 4: doubling the steps divides the error by about 16.
        let mut scene = Scene::builtin("oscillator").unwrap().unwrap();
        scene.run.t_end = Some(10.0);
        let options = BenchOptions {
            methods: vec!["svi:3/2".parse().unwrap(), BenchMethod::Dop853],
            batches: 1,
            min_batch: 0.0,
            steps: vec![20, 40, 80],
            tolerances: vec![1e-8],
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        let steps: Vec<usize> = records
            .iter()
            .filter(|r| r.h.is_some())
            .map(|r| r.steps)
            .collect();
        assert_eq!(steps, [20, 40, 80]);
        for pair in records[..3].windows(2) {
            let ratio = pair[0].final_error / pair[1].final_error;
            assert!(ratio > 12.0 && ratio < 20.0, "{pair:?}");
        }
        assert_eq!(records.len(), 4);
        assert_eq!(
            (records[3].method.as_str(), records[3].parameter),
            ("dop853", 1e-8)
        );

        // Out of range: an error naming the option (issue #14, item 8).
        for (steps, tolerances, option) in [
            (vec![10, 0], vec![], "--steps"),
            (vec![], vec![1e-8, -1.0], "--tolerances"),
        ] {
            let options = BenchOptions {
                steps,
                tolerances,
                ..options.clone()
            };
            let error = work_precision(&scene, &options).unwrap_err();
            assert!(
                matches!(error, SceneError::InvalidOption { option: named, .. } if named == option),
                "{error}"
            );
        }
    }

    #[test]
    fn the_adaptive_modes_are_measured_beside_the_fixed_steps() {
        // Two periods of Kepler e = 0.9 against the exact orbit: svi:5 (order 8) in τ with
        // g = |q| at 40 and 80 τ-steps per span, step doubling at two tolerances.
        let mut scene = Scene::builtin("kepler-e0.9").unwrap().unwrap();
        scene.run.t_end = Some(4.0 * std::f64::consts::PI);
        let options = BenchOptions {
            methods: parse_methods("svi:5@sundman:1,svi:5@step").unwrap(),
            batches: 1,
            min_batch: 0.0,
            steps: vec![40, 80],
            tolerances: vec![1e-6, 1e-8],
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(
            labels(&records),
            [
                ("svi:5@sundman:1", 40.0),
                ("svi:5@sundman:1", 80.0),
                ("svi:5@step", 1e-6),
                ("svi:5@step", 1e-8)
            ]
        );
        let (coarse, fine) = (&records[0], &records[1]);
        assert_eq!(coarse.h, Some(scene.run.t_end.unwrap() / 40.0));
        // Order 8: halving Δτ divides the error by about 2⁸.
        let ratio = coarse.final_error / fine.final_error;
        assert!(ratio > 50.0 && ratio < 2000.0, "{coarse:?} {fine:?}");
        assert!(fine.final_error < 1e-6, "{fine:?}");
        for record in &records[2..] {
            assert!(record.h.is_none());
            assert!(record.final_error < 10.0 * record.parameter, "{record:?}");
        }
    }

    #[test]
    fn a_requested_step_count_that_fails_is_a_warning_and_the_others_are_kept() {
        // Two periods of Kepler e = 0.9: svi:5 in τ with g = |q| cannot take 2 τ-steps per span
        // (the stage solve does not converge), but 40 are fine; asked for both, the bench keeps
        // the 40, and asked for 2 alone it is the error.
        let mut scene = Scene::builtin("kepler-e0.9").unwrap().unwrap();
        scene.run.t_end = Some(4.0 * std::f64::consts::PI);
        let options = BenchOptions {
            methods: parse_methods("svi:5@sundman:1").unwrap(),
            batches: 1,
            min_batch: 0.0,
            steps: vec![2, 40],
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(labels(&records), [("svi:5@sundman:1", 40.0)]);
        let alone = BenchOptions {
            steps: vec![2],
            ..options
        };
        assert!(work_precision(&scene, &alone).is_err());
    }

    #[test]
    fn a_model_without_exact_solution_is_measured_against_a_resolved_run() {
        // The stiff spring pendulum to T = 1 has no exact solution: the reference is svi:7/6
        // at h = 5e-4 (checked against 1e-3). multiscale:6 at 4 steps (h = 0.25, 4 spring
        // periods per step) has a slow-angle error below 1e-5; an unknown coordinate is an
        // error naming the option.
        let mut scene = Scene::builtin("stiff-spring-pendulum").unwrap().unwrap();
        scene.run.t_end = Some(1.0);
        let options = BenchOptions {
            methods: parse_methods("multiscale:6").unwrap(),
            batches: 1,
            min_batch: 0.0,
            steps: vec![4],
            coordinate: Some("theta".into()),
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(records.len(), 1);
        assert!(records[0].final_error < 1e-5, "{records:?}");
        let unknown = BenchOptions {
            coordinate: Some("phi".into()),
            ..options
        };
        assert!(matches!(
            work_precision(&scene, &unknown),
            Err(SceneError::InvalidOption {
                option: "--coordinate",
                ..
            })
        ));
    }

    #[test]
    fn a_tolerance_that_loses_the_orbit_is_skipped_not_the_end_of_the_sweep() {
        // Dopri5 on Kepler (T = 2000) does not reach the horizon at tol = 1e-3.
        let scene = Scene::builtin("kepler").unwrap().unwrap();
        let single = BenchOptions {
            methods: vec![BenchMethod::Dopri5],
            batches: 1,
            min_batch: 0.0,
            tolerances: vec![1e-3],
            ..BenchOptions::default()
        };
        assert!(matches!(
            work_precision(&scene, &single),
            Err(SceneError::BenchParameter(_))
        ));
        let sweep = BenchOptions {
            target: Some(1e-3),
            tolerances: Vec::new(),
            ..single
        };
        let records = work_precision(&scene, &sweep).unwrap().records;
        assert!(!records.is_empty());
        assert!(records[0].parameter < 1e-3, "{records:?}");
        assert!(records.last().unwrap().final_error < 1e-3, "{records:?}");
    }

    #[test]
    fn molly_runs_the_stiff_spring_pendulum_at_the_given_steps_and_in_a_sweep() {
        // The stiff spring pendulum to T = 1, slow-angle error against the resolved reference:
        // 6.4e-6 at 100 steps (h = 0.01, hω = 1) and 7.4e-8 at 1000, energy errors 7.3e-4 and
        // 7.6e-6 (a prototype of the same formulas against RK4 at h = 2.5e-5), bounded here at
        // about twice that; order 2: ten times the steps, a hundredth of the errors.
        let mut scene = Scene::builtin("stiff-spring-pendulum").unwrap().unwrap();
        scene.run.t_end = Some(1.0);
        let options = BenchOptions {
            methods: parse_methods("molly").unwrap(),
            batches: 1,
            min_batch: 0.0,
            steps: vec![100, 1000],
            coordinate: Some("theta".into()),
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(labels(&records), [("molly", 100.0), ("molly", 1000.0)]);
        let (coarse, fine) = (&records[0], &records[1]);
        assert!(coarse.final_error < 1.3e-5, "{coarse:?}");
        assert!(fine.final_error < 1.5e-7, "{fine:?}");
        let ratio = coarse.final_error / fine.final_error;
        assert!(ratio > 60.0 && ratio < 140.0, "{ratio}");
        let ratio = coarse.energy_error_max / fine.energy_error_max;
        assert!(ratio > 60.0 && ratio < 140.0, "{ratio}");
        assert_eq!(
            (
                coarse.h,
                coarse.steps,
                coarse.evaluations,
                coarse.iterations
            ),
            (Some(0.01), 100, 200, 0)
        );
        assert!(coarse.momentum_error_max.is_none() && coarse.seconds > 0.0);
        // A sweep over step counts, as the fixed-step methods: up to the target error, the
        // error falling by about √10 per point at the end (order 2).
        let sweep = BenchOptions {
            steps: Vec::new(),
            target: Some(1e-7),
            ..options
        };
        let records = work_precision(&scene, &sweep).unwrap().records;
        assert!(records.len() >= 5, "{records:?}");
        assert!(records.windows(2).all(|pair| pair[1].steps > pair[0].steps));
        assert!(records.last().unwrap().final_error < 1e-7, "{records:?}");
        for pair in records[records.len() - 3..].windows(2) {
            let ratio = pair[0].final_error / pair[1].final_error;
            assert!(ratio > 2.0 && ratio < 5.0, "{pair:?}");
        }
    }

    #[test]
    fn molly_on_another_model_is_an_error_naming_it() {
        // Kepler, the oscillator and the double pendulum (whose reference run it does not
        // wait for) are not spring pendulums: a typed error, not a panic.
        for name in ["kepler", "oscillator", "double-pendulum"] {
            let scene = Scene::builtin(name).unwrap().unwrap();
            let options = BenchOptions {
                methods: parse_methods("molly").unwrap(),
                batches: 1,
                min_batch: 0.0,
                steps: vec![10],
                ..BenchOptions::default()
            };
            let error = work_precision(&scene, &options).unwrap_err();
            assert!(
                matches!(&error, SceneError::MethodNotApplicable { method, .. } if method == "molly"),
                "{error}"
            );
            let message = error.to_string();
            assert!(
                message.contains("'molly'") && message.contains("spring-pendulum"),
                "{message}"
            );
        }
    }

    #[test]
    fn radau5_reaches_an_error_that_falls_with_its_tolerance() {
        // The oscillator to t = 10 against its exact solution. RADAU5 runs at the internal
        // tolerance 0.1·tol^(2/3) (2.2e-4, 4.6e-6, 1.0e-7 here); measured errors 5.62e-5,
        // 1.26e-6, 2.71e-8 (a factor 45 per 3 decades of tol, error ∝ tol^0.55), bounded here
        // at about twice that.
        const ERROR_BOUNDS: [f64; 3] = [1e-4, 3e-6, 6e-8];
        let mut scene = Scene::builtin("oscillator").unwrap().unwrap();
        scene.run.t_end = Some(10.0);
        let options = BenchOptions {
            methods: vec![BenchMethod::Radau5],
            batches: 1,
            min_batch: 0.0,
            tolerances: vec![1e-4, 1e-7, 1e-10],
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(
            labels(&records),
            [("radau5", 1e-4), ("radau5", 1e-7), ("radau5", 1e-10)]
        );
        for (record, bound) in records.iter().zip(ERROR_BOUNDS) {
            assert!(record.final_error < bound, "{record:?}");
            assert!(record.h.is_none() && record.seconds > 0.0, "{record:?}");
            assert!(
                record.evaluations > 0 && record.iterations > 0,
                "{record:?}"
            );
        }
        for pair in records.windows(2) {
            assert!(pair[1].final_error < pair[0].final_error / 5.0, "{pair:?}");
            assert!(pair[1].steps > pair[0].steps, "{pair:?}");
        }
        // A sweep goes by whole decades (not stalled by an error that falls 1.9× per half
        // decade) and ends above RADAU5's floor (rtol > 1e-15), at the target at the latest.
        let sweep = BenchOptions {
            tolerances: Vec::new(),
            target: Some(1e-9),
            ..options
        };
        let records = work_precision(&scene, &sweep).unwrap().records;
        assert!(records.len() >= 3, "{records:?}");
        for (k, record) in records.iter().enumerate() {
            assert_eq!(record.parameter, 10f64.powf(-3.0 - k as f64), "{records:?}");
        }
        assert!(
            records.iter().all(|r| r.parameter > RADAU5_TOLERANCE_FLOOR),
            "{records:?}"
        );
        assert!(records.last().unwrap().final_error < 1e-9, "{records:?}");
    }

    #[test]
    fn radau5_runs_the_stiff_spring_pendulum_with_its_exact_jacobian() {
        // The stiff spring pendulum (k = 1e4) to T = 1, slow-angle error against the resolved
        // reference: measured 4.29e-7 at tol = 1e-6 and 8.64e-9 at 1e-9 (214 and 193 steps:
        // the step follows the spring either way), bounded here at about twice that.
        const STIFF_BOUNDS: [f64; 2] = [1e-6, 2e-8];
        let mut scene = Scene::builtin("stiff-spring-pendulum").unwrap().unwrap();
        scene.run.t_end = Some(1.0);
        let options = BenchOptions {
            methods: vec![BenchMethod::Radau5],
            batches: 1,
            min_batch: 0.0,
            tolerances: vec![1e-6, 1e-9],
            coordinate: Some("theta".into()),
            ..BenchOptions::default()
        };
        let records = work_precision(&scene, &options).unwrap().records;
        assert_eq!(records.len(), 2);
        assert!(records[0].final_error < STIFF_BOUNDS[0], "{records:?}");
        assert!(records[1].final_error < STIFF_BOUNDS[1], "{records:?}");
        assert!(
            records[1].final_error < records[0].final_error,
            "{records:?}"
        );
    }

    #[test]
    fn radau5_where_it_cannot_run_is_an_error_not_a_panic() {
        let scene = Scene::builtin("oscillator").unwrap().unwrap();
        // Tolerances RADAU5 rejects (rtol ≤ 10·uround = 1e-15): an error naming the option,
        // before anything runs; dop853 takes them.
        for tol in [1e-15, 1e-16, 1e-20] {
            let options = BenchOptions {
                methods: vec![BenchMethod::Radau5, BenchMethod::Dop853],
                batches: 1,
                min_batch: 0.0,
                tolerances: vec![1e-8, tol],
                ..BenchOptions::default()
            };
            let error = work_precision(&scene, &options).unwrap_err();
            assert!(
                matches!(
                    error,
                    SceneError::InvalidOption {
                        option: "--tolerances",
                        ..
                    }
                ),
                "{error}"
            );
            assert!(error.to_string().contains("radau5"), "{error}");
            let dop853 = BenchOptions {
                methods: vec![BenchMethod::Dop853],
                tolerances: vec![tol],
                ..options
            };
            assert!(dop853.check().is_ok());
        }
        // A rigid body: the error every peer gives; a chain of runtime dimension: the peers
        // need a model of fixed size.
        let message = |name, method| {
            let scene = Scene::builtin(name).unwrap().unwrap();
            let options = BenchOptions {
                methods: vec![method],
                ..BenchOptions::default()
            };
            work_precision(&scene, &options).unwrap_err().to_string()
        };
        assert_eq!(
            message("rigid-body", BenchMethod::Radau5),
            message("rigid-body", BenchMethod::Dop853)
        );
        for method in [BenchMethod::Radau5, BenchMethod::Dop853] {
            let message = message("fput", method);
            assert!(message.contains("needs a model of fixed size"), "{message}");
        }
    }

    #[test]
    fn the_default_methods_on_a_chain_are_the_ones_a_chain_runs() {
        // The default list names peers and adaptive modes, which need a model of fixed size:
        // on a chain it keeps the library's fixed-step methods, so `svi bench fput` runs, and
        // `--tolerances` (the peers' option) is the option blamed, not the `--methods` nobody
        // gave.
        let mut scene = Scene::builtin("fput").unwrap().unwrap();
        scene
            .apply(&svi_experiments::Overrides {
                run: svi_experiments::scene::overrides::RunFlags {
                    t_end: Some(5.0),
                    ..Default::default()
                },
                ..Default::default()
            })
            .unwrap();
        let options = BenchOptions {
            batches: 1,
            min_batch: 0.0,
            steps: vec![50],
            ..BenchOptions::default()
        };
        let sweeps = work_precision(&scene, &options).unwrap();
        let labels: Vec<&str> = (sweeps.records.iter())
            .map(|record| record.method.as_str())
            .collect();
        assert_eq!(
            labels,
            ["svi:7/6", "svi:6/5", "svi:9/8", "svi:6/12", "sc:9"]
        );
        let error = work_precision(
            &scene,
            &BenchOptions {
                tolerances: vec![1e-3],
                ..options
            },
        )
        .unwrap_err();
        assert!(
            matches!(
                error,
                SceneError::NotApplicable {
                    option: "--tolerances",
                    ..
                }
            ),
            "{error}"
        );
    }
}

mod stability {
    use svi_experiments::stability::*;

    #[test]
    fn classic_methods_have_their_known_intervals() {
        // Störmer–Verlet and symplectic Euler on the oscillator: stable exactly for z < 4
        // (tr S = 2 − z); the variational midpoint rule is the implicit midpoint rule there:
        // |eigenvalues| = 1 for every z.
        for name in ["verlet", "symplectic-euler", "trapezoid"] {
            let Answer::Report(report) = run(
                name.parse().unwrap(),
                &Request::Range {
                    z_min: 1e-6,
                    z_max: 10.0,
                    samples: 200,
                },
            )
            .unwrap() else {
                unreachable!()
            };
            assert_eq!(report.stable.len(), 1, "{name}: {:?}", report.stable);
            assert!(
                (report.stable[0].upper - 4.0).abs() < 1e-9,
                "{name}: {:?}",
                report.stable
            );
        }
        let Answer::Report(midpoint) = run(
            "midpoint".parse().unwrap(),
            &Request::Range {
                z_min: 1e-6,
                z_max: 900.0,
                samples: 300,
            },
        )
        .unwrap() else {
            unreachable!()
        };
        assert!(
            midpoint.a_stable && midpoint.p_stable,
            "{:?}",
            midpoint.stable
        );
    }

    #[test]
    fn every_figure_configuration_parses_and_rigid_methods_are_refused() {
        assert_eq!(figure_configurations().len(), 6);
        let error = run("lie-svi".parse().unwrap(), &Request::Values(vec![1.0])).unwrap_err();
        assert!(error.to_string().contains("'lie-svi'"), "{error}");
    }
}

mod scale {
    use svi_experiments::scale::*;

    #[test]
    fn a_small_measurement_runs_every_configuration() {
        let args = ScaleArgs {
            sizes: vec![50, 20],
            steps: 2,
            batches: 1,
            min_run: 0.0,
            out_dir: "unused".into(),
        };
        let measurements = scale(&args).unwrap();
        assert_eq!(measurements.len(), 6);
        assert_eq!((measurements[0].n, measurements[5].n), (20, 50));
        assert!(measurements.iter().all(|m| m.seconds_per_step.is_finite()));
        // The fixed point and Verlet need no Newton iteration of Verlet, SVI a few.
        assert_eq!(measurements[1].iterations_per_step, 0.0);
        assert!(measurements[2].iterations_per_step >= 1.0);
    }
}

/// A scene's derivatives: the gradient against the chain rule through the run's sensitivity
/// block, and the bad losses the gradient refuses.
mod gradient {
    use super::{method, scene};
    use svi_experiments::scene::method::SceneMethod;
    use svi_experiments::{Control, Scene, SceneError};

    /// ℓ_j = (j + 1) q₁ + ½ q̇₂²: a weight per output, q and q̇ both in it.
    fn loss(j: usize, _t: f64, q: &[f64], v: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
        let weight = (j + 1) as f64;
        let value = weight * q[0] + 0.5 * v[1] * v[1];
        (value, vec![weight, 0.0], vec![0.0, v[1]])
    }

    /// Kepler by the midpoint rule, differentiated with respect to e, the phase and q0.
    fn kepler() -> Scene {
        let mut kepler = scene("kepler");
        kepler.method.name = Some(SceneMethod::Registry(method("midpoint")));
        kepler.run.h = Some(0.05);
        kepler.run.t_end = Some(2.0);
        kepler.run.sensitivity = Some(vec!["e".into(), "phase".into(), "q0".into()]);
        kepler.run.sensitivity_every = Some(8);
        kepler
    }

    #[test]
    fn a_native_loss_has_the_gradient_of_the_sensitivities_chain_rule() {
        let scene = kepler();
        let summary = scene.run(Control::default()).unwrap();
        let block = summary.sensitivity.unwrap();
        // Σ_j ∇ℓ_j · ∂(q, q̇)(t_j)/∂(column), through the Jacobians of every output.
        let mut chained = vec![0.0; block.columns.len()];
        let mut value = 0.0;
        for (j, output) in block.outputs.iter().enumerate() {
            let (ell, dq, dv) = loss(j, output.t, &output.q, &output.v);
            value += ell;
            let nabla: Vec<f64> = dq.into_iter().chain(dv).collect();
            for (c, total) in chained.iter_mut().enumerate() {
                *total += (0..4)
                    .map(|r| nabla[r] * output.jacobian[r][c])
                    .sum::<f64>();
            }
        }
        let gradient = scene.gradient(&loss, Some(2)).unwrap();
        assert_eq!(gradient.columns, ["e", "phase", "q0_q1", "q0_q2"]);
        assert!((gradient.value - value).abs() <= 1e-13 * value.abs());
        let largest = chained.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (adjoint, forward) in gradient.gradient.iter().zip(&chained) {
            assert!(
                (adjoint - forward).abs() <= 1e-11 * largest,
                "{adjoint} {forward}"
            );
        }
        assert!(gradient.peak_stored >= 2);
    }

    #[test]
    fn a_loss_that_is_not_finite_or_a_gradient_without_names_is_refused() {
        let nan = |j: usize, _t: f64, q: &[f64], v: &[f64]| {
            let value = if j == 2 { f64::NAN } else { q[0] };
            (value, vec![0.0; q.len()], vec![0.0; v.len()])
        };
        let error = kepler().gradient(&nan, None).unwrap_err().to_string();
        assert!(error.contains("loss at output 2"), "{error}");
        let short = |_j: usize, _t: f64, q: &[f64], _v: &[f64]| (q[0], vec![1.0], vec![]);
        let error = kepler().gradient(&short, None).unwrap_err().to_string();
        assert!(error.contains("loss at output"), "{error}");
        let mut unnamed = kepler();
        unnamed.run.sensitivity = None;
        unnamed.run.sensitivity_every = None;
        assert!(matches!(
            unnamed.gradient(&loss, None),
            Err(SceneError::NotApplicable {
                option: "gradient",
                ..
            })
        ));
        let error = kepler().gradient(&loss, Some(0)).unwrap_err().to_string();
        assert!(error.contains("checkpoints"), "{error}");
    }
}
