//! Scenes with holonomic constraints: a Lagrangian written as text with
//! `constraints = ["x^2 + y^2 + z^2 - l^2", ...]`, run by a constrained method
//! ([`svi::method::constrained::ConstrainedMethod`]: `rattle`, `rattle-yoshida4`, ...).
//!
//! A scene's method ([`SceneMethod`], `[method] name` and `--method`; see
//! [`crate::scene::method`]) is either a method of
//! the registry ([`svi::method::registry::METHODS`]) or a constrained one; a scene with
//! constraints takes a constrained method (by default `rattle`), every other scene a method of
//! the registry, and each mismatch is an error that lists the methods the scene takes. What a
//! constrained run cannot use (adaptivity, output times, recovery, a divergence limit, points
//! and quadrature, the `solution` diagnostic) is refused by name ([`Scene::check`]).
//!
//! ```toml
//! lagrangian = "0.5*m*(vx^2 + vy^2 + vz^2) - m*g*z"
//! coordinates = ["x", "y", "z"]
//! constraints = ["x^2 + y^2 + z^2 - l^2"]   # g(q) = 0, in q and the parameters
//! symmetries = [["-y", "x", "0"]]           # optional: rotations about the vertical
//!
//! [method]
//! name = "rattle-kahan-li8"                 # default "rattle"
//! ```

use svi::method::constrained::ConstrainedMethod;
use svi::method::registry;
use svi::model::text::TextModel;

use crate::scene::method::{SceneMethod, constrained_names};
use crate::scene::schema::{AdaptMode, Diagnostic, RecoveryKind};
use crate::scene::{Scene, SceneError, Text};

/// The method a scene with constraints runs when it names none.
pub const DEFAULT_CONSTRAINED_METHOD: &str = "rattle";

/// A reason listing the constrained methods, for errors about a scene's method.
fn with_constraints_take() -> String {
    format!(
        "a scene with constraints takes a constrained method ({})",
        constrained_names()
    )
}

impl Scene {
    /// Whether the scene has holonomic constraints or names a constrained method: it runs on
    /// the constrained path ([`Scene::constrained_method`]).
    pub fn is_constrained(&self) -> bool {
        self.constraints.is_some() || matches!(self.method.name, Some(SceneMethod::Constrained(_)))
    }

    /// The constrained method of a scene with constraints: `[method] name`, by default
    /// [`DEFAULT_CONSTRAINED_METHOD`]. An error says which methods the scene takes when its
    /// method does not fit it (a method of the registry with constraints, a constrained
    /// method without).
    pub fn constrained_method(&self) -> Result<ConstrainedMethod, SceneError> {
        let option = "--method (method.name)";
        match (&self.method.name, &self.constraints) {
            (Some(SceneMethod::Constrained(method)), Some(_)) => Ok(method.clone()),
            (None, Some(_)) => Ok(ConstrainedMethod::named(DEFAULT_CONSTRAINED_METHOD)
                .unwrap_or_else(|| unreachable!("rattle is a constrained method"))),
            // The registry's names of the segment rules and svi:P/Q name their constrained
            // versions in a scene with constraints.
            (Some(SceneMethod::Registry(spec)), Some(_))
                if ConstrainedMethod::named(&spec.to_string()).is_some() =>
            {
                Ok(ConstrainedMethod::named(&spec.to_string())
                    .unwrap_or_else(|| unreachable!("checked by the guard")))
            }
            (Some(SceneMethod::Registry(spec)), Some(_)) => Err(SceneError::NotApplicable {
                option,
                reason: format!(
                    "{spec} integrates without constraints; {}",
                    with_constraints_take()
                ),
            }),
            (method, None) => Err(SceneError::NotApplicable {
                option,
                reason: format!(
                    "{} is a constrained method, and the scene has no constraints (constraints \
                     = [\"...\"] beside a lagrangian written as text); its methods are those \
                     of svi run --help ({})",
                    method
                        .as_ref()
                        .map_or_else(String::new, ToString::to_string),
                    registry::known_names()
                ),
            }),
        }
    }

    /// The checks of a scene with constraints ([`Scene::check`] calls it instead of those of
    /// the other scenes): a constrained method, a Lagrangian written as text that RATTLE can
    /// integrate (½q̇ᵀMq̇ − V(q): constant mass, autonomous, unforced), at least one
    /// constraint, an initial state on ℝᴺ, and none of the options a constrained run does not
    /// use.
    pub(crate) fn check_constrained(&self) -> Result<(), SceneError> {
        self.constrained_method()?;
        let Some(Ok(Text::Model(model))) = self.text() else {
            // check_model has reported the model's errors: this is a chain, or no text.
            return Err(SceneError::NotApplicable {
                option: "constraints",
                reason: "belong to a Lagrangian written as text with named coordinates".into(),
            });
        };
        if model.constraint_count() == 0 {
            return Err(svi::Error::invalid(
                "constraints",
                "the list is empty: give at least one constraint g(q) = 0, or drop constraints \
                 and run the model with a method of the registry (svi, verlet, ...)",
            )
            .into());
        }
        check_declarations(&model, &self.constrained_method()?)?;
        self.check_vector_initial()?;
        let run = &self.run;
        let refused = [
            (
                run.adapt.is_some_and(|adapt| adapt != AdaptMode::None),
                "--adapt (run.adapt)",
            ),
            (run.tol.is_some(), "--tol (run.tol)"),
            (run.monitor.is_some(), "--monitor (run.monitor)"),
            (run.min_points.is_some(), "run.min_points"),
            (run.max_points.is_some(), "run.max_points"),
            (
                run.recovery == Some(RecoveryKind::HalveStep),
                "--recovery (run.recovery)",
            ),
            (run.max_halvings.is_some(), "run.max_halvings"),
            (
                run.divergence_limit.is_some(),
                "--divergence-limit (run.divergence_limit)",
            ),
            (self.method.points.is_some(), "--points (method.points)"),
            (
                self.method.quadrature.is_some(),
                "--quadrature (method.quadrature)",
            ),
            (
                self.output.output_times.is_some(),
                "--output-times (output.output_times)",
            ),
            (self.output.dense, "dense"),
            (
                self.wants_explicitly(Diagnostic::Solution),
                "--diagnostics solution (output.diagnostics)",
            ),
            (
                self.wants_explicitly(Diagnostic::Momentum)
                    && self.symmetries.as_ref().is_none_or(Vec::is_empty),
                "--diagnostics momentum (output.diagnostics)",
            ),
        ];
        if let Some((_, option)) = refused.into_iter().find(|(given, _)| *given) {
            return Err(SceneError::NotApplicable {
                option,
                reason: "not for a constrained run: it takes fixed steps --h to --t-end, the \
                         energy and momentum diagnostics (momentum with symmetries = [...]) and \
                         writes --out with --every and --multipliers"
                    .into(),
            });
        }
        if let Some(steps) = run.max_steps {
            crate::scene::limits::count(
                "--max-steps (run.max_steps)",
                steps,
                1,
                svi::stepping::grid::MAX_STEPS,
                "steps",
            )?;
        }
        Ok(())
    }
}

/// A Lagrangian that a constrained scene runs: ½q̇ᵀMq̇ − V(q), autonomous and unforced. (In
/// Rust the segment rules and the constrained SVI take any regular L; the scene's run path
/// computes velocities as M⁻¹p, for a constant M.)
fn check_declarations(model: &TextModel, method: &ConstrainedMethod) -> Result<(), SceneError> {
    let reason = if model.forced() {
        "has forces"
    } else if model.time_dependent() {
        "depends on t"
    } else if model.structure() != svi::Structure::ConstantMass {
        "is not recognised as ½q̇ᵀMq̇ − V(q) with a constant mass matrix M"
    } else {
        return Ok(());
    };
    Err(SceneError::NotApplicable {
        option: "lagrangian",
        reason: format!(
            "scenes with constraints run L = ½q̇ᵀMq̇ − V(q) (constant mass, autonomous, \
             unforced) with {}; this L {reason} (from Rust, midpoint and svi:P/Q take any \
             regular unforced L)",
            method.name()
        ),
    })
}
