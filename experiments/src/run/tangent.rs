//! Runs with chaos indicators (`--indicators`): the fixed-step tangent run of the library
//! ([`Integrator::try_run_tangent`]) behind the same [`Solver`] as every run, so the scene's
//! diagnostics, trajectory, progress and stop flag observe it as they observe a plain run
//! (their points completed at the steps they want), and the indicators come back for the
//! summary.

use std::cell::RefCell;
use std::ops::ControlFlow;

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::analysis::chaos::{
    Gali, GaliOptions, LyapunovSpectrum, MaximalLyapunov, MaximalOptions, Megno, MegnoOptions,
    Sali, SaliOptions, SpectrumOptions,
};
use svi::method::space::{Initial, Space, State};
use svi::observer::Observer;
use svi::solve::{Adaptivity, Solution, SolveOptions, Span};
use svi::stepping::event::Event;
use svi::stepping::run::RunFailure;
use svi::stepping::tangent::{TangentObserver, TangentStep};
use svi::{Dimension, Error, Euclidean, Integrator, Method, PhasePoint};

use crate::report::chaos::IndicatorSummary;
use crate::run::solver::Solver;
use crate::scene::schema::Indicator;

/// The indicators of one run, each present when asked for: one tangent observer.
type Indicators = (
    Option<Megno>,
    Option<MaximalLyapunov>,
    Option<LyapunovSpectrum>,
    Option<Sali>,
    Option<Gali>,
);

/// The indicators `asked` for, with their default options, for a model of `n` coordinates
/// (GALI of order n).
fn indicators(asked: &[Indicator], n: usize) -> Result<Indicators, Error> {
    let wants = |indicator| asked.contains(&indicator);
    Ok((
        wants(Indicator::Megno)
            .then(|| Megno::new(MegnoOptions::default()))
            .transpose()?,
        wants(Indicator::Lyapunov)
            .then(|| MaximalLyapunov::new(MaximalOptions::default()))
            .transpose()?,
        wants(Indicator::Spectrum)
            .then(|| LyapunovSpectrum::new(SpectrumOptions::default()))
            .transpose()?,
        wants(Indicator::Sali)
            .then(|| Sali::new(SaliOptions::default()))
            .transpose()?,
        wants(Indicator::Gali)
            .then(|| Gali::new(GaliOptions::default().with_k(n)))
            .transpose()?,
    ))
}

/// What the indicators found, for the summary.
fn summary((megno, lyapunov, spectrum, sali, gali): &Indicators) -> IndicatorSummary {
    IndicatorSummary {
        megno: megno.as_ref().map(Megno::mean),
        lyapunov_max: lyapunov.as_ref().map(MaximalLyapunov::exponent),
        lyapunov: spectrum.as_ref().map(|s| s.exponents().to_vec()),
        sali: sali.as_ref().map(Sali::value),
        gali: gali.as_ref().map(Gali::value),
    }
}

/// The indicators and the run's point observers, as one observer of the tangent run.
struct Observed<'a, L, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    indicators: &'a mut Indicators,
    model: &'a L,
    points: &'a mut dyn Observer<L, PhasePoint<N>>,
}

impl<L, N: Dimension> TangentObserver<N> for Observed<'_, L, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        self.indicators.begin(t0, state)
    }

    fn wants_point(&self, step: usize) -> bool {
        self.points.wants(step)
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        let mut flow = self.indicators.observe(step)?;
        if let Some(point) = step.point
            && self.points.observe(self.model, step.step, point).is_break()
        {
            flow = ControlFlow::Break(());
        }
        Ok(flow)
    }
}

/// A fixed-step run of `integrator` by its tangent maps, with the `indicators` asked for.
pub(super) struct TangentRun<'a, L, M, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    pub(super) integrator: &'a Integrator<L, M, Euclidean<N>>,
    pub(super) asked: Vec<Indicator>,
    pub(super) h: f64,
    pub(super) found: RefCell<Option<IndicatorSummary>>,
}

impl<L: svi::Lagrangian<N>, M: Method<N> + Clone, N: Dimension> Solver<L, Euclidean<N>>
    for TangentRun<'_, L, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn solve(
        &self,
        span: &Span,
        initial: Initial<N>,
        _options: &SolveOptions,
        events: &[Event<'_>],
        observer: &mut dyn Observer<L, PhasePoint<N>>,
    ) -> Result<Solution<Euclidean<N>>, RunFailure<Euclidean<N>>> {
        let rejected = RunFailure::rejected;
        // The scene's checks refuse events and output times with indicators.
        if !events.is_empty() {
            return Err(rejected(Error::invalid(
                "events",
                "a tangent run locates none",
            )));
        }
        let model = self.integrator.model();
        let n = initial.position().len();
        let mut indicators = indicators(&self.asked, n).map_err(rejected)?;
        if observer.wants(0) {
            let first = Solver::first_point(
                self,
                span.t0,
                &initial,
                &Euclidean::<N>::initial_guess(&initial),
            )
            .map_err(rejected)?;
            if observer.observe(model, 0, &first).is_break() {
                return Err(rejected(Error::invalid(
                    "stop",
                    "stopped before the first step",
                )));
            }
        }
        let mut observed = Observed {
            indicators: &mut indicators,
            model,
            points: observer,
        };
        let run =
            self.integrator
                .try_run_tangent(span.t0, initial, self.h, span.t_end, &mut observed)?;
        *self.found.borrow_mut() = Some(summary(&indicators));
        Ok(Solution {
            points: Vec::new(),
            last: run.last,
            statistics: run.statistics,
            adaptivity: Adaptivity::default(),
            stopped: run.stopped,
            dense: None,
            events: Vec::new(),
            terminal: None,
        })
    }

    fn model(&self) -> &L {
        self.integrator.model()
    }

    fn first_point(
        &self,
        t0: f64,
        initial: &Initial<N>,
        guess: &nalgebra::OVector<f64, N>,
    ) -> Result<PhasePoint<N>, Error> {
        Solver::first_point(self.integrator, t0, initial, guess)
    }

    fn info(&self) -> svi::MethodInfo {
        Solver::info(self.integrator)
    }

    fn indicators(&self) -> Option<IndicatorSummary> {
        self.found.borrow().clone()
    }
}
