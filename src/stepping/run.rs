//! The one stepping loop, shared by every method.
//!
//! [`Integrator::run`] validates its inputs, converts the initial state to the method's
//! coordinates, and advances with fixed steps: times are t_k = t_0 + k·h (never accumulated
//! with `t += h`), the last step is shortened to land on the horizon when (t_end − t_0)/h is
//! not an integer, and the increments returned by the method are added with compensated
//! (Kahan) summation so long runs keep their accuracy. Observers see the initial point and
//! every step they ask for; a run that observes nothing completes no phase points and
//! computes no diagnostics. Failures come back with the step index and time.
//!
//! [`Integrator::try_run`] is the full form: it takes [`RunOptions`] (a [`Recovery`] policy
//! for failed steps, a divergence limit on the state) and returns a failure as a
//! [`RunFailure`], which carries the run up to the last good state besides the typed error.
//! [`Integrator::run`] is `try_run` with default options, keeping only the error.

use crate::error::{StepFailure, require_finite, require_finite_entries, require_positive};
use crate::method::{Coordinates, PhasePoint, State, TangentMap};
use crate::model::derived::LagrangianExt;
use crate::stepping::grid::{grid_step, step_count};
use crate::stepping::observer::Observer;
use crate::{Error, Lagrangian, Method, Structure};
use nalgebra::SVector;
use std::ops::ControlFlow;

/// Totals of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Statistics {
    /// Steps taken (a step recovered from half steps counts once).
    pub steps: usize,
    /// Failed steps retried with half the step size ([`Recovery::HalveStep`]), at any depth.
    pub retries: usize,
    /// Nonlinear (Newton) iterations, summed over all steps.
    pub iterations: usize,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: usize,
}

/// The result of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Run<const N: usize> {
    /// The last state reached, completed to (t, q, q̇, p).
    pub last: PhasePoint<N>,
    /// The last state in the method's own coordinates.
    pub state: State<N>,
    /// Work done.
    pub statistics: Statistics,
    /// Whether an observer stopped the run before the horizon.
    pub stopped: bool,
}

/// What the stepping loop does when a step fails.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Recovery {
    /// Stop the run with the step's error (the default).
    #[default]
    None,
    /// Retry a failed step as two steps of half the size, each again recoverable, at most
    /// `max_halvings` times in a row (so the smallest sub-step is h/2^max_halvings); then
    /// continue with the original step.
    HalveStep {
        /// Largest number of successive halvings, at most [`RunOptions::MAX_HALVINGS`].
        max_halvings: usize,
    },
}

/// Options of [`Integrator::try_run`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[non_exhaustive]
pub struct RunOptions {
    /// Recovery policy for failed steps (default: none).
    pub recovery: Recovery,
    /// Fail with [`Error::Diverged`] as soon as a component of the state (q, y) exceeds this
    /// in absolute value (default: no limit; NaN and ∞ are always caught).
    pub divergence_limit: Option<f64>,
}

impl RunOptions {
    /// Largest `max_halvings` accepted by [`Recovery::HalveStep`] (2²⁰ sub-steps per step).
    pub const MAX_HALVINGS: usize = 20;

    /// Set the recovery policy.
    pub fn with_recovery(mut self, recovery: Recovery) -> Self {
        self.recovery = recovery;
        self
    }

    /// Set the divergence limit.
    pub fn with_divergence_limit(mut self, limit: f64) -> Self {
        self.divergence_limit = Some(limit);
        self
    }

    /// Check the options: halvings at most [`RunOptions::MAX_HALVINGS`], a positive finite
    /// divergence limit.
    pub fn validate(&self) -> Result<(), Error> {
        if let Recovery::HalveStep { max_halvings } = self.recovery
            && max_halvings > Self::MAX_HALVINGS
        {
            return Err(Error::invalid(
                "max_halvings",
                format!(
                    "{max_halvings} is more than {} successive halvings",
                    Self::MAX_HALVINGS
                ),
            ));
        }
        if let Some(limit) = self.divergence_limit {
            require_positive("divergence_limit", limit)?;
        }
        Ok(())
    }
}

/// A run that failed: the error, and the run up to the last good state.
///
/// Observers passed to [`Integrator::try_run`] keep what they saw before the failure (a
/// [`crate::stepping::observer::Trajectory`] holds the trajectory so far).
#[derive(Debug, Clone, PartialEq)]
pub struct RunFailure<const N: usize> {
    /// What went wrong, with step index and time.
    pub error: Error,
    /// The run up to the last good state (`last` is that state, at the start of the failing
    /// step); `None` when the inputs were rejected before the first step.
    pub partial: Option<Run<N>>,
}

impl<const N: usize> std::fmt::Display for RunFailure<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(run) = &self.partial {
            write!(
                f,
                "; last good state after {} steps at t = {}: q = {:?}, v = {:?}",
                run.statistics.steps,
                run.last.t,
                run.last.q.as_slice(),
                run.last.v.as_slice()
            )?;
        }
        Ok(())
    }
}

impl<const N: usize> std::error::Error for RunFailure<N> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl<const N: usize> From<RunFailure<N>> for Error {
    fn from(failure: RunFailure<N>) -> Error {
        failure.error
    }
}

/// The state of a run between steps.
struct Progress<const N: usize> {
    /// Time of `state`.
    t: f64,
    state: State<N>,
    /// Kahan compensation of `state`.
    compensation: State<N>,
    /// Newton start of the next inverse Legendre map (the last velocity completed).
    guess: SVector<f64, N>,
    statistics: Statistics,
}

/// An initial state: configuration with either velocity or momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Initial<const N: usize> {
    /// (q0, q̇0).
    Velocity {
        /// Configuration.
        q: SVector<f64, N>,
        /// Velocity.
        v: SVector<f64, N>,
    },
    /// (q0, p0).
    Momentum {
        /// Configuration.
        q: SVector<f64, N>,
        /// Momentum.
        p: SVector<f64, N>,
    },
}

/// A model and a method, ready to run.
#[derive(Debug, Clone)]
pub struct Integrator<L, M, const N: usize> {
    model: L,
    method: M,
}

impl<L: Lagrangian<N>, M: Method<N>, const N: usize> Integrator<L, M, N> {
    /// Pair a model with a method.
    pub fn new(model: L, method: M) -> Self {
        Integrator { model, method }
    }

    /// The model.
    pub fn model(&self) -> &L {
        &self.model
    }

    /// The method.
    pub fn method(&self) -> &M {
        &self.method
    }

    /// Complete a method state to a phase point (q̇ from p by the inverse Legendre map, or
    /// p from q̇), with `guess` as the Newton start of the inverse Legendre map.
    pub fn phase_point(
        &self,
        t: f64,
        state: &State<N>,
        guess: &SVector<f64, N>,
    ) -> Result<PhasePoint<N>, Error> {
        let (v, p) = match self.method.info().coordinates {
            Coordinates::Momentum => (self.model.velocity(t, &state.q, &state.y, guess)?, state.y),
            Coordinates::Velocity => (state.y, self.model.momentum(t, &state.q, &state.y)),
        };
        Ok(PhasePoint {
            t,
            q: state.q,
            v,
            p,
        })
    }

    /// The method state for an initial condition.
    pub fn initial_state(&self, t0: f64, initial: &Initial<N>) -> Result<State<N>, Error> {
        let (q, second, name) = match initial {
            Initial::Velocity { q, v } => (q, v, "initial velocity"),
            Initial::Momentum { q, p } => (q, p, "initial momentum"),
        };
        require_finite_entries("initial position", q)?;
        require_finite_entries(name, second)?;
        let y = match (self.method.info().coordinates, initial) {
            (Coordinates::Momentum, Initial::Momentum { p, .. }) => *p,
            (Coordinates::Velocity, Initial::Velocity { v, .. }) => *v,
            (Coordinates::Momentum, Initial::Velocity { q, v }) => self.model.momentum(t0, q, v),
            (Coordinates::Velocity, Initial::Momentum { q, p }) => {
                self.model.velocity(t0, q, p, p)?
            }
        };
        let state = State { q: *q, y };
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: t0,
            });
        }
        Ok(state)
    }

    /// Check a [`Structure::ConstantMass`] declaration at the initial state: L_qv must vanish
    /// and L_vv must not change with q̇ (a necessary condition, checked once per run).
    pub(crate) fn check_structure(&self, t: f64, state: &State<N>) -> Result<(), Error> {
        if L::STRUCTURE != Structure::ConstantMass {
            return Ok(());
        }
        let shifted = state.y * 2.0 + SVector::repeat(1.0);
        let first = self.model.second_derivatives(t, &state.q, &state.y);
        let second = self.model.second_derivatives(t, &state.q, &shifted);
        let scale = 1.0 + first.vv.amax() + first.qq.amax();
        let coupling = first.qv.amax().max(second.qv.amax());
        let change = (first.vv - second.vv).amax();
        if coupling > 1e-12 * scale || change > 1e-12 * scale {
            return Err(Error::invalid(
                "structure",
                format!(
                    "the model declares a constant mass matrix, but ∂²L/∂q∂q̇ = {coupling:e} and \
                     ∂²L/∂q̇² changes by {change:e} with q̇"
                ),
            ));
        }
        Ok(())
    }

    /// Integrate from `t0` to `t_end` with step `h`, reporting to `observer`.
    ///
    /// The same as [`Integrator::try_run`] with [`RunOptions::default`] (no recovery, no
    /// divergence limit), keeping only the error of a failed run. The observer still holds
    /// everything it saw before the failure.
    pub fn run<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        initial: Initial<N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        self.try_run(t0, initial, h, t_end, &RunOptions::default(), observer)
            .map_err(|failure| failure.error)
    }

    /// Integrate from `t0` to `t_end` with step `h` under `options`, reporting to `observer`;
    /// a failure comes back with the run up to the last good state.
    ///
    /// Every step is checked where it happens: a nonlinear solve that does not converge or
    /// meets a singular matrix, a non-finite state, and (with
    /// [`RunOptions::divergence_limit`]) a state beyond a bound. With
    /// [`Recovery::HalveStep`] a failed step is retried as two steps of half the size
    /// (recursively, up to the given depth) and the run continues with the original step; the
    /// time grid t_k = t_0 + k·h is kept and observers see the same step points as without
    /// recovery.
    ///
    /// # Errors
    /// A [`RunFailure`]: the typed [`Error`] (with step index and time for failures during the
    /// run) and, unless the inputs were rejected before the first step, the [`Run`] up to the
    /// last good state (its `last` point, `state` and `statistics`).
    pub fn try_run<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        initial: Initial<N>,
        h: f64,
        t_end: f64,
        options: &RunOptions,
        observer: &mut O,
    ) -> Result<Run<N>, RunFailure<N>> {
        let rejected = |error: Error| RunFailure {
            error,
            partial: None,
        };
        require_finite("t0", t0).map_err(rejected)?;
        require_finite("t_end", t_end).map_err(rejected)?;
        require_positive("h", h).map_err(rejected)?;
        options.validate().map_err(rejected)?;
        if t_end <= t0 {
            return Err(rejected(Error::invalid(
                "t_end",
                format!("the horizon {t_end} is not after the start {t0}"),
            )));
        }
        let steps = step_count(t_end - t0, h).map_err(rejected)?;
        let mut workspace = self.method.workspace(&self.model, h).map_err(rejected)?;
        let state = self.initial_state(t0, &initial).map_err(rejected)?;
        self.check_structure(t0, &state).map_err(rejected)?;
        let guess = match initial {
            Initial::Velocity { v, .. } => v,
            Initial::Momentum { p, .. } => p,
        };
        let mut progress = Progress {
            t: t0,
            state,
            compensation: State::zeros(),
            guess,
            statistics: Statistics::default(),
        };
        let mut stopped = false;
        if observer.wants(0) {
            match self.complete(0, t0, &progress.state, &progress.guess) {
                Ok(point) => {
                    progress.guess = point.v;
                    stopped = observer.observe(&self.model, 0, &point).is_break();
                }
                Err(error) => return Err(self.failure(error, &progress, false)),
            }
        }
        let mut increment = State::zeros();
        for k in 0..steps {
            if stopped {
                break;
            }
            let (t, step_size, end) = grid_step(t0, t_end, h, steps, k);
            let depth = match options.recovery {
                Recovery::None => 0,
                Recovery::HalveStep { max_halvings } => max_halvings,
            };
            if let Err(failure) = self.advance(
                &mut workspace,
                &mut progress,
                &mut increment,
                t,
                step_size,
                depth,
                options.divergence_limit,
            ) {
                return Err(self.failure(failure.at(k, t), &progress, false));
            }
            progress.statistics.steps += 1;
            progress.t = end;
            if observer.wants(k + 1) {
                match self.complete(k + 1, progress.t, &progress.state, &progress.guess) {
                    Ok(point) => {
                        progress.guess = point.v;
                        if let ControlFlow::Break(()) = observer.observe(&self.model, k + 1, &point)
                        {
                            stopped = k + 1 < steps;
                            break;
                        }
                    }
                    Err(error) => return Err(self.failure(error, &progress, false)),
                }
            }
        }
        let last = self
            .complete(
                progress.statistics.steps,
                progress.t,
                &progress.state,
                &progress.guess,
            )
            .map_err(|error| self.failure(error, &progress, stopped))?;
        Ok(Run {
            last,
            state: progress.state,
            statistics: progress.statistics,
            stopped,
        })
    }

    /// [`Integrator::phase_point`], with a non-finite velocity or momentum (from a finite
    /// state, e.g. an overflowing ∂L/∂q̇) reported as [`Error::NonFinite`] at `step`.
    fn complete(
        &self,
        step: usize,
        t: f64,
        state: &State<N>,
        guess: &SVector<f64, N>,
    ) -> Result<PhasePoint<N>, Error> {
        let point = self.phase_point(t, state, guess)?;
        if point.v.iter().chain(point.p.iter()).all(|x| x.is_finite()) {
            Ok(point)
        } else {
            Err(Error::NonFinite {
                what: "velocity or momentum".into(),
                step,
                t,
            })
        }
    }

    /// Advance `progress` over [t, t + h]: one step, or (after a failure, while `depth` > 0)
    /// two half steps, each of them again recoverable with one halving less. On failure the
    /// state is left as it was at t and the first failure (that of the full step) is returned.
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &self,
        workspace: &mut M::Workspace,
        progress: &mut Progress<N>,
        increment: &mut State<N>,
        t: f64,
        h: f64,
        depth: usize,
        divergence_limit: Option<f64>,
    ) -> Result<(), StepFailure> {
        let saved = (progress.state, progress.compensation);
        let failure =
            match self
                .method
                .step(&self.model, workspace, t, h, &progress.state, increment)
            {
                Ok(report) => {
                    progress
                        .state
                        .add_compensated(&mut progress.compensation, increment);
                    progress.statistics.iterations += report.iterations;
                    progress.statistics.evaluations += report.evaluations;
                    let norm = || progress.state.q.amax().max(progress.state.y.amax());
                    if !progress.state.is_finite() {
                        StepFailure::NonFinite
                    } else if let Some(limit) = divergence_limit.filter(|limit| norm() > *limit) {
                        StepFailure::Diverged {
                            norm: norm(),
                            limit,
                        }
                    } else {
                        return Ok(());
                    }
                }
                Err(failure) => failure,
            };
        (progress.state, progress.compensation) = saved;
        if depth == 0 {
            return Err(failure);
        }
        progress.statistics.retries += 1;
        let half = 0.5 * h;
        for (start, size) in [(t, half), (t + half, h - half)] {
            if self
                .advance(
                    workspace,
                    progress,
                    increment,
                    start,
                    size,
                    depth - 1,
                    divergence_limit,
                )
                .is_err()
            {
                (progress.state, progress.compensation) = saved;
                return Err(failure);
            }
        }
        Ok(())
    }

    /// A failure during the run, with the run up to the last good state. Should the inverse
    /// Legendre map fail at that state, its velocity is the last one completed.
    fn failure(&self, error: Error, progress: &Progress<N>, stopped: bool) -> RunFailure<N> {
        let last = self
            .phase_point(progress.t, &progress.state, &progress.guess)
            .unwrap_or_else(|_| {
                let (v, p) = match self.method.info().coordinates {
                    Coordinates::Momentum => (progress.guess, progress.state.y),
                    Coordinates::Velocity => (progress.state.y, progress.guess),
                };
                PhasePoint {
                    t: progress.t,
                    q: progress.state.q,
                    v,
                    p,
                }
            });
        RunFailure {
            error,
            partial: Some(Run {
                last,
                state: progress.state,
                statistics: progress.statistics,
                stopped,
            }),
        }
    }

    /// [`Integrator::run`] from (q0, q̇0).
    pub fn run_from_velocity<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        q0: SVector<f64, N>,
        v0: SVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        self.run(t0, Initial::Velocity { q: q0, v: v0 }, h, t_end, observer)
    }

    /// [`Integrator::run`] from (q0, p0).
    pub fn run_from_momentum<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        q0: SVector<f64, N>,
        p0: SVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        self.run(t0, Initial::Momentum { q: q0, p: p0 }, h, t_end, observer)
    }

    /// One step from `state` at time `t` with step `h`, and its exact Jacobian (the tangent
    /// map) with respect to the method's coordinates.
    pub fn tangent_map(
        &self,
        t: f64,
        state: &State<N>,
        h: f64,
    ) -> Result<(State<N>, TangentMap<N>), Error> {
        require_finite("t", t)?;
        require_positive("h", h)?;
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "state".into(),
                step: 0,
                t,
            });
        }
        let mut workspace = self.method.workspace(&self.model, h)?;
        let (increment, tangent) = self
            .method
            .tangent_map(&self.model, &mut workspace, t, h, state)
            .map_err(|failure| failure.at(0, t))?;
        let next = State {
            q: state.q + increment.q,
            y: state.y + increment.y,
        };
        Ok((next, tangent))
    }
}
