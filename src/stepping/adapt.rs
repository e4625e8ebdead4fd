//! The adaptive modes of [`super::solve`], on the loop of [`crate::Integrator::try_run`]
//! (the same checks, compensated sums and observers; observers see the accepted steps).
//!
//! - [`Adapt::Step`](super::solve::Adapt::Step): step doubling as in Porcù & Penati's slides. From (t, y) the method takes
//!   two steps of h (result X2) and one of 2h (result W); with r the order,
//!   h_opt = h (θ / ‖W − X2‖)^(1/(r+1)) for the threshold θ = max(ρ tol_step, ν).
//!   ρ = min(2^r − 1, 15) is the ratio between the errors of W and X2 the controller trusts:
//!   asymptotically it is 2^r − 1, but for high orders (4095 for SVI 7/6) the 2h step near
//!   a close approach is not in the asymptotic regime, and trusting 2^r − 1 left the final
//!   error of Kepler e = 0.9 over T = 2000 at 85–700 × tol (the slides' 2(2^r + 1)).
//!   ν = 10⁴ ε max(1, ‖X2‖∞) is the resolution of the estimate itself: the nonlinear solves
//!   stop at increments of about 10⁻¹² there, so ‖W − X2‖ never falls below it however
//!   small h gets. Without the floor a tolerance below it shrank the steps to the minimum
//!   and aborted (tol = 1e-10 at t ≈ 333); with it the step is accepted at the resolution
//!   and counted in [`Adaptivity::unmet`](super::solve::Adaptivity::unmet), and a step whose
//!   estimate is below the resolution grows by `max_growth` (the estimate tells nothing
//!   more; shrinking on it would crawl). A retry whose estimate did not fall with the
//!   smaller step at least as h^((r+1)/2) and is below 10⁶ ε max(1, ‖X2‖∞) (noise above ν:
//!   up to 5·10⁴ ε at some close approaches) is accepted as it is, counted as unmet too, and raises ν to that estimate
//!   for the rest of the run, instead of shrinking to the minimum and aborting. The step is
//!   accepted (keeping the more accurate X2) when h_opt ≥ h, and retried with h_opt
//!   otherwise; the next h is safety · h_opt, with growth and shrink bounded, and a step
//!   below the minimum (repeated non-convergence) ends in [`Error::StepSizeTooSmall`].
//!   Measured on Kepler e = 0.9, T = 2000, SVI 7/6 (`tests/step_doubling.rs`): final error
//!   0.09, 0.41, 0.21 and 4.8 × tol for tol = 1e-6 … 1e-9; 4.1e-9 for tol = 1e-10 and
//!   1e-11, every step unmet — below 1e-9 the estimate cannot tell the steps apart, and the errors
//!   of 5·10⁴ non-symplectic steps add up (fixed steps reach 6e-12 there with 4·10⁵ steps).
//!   Each accepted step is still a composition of symplectic maps and conserves the Noether
//!   momenta exactly, but the step size depends on the state, so the map over many steps
//!   is not symplectic and the energy error drifts; [`crate::stepping::reparam`] adapts the
//!   physical step and keeps the geometry.
//! - [`Adapt::Degree`](super::solve::Adapt::Degree): fixed h, and the number of CGL points of each step chosen between
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

use crate::error::{Error, require_positive};
use crate::method::space::{Space, StepState};
use crate::method::step::Step;
use crate::spectral::MAX_POINTS;
use crate::stepping::grid::{grid_step, grid_steps, resolution};
use crate::stepping::observer::Observer;
use crate::stepping::outputs::Outputs;
use crate::stepping::run::{Cursor, Integrator, Progress, RunFailure, Statistics};
use crate::stepping::solve::{Adaptivity, SolveOptions, Span};

/// Chebyshev coefficient magnitudes a_k = max over components |c_k| (k = 0..s) of the
/// polynomial through the CGL node values (offsets, `width` numbers per node: node 0 is zero).
/// The largest ratio between the error of a 2h step and of two h steps that step doubling
/// trusts (2^r − 1 in the asymptotic regime, 15 for r = 4).
const MAX_TRUSTED_RATIO: f64 = 15.0;

/// The resolution of the step-doubling estimate ‖W − X₂‖ in units of ε·max(1, ‖X₂‖∞): the
/// nonlinear solves stop at increments of this size (measured on Kepler e = 0.9 with SVI 7/6
/// at steps of 1e-8, where the true difference is zero: up to 7·10³).
const ESTIMATE_NOISE: f64 = 1e4;

/// The largest estimate, in the units of [`ESTIMATE_NOISE`], that step doubling may take for
/// noise when it does not fall with the step (above it, a pre-asymptotic error).
const MAX_NOISE: f64 = 1e6;

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
    /// One trial step of an adaptive mode from `from` at `t` with size `h` (counted in
    /// `statistics.steps`), with the step's index and time attached to a failure; with the
    /// divergence limit of `options`, and [`Error::TooManySteps`] instead once the steps
    /// taken reach `options.max_steps`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trial(
        &self,
        method: &M,
        workspace: &mut M::Workspace,
        increment: &mut S::State,
        t: f64,
        h: f64,
        from: &Cursor<S>,
        options: &SolveOptions,
        statistics: &mut Statistics,
    ) -> Result<Cursor<S>, Error> {
        let index = statistics.steps;
        options.budget(index, t)?;
        let mut next = from.clone();
        self.attempt(
            method,
            workspace,
            increment,
            t,
            h,
            &mut next,
            options.run.divergence_limit,
            statistics,
        )
        .map_err(|failure| failure.at(index, t))?;
        statistics.steps += 1;
        Ok(next)
    }

    /// Step doubling (see the module docs): two steps of h against one of 2h, accepted when
    /// the optimal step is not smaller; observers see the points of the accepted steps.
    pub(super) fn solve_step_adaptive<O: Observer<L, S::Point>>(
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
        let trusted = (2f64.powi(order) - 1.0).min(MAX_TRUSTED_RATIO);
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
        let mut half = method.workspace(self.model(), h).map_err(rejected)?;
        let mut full = method.workspace(self.model(), 2.0 * h).map_err(rejected)?;
        let mut increment = progress.cursor.state.zeros_like();
        let mut adaptivity = Adaptivity::default();
        let mut rejections = 0;
        // (step, estimate) of the last rejected trial of the current step.
        let mut previous: Option<(f64, f64)> = None;
        // The largest estimate found to be noise (see `stalled` below).
        let mut observed_noise: f64 = 0.0;
        if observer.wants(0) && self.observe(0, None, progress, observer)? {
            return Ok((adaptivity, true));
        }
        while progress.t < span.t_end {
            let t = progress.t;
            let remaining = span.t_end - t;
            let last = 2.0 * h >= remaining * (1.0 - 1e-12);
            let end = if last { span.t_end } else { t + 2.0 * h };
            let dt = if last { 0.5 * remaining } else { h };
            let mid = t + dt;
            let mark = outputs.mark();
            let guess = outputs.guess.clone();
            let start = progress.cursor.clone();
            let statistics = &mut progress.statistics;
            // An output or event that fails on the trial's converged steps (a non-finite event
            // function) is the solve's failure, not a reason to retry a smaller step.
            let mut served = Ok(());
            let mut trial = || -> Result<(Cursor<S>, Cursor<S>, f64, f64), Error> {
                let x1 = self.trial(
                    method,
                    &mut half,
                    &mut increment,
                    t,
                    dt,
                    &start,
                    options,
                    statistics,
                )?;
                served = self.emit(
                    method,
                    &half,
                    outputs,
                    statistics.steps,
                    t,
                    dt,
                    &start.state,
                    &x1.state,
                    mid,
                );
                served.clone()?;
                let x2 = self.trial(
                    method,
                    &mut half,
                    &mut increment,
                    mid,
                    end - mid,
                    &x1,
                    options,
                    statistics,
                )?;
                served = self.emit(
                    method,
                    &half,
                    outputs,
                    statistics.steps,
                    mid,
                    end - mid,
                    &x1.state,
                    &x2.state,
                    end,
                );
                served.clone()?;
                let w = self.trial(
                    method,
                    &mut full,
                    &mut increment,
                    t,
                    end - t,
                    &start,
                    options,
                    statistics,
                )?;
                let error = w.state.distance(&x2.state);
                let size = x2.state.distance(&x2.state.zeros_like());
                Ok((x1, x2, error, size))
            };
            let result = trial();
            if let Err(error) = served {
                return Err(self.failure(error, progress, false));
            }
            let optimal = match result {
                Ok((x1, x2, error, size)) => {
                    // The slides' h_opt is the step whose single-step error is tol_step, with
                    // the trusted ratio between the 2h and the h steps' errors capped and the
                    // estimate's own resolution as a floor (see the module docs).
                    let tol_step = tol * dt / length;
                    let noise = (ESTIMATE_NOISE * f64::EPSILON * size.max(1.0)).max(observed_noise);
                    let threshold = (trusted * tol_step).max(noise);
                    // An estimate at its resolution says the step is as accurate as can be
                    // told: the step grows (shrinking on noise would crawl). One that did not
                    // fall with the smaller retry as h^((r+1)/2) at least is noise too: the
                    // step is accepted as it is, and the resolution is at least that from
                    // now on.
                    let stalled = error <= MAX_NOISE * f64::EPSILON * size.max(1.0)
                        && matches!(previous, Some((before, estimate))
                            if error >= estimate * (dt / before).powf(0.5 / exponent));
                    if stalled {
                        observed_noise = observed_noise.max(error);
                    }
                    let optimal = if error <= noise {
                        f64::INFINITY
                    } else if stalled {
                        dt
                    } else {
                        dt * (threshold / error).powf(exponent)
                    };
                    if optimal >= dt {
                        adaptivity.record(dt, points);
                        adaptivity.record(end - mid, points);
                        previous = None;
                        if trusted * tol_step < noise || stalled {
                            adaptivity.unmet += 2;
                        }
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
                            if outputs.terminal_time().is_some_and(|event| event <= time) {
                                // A terminal event inside this step ended the solve.
                                return Ok((adaptivity, false));
                            }
                            if observer.wants(step)
                                && self.observe(step, Some(&half), progress, observer)?
                            {
                                // Stopped after the first of the pair: drop the outputs
                                // served from the second.
                                outputs.rollback_after(time);
                                return Ok((adaptivity, time < span.t_end));
                            }
                        }
                        continue;
                    }
                    previous = Some((dt, error));
                    optimal
                }
                // A trial step too large for the nonlinear solve is rejected like one too
                // inaccurate.
                Err(Error::NonConvergence { .. })
                | Err(Error::SingularMatrix { .. })
                | Err(Error::NonFinite { .. }) => {
                    previous = None;
                    0.0
                }
                Err(other) => return Err(self.failure(other, progress, false)),
            };
            outputs.rollback(mark);
            outputs.guess = guess;
            method.restart(&mut half);
            method.restart(&mut full);
            adaptivity.rejected += 1;
            rejections += 1;
            h = (options.safety * optimal).max(dt * options.max_shrink);
            if h < min_step || rejections > options.max_rejections {
                let error = Error::StepSizeTooSmall {
                    cause: "the tolerance cannot be met",
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
    pub(super) fn solve_degree_adaptive<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        options: &SolveOptions,
        progress: &mut Progress<S>,
        outputs: &mut Outputs<'_, S>,
        observer: &mut O,
    ) -> Result<(Adaptivity, bool), RunFailure<S>> {
        let rejected = RunFailure::rejected;
        let base = self.method();
        let no_degree = || {
            rejected(Error::invalid(
                "adapt",
                format!(
                    "method {} has no polynomial degree to adapt",
                    base.info().name
                ),
            ))
        };
        // A constant: for a method without points nothing below is compiled.
        if M::WITHOUT_POINTS {
            return Err(no_degree());
        }
        let tol = options.tolerance().map_err(rejected)?;
        let h = options.step().map_err(rejected)?;
        let Some(initial_points) = base.points() else {
            return Err(no_degree());
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
        let mut increment = progress.cursor.state.zeros_like();
        let width = S::node_width(&progress.cursor.state);
        let mut points = initial_points.clamp(low, high);
        let mut magnitudes = [0.0; MAX_POINTS];
        let mut adaptivity = Adaptivity::default();
        // The points used by the previous step, whose warm start continues into this one.
        let mut warm = None;
        // (points, error estimate) of the last accepted step.
        let mut previous: Option<(usize, f64)> = None;
        if observer.wants(0) && self.observe(0, None, progress, observer)? {
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
                    options,
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
                let s = offsets.len() / width;
                chebyshev_magnitudes(offsets, width, &mut magnitudes[..=s]);
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
                    progress.statistics.steps,
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
                if outputs.terminal.is_some() {
                    return Ok((adaptivity, false));
                }
                if observer.wants(k + 1)
                    && self.observe(k + 1, Some(&steppers[points - low].1), progress, observer)?
                {
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
