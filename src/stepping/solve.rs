//! `solve`: states at requested times, dense output, and step- or degree-adaptivity.
//!
//! The calling convention of Porcù & Penati's `[T, Y] = spectralvarint(odefun, tspan, y0,
//! options)`: a model, a [`Span`] (a horizon or a list of output times), an [`crate::Initial`] state
//! and [`SolveOptions`]; the result is the phase point at every output time plus statistics.
//!
//! # Dense output
//! Every step of [`crate::Svi`] and [`crate::SpectralCollocation`] carries its interpolating
//! polynomial ([`crate::Method::dense_output`]); an output time inside a step is read off it, and the
//! step is never shortened to land on an output time (that would break the fixed-step
//! geometry). At interior times p is the Legendre map of the polynomial's (q, q̇). Methods
//! without a step polynomial are interpolated by the cubic Hermite polynomial of the step's
//! end points.
//!
//! # Tolerance
//! `tol` bounds the sum of the local errors over the span: each step is held to
//! tol · (step length) / (span length) (error per unit step). The final error also carries
//! the propagation of those local errors: on Kepler orbits an energy error becomes a phase
//! error that grows linearly in time. Step adaptivity on Kepler e = 0.9 over 318 orbits
//! ends within 0.1–5 × `tol` for tol = 1e-6 … 1e-9 and at the resolution of its error
//! estimate (4e-9) below that ([`super::adapt`]); degree adaptivity was measured at
//! 1–20 × `tol` on e = 0.5 over 318 orbits. [`crate::stepping::reparam`] adapts the physical
//! step with fixed steps in τ instead.
//!
//! # Adaptivity ([`Adapt`])
//! - [`Adapt::None`]: fixed steps t_k = t_0 + k·h, exactly [`crate::Integrator::run`]'s
//!   geometry. Symplectic methods stay symplectic, momenta of symmetries are conserved, and
//!   energy errors stay bounded over exponentially long times (backward error analysis).
//! - [`Adapt::Step`] (step doubling) and [`Adapt::Degree`] (points per step): see
//!   [`super::adapt`].

use crate::error::{Error, require_finite, require_positive};
use crate::method::space::Space;
use crate::method::step::Step;
use crate::stepping::dense::DenseOutput;
use crate::stepping::event::{DEFAULT_EVENT_SAMPLES, Event, EventPoint, EventTracker};
use crate::stepping::grid::{MAX_STEPS, check_span, grid_steps};
use crate::stepping::observer::Observer;
use crate::stepping::outputs::Outputs;
use crate::stepping::run::{Integrator, Progress, Recovery, RunFailure, RunOptions, Statistics};
use std::fmt;
use std::ops::ControlFlow;
use std::str::FromStr;

/// Which adaptivity [`solve`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Adapt {
    /// Fixed step `h`.
    None,
    /// Step-size control by step doubling to meet `tol`.
    #[default]
    Step,
    /// Fixed step `h`; the number of interpolation points per step chosen to meet `tol`.
    Degree,
    /// Symplectic-energy-momentum steps: each step's size fixed by discrete energy
    /// conservation, the first of size `h` ([`super::sem`]; SVI on autonomous models).
    Sem,
}

impl FromStr for Adapt {
    type Err = Error;
    fn from_str(text: &str) -> Result<Self, Error> {
        match text {
            "none" => Ok(Adapt::None),
            "step" => Ok(Adapt::Step),
            "degree" => Ok(Adapt::Degree),
            "sem" => Ok(Adapt::Sem),
            other => Err(Error::invalid(
                "adapt",
                format!("unknown mode {other:?}; use step, degree, sem or none"),
            )),
        }
    }
}

impl fmt::Display for Adapt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Adapt::None => "none",
            Adapt::Step => "step",
            Adapt::Degree => "degree",
            Adapt::Sem => "sem",
        })
    }
}

/// The time span of a solve and the times at which states are returned.
#[derive(Debug, Clone, PartialEq)]
pub struct Span {
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t_end: f64,
    /// Output times, strictly increasing, inside [t0, t_end].
    pub output_times: Vec<f64>,
}

impl Span {
    /// From `t0` to `t_end`, with output at both ends.
    pub fn new(t0: f64, t_end: f64) -> Self {
        Span {
            t0,
            t_end,
            output_times: vec![t0, t_end],
        }
    }

    /// Output at `times`; the span runs from the first to the last.
    pub fn times(times: &[f64]) -> Self {
        Span {
            t0: times.first().copied().unwrap_or(f64::NAN),
            t_end: times.last().copied().unwrap_or(f64::NAN),
            output_times: times.to_vec(),
        }
    }

    /// From `t0` to `t_end`, with output at `output_times`.
    pub fn with_outputs(t0: f64, t_end: f64, output_times: Vec<f64>) -> Self {
        Span {
            t0,
            t_end,
            output_times,
        }
    }

    pub(super) fn validate(&self) -> Result<(), Error> {
        check_span(self.t0, self.t_end)?;
        if self.output_times.is_empty() {
            return Err(Error::invalid("output_times", "no output time given"));
        }
        for (i, &time) in self.output_times.iter().enumerate() {
            require_finite(&format!("output_times[{i}]"), time)?;
            if time < self.t0 || time > self.t_end {
                return Err(Error::invalid(
                    "output_times",
                    format!(
                        "time {time:?} (entry {i}) is outside the span [{:?}, {:?}]",
                        self.t0, self.t_end
                    ),
                ));
            }
            if i > 0 && time <= self.output_times[i - 1] {
                return Err(Error::invalid(
                    "output_times",
                    format!(
                        "times must increase strictly: entry {i} ({time:?}) follows {:?}",
                        self.output_times[i - 1]
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Options of [`solve`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SolveOptions {
    /// Adaptivity mode.
    pub adapt: Adapt,
    /// Step size: required for [`Adapt::None`] and [`Adapt::Degree`]; the first trial step
    /// for [`Adapt::Step`] (chosen from the initial state when `None`).
    pub h: Option<f64>,
    /// Target for the final error (see the module docs); required for the adaptive modes.
    pub tol: Option<f64>,
    /// Smallest step [`Adapt::Step`] may take; default span · 1e-12.
    pub min_step: Option<f64>,
    /// Largest step [`Adapt::Step`] may take; default the span.
    pub max_step: Option<f64>,
    /// Largest factor by which a step may grow (> 1).
    pub max_growth: f64,
    /// Smallest factor by which a step may shrink (in (0, 1)).
    pub max_shrink: f64,
    /// Safety factor on the optimal step (in (0, 1]).
    pub safety: f64,
    /// Fewest interpolation points [`Adapt::Degree`] may use (≥ 2).
    pub min_points: usize,
    /// Most interpolation points [`Adapt::Degree`] may use.
    pub max_points: usize,
    /// Consecutive rejections of one step before the solve gives up.
    pub max_rejections: usize,
    /// Most steps a solve may take (at least 1; default [`MAX_STEPS`], as for fixed grids):
    /// the trial steps of the adaptive modes, accepted or rejected, and the τ-steps of
    /// [`crate::Integrator::try_solve_reparametrized`]. An adaptive solve that reaches it
    /// before the horizon ends in [`Error::TooManySteps`] (with the run so far); a fixed grid
    /// that needs more is rejected before its first step.
    pub max_steps: usize,
    /// Recovery of failed steps ([`Adapt::None`] only: the adaptive modes retry failed trial
    /// steps themselves) and the divergence limit on the state.
    pub run: RunOptions,
    /// Keep every accepted step's polynomial ([`Solution::dense`]), so that the solution can
    /// be evaluated at any time of the span after the solve; on ℝᴺ, not with the
    /// reparametrised solve (default `false`).
    pub dense: bool,
    /// Interior samples of every event function per step, besides the step's end
    /// ([`crate::stepping::event`]): crossings closer together than a step over
    /// `event_samples + 1` may be missed (default 4, at most 1000).
    pub event_samples: usize,
}

impl Default for SolveOptions {
    /// Step adaptivity with `tol` = 1e-8.
    fn default() -> Self {
        SolveOptions {
            adapt: Adapt::Step,
            h: None,
            tol: Some(1e-8),
            min_step: None,
            max_step: None,
            max_growth: 4.0,
            max_shrink: 0.1,
            safety: 0.9,
            min_points: 3,
            max_points: 24,
            max_rejections: 30,
            max_steps: MAX_STEPS,
            run: RunOptions::default(),
            dense: false,
            event_samples: DEFAULT_EVENT_SAMPLES,
        }
    }
}

impl SolveOptions {
    /// Fixed step `h`.
    pub fn fixed_step(h: f64) -> Self {
        SolveOptions {
            adapt: Adapt::None,
            h: Some(h),
            tol: None,
            ..SolveOptions::default()
        }
    }

    /// Step-size adaptivity to meet `tol`.
    pub fn step_adaptive(tol: f64) -> Self {
        SolveOptions {
            tol: Some(tol),
            ..SolveOptions::default()
        }
    }

    /// Symplectic-energy-momentum steps ([`Adapt::Sem`]), the first of size `h`.
    pub fn energy_fitted(h: f64) -> Self {
        SolveOptions {
            adapt: Adapt::Sem,
            h: Some(h),
            tol: None,
            ..SolveOptions::default()
        }
    }

    /// Degree adaptivity with step `h` to meet `tol`, between `min_points` and `max_points`.
    pub fn degree_adaptive(h: f64, tol: f64, min_points: usize, max_points: usize) -> Self {
        SolveOptions {
            adapt: Adapt::Degree,
            h: Some(h),
            tol: Some(tol),
            min_points,
            max_points,
            ..SolveOptions::default()
        }
    }

    fn validate_budget(&self) -> Result<(), Error> {
        if self.max_steps == 0 {
            return Err(Error::invalid("max_steps", "must be at least 1"));
        }
        Ok(())
    }

    /// [`Error::TooManySteps`] when `steps`, the steps taken so far, have used up
    /// `max_steps` (checked before each step whose count is not known in advance).
    pub(super) fn budget(&self, steps: usize, t: f64) -> Result<(), Error> {
        if steps >= self.max_steps {
            return Err(Error::TooManySteps {
                step: steps,
                t,
                max_steps: self.max_steps,
            });
        }
        Ok(())
    }

    pub(super) fn tolerance(&self) -> Result<f64, Error> {
        let tol = self.tol.ok_or_else(|| {
            Error::invalid("tol", format!("adapt = {} needs a tolerance", self.adapt))
        })?;
        require_positive("tol", tol)?;
        if tol < 1e-15 {
            return Err(Error::invalid(
                "tol",
                format!("{tol:e} is below what double precision can deliver (1e-15)"),
            ));
        }
        Ok(tol)
    }

    pub(super) fn step(&self) -> Result<f64, Error> {
        let h = self
            .h
            .ok_or_else(|| Error::invalid("h", format!("adapt = {} needs a step", self.adapt)))?;
        require_positive("h", h)?;
        Ok(h)
    }

    /// The options [`crate::Integrator::try_solve_reparametrized`] reads: the run options,
    /// without recovery (a failed τ-step ends the run), and the step budget.
    pub(super) fn validate_reparametrized(&self) -> Result<(), Error> {
        self.run.validate()?;
        self.validate_budget()?;
        if self.run.recovery != Recovery::None {
            return Err(Error::invalid(
                "recovery",
                "reparam takes fixed steps in τ and has no recovery of failed steps",
            ));
        }
        if self.dense {
            return Err(Error::invalid(
                "dense",
                "the reparametrised solve keeps no step polynomials: ask for output times",
            ));
        }
        Ok(())
    }

    fn validate(&self) -> Result<(), Error> {
        if !(self.max_growth.is_finite() && self.max_growth > 1.0) {
            return Err(Error::invalid(
                "max_growth",
                format!("{:?} must be a finite number above 1", self.max_growth),
            ));
        }
        if !(self.max_shrink > 0.0 && self.max_shrink < 1.0) {
            return Err(Error::invalid(
                "max_shrink",
                format!("{:?} must lie in (0, 1)", self.max_shrink),
            ));
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return Err(Error::invalid(
                "safety",
                format!("{:?} must lie in (0, 1]", self.safety),
            ));
        }
        if self.max_rejections == 0 {
            return Err(Error::invalid("max_rejections", "must be at least 1"));
        }
        if self.event_samples > MAX_EVENT_SAMPLES {
            return Err(Error::invalid(
                "event_samples",
                format!(
                    "{} is more than {MAX_EVENT_SAMPLES} samples per step",
                    self.event_samples
                ),
            ));
        }
        self.validate_budget()?;
        if let Some(h) = self.min_step {
            require_positive("min_step", h)?;
        }
        if let Some(h) = self.max_step {
            require_positive("max_step", h)?;
        }
        self.run.validate()?;
        if self.adapt != Adapt::None && self.run.recovery != Recovery::None {
            return Err(Error::invalid(
                "recovery",
                format!(
                    "adapt = {} retries failed steps itself; recovery applies to fixed steps \
                     (adapt = none)",
                    self.adapt
                ),
            ));
        }
        Ok(())
    }
}

/// Most interior samples of an event function per step ([`SolveOptions::event_samples`]).
pub const MAX_EVENT_SAMPLES: usize = 1000;

/// What the adaptive modes did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Adaptivity {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected trial steps (the work they cost is in [`Statistics`]).
    pub rejected: usize,
    /// Smallest accepted step.
    pub min_step: f64,
    /// Largest accepted step.
    pub max_step: f64,
    /// (points, accepted steps that used them), by increasing points.
    pub points: Vec<(usize, usize)>,
    /// Steps of [`Adapt::Degree`] that missed the tolerance even with `max_points`, steps
    /// of [`Adapt::Step`] accepted at the resolution of the error estimate (a tolerance per
    /// step below what the estimate can tell; see [`super::adapt`]), and steps of
    /// [`Adapt::Sem`] whose energy equation had no root (the fallback that minimises the
    /// energy error; see [`super::sem`]).
    pub unmet: usize,
}

impl Adaptivity {
    pub(super) fn record(&mut self, h: f64, points: Option<usize>) {
        if self.accepted == 0 {
            self.min_step = h;
            self.max_step = h;
        }
        self.accepted += 1;
        self.min_step = self.min_step.min(h);
        self.max_step = self.max_step.max(h);
        if let Some(points) = points {
            match self.points.binary_search_by_key(&points, |&(p, _)| p) {
                Ok(i) => self.points[i].1 += 1,
                Err(i) => self.points.insert(i, (points, 1)),
            }
        }
    }
}

/// The result of [`solve`] on the space `S` (on ℝᴺ: [`crate::Solution`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Solution<S: Space> {
    /// The point at each output time, in order.
    pub points: Vec<S::Point>,
    /// The point at the end of the span (whether or not it is an output time), or where an
    /// observer stopped the solve.
    pub last: S::Point,
    /// Work done, including rejected trial steps; `steps` counts the method steps taken.
    pub statistics: Statistics,
    /// What the adaptivity did (step sizes, points used, rejections).
    pub adaptivity: Adaptivity,
    /// Whether an observer stopped the solve before the end of the span.
    pub stopped: bool,
    /// Every accepted step's polynomial, with [`SolveOptions::dense`]
    /// ([`DenseOutput::at`] evaluates the solution at any time of the span).
    pub dense: Option<DenseOutput>,
    /// The located events ([`Integrator::try_solve_events`]), in time order.
    pub events: Vec<EventPoint<S::Point>>,
    /// The index in `events` of the terminal event that ended the solve (`last` is its
    /// point), if one did.
    pub terminal: Option<usize>,
}

/// Solve from `initial` over `span` with `method`: the states at the span's output times.
///
/// ```
/// use nalgebra::{SVector, U1};
/// use svi::solve::{Span, SolveOptions, solve};
/// use svi::{Initial, Lagrangian, Scalar, Svi};
///
/// /// Harmonic oscillator L = q̇²/2 − q²/2.
/// struct Oscillator;
/// impl Lagrangian<U1> for Oscillator {
///     const TIME_DEPENDENT: bool = false;
///     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
///         (v[0] * v[0] - q[0] * q[0]) * 0.5
///     }
/// }
///
/// let initial = Initial::Velocity { q: SVector::from([1.0]), v: SVector::from([0.0]) };
/// let span = Span::times(&[0.0, 0.25, 0.5, 1.0]);
/// let solution = solve(Oscillator, Svi::new(5), &span, initial, &SolveOptions::default())?;
/// for point in &solution.points {
///     assert!((point.q[0] - point.t.cos()).abs() < 1e-7);
/// }
/// # Ok::<(), svi::Error>(())
/// ```
pub fn solve<L, M: Step<L, S> + Clone, S: Space>(
    model: L,
    method: M,
    span: &Span,
    initial: S::Initial,
    options: &SolveOptions,
) -> Result<Solution<S>, Error> {
    Integrator::new(model, method).solve(span, initial, options)
}

impl<L, M: Step<L, S> + Clone, S: Space> Integrator<L, M, S> {
    /// [`solve`] with this integrator's model and method.
    pub fn solve(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
    ) -> Result<Solution<S>, Error> {
        self.try_solve(span, initial, options, &mut ())
            .map_err(|failure| failure.error)
    }

    /// [`solve`] reporting every accepted step to `observer` (as [`Integrator::try_run`]
    /// does, with the accepted steps counted from 1); a failure comes back with the run up to
    /// the last good state, and the observer keeps what it saw.
    pub fn try_solve<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
        observer: &mut O,
    ) -> Result<Solution<S>, RunFailure<S>> {
        self.try_solve_events(span, initial, options, &[], observer)
    }

    /// [`Integrator::try_solve`] locating `events` on every accepted step
    /// ([`crate::stepping::event`]): they come back in [`Solution::events`], and the first
    /// crossing of a terminal one ends the solve at its time ([`Solution::terminal`]).
    ///
    /// # Errors
    /// Those of [`Integrator::try_solve`]; [`Error::NonFinite`] naming an event whose value
    /// is not finite; [`Error::InvalidParameter`] (`events`) for a method with neither a
    /// step polynomial nor an interpolant on its space.
    pub fn try_solve_events<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
        events: &[Event<'_>],
        observer: &mut O,
    ) -> Result<Solution<S>, RunFailure<S>> {
        let mut observer: &mut dyn Observer<L, S::Point> = observer;
        self.solve_observed(span, initial, options, events, &mut observer)
    }

    /// [`Integrator::try_solve`] with the observer behind a trait object, so that the
    /// drivers (fixed, step- and degree-adaptive, energy-fitted) are compiled once per model
    /// and method whatever observers the callers use: a call per accepted step, next to a
    /// step's nonlinear solve.
    fn solve_observed(
        &self,
        span: &Span,
        initial: S::Initial,
        options: &SolveOptions,
        events: &[Event<'_>],
        observer: &mut &mut dyn Observer<L, S::Point>,
    ) -> Result<Solution<S>, RunFailure<S>> {
        span.validate().map_err(RunFailure::rejected)?;
        options.validate().map_err(RunFailure::rejected)?;
        let mut progress = self
            .start(span.t0, &initial)
            .map_err(RunFailure::rejected)?;
        let mut outputs = Outputs::new(&span.output_times, progress.guess.clone());
        if !events.is_empty() {
            let first = self
                .phase_point(span.t0, &progress.cursor.state, &outputs.guess)
                .map_err(RunFailure::rejected)?;
            let (q, v, _) = S::point_vectors(&first).ok_or_else(|| {
                RunFailure::rejected(Error::invalid("events", "events are located on ℝᴺ only"))
            })?;
            let tracker = EventTracker::new(events, options.event_samples, (span.t0, q, v))
                .map_err(RunFailure::rejected)?;
            outputs.events = Some(tracker);
        }
        if options.dense {
            let samples = match options.adapt {
                Adapt::Degree => options.max_points,
                _ => self.method().points().unwrap_or(0),
            };
            let first = self
                .phase_point(span.t0, &progress.cursor.state, &outputs.guess)
                .map_err(RunFailure::rejected)?;
            let Some((q, ..)) = S::point_vectors(&first) else {
                return Err(RunFailure::rejected(Error::invalid(
                    "dense",
                    "dense output is kept on ℝᴺ only: ask for output times",
                )));
            };
            let mut dense = DenseOutput::new(q.len(), samples);
            // Fixed steps: their count is known, the buffers are sized once.
            if let (Adapt::None, Some(h)) = (options.adapt, options.h) {
                dense.reserve(grid_steps(span.t0, span.t_end, h).unwrap_or(0));
            }
            outputs.dense = Some(dense);
        }
        if outputs.next() == Some(span.t0) {
            let point = self
                .phase_point(span.t0, &progress.cursor.state, &outputs.guess)
                .map_err(RunFailure::rejected)?;
            outputs.guess = S::velocity(&point);
            outputs.points.push(point);
        }
        let driven = match options.adapt {
            Adapt::None => self.solve_fixed(span, options, &mut progress, &mut outputs, observer),
            Adapt::Step => {
                self.solve_step_adaptive(span, options, &mut progress, &mut outputs, observer)
            }
            Adapt::Degree => {
                self.solve_degree_adaptive(span, options, &mut progress, &mut outputs, observer)
            }
            Adapt::Sem => self.solve_sem(span, options, &mut progress, &mut outputs, observer),
        };
        // A failed solve keeps the events it located.
        let (adaptivity, stopped) = driven.map_err(|failure| RunFailure {
            events: std::mem::take(&mut outputs.located).into_boxed_slice(),
            ..failure
        })?;
        // The end point as `try_run` completes it (from the velocity last observed).
        let run = self.finish(None, progress, stopped)?;
        let last = match outputs.terminal {
            Some(k) => outputs.located[k].point.clone(),
            None => run.last,
        };
        Ok(Solution {
            points: outputs.points,
            last,
            statistics: run.statistics,
            adaptivity,
            stopped: stopped && outputs.terminal.is_none(),
            dense: outputs.dense,
            events: outputs.located,
            terminal: outputs.terminal,
        })
    }

    /// Fixed steps: the grid loop of [`Integrator::try_run`] (recovery, divergence limit,
    /// observers), serving the output times after each step.
    fn solve_fixed<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        options: &SolveOptions,
        progress: &mut Progress<S>,
        outputs: &mut Outputs<'_, S>,
        observer: &mut O,
    ) -> Result<(Adaptivity, bool), RunFailure<S>> {
        let h = options.step().map_err(RunFailure::rejected)?;
        let steps = grid_steps(span.t0, span.t_end, h).map_err(RunFailure::rejected)?;
        if steps > options.max_steps {
            return Err(RunFailure::rejected(Error::invalid(
                "max_steps",
                format!(
                    "the span needs {steps} steps of h = {h:e}, more than max_steps = {}",
                    options.max_steps
                ),
            )));
        }
        let mut workspace = self
            .method()
            .workspace(self.model(), h)
            .map_err(RunFailure::rejected)?;
        let mut adaptivity = Adaptivity::default();
        let points = self.method().points();
        let stopped = self.run_grid(
            &mut workspace,
            progress,
            (span.t0, span.t_end, h, steps),
            &options.run,
            observer,
            // The start of a step is read only to serve output times inside it, or to keep
            // its polynomial.
            outputs.wants_steps(),
            |workspace, t, size, start, progress| {
                if let Some(start) = start {
                    self.emit(
                        self.method(),
                        workspace,
                        outputs,
                        progress.statistics.steps,
                        t,
                        size,
                        start,
                        &progress.cursor.state,
                        progress.t,
                    )?;
                }
                adaptivity.record(size, points);
                Ok(if outputs.terminal.is_some() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                })
            },
        )?;
        Ok((adaptivity, stopped))
    }
}
