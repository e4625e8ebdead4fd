//! The hostile suite of the command line (issue #14): scene files (structured TOML with
//! hostile values, and arbitrary text; field and pseudospectral scenes too), hostile numbers
//! in every numeric option of `svi run`, `svi bench`, `svi stability` and `svi stress`,
//! hostile file paths, and the binary itself.
//!
//! In process, through the parsers and checks the binary uses (the commands' clap structs,
//! [`Scene::load`], `apply`, the commands' `check`), nothing may panic; a rejection is a
//! message with no number printed in full (300 digits), and one that blames an option names
//! an option the arguments gave; options that pass their checks are within their caps; a run
//! that succeeds reports finite numbers only. The binary runs with a timeout per case
//! ([`HANG`]): it must end within it, with exit status 0, 1 or 2 and no panic, and `svi run
//! --json` with status 0 prints finite numbers only.
//!
//! Every test takes its case count from [`cases`]: about 16 000 inputs per `cargo test` (a
//! few seconds); `SVI_HOSTILE_CASES=K` multiplies every count by K (K = 10: about 160 000
//! inputs, the "full run").

use crate::common;
use common::*;

use clap::Parser;
use proptest::prelude::*;
use proptest::sample::select;
use serde_json::Value;
use svi_experiments::bench::{BenchArgs, BenchMethod, work_precision};
use svi_experiments::scene::limits::{
    MAX_BATCH_SECONDS, MAX_BATCHES, MAX_BISECTIONS, MAX_DRIFT_STEPS, MAX_RUN_SECONDS, MAX_SAMPLES,
    MAX_STEPS, MIN_PEER_TOLERANCE,
};
use svi_experiments::stability::{Answer, Request, StabilityArgs};
use svi_experiments::stress::{StressArgs, stress};
use svi_experiments::{Control, Overrides, Scene, SceneError, parse_parameter};

use crate::hostile_cases;
use crate::hostile_support;
use hostile_cases::cases;
use hostile_support::*;

// ---- scene files --------------------------------------------------------------------------

/// A scene: the fields of the format on ℝᴺ and on Lie groups, each mostly valid, some hostile,
/// some misspelt or of the other space.
fn scene_text() -> impl Strategy<Value = String> {
    let model = prop_oneof![
        6 => select(svi_models::MODEL_NAMES.to_vec()).prop_map(String::from),
        2 => select(svi_models::RIGID_MODEL_NAMES.to_vec()).prop_map(String::from),
        // The models on other groups whose runs take milliseconds (not the 8-link chain).
        1 => select(vec!["falling-body", "dual-spin"]).prop_map(String::from),
        1 => select(svi_models::LOCAL_MODEL_NAMES.to_vec()).prop_map(String::from),
        1 => "[a-z-]{0,12}",
    ];
    let method = prop_oneof![
        6 => select(
            svi::method::registry::METHODS
                .iter()
                .map(|entry| entry.name)
                .collect::<Vec<_>>()
        ).prop_map(String::from),
        1 => select(vec![
            "svi:4/3", "svi:5", "sc:4", "svi:1", "sc:3/2", "verlet:2", "lie-svi:3/2",
            "lie-svi-reduced:2", "svi:300",
        ]).prop_map(String::from),
        1 => "[a-z-]{0,12}",
    ];
    let parameter = select(vec![
        "e",
        "sigma",
        "m",
        "g",
        "k",
        "l",
        "m1",
        "m2",
        "d1",
        "d2",
        "c",
        "zeta",
        "drive",
        "amplitude",
        "i1",
        "i2",
        "i3",
        "x",
    ]);
    let small = |low: f64, high: f64| (low..high).prop_map(|x| format!("{x:?}"));
    let vector = |len: std::ops::Range<usize>| {
        mostly(proptest::collection::vec(-2.0f64..2.0, len).prop_map(|v| format!("{v:?}")))
    };
    (
        model,
        few((parameter, mostly(small(0.0, 0.95)))),
        few((
            select(vec![
                "t0",
                "q",
                "v",
                "p",
                "rotation",
                "quaternion",
                "omega",
                "momentum",
                "g",
                "log",
                "xi",
            ]),
            vector(0..5),
        )),
        (
            method,
            proptest::option::of(mostly((2usize..9).prop_map(|p| p.to_string()))),
            proptest::option::of(mostly((1usize..12).prop_map(|m| m.to_string()))),
            proptest::option::of(select(vec!["\"full\"", "\"reduced\"", "\"half\"", "1"])),
        ),
        (mostly(small(0.001, 0.5)), mostly(small(0.0, 5.0))),
        few((
            select(vec![
                "recovery",
                "max_halvings",
                "divergence_limit",
                "max_steps",
                "adapt",
                "tol",
                "min_points",
                "max_points",
                "horizon",
            ]),
            prop_oneof![
                1 => toml_value(),
                1 => select(vec![
                    "\"none\"", "\"halve-step\"", "\"halve\"", "\"step\"", "\"degree\"", "3",
                    "1e3", "1e-8", "1e-300", "24",
                ])
                .prop_map(String::from),
            ],
        )),
        proptest::option::of(select(vec![
            "diagnostics = [\"energy\"]",
            "diagnostics = [\"entropy\"]",
            "diagnostics = [\"momentum\", \"solution\"]",
            "diagnostics = [\"none\"]",
            "every = 3",
            "diagnostics = []",
            "output_times = [0.5, 1.0]",
            "output_times = [1e300]",
            "output_times = [nan]",
            "output_times = []",
        ])),
    )
        .prop_map(
            |(
                model,
                parameters,
                initial,
                (method, points, quadrature, form),
                (h, t_end),
                run,
                output,
            )| {
                let mut text = format!("model = \"{model}\"\n[parameters]\n");
                for (name, value) in parameters {
                    text.push_str(&format!("{name} = {value}\n"));
                }
                text.push_str("[initial]\n");
                for (name, value) in initial {
                    text.push_str(&format!("{name} = {value}\n"));
                }
                text.push_str(&format!("[method]\nname = \"{method}\"\n"));
                if let Some(points) = points {
                    text.push_str(&format!("points = {points}\n"));
                }
                if let Some(quadrature) = quadrature {
                    text.push_str(&format!("quadrature = {quadrature}\n"));
                }
                if let Some(form) = form {
                    text.push_str(&format!("form = {form}\n"));
                }
                text.push_str(&format!("[run]\nh = {h}\nt_end = {t_end}\n"));
                for (name, value) in run {
                    text.push_str(&format!("{name} = {value}\n"));
                }
                if let Some(line) = output {
                    text.push_str(&format!("[output]\n{line}\n"));
                }
                text
            },
        )
}

/// Largest number of steps a hostile run may take in process (longer ones are shortened).
const MAX_TEST_STEPS: f64 = 2000.0;

/// How far a hostile scene got: rejected, valid but too long to run here, run.
const OUTCOMES: [&str; 3] = ["rejected", "valid but long", "run"];

/// Whether a checked scene is short enough to run in a test: a fixed grid of at most
/// [`MAX_TEST_STEPS`] steps, or an adaptive run over a span of at most 20 with a tolerance
/// of at least 1e-12; few points, few halvings. A step or span that the library rejects at
/// once (not finite, not positive) is short.
fn short(scene: &Scene) -> bool {
    let (Some(h), Some(t_end)) = (scene.run.h, scene.run.t_end) else {
        return false;
    };
    // A chain runs here by the methods that keep its sparsity: the dense ones (the reference
    // methods' acceleration Jacobian by automatic differentiation of the whole L, multiscale)
    // take a quarter of a second per step at the chains' default sizes.
    if scene.is_local()
        && !scene
            .method_spec()
            .is_ok_and(|spec| SPARSE_ON_CHAINS.contains(&spec.name()))
    {
        return false;
    }
    let span = t_end - scene.initial.t0.unwrap_or(0.0);
    let adaptive = scene.run.adapt.is_some_and(|adapt| adapt.name() != "none");
    let rejected = !(h.is_finite() && h > 0.0 && span.is_finite() && span > 0.0);
    let steps_ok = if adaptive {
        let tol = scene.run.tol.unwrap_or(1e-8);
        // Step doubling needs about span·tol^(−1/order) steps: a first-order method at
        // tol = 1e-8 takes 10⁸ (kepler with symplectic-euler ran for minutes). Low orders run
        // here only at loose tolerances.
        let order = scene
            .method_spec()
            .ok()
            .and_then(|spec| spec.info().ok())
            .map_or(1, |info| info.order);
        let floor = if order >= 4 { 1e-12 } else { 1e-4 };
        span <= 20.0 && (tol >= floor || !(tol.is_finite() && tol > 0.0))
    } else {
        span / h <= MAX_TEST_STEPS
    };
    (rejected || steps_ok)
        && scene.points().unwrap_or(0) <= 16
        && scene.quadrature().unwrap_or(0) <= 32
        && scene.run.max_points.unwrap_or(0) <= 24
        && scene.run.max_halvings.unwrap_or(0) <= 6
}

/// The methods that run a chain without dense matrices.
const SPARSE_ON_CHAINS: &[&str] = &[
    "svi",
    "svi-newton",
    "sc",
    "verlet",
    "yoshida4",
    "kahan-li6",
    "kahan-li8",
    "midpoint",
    "trapezoid",
    "symplectic-euler",
    "symplectic-euler-adjoint",
    "explicit-euler",
    "implicit-euler",
    "rk4",
];

/// Most steps of a hostile run in process. A run that [`short`] lets through can still need
/// steps of any size (a huge parameter makes the model stiff: `double-pendulum --param
/// g=2.9e18 --adapt step` needs some 10¹¹); the budget ends it with `too_many_steps`.
const TEST_STEP_BUDGET: usize = 20_000;

/// Cap the scene's step budget at [`TEST_STEP_BUDGET`].
fn with_test_budget(scene: &mut Scene) {
    let budget = scene.run.max_steps.unwrap_or(TEST_STEP_BUDGET);
    scene.run.max_steps = Some(budget.min(TEST_STEP_BUDGET));
}

/// Parse `text`; if it is a valid scene, run it when it is short. Never panics; a failure
/// is a message, a success finite numbers.
fn parse_and_maybe_run(text: &str) -> Result<usize, TestCaseError> {
    let context = [text.to_string()];
    let mut scene = match Scene::from_toml(text, "hostile scene") {
        Ok(scene) => scene,
        Err(error) => {
            check_error(&error, &context)?;
            return Ok(0);
        }
    };
    prop_assert!(scene.output.trajectory.is_none());
    if !short(&scene) {
        return Ok(1);
    }
    with_test_budget(&mut scene);
    match scene.run(Control::QUIET) {
        Ok(summary) => {
            prop_assert!(summary.steps as f64 <= 1e5);
            check_summary(&summary, text)?;
        }
        Err(error) => {
            check_error(&error, &context)?;
            if let SceneError::RunFailed { partial, .. } = &error {
                prop_assert!(
                    partial.state.configuration().iter().all(|x| x.is_finite()),
                    "{}",
                    error
                );
            }
        }
    }
    Ok(2)
}

#[test]
fn structured_hostile_scenes_never_panic() {
    let counts = run_counting("structured scenes", 4000, &OUTCOMES, scene_text(), |text| {
        parse_and_maybe_run(&text)
    });
    // The generator reaches every path: rejections, valid scenes, runs.
    let total: usize = counts.iter().sum();
    assert!(counts[0] > total / 10, "{counts:?}");
    assert!(counts[2] > total / 20, "{counts:?}");
}

#[test]
fn arbitrary_scene_text_never_panics() {
    let text = prop_oneof![
        1 => ".{0,200}",
        1 => "[a-z_\\[\\]\"=.,0-9 \n-]{0,200}",
    ];
    run_counting("arbitrary text", 3000, &OUTCOMES, text, |text| {
        parse_and_maybe_run(&text)
    });
}

// ---- field and pseudospectral scene files -------------------------------------------------

/// A field or pseudospectral scene: one of their models (or an unknown one), hostile
/// parameters, a method, the mesh, step and horizon, mostly valid and some hostile; and
/// `svi run` flags to apply on top.
fn space_time_scene_text() -> impl Strategy<Value = (String, Vec<String>)> {
    let model = select(vec![
        "wave",
        "sine-gordon-kink",
        "sine-gordon-breather",
        "phi4-kink",
        "sine-gordon-kink-antikink",
        "schrodinger-packet",
        "nls-soliton",
        "kepler",
    ]);
    let parameter = (
        select(vec![
            "c",
            "speed",
            "position",
            "omega",
            "sigma",
            "k0",
            "x0",
            "eta",
            "mass",
            "collision",
        ]),
        mostly(select(vec!["0.5", "1.0", "-0.3", "2.0"]).prop_map(String::from)),
    );
    let method = prop_oneof![
        2 => Just(None),
        3 => select(vec!["\"midpoint\"", "\"svi:2\"", "\"svi:4\"", "\"svi:4/3\"", "\"strang\""])
            .prop_map(|m| Some(m.to_string())),
        1 => toml_value().prop_map(Some),
    ];
    let points = prop_oneof![
        1 => Just(None),
        3 => mostly(select(vec!["8", "16", "33", "64", "101"]).prop_map(String::from)).prop_map(Some),
    ];
    let quadrature = prop_oneof![
        3 => Just(None),
        1 => mostly(select(vec!["\"trapezoid\"", "\"midpoint\""]).prop_map(String::from))
            .prop_map(Some),
    ];
    // A moving mesh: its monitor and the keys that go with it (or, hostile, without it).
    let moving = prop_oneof![
        3 => Just(Vec::new()),
        1 => few((
            select(vec!["monitor", "monitor_scale", "monitor_curvature", "smoothing"]),
            mostly(
                select(vec!["\"arc-length\"", "\"curvature\"", "1.0", "4.0", "0.0"])
                    .prop_map(String::from),
            ),
        )),
    ];
    let h = mostly(select(vec!["0.01", "0.02", "0.05"]).prop_map(String::from));
    let t_end = mostly(select(vec!["0.1", "0.5", "1.0"]).prop_map(String::from));
    let text = (
        model,
        few(parameter),
        method,
        points,
        quadrature,
        moving,
        h,
        t_end,
    )
        .prop_map(
            |(model, parameters, method, points, quadrature, moving, h, t_end)| {
                let mut text = format!("model = \"{model}\"\n");
                if let Some(method) = method {
                    text.push_str(&format!("method = {method}\n"));
                }
                text.push_str("[parameters]\n");
                for (name, value) in parameters {
                    text.push_str(&format!("{name} = {value}\n"));
                }
                text.push_str("[mesh]\n");
                if let Some(points) = points {
                    text.push_str(&format!("points = {points}\n"));
                }
                if let Some(quadrature) = quadrature {
                    text.push_str(&format!("quadrature = {quadrature}\n"));
                }
                for (key, value) in moving {
                    text.push_str(&format!("{key} = {value}\n"));
                }
                text.push_str(&format!("[run]\nh = {h}\nt_end = {t_end}\n"));
                text
            },
        );
    // `svi run`'s flags on top: --param (the mesh points too), --h, --t-end, --every, and
    // --method (on a field scene an error naming it).
    let mode = Mode::InProcess;
    let flags = prop_oneof![
        1 => Just(Vec::new()),
        1 => vec![
            flag(
                "--param",
                (
                    select(vec![
                        "points",
                        "eta",
                        "c",
                        "speed",
                        "omega",
                        "sigma",
                        "smoothing",
                        "monitor_scale",
                        "monitor_curvature",
                    ]),
                    mode.number_or(&["16", "64", "0.5"]),
                )
                    .prop_map(|(name, value)| format!("{name}={value}"))
                    .boxed(),
            ),
            flag("--h", mode.number_or(&["0.01", "0.05"])),
            flag("--t-end", mode.number_or(&["0.2", "1"])),
            flag("--every", mode.number_or(&["1", "3"])),
            flag(
                "--method",
                select(vec!["midpoint", "svi:3", "svi:4/3", "verlet"])
                    .prop_map(String::from)
                    .boxed(),
            ),
        ]
        .prop_map(|flags| flags.concat()),
    ];
    (text, flags)
}

/// Most nodes × time levels of a hostile field or pseudospectral run in process.
const MAX_TEST_NODE_LEVELS: f64 = 2e5;

/// Nodes × time levels of a run of `model` with `parameters` on `points` nodes with step h
/// to t_end (the model's defaults where absent), from the model's own defaults; `None` for
/// an unknown model or a rejected parameter (the run is then rejected at once).
fn node_levels(
    model: &str,
    parameters: &std::collections::BTreeMap<String, f64>,
    points: Option<usize>,
    run: &svi_experiments::scene::field::FieldRunSection,
) -> Option<f64> {
    struct Defaults<'a>(&'a std::collections::BTreeMap<String, f64>);
    fn defaults<const C: usize>(
        mut model: impl svi::model::density::FieldDefaults<C>,
        parameters: &std::collections::BTreeMap<String, f64>,
    ) -> Option<(usize, f64, f64)> {
        for (name, value) in parameters {
            model.set_parameter(name, *value).ok()?;
        }
        Some((
            model.default_points(),
            model.default_step(),
            model.default_horizon(),
        ))
    }
    impl svi_models::FieldModelVisitor for Defaults<'_> {
        type Output = Option<(usize, f64, f64)>;
        fn visit<M: svi_models::FieldZooModel>(self, model: M) -> Self::Output {
            defaults(model, self.0)
        }
    }
    impl svi_models::SpectralModelVisitor for Defaults<'_> {
        type Output = Option<(usize, f64, f64)>;
        fn visit<M: svi_models::SpectralZooModel>(self, model: M) -> Self::Output {
            defaults(model, self.0)
        }
    }
    let (default_points, default_step, default_horizon) =
        svi_models::visit_field_model(model, Defaults(parameters))
            .or_else(|| svi_models::visit_spectral_model(model, Defaults(parameters)))??;
    let h = run.h.unwrap_or(default_step);
    let t_end = run.t_end.unwrap_or(default_horizon);
    Some(points.unwrap_or(default_points) as f64 * (t_end / h).ceil())
}

/// Whether a run of `node_levels` is short enough to run here; a step or span the run
/// rejects at once (not finite, not positive) is short too.
fn short_space_time(node_levels: Option<f64>) -> bool {
    node_levels.is_none_or(|work| !(work.is_finite() && work > 0.0) || work <= MAX_TEST_NODE_LEVELS)
}

/// Load `text` from a file as the binary does (a field scene, else a pseudospectral one, else
/// a scene on ℝᴺ or SO(3), which such a file is not); run it when it is short. Never panics;
/// a failure is a message, a success finite numbers.
fn load_and_maybe_run_space_time(
    text: &str,
    args: &[String],
    file: &std::path::Path,
) -> Result<usize, TestCaseError> {
    use svi_experiments::scene::field::FieldScene;
    use svi_experiments::scene::spectral::SpectralScene;
    let mut context = args.to_vec();
    context.push(text.to_string());
    let overrides = match RunCli::try_parse_from(
        ["run", "scene.toml"]
            .into_iter()
            .chain(args.iter().map(String::as_str)),
    ) {
        Ok(parsed) => parsed.overrides,
        Err(error) => {
            check_message(&error.to_string(), &context)?;
            return Ok(0);
        }
    };
    std::fs::write(file, text).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let path = file.to_str().unwrap_or_default();
    let rejected = |error: SceneError| -> Result<usize, TestCaseError> {
        check_error(&error, &context)?;
        Ok(0)
    };
    // Apply the flags, skip a long run (or a costly `cheap`-failing one), run the rest.
    macro_rules! run_if_short {
        ($loaded:expr, $cheap:expr) => {{
            let scene = match $loaded.and_then(|mut scene| scene.apply(&overrides).map(|()| scene))
            {
                Ok(scene) => scene,
                Err(error) => return rejected(error),
            };
            let work = node_levels(
                &scene.model,
                &scene.parameters,
                scene.mesh.points,
                &scene.run,
            );
            if !(short_space_time(work) && $cheap(&scene)) {
                return Ok(1);
            }
            scene
                .run(false)
                .map(|summary| serde_json::to_value(summary).unwrap())
        }};
    }
    let outcome = if let Some(scene) = FieldScene::load(path) {
        run_if_short!(scene, |_: &FieldScene| true)
    } else if let Some(scene) = SpectralScene::load(path) {
        // High Galerkin degrees cost many stages per step.
        run_if_short!(scene, |scene: &SpectralScene| scene
            .scheme()
            .map_or(true, |scheme| scheme.order() <= 8))
    } else {
        return match Scene::load(path) {
            Ok(scene) => Err(TestCaseError::fail(format!("{text} loaded as {scene:?}"))),
            Err(error) => rejected(error),
        };
    };
    match outcome {
        Ok(json) => {
            // Every number a successful run reports is finite: serde prints NaN and ±∞ as
            // null, so null is allowed only where a field is optional (`dx` on a moving mesh).
            const OPTIONAL: [&str; 3] = ["multisymplectic_residual_max", "trajectory", "error"];
            let moving = json["method"] == "r-adaptive";
            for (key, value) in json.as_object().into_iter().flatten() {
                prop_assert!(
                    value.as_f64().is_some_and(f64::is_finite)
                        || !(value.is_number() || value.is_null())
                        || (value.is_null() && OPTIONAL.contains(&key.as_str()))
                        || (value.is_null() && moving && key == "dx"),
                    "{}: {} = {}",
                    text,
                    key,
                    value
                );
            }
            prop_assert_eq!(&json["status"], "ok");
        }
        Err(error) => check_error(&error, &context)?,
    }
    Ok(2)
}

#[test]
fn hostile_field_and_pseudospectral_scenes_never_panic() {
    let scratch = Scratch::new("hostile-space-time");
    let file = scratch.join("scene.toml");
    let counts = run_counting(
        "field and pseudospectral scenes",
        1500,
        &OUTCOMES,
        space_time_scene_text(),
        |(text, args)| load_and_maybe_run_space_time(&text, &args, &file),
    );
    let total: usize = counts.iter().sum();
    assert!(counts[0] > total / 20, "{counts:?}");
    assert!(counts[2] > total / 10, "{counts:?}");
}

// ---- svi run's arguments ------------------------------------------------------------------

/// `svi run`'s arguments, parsed as the binary parses them: a scene and the overrides.
#[derive(Debug, Parser)]
struct RunCli {
    scene: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
}

/// `svi run`'s arguments: a scene, then every flag mostly with a hostile value (in the
/// binary also a hostile output path).
fn run_arguments(mode: Mode) -> impl Strategy<Value = Vec<String>> {
    let scene = select(vec![
        "kepler",
        "oscillator",
        "pendulum",
        "double-pendulum",
        "damped-oscillator",
        "damped-pendulum",
        "rigid-body",
        "heavy-top",
        "pendulum-3d",
        "kepler-recovery",
        "oscillator-beyond-stability",
        "fput",
        "toda",
        "henon-heiles",
        "keppler",
    ]);
    let numeric = vec![
        flag("--points", mode.number_or(&["2", "3", "6", "9"])),
        flag("--quadrature", mode.number_or(&["1", "2", "5", "12"])),
        flag("--h", mode.number_or(&["0.01", "0.1", "0.5"])),
        flag("--t-end", mode.number_or(&["1", "5", "20"])),
        flag("--every", mode.number_or(&["1", "3"])),
        flag("--tol", mode.number_or(&["1e-6", "1e-9"])),
        flag("--divergence-limit", mode.number_or(&["1e3", "10"])),
        flag("--max-steps", mode.number_or(&["1", "1000"])),
        flag(
            "--output-times",
            prop_oneof![
                mode.number_or(&["0.5", "1"]),
                (mode.hostile(), mode.hostile()).prop_map(|(a, b)| format!("{a},{b}")),
                Just("0.5,1,1.5".to_string()),
            ]
            .boxed(),
        ),
        flag(
            "--param",
            (
                select(vec![
                    "e", "phase", "sigma", "g", "k", "m", "i1", "zeta", "bogus",
                ]),
                mode.hostile(),
            )
                .prop_map(|(name, value)| format!("{name}={value}"))
                .boxed(),
        ),
    ];
    let mut other = vec![
        flag(
            "--method",
            select(vec![
                "svi", "sc", "verlet", "midpoint", "svi:7/6", "lie-svi", "sc:9/4", "svi:1",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--adapt",
            select(vec!["none", "step", "degree", "sometimes"])
                .prop_map(String::from)
                .boxed(),
        ),
        flag(
            "--recovery",
            select(vec!["none", "halve-step"])
                .prop_map(String::from)
                .boxed(),
        ),
        flag(
            "--diagnostics",
            select(vec!["energy", "none", "momentum,solution", "energy,none"])
                .prop_map(String::from)
                .boxed(),
        ),
        flag(
            "--event",
            select(vec![
                "peri: q1*vq1 + q2*vq2 @up",
                "t - 1 @terminal",
                "bad: 1/(t - t)",
                "e: t @sideways",
                "nosuch + 1",
                "",
                ": q1",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--section",
            select(vec![
                "q1=0,v1>0",
                "q2=0",
                "q9=0",
                "v1=0",
                "q1=nan",
                "q1=0,v1",
                "=0",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--indicators",
            select(vec![
                "megno",
                "spectrum,sali",
                "lyapunov",
                "gali,megno",
                "chaos",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--sensitivity",
            select(vec![
                "e", "e,phase", "q0,v0", "p0", "l,c,q0", "e,e", "", "nan", "q0,mass",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--sensitivity-every",
            select(vec!["1", "7", "0", "-3", "1e9"])
                .prop_map(String::from)
                .boxed(),
        ),
    ];
    if mode == Mode::Binary {
        other.push(flag("--out", output_path()));
        other.push(flag("--events-out", output_path()));
    }
    (
        scene,
        proptest::sample::subsequence(numeric, 0..=5),
        proptest::sample::subsequence(other, 0..=2),
    )
        .prop_flat_map(|(scene, numeric, other)| {
            let flags: Vec<BoxedStrategy<Vec<String>>> = numeric.into_iter().chain(other).collect();
            (Just(scene), flags).prop_map(|(scene, flags)| {
                std::iter::once(scene.to_string())
                    .chain(flags.into_iter().flatten())
                    .collect::<Vec<String>>()
            })
        })
}

/// How far `svi run`'s arguments got.
const RUN_OUTCOMES: [&str; 5] = [
    "rejected by clap",
    "rejected by the checks",
    "valid but long",
    "run",
    "run shortened",
];

/// Parse, load, apply and run `args` as `svi run` does, shortened where the arguments ask
/// for a long run.
fn run_in_process(args: &[String]) -> Result<usize, TestCaseError> {
    let parsed =
        match RunCli::try_parse_from(std::iter::once("run").chain(args.iter().map(String::as_str)))
        {
            Ok(parsed) => parsed,
            Err(error) => {
                let message = error.to_string();
                check_message(&message, args)?;
                return Ok(0);
            }
        };
    let name = parsed.scene.as_deref().unwrap_or("kepler");
    let loaded =
        Scene::load(name).and_then(|mut scene| scene.apply(&parsed.overrides).map(|()| scene));
    let mut scene = match loaded {
        Ok(scene) => scene,
        Err(error) => {
            check_error(&error, args)?;
            return Ok(1);
        }
    };
    prop_assert!(scene.output.trajectory.is_none());
    let mut outcome = 3;
    if !short(&scene) {
        // Keep the run short whatever the arguments asked for: a shorter horizon (a
        // horizon the library rejects stays).
        let h = *scene.run.h.get_or_insert(0.1);
        let t0 = scene.initial.t0.unwrap_or(0.0);
        let adaptive = scene.run.adapt.is_some_and(|adapt| adapt.name() != "none");
        let longest = if adaptive { 20.0 } else { MAX_TEST_STEPS * h };
        let t_end = scene.run.t_end.unwrap_or(t0 + 1e3);
        if longest.is_finite() && (t_end - t0).is_finite() && t_end - t0 > longest {
            scene.run.t_end = Some(t0 + longest);
        }
        if !short(&scene) {
            return Ok(2);
        }
        outcome = 4;
    }
    with_test_budget(&mut scene);
    match scene.run(Control::QUIET) {
        Ok(summary) => check_summary(&summary, &format!("{args:?}"))?,
        Err(error) => check_error(&error, args)?,
    }
    Ok(outcome)
}

/// `svi run` arguments in process, 1500 cases of the `stream`-th sequence (two tests, so
/// that the 3000 cases of a CI run take both cores).
fn hostile_numbers_in_svi_run(stream: u64) {
    let counts = run_counting_stream(
        &format!("svi run arguments ({})", stream + 1),
        stream,
        1500,
        &RUN_OUTCOMES,
        run_arguments(Mode::InProcess),
        |args| run_in_process(&args),
    );
    assert!(counts[1] > 0 && counts[3] + counts[4] > 0, "{counts:?}");
}

#[test]
fn hostile_numbers_in_svi_run_never_panic() {
    hostile_numbers_in_svi_run(0);
}

#[test]
fn hostile_numbers_in_svi_run_never_panic_more() {
    hostile_numbers_in_svi_run(1);
}

proptest! {
    #![proptest_config(cases(1000))]

    #[test]
    fn method_specifications_and_parameters_parse_or_fail_cleanly(text in ".{0,16}") {
        if let Ok(spec) = text.parse::<BenchMethod>() {
            prop_assert_eq!(spec.to_string().parse::<BenchMethod>().ok(), Some(spec));
        }
        if let Err(error) = text.parse::<svi::MethodSpec>() {
            prop_assert!(error.to_string().starts_with("invalid method: "), "{}", error);
        }
        match parse_parameter(&text) {
            Ok((name, value)) => {
                prop_assert!(!name.is_empty());
                prop_assert!(!value.is_nan() || text.to_lowercase().contains("nan"));
            }
            Err(error) => prop_assert!(error.to_string().starts_with("malformed parameter")),
        }
    }
}

// ---- svi bench, stability, stress --------------------------------------------------------

/// `svi bench`'s arguments, parsed as the binary parses them.
#[derive(Debug, Parser)]
struct BenchCli {
    #[command(flatten)]
    args: BenchArgs,
}

/// `svi bench`'s arguments: a scene, cheap methods, and every numeric option mostly hostile
/// (the valid values keep a case to milliseconds).
fn bench_arguments(mode: Mode) -> impl Strategy<Value = Vec<String>> {
    (
        select(vec![
            "oscillator",
            "kepler",
            "pendulum",
            "rigid-body",
            "fput",
            "kepler-text",
            "nosuch",
        ]),
        vec![
            flag(
                "--methods",
                select(vec![
                    "verlet",
                    "svi:3/2",
                    "dop853",
                    "verlet,dopri5",
                    "radau5",
                    ",",
                    "rk4",
                    "lie-svi",
                ])
                .prop_map(String::from)
                .boxed(),
            ),
            flag("--t-end", mode.number_or(&["1", "10"])),
            flag("--target", mode.number_or(&["1e-3"])),
            flag("--max-run", mode.number_or(&["0.01", "3600"])),
            flag("--batches", mode.number_or(&["1", "2"])),
            flag("--min-batch", mode.number_or(&["0", "1e-300"])),
            flag("--steps", mode.number_or(&["1", "10", "20"])),
            flag("--tolerances", mode.number_or(&["1e-3", "1e-6"])),
            flag(
                "--param",
                (select(vec!["e", "sigma", "g", "bogus"]), mode.hostile())
                    .prop_map(|(name, value)| format!("{name}={value}"))
                    .boxed(),
            ),
        ],
    )
        .prop_map(|(scene, flags)| {
            std::iter::once(scene.to_string())
                .chain(flags.into_iter().flatten())
                .collect()
        })
}

/// How far a bench, stability or stress case got.
const COMMAND_OUTCOMES: [&str; 4] = [
    "rejected by clap",
    "rejected by the checks",
    "checked (too long to run here)",
    "run",
];

/// Parse and check `args` as `svi bench` does; run the sweep when every method runs at given
/// points (no sweep), in one short batch.
fn bench_in_process(args: &[String]) -> Result<usize, TestCaseError> {
    let parsed = match BenchCli::try_parse_from(
        std::iter::once("bench").chain(args.iter().map(String::as_str)),
    ) {
        Ok(parsed) => parsed.args,
        Err(error) => {
            check_message(&error.to_string(), args)?;
            return Ok(0);
        }
    };
    let (overrides, mut options) = match parsed.options() {
        Ok(parts) => parts,
        Err(error) => {
            check_error(&error, args)?;
            return Ok(1);
        }
    };
    if let Err(error) = options.check() {
        check_error(&error, args)?;
        return Ok(1);
    }
    // Everything that passed is within its cap: no sweep can run without bound.
    prop_assert!((1..=MAX_BATCHES).contains(&options.batches));
    prop_assert!((0.0..=MAX_BATCH_SECONDS).contains(&options.min_batch));
    prop_assert!(options.max_run().is_finite() && options.max_run() > 0.0);
    prop_assert!(options.max_run() <= MAX_RUN_SECONDS);
    prop_assert!(options.target().is_finite() && options.target() > 0.0);
    prop_assert!(options.steps.iter().all(|s| (1..=MAX_STEPS).contains(s)));
    prop_assert!(
        options
            .tolerances
            .iter()
            .all(|t| t.is_finite() && *t >= MIN_PEER_TOLERANCE)
    );
    let fixed = options
        .methods
        .iter()
        .any(|m| matches!(m, BenchMethod::Library(_)));
    let peers = options
        .methods
        .iter()
        .any(|m| !matches!(m, BenchMethod::Library(_)));
    let sweeps = (fixed && options.steps.is_empty()) || (peers && options.tolerances.is_empty());
    if sweeps || options.batches > 2 || options.min_batch > 1e-3 {
        return Ok(2);
    }
    options.verbose = false;
    let name = parsed.scene.as_deref().unwrap_or("kepler");
    let result = Scene::load(name)
        .and_then(|mut scene| scene.apply(&overrides).map(|()| scene))
        .and_then(|scene| work_precision(&scene, &options));
    match result {
        Ok(records) => {
            for record in &records.records {
                prop_assert!(record.steps > 0 && record.seconds >= 0.0, "{:?}", record);
            }
        }
        Err(error) => check_error(&error, args)?,
    }
    Ok(3)
}

#[test]
fn hostile_numbers_in_svi_bench_are_checked_first() {
    let counts = run_counting(
        "svi bench arguments",
        2000,
        &COMMAND_OUTCOMES,
        bench_arguments(Mode::InProcess),
        |args| bench_in_process(&args),
    );
    // Few random cases pass every check with nothing to sweep (some seeds give none of 2000):
    // the run path is also reached by a fixed case.
    assert!(counts[1] > 0, "{counts:?}");
    let runs = [
        "oscillator",
        "--methods",
        "verlet,dop853",
        "--steps",
        "10",
        "--tolerances",
        "1e-6",
        "--t-end",
        "1",
        "--batches",
        "1",
        "--min-batch",
        "0",
    ]
    .map(String::from);
    assert_eq!(bench_in_process(&runs).unwrap(), 3);
}

/// `svi stability`'s arguments, parsed as the binary parses them.
#[derive(Debug, Parser)]
struct StabilityCli {
    #[command(flatten)]
    args: StabilityArgs,
}

/// `svi stability`'s arguments: every numeric option mostly hostile.
fn stability_arguments(mode: Mode) -> impl Strategy<Value = Vec<String>> {
    vec![
        flag(
            "--method",
            select(vec![
                "svi:5/4", "sc:5", "verlet", "midpoint", "lie-svi", "svi:300", "rk4",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        prop_oneof![
            3 => Just(Vec::new()),
            1 => proptest::collection::vec(mode.number_or(&["0.5", "1", "400"]), 1..4)
                .prop_map(|values| vec!["--z".to_string(), values.join(",")]),
        ]
        .boxed(),
        flag("--z-min", mode.number_or(&["1e-6", "0.1"])),
        flag("--z-max", mode.number_or(&["10", "900", "1e20"])),
        flag("--samples", mode.number_or(&["2", "3", "20"])),
        prop_oneof![3 => Just(Vec::new()), 1 => Just(vec!["--figures".to_string()])].boxed(),
    ]
    .prop_map(|flags| flags.into_iter().flatten().collect())
}

/// Parse, check and (for small requests) run `args` as `svi stability` does, without
/// writing files.
fn stability_in_process(args: &[String]) -> Result<usize, TestCaseError> {
    let parsed = match StabilityCli::try_parse_from(
        std::iter::once("stability").chain(args.iter().map(String::as_str)),
    ) {
        Ok(parsed) => parsed.args,
        Err(error) => {
            check_message(&error.to_string(), args)?;
            return Ok(0);
        }
    };
    let request = parsed.request();
    let methods: Vec<svi::MethodSpec> = if parsed.figures {
        svi_experiments::stability::figure_configurations()
            .into_iter()
            .map(|(_, spec)| spec)
            .collect()
    } else {
        match parsed.method.parse::<svi::MethodSpec>() {
            Ok(spec) => vec![spec],
            Err(error) => {
                check_message(&error.to_string(), args)?;
                return Ok(1);
            }
        }
    };
    if let Some(error) = methods.iter().find_map(|spec| request.check(*spec).err()) {
        check_error(&error, args)?;
        return Ok(1);
    }
    if let Request::Range { samples, .. } = request {
        prop_assert!((2..=MAX_SAMPLES).contains(&samples));
        if samples > 50 {
            return Ok(2);
        }
    }
    for spec in methods {
        match svi_experiments::stability::run(spec, &request) {
            Ok(Answer::Report(report)) => {
                prop_assert!(report.points.iter().all(|p| p.z.is_finite()));
            }
            Ok(Answer::Points(points)) => {
                prop_assert!(points.iter().all(|p| p.z.is_finite() && p.rho.is_finite()));
            }
            Err(error) => check_error(&error, args)?,
        }
    }
    Ok(3)
}

#[test]
fn hostile_numbers_in_svi_stability_are_checked_first() {
    let counts = run_counting(
        "svi stability arguments",
        1500,
        &COMMAND_OUTCOMES,
        stability_arguments(Mode::InProcess),
        |args| stability_in_process(&args),
    );
    assert!(counts[1] > 0 && counts[3] > 0, "{counts:?}");
}

/// `svi stress`'s arguments, parsed as the binary parses them.
#[derive(Debug, Parser)]
struct StressCli {
    #[command(flatten)]
    args: StressArgs,
}

/// `svi stress`'s arguments: one cheap case and method (or a wrong one), and every numeric
/// option mostly hostile.
fn stress_arguments(mode: Mode) -> impl Strategy<Value = Vec<String>> {
    vec![
        flag(
            "--cases",
            select(vec![
                "oscillator",
                "kepler",
                "nope",
                "",
                "oscillator,oscillator",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag(
            "--methods",
            select(vec![
                "verlet",
                "dop853",
                "verlet,dop853",
                "midpoint",
                "dopri5",
                "radau5",
                ",",
                "rk4",
            ])
            .prop_map(String::from)
            .boxed(),
        ),
        flag("--steps", mode.number_or(&["200", "400", "100000"])),
        flag("--bisections", mode.number_or(&["0", "1", "50"])),
        flag("--tolerance", mode.number_or(&["1e-6", "1e-300"])),
    ]
    .prop_map(|flags| flags.into_iter().flatten().collect())
}

/// Parse and check `args` as `svi stress` does; run the oscillator case when it is short.
fn stress_in_process(args: &[String]) -> Result<usize, TestCaseError> {
    let parsed = match StressCli::try_parse_from(
        std::iter::once("stress").chain(args.iter().map(String::as_str)),
    ) {
        Ok(parsed) => parsed.args,
        Err(error) => {
            check_message(&error.to_string(), args)?;
            return Ok(0);
        }
    };
    let mut options = match parsed
        .options()
        .and_then(|options| options.check().map(|()| options))
    {
        Ok(options) => options,
        Err(error) => {
            check_error(&error, args)?;
            return Ok(1);
        }
    };
    prop_assert!(options.drift_steps <= MAX_DRIFT_STEPS);
    prop_assert!(options.bisections() <= MAX_BISECTIONS);
    prop_assert!(options.tolerance().is_finite() && options.tolerance() >= MIN_PEER_TOLERANCE);
    let cheap = options.cases.iter().all(|case| case == "oscillator")
        && !options.cases.is_empty()
        && options.drift_steps <= 1000
        && options.bisections() <= 1;
    if !cheap {
        return Ok(2);
    }
    options.verbose = false;
    match stress(&options) {
        Ok(records) => prop_assert!(!records.is_empty()),
        Err(error) => check_error(&error, args)?,
    }
    Ok(3)
}

#[test]
fn hostile_numbers_in_svi_stress_are_checked_first() {
    let counts = run_counting(
        "svi stress arguments",
        1500,
        &COMMAND_OUTCOMES,
        stress_arguments(Mode::InProcess),
        |args| stress_in_process(&args),
    );
    assert!(counts[1] > 0 && counts[2] > 0, "{counts:?}");
}

// ---- paths ----------------------------------------------------------------------------------

/// A path as a user might give one: existing directories and files of every kind that
/// cannot block (devices that could are left to the binary test, which has a timeout),
/// missing ones, relative, odd characters, overlong, with NUL.
fn hostile_path() -> BoxedStrategy<String> {
    prop_oneof![
        2 => select(vec![
            "/", ".", "..", "", " ", "/tmp", "/dev/null", "/proc/self/status", "/proc/self/mem",
            "/etc/hostname", "/nonexistent/scene.toml", "kepler.toml", "./kepler", "-", "~",
            "a\0b", "scene.toml/", "/proc/self/fd/0",
        ])
        .prop_map(String::from),
        1 => "[a-z./ -]{1,30}",
        1 => ".{1,20}",
        1 => (1usize..5000).prop_map(|n| "a/".repeat(n / 2) + "x.toml"),
    ]
    .boxed()
}

/// An output path (`--out`, `--out-dir`) for the binary, run in a scratch directory:
/// directories, devices that cannot block, missing directories, odd and overlong relative
/// paths (never an absolute path a test could write to).
fn output_path() -> BoxedStrategy<String> {
    prop_oneof![
        2 => select(vec![
            "/", ".", "..", "", " ", "/dev/null", "/dev/full", "/proc/self/status",
            "/nonexistent/out.csv", "out/", "a\0b", "-", "--json",
        ])
        .prop_map(String::from),
        1 => "[a-z]{1,8}(/[a-z]{1,8}){0,2}",
        1 => (1usize..5000).prop_map(|n| "a".repeat(n)),
    ]
    .boxed()
}

#[test]
fn hostile_scene_paths_are_named_never_read_without_bound() {
    // /proc/self/fd/0 is the test's stdin: harmless only because it is never opened unless a
    // regular file; a regression would show as a hang of this test.
    run_counting(
        "scene paths",
        1500,
        &["rejected", "loaded"],
        hostile_path(),
        |path| match Scene::load(&path) {
            Ok(_) => Ok(1),
            Err(error) => {
                check_error(&error, std::slice::from_ref(&path))?;
                if let SceneError::NotASceneFile { path: named, .. }
                | SceneError::Read { path: named, .. } = &error
                {
                    prop_assert_eq!(named.to_str(), Some(path.as_str()));
                }
                Ok(0)
            }
        },
    );
}

// ---- the binary ---------------------------------------------------------------------------

/// A whole command line: a subcommand with hostile arguments, sometimes a hostile path as
/// its scene or output, made short where its values are valid.
fn command_line() -> impl Strategy<Value = Vec<String>> {
    let run = (run_arguments(Mode::InProcess), any::<bool>()).prop_map(|(args, json)| {
        let mut all = vec!["run".to_string()];
        all.extend(args);
        if json {
            all.push("--json".into());
        }
        all
    });
    let bench = bench_arguments(Mode::Binary).prop_map(|args| {
        let mut all = vec!["bench".to_string()];
        all.extend(args);
        all
    });
    let stability = stability_arguments(Mode::Binary).prop_map(|args| {
        let mut all = vec!["stability".to_string()];
        all.extend(args);
        all
    });
    let stress = stress_arguments(Mode::Binary).prop_map(|args| {
        let mut all = vec!["stress".to_string()];
        all.extend(args);
        all
    });
    let paths = (
        select(vec!["run", "bench"]),
        prop_oneof![
            2 => select(vec!["/dev/zero", "/dev/urandom", "/dev/stdin", "/dev/tty", "/dev/full"])
                .prop_map(String::from),
            1 => Just("fifo".to_string()),
            1 => hostile_path(),
        ],
        proptest::option::of(output_path()),
    )
        .prop_map(|(command, path, out)| {
            // A hostile scene path is never a built-in scene (which would run and write).
            let path = if svi_experiments::builtin_scene(&path).is_some() {
                "/dev/zero".to_string()
            } else {
                path
            };
            let mut all = vec![command.to_string(), path];
            if let Some(out) = out {
                all.extend([
                    if command == "run" {
                        "--out"
                    } else {
                        "--out-dir"
                    }
                    .to_string(),
                    out,
                ]);
            }
            all
        });
    prop_oneof![4 => run, 1 => bench, 1 => stability, 1 => stress, 2 => paths]
}

/// Whether the binary's command line is short to run whatever valid values it holds: a run
/// capped in steps, a bench without sweeps, a small stability grid, a short stress case.
/// Commands that are not get their expensive options replaced by cheap ones.
fn made_short(mut args: Vec<String>, out: &str) -> Vec<String> {
    let has = |args: &[String], flag: &str| args.iter().any(|arg| arg == flag);
    match args[0].as_str() {
        "run" => {
            // The run generator's valid values keep a fixed grid under 2000 steps; the
            // scene's own horizon and an adaptive run are capped by a short horizon.
            if !has(&args, "--t-end") {
                args.extend(["--t-end".into(), "5".into()]);
            }
        }
        "bench" => {
            for (flag, value) in [
                ("--steps", "10"),
                ("--tolerances", "1e-6"),
                ("--batches", "1"),
                ("--min-batch", "0"),
                ("--t-end", "10"),
                ("--methods", "verlet"),
            ] {
                if !has(&args, flag) {
                    args.extend([flag.into(), value.into()]);
                }
            }
            if !has(&args, "--out-dir") {
                args.extend(["--out-dir".into(), out.into()]);
            }
        }
        "stability" => {
            if !has(&args, "--samples") && !has(&args, "--z") {
                args.extend(["--samples".into(), "20".into()]);
            }
            if !has(&args, "--out-dir") && !has(&args, "--z") {
                args.extend(["--out-dir".into(), out.into()]);
            }
        }
        _ => {
            for (flag, value) in [
                ("--cases", "oscillator"),
                ("--methods", "verlet"),
                ("--steps", "200"),
                ("--bisections", "1"),
            ] {
                if !has(&args, flag) {
                    args.extend([flag.into(), value.into()]);
                }
            }
            if !has(&args, "--out-dir") {
                args.extend(["--out-dir".into(), out.into()]);
            }
        }
    }
    args
}

/// Run the binary on `args` in `dir` with a timeout; check its end.
fn binary_case(dir: &std::path::Path, args: &[String]) -> Result<usize, TestCaseError> {
    // Arguments cannot hold NUL bytes (an OS rule, not svi's).
    let args: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| !a.contains('\0'))
        .collect();
    let output = svi_within_in(Some(dir), &args, HANG).map_err(TestCaseError::fail)?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    prop_assert!(!stderr.contains("panicked"), "{:?}: {}", args, stderr);
    let code = output.status.code();
    prop_assert!(
        matches!(code, Some(0..=2)),
        "{:?}: {:?} {}",
        args,
        code,
        stderr
    );
    prop_assert!(!has_long_number(&stderr), "{:?}: {}", args, stderr);
    if code != Some(0) {
        prop_assert!(stderr.contains("error"), "{:?}: {}", args, stderr);
    }
    if code == Some(0) && args[0] == "run" && args.contains(&"--json") {
        let json: Value = serde_json::from_slice(&output.stdout)
            .map_err(|e| TestCaseError::fail(format!("{args:?}: {e}")))?;
        check_summary_json(&json, &format!("{args:?}"))?;
    }
    Ok(code.unwrap_or(0) as usize)
}

#[test]
fn the_binary_ends_in_time_with_status_0_1_or_2() {
    // Relative paths (outputs, the FIFO "fifo") are in a scratch directory.
    let dir = Scratch::new("hostile-binary");
    let _ = std::process::Command::new("mkfifo")
        .arg(dir.join("fifo"))
        .status();
    let counts = run_counting(
        "binary command lines",
        150,
        &["exit 0", "exit 1", "exit 2"],
        command_line(),
        |args| binary_case(&dir.0, &made_short(args, "out")),
    );
    assert!(counts[0] > 0 && counts[2] > 0, "{counts:?}");
}

// ---- scenes with holonomic constraints ----------------------------------------------------

/// A scene with constraints: the spherical pendulum's Lagrangian (or one a constrained
/// method refuses), constraints mostly valid and some hostile (none, redundant, constant,
/// contradictory, too many, reading a velocity or t, malformed, singular), hostile
/// parameters, an initial state on, near or far from the sphere, a method (constrained, of
/// the registry, unknown), a step (some too large for Newton's method) and the options a
/// constrained run refuses.
fn constrained_scene_text() -> impl Strategy<Value = String> {
    let sphere = "x^2 + y^2 + z^2 - l^2";
    let constraints = prop_oneof![
        4 => Just(format!("[\"{sphere}\"]")),
        3 => select(vec![
            "[]",
            "[\"x^2 + y^2 + z^2 - l^2\", \"x^2 + y^2 + z^2 - l^2\"]",
            "[\"x^2 + y^2 + z^2 - l^2\", \"x^2 + y^2 + z^2 - 4*l^2\"]",
            "[\"l - 1\"]",
            "[\"0\"]",
            "[\"x^2 + y^2 + z^2 - l^2\", \"x\", \"y\", \"z\"]",
            "[\"x^2 + y^2 + z^2 - l^2\", \"x - y\", \"y + z\"]",
            "[\"x^2 + y^2 + z^2 - l^2\", \"z + 0.5*l\"]",
            "[\"x*vx\"]",
            "[\"x^2 - t\"]",
            "[\"x^2 +\"]",
            "[\"w^2 - 1\"]",
            "[\"x^99999 - 1\"]",
            "[\"1/(x^2 + y^2 + z^2) - 1\"]",
            "[\"sqrt(x) - 1\"]",
            "[\"x^2 + y^2 + z^2 - 1e300\"]",
            "[\"abs(x) + abs(y) + abs(z) - l\"]",
            "[\"\"]",
        ])
        .prop_map(String::from),
    ];
    let lagrangian = prop_oneof![
        6 => Just("0.5*m*(vx^2 + vy^2 + vz^2) - m*g*z"),
        1 => select(vec![
            "0.5*(vx^2 + vy^2 + vz^2)*x - g*z",
            "0.5*(vx^2 + vy^2 + vz^2) - g*z*t",
            "vx*vy + 0.5*vz^2",
            "0.5*(vx^2 + vy^2 + vz^2) - g/z",
            "1e300*(vx^2 + vy^2 + vz^2) - g*z",
        ]),
    ];
    let value = || {
        prop_oneof![
            6 => (0.5f64..2.0).prop_map(|x| format!("{x:?}")),
            1 => select(vec!["0.0", "-1.0", "nan", "inf", "-inf", "1e300", "1e-300", "5e-324"])
                .prop_map(String::from),
        ]
    };
    let position = prop_oneof![
        6 => Just("[0.7173560908995228, 0.0, -0.6967067093471654]"),
        2 => Just("[0.7180734469904223, 0.0, -0.6974034160565126]"), // 1e-3 outside
        1 => select(vec![
            "[0.0, 0.0, 0.0]",
            "[1e300, 0.0, 0.0]",
            "[0.7, 0.0]",
            "[0.0, 0.0, -1.0, 0.0]",
            "[100.0, 100.0, 100.0]",
        ]),
    ];
    let velocity = prop_oneof![
        4 => Just("v = [0.0, 2.0, 0.0]"),
        1 => select(vec![
            "v = [0.5, 2.0, -0.3]",
            "p = [0.0, 2.0, 0.0]",
            "v = [1e300, 0.0, 0.0]",
            "v = [0.0, 2.0]",
            "v = [0.0, 2.0, 0.0]\np = [0.0, 2.0, 0.0]",
        ]),
    ];
    let method = prop_oneof![
        4 => select(svi::method::constrained::ConstrainedMethod::names())
            .prop_map(|name| format!("\"{name}\"")),
        1 => select(vec![
            "\"verlet\"",
            "\"svi:4\"",
            "\"shake\"",
            "\"rattle:4\"",
            "3",
            "\"svi:1/1\"",
            "\"svi:500/4\"",
            "\"svi:5/0@nodes\"",
            "\"svi:0/0@nodes\"",
        ])
            .prop_map(String::from),
        1 => Just(String::new()),
    ];
    let step = prop_oneof![
        6 => (0.001f64..0.1).prop_map(|h| format!("{h:?}")),
        1 => select(vec!["100.0", "10.0", "1e-300", "-0.1", "0.0", "nan", "inf"])
            .prop_map(String::from),
    ];
    let option = proptest::option::of(select(vec![
        "[run]\nadapt = \"step\"",
        "[run]\ntol = 1e-9",
        "[run]\nrecovery = \"halve-step\"",
        "[run]\ndivergence_limit = 10.0",
        "[run]\nmax_steps = 3",
        "[method]\npoints = 5",
        "[output]\noutput_times = [0.5]",
        "[output]\nmultipliers = true",
        "[output]\ndiagnostics = [\"solution\"]",
        "[output]\ndiagnostics = [\"momentum\"]",
        "[output]\ndiagnostics = [\"none\"]",
        "forces = [\"-vx\", \"-vy\", \"-vz\"]",
        "symmetries = [[\"-y\", \"x\", \"0\"]]",
    ]));
    (
        (lagrangian, constraints),
        (value(), value(), value()),
        (position, velocity),
        (method, step, (0.05f64..2.0).prop_map(|t| format!("{t:?}"))),
        option,
    )
        .prop_map(
            |((lagrangian, constraints), (m, g, l), (q, v), (method, h, t_end), option)| {
                let mut text = format!(
                    "lagrangian = \"{lagrangian}\"\ncoordinates = [\"x\", \"y\", \"z\"]\n\
                     constraints = {constraints}\n"
                );
                let (top, section) = match option {
                    Some(line) if !line.starts_with('[') => (line, ""),
                    Some(line) => ("", line),
                    None => ("", ""),
                };
                if !top.is_empty() {
                    text.push_str(top);
                    text.push('\n');
                }
                text.push_str(&format!(
                    "[parameters]\nm = {m}\ng = {g}\nl = {l}\n[initial]\nq = {q}\n{v}\n"
                ));
                if !method.is_empty() {
                    text.push_str(&format!("[method]\nname = {method}\n"));
                }
                text.push_str(&format!("[run]\nh = {h}\nt_end = {t_end}\n"));
                // A second [run] or [method] table is a TOML error: fold the option in.
                match section.split_once('\n') {
                    Some(("[run]", line)) => text.push_str(&format!("{line}\n")),
                    Some(("[method]", line)) if !method.is_empty() => {
                        text = text.replace("[run]\n", &format!("{line}\n[run]\n"));
                    }
                    Some(_) => {
                        text.push_str(section);
                        text.push('\n');
                    }
                    None => {}
                }
                text
            },
        )
}

#[test]
fn hostile_constrained_scenes_never_panic() {
    let counts = run_counting(
        "constrained scenes",
        1500,
        &OUTCOMES,
        constrained_scene_text(),
        |text| parse_and_maybe_run(&text),
    );
    assert!(counts[0] > 0 && counts[2] > 0, "{counts:?}");
}

/// The spherical pendulum with `constraints`, the initial `q`, the step `h` and `extra`
/// lines (`[parameters] l` = `l`).
fn sphere_scene(constraints: &str, l: &str, q: &str, h: &str, extra: &str) -> String {
    format!(
        "lagrangian = \"0.5*(vx^2 + vy^2 + vz^2) - 9.81*z\"\ncoordinates = [\"x\", \"y\", \
         \"z\"]\nconstraints = {constraints}\n{extra}\n[parameters]\nl = {l}\n[initial]\nq = \
         {q}\nv = [0.0, 2.0, 0.0]\n[run]\nh = {h}\nt_end = 1.0\n"
    )
}

#[test]
fn hostile_constraints_are_typed_errors_naming_them_and_never_a_silent_zero() {
    let on = "[0.7173560908995228, 0.0, -0.6967067093471654]";
    let sphere = "[\"x^2 + y^2 + z^2 - l^2\"]";
    // (constraints, l, q, h, extra lines, what the error says: bad input naming it).
    let cases = [
        ("[]", "1.0", on, "0.01", "", "the list is empty"),
        (
            "[\"x^2 + y^2 + z^2 - l^2\", \"x^2 + y^2 + z^2 - l^2\"]",
            "1.0",
            on,
            "0.01",
            "",
            "x^2 + y^2 + z^2 - l^2 is redundant",
        ),
        ("[\"l - 1\"]", "1.0", on, "0.01", "", "constraint 'l - 1'"),
        (
            "[\"x^2 + y^2 + z^2 - l^2\", \"x\", \"y\", \"z\"]",
            "1.0",
            on,
            "0.01",
            "",
            "4 constraints on 3 coordinates",
        ),
        (sphere, "nan", on, "0.01", "", "parameter 'l' = NaN"),
        (sphere, "inf", on, "0.01", "", "parameter 'l' = inf"),
        ("[\"x*vx\"]", "1.0", on, "0.01", "", "constraint 'x*vx'"),
        (
            sphere,
            "1.0",
            on,
            "0.01",
            "[method]\nname = \"verlet\"",
            "rattle-kahan-li8",
        ),
        // The origin: the sphere's gradient vanishes there.
        (
            sphere,
            "1.0",
            "[0.0, 0.0, 0.0]",
            "0.01",
            "",
            "does not depend on q",
        ),
    ];
    for (constraints, l, q, h, extra, says) in cases {
        let (top, method) = match extra.strip_prefix("[method]\n") {
            Some(line) => ("", line),
            None => (extra, ""),
        };
        let mut text = sphere_scene(constraints, l, q, h, top);
        if !method.is_empty() {
            text = text.replace("[run]", &format!("[method]\n{method}\n[run]"));
        }
        let error = Scene::from_toml(&text, "t")
            .and_then(|scene| scene.run(Control::QUIET))
            .expect_err(&text);
        assert!(error.is_bad_input(), "{text}: {error}");
        assert!(error.to_string().contains(says), "{says}: {error}");
    }
    // 1e-3 off the sphere: projected, with a warning that says how far.
    let off = "[0.7180734469904223, 0.0, -0.6974034160565126]";
    let summary = Scene::from_toml(&sphere_scene(sphere, "1.0", off, "0.01", ""), "t")
        .and_then(|scene| scene.run(Control::QUIET))
        .unwrap();
    assert_eq!(summary.warnings.len(), 1, "{:?}", summary.warnings);
    assert_eq!(summary.warnings[0].kind, "projection");
    assert!(summary.warnings[0].message.contains("q0 moved by 1.000e-3"));
    // Newton cannot take the step: a failed run with its last good state, never a status 0.
    let long = sphere_scene(sphere, "1.0", on, "100.0", "").replace("t_end = 1.0", "t_end = 1e3");
    let error = Scene::from_toml(&long, "t")
        .unwrap()
        .run(Control::QUIET)
        .unwrap_err();
    let SceneError::RunFailed { partial, source } = &error else {
        panic!("{error}")
    };
    assert!(matches!(source, svi::Error::NonConvergence { step: 0, .. }));
    assert_eq!(
        partial.status,
        svi_experiments::report::summary::Status::Failed
    );
    assert!(!error.is_bad_input());
}
