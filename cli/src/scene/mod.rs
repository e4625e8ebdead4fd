//! # svi-cli — scenes for the `svi` command-line tool
//!
//! A [`Scene`] says what to simulate: a model of the zoo and its parameters, an initial
//! state, a method and its options, the step and horizon, and the outputs wanted. Scenes are
//! TOML files; the built-in ones ([`BUILTIN_SCENES`]) reproduce the experiments of Li, Wu,
//! Leok (2018) and run each zoo model with its defaults. Command-line flags ([`Overrides`])
//! are applied on top of a scene, and [`Scene::run`] integrates it and returns a [`Summary`].
//!
//! ```toml
//! model = "kepler"
//!
//! [parameters]          # model parameters, name = value (absent: the model's defaults)
//! e = 0.5
//!
//! [initial]             # optional; absent fields come from the model's default state
//! t0 = 0.0
//! q = [0.5, 0.0]
//! v = [0.0, 1.7320508075688772]   # or p = [...], not both
//!
//! [method]
//! name = "svi"          # NAME, NAME:P or NAME:P/M of svi::method::registry::METHODS:
//!                       # "svi" (default), "svi:7/6", "sc:9", "midpoint", "verlet", ...
//! points = 6            # Chebyshev–Gauss–Lobatto points, svi and sc (default 6): the same
//!                       # as name = "svi:6"
//! quadrature = 12       # Gauss–Legendre points, svi only (default 2 × points)
//!
//! [run]                 # absent: the model's default step and horizon
//! h = 0.2               # the step (unused by adapt = "step")
//! t_end = 2000.0
//! adapt = "none"        # "none" (default), "step" (step doubling) or "degree" (points per
//!                       # step, svi and sc), both to meet `tol`
//! tol = 1e-9            # target final error of the adaptive modes
//! min_points = 3        # bounds of adapt = "degree" (defaults 3 and 24)
//! max_points = 24
//! recovery = "none"     # or "halve-step": retry a failed step as two half steps
//! # max_halvings = 4    # with "halve-step": successive halvings allowed (default 4)
//! # divergence_limit = 1e6   # stop once |q_i| or |p_i| exceeds this (default: no limit)
//!
//! [output]
//! trajectory = "kepler.csv"   # write the trajectory as CSV (absent: none)
//! every = 10                  # every 10th step (default 1)
//! output_times = [1.0, 2.5]   # report (and write) the states at these times, read off each
//!                             # step's polynomial (dense output), instead of every step
//! diagnostics = ["energy", "momentum", "solution"]   # the default: all three
//! ```
//!
//! A built-in name wins over a file of the same name (write `./kepler` for the file). Paths in
//! a scene (the trajectory file) are relative to the working directory.
//!
//! Forces (friction, driving) are part of a model's definition: the forced zoo models
//! (`damped-oscillator`, `damped-pendulum`, `driven-oscillator`) are chosen by name like any
//! other, and their force parameters are ordinary `[parameters]`.
//!
//! The model, chosen by name at run time, reaches the one generic runner as its concrete
//! type through [`svi_models::visit_model`]; the method, a [`MethodSpec`] of the library's
//! registry ([`svi::method::registry`]), reaches it as its concrete type through
//! [`MethodSpec::visit_vector`]. Observers are built only for the diagnostics and outputs
//! asked for.

pub mod builtin;
pub mod error;
pub mod overrides;
pub mod schema;

pub use error::SceneError;

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::SVector;
use serde::Deserialize;
use svi::method::registry::SpaceKind;
use svi::{Initial, MethodSpec, RunOptions};
use svi_models::ZooModel;

use builtin::builtin_scene;
use overrides::Overrides;
use schema::{
    AdaptMode, Diagnostic, InitialSection, MethodSection, OutputSection, RecoveryKind, RunSection,
};

/// A scene: what to simulate and what to report. Absent fields fall back to the model's
/// [`svi::Defaults`] and the method's defaults.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Zoo model name (see [`svi_models::MODEL_NAMES`]).
    pub model: String,
    /// Model parameters, name → value, applied on top of the model's defaults.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// Initial state; absent fields come from the model's default state.
    #[serde(default)]
    pub initial: InitialSection,
    /// Method and options.
    #[serde(default)]
    pub method: MethodSection,
    /// Step and horizon.
    #[serde(default)]
    pub run: RunSection,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSection,
}

impl Scene {
    /// Parse a scene from TOML; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|source| SceneError::Parse {
            origin: origin.into(),
            source,
        })?;
        scene.check()?;
        Ok(scene)
    }

    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
        builtin_scene(name).map(|text| Scene::from_toml(text, &format!("built-in scene '{name}'")))
    }

    /// A built-in scene if `name_or_path` names one, else the scene file at that path.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(scene) = Scene::builtin(name_or_path) {
            return scene;
        }
        let path = Path::new(name_or_path);
        match std::fs::read_to_string(path) {
            Ok(text) => Scene::from_toml(&text, &format!("'{}'", path.display())),
            Err(error)
                if error.kind() == std::io::ErrorKind::NotFound
                    && path.extension().is_none()
                    && path.components().count() == 1 =>
            {
                Err(SceneError::UnknownScene {
                    name: name_or_path.into(),
                })
            }
            Err(source) => Err(SceneError::Read {
                path: path.into(),
                source,
            }),
        }
    }

    /// Consistency checks that need no model: a method for models on ℝᴺ with valid options,
    /// one of v and p, `every` only with a file, valid run options (recovery and divergence
    /// limit only for fixed-step runs).
    pub fn check(&self) -> Result<(), SceneError> {
        self.method_spec()?;
        if self.initial.v.is_some() && self.initial.p.is_some() {
            return Err(SceneError::VelocityAndMomentum);
        }
        if self.run.options()? != RunOptions::default()
            && (self.run.adapt.is_some_and(|adapt| adapt != AdaptMode::None)
                || self.output.output_times.is_some())
        {
            return Err(svi::Error::invalid(
                "recovery",
                "recovery and divergence_limit apply to fixed-step runs (adapt = \"none\", no \
                 output_times)",
            )
            .into());
        }
        match (self.output.every, &self.output.trajectory) {
            (Some(_), None) => Err(SceneError::EveryWithoutOutput),
            (Some(0), Some(_)) => {
                Err(svi::Error::invalid("every", "0 steps; need at least 1").into())
            }
            _ => Ok(()),
        }
    }

    /// Apply command-line overrides.
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        let Overrides {
            method,
            points,
            quadrature,
            h,
            t_end,
            parameters,
            every,
            out,
            diagnostics,
            adapt,
            tol,
            output_times,
            recovery,
            divergence_limit,
        } = overrides;
        if let Some(method) = method {
            method.check_space(SpaceKind::Vector)?;
            // The options written in `--method` replace the scene's; the others carry over.
            self.method.name = *method;
            if method.points().is_some() {
                self.method.points = None;
            }
            if method.quadrature().is_some() {
                self.method.quadrature = None;
            }
        }
        let entry = self.method.name.entry();
        if !entry.takes_quadrature() && quadrature.is_some() {
            return Err(SceneError::OptionNotForMethod {
                option: "quadrature",
                method: self.method.name,
            });
        }
        if !entry.takes_points() && points.is_some() {
            return Err(SceneError::OptionNotForMethod {
                option: "points",
                method: self.method.name,
            });
        }
        set(&mut self.method.points, points);
        set(&mut self.method.quadrature, quadrature);
        set(&mut self.run.h, h);
        set(&mut self.run.t_end, t_end);
        for (name, value) in parameters {
            self.parameters.insert(name.clone(), *value);
        }
        set(&mut self.output.every, every);
        set(&mut self.output.trajectory, out);
        set(&mut self.output.diagnostics, diagnostics);
        set(&mut self.run.adapt, adapt);
        set(&mut self.run.tol, tol);
        set(&mut self.output.output_times, output_times);
        if *recovery == Some(RecoveryKind::None) {
            self.run.max_halvings = None;
        }
        set(&mut self.run.recovery, recovery);
        set(&mut self.run.divergence_limit, divergence_limit);
        self.check()
    }

    /// The method in use: `[method] name` with `points` and `quadrature` applied on top
    /// (each only for a method that takes it). An error names the method if it is not for
    /// models on ℝᴺ, or the option out of range.
    pub fn method_spec(&self) -> Result<MethodSpec, SceneError> {
        let mut spec = self.method.name;
        spec.check_space(SpaceKind::Vector)?;
        if let Some(points) = self.method.points
            && spec.entry().takes_points()
        {
            spec = spec.with_points(points)?;
        }
        if let Some(quadrature) = self.method.quadrature
            && spec.entry().takes_quadrature()
        {
            spec = spec.with_quadrature(quadrature)?;
        }
        Ok(spec)
    }

    /// The number of CGL points in use (`None` for the classic methods or an invalid
    /// method).
    pub fn points(&self) -> Option<usize> {
        self.method_spec().ok()?.points_in_use()
    }

    /// The number of Gauss–Legendre points in use (`None` for all methods but svi or an
    /// invalid method).
    pub fn quadrature(&self) -> Option<usize> {
        self.method_spec().ok()?.quadrature_in_use()
    }

    /// Whether `diagnostic` is asked for.
    pub fn wants(&self, diagnostic: Diagnostic) -> bool {
        self.output
            .diagnostics
            .as_ref()
            .is_none_or(|wanted| wanted.contains(&diagnostic))
    }

    /// Apply the scene's parameters to `model` and resolve the initial time and state, the
    /// step and the horizon (scene values, else the model's defaults).
    pub fn resolve<M: ZooModel<N>, const N: usize>(
        &self,
        model: &mut M,
    ) -> Result<(f64, Initial<N>, f64, f64), SceneError> {
        let scene = self;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let (default_t0, default_q, default_v) = model.initial_state();
        let vector = |field: &'static str, values: &Option<Vec<f64>>| {
            values
                .as_ref()
                .map(|values| {
                    if values.len() == N {
                        Ok(SVector::<f64, N>::from_iterator(values.iter().copied()))
                    } else {
                        Err(SceneError::Dimension {
                            model: model.name().into(),
                            field,
                            expected: N,
                            found: values.len(),
                        })
                    }
                })
                .transpose()
        };
        let q = vector("q", &scene.initial.q)?.unwrap_or(default_q);
        let initial = match (
            vector("v", &scene.initial.v)?,
            vector("p", &scene.initial.p)?,
        ) {
            (Some(_), Some(_)) => return Err(SceneError::VelocityAndMomentum),
            (Some(v), None) => Initial::Velocity { q, v },
            (None, Some(p)) => Initial::Momentum { q, p },
            (None, None) => Initial::Velocity { q, v: default_v },
        };
        Ok((
            scene.initial.t0.unwrap_or(default_t0),
            initial,
            scene.run.h.unwrap_or_else(|| model.default_step()),
            scene.run.t_end.unwrap_or_else(|| model.default_horizon()),
        ))
    }
}

/// `target = value` if a value is given.
pub(crate) fn set<T: Clone>(target: &mut Option<T>, value: &Option<T>) {
    if let Some(value) = value {
        *target = Some(value.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::*;
    use svi::Recovery;
    use svi_models::MODEL_NAMES;

    fn scene(name: &str) -> Scene {
        Scene::builtin(name).expect("built-in").expect("parses")
    }

    fn overrides() -> Overrides {
        Overrides::default()
    }

    fn method(text: &str) -> MethodSpec {
        text.parse().expect("a method")
    }

    #[test]
    fn every_builtin_scene_parses_and_names_a_zoo_model() {
        assert_eq!(
            builtin_scene_names(),
            [
                "oscillator",
                "kepler",
                "pendulum",
                "spring-pendulum",
                "double-pendulum",
                "damped-oscillator",
                "damped-pendulum",
                "driven-oscillator",
                "stiff-spring-pendulum",
                "stiff-spring-pendulum-coarse",
                "kepler-long",
                "kepler-e0.9",
                "kepler-e0.99",
                "kepler-recovery",
                "double-pendulum-chaotic",
                "oscillator-beyond-stability"
            ]
        );
        for name in builtin_scene_names() {
            let scene = scene(name);
            assert!(MODEL_NAMES.contains(&scene.model.as_str()), "{name}");
            if MODEL_NAMES.contains(&name) {
                assert_eq!(scene.model, name);
                assert_eq!(scene.method.name, method("svi"));
            } else {
                // The stress scenes are named after their model.
                assert!(name.contains(&scene.model), "{name}");
            }
        }
        assert!(Scene::builtin("kepler2").is_none());
    }

    #[test]
    fn oscillator_scene_is_the_papers_setting() {
        let scene = scene("oscillator");
        assert_eq!(scene.parameters["sigma"], 1.0);
        assert_eq!(scene.initial.t0, Some(0.0));
        assert_eq!(scene.initial.q, Some(vec![0.0]));
        assert_eq!(scene.initial.p, Some(vec![1.0]));
        assert_eq!(scene.initial.v, None);
        assert_eq!(scene.run.h, Some(1.0));
        assert_eq!(scene.run.t_end, Some(100.0));
        assert_eq!(scene.points(), Some(9));
        assert_eq!(scene.quadrature(), Some(18));
        assert!(scene.output.trajectory.is_none());
        for diagnostic in [
            Diagnostic::Energy,
            Diagnostic::Momentum,
            Diagnostic::Solution,
        ] {
            assert!(scene.wants(diagnostic));
        }
    }

    #[test]
    fn kepler_scene_is_the_papers_setting() {
        let scene = scene("kepler");
        assert_eq!(scene.parameters["e"], 0.5);
        assert_eq!(scene.initial, InitialSection::default());
        assert_eq!(scene.run.h, Some(0.2));
        assert_eq!(scene.run.t_end, Some(2000.0));
        assert_eq!(scene.points(), Some(6));
        assert_eq!(scene.quadrature(), Some(12));
        assert_eq!(DEFAULT_SCENE, "kepler");
    }

    #[test]
    fn the_other_scenes_use_the_model_defaults() {
        for name in ["pendulum", "spring-pendulum", "double-pendulum"] {
            let scene = scene(name);
            assert!(scene.parameters.is_empty(), "{name}");
            assert_eq!(scene.initial, InitialSection::default(), "{name}");
            assert_eq!(scene.run, RunSection::default(), "{name}");
            assert_eq!(scene.points(), Some(6), "{name}");
        }
    }

    #[test]
    fn a_minimal_scene_falls_back_to_defaults() {
        let scene = Scene::from_toml("model = \"pendulum\"\n", "test").unwrap();
        assert_eq!(scene.method.name, method("svi"));
        assert_eq!(scene.points(), Some(svi::Svi::default().points));
        assert_eq!(scene.quadrature(), Some(2 * svi::Svi::default().points));
        assert_eq!(scene.output, OutputSection::default());
    }

    #[test]
    fn overrides_replace_scene_fields() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                method: Some(method("svi")),
                points: Some(5),
                quadrature: Some(7),
                h: Some(0.05),
                t_end: Some(10.0),
                parameters: vec![("e".into(), 0.9)],
                every: Some(10),
                out: Some("x.csv".into()),
                diagnostics: Some(vec![Diagnostic::Energy]),
                adapt: Some(AdaptMode::Degree),
                tol: Some(1e-9),
                output_times: Some(vec![1.0, 2.0]),
                recovery: None,
                divergence_limit: None,
            })
            .unwrap();
        assert_eq!(scene.run.adapt, Some(AdaptMode::Degree));
        assert_eq!(scene.run.tol, Some(1e-9));
        assert_eq!(scene.output.output_times, Some(vec![1.0, 2.0]));
        // Recovery and a divergence limit are for fixed-step runs only.
        let recovery = Overrides {
            recovery: Some(RecoveryKind::HalveStep),
            divergence_limit: Some(1e9),
            ..Overrides::default()
        };
        assert!(scene.clone().apply(&recovery).is_err());
        let mut fixed = self::scene("kepler");
        fixed.apply(&recovery).unwrap();
        assert_eq!(fixed.run.recovery, Some(RecoveryKind::HalveStep));
        assert_eq!(
            fixed.run.options().unwrap(),
            RunOptions::default()
                .with_recovery(Recovery::HalveStep {
                    max_halvings: DEFAULT_MAX_HALVINGS
                })
                .with_divergence_limit(1e9)
        );
        assert_eq!(scene.points(), Some(5));
        assert_eq!(scene.quadrature(), Some(7));
        assert_eq!(scene.run.h, Some(0.05));
        assert_eq!(scene.run.t_end, Some(10.0));
        assert_eq!(scene.parameters["e"], 0.9);
        assert_eq!(scene.output.every, Some(10));
        assert_eq!(scene.output.trajectory, Some("x.csv".into()));
        assert!(scene.wants(Diagnostic::Energy));
        assert!(!scene.wants(Diagnostic::Momentum));
        assert!(!scene.wants(Diagnostic::Solution));
    }

    #[test]
    fn points_without_quadrature_keep_the_papers_rule() {
        let mut scene = scene("oscillator");
        scene
            .apply(&Overrides {
                points: Some(4),
                ..overrides()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), Some(8));
    }

    #[test]
    fn switching_to_sc_drops_the_quadrature_and_rejects_it_as_a_flag() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                method: Some(method("sc")),
                ..overrides()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), None);
        let error = scene
            .apply(&Overrides {
                quadrature: Some(12),
                ..overrides()
            })
            .unwrap_err();
        assert!(matches!(
            error,
            SceneError::OptionNotForMethod {
                option: "quadrature",
                method
            } if method == self::method("sc")
        ));
    }

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
                    method: Some(kind),
                    ..overrides()
                })
                .unwrap();
            assert_eq!((scene.points(), scene.quadrature()), (None, None));
            let error = scene
                .apply(&Overrides {
                    points: Some(4),
                    ..overrides()
                })
                .unwrap_err();
            assert_eq!(
                error.to_string(),
                format!(
                    "--points is an option of svi and sc, not of {}",
                    kind.name()
                )
            );
            let summary = scene.run(false).unwrap();
            assert_eq!(summary.method, kind.name());
            assert_eq!((summary.points, summary.quadrature), (None, None));
            assert!(summary.symplectic && summary.order <= 2);
            // h = 1 on the oscillator: first- and second-order methods are coarse (the phase
            // is lost) but stable, with bounded energy error.
            assert!(summary.energy_error_max.unwrap() <= 0.5, "{kind}");
            assert!(summary.solution_error_max.unwrap() < 2.0, "{kind}");
        }
    }

    #[test]
    fn the_damped_oscillator_scene_reports_its_solution_error() {
        let scene = scene("damped-oscillator");
        assert_eq!(scene.parameters["zeta"], 0.1);
        assert_eq!((scene.run.h, scene.run.t_end), (Some(0.1), Some(50.0)));
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 500);
        assert!(summary.solution_error_max.unwrap() < 1e-12);
        // E(50) = E(0) e^{−5}-ish: the friction removed almost all the energy.
        assert!(summary.energy_final < 0.01 * summary.energy_initial);
        let mut verlet = scene.clone();
        verlet.method.name = method("verlet");
        let summary = verlet.run(false).unwrap();
        // Second order: 1.6e-3 at h = 0.1.
        let error = summary.solution_error_max.unwrap();
        assert!(error > 1e-3 && error < 2e-3, "{error:e}");
        assert_eq!(summary.evaluations, 501);
    }

    #[test]
    fn scene_format_errors_name_the_line() {
        let text = "model = \"kepler\"\n[run]\nh = 0.1\nstep = 3\n";
        let error = Scene::from_toml(text, "'test.toml'").unwrap_err();
        let SceneError::Parse { origin, source } = &error else {
            panic!("{error}")
        };
        assert_eq!(origin, "'test.toml'");
        let message = source.to_string();
        assert!(message.contains("line 4"), "{message}");
        assert!(message.contains("step"), "{message}");
    }

    #[test]
    fn unknown_method_and_diagnostic_names_are_listed() {
        let error =
            Scene::from_toml("model = \"kepler\"\n[method]\nname = \"rk4\"\n", "t").unwrap_err();
        let SceneError::Parse { source, .. } = &error else {
            panic!("{error}")
        };
        assert!(
            source
                .to_string()
                .contains("unknown method 'rk4' (known: svi, sc, symplectic-euler,")
        );
        let text = "model = \"kepler\"\n[output]\ndiagnostics = [\"energy\", \"angular\"]\n";
        let SceneError::Parse { source, .. } = Scene::from_toml(text, "t").unwrap_err() else {
            panic!()
        };
        let message = source.to_string();
        assert!(
            message.contains("unknown diagnostic 'angular'"),
            "{message}"
        );
        assert!(message.contains("line 3"), "{message}");
    }

    #[test]
    fn both_velocity_and_momentum_are_rejected() {
        let text = "model = \"kepler\"\n[initial]\nq = [1, 0]\nv = [0, 1]\np = [0, 1]\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::VelocityAndMomentum)
        ));
    }

    #[test]
    fn every_needs_a_file_and_a_positive_count() {
        let text = "model = \"kepler\"\n[output]\nevery = 10\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::EveryWithoutOutput)
        ));
        let text = "model = \"kepler\"\n[output]\nevery = 0\ntrajectory = \"x.csv\"\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::Svi(svi::Error::InvalidParameter { name, .. })) if name == "every"
        ));
    }

    #[test]
    fn wrong_dimension_names_field_and_sizes() {
        let text = "model = \"kepler\"\n[initial]\nq = [1, 0, 0]\n";
        let error = Scene::from_toml(text, "t").unwrap().run(false).unwrap_err();
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
        let error = Scene::from_toml(text, "t").unwrap().run(false).unwrap_err();
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
            .run(false)
            .unwrap_err();
        assert!(matches!(error, SceneError::UnknownModel(_)));
        assert!(error.to_string().contains("known: oscillator, pendulum"));
    }

    #[test]
    fn a_missing_bare_name_is_an_unknown_scene_and_a_missing_path_a_read_error() {
        let error = Scene::load("keppler").unwrap_err();
        assert!(matches!(error, SceneError::UnknownScene { .. }));
        assert!(error.to_string().contains("oscillator, kepler"), "{error}");
        let path = std::env::temp_dir().join("svi-cli-no-such-dir/scene.toml");
        let error = Scene::load(path.to_str().unwrap()).unwrap_err();
        assert!(matches!(error, SceneError::Read { .. }), "{error}");
    }

    #[test]
    fn a_run_that_asks_for_nothing_reports_no_errors() {
        let mut scene = scene("oscillator");
        scene.output.diagnostics = Some(vec![]);
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 100);
        assert_eq!(summary.energy_error_max, None);
        assert_eq!(summary.momentum_error_max, None);
        assert_eq!(summary.solution_error_max, None);
        // q(100) = sin(100) for q0 = 0, p0 = 1.
        assert!(
            (summary.q[0] - 100f64.sin()).abs() < 1e-10,
            "{:?}",
            summary.q
        );
    }

    #[test]
    fn the_summary_reports_the_initial_and_final_energy() {
        let mut scene = scene("kepler");
        scene.run.t_end = Some(2.0);
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 10);
        assert!((summary.energy_initial + 0.5).abs() < 1e-15);
        assert!(
            (summary.energy_final + 0.5).abs() < 1e-9,
            "{}",
            summary.energy_final
        );
        assert_eq!(summary.parameters, Parameters(vec![("e", 0.5)]));
        assert_eq!(summary.coordinates, ["q1", "q2"]);
        assert!(summary.to_string().contains("kepler (e = 0.5)"));
    }
}
