//! Every check of a scene's input that needs no model ([`Scene::check`]): the model fields,
//! a method for the scene's space, initial-state fields of that space, the run and output
//! options, and no option the scene cannot use. A [`CheckedScene`] is a scene that passed
//! them, borrowed so that it cannot change: a run path checks a scene once and runs it as
//! often as it likes (the bench's timed repetitions, an ensemble's member).

use svi::MethodSpec;
use svi::method::registry::{self, SpaceKind};

use crate::scene::error::methods_with;
use crate::scene::schema::{AdaptMode, Diagnostic, RecoveryKind};
use crate::scene::{Scene, SceneError, group, limits, rigid};
use svi_models::PARAMETRIC_MODEL_NAMES;

/// A scene that passed [`Scene::check`], borrowed so that it stays as checked: its runs
/// ([`CheckedScene::run`]) do not check it again.
#[derive(Debug, Clone, Copy)]
pub struct CheckedScene<'a>(&'a Scene);

impl std::ops::Deref for CheckedScene<'_> {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        self.0
    }
}

impl Scene {
    /// The scene, checked ([`Scene::check`]) once for any number of runs.
    pub fn checked(&self) -> Result<CheckedScene<'_>, SceneError> {
        self.check()?;
        Ok(CheckedScene(self))
    }

    /// The model fields: a zoo `model` or a `lagrangian` (parsed, with the initial state,
    /// step and horizon it has no defaults for), and the fields of a text model only with
    /// one.
    fn check_model(&self) -> Result<(), SceneError> {
        let Some(model) = self.text() else {
            let text_fields = [
                (self.coordinates.is_some(), "coordinates"),
                (self.forces.is_some(), "forces"),
                (self.symmetries.is_some(), "symmetries"),
                (self.boundary.is_some(), "boundary"),
                (self.constraints.is_some(), "constraints"),
            ];
            if let Some((_, option)) = text_fields.into_iter().find(|(given, _)| *given) {
                return Err(SceneError::NotApplicable {
                    option,
                    reason: "belongs to a Lagrangian written as text (lagrangian = \"...\") or a \
                             Hamiltonian (hamiltonian = \"...\")"
                        .into(),
                });
            }
            if self.model.is_empty() {
                return Err(SceneError::NoModel);
            }
            return Ok(());
        };
        if !self.model.is_empty() {
            return Err(SceneError::ModelAndLagrangian {
                model: self.model.clone(),
            });
        }
        if self.lagrangian.is_some() && self.hamiltonian.is_some() {
            return Err(SceneError::LagrangianAndHamiltonian);
        }
        model?;
        if self.boundary.is_some() && !self.is_text_chain() {
            return Err(SceneError::NotApplicable {
                option: "boundary",
                reason: "belongs to a chain of indexed coordinates (coordinates = [\"q[1..n]\"])"
                    .into(),
            });
        }
        let initial = &self.initial;
        let needed = [
            (initial.q.is_none(), "initial.q"),
            (
                initial.v.is_none() && initial.p.is_none(),
                "initial.v (or initial.p)",
            ),
            (
                self.run.h.is_none() && self.run.adapt != Some(AdaptMode::Step),
                "run.h",
            ),
            (self.run.t_end.is_none(), "run.t_end"),
        ];
        if let Some((_, field)) = needed.into_iter().find(|(missing, _)| *missing) {
            return Err(SceneError::TextModelNeeds { field });
        }
        Ok(())
    }

    /// The options a runtime-dimension scene cannot use: degree adaptivity, and the
    /// diagnostics it has nothing for (momentum, solution). Its method is any of ℝᴺ (one
    /// that would hold a dense n × n matrix refuses a chain too large for it as the run
    /// starts, naming itself and the size).
    fn check_local(&self, spec: MethodSpec) -> Result<(), SceneError> {
        spec.vector_method()?;
        for (diagnostic, option, what) in [
            (
                Diagnostic::Momentum,
                "--diagnostics momentum (output.diagnostics)",
                "declares no symmetry, hence no Noether momentum to measure",
            ),
            (
                Diagnostic::Solution,
                "--diagnostics solution (output.diagnostics)",
                "has no exact solution to measure against",
            ),
        ] {
            if self.wants_explicitly(diagnostic) {
                return Err(self.not_measurable(option, what));
            }
        }
        Ok(())
    }

    /// Consistency checks that need no model: a method for the scene's space with valid
    /// options, initial-state fields of that space (one of each exclusive pair), valid run
    /// options, and no option the scene cannot use (see [`SceneError::NotApplicable`]).
    pub fn check(&self) -> Result<(), SceneError> {
        self.check_model()?;
        if self.is_constrained() {
            self.check_constrained()?;
            return self.check_output();
        }
        let spec = self.method_spec()?;
        let initial = &self.initial;
        match self.space() {
            SpaceKind::Vector => {
                self.check_vector_initial()?;
                if self.is_local() {
                    self.check_local(spec)?;
                }
            }
            SpaceKind::Group if !self.is_rigid() => {
                group::check_initial(initial, &self.model)?;
                rigid::method(spec, self.method.form)?;
            }
            SpaceKind::Group => {
                let vector = [
                    (initial.q.is_some(), "initial.q"),
                    (initial.v.is_some(), "initial.v"),
                    (initial.p.is_some(), "initial.p"),
                    (initial.g.is_some(), "initial.g"),
                    (initial.log.is_some(), "initial.log"),
                    (initial.xi.is_some(), "initial.xi"),
                ];
                if let Some((_, option)) = vector.into_iter().find(|(given, _)| *given) {
                    return Err(SceneError::NotApplicable {
                        option,
                        reason: format!(
                            "applies to scenes on ℝᴺ; the rigid body '{}' takes rotation or \
                             quaternion, and omega or momentum",
                            self.model
                        ),
                    });
                }
                rigid::check_initial(initial)?;
                rigid::method(spec, self.method.form)?;
                if self.wants_explicitly(Diagnostic::Solution) {
                    return Err(SceneError::NotApplicable {
                        option: "--diagnostics solution (output.diagnostics)",
                        reason: format!(
                            "the rigid body '{}' has no exact solution to measure against",
                            self.model
                        ),
                    });
                }
            }
        }
        self.check_run(spec)?;
        self.check_output()
    }

    /// The initial state of a scene on ℝᴺ: none of the rigid bodies' fields, and not both v
    /// and p.
    pub(crate) fn check_vector_initial(&self) -> Result<(), SceneError> {
        let initial = &self.initial;
        let rigid = [
            (initial.rotation.is_some(), "initial.rotation"),
            (initial.quaternion.is_some(), "initial.quaternion"),
            (initial.omega.is_some(), "initial.omega"),
            (initial.momentum.is_some(), "initial.momentum"),
            (initial.g.is_some(), "initial.g"),
            (initial.log.is_some(), "initial.log"),
            (initial.xi.is_some(), "initial.xi"),
            (self.method.form.is_some(), "--form (method.form)"),
        ];
        if let Some((_, option)) = rigid.into_iter().find(|(given, _)| *given) {
            return Err(SceneError::NotApplicable {
                option,
                reason: format!(
                    "applies to scenes on Lie groups only (see svi list); '{}' is a model on ℝᴺ",
                    self.model_name()
                ),
            });
        }
        if initial.v.is_some() && initial.p.is_some() {
            return Err(SceneError::VelocityAndMomentum);
        }
        Ok(())
    }

    /// `[run]`: valid run options; `tol`, `min_points` and `max_points` only with the modes
    /// that use them; degree adaptivity only for a method with points; recovery only at fixed
    /// steps.
    fn check_run(&self, spec: MethodSpec) -> Result<(), SceneError> {
        let run = &self.run;
        run.options()?;
        if let Some(steps) = run.max_steps {
            limits::count(
                "--max-steps (run.max_steps)",
                steps,
                1,
                svi::stepping::grid::MAX_STEPS,
                "steps",
            )?;
        }
        let adapt = run.adapt.unwrap_or_default();
        let not_applicable =
            |option, reason: String| Err(SceneError::NotApplicable { option, reason });
        if matches!(adapt, AdaptMode::None | AdaptMode::Reparam | AdaptMode::Sem)
            && run.tol.is_some()
        {
            return not_applicable(
                "--tol (run.tol)",
                format!(
                    "sets the tolerance of --adapt step and --adapt degree; this run has {} \
                     (adapt {}{})",
                    if adapt == AdaptMode::Sem {
                        "steps fixed by energy conservation"
                    } else {
                        "fixed steps"
                    },
                    adapt.name(),
                    match adapt {
                        AdaptMode::Reparam => ": choose --h, the step in τ",
                        AdaptMode::Sem => ": --h is the first step",
                        _ => "",
                    }
                ),
            );
        }
        if adapt == AdaptMode::Sem
            && (self.space() != SpaceKind::Vector || self.is_local() || spec.name() != "svi")
        {
            return not_applicable(
                "--adapt sem (run.adapt)",
                format!(
                    "fits the steps of svi on models on ℝᴺ of fixed dimension to discrete \
                     energy conservation, not of {} on this model",
                    spec.name()
                ),
            );
        }
        if adapt != AdaptMode::Reparam && run.monitor.is_some() {
            return not_applicable(
                "--monitor (run.monitor)",
                format!(
                    "sets the monitor of --adapt reparam, not of adapt {}",
                    adapt.name()
                ),
            );
        }
        if adapt == AdaptMode::Reparam {
            self.monitor()?;
            if self.space() != SpaceKind::Vector || self.is_local() {
                return not_applicable(
                    "--adapt reparam (run.adapt)",
                    "reparametrises models on ℝᴺ of fixed dimension (not rigid bodies or \
                     chains)"
                        .into(),
                );
            }
        }
        for (bound, option) in [
            (run.min_points, "run.min_points"),
            (run.max_points, "run.max_points"),
        ] {
            if bound.is_some() && adapt != AdaptMode::Degree {
                return not_applicable(
                    option,
                    format!(
                        "bounds the points of adapt = \"degree\", not of adapt = \"{}\"",
                        adapt.name()
                    ),
                );
            }
        }
        if adapt == AdaptMode::Degree && !spec.entry().takes_points() {
            return not_applicable(
                "--adapt degree (run.adapt)",
                format!(
                    "method {} has no polynomial degree to adapt (methods with points: {})",
                    spec.name(),
                    methods_with(spec.space(), registry::Entry::takes_points)
                ),
            );
        }
        if adapt != AdaptMode::None && run.recovery == Some(RecoveryKind::HalveStep) {
            return not_applicable(
                "--recovery (run.recovery)",
                format!(
                    "adapt {} retries failed steps itself; recovery applies to fixed steps \
                     (adapt none)",
                    adapt.name()
                ),
            );
        }
        Ok(())
    }

    /// `[output]`: `every` only with a trajectory file and without output times, `none` alone
    /// among the diagnostics.
    fn check_output(&self) -> Result<(), SceneError> {
        self.check_output_files()
    }

    /// Events and a section: on ℝᴺ, unconstrained, not in steps of τ; a section's points
    /// fill the trajectory file, so not with output times or thinning. (The names in them
    /// are checked against the model's when the run builds them.)
    fn check_events(&self) -> Result<(), SceneError> {
        let section = self.output.section.is_some();
        self.check_indicators()?;
        self.check_sensitivity()?;
        if !self.has_events() && !section {
            return Ok(());
        }
        let option = if section {
            "--section (output.section)"
        } else {
            "--event (events)"
        };
        let refuse = |reason: &str| {
            Err(SceneError::NotApplicable {
                option,
                reason: reason.into(),
            })
        };
        if self.is_constrained() {
            return refuse("events are not located in constrained runs yet");
        }
        if self.space() == SpaceKind::Group {
            return refuse("events are located on ℝᴺ: rigid-body scenes have none");
        }
        if self.run.adapt == Some(AdaptMode::Reparam) {
            return refuse("events are not located in fixed steps of τ (adapt = reparam)");
        }
        if section && self.output.output_times.is_some() {
            return refuse(
                "the section's points fill the trajectory file: leave out --output-times",
            );
        }
        if section && self.output.every.is_some() {
            return refuse("the section's points fill the trajectory file: leave out --every");
        }
        Ok(())
    }

    /// Chaos indicators: the tangent maps of fixed steps on ℝᴺ, without what a tangent run
    /// does not serve (output times, events, a section, recovery of failed steps).
    fn check_indicators(&self) -> Result<(), SceneError> {
        if self.run.indicators.as_ref().is_none_or(Vec::is_empty) {
            return Ok(());
        }
        let refuse = |reason: &str| {
            Err(SceneError::NotApplicable {
                option: "--indicators (run.indicators)",
                reason: reason.into(),
            })
        };
        if self.is_constrained() {
            return refuse("constrained runs have no tangent map yet");
        }
        if self.space() == SpaceKind::Group {
            return refuse("computed on ℝᴺ from the tangent maps: not for rigid-body scenes");
        }
        if !matches!(self.run.adapt, None | Some(AdaptMode::None)) {
            return refuse("takes the tangent maps of fixed steps: leave out --adapt");
        }
        if self.run.recovery == Some(RecoveryKind::HalveStep) {
            return refuse(
                "a halved step would change the map whose tangent is observed: leave out \
                 --recovery",
            );
        }
        if self.output.output_times.is_some() {
            return refuse("a tangent run serves no output times: leave out --output-times");
        }
        if self.has_events() || self.output.section.is_some() {
            return refuse("a tangent run locates no events: leave out --event and --section");
        }
        Ok(())
    }

    /// Sensitivities: the tangent maps of fixed steps of a zoo model whose parameters can be
    /// differentiated, without what a fixed-step run does not serve.
    fn check_sensitivity(&self) -> Result<(), SceneError> {
        let refuse = |reason: String| {
            Err(SceneError::NotApplicable {
                option: "--sensitivity (run.sensitivity)",
                reason,
            })
        };
        let Some(names) = &self.run.sensitivity else {
            if self.run.sensitivity_every.is_some() {
                return Err(SceneError::NotApplicable {
                    option: "--sensitivity-every (run.sensitivity_every)",
                    reason: "sets the outputs of --sensitivity, which is not given".into(),
                });
            }
            return Ok(());
        };
        if names.is_empty() {
            return refuse("names nothing to differentiate with respect to".into());
        }
        if self.run.sensitivity_every == Some(0) {
            return Err(SceneError::InvalidOption {
                option: "--sensitivity-every (run.sensitivity_every)",
                reason: "0 steps between outputs (at least 1)".into(),
            });
        }
        if self.is_text()
            || self.space() != SpaceKind::Vector
            || !PARAMETRIC_MODEL_NAMES.contains(&self.model.as_str())
        {
            // A model written as text has no name ('' said "model '' has no parameters").
            let model = if self.is_text() {
                "a model written as text".to_string()
            } else {
                format!("model '{}'", self.model)
            };
            return refuse(format!(
                "{model} has no parameters that can be differentiated (models that do: {})",
                PARAMETRIC_MODEL_NAMES.join(", ")
            ));
        }
        if !matches!(self.run.adapt, None | Some(AdaptMode::None)) {
            return refuse("differentiates fixed steps: leave out --adapt".into());
        }
        if self.run.recovery == Some(RecoveryKind::HalveStep) {
            return refuse(
                "a halved step would change the map that is differentiated: leave out --recovery"
                    .into(),
            );
        }
        if self.output.output_times.is_some() {
            return refuse(
                "reports at the grid's steps (--sensitivity-every): leave out --output-times"
                    .into(),
            );
        }
        if self.has_events() || self.output.section.is_some() {
            return refuse(
                "differentiates the run to its horizon: leave out --event and --section".into(),
            );
        }
        Ok(())
    }

    /// The output files and what they need.
    fn check_output_files(&self) -> Result<(), SceneError> {
        let output = &self.output;
        if self.wants_explicitly(Diagnostic::None)
            && output
                .diagnostics
                .as_ref()
                .is_some_and(|wanted| wanted.len() > 1)
        {
            return Err(SceneError::NotApplicable {
                option: "--diagnostics (output.diagnostics)",
                reason: "none means no diagnostic: give it alone, or list the diagnostics \
                         wanted"
                    .into(),
            });
        }
        if output.multipliers == Some(true) {
            if !self.is_constrained() {
                return Err(SceneError::NotApplicable {
                    option: "--multipliers (output.multipliers)",
                    reason: "writes the Lagrange multipliers of a scene with constraints \
                             (constraints = [...]); this scene has none"
                        .into(),
                });
            }
            if output.trajectory.is_none() && !output.record {
                return Err(SceneError::NotApplicable {
                    option: "--multipliers (output.multipliers)",
                    reason: "adds the multipliers to the trajectory: give --out FILE \
                             (output.trajectory) too"
                        .into(),
                });
            }
        }
        self.check_events()?;
        if output.plot.is_some() && output.trajectory.is_none() {
            return Err(SceneError::NotApplicable {
                option: "--plot (output.plot)",
                reason: "draws the trajectory file: give --out FILE (output.trajectory) too".into(),
            });
        }
        if output.events.is_some() && !self.has_events() {
            return Err(SceneError::NotApplicable {
                option: crate::report::output::EVENTS,
                reason: "writes the located events: give --event (events) too".into(),
            });
        }
        crate::report::output::check_run_outputs(
            output.trajectory.as_deref(),
            output.plot.as_deref(),
            output.events.as_deref(),
            self.source.as_deref(),
        )?;
        let kept = output.trajectory.is_some() || output.record;
        match (output.every, kept) {
            (Some(_), false) => Err(SceneError::EveryWithoutOutput),
            (Some(0), true) => Err(svi::Error::invalid("every", "0 steps; need at least 1").into()),
            (Some(_), true) if output.output_times.is_some() => Err(SceneError::NotApplicable {
                option: "--every (output.every)",
                reason: "thins the steps written to the trajectory; with --output-times \
                             the trajectory holds the states at those times"
                    .into(),
            }),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn options_the_scene_cannot_use_are_named() {
        for (text, option) in [
            ("[run]\ntol = 1e-9\n", "--tol (run.tol)"),
            (
                "[run]\nadapt = \"step\"\nmin_points = 4\n",
                "run.min_points",
            ),
            (
                "[method]\nname = \"verlet\"\n[run]\nadapt = \"degree\"\ntol = 1e-9\n",
                "--adapt degree (run.adapt)",
            ),
            (
                "[run]\nadapt = \"step\"\ntol = 1e-9\nrecovery = \"halve-step\"\n",
                "--recovery (run.recovery)",
            ),
            ("[method]\nform = \"full\"\n", "--form (method.form)"),
            ("[initial]\nomega = [1, 0, 0]\n", "initial.omega"),
            (
                "[output]\ndiagnostics = [\"none\", \"energy\"]\n",
                "--diagnostics (output.diagnostics)",
            ),
            (
                "[output]\ntrajectory = \"x.csv\"\nevery = 2\noutput_times = [1.0]\n",
                "--every (output.every)",
            ),
        ] {
            let text = format!("model = \"kepler\"\n{text}");
            match Scene::from_toml(&text, "t") {
                Err(error @ SceneError::NotApplicable { option: named, .. }) => {
                    assert_eq!(named, option, "{text}: {error}");
                    assert!(error.is_bad_input());
                }
                other => panic!("{text}: {other:?}"),
            }
        }
        // The rigid bodies take their own initial fields, and not those on ℝᴺ.
        let top = "model = \"heavy-top\"\n[initial]\nrotation = [0.1, 0, 0]\nomega = [0, 0, 5]\n";
        assert_eq!(
            Scene::from_toml(top, "t").unwrap().space(),
            SpaceKind::Group
        );
        let error = Scene::from_toml("model = \"heavy-top\"\n[initial]\nv = [1, 0, 0]\n", "t");
        assert!(
            matches!(
                error,
                Err(SceneError::NotApplicable {
                    option: "initial.v",
                    ..
                })
            ),
            "{error:?}"
        );
    }
}
