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

use crate::error::{require_finite, require_positive};
use crate::method::{PhasePoint, State, StepReport};
use crate::model::derived::LagrangianExt;
use crate::spectral::MAX_POINTS;
use crate::stepping::grid::{grid_step, step_count};
use crate::{Error, Initial, Integrator, Lagrangian, Method, Statistics};
use nalgebra::SVector;
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
        require_finite("t0", self.t0)?;
        require_finite("t_end", self.t_end)?;
        if self.t_end <= self.t0 {
            return Err(Error::invalid(
                "t_end",
                format!(
                    "the horizon {} is not after the start {}",
                    self.t_end, self.t0
                ),
            ));
        }
        if self.output_times.is_empty() {
            return Err(Error::invalid("output_times", "no output time given"));
        }
        for (i, &time) in self.output_times.iter().enumerate() {
            require_finite(&format!("output_times[{i}]"), time)?;
            if time < self.t0 || time > self.t_end {
                return Err(Error::invalid(
                    "output_times",
                    format!(
                        "time {time} (entry {i}) is outside the span [{}, {}]",
                        self.t0, self.t_end
                    ),
                ));
            }
            if i > 0 && time <= self.output_times[i - 1] {
                return Err(Error::invalid(
                    "output_times",
                    format!(
                        "times must increase strictly: entry {i} ({time}) follows {}",
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
                format!("{} must be a finite number above 1", self.max_growth),
            ));
        }
        if !(self.max_shrink > 0.0 && self.max_shrink < 1.0) {
            return Err(Error::invalid(
                "max_shrink",
                format!("{} must lie in (0, 1)", self.max_shrink),
            ));
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return Err(Error::invalid(
                "safety",
                format!("{} must lie in (0, 1]", self.safety),
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

/// The result of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct Solution<const N: usize> {
    /// The phase point at each output time, in order.
    pub points: Vec<PhasePoint<N>>,
    /// The phase point at the end of the span (whether or not it is an output time).
    pub last: PhasePoint<N>,
    /// Work done, including rejected trial steps; `steps` counts the method steps taken.
    pub statistics: Statistics,
    /// What the adaptivity did (step sizes, points used, rejections).
    pub adaptivity: Adaptivity,
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
pub fn solve<L: Lagrangian<N>, M: Method<N> + Clone, const N: usize>(
    model: L,
    method: M,
    span: &Span,
    initial: Initial<N>,
    options: &SolveOptions,
) -> Result<Solution<N>, Error> {
    Integrator::new(model, method).solve(span, initial, options)
}

/// The current state, with the compensation of its Kahan sums.
#[derive(Debug, Clone, Copy)]
struct Cursor<const N: usize> {
    state: State<N>,
    compensation: State<N>,
}

impl<const N: usize> Cursor<N> {
    fn advanced(mut self, increment: &State<N>) -> Self {
        self.state
            .add_compensated(&mut self.compensation, increment);
        self
    }
}

/// Output times not yet served, and the points produced so far.
struct Outputs<'a, const N: usize> {
    times: &'a [f64],
    points: Vec<PhasePoint<N>>,
    /// Last velocity, the Newton start of the next inverse Legendre map.
    guess: SVector<f64, N>,
}

impl<const N: usize> Outputs<'_, N> {
    fn next(&self) -> Option<f64> {
        self.times.get(self.points.len()).copied()
    }
}

/// A method with its workspace.
struct Stepper<'a, L, M: Method<N>, const N: usize> {
    integrator: &'a Integrator<L, M, N>,
    method: M,
    workspace: M::Workspace,
    increment: State<N>,
}

impl<L: Lagrangian<N>, M: Method<N>, const N: usize> Stepper<'_, L, M, N> {
    /// Step from `cursor` at `t` with size `h`, counting the work in `statistics`.
    fn step(
        &mut self,
        t: f64,
        h: f64,
        cursor: &Cursor<N>,
        statistics: &mut Statistics,
    ) -> Result<Cursor<N>, Error> {
        let index = statistics.steps;
        let report: StepReport = self
            .method
            .step(
                self.integrator.model(),
                &mut self.workspace,
                t,
                h,
                &cursor.state,
                &mut self.increment,
            )
            .map_err(|failure| failure.at(index, t))?;
        statistics.steps += 1;
        statistics.iterations += report.iterations;
        statistics.evaluations += report.evaluations;
        let next = cursor.advanced(&self.increment);
        if !next.state.is_finite() {
            return Err(Error::NonFinite {
                what: "state".into(),
                step: index,
                t,
            });
        }
        Ok(next)
    }

    /// Serve every output time in (t, t + h] (`last`: the step ends the span) from the step
    /// just taken from `start` to `end`.
    fn emit(
        &self,
        outputs: &mut Outputs<'_, N>,
        t: f64,
        h: f64,
        start: &State<N>,
        end: &State<N>,
        end_time: f64,
    ) -> Result<(), Error> {
        let integrator = self.integrator;
        let model = integrator.model();
        let mut ends: Option<(PhasePoint<N>, PhasePoint<N>)> = None;
        while let Some(time) = outputs.next() {
            if time > end_time {
                break;
            }
            let point = if time == end_time {
                integrator.phase_point(end_time, end, &outputs.guess)?
            } else {
                let theta = ((time - t) / h).clamp(0.0, 1.0);
                let (q, v) = match self.method.dense_output(&self.workspace, start, h, theta) {
                    Some(dense) => dense,
                    None => {
                        let (a, b) = match ends {
                            Some(known) => known,
                            None => {
                                let known = (
                                    integrator.phase_point(t, start, &outputs.guess)?,
                                    integrator.phase_point(end_time, end, &outputs.guess)?,
                                );
                                ends = Some(known);
                                known
                            }
                        };
                        hermite(&a, &b, time)
                    }
                };
                PhasePoint {
                    t: time,
                    q,
                    v,
                    p: model.momentum(time, &q, &v),
                }
            };
            outputs.guess = point.v;
            outputs.points.push(point);
        }
        Ok(())
    }
}

/// Cubic Hermite interpolation of (q, q̇) between two phase points.
fn hermite<const N: usize>(
    a: &PhasePoint<N>,
    b: &PhasePoint<N>,
    time: f64,
) -> (SVector<f64, N>, SVector<f64, N>) {
    let h = b.t - a.t;
    let s = (time - a.t) / h;
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    );
    let (d00, d10, d01, d11) = (
        6.0 * s2 - 6.0 * s,
        3.0 * s2 - 4.0 * s + 1.0,
        -6.0 * s2 + 6.0 * s,
        3.0 * s2 - 2.0 * s,
    );
    let q = a.q * h00 + a.v * (h * h10) + b.q * h01 + b.v * (h * h11);
    let v = (a.q * d00 + b.q * d01) / h + a.v * d10 + b.v * d11;
    (q, v)
}

/// ‖a − b‖∞ over q and y.
fn distance<const N: usize>(a: &State<N>, b: &State<N>) -> f64 {
    (a.q - b.q).amax().max((a.y - b.y).amax())
}

/// Chebyshev coefficient magnitudes a_k = max over components |c_k| (k = 0..s) of the
/// polynomial through the CGL node values (offsets: node 0 is zero).
fn chebyshev_magnitudes<const N: usize>(offsets: &[f64], out: &mut [f64]) {
    let s = offsets.len() / N;
    for (k, a) in out.iter_mut().enumerate().take(s + 1) {
        let mut c = [0.0; N];
        for (nu, node) in offsets.chunks_exact(N).enumerate() {
            let nu = nu + 1;
            // x_ν = −cos(νπ/s), so T_k(x_ν) = (−1)^k cos(kνπ/s).
            let weight = if nu == s { 0.5 } else { 1.0 };
            let angle = std::f64::consts::PI * ((k * nu) % (2 * s)) as f64 / s as f64;
            let tk = if k % 2 == 0 {
                angle.cos()
            } else {
                -angle.cos()
            };
            for (ci, x) in c.iter_mut().zip(node) {
                *ci += weight * tk * x;
            }
        }
        let scale = if k == 0 || k == s { 1.0 } else { 2.0 } / s as f64;
        *a = c.iter().fold(0.0f64, |m, ci| m.max((ci * scale).abs()));
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

impl<L: Lagrangian<N>, M: Method<N> + Clone, const N: usize> Integrator<L, M, N> {
    /// [`solve`] with this integrator's model and method.
    pub fn solve(
        &self,
        span: &Span,
        initial: Initial<N>,
        options: &SolveOptions,
    ) -> Result<Solution<N>, Error> {
        span.validate()?;
        options.validate()?;
        let state = self.initial_state(span.t0, &initial)?;
        self.check_structure(span.t0, &state)?;
        let guess = match initial {
            Initial::Velocity { v, .. } => v,
            Initial::Momentum { p, .. } => p,
        };
        let mut outputs = Outputs {
            times: &span.output_times,
            points: Vec::with_capacity(span.output_times.len()),
            guess,
        };
        if outputs.next() == Some(span.t0) {
            let point = self.phase_point(span.t0, &state, &guess)?;
            outputs.guess = point.v;
            outputs.points.push(point);
        }
        let cursor = Cursor {
            state,
            compensation: State::zeros(),
        };
        let mut statistics = Statistics::default();
        let (adaptivity, end) = match options.adapt {
            Adapt::None => {
                self.solve_fixed(span, options.step()?, cursor, &mut outputs, &mut statistics)?
            }
            Adapt::Step => {
                self.solve_step_adaptive(span, options, cursor, &mut outputs, &mut statistics)?
            }
            Adapt::Degree => {
                self.solve_degree_adaptive(span, options, cursor, &mut outputs, &mut statistics)?
            }
        };
        let last = match outputs.points.last() {
            Some(point) if point.t == span.t_end => *point,
            _ => self.phase_point(span.t_end, &end, &outputs.guess)?,
        };
        Ok(Solution {
            points: outputs.points,
            last,
            statistics,
            adaptivity,
        })
    }

    fn stepper(&self, method: M, h: f64) -> Result<Stepper<'_, L, M, N>, Error> {
        let workspace = method.workspace(self.model(), h)?;
        Ok(Stepper {
            integrator: self,
            method,
            workspace,
            increment: State::zeros(),
        })
    }

    fn solve_fixed(
        &self,
        span: &Span,
        h: f64,
        mut cursor: Cursor<N>,
        outputs: &mut Outputs<'_, N>,
        statistics: &mut Statistics,
    ) -> Result<(Adaptivity, State<N>), Error> {
        let steps = step_count(span.t_end - span.t0, h)?;
        let mut adaptivity = Adaptivity::default();
        let points = self.method().points();
        let mut stepper = self.stepper(self.method().clone(), h)?;
        for k in 0..steps {
            let (t, size, end_time) = grid_step(span.t0, span.t_end, h, steps, k);
            let next = stepper.step(t, size, &cursor, statistics)?;
            stepper.emit(outputs, t, size, &cursor.state, &next.state, end_time)?;
            adaptivity.record(size, points);
            cursor = next;
        }
        Ok((adaptivity, cursor.state))
    }

    fn solve_step_adaptive(
        &self,
        span: &Span,
        options: &SolveOptions,
        mut cursor: Cursor<N>,
        outputs: &mut Outputs<'_, N>,
        statistics: &mut Statistics,
    ) -> Result<(Adaptivity, State<N>), Error> {
        let tol = options.tolerance()?;
        let length = span.t_end - span.t0;
        let min_step = options.min_step.unwrap_or(length * 1e-12);
        let max_step = options.max_step.unwrap_or(length).min(length);
        let order = self.method().info().order as i32;
        let numerator = 2.0 * (2f64.powi(order) + 1.0);
        let exponent = 1.0 / (f64::from(order) + 1.0);
        let mut h = match options.h {
            Some(h) => {
                require_positive("h", h)?;
                h
            }
            None => {
                let point = self.phase_point(span.t0, &cursor.state, &outputs.guess)?;
                let size = point.q.amax().max(1e-3);
                let speed = point.v.amax().max(1e-12);
                0.01 * size / speed
            }
        }
        .clamp(min_step, max_step);
        let points = self.method().points();
        let mut half = self.stepper(self.method().clone(), h)?;
        let mut full = self.stepper(self.method().clone(), 2.0 * h)?;
        let mut adaptivity = Adaptivity::default();
        let mut rejections = 0;
        let mut t = span.t0;
        while t < span.t_end {
            let remaining = span.t_end - t;
            let last = 2.0 * h >= remaining * (1.0 - 1e-12);
            let end = if last { span.t_end } else { t + 2.0 * h };
            let dt = if last { 0.5 * remaining } else { h };
            let mid = t + dt;
            let mark = outputs.points.len();
            let guess = outputs.guess;
            let mut trial = || -> Result<(Cursor<N>, f64), Error> {
                let x1 = half.step(t, dt, &cursor, statistics)?;
                half.emit(outputs, t, dt, &cursor.state, &x1.state, mid)?;
                let x2 = half.step(mid, end - mid, &x1, statistics)?;
                half.emit(outputs, mid, end - mid, &x1.state, &x2.state, end)?;
                let w = full.step(t, end - t, &cursor, statistics)?;
                Ok((x2, distance(&w.state, &x2.state)))
            };
            let optimal = match trial() {
                Ok((x2, error)) => {
                    // The slides' h_opt is the step whose single-step error is tol_step.
                    let tol_step = tol * dt / length;
                    let optimal = dt * (numerator * tol_step / error).powf(exponent);
                    if optimal >= dt {
                        cursor = x2;
                        adaptivity.record(dt, points);
                        adaptivity.record(end - mid, points);
                        t = end;
                        rejections = 0;
                        h = (options.safety * optimal)
                            .clamp(dt * options.max_shrink, dt * options.max_growth)
                            .min(max_step);
                        continue;
                    }
                    optimal
                }
                // A trial step too large for the nonlinear solve is rejected like one too
                // inaccurate.
                Err(Error::NonConvergence { .. })
                | Err(Error::SingularMatrix { .. })
                | Err(Error::NonFinite { .. }) => 0.0,
                Err(other) => return Err(other),
            };
            outputs.points.truncate(mark);
            outputs.guess = guess;
            half.method.restart(&mut half.workspace);
            full.method.restart(&mut full.workspace);
            adaptivity.rejected += 1;
            rejections += 1;
            h = (options.safety * optimal).max(dt * options.max_shrink);
            if h < min_step || rejections > options.max_rejections {
                return Err(Error::StepSizeTooSmall {
                    t,
                    h,
                    min_step,
                    rejections,
                });
            }
        }
        Ok((adaptivity, cursor.state))
    }

    fn solve_degree_adaptive(
        &self,
        span: &Span,
        options: &SolveOptions,
        mut cursor: Cursor<N>,
        outputs: &mut Outputs<'_, N>,
        statistics: &mut Statistics,
    ) -> Result<(Adaptivity, State<N>), Error> {
        let tol = options.tolerance()?;
        let h = options.step()?;
        let base = self.method();
        let Some(initial_points) = base.points() else {
            return Err(Error::invalid(
                "adapt",
                format!(
                    "method {} has no polynomial degree to adapt",
                    base.info().name
                ),
            ));
        };
        let (low, high) = (options.min_points, options.max_points);
        if !(2..=MAX_POINTS).contains(&low) || !(low..=MAX_POINTS).contains(&high) {
            return Err(Error::invalid(
                "points",
                format!(
                    "min_points = {low}, max_points = {high}: need 2 ≤ min_points ≤ max_points ≤ \
                     {MAX_POINTS}"
                ),
            ));
        }
        let length = span.t_end - span.t0;
        let steps = step_count(length, h)?;
        // One method and workspace per number of points, built once (tables are small).
        let mut steppers = (low..=high)
            .map(|points| {
                let method = base.with_points(points).ok_or_else(|| {
                    Error::invalid("adapt", "the method cannot change its number of points")
                })?;
                self.stepper(method, h)
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let orders: Vec<f64> = steppers
            .iter()
            .map(|stepper| stepper.method.info().order as f64)
            .collect();
        let mut points = initial_points.clamp(low, high);
        let mut magnitudes = [0.0; MAX_POINTS];
        let mut adaptivity = Adaptivity::default();
        // The points used by the previous step, whose warm start continues into this one.
        let mut warm = None;
        // (points, error estimate) of the last accepted step.
        let mut previous: Option<(usize, f64)> = None;
        for k in 0..steps {
            let (t, size, end_time) = grid_step(span.t0, span.t_end, h, steps, k);
            let tol_step = tol * size / length;
            loop {
                let stepper = &mut steppers[points - low];
                if warm != Some(points) {
                    stepper.method.restart(&mut stepper.workspace);
                }
                let next = match stepper.step(t, size, &cursor, statistics) {
                    Ok(next) => next,
                    Err(Error::NonConvergence { .. } | Error::NonFinite { .. })
                        if points < high =>
                    {
                        adaptivity.rejected += 1;
                        warm = None;
                        points += 1;
                        continue;
                    }
                    Err(error) => return Err(error),
                };
                warm = Some(points);
                let offsets = stepper
                    .method
                    .node_offsets(&stepper.workspace)
                    .ok_or_else(|| Error::invalid("adapt", "the method has no step polynomial"))?;
                let s = offsets.len() / N;
                chebyshev_magnitudes::<N>(offsets, &mut magnitudes[..=s]);
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
                stepper.emit(outputs, t, size, &cursor.state, &next.state, end_time)?;
                adaptivity.record(size, Some(points));
                cursor = next;
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
        Ok((adaptivity, cursor.state))
    }
}
