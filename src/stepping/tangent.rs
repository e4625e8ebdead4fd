//! Fixed-step runs on ℝᴺ that step by the exact tangent map ([`Step::tangent_map`]) and hand
//! each step's Jacobian to a [`TangentObserver`]: the linearised flow of the method itself,
//! from which chaos indicators are computed ([`crate::analysis::chaos`]).
//!
//! [`Integrator::try_run_tangent`] walks the same grid as [`Integrator::try_run`] (t_k =
//! t_0 + k·h, the last step shortened to land on the horizon, [`crate::stepping::grid`]) with
//! one workspace for the whole run, so the methods' warm starts carry over from step to
//! step as in a plain run, and adds the increments with the same compensated summation.
//! Each step is taken by [`Step::tangent_map`]: the step and its Jacobian
//! Φ_k = ∂(q_{k+1}, y_{k+1})/∂(q_k, y_k) (y = p or q̇, the method's coordinates), exact up to
//! the convergence of the step's nonlinear solve (implicit function theorem on the converged
//! equations, derivatives of L by automatic differentiation). The product Φ_{k−1} ⋯ Φ_0 is
//! the Jacobian of the numerical flow: for a symplectic method in (q, p) every factor is
//! symplectic, and the Lyapunov spectrum of the discrete flow pairs as ±λ.
//!
//! A run here takes no recovery (a failed step is an error: halving it would change the map
//! whose Jacobian is observed) and no divergence limit (NaN and ∞ are caught); its
//! [`Statistics`](crate::stepping::run::Statistics) count the work of the steps' solves as a
//! plain run does (the Jacobians' own derivative evaluations are not counted).

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::method::Euclidean;
use crate::method::space::{Initial, PhasePoint, State, StepState, TangentMap};
use crate::method::step::Step;
use crate::stepping::grid::{grid_step, grid_steps};
use crate::stepping::run::{Integrator, Progress, Run, RunFailure};
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::ops::ControlFlow;

/// One step of a tangent run, as a [`TangentObserver`] sees it.
#[derive(Debug)]
pub struct TangentStep<'a, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The number of steps taken (1 after the first step): this is the state after step
    /// `step − 1` of the grid, counted from 0 as failures count them.
    pub step: usize,
    /// The time at the end of the step.
    pub t: f64,
    /// The size of the step (h, or the shortened last step).
    pub h: f64,
    /// Whether this is the last step of the run.
    pub last: bool,
    /// The state at the end of the step, in the method's coordinates (q, y).
    pub state: &'a State<N>,
    /// The state completed to a point (t, q, q̇, p), when [`TangentObserver::wants_point`]
    /// asked for it; `None` otherwise.
    pub point: Option<&'a PhasePoint<N>>,
    /// The step's Jacobian ∂(q', y')/∂(q, y) at the state at its start.
    pub tangent: &'a TangentMap<N>,
}

/// Receives the tangent map of every step of [`Integrator::try_run_tangent`].
///
/// Observers compose as tuples (each sees every step; the run stops when one asks to or
/// fails), switch on and off as `Option`, and pass as `&mut O`.
pub trait TangentObserver<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Called once before the first step with the start time and the initial state (in the
    /// method's coordinates): check the options against the dimension 2N of the phase space
    /// and allocate every buffer here, so that [`TangentObserver::observe`] allocates nothing.
    ///
    /// # Errors
    /// Options that do not fit the run (an [`Error::InvalidParameter`] naming the option):
    /// the run is rejected before its first step.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let _ = (t0, state);
        Ok(())
    }

    /// Whether the state after step number `step` is to be completed to a point (the inverse
    /// Legendre map: it costs a solve for methods in (q, p) on models without a constant mass
    /// matrix). The default: no.
    fn wants_point(&self, step: usize) -> bool {
        let _ = step;
        false
    }

    /// Receive a step and its tangent map; `Break` stops the run (a normal end, not an
    /// error).
    ///
    /// # Errors
    /// What the observer cannot go on from (e.g. deviation vectors that overflowed): the run
    /// fails with it, and with the run up to the state after this step.
    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error>;
}

impl<N: Dimension, O: TangentObserver<N> + ?Sized> TangentObserver<N> for &mut O
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        (**self).begin(t0, state)
    }
    fn wants_point(&self, step: usize) -> bool {
        (**self).wants_point(step)
    }
    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        (**self).observe(step)
    }
}

/// An observer that may be absent: `None` sees nothing and never stops the run.
impl<N: Dimension, O: TangentObserver<N>> TangentObserver<N> for Option<O>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        self.as_mut().map_or(Ok(()), |o| o.begin(t0, state))
    }
    fn wants_point(&self, step: usize) -> bool {
        self.as_ref().is_some_and(|o| o.wants_point(step))
    }
    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.as_mut()
            .map_or(Ok(ControlFlow::Continue(())), |o| o.observe(step))
    }
}

impl<N: Dimension> TangentObserver<N> for ()
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, _: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        Ok(ControlFlow::Continue(()))
    }
}

macro_rules! tuple_tangent_observer {
    ($($name:ident),+) => {
        impl<N: Dimension, $($name: TangentObserver<N>),+> TangentObserver<N> for ($($name,)+)
        where
            DefaultAllocator: Allocator<N> + Allocator<N, N>,
        {
            fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                $($name.begin(t0, state)?;)+
                Ok(())
            }
            fn wants_point(&self, step: usize) -> bool {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                false $(|| $name.wants_point(step))+
            }
            fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                let mut flow = ControlFlow::Continue(());
                $(
                    if $name.observe(step)?.is_break() {
                        flow = ControlFlow::Break(());
                    }
                )+
                Ok(flow)
            }
        }
    };
}

tuple_tangent_observer!(A);
tuple_tangent_observer!(A, B);
tuple_tangent_observer!(A, B, C);
tuple_tangent_observer!(A, B, C, D);
tuple_tangent_observer!(A, B, C, D, E);

/// The error of a failed tangent step `k` at `t`: a method that cannot give its tangent map
/// on this model ([`StepFailure::Unsupported`]) is named; other failures carry the step and
/// time ([`StepFailure::at`]).
fn tangent_failure(method: &str, failure: StepFailure, k: usize, t: f64) -> Error {
    match failure {
        StepFailure::Unsupported { option, reason } => Error::invalid(
            "method",
            format!(
                "{method} has no tangent map here ({option}: {reason}), at step {k} \
                 (t = {t:?})"
            ),
        ),
        other => other.at(k, t),
    }
}

impl<L, M: Step<L, Euclidean<N>>, N: Dimension> Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Integrate from `t0` to `t_end` with fixed steps `h` by the method's exact tangent map,
    /// handing every step's Jacobian to `observer` (see the [module](self) documentation).
    ///
    /// The run's states are those of [`Integrator::try_run`] on the same grid (the same
    /// steps from the same warm workspace, up to what computing the Jacobian changes in a
    /// method's warm start: round-off).
    ///
    /// # Errors
    /// A [`RunFailure`]: inputs rejected before the first step (the grid, the initial state,
    /// the model's declarations, the observer's options in [`TangentObserver::begin`]) with
    /// no partial run; a method whose tangent map is not available on the model as
    /// [`Error::InvalidParameter`] `method`, naming it; a failed step as its typed error with
    /// step index and time (a non-converged solve, a singular matrix, a non-finite state);
    /// an observer's error; each with the run up to the last good state.
    pub fn try_run_tangent<O: TangentObserver<N> + ?Sized>(
        &self,
        t0: f64,
        initial: Initial<N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<Euclidean<N>>, RunFailure<Euclidean<N>>> {
        let steps = grid_steps(t0, t_end, h).map_err(RunFailure::rejected)?;
        let (model, method) = (self.model(), self.method());
        let mut workspace = method.workspace(model, h).map_err(RunFailure::rejected)?;
        let mut progress = self.start(t0, &initial).map_err(RunFailure::rejected)?;
        observer
            .begin(t0, &progress.cursor.state)
            .map_err(RunFailure::rejected)?;
        let name = method.info().name;
        let mut stopped = false;
        for k in 0..steps {
            let (t, size, end) = grid_step(t0, t_end, h, steps, k);
            let state = &progress.cursor.state;
            let (increment, tangent, report) = method
                .tangent_map(model, &mut workspace, t, size, state)
                .map_err(|failure| {
                    self.failure(tangent_failure(name, failure, k, t), &progress, false)
                })?;
            let cursor = &mut progress.cursor;
            cursor
                .state
                .add_checked(&mut cursor.compensation, &increment, None)
                .map_err(|failure| self.failure(failure.at(k, t), &progress, false))?;
            progress.statistics.steps += 1;
            progress.statistics.record(report);
            progress.t = end;
            let point = if observer.wants_point(k + 1) {
                self.complete_progress(&workspace, k + 1, &mut progress)
                    .map_err(|error| self.failure(error, &progress, false))?;
                progress.point.as_ref()
            } else {
                None
            };
            let seen = TangentStep {
                step: k + 1,
                t: end,
                h: size,
                last: k + 1 == steps,
                state: &progress.cursor.state,
                point,
                tangent: &tangent,
            };
            match observer.observe(&seen) {
                Ok(ControlFlow::Continue(())) => {}
                Ok(ControlFlow::Break(())) => {
                    stopped = k + 1 < steps;
                    break;
                }
                Err(error) => return Err(self.failure(error, &progress, false)),
            }
        }
        self.finish(Some(&workspace), progress, stopped)
    }

    /// Complete the current state of `progress` to a point into `progress.point` (reusing
    /// the memory of the last point completed), from what `workspace` (of the run that
    /// reached it) holds where it can; the completed velocity becomes the next Newton start.
    fn complete_progress(
        &self,
        workspace: &M::Workspace,
        step: usize,
        progress: &mut Progress<Euclidean<N>>,
    ) -> Result<(), Error> {
        let (t, state, guess) = (progress.t, &progress.cursor.state, &progress.guess);
        let point = match progress.point.take() {
            Some(mut point) => self
                .complete_into(Some(workspace), step, t, state, guess, &mut point)
                .map(|()| point),
            None => self.complete(Some(workspace), step, t, state, guess),
        }?;
        progress.guess.copy_from(&point.v);
        progress.point = Some(point);
        Ok(())
    }
}
