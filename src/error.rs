//! The one error type of the library.
//!
//! A normal end of a run (horizon reached, an observer asked to stop) is not an error. Every
//! failure carries the context needed to act on it: which parameter, which step, which time.

use thiserror::Error as ThisError;

/// Everything that can go wrong in `svi`.
#[derive(Debug, Clone, PartialEq, ThisError)]
#[non_exhaustive]
pub enum Error {
    /// A parameter, option or input value is out of its allowed range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Name of the offending parameter (as the user spells it).
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The nonlinear solve of a step did not converge.
    #[error(
        "nonlinear solve did not converge at step {step} (t = {t:?}): {iterations} iterations, last increment {residual:e}"
    )]
    NonConvergence {
        /// Index of the failing step (the step from `t` to `t + h`), counted from 0.
        step: usize,
        /// Time at the start of the failing step.
        t: f64,
        /// Iterations performed.
        iterations: usize,
        /// Infinity norm of the last increment of the unknowns (Newton or fixed-point); the
        /// field keeps its historical name.
        residual: f64,
    },
    /// The Newton matrix of a step was singular.
    #[error("singular Newton matrix at step {step} (t = {t:?})")]
    SingularMatrix {
        /// Index of the failing step.
        step: usize,
        /// Time at the start of the failing step.
        t: f64,
    },
    /// The inverse Legendre map q̇(q, p) did not converge, or met a singular mass matrix
    /// (`residual` infinite).
    #[error("{}", legendre_message(*t, *iterations, *residual))]
    LegendreMap {
        /// Time of the state being converted.
        t: f64,
        /// Iterations performed.
        iterations: usize,
        /// Infinity norm of the last Newton increment.
        residual: f64,
    },
    /// The step-size control needed a step below the minimum: the tolerance cannot be met
    /// (step doubling), or the energy equation has no step above it (symplectic-energy-
    /// momentum steps); `cause` says which.
    #[error(
        "step size {h:e} at t = {t:?} is below the minimum {min_step:e} after {rejections} rejected steps: {cause}"
    )]
    StepSizeTooSmall {
        /// Why the step had to be this small, e.g. "the tolerance cannot be met".
        cause: &'static str,
        /// Time at which the step was tried.
        t: f64,
        /// The step size that would be needed next.
        h: f64,
        /// The smallest step allowed.
        min_step: f64,
        /// Consecutive rejections at `t`.
        rejections: usize,
    },
    /// A state or an intermediate value became NaN or infinite.
    #[error("non-finite {what} at step {step} (t = {t:?})")]
    NonFinite {
        /// What became non-finite (for example "state" or "initial momentum").
        what: String,
        /// Index of the step in which it happened.
        step: usize,
        /// Time at the start of that step.
        t: f64,
    },
    /// The state left the bound set by [`crate::stepping::run::RunOptions::divergence_limit`]:
    /// the signature of a step beyond the method's stability limit.
    #[error(
        "state diverged at step {step} (t = {t:?}): largest component {norm:e} exceeds the limit {limit:e}"
    )]
    Diverged {
        /// Index of the step after which the bound was exceeded.
        step: usize,
        /// Time at the start of that step.
        t: f64,
        /// Largest absolute component of the state (q, y) after the step.
        norm: f64,
        /// The bound that was exceeded.
        limit: f64,
    },
    /// An adaptive or reparametrised solve used up its step budget
    /// ([`crate::stepping::solve::SolveOptions::max_steps`]) before the horizon: the steps it
    /// chose are too small for the span (a stiff or runaway problem, or a tolerance too
    /// tight for the method).
    #[error(
        "the run took its {max_steps} allowed steps and stopped at t = {t:?}, before the horizon: its steps are too small for the span"
    )]
    TooManySteps {
        /// Index of the step that would have exceeded the budget.
        step: usize,
        /// Time reached.
        t: f64,
        /// The budget.
        max_steps: usize,
    },
    /// A Lie-group step's algebra increment left the natural chart (on a rotation factor a
    /// rotation by π or more in one step), where the chart no longer describes the step.
    #[error(
        "the step at step {step} (t = {t:?}) reaches {reach:.3} of the natural chart's domain (a rotation by {reach:.3}π or more in one step); take a smaller step"
    )]
    OutsideChart {
        /// Index of the step.
        step: usize,
        /// Start time of the step.
        t: f64,
        /// The step's [`crate::model::group::LieGroup::chart_reach`] (≥ 1).
        reach: f64,
    },
    /// A moving mesh folded: after the step, two nodes crossed or met (a cell of width ≤ 0),
    /// so the field on it would be meaningless ([`crate::field::r_adaptive`]).
    #[error(
        "the moving mesh folded at step {step} (t = {t:?}): cell {cell} has width {width:e}; take a smaller step or more smoothing"
    )]
    MeshFold {
        /// Index of the step.
        step: usize,
        /// Start time of the step.
        t: f64,
        /// Index of the first cell of non-positive width (between nodes `cell` and
        /// `cell + 1`).
        cell: usize,
        /// Its width x_{cell+1} − x_cell.
        width: f64,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(name: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            reason: reason.into(),
        }
    }

    /// The kind of error as a stable snake-case name (for machine-readable reports):
    /// `invalid_parameter`, `non_convergence`, `singular_matrix`, `legendre_map`,
    /// `step_size_too_small`, `non_finite`, `diverged`, `too_many_steps`, `outside_chart` or
    /// `mesh_fold`.
    pub fn kind(&self) -> &'static str {
        match self {
            Error::InvalidParameter { .. } => "invalid_parameter",
            Error::NonConvergence { .. } => "non_convergence",
            Error::SingularMatrix { .. } => "singular_matrix",
            Error::LegendreMap { .. } => "legendre_map",
            Error::StepSizeTooSmall { .. } => "step_size_too_small",
            Error::NonFinite { .. } => "non_finite",
            Error::Diverged { .. } => "diverged",
            Error::TooManySteps { .. } => "too_many_steps",
            Error::OutsideChart { .. } => "outside_chart",
            Error::MeshFold { .. } => "mesh_fold",
        }
    }

    /// The index of the failing step, for failures that happen in a step.
    pub fn step(&self) -> Option<usize> {
        match *self {
            Error::NonConvergence { step, .. }
            | Error::SingularMatrix { step, .. }
            | Error::NonFinite { step, .. }
            | Error::Diverged { step, .. }
            | Error::TooManySteps { step, .. }
            | Error::OutsideChart { step, .. }
            | Error::MeshFold { step, .. } => Some(step),
            _ => None,
        }
    }

    /// The time at which the failure happened (the start of the failing step), for failures
    /// during a run.
    pub fn time(&self) -> Option<f64> {
        match *self {
            Error::NonConvergence { t, .. }
            | Error::SingularMatrix { t, .. }
            | Error::NonFinite { t, .. }
            | Error::Diverged { t, .. }
            | Error::LegendreMap { t, .. }
            | Error::StepSizeTooSmall { t, .. }
            | Error::TooManySteps { t, .. }
            | Error::OutsideChart { t, .. }
            | Error::MeshFold { t, .. } => Some(t),
            Error::InvalidParameter { .. } => None,
        }
    }
}

/// The message of [`Error::LegendreMap`]: a singular mass matrix (an infinite `residual`) is
/// named as such.
fn legendre_message(t: f64, iterations: usize, residual: f64) -> String {
    if residual.is_finite() {
        format!(
            "inverse Legendre map did not converge at t = {t:?}: {iterations} iterations, last \
             increment {residual:e}"
        )
    } else {
        format!(
            "inverse Legendre map failed at t = {t:?}: the mass matrix (the Hessian of L in the \
             velocities) is singular there: L must depend on every velocity, at least \
             quadratically, for the velocities to follow from the momenta"
        )
    }
}

/// Why one step failed, without the step's context (the [`crate::Integrator`] adds it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepFailure {
    /// The nonlinear iteration reached its cap.
    NonConvergence {
        /// Iterations performed.
        iterations: usize,
        /// Infinity norm of the last increment.
        residual: f64,
    },
    /// The Newton matrix was singular.
    SingularMatrix,
    /// A value became NaN or infinite.
    NonFinite,
    /// The state after the step exceeds the divergence limit (set by the stepping loop, never
    /// by a method).
    Diverged {
        /// Largest absolute component of the state after the step.
        norm: f64,
        /// The bound that was exceeded.
        limit: f64,
    },
    /// A Lie-group step left the natural chart ([`Error::OutsideChart`]).
    OutsideChart {
        /// The step's [`crate::model::group::LieGroup::chart_reach`] (≥ 1).
        reach: f64,
    },
    /// The method cannot do what was asked of it on this model (an
    /// [`Error::InvalidParameter`] named `option`).
    Unsupported {
        /// The option or operation asked for.
        option: &'static str,
        /// Why not.
        reason: &'static str,
    },
}

impl StepFailure {
    /// Attach the step index and start time.
    pub fn at(self, step: usize, t: f64) -> Error {
        match self {
            StepFailure::NonConvergence {
                iterations,
                residual,
            } => Error::NonConvergence {
                step,
                t,
                iterations,
                residual,
            },
            StepFailure::SingularMatrix => Error::SingularMatrix { step, t },
            StepFailure::NonFinite => Error::NonFinite {
                what: "state".into(),
                step,
                t,
            },
            StepFailure::Diverged { norm, limit } => Error::Diverged {
                step,
                t,
                norm,
                limit,
            },
            StepFailure::OutsideChart { reach } => Error::OutsideChart { step, t, reach },
            StepFailure::Unsupported { option, reason } => Error::invalid(option, reason),
        }
    }
}

/// Check that `value` is finite and strictly positive.
pub(crate) fn require_positive(name: &str, value: f64) -> Result<(), Error> {
    if !value.is_finite() {
        return Err(Error::invalid(name, format!("{value:?} is not finite")));
    }
    if value <= 0.0 {
        return Err(Error::invalid(name, format!("{value:?} must be positive")));
    }
    Ok(())
}

/// Check that `value` is finite.
pub(crate) fn require_finite(name: &str, value: f64) -> Result<(), Error> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(name, format!("{value:?} is not finite")))
    }
}

/// Check that every entry of `values` is finite; an error names the entry, `name[i]`.
pub(crate) fn require_finite_entries<'a>(
    name: &str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), Error> {
    // The entry's name is formatted only for the error (this runs over n entries per run).
    match values.into_iter().enumerate().find(|(_, x)| !x.is_finite()) {
        Some((i, x)) => require_finite(&format!("{name}[{i}]"), *x),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_steps_and_times_of_errors() {
        let failure = StepFailure::NonConvergence {
            iterations: 50,
            residual: 1e-3,
        }
        .at(7, 1.4);
        assert_eq!(failure.kind(), "non_convergence");
        assert_eq!((failure.step(), failure.time()), (Some(7), Some(1.4)));
        let invalid = Error::invalid("h", "must be positive");
        assert_eq!(invalid.kind(), "invalid_parameter");
        assert_eq!((invalid.step(), invalid.time()), (None, None));
        let legendre = Error::LegendreMap {
            t: 2.0,
            iterations: 3,
            residual: 1.0,
        };
        assert_eq!((legendre.kind(), legendre.step()), ("legendre_map", None));
        assert_eq!(legendre.time(), Some(2.0));
    }
}
