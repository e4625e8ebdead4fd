//! Time-reparametrised runs: fixed steps in computational time τ, physical steps dt = g dτ.
//!
//! [`Integrator::try_solve_reparametrized`] runs the integrator's method on the τ-Lagrangian
//! L̃ = g (L(q, q'/g) + E₀) of [`crate::model::reparametrized`] (Leok, *Generalized
//! Variational Integrators*, §5.6: the Poincaré transformation) with a fixed step Δτ, so the
//! method keeps its geometry in τ — a symplectic method is symplectic for K = g (H − E₀),
//! momenta of symmetries of L that leave g invariant are conserved exactly, and backward
//! error analysis bounds the energy error — while the physical steps shrink where g is
//! small. Measured on Kepler e = 0.9 (svi 9/8, g = |q|, Δτ = 0.3): the largest energy error
//! was 1.0e-12, 1.0e-11 and 1.0e-10 after 10⁴, 10⁵ and 10⁶ steps, a linear growth of about
//! 10⁻¹⁶ a step at the level where the stage solves stop (step doubling at tol 1e-8 grew to
//! 1.1e-7).
//!
//! # Physical time
//! Over a step, t advances by ∫ g(q(σ)) dσ. On the step polynomial of a spectral method
//! (its dense output) this is a Gauss–Legendre rule of ⌊r/2⌋ + 1 points for a method of
//! order r (exact on polynomials of degree r + 1): the integral a variational integrator of
//! the extended Lagrangian L̃ + ½(s' − g(q))² would give its coordinate s = t with its own
//! quadrature, up to quadrature error of the method's order. Methods without a step
//! polynomial (the classic variational integrators, order ≤ 2) use the trapezoidal rule
//! ½ Δτ (g(q_k) + g(q_{k+1})), which is exactly Störmer–Verlet's rule for s. The sum over
//! steps is compensated.
//!
//! # Output times
//! The last step is shortened so that it ends at t_end: its Δτ solves t(Δτ) = t_end by
//! Newton's method on whole steps (dt/dΔτ = g at the step's end), so the final state has
//! the accuracy of a step, not of the dense output. Output times inside the span are read
//! off the step polynomial at the σ that solves t(σ) = t_out (Newton's method on the
//! quadrature of g over [0, σ]); methods without a step polynomial serve only the ends.
//!
//! Observers receive physical points (t, q, q̇ = q'/g, p), counted by τ-steps.

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::method::space::{Euclidean, Initial, PhasePoint, State, StepState};
use crate::method::{Method, MethodInfo};
use crate::model::derived::LagrangianExt;
use crate::model::reparametrized::{Monitor, Reparametrized, not_reparametrizable};
use crate::model::{ConstantMass, Lagrangian};
use crate::spectral::quadrature::GaussLegendre;
use crate::stepping::observer::Observer;
use crate::stepping::run::{Cursor, Integrator, Run, RunFailure, Statistics};
use crate::stepping::solve::{Adaptivity, Solution, SolveOptions, Span};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};

/// Newton iterations allowed for the last step's Δτ and for an output time's σ.
const TIME_NEWTON_ITERATIONS: usize = 40;

/// A failure after the start of a run in physical time: the run up to `last`, the last good
/// physical point (its state in (q, p)).
pub(crate) fn failure_after<N: Dimension>(
    error: Error,
    last: &PhasePoint<N>,
    statistics: Statistics,
) -> RunFailure<Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    RunFailure {
        error,
        partial: Some(Run {
            last: last.clone(),
            state: State {
                q: last.q.clone(),
                y: last.p.clone(),
            },
            statistics,
            stopped: false,
        }),
        events: Box::default(),
    }
}

/// Newton's method on the size σ of a run's last step so that it ends on `t_end`: the step
/// just taken had size σ₀ and ended at t_end + r₀ with dt/dσ = s₀ there (`first` = (σ₀, r₀,
/// s₀)); `retake(σ)` takes the step again from its start with size σ and returns its (r, s).
/// The iterates stay inside the bracket (lo, hi) of sizes that fall short of and reach t_end
/// (bisection where a Newton step leaves it), until |r| ≤ 4ε max(|t_end|, 1). Returns the
/// size of the step last taken; [`Error::NonConvergence`] at (`step`, `t`) after
/// [`TIME_NEWTON_ITERATIONS`].
pub(crate) fn land_on_horizon(
    t_end: f64,
    first: (f64, f64, f64),
    (step, t): (usize, f64),
    mut retake: impl FnMut(f64) -> Result<(f64, f64), Error>,
) -> Result<f64, Error> {
    let tolerance = 4.0 * f64::EPSILON * t_end.abs().max(1.0);
    let (mut size, mut residual, mut slope) = first;
    let (mut lo, mut hi) = (0.0, size);
    let mut iterations = 0;
    while residual.abs() > tolerance {
        if iterations == TIME_NEWTON_ITERATIONS {
            return Err(Error::NonConvergence {
                step,
                t,
                iterations,
                residual,
            });
        }
        iterations += 1;
        if residual > 0.0 {
            hi = size;
        } else {
            lo = size;
        }
        size -= residual / slope;
        if !(size > lo && size < hi) {
            size = 0.5 * (lo + hi);
        }
        (residual, slope) = retake(size)?;
    }
    Ok(size)
}

/// The value g(q), checked positive and finite.
fn monitor_value<L: Lagrangian<N>, G: Monitor<N>, N: Dimension>(
    tilde: &Reparametrized<'_, L, G>,
    q: &OVector<f64, N>,
    tau: f64,
) -> Result<f64, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let g = tilde.monitor_value(q);
    if g.is_finite() && g > 0.0 {
        Ok(g)
    } else {
        Err(Error::invalid(
            "monitor",
            format!("g(q) = {g:e} at q = {q:?} (τ = {tau}); a monitor must be positive and finite"),
        ))
    }
}

/// How physical time is integrated over one τ-step: Gauss–Legendre on the step polynomial,
/// or the trapezoidal rule on the end points (see the module docs).
struct TimeRule {
    rule: GaussLegendre,
}

impl TimeRule {
    fn new(info: &MethodInfo) -> Result<Self, Error> {
        Ok(TimeRule {
            rule: GaussLegendre::new(info.order / 2 + 1)?,
        })
    }

    /// ∫₀^{θΔτ} g(q(σ)) dσ over the step just taken from `start` with size `dtau`, for
    /// θ ∈ (0, 1]; `end` is the step's end state (used without a step polynomial, θ = 1).
    #[allow(clippy::too_many_arguments)]
    fn elapsed<L: Lagrangian<N>, M: Method<N>, G: Monitor<N>, N: Dimension>(
        &self,
        method: &M,
        workspace: &M::Workspace,
        tilde: &Reparametrized<'_, L, G>,
        start: &State<N>,
        end: &State<N>,
        dtau: f64,
        theta: f64,
        tau: f64,
    ) -> Result<Option<f64>, Error>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let mut sum = 0.0;
        for (&x, &w) in self.rule.nodes().iter().zip(self.rule.weights()) {
            let at = 0.5 * theta * (x + 1.0);
            let Some((q, _)) = method.dense_output(workspace, start, dtau, at) else {
                if theta < 1.0 {
                    return Ok(None);
                }
                let g0 = monitor_value(tilde, &start.q, tau)?;
                let g1 = monitor_value(tilde, &end.q, tau + dtau)?;
                return Ok(Some(0.5 * dtau * (g0 + g1)));
            };
            sum += w * monitor_value(tilde, &q, tau + at * dtau)?;
        }
        Ok(Some(0.5 * theta * dtau * sum))
    }
}

/// A physical time kept as a compensated sum.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clock {
    /// The time.
    pub(crate) t: f64,
    compensation: f64,
}

impl Clock {
    /// A clock at `t`.
    pub(crate) fn new(t: f64) -> Self {
        Clock {
            t,
            compensation: 0.0,
        }
    }

    /// t += dt (Kahan).
    pub(crate) fn add(&mut self, dt: f64) {
        let y = dt - self.compensation;
        let t = self.t + y;
        self.compensation = (t - self.t) - y;
        self.t = t;
    }
}

impl<L: Lagrangian<N>, M: Method<N> + Clone, N: Dimension> Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Solve over `span` with fixed steps Δτ = `options.h` in computational time τ, dt = g(q)
    /// dτ (see the module docs): the method runs on [`Reparametrized`] at the initial energy.
    /// The model must be autonomous and unforced; `options.adapt` and `options.tol` are not
    /// used (the steps follow from Δτ and the monitor), `options.run` gives the divergence
    /// limit (recovery is not available: a failed τ-step ends the run). `observer` sees the
    /// physical point after every τ-step. [`Solution::adaptivity`] reports the physical step
    /// sizes. With the [`crate::model::reparametrized::Potential`] monitor, Störmer–Verlet or
    /// one of its compositions and a constant-mass model, the run takes the explicit
    /// logarithmic-Hamiltonian splitting of [`crate::stepping::logh`] instead.
    pub fn try_solve_reparametrized<G: Monitor<N>, O: Observer<L, PhasePoint<N>>>(
        &self,
        monitor: &G,
        span: &Span,
        initial: Initial<N>,
        options: &SolveOptions,
        observer: &mut O,
    ) -> Result<Solution<Euclidean<N>>, RunFailure<Euclidean<N>>> {
        let mut observer: &mut dyn Observer<L, PhasePoint<N>> = observer;
        self.solve_in_tau(monitor, span, initial, options, &mut observer)
    }

    /// [`Integrator::try_solve_reparametrized`] with the observer behind a trait object
    /// (compiled once per model, method and monitor, as [`Integrator::try_solve`] is).
    fn solve_in_tau<G: Monitor<N>>(
        &self,
        monitor: &G,
        span: &Span,
        initial: Initial<N>,
        options: &SolveOptions,
        observer: &mut &mut dyn Observer<L, PhasePoint<N>>,
    ) -> Result<Solution<Euclidean<N>>, RunFailure<Euclidean<N>>> {
        // Tested on constants first: for a model or method they exclude, nothing below
        // (the method on the τ-Lagrangian, the splitting) is compiled.
        if L::TIME_DEPENDENT || L::FORCED {
            return Err(RunFailure::rejected(not_reparametrizable::<L, N>()));
        }
        if M::COMPOSES_VERLET
            && ConstantMass::<L, N>::DECLARED
            && monitor.logarithmic()
            && let Some(fractions) = self.method().verlet_fractions()
        {
            return self.try_solve_logh(fractions, span, initial, options, observer);
        }
        let rejected = RunFailure::rejected;
        span.validate().map_err(rejected)?;
        options.validate_reparametrized().map_err(rejected)?;
        let dtau = options.step().map_err(rejected)?;
        let model = self.model();
        let method = self.method();
        let start = self.start(span.t0, &initial).map_err(rejected)?;
        let first = self
            .phase_point(span.t0, &start.cursor.state, &start.guess)
            .map_err(rejected)?;
        let energy = model.energy(span.t0, &first.q, &first.v);
        let tilde = Reparametrized::new(model, monitor, energy).map_err(rejected)?;
        let g0 = monitor_value(&tilde, &first.q, 0.0).map_err(rejected)?;
        let inner: Integrator<_, M, Euclidean<N>> = Integrator::new(tilde, method.clone());
        let mut progress = inner
            .start(
                0.0,
                &Initial::Momentum {
                    q: first.q.clone(),
                    p: first.p.clone(),
                },
            )
            .map_err(rejected)?;
        progress.guess = &first.v * g0;
        let mut workspace = Method::workspace(method, inner.model(), dtau).map_err(rejected)?;
        let time = TimeRule::new(&Method::info(method)).map_err(rejected)?;
        let limit = options.run.divergence_limit;
        let points = method.points();
        let mut adaptivity = Adaptivity::default();
        let mut outputs: Vec<PhasePoint<N>> = Vec::with_capacity(span.output_times.len());
        let mut served = 0;
        if span.output_times[0] == span.t0 {
            outputs.push(first.clone());
            served = 1;
        }
        let mut clock = Clock::new(span.t0);
        let mut last = first.clone();
        let mut increment = progress.cursor.state.zeros_like();
        let failure = failure_after::<N>;
        // The physical point of a τ-state at time t (the inverse Legendre map of L̃, then
        // q̇ = q'/g).
        let physical = |t: f64,
                        tau: f64,
                        state: &State<N>,
                        guess: &OVector<f64, N>,
                        workspace: &M::Workspace|
         -> Result<(PhasePoint<N>, OVector<f64, N>), Error> {
            let point = inner.complete(Some(workspace), 0, tau, state, guess)?;
            let g = monitor_value(inner.model(), &point.q, tau)?;
            let physical = PhasePoint {
                t,
                q: point.q,
                v: &point.v / g,
                p: point.p,
            };
            Ok((physical, point.v))
        };
        if observer.wants(0) && observer.observe(model, 0, &first).is_break() {
            return Ok(Solution {
                points: outputs,
                last: first,
                statistics: progress.statistics,
                adaptivity,
                stopped: true,
                dense: None,
                events: Vec::new(),
                terminal: None,
            });
        }
        let mut k = 0usize;
        // The cursor at the start of the current step (its memory reused from step to step).
        let mut begin: Cursor<Euclidean<N>> = progress.cursor.clone();
        loop {
            options
                .budget(k, clock.t)
                .map_err(|error| failure(error, &last, progress.statistics))?;
            let tau = k as f64 * dtau;
            begin.state.assign(&progress.cursor.state);
            begin.compensation.assign(&progress.cursor.compensation);
            let step = |cursor: &mut Cursor<Euclidean<N>>,
                        workspace: &mut M::Workspace,
                        increment: &mut State<N>,
                        size: f64,
                        statistics: &mut Statistics|
             -> Result<f64, Error> {
                inner
                    .attempt(
                        method, workspace, increment, tau, size, cursor, limit, statistics,
                    )
                    .map_err(|failure: StepFailure| failure.at(k, clock.t))?;
                let dt = time
                    .elapsed(
                        method,
                        workspace,
                        inner.model(),
                        &begin.state,
                        &cursor.state,
                        size,
                        1.0,
                        tau,
                    )?
                    .unwrap_or(f64::NAN);
                if dt.is_finite() && dt > 0.0 {
                    Ok(dt)
                } else {
                    Err(Error::NonFinite {
                        what: format!("physical step {dt:e}"),
                        step: k,
                        t: clock.t,
                    })
                }
            };
            let mut size = dtau;
            let mut dt = step(
                &mut progress.cursor,
                &mut workspace,
                &mut increment,
                size,
                &mut progress.statistics,
            )
            .map_err(|error| failure(error, &last, progress.statistics))?;
            let finish = clock.t + dt >= span.t_end;
            // The output times inside this step, from its polynomial (on the last step those
            // before t_end, served before its Δτ is shortened to land on t_end).
            while let Some(&target) = span.output_times.get(served).filter(|&&target| {
                if finish {
                    target < span.t_end
                } else {
                    target <= clock.t + dt
                }
            }) {
                let point = self
                    .output_point(
                        &inner,
                        &time,
                        &workspace,
                        &begin.state,
                        clock.t,
                        tau,
                        size,
                        dt,
                        target,
                    )
                    .map_err(|error| failure(error, &last, progress.statistics))?;
                outputs.push(point);
                served += 1;
            }
            if finish {
                let residual = clock.t + dt - span.t_end;
                let slope = |size: f64, cursor: &Cursor<Euclidean<N>>| {
                    monitor_value(inner.model(), &cursor.state.q, tau + size)
                };
                let first = slope(size, &progress.cursor)
                    .map_err(|error| failure(error, &last, progress.statistics))?;
                size =
                    land_on_horizon(span.t_end, (size, residual, first), (k, clock.t), |retry| {
                        progress.cursor = begin.clone();
                        Method::restart(method, &mut workspace);
                        dt = step(
                            &mut progress.cursor,
                            &mut workspace,
                            &mut increment,
                            retry,
                            &mut progress.statistics,
                        )?;
                        Ok((clock.t + dt - span.t_end, slope(retry, &progress.cursor)?))
                    })
                    .map_err(|error| failure(error, &last, progress.statistics))?;
            }
            clock.add(dt);
            if finish {
                clock.t = span.t_end;
            }
            k += 1;
            progress.statistics.steps = k;
            adaptivity.record(dt, points);
            let wants = observer.wants(k);
            if wants || finish {
                (last, progress.guess) = physical(
                    clock.t,
                    tau + size,
                    &progress.cursor.state,
                    &progress.guess,
                    &workspace,
                )
                .map_err(|error| failure(error, &last, progress.statistics))?;
                if wants && observer.observe(model, k, &last).is_break() {
                    return Ok(Solution {
                        points: outputs,
                        last,
                        statistics: progress.statistics,
                        adaptivity,
                        stopped: !finish,
                        dense: None,
                        events: Vec::new(),
                        terminal: None,
                    });
                }
            }
            if finish {
                if served < span.output_times.len() {
                    outputs.push(last.clone());
                }
                return Ok(Solution {
                    points: outputs,
                    last,
                    statistics: progress.statistics,
                    adaptivity,
                    stopped: false,
                    dense: None,
                    events: Vec::new(),
                    terminal: None,
                });
            }
        }
    }

    /// The physical point at `target` ∈ (t, t + dt] inside the τ-step of size `size` from
    /// `start` at (τ, t): σ solves t + ∫₀^σ g = target by Newton's method, then the step
    /// polynomial at σ gives (q, q'), and p = ∂L̃/∂q'.
    #[allow(clippy::too_many_arguments)]
    fn output_point<G: Monitor<N>>(
        &self,
        inner: &Integrator<Reparametrized<'_, L, G>, M, Euclidean<N>>,
        time: &TimeRule,
        workspace: &M::Workspace,
        start: &State<N>,
        t: f64,
        tau: f64,
        size: f64,
        dt: f64,
        target: f64,
    ) -> Result<PhasePoint<N>, Error> {
        let method = self.method();
        let no_polynomial = || {
            Error::invalid(
                "output_times",
                format!(
                    "{target:?} lies inside a step, and {} has no step polynomial to read it \
                     from: ask for output at the ends of the span",
                    Method::info(method).name
                ),
            )
        };
        let mut theta = ((target - t) / dt).clamp(0.0, 1.0);
        for _ in 0..TIME_NEWTON_ITERATIONS {
            let elapsed = time
                .elapsed(
                    method,
                    workspace,
                    inner.model(),
                    start,
                    start,
                    size,
                    theta,
                    tau,
                )?
                .ok_or_else(no_polynomial)?;
            let residual = t + elapsed - target;
            if residual.abs() <= 4.0 * f64::EPSILON * target.abs().max(1.0) {
                break;
            }
            let (q, _) = method
                .dense_output(workspace, start, size, theta)
                .ok_or_else(no_polynomial)?;
            let g = monitor_value(inner.model(), &q, tau + theta * size)?;
            theta = (theta - residual / (g * size)).clamp(0.0, 1.0);
        }
        let (q, w) = method
            .dense_output(workspace, start, size, theta)
            .ok_or_else(no_polynomial)?;
        let g = monitor_value(inner.model(), &q, tau + theta * size)?;
        let p = inner.model().momentum(0.0, &q, &w);
        Ok(PhasePoint {
            t: target,
            q,
            v: w / g,
            p,
        })
    }
}

/// [`Integrator::try_solve_reparametrized`] for `model` and `method` without observers.
///
/// ```
/// use nalgebra::{SVector, U2};
/// use svi::model::reparametrized::Sundman;
/// use svi::solve::{SolveOptions, Span};
/// use svi::stepping::reparam::solve_reparametrized;
/// use svi::{Initial, Lagrangian, Scalar, Svi};
///
/// /// Kepler: L = |v|²/2 + 1/|q|, an orbit of eccentricity 0.9 from its pericentre.
/// struct Kepler;
/// impl Lagrangian<U2> for Kepler {
///     const TIME_DEPENDENT: bool = false;
///     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
///         v.dot(v) * 0.5 + q.dot(q).sqrt().recip()
///     }
/// }
/// let initial = Initial::Velocity {
///     q: SVector::from([0.1, 0.0]),
///     v: SVector::from([0.0, 19f64.sqrt()]),
/// };
/// let span = Span::new(0.0, std::f64::consts::TAU);
/// let options = SolveOptions::fixed_step(0.05);
/// let solution = solve_reparametrized(Kepler, Svi::new(5), Sundman { alpha: 1.5 }, &span, initial, &options)?;
/// // Back at the pericentre after one period.
/// assert!((solution.last.q - SVector::from([0.1, 0.0])).norm() < 1e-6);
/// # Ok::<(), svi::Error>(())
/// ```
pub fn solve_reparametrized<L: Lagrangian<N>, M: Method<N> + Clone, G: Monitor<N>, N: Dimension>(
    model: L,
    method: M,
    monitor: G,
    span: &Span,
    initial: Initial<N>,
    options: &SolveOptions,
) -> Result<Solution<Euclidean<N>>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    Integrator::new(model, method)
        .try_solve_reparametrized(&monitor, span, initial, options, &mut ())
        .map_err(|failure| failure.error)
}
