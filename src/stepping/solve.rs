//! `solve`: states at requested times, dense output, and step- or degree-adaptivity.
//!
//! The calling convention of Porcù & Penati's `[T, Y] = spectralvarint(odefun, tspan, y0,
//! options)`: a model, a [`Span`] (a horizon or a list of output times), an [`Initial`] state
//! and [`SolveOptions`]; the result is the phase point at every output time plus statistics.
//!
//! # Dense output
//! Every step of [`crate::Svi`] and [`crate::SpectralCollocation`] carries its interpolating
//! polynomial ([`Method::dense_output`]); an output time inside a step is read off it, and the
//! step is never shortened to land on an output time (that would break the fixed-step
//! geometry). At interior times p is the Legendre map of the polynomial's (q, q̇). Methods
//! without a step polynomial are interpolated by the cubic Hermite polynomial of the step's
//! end points.
//!
//! # Tolerance
//! `tol` bounds the sum of the local errors over the span: each step is held to
//! tol · (step length) / (span length) (error per unit step). The final error also carries
//! the propagation of those local errors: on Kepler orbits an energy error becomes a phase
//! error that grows linearly in time, so after a few close approaches (e = 0.9) the final
//! position error was measured at 1–300 × `tol` with step adaptivity, and at 1–20 × `tol`
//! with degree adaptivity on e = 0.5 over 318 orbits.
//!
//! # Adaptivity ([`Adapt`])
//! - [`Adapt::None`]: fixed steps t_k = t_0 + k·h, exactly [`crate::Integrator::run`]'s
//!   geometry. Symplectic methods stay symplectic, momenta of symmetries are conserved, and
//!   energy errors stay bounded over exponentially long times (backward error analysis).
//! - [`Adapt::Step`]: step doubling as in Porcù & Penati's slides. From (t, y) the method takes
//!   two steps of h (result X2) and one of 2h (result W); with r the order,
//!   h_opt = h (2(2^r + 1) tol_step / ‖W − X2‖)^(1/(r+1)). The step is accepted (keeping the
//!   more accurate X2) when h_opt ≥ h, and retried with h_opt otherwise; the next h is
//!   safety · h_opt, with growth and shrink bounded, and a step below the minimum ends in
//!   [`Error::StepSizeTooSmall`]. Each accepted step is still a composition of symplectic
//!   maps and conserves the Noether momenta exactly, but the step size depends on the state,
//!   so the map over many steps is not symplectic and the energy error may drift.
//! - [`Adapt::Degree`]: fixed h, and the number of CGL points of each step chosen between
//!   `min_points` and `max_points` from the decay of the step polynomial's Chebyshev
//!   coefficients a_k (max over components). With the tail a_s and its decay rate ρ per
//!   degree, the local error of s' + 1 points is estimated as a_s ρ^(s' − s + (r − s')/2)
//!   for a method of order r (r = 2s' for SVI, whose end points are superconvergent, so the
//!   end-point error falls faster than the polynomial's tail; r ≈ s' for SC).
//!   A step whose estimate exceeds tol_step is retried with more points; the next step's
//!   points are chosen ahead from the trend of the estimates (raised before the tolerance
//!   is missed, lowered by at most one per step and only with a margin). Every step is
//!   a symplectic map with its own degree, momenta of symmetries are conserved exactly, the
//!   time grid is fixed; the composition of different symplectic maps is symplectic, but
//!   the choice of map depends on the state, so there is no modified Hamiltonian and no
//!   bounded-energy guarantee.

use crate::error::{Error, require_finite, require_positive};
use crate::method::space::{Space, StepState};
use crate::method::step::Step;
use crate::spectral::MAX_POINTS;
use crate::stepping::grid::{check_span, grid_step, grid_steps, resolution};
use crate::stepping::observer::Observer;
use crate::stepping::run::{
    Cursor, Integrator, Progress, Recovery, RunFailure, RunOptions, Statistics,
};
use std::fmt;
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
}

impl FromStr for Adapt {
    type Err = Error;
    fn from_str(text: &str) -> Result<Self, Error> {
        match text {
            "none" => Ok(Adapt::None),
            "step" => Ok(Adapt::Step),
            "degree" => Ok(Adapt::Degree),
            other => Err(Error::invalid(
                "adapt",
                format!("unknown mode {other:?}; use step, degree or none"),
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

    fn validate(&self) -> Result<(), Error> {
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
    /// Recovery of failed steps ([`Adapt::None`] only: the adaptive modes retry failed trial
    /// steps themselves) and the divergence limit on the state.
    pub run: RunOptions,
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
            run: RunOptions::default(),
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

    fn tolerance(&self) -> Result<f64, Error> {
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

    fn step(&self) -> Result<f64, Error> {
        let h = self
            .h
            .ok_or_else(|| Error::invalid("h", format!("adapt = {} needs a step", self.adapt)))?;
        require_positive("h", h)?;
        Ok(h)
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
    /// Steps of [`Adapt::Degree`] that missed the tolerance even with `max_points`.
    pub unmet: usize,
}

impl Adaptivity {
    fn record(&mut self, h: f64, points: Option<usize>) {
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
}

/// Solve from `initial` over `span` with `method`: the states at the span's output times.
///
/// ```
/// use nalgebra::SVector;
/// use svi::solve::{Span, SolveOptions, solve};
/// use svi::{Initial, Lagrangian, Scalar, Svi};
///
/// /// Harmonic oscillator L = q̇²/2 − q²/2.
/// struct Oscillator;
/// impl Lagrangian<1> for Oscillator {
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

/// Output times not yet served, and the points produced so far.
struct Outputs<'a, S: Space> {
    times: &'a [f64],
    points: Vec<S::Point>,
    /// Last velocity, the Newton start of the next inverse Legendre map.
    guess: S::Velocity,
}

impl<S: Space> Outputs<'_, S> {
    fn next(&self) -> Option<f64> {
        self.times.get(self.points.len()).copied()
    }
}

/// Chebyshev coefficient magnitudes a_k = max over components |c_k| (k = 0..s) of the
/// polynomial through the CGL node values (offsets, `width` numbers per node: node 0 is zero).
fn chebyshev_magnitudes(offsets: &[f64], width: usize, out: &mut [f64]) {
    let s = offsets.len() / width;
    for (k, a) in out.iter_mut().enumerate().take(s + 1) {
        let scale = if k == 0 || k == s { 1.0 } else { 2.0 } / s as f64;
        *a = 0.0;
        for component in 0..width {
            let mut c = 0.0;
            for (nu, node) in offsets.chunks_exact(width).enumerate() {
                let nu = nu + 1;
                // x_ν = −cos(νπ/s), so T_k(x_ν) = (−1)^k cos(kνπ/s).
                let weight = if nu == s { 0.5 } else { 1.0 };
                let angle = std::f64::consts::PI * ((k * nu) % (2 * s)) as f64 / s as f64;
                let tk = if k % 2 == 0 {
                    angle.cos()
                } else {
                    -angle.cos()
                };
                c += weight * tk * node[component];
            }
            *a = a.max((c * scale).abs());
        }
    }
}

/// The local-error model of degree adaptivity, from the Chebyshev magnitudes a_0..a_s of the
/// step polynomial: the tail a_s and its decay rate per degree ρ = max(a_s/a_{s−1},
/// √(a_s/a_{s−2})) (the square root covers problems whose odd or even coefficients vanish).
fn decay(magnitudes: &[f64]) -> (f64, f64) {
    let s = magnitudes.len() - 1;
    let floor = f64::EPSILON * magnitudes[1].max(f64::MIN_POSITIVE);
    let tail = magnitudes[s].max(floor);
    let mut rho = tail / magnitudes[s - 1].max(floor);
    if s >= 3 {
        rho = rho.max((tail / magnitudes[s - 2].max(floor)).sqrt());
    }
    (tail, rho.min(1.0))
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
        span.validate().map_err(RunFailure::rejected)?;
        options.validate().map_err(RunFailure::rejected)?;
        let mut progress = self
            .start(span.t0, &initial)
            .map_err(RunFailure::rejected)?;
        let mut outputs = Outputs {
            times: &span.output_times,
            points: Vec::with_capacity(span.output_times.len()),
            guess: progress.guess,
        };
        if outputs.next() == Some(span.t0) {
            let point = self
                .phase_point(span.t0, &progress.cursor.state, &outputs.guess)
                .map_err(RunFailure::rejected)?;
            outputs.guess = S::velocity(&point);
            outputs.points.push(point);
        }
        let (adaptivity, stopped) = match options.adapt {
            Adapt::None => self.solve_fixed(span, options, &mut progress, &mut outputs, observer),
            Adapt::Step => {
                self.solve_step_adaptive(span, options, &mut progress, &mut outputs, observer)
            }
            Adapt::Degree => {
                self.solve_degree_adaptive(span, options, &mut progress, &mut outputs, observer)
            }
        }?;
        // The end point as `try_run` completes it (from the velocity last observed).
        let run = self.finish(progress, stopped)?;
        Ok(Solution {
            points: outputs.points,
            last: run.last,
            statistics: run.statistics,
            adaptivity,
            stopped,
        })
    }

    /// Serve every output time in (t, t + h] from the step of `method` just taken from
    /// `start` at `t` to `end` at `end_time`: at `end_time` itself the completed end point,
    /// inside the step the method's dense output or, without one, the space's interpolant of
    /// the completed end points.
    #[allow(clippy::too_many_arguments)]
    fn emit(
        &self,
        method: &M,
        workspace: &M::Workspace,
        outputs: &mut Outputs<'_, S>,
        t: f64,
        h: f64,
        start: &S::State,
        end: &S::State,
        end_time: f64,
    ) -> Result<(), Error> {
        let model = self.model();
        let mut ends: Option<(S::Point, S::Point)> = None;
        while let Some(time) = outputs.next() {
            if time > end_time {
                break;
            }
            let point = if time == end_time {
                self.phase_point(end_time, end, &outputs.guess)?
            } else if let Some(point) = method.dense_point(model, workspace, t, h, start, time) {
                point
            } else {
                let (a, b) = match ends {
                    Some(known) => known,
                    None => {
                        let known = (
                            self.phase_point(t, start, &outputs.guess)?,
                            self.phase_point(end_time, end, &outputs.guess)?,
                        );
                        ends = Some(known);
                        known
                    }
                };
                method.interpolate(model, &a, &b, time).ok_or_else(|| {
                    Error::invalid(
                        "output_times",
                        format!(
                            "{time:?} lies inside a step, and {} has neither dense output nor an \
                             interpolant on its space: ask for output at the ends of the span",
                            method.info().name
                        ),
                    )
                })?
            };
            outputs.guess = S::velocity(&point);
            outputs.points.push(point);
        }
        Ok(())
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
            |workspace, t, size, start, progress| {
                self.emit(
                    self.method(),
                    workspace,
                    outputs,
                    t,
                    size,
                    start,
                    &progress.cursor.state,
                    progress.t,
                )?;
                adaptivity.record(size, points);
                Ok(())
            },
        )?;
        Ok((adaptivity, stopped))
    }

    /// One trial step of an adaptive mode from `from` at `t` with size `h` (counted in
    /// `statistics.steps`), with the step's index and time attached to a failure.
    #[allow(clippy::too_many_arguments)]
    fn trial(
        &self,
        method: &M,
        workspace: &mut M::Workspace,
        increment: &mut S::State,
        t: f64,
        h: f64,
        from: &Cursor<S>,
        divergence_limit: Option<f64>,
        statistics: &mut Statistics,
    ) -> Result<Cursor<S>, Error> {
        let index = statistics.steps;
        let next = self
            .attempt(
                method,
                workspace,
                increment,
                t,
                h,
                from,
                divergence_limit,
                statistics,
            )
            .map_err(|failure| failure.at(index, t))?;
        statistics.steps += 1;
        Ok(next)
    }

    /// Step doubling (see the module docs): two steps of h against one of 2h, accepted when
    /// the optimal step is not smaller; observers see the points of the accepted steps.
    fn solve_step_adaptive<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        options: &SolveOptions,
        progress: &mut Progress<S>,
        outputs: &mut Outputs<'_, S>,
        observer: &mut O,
    ) -> Result<(Adaptivity, bool), RunFailure<S>> {
        let rejected = RunFailure::rejected;
        let tol = options.tolerance().map_err(rejected)?;
        let length = span.t_end - span.t0;
        let finest = resolution(span.t0, span.t_end);
        let min_step = match options.min_step {
            Some(min_step) if min_step < finest => {
                return Err(rejected(Error::invalid(
                    "min_step",
                    format!(
                        "{min_step:e} is below the finest step {finest:e} whose times floating \
                         point can tell apart near the span"
                    ),
                )));
            }
            Some(min_step) => min_step,
            None => (length * 1e-12).max(finest),
        };
        let max_step = options.max_step.unwrap_or(length).min(length);
        if min_step > max_step {
            return Err(rejected(Error::invalid(
                "min_step",
                format!(
                    "{min_step:e} is above the largest step {max_step:e} (max_step, or the span)"
                ),
            )));
        }
        let method = self.method();
        let order = method.info().order as i32;
        let numerator = 2.0 * (2f64.powi(order) + 1.0);
        let exponent = 1.0 / (f64::from(order) + 1.0);
        let mut h = match options.h {
            Some(h) => {
                require_positive("h", h).map_err(rejected)?;
                h
            }
            None => {
                let point = self
                    .phase_point(span.t0, &progress.cursor.state, &outputs.guess)
                    .map_err(rejected)?;
                let (size, speed) = S::size_and_speed(&point);
                0.01 * size.max(1e-3) / speed.max(1e-12)
            }
        }
        .clamp(min_step, max_step);
        let points = method.points();
        let limit = options.run.divergence_limit;
        let mut half = method.workspace(self.model(), h).map_err(rejected)?;
        let mut full = method.workspace(self.model(), 2.0 * h).map_err(rejected)?;
        let mut increment = S::State::zeros();
        let mut adaptivity = Adaptivity::default();
        let mut rejections = 0;
        if observer.wants(0) && self.observe(0, progress, observer)? {
            return Ok((adaptivity, true));
        }
        while progress.t < span.t_end {
            let t = progress.t;
            let remaining = span.t_end - t;
            let last = 2.0 * h >= remaining * (1.0 - 1e-12);
            let end = if last { span.t_end } else { t + 2.0 * h };
            let dt = if last { 0.5 * remaining } else { h };
            let mid = t + dt;
            let mark = outputs.points.len();
            let guess = outputs.guess;
            let start = progress.cursor;
            let statistics = &mut progress.statistics;
            let mut trial = || -> Result<(Cursor<S>, Cursor<S>, f64), Error> {
                let x1 = self.trial(
                    method,
                    &mut half,
                    &mut increment,
                    t,
                    dt,
                    &start,
                    limit,
                    statistics,
                )?;
                self.emit(method, &half, outputs, t, dt, &start.state, &x1.state, mid)?;
                let x2 = self.trial(
                    method,
                    &mut half,
                    &mut increment,
                    mid,
                    end - mid,
                    &x1,
                    limit,
                    statistics,
                )?;
                self.emit(
                    method,
                    &half,
                    outputs,
                    mid,
                    end - mid,
                    &x1.state,
                    &x2.state,
                    end,
                )?;
                let w = self.trial(
                    method,
                    &mut full,
                    &mut increment,
                    t,
                    end - t,
                    &start,
                    limit,
                    statistics,
                )?;
                Ok((x1, x2, w.state.distance(&x2.state)))
            };
            let optimal = match trial() {
                Ok((x1, x2, error)) => {
                    // The slides' h_opt is the step whose single-step error is tol_step.
                    let tol_step = tol * dt / length;
                    let optimal = dt * (numerator * tol_step / error).powf(exponent);
                    if optimal >= dt {
                        adaptivity.record(dt, points);
                        adaptivity.record(end - mid, points);
                        rejections = 0;
                        h = (options.safety * optimal)
                            .clamp(dt * options.max_shrink, dt * options.max_growth)
                            .min(max_step);
                        for (step, cursor, time) in [
                            (adaptivity.accepted - 1, x1, mid),
                            (adaptivity.accepted, x2, end),
                        ] {
                            progress.cursor = cursor;
                            progress.t = time;
                            if observer.wants(step) && self.observe(step, progress, observer)? {
                                // Stopped after the first of the pair: drop the outputs
                                // served from the second.
                                let served = outputs
                                    .points
                                    .partition_point(|point| S::time(point) <= time);
                                outputs.points.truncate(served);
                                return Ok((adaptivity, time < span.t_end));
                            }
                        }
                        continue;
                    }
                    optimal
                }
                // A trial step too large for the nonlinear solve is rejected like one too
                // inaccurate.
                Err(Error::NonConvergence { .. })
                | Err(Error::SingularMatrix { .. })
                | Err(Error::NonFinite { .. }) => 0.0,
                Err(other) => return Err(self.failure(other, progress, false)),
            };
            outputs.points.truncate(mark);
            outputs.guess = guess;
            method.restart(&mut half);
            method.restart(&mut full);
            adaptivity.rejected += 1;
            rejections += 1;
            h = (options.safety * optimal).max(dt * options.max_shrink);
            if h < min_step || rejections > options.max_rejections {
                let error = Error::StepSizeTooSmall {
                    t,
                    h,
                    min_step,
                    rejections,
                };
                return Err(self.failure(error, progress, false));
            }
        }
        Ok((adaptivity, false))
    }

    /// Fixed h, the number of points of each step chosen from the decay of the step
    /// polynomial's Chebyshev coefficients (see the module docs).
    fn solve_degree_adaptive<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        options: &SolveOptions,
        progress: &mut Progress<S>,
        outputs: &mut Outputs<'_, S>,
        observer: &mut O,
    ) -> Result<(Adaptivity, bool), RunFailure<S>> {
        let rejected = RunFailure::rejected;
        let tol = options.tolerance().map_err(rejected)?;
        let h = options.step().map_err(rejected)?;
        let base = self.method();
        let Some(initial_points) = base.points() else {
            return Err(rejected(Error::invalid(
                "adapt",
                format!(
                    "method {} has no polynomial degree to adapt",
                    base.info().name
                ),
            )));
        };
        let (low, high) = (options.min_points, options.max_points);
        if !(2..=MAX_POINTS).contains(&low) || !(low..=MAX_POINTS).contains(&high) {
            return Err(rejected(Error::invalid(
                "points",
                format!(
                    "min_points = {low}, max_points = {high}: need 2 ≤ min_points ≤ max_points ≤ \
                     {MAX_POINTS}"
                ),
            )));
        }
        let length = span.t_end - span.t0;
        let steps = grid_steps(span.t0, span.t_end, h).map_err(rejected)?;
        // One method and workspace per number of points, built once (tables are small).
        let mut steppers = (low..=high)
            .map(|points| {
                let method = base.with_points(points).ok_or_else(|| {
                    Error::invalid("adapt", "the method cannot change its number of points")
                })?;
                let workspace = method.workspace(self.model(), h)?;
                Ok((method, workspace))
            })
            .collect::<Result<Vec<_>, Error>>()
            .map_err(rejected)?;
        let orders: Vec<f64> = steppers
            .iter()
            .map(|(method, _)| method.info().order as f64)
            .collect();
        let limit = options.run.divergence_limit;
        let mut increment = S::State::zeros();
        let mut points = initial_points.clamp(low, high);
        let mut magnitudes = [0.0; MAX_POINTS];
        let mut adaptivity = Adaptivity::default();
        // The points used by the previous step, whose warm start continues into this one.
        let mut warm = None;
        // (points, error estimate) of the last accepted step.
        let mut previous: Option<(usize, f64)> = None;
        if observer.wants(0) && self.observe(0, progress, observer)? {
            return Ok((adaptivity, true));
        }
        for k in 0..steps {
            let (t, size, end_time) = grid_step(span.t0, span.t_end, h, steps, k);
            let tol_step = tol * size / length;
            loop {
                let (method, workspace) = &mut steppers[points - low];
                if warm != Some(points) {
                    method.restart(workspace);
                }
                let next = match self.trial(
                    method,
                    workspace,
                    &mut increment,
                    t,
                    size,
                    &progress.cursor,
                    limit,
                    &mut progress.statistics,
                ) {
                    Ok(next) => next,
                    Err(Error::NonConvergence { .. } | Error::NonFinite { .. })
                        if points < high =>
                    {
                        adaptivity.rejected += 1;
                        warm = None;
                        points += 1;
                        continue;
                    }
                    Err(error) => return Err(self.failure(error, progress, false)),
                };
                warm = Some(points);
                let Some(offsets) = method.node_offsets(workspace) else {
                    let error = Error::invalid("adapt", "the method has no step polynomial");
                    return Err(self.failure(error, progress, false));
                };
                let s = offsets.len() / S::NODE_WIDTH;
                chebyshev_magnitudes(offsets, S::NODE_WIDTH, &mut magnitudes[..=s]);
                let (tail, rho) = decay(&magnitudes[..=s]);
                // a_s ρ^(s' − s) is the tail with s' + 1 points, and the end point of a
                // method of order r beats it by ρ^((r − s')/2) (measured on Kepler
                // problems: within a factor 5 for SVI, r = 2s'; SC has r ≈ s').
                let estimate = |p: usize| {
                    let degree = (p - 1) as f64;
                    let exponent = degree - s as f64 + 0.5 * (orders[p - low] - degree).max(0.0);
                    tail * rho.powf(exponent)
                };
                let target = options.safety * tol_step;
                if estimate(points) > tol_step && points < high {
                    adaptivity.rejected += 1;
                    points = (points + 1..=high)
                        .find(|&p| estimate(p) <= target)
                        .unwrap_or(high);
                    continue;
                }
                if estimate(points) > tol_step {
                    adaptivity.unmet += 1;
                }
                if let Err(error) = self.emit(
                    method,
                    workspace,
                    outputs,
                    t,
                    size,
                    &progress.cursor.state,
                    &next.state,
                    end_time,
                ) {
                    return Err(self.failure(error, progress, false));
                }
                adaptivity.record(size, Some(points));
                progress.cursor = next;
                progress.t = end_time;
                if observer.wants(k + 1) && self.observe(k + 1, progress, observer)? {
                    return Ok((adaptivity, k + 1 < steps));
                }
                // The next step's estimate, extrapolated from the trend of the last two at
                // the same points, chooses the next points: more before the tolerance is
                // missed (a rejection costs a whole step), fewer with a margin (hysteresis).
                let now = estimate(points);
                let growth = match previous {
                    Some((p, before)) if p == points && before > 0.0 => {
                        (now / before).clamp(1.0, 1e3)
                    }
                    _ => 1.0,
                };
                previous = Some((points, now));
                if now * growth * growth > target && points < high {
                    points = (points + 1..=high)
                        .find(|&p| estimate(p) * growth * growth <= target)
                        .unwrap_or(high);
                } else if points > low && estimate(points - 1) <= 0.1 * target {
                    points -= 1;
                }
                break;
            }
        }
        Ok((adaptivity, false))
    }
}
