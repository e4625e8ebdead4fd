//! Symplectic-energy-momentum variational integrators (Kane, Marsden & Ortiz 1999; Leok,
//! *Generalized Variational Integrators*, §5.2.1 and §5.5): the step size as an unknown,
//! fixed by discrete energy conservation.
//!
//! # The equations
//! Let the time step h_k be a degree of freedom of the discrete action next to the
//! configurations, S_d = Σ_k L_d(q_k, q_{k+1}, h_k), with the Galerkin discrete Lagrangian of
//! SVI: L_d = h Σ_μ b_μ L(q(c_μ h), q̇(c_μ h)) on the step polynomial through s + 1
//! Chebyshev–Gauss–Lobatto nodes, interior nodes stationary (§5.5). Varying the node times as
//! well as the nodes gives, besides the discrete Euler–Lagrange equation
//! D₂L_d(q_{k−1}, q_k, h_{k−1}) + D₁L_d(q_k, q_{k+1}, h_k) = 0, the discrete energy equation
//!
//! E_d(q_k, q_{k+1}, h_k) = E_d(q_{k−1}, q_k, h_{k−1}),  E_d = −∂L_d/∂h
//!
//! (the multipliers ω_k of §5.2.1 eliminated). With the nodes held fixed,
//! −∂L_d/∂h = Σ_μ b_μ (p_μ·q̇_μ − L_μ), the quadrature average of the energy along the step
//! polynomial ([`crate::method::step::Step::discrete_energy`]); the interior nodes are
//! stationary, so the derivative of the reduced L_d is the same. In position–momentum form a
//! step solves p_k = −D₁L_d(q_k, q_{k+1}, h_k) (SVI's stage equations at a given h) and the
//! scalar equation
//!
//! F(h) = E_d(q_k, q_{k+1}(h), h) − E* = 0
//!
//! for h, where E* is the discrete energy of the first step, taken with the user's step h₀
//! (Kane et al.: the first step sets the level). With 2 points and the midpoint rule this is
//! the second-order integrator of Kane, Marsden & Ortiz; with s + 1 points and m Gauss points
//! its order-2s generalisation of §5.5. The map (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) with the
//! energy-fitted h is symplectic on each energy surface, conserves the Noether momenta of
//! L_d's symmetries and conserves E_d exactly: steps are chosen by the dynamics (shorter where
//! the local energy error of a fixed step would grow, as near a pericentre).
//!
//! # Solving for h
//! F is evaluated by taking the step: SVI solves its stage equations at the trial h and the
//! step polynomial gives E_d. The secant method starts at the previous step's h and 1.1 h, and
//! stops when |F| reaches the round-off level 16 ε max(1, |E*|) or the update of h falls below
//! 16 ε h. It is kept inside [h_prev · `max_shrink`, h_prev · `max_growth`] (and the solve's
//! `min_step`, by default 10⁻⁶ h₀, and `max_step`); a step that would have to fall to
//! `min_step` ends the run with [`Error::StepSizeTooSmall`] (the energy equation lost its
//! root, and the steps would crawl).
//!
//! # Where F has no root
//! Near turning points the energy equation may have no solution (§5.5, "Solvability of the
//! Energy Equation"; Kane et al. 1999; Lew et al. 2004): the secant leaves the bracket or does
//! not converge. The step then takes the h that minimises F(h)² on the bracket (Brent's
//! method, argmin's [`BrentOpt`]): the run goes on with a small energy error in that step, and
//! the step is counted in [`Adaptivity::unmet`]. Every trial step counts in
//! [`Statistics::steps`](super::run::Statistics) and the discarded ones in
//! [`Adaptivity::rejected`].
//!
//! # The last step
//! The step that reaches the end of the span is cut to land on it and is not energy-fitted
//! (its energy error is that of one SVI step of that size).

use crate::error::Error;
use crate::method::space::{Space, StepState};
use crate::method::step::Step;
use crate::stepping::observer::Observer;
use crate::stepping::outputs::Outputs;
use crate::stepping::run::{Cursor, Integrator, Progress, RunFailure};
use crate::stepping::solve::{Adaptivity, SolveOptions, Span};
use argmin::core::{CostFunction, Executor};
use argmin::solver::brent::BrentOpt;
use std::cell::RefCell;

/// Secant iterations on h before the minimisation takes over.
const SECANT_ITERATIONS: usize = 16;

/// Iterations of Brent's minimisation of F(h)².
const BRENT_ITERATIONS: u64 = 60;

/// The trial steps of one energy-fitted step: from `begin` at `t`, each trial restarts the
/// method (its warm start belongs to the previous trial) and returns F(h) = E_d − E*.
struct Trials<'a, L, M: Step<L, S>, S: Space> {
    integrator: &'a Integrator<L, M, S>,
    workspace: &'a mut M::Workspace,
    increment: &'a mut S::State,
    progress: &'a mut Progress<S>,
    t: f64,
    options: &'a SolveOptions,
    /// The size of the last successful trial and its end (the step the workspace holds).
    last: Option<(f64, Cursor<S>)>,
    /// Whether a trial was taken (the next one restarts the method).
    tried: bool,
}

impl<L, M: Step<L, S> + Clone, S: Space> Trials<'_, L, M, S> {
    /// Take the step of size `h` and return its discrete energy.
    fn energy(&mut self, h: f64) -> Result<f64, Error> {
        let method = self.integrator.method();
        if self.tried {
            method.restart(self.workspace);
        }
        self.tried = true;
        let next = self.integrator.trial(
            method,
            self.workspace,
            self.increment,
            self.t,
            h,
            &self.progress.cursor,
            self.options,
            &mut self.progress.statistics,
        )?;
        let energy = method
            .discrete_energy(
                self.integrator.model(),
                self.workspace,
                self.t,
                h,
                &self.progress.cursor.state,
            )
            .ok_or_else(|| {
                Error::invalid(
                    "adapt",
                    format!(
                        "adapt = sem needs a Galerkin method (svi) and an autonomous, unforced \
                         model, whose energy is conserved; {} on this model has no discrete \
                         energy",
                        method.info().name
                    ),
                )
            })?;
        self.last = Some((h, next));
        if energy.is_finite() {
            Ok(energy)
        } else {
            Err(Error::NonFinite {
                what: "discrete energy".into(),
                step: self.progress.statistics.steps.saturating_sub(1),
                t: self.t,
            })
        }
    }

    /// [`Trials::energy`], with a step whose solve does not converge, or whose state is not
    /// finite or diverges, giving NaN: a step size to stay away from, not the end of the run.
    fn failing_as_nan(&mut self, h: f64) -> Result<f64, Error> {
        match self.energy(h) {
            Err(
                Error::NonConvergence { .. } | Error::NonFinite { .. } | Error::Diverged { .. },
            ) => Ok(f64::NAN),
            other => other,
        }
    }

    /// The step of size `h`, taken again unless it was the last trial.
    fn take(&mut self, h: f64) -> Result<Cursor<S>, Error> {
        if self.last.as_ref().is_none_or(|(size, _)| *size != h) {
            self.energy(h)?;
        }
        let (_, next) = self.last.take().ok_or_else(|| {
            Error::invalid(
                "adapt",
                "sem: no trial step to accept (internal)".to_string(),
            )
        })?;
        Ok(next)
    }
}

/// F(h)² for argmin, over the trials of one step.
struct Squared<'a, 'b, L, M: Step<L, S>, S: Space> {
    trials: &'b RefCell<&'b mut Trials<'a, L, M, S>>,
    target: f64,
}

impl<L, M: Step<L, S> + Clone, S: Space> CostFunction for Squared<'_, '_, L, M, S> {
    type Param = f64;
    type Output = f64;

    /// A step that fails costs +∞ (Brent's method then stays away from it).
    fn cost(&self, h: &f64) -> Result<f64, argmin::core::Error> {
        let residual = self.trials.borrow_mut().failing_as_nan(*h)? - self.target;
        Ok(if residual.is_nan() {
            f64::INFINITY
        } else {
            residual * residual
        })
    }
}

/// How one energy-fitted step was found.
enum Fit {
    /// A root of F.
    Root(f64),
    /// No root in the bracket: the minimiser of F².
    Minimum(f64),
}

impl<L, M: Step<L, S> + Clone, S: Space> Integrator<L, M, S> {
    /// Symplectic-energy-momentum steps (see the module docs) from `progress` over `span`,
    /// the first of size `options.h`; output times served from each step's polynomial.
    pub(super) fn solve_sem<O: Observer<L, S::Point>>(
        &self,
        span: &Span,
        options: &SolveOptions,
        progress: &mut Progress<S>,
        outputs: &mut Outputs<'_, S>,
        observer: &mut O,
    ) -> Result<(Adaptivity, bool), RunFailure<S>> {
        let rejected = RunFailure::rejected;
        let h0 = options.step().map_err(rejected)?;
        let length = span.t_end - span.t0;
        // Steps shrinking a millionfold below the first mean the energy equation has lost
        // its root (the run would crawl): an error, unless the caller allows smaller ones.
        let min_step = options.min_step.unwrap_or(h0 * 1e-6);
        let max_step = options.max_step.unwrap_or(length);
        let method = self.method();
        let mut workspace = method.workspace(self.model(), h0).map_err(rejected)?;
        let mut increment = progress.cursor.state.zeros_like();
        let points = method.points();
        let mut adaptivity = Adaptivity::default();
        if observer.wants(0) && self.observe(0, None, progress, observer)? {
            return Ok((adaptivity, true));
        }
        let mut target = None;
        // dF/dh of the last step's secant.
        let mut slope = None;
        // The fitted size of the step before the last (the first step's h₀ is not fitted).
        let mut previous: Option<f64> = None;
        let mut h = h0;
        let mut k = 0;
        while progress.t < span.t_end {
            let t = progress.t;
            let remaining = span.t_end - t;
            let mut trials = Trials {
                integrator: self,
                workspace: &mut workspace,
                increment: &mut increment,
                progress,
                t,
                options,
                last: None,
                tried: false,
            };
            let found = match target {
                // The first step sets the level E*.
                None => trials.energy(h.min(remaining)).map(|energy| {
                    target = Some(energy);
                    Fit::Root(h.min(remaining))
                }),
                Some(target) => {
                    let bracket = (
                        (h * options.max_shrink).max(min_step),
                        (h * options.max_growth).min(max_step),
                    );
                    // The first trial continues the trend of the last two steps.
                    let guess =
                        previous.map_or(h, |before| (2.0 * h - before).clamp(bracket.0, bracket.1));
                    fit_step(&mut trials, target, guess, bracket, &mut slope)
                }
            };
            let fit = match found {
                Ok(fit) => fit,
                // No discrete energy (the method or the model): bad input, not a failed run.
                Err(error @ Error::InvalidParameter { .. }) => {
                    return Err(RunFailure::rejected(error));
                }
                Err(error) => return Err(self.failure(error, trials.progress, false)),
            };
            let fitted = match fit {
                Fit::Root(size) => size,
                Fit::Minimum(size) => {
                    adaptivity.unmet += 1;
                    size
                }
            };
            if fitted <= min_step && fitted < remaining {
                let error = Error::StepSizeTooSmall {
                    cause: "the discrete energy equation fits no larger step",
                    t,
                    h: fitted,
                    min_step,
                    rejections: progress.statistics.steps - adaptivity.accepted,
                };
                return Err(self.failure(error, progress, false));
            }
            // The step that would pass the end is cut to land on it.
            let size = if fitted >= remaining {
                remaining
            } else {
                fitted
            };
            let next = match trials.take(size) {
                Ok(next) => next,
                Err(error) => return Err(self.failure(error, trials.progress, false)),
            };
            let end_time = if size == remaining {
                span.t_end
            } else {
                t + size
            };
            if let Err(error) = self.emit(
                method,
                &workspace,
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
            adaptivity.record(size, points);
            adaptivity.rejected = progress.statistics.steps - adaptivity.accepted;
            progress.cursor = next;
            progress.t = end_time;
            k += 1;
            if target.is_some() && k > 1 {
                previous = Some(h);
            }
            h = fitted;
            if outputs.terminal.is_some() {
                return Ok((adaptivity, false));
            }
            if observer.wants(k) && self.observe(k, Some(&workspace), progress, observer)? {
                return Ok((adaptivity, progress.t < span.t_end));
            }
        }
        Ok((adaptivity, false))
    }
}

/// Solve F(h) = 0 by the secant method from `h` inside `bracket`; where it fails, the
/// minimiser of F² on the bracket (see the module docs).
fn fit_step<L, M: Step<L, S> + Clone, S: Space>(
    trials: &mut Trials<'_, L, M, S>,
    target: f64,
    h: f64,
    (lower, upper): (f64, f64),
    slope: &mut Option<f64>,
) -> Result<Fit, Error> {
    let tolerance = 16.0 * f64::EPSILON * target.abs().max(1.0);
    let mut upper = upper;
    let (mut a, mut fa) = (h, trials.failing_as_nan(h)? - target);
    if fa.abs() <= tolerance {
        return Ok(Fit::Root(a));
    }
    if fa.is_nan() {
        // The step fails at the guess: minimise below it.
        return minimise(trials, target, h, (lower, h.max(lower)), tolerance);
    }
    // The second point from the last step's slope F'(h) (F changes slowly from step to
    // step), else 10 % away.
    let mut b = match *slope {
        Some(slope) if slope.is_finite() && slope != 0.0 => (h - fa / slope).clamp(lower, upper),
        _ => (1.1 * h).min(upper),
    };
    if b == a {
        b = if a > lower { 0.9 * h } else { 1.1 * h };
    }
    let mut fb = trials.failing_as_nan(b)? - target;
    for _ in 0..SECANT_ITERATIONS {
        if fb.is_nan() {
            // The step fails at b: no larger step is tried.
            upper = upper.min(b).max(lower);
            break;
        }
        *slope = Some((fb - fa) / (b - a));
        if fb.abs() <= tolerance {
            return Ok(Fit::Root(b));
        }
        let next = b - fb * (b - a) / (fb - fa);
        if !(next.is_finite() && next >= lower && next <= upper) {
            break;
        }
        if (next - b).abs() <= 16.0 * f64::EPSILON * b {
            return Ok(Fit::Root(b));
        }
        (a, fa) = (b, fb);
        b = next;
        fb = trials.failing_as_nan(b)? - target;
    }
    *slope = None;
    minimise(trials, target, h, (lower, upper), tolerance)
}

/// The minimiser of F(h)² on [lower, upper] by Brent's method: a root if F vanishes there
/// to within `tolerance`, else the fallback of the module docs.
fn minimise<L, M: Step<L, S> + Clone, S: Space>(
    trials: &mut Trials<'_, L, M, S>,
    target: f64,
    h: f64,
    (lower, upper): (f64, f64),
    tolerance: f64,
) -> Result<Fit, Error> {
    let cell = RefCell::new(trials);
    let problem = Squared {
        trials: &cell,
        target,
    };
    let solver =
        BrentOpt::new(lower, upper).set_tolerance(f64::EPSILON.sqrt(), 16.0 * f64::EPSILON * h);
    let result = Executor::new(problem, solver)
        .configure(|state| state.max_iters(BRENT_ITERATIONS))
        .run()
        .map_err(|error| match error.downcast::<Error>() {
            Ok(error) => error,
            Err(other) => Error::invalid(
                "adapt",
                format!(
                    "sem: minimising the energy error on [{lower:e}, {upper:e}] failed: {other}"
                ),
            ),
        })?;
    let best = result.state.best_param.unwrap_or(h);
    // A root the secant missed (it left the bracket on the way) is a root all the same.
    if result.state.best_cost.sqrt() <= tolerance {
        Ok(Fit::Root(best))
    } else {
        Ok(Fit::Minimum(best))
    }
}
