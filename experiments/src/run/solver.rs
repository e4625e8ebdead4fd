//! How a run solves: the one loop of [`Integrator::try_solve`], or fixed steps in
//! computational time τ ([`InTau`], `adapt = "reparam"`), behind one trait object.

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::Dimension;
use svi::method::space::Space;
use svi::method::step::Step;
use svi::model::reparametrized::MonitorSpec;
use svi::observer::Observer;
use svi::solve::{Solution, SolveOptions, Span};
use svi::stepping::event::Event;
use svi::stepping::run::RunFailure;
use svi::{Integrator, Method};

use crate::report::chaos::IndicatorSummary;

/// How [`run_scene`](super::run_scene) solves: the one loop ([`Integrator::try_solve`]), or
/// fixed steps in computational time ([`InTau`]). A trait object, so that
/// [`run_scene`](super::run_scene) is compiled once per model and space, not once per method as
/// well.
pub(super) trait Solver<L, S: Space> {
    /// Solve over `span` from `initial`, locating `events`, reporting the accepted steps to
    /// `observer`.
    fn solve(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
        events: &[Event<'_>],
        observer: &mut dyn Observer<L, S::Point>,
    ) -> Result<Solution<S>, RunFailure<S>>;

    /// The model.
    fn model(&self) -> &L;

    /// The phase point of `initial` at `t0` (`guess`: the start of an inverse Legendre map).
    fn first_point(
        &self,
        t0: f64,
        initial: &S::Initial,
        guess: &S::Velocity,
    ) -> Result<S::Point, svi::Error>;

    /// The method's name, order and properties.
    fn info(&self) -> svi::MethodInfo;

    /// The chaos indicators of the last solve, for a solver that computes them.
    fn indicators(&self) -> Option<IndicatorSummary> {
        None
    }
}

impl<L, M: Step<L, S> + Clone, S: Space> Solver<L, S> for Integrator<L, M, S> {
    fn solve(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
        events: &[Event<'_>],
        mut observer: &mut dyn Observer<L, S::Point>,
    ) -> Result<Solution<S>, RunFailure<S>> {
        self.try_solve_events(span, initial, options, events, &mut observer)
    }

    fn model(&self) -> &L {
        Integrator::model(self)
    }

    fn first_point(
        &self,
        t0: f64,
        initial: &S::Initial,
        guess: &S::Velocity,
    ) -> Result<S::Point, svi::Error> {
        let first = self.initial_state(t0, initial)?;
        self.phase_point(t0, &first, guess)
    }

    fn info(&self) -> svi::MethodInfo {
        self.method().info()
    }
}

/// `adapt = "reparam"`: the integrator on ℝᴺ in computational time τ with its monitor
/// ([`Integrator::try_solve_reparametrized`]).
pub(super) struct InTau<'a, L, M, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    pub(super) integrator: &'a Integrator<L, M, svi::Euclidean<N>>,
    pub(super) monitor: MonitorSpec,
}

impl<L: svi::Lagrangian<N>, M: Method<N> + Clone, N: Dimension> Solver<L, svi::Euclidean<N>>
    for InTau<'_, L, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn solve(
        &self,
        span: &Span,
        initial: svi::Initial<N>,
        options: &SolveOptions,
        events: &[Event<'_>],
        mut observer: &mut dyn Observer<L, svi::PhasePoint<N>>,
    ) -> Result<Solution<svi::Euclidean<N>>, RunFailure<svi::Euclidean<N>>> {
        // The scene's checks refuse events with steps in τ.
        if !events.is_empty() {
            return Err(RunFailure::rejected(svi::Error::invalid(
                "events",
                "events are not located in fixed steps of τ (adapt = reparam)",
            )));
        }
        self.integrator.try_solve_reparametrized(
            &self.monitor,
            span,
            initial,
            options,
            &mut observer,
        )
    }

    fn model(&self) -> &L {
        self.integrator.model()
    }

    fn first_point(
        &self,
        t0: f64,
        initial: &svi::Initial<N>,
        guess: &nalgebra::OVector<f64, N>,
    ) -> Result<svi::PhasePoint<N>, svi::Error> {
        Solver::first_point(self.integrator, t0, initial, guess)
    }

    fn info(&self) -> svi::MethodInfo {
        Solver::info(self.integrator)
    }
}
