//! The one stepping loop, shared by every method on every space.
//!
//! [`Integrator`] pairs a model with a method ([`Step`]) on a [`Space`] — ℝᴺ or SO(3) — and
//! everything below is written once for all of them. [`Integrator::run`] validates its inputs, converts the initial state to the method's
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

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure, require_finite, require_positive};
use crate::method::space::{Initial, PhasePoint, Space, StepState};
use crate::method::step::Step;
use crate::method::{Euclidean, StepReport};
use crate::stepping::event::EventPoint;
use crate::stepping::grid::{grid_step, grid_steps};
use crate::stepping::observer::Observer;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};
use std::marker::PhantomData;
use std::ops::ControlFlow;
use std::sync::OnceLock;

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
    /// Jacobians of the nonlinear solves assembled and LU-factorised, summed over all steps.
    pub factorizations: usize,
    /// Symbolic analyses of a sparse linear solver's pattern (one per pattern and run).
    pub analyses: usize,
}

impl Statistics {
    /// Add the work of one step.
    pub(crate) fn record(&mut self, report: StepReport) {
        self.iterations += report.iterations;
        self.evaluations += report.evaluations;
        self.factorizations += report.factorizations;
        self.analyses += report.analyses;
    }
}

/// The result of a run on the space `S` (on ℝᴺ: [`crate::Run`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Run<S: Space> {
    /// The last state reached, completed to a point ((t, q, q̇, p) on ℝᴺ).
    pub last: S::Point,
    /// The last state in the method's own coordinates.
    pub state: S::State,
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

/// A run that failed: the error, and the run up to the last good state (on ℝᴺ:
/// [`crate::RunFailure`]).
///
/// Observers passed to [`Integrator::try_run`] keep what they saw before the failure (a
/// [`crate::stepping::observer::Trajectory`] holds the trajectory so far).
#[derive(Debug, Clone, PartialEq)]
pub struct RunFailure<S: Space> {
    /// What went wrong, with step index and time.
    pub error: Error,
    /// The run up to the last good state (`last` is that state, at the start of the failing
    /// step); `None` when the inputs were rejected before the first step.
    pub partial: Option<Run<S>>,
    /// The events a solve located before it failed ([`Integrator::try_solve_events`]), in
    /// the order of their times (a boxed slice: a failure stays small to return).
    pub events: Box<[EventPoint<S::Point>]>,
}

impl<S: Space> RunFailure<S> {
    /// A failure before the first step: no partial run, no events.
    pub fn rejected(error: Error) -> Self {
        RunFailure {
            error,
            partial: None,
            events: Box::default(),
        }
    }
}

impl<S: Space> std::fmt::Display for RunFailure<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(run) = &self.partial {
            write!(
                f,
                "; last good state after {} steps at t = {}: {}",
                run.statistics.steps,
                S::time(&run.last),
                S::describe(&run.last)
            )?;
        }
        Ok(())
    }
}

impl<S: Space + std::fmt::Debug> std::error::Error for RunFailure<S> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl<S: Space> From<RunFailure<S>> for Error {
    fn from(failure: RunFailure<S>) -> Error {
        failure.error
    }
}

/// A state with the compensation of its Kahan sums.
#[derive(Debug, Clone)]
pub(crate) struct Cursor<S: Space> {
    pub(crate) state: S::State,
    pub(crate) compensation: S::State,
}

impl<S: Space> Cursor<S> {
    /// A cursor at `state` with no compensation yet.
    pub(crate) fn new(state: S::State) -> Self {
        Cursor {
            compensation: state.zeros_like(),
            state,
        }
    }
}

/// The state of a run between steps.
pub(crate) struct Progress<S: Space> {
    /// Time of `cursor`.
    pub(crate) t: f64,
    pub(crate) cursor: Cursor<S>,
    /// Newton start of the next inverse Legendre map (the last velocity completed).
    pub(crate) guess: S::Velocity,
    pub(crate) statistics: Statistics,
    /// The last point handed to an observer, whose memory the next one reuses.
    pub(crate) point: Option<S::Point>,
}

/// A model and a method on the space `S`, ready to run.
///
/// On ℝᴺ, `S` is [`Euclidean<N>`](crate::method::Euclidean) and is inferred from the model:
/// `Integrator::new(model, Svi::new(6))`. On SO(3) it is
/// [`crate::lie_group::RigidBodyIntegrator`].
#[derive(Debug, Clone)]
pub struct Integrator<L, M, S> {
    model: L,
    method: M,
    /// Set once the model's declarations have passed [`Step::check_model`] (at the first
    /// run's initial state): the model and method cannot change, so later runs skip it.
    checked: OnceLock<()>,
    space: PhantomData<fn() -> S>,
}

impl<L, M: Step<L, S>, S: Space> Integrator<L, M, S> {
    /// Pair a model with a method.
    pub fn new(model: L, method: M) -> Self {
        Integrator {
            model,
            method,
            checked: OnceLock::new(),
            space: PhantomData,
        }
    }

    /// The model.
    pub fn model(&self) -> &L {
        &self.model
    }

    /// The method.
    pub fn method(&self) -> &M {
        &self.method
    }

    /// Complete a method state to a point (q̇ from p by the inverse Legendre map, or p from
    /// q̇), with `guess` as the Newton start of the inverse Legendre map.
    pub fn phase_point(
        &self,
        t: f64,
        state: &S::State,
        guess: &S::Velocity,
    ) -> Result<S::Point, Error> {
        self.method.complete(&self.model, None, t, state, guess)
    }

    /// The method state for an initial condition, after checking it.
    pub fn initial_state(&self, t0: f64, initial: &S::Initial) -> Result<S::State, Error> {
        self.method.initial_state(&self.model, t0, initial)
    }

    /// Integrate from `t0` to `t_end` with step `h`, reporting to `observer`.
    ///
    /// The same as [`Integrator::try_run`] with [`RunOptions::default`] (no recovery, no
    /// divergence limit), keeping only the error of a failed run. The observer still holds
    /// everything it saw before the failure.
    pub fn run<O: Observer<L, S::Point>>(
        &self,
        t0: f64,
        initial: S::Initial,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<S>, Error> {
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
    pub fn try_run<O: Observer<L, S::Point>>(
        &self,
        t0: f64,
        initial: S::Initial,
        h: f64,
        t_end: f64,
        options: &RunOptions,
        observer: &mut O,
    ) -> Result<Run<S>, RunFailure<S>> {
        let steps = grid_steps(t0, t_end, h).map_err(RunFailure::rejected)?;
        options.validate().map_err(RunFailure::rejected)?;
        let mut workspace = self
            .method
            .workspace(&self.model, h)
            .map_err(RunFailure::rejected)?;
        let mut progress = self.start(t0, &initial).map_err(RunFailure::rejected)?;
        let stopped = self.run_grid(
            &mut workspace,
            &mut progress,
            (t0, t_end, h, steps),
            options,
            observer,
            false,
            |_, _, _, _, _| Ok(ControlFlow::Continue(())),
        )?;
        self.finish(Some(&workspace), progress, stopped)
    }

    /// One step of size `h` from `state` at `t` with a fresh workspace (a cold start): the
    /// new state (without compensated summation) and the work done.
    pub fn step(&self, t: f64, state: &S::State, h: f64) -> Result<(S::State, StepReport), Error> {
        let mut workspace = self.cold_workspace(t, state, h)?;
        let mut increment = state.zeros_like();
        let report = self
            .method
            .step(&self.model, &mut workspace, t, h, state, &mut increment)
            .map_err(|failure| failure.at(0, t))?;
        Ok((state.plus(&increment), report))
    }

    /// One step from `state` at time `t` with step `h`, and its exact Jacobian (the tangent
    /// map) with respect to the method's coordinates.
    pub fn tangent_map(
        &self,
        t: f64,
        state: &S::State,
        h: f64,
    ) -> Result<(S::State, S::Tangent), Error> {
        let mut workspace = self.cold_workspace(t, state, h)?;
        let (increment, tangent, _) = self
            .method
            .tangent_map(&self.model, &mut workspace, t, h, state)
            .map_err(|failure| failure.at(0, t))?;
        Ok((state.plus(&increment), tangent))
    }

    /// A fresh workspace for one step of size `h` from `state` at `t`, after checking all
    /// three.
    fn cold_workspace(&self, t: f64, state: &S::State, h: f64) -> Result<M::Workspace, Error> {
        require_finite("t", t)?;
        require_positive("h", h)?;
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "state".into(),
                step: 0,
                t,
            });
        }
        self.method.workspace(&self.model, h)
    }

    /// The progress of a run at its start: the initial state in the method's coordinates,
    /// after the model's declarations are checked (by the integrator's first run that gets
    /// this far; a failed check is repeated by the next run).
    pub(crate) fn start(&self, t0: f64, initial: &S::Initial) -> Result<Progress<S>, Error> {
        let state = self.initial_state(t0, initial)?;
        if self.checked.get().is_none() {
            self.method.check_model(&self.model, t0, &state)?;
            // Another thread's run may have set it first: the same fact.
            let _ = self.checked.set(());
        }
        Ok(Progress {
            t: t0,
            cursor: Cursor::new(state),
            guess: S::initial_guess(initial),
            statistics: Statistics::default(),
            point: None,
        })
    }

    /// The fixed-grid loop: `steps` steps of the grid (t0, t_end, h) from `progress`, with
    /// recovery, divergence limit and observers, calling `after_step(workspace, t, h, start,
    /// end)` after each step (dense output of the step just taken). The state at the start
    /// of each step is kept (copied) only with `keep_start`; otherwise `start` is `None`.
    /// Returns whether an observer stopped the run.
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    pub(crate) fn run_grid<O: Observer<L, S::Point>>(
        &self,
        workspace: &mut M::Workspace,
        progress: &mut Progress<S>,
        (t0, t_end, h, steps): (f64, f64, f64, usize),
        options: &RunOptions,
        observer: &mut O,
        keep_start: bool,
        mut after_step: impl FnMut(
            &M::Workspace,
            f64,
            f64,
            Option<&S::State>,
            &Progress<S>,
        ) -> Result<ControlFlow<()>, Error>,
    ) -> Result<bool, RunFailure<S>> {
        let depth = match options.recovery {
            Recovery::None => 0,
            Recovery::HalveStep { max_halvings } => max_halvings,
        };
        if observer.wants(0) && self.observe(0, Some(workspace), progress, observer)? {
            return Ok(true);
        }
        let mut increment = progress.cursor.state.zeros_like();
        let mut start = keep_start.then(|| progress.cursor.state.clone());
        for k in 0..steps {
            let (t, step_size, end) = grid_step(t0, t_end, h, steps, k);
            if let Some(start) = &mut start {
                start.assign(&progress.cursor.state);
            }
            if let Err(failure) = self.advance(
                &self.method,
                workspace,
                progress,
                &mut increment,
                t,
                step_size,
                depth,
                options.divergence_limit,
            ) {
                return Err(self.failure(failure.at(k, t), progress, false));
            }
            progress.statistics.steps += 1;
            progress.t = end;
            let flow = after_step(workspace, t, step_size, start.as_ref(), progress)
                .map_err(|error| self.failure(error, progress, false))?;
            if flow.is_break() {
                return Ok(true);
            }
            if observer.wants(k + 1) && self.observe(k + 1, Some(workspace), progress, observer)? {
                return Ok(k + 1 < steps);
            }
        }
        Ok(false)
    }

    /// Complete the current point (from `workspace`, of the run that reached it, where it
    /// can) and hand it to `observer` as the point after step `step`; whether the observer
    /// asked to stop.
    pub(crate) fn observe<O: Observer<L, S::Point>>(
        &self,
        step: usize,
        workspace: Option<&M::Workspace>,
        progress: &mut Progress<S>,
        observer: &mut O,
    ) -> Result<bool, RunFailure<S>> {
        let Progress {
            t,
            cursor,
            guess,
            point: kept,
            ..
        } = progress;
        // The last observed point's memory is reused, completed where it lies: a point moved
        // out and back is copied in pieces and read whole, which stalls the loads of a cheap
        // step's observers on the stores.
        let completed = match kept {
            Some(point) => self
                .complete_into(workspace, step, *t, &cursor.state, guess, point)
                .map(|()| point),
            None => self
                .complete(workspace, step, *t, &cursor.state, guess)
                .map(|point| kept.insert(point)),
        };
        match completed {
            Ok(point) => {
                S::assign_velocity(guess, point);
                Ok(observer.observe(&self.model, step, point).is_break())
            }
            Err(error) => Err(self.failure(error, progress, false)),
        }
    }

    /// The finished run at `progress`, its last point completed from `workspace` (of the run
    /// that reached it) where one is at hand.
    pub(crate) fn finish(
        &self,
        workspace: Option<&M::Workspace>,
        progress: Progress<S>,
        stopped: bool,
    ) -> Result<Run<S>, RunFailure<S>> {
        let last = self
            .complete(
                workspace,
                progress.statistics.steps,
                progress.t,
                &progress.cursor.state,
                &progress.guess,
            )
            .map_err(|error| self.failure(error, &progress, stopped))?;
        Ok(Run {
            last,
            state: progress.cursor.state,
            statistics: progress.statistics,
            stopped,
        })
    }

    /// [`Integrator::phase_point`] (from what `workspace`, of the run that reached `state`,
    /// holds where it can), with a non-finite velocity or momentum (from a finite state, e.g.
    /// an overflowing ∂L/∂q̇) reported as [`Error::NonFinite`] at `step`.
    pub(crate) fn complete(
        &self,
        workspace: Option<&M::Workspace>,
        step: usize,
        t: f64,
        state: &S::State,
        guess: &S::Velocity,
    ) -> Result<S::Point, Error> {
        let point = self
            .method
            .complete(&self.model, workspace, t, state, guess)?;
        self.check_point(&point, step, t)?;
        Ok(point)
    }

    /// [`Integrator::complete`] into `point`, a point of an earlier completion of this run.
    pub(crate) fn complete_into(
        &self,
        workspace: Option<&M::Workspace>,
        step: usize,
        t: f64,
        state: &S::State,
        guess: &S::Velocity,
        point: &mut S::Point,
    ) -> Result<(), Error> {
        self.method
            .complete_into(&self.model, workspace, t, state, guess, point)?;
        self.check_point(point, step, t)
    }

    /// [`Error::NonFinite`] at `step` unless every number of `point` is finite.
    fn check_point(&self, point: &S::Point, step: usize, t: f64) -> Result<(), Error> {
        if self.method.point_is_finite(point) {
            Ok(())
        } else {
            Err(Error::NonFinite {
                what: "velocity or momentum".into(),
                step,
                t,
            })
        }
    }

    /// One step of `method` from `cursor` at `t` with size `h`, in place (the increment
    /// added with compensated summation), checked for finite values and against the
    /// divergence limit; on failure `cursor` is left as it was.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn attempt(
        &self,
        method: &M,
        workspace: &mut M::Workspace,
        increment: &mut S::State,
        t: f64,
        h: f64,
        cursor: &mut Cursor<S>,
        divergence_limit: Option<f64>,
        statistics: &mut Statistics,
    ) -> Result<(), StepFailure> {
        let report = method.step(&self.model, workspace, t, h, &cursor.state, increment)?;
        statistics.record(report);
        cursor
            .state
            .add_checked(&mut cursor.compensation, increment, divergence_limit)
    }

    /// Advance `progress` over [t, t + h]: one step, or (after a failure, while `depth` > 0)
    /// two half steps, each of them again recoverable with one halving less. On failure the
    /// state is left as it was at t and the first failure (that of the full step) is returned.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn advance(
        &self,
        method: &M,
        workspace: &mut M::Workspace,
        progress: &mut Progress<S>,
        increment: &mut S::State,
        t: f64,
        h: f64,
        depth: usize,
        divergence_limit: Option<f64>,
    ) -> Result<(), StepFailure> {
        let failure = match self.attempt(
            method,
            workspace,
            increment,
            t,
            h,
            &mut progress.cursor,
            divergence_limit,
            &mut progress.statistics,
        ) {
            Ok(()) => return Ok(()),
            Err(failure) => failure,
        };
        if depth == 0 {
            return Err(failure);
        }
        progress.statistics.retries += 1;
        let saved = progress.cursor.clone();
        let half = 0.5 * h;
        for (start, size) in [(t, half), (t + half, h - half)] {
            if self
                .advance(
                    method,
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
                progress.cursor = saved;
                return Err(failure);
            }
        }
        Ok(())
    }

    /// A failure during the run, with the run up to the last good state. Should the inverse
    /// Legendre map fail at that state, its velocity is the last one completed.
    pub(crate) fn failure(
        &self,
        error: Error,
        progress: &Progress<S>,
        stopped: bool,
    ) -> RunFailure<S> {
        let state = &progress.cursor.state;
        let last = self
            .phase_point(progress.t, state, &progress.guess)
            .unwrap_or_else(|_| self.method.incomplete(progress.t, state, &progress.guess));
        RunFailure {
            error,
            partial: Some(Run {
                last,
                state: state.clone(),
                statistics: progress.statistics,
                stopped,
            }),
            events: Box::default(),
        }
    }
}

impl<L, M: Step<L, Euclidean<N>>, N: Dimension> Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// [`Integrator::run`] from (q0, q̇0).
    pub fn run_from_velocity<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        q0: OVector<f64, N>,
        v0: OVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<Euclidean<N>>, Error> {
        self.run(t0, Initial::Velocity { q: q0, v: v0 }, h, t_end, observer)
    }

    /// [`Integrator::run`] from (q0, p0).
    pub fn run_from_momentum<O: Observer<L, PhasePoint<N>>>(
        &self,
        t0: f64,
        q0: OVector<f64, N>,
        p0: OVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<Euclidean<N>>, Error> {
        self.run(t0, Initial::Momentum { q: q0, p: p0 }, h, t_end, observer)
    }
}
