//! The one stepping loop, shared by every method.
//!
//! [`Integrator::run`] validates its inputs, converts the initial state to the method's
//! coordinates, and advances with fixed steps: times are t_k = t_0 + k·h (never accumulated
//! with `t += h`), the last step is shortened to land on the horizon when (t_end − t_0)/h is
//! not an integer, and the increments returned by the method are added with compensated
//! (Kahan) summation so long runs keep their accuracy. Observers see the initial point and
//! every step they ask for; a run that observes nothing completes no phase points and
//! computes no diagnostics. Failures come back with the step index and time.

use crate::derived::LagrangianExt;
use crate::error::{require_finite, require_positive};
use crate::method::{Coordinates, PhasePoint, State, TangentMap};
use crate::observer::Observer;
use crate::{Error, Lagrangian, Method, Structure};
use nalgebra::SVector;
use std::ops::ControlFlow;

/// Totals of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Statistics {
    /// Steps taken.
    pub steps: usize,
    /// Nonlinear (Newton) iterations, summed over all steps.
    pub iterations: usize,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: usize,
}

/// The result of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Run<const N: usize> {
    /// The last state reached, completed to (t, q, q̇, p).
    pub last: PhasePoint<N>,
    /// The last state in the method's own coordinates.
    pub state: State<N>,
    /// Work done.
    pub statistics: Statistics,
    /// Whether an observer stopped the run before the horizon.
    pub stopped: bool,
}

/// An initial state: configuration with either velocity or momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Initial<const N: usize> {
    /// (q0, q̇0).
    Velocity {
        /// Configuration.
        q: SVector<f64, N>,
        /// Velocity.
        v: SVector<f64, N>,
    },
    /// (q0, p0).
    Momentum {
        /// Configuration.
        q: SVector<f64, N>,
        /// Momentum.
        p: SVector<f64, N>,
    },
}

/// A model and a method, ready to run.
#[derive(Debug, Clone)]
pub struct Integrator<L, M, const N: usize> {
    model: L,
    method: M,
}

impl<L: Lagrangian<N>, M: Method<N>, const N: usize> Integrator<L, M, N> {
    /// Pair a model with a method.
    pub fn new(model: L, method: M) -> Self {
        Integrator { model, method }
    }

    /// The model.
    pub fn model(&self) -> &L {
        &self.model
    }

    /// The method.
    pub fn method(&self) -> &M {
        &self.method
    }

    /// Complete a method state to a phase point (q̇ from p by the inverse Legendre map, or
    /// p from q̇), with `guess` as the Newton start of the inverse Legendre map.
    pub fn phase_point(
        &self,
        t: f64,
        state: &State<N>,
        guess: &SVector<f64, N>,
    ) -> Result<PhasePoint<N>, Error> {
        let (v, p) = match self.method.info().coordinates {
            Coordinates::Momentum => (self.model.velocity(t, &state.q, &state.y, guess)?, state.y),
            Coordinates::Velocity => (state.y, self.model.momentum(t, &state.q, &state.y)),
        };
        Ok(PhasePoint {
            t,
            q: state.q,
            v,
            p,
        })
    }

    /// The method state for an initial condition.
    pub fn initial_state(&self, t0: f64, initial: &Initial<N>) -> Result<State<N>, Error> {
        let (q, second, name) = match initial {
            Initial::Velocity { q, v } => (q, v, "initial velocity"),
            Initial::Momentum { q, p } => (q, p, "initial momentum"),
        };
        for (i, x) in q.iter().enumerate() {
            require_finite(&format!("initial position[{i}]"), *x)?;
        }
        for (i, x) in second.iter().enumerate() {
            require_finite(&format!("{name}[{i}]"), *x)?;
        }
        let y = match (self.method.info().coordinates, initial) {
            (Coordinates::Momentum, Initial::Momentum { p, .. }) => *p,
            (Coordinates::Velocity, Initial::Velocity { v, .. }) => *v,
            (Coordinates::Momentum, Initial::Velocity { q, v }) => self.model.momentum(t0, q, v),
            (Coordinates::Velocity, Initial::Momentum { q, p }) => {
                self.model.velocity(t0, q, p, p)?
            }
        };
        let state = State { q: *q, y };
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: t0,
            });
        }
        Ok(state)
    }

    /// Check a [`Structure::ConstantMass`] declaration at the initial state: L_qv must vanish
    /// and L_vv must not change with q̇ (a necessary condition, checked once per run).
    pub(crate) fn check_structure(&self, t: f64, state: &State<N>) -> Result<(), Error> {
        if L::STRUCTURE != Structure::ConstantMass {
            return Ok(());
        }
        let shifted = state.y * 2.0 + SVector::repeat(1.0);
        let first = self.model.second_derivatives(t, &state.q, &state.y);
        let second = self.model.second_derivatives(t, &state.q, &shifted);
        let scale = 1.0 + first.vv.amax() + first.qq.amax();
        let coupling = first.qv.amax().max(second.qv.amax());
        let change = (first.vv - second.vv).amax();
        if coupling > 1e-12 * scale || change > 1e-12 * scale {
            return Err(Error::invalid(
                "structure",
                format!(
                    "the model declares a constant mass matrix, but ∂²L/∂q∂q̇ = {coupling:e} and \
                     ∂²L/∂q̇² changes by {change:e} with q̇"
                ),
            ));
        }
        Ok(())
    }

    /// Integrate from `t0` to `t_end` with step `h`, reporting to `observer`.
    pub fn run<O: Observer<L, N>>(
        &self,
        t0: f64,
        initial: Initial<N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        require_finite("t0", t0)?;
        require_finite("t_end", t_end)?;
        require_positive("h", h)?;
        if t_end <= t0 {
            return Err(Error::invalid(
                "t_end",
                format!("the horizon {t_end} is not after the start {t0}"),
            ));
        }
        let steps = step_count(t_end - t0, h)?;
        let mut workspace = self.method.workspace(&self.model, h)?;
        let mut state = self.initial_state(t0, &initial)?;
        self.check_structure(t0, &state)?;
        let mut guess = match initial {
            Initial::Velocity { v, .. } => v,
            Initial::Momentum { p, .. } => p,
        };
        let mut statistics = Statistics::default();
        let mut stopped = false;
        if observer.wants(0) {
            let point = self.phase_point(t0, &state, &guess)?;
            guess = point.v;
            stopped = observer.observe(&self.model, 0, &point).is_break();
        }
        let mut compensation = State::zeros();
        let mut increment = State::zeros();
        let mut t = t0;
        for k in 0..steps {
            if stopped {
                break;
            }
            t = t0 + k as f64 * h;
            let step_size = if k + 1 == steps { t_end - t } else { h };
            let report = self
                .method
                .step(
                    &self.model,
                    &mut workspace,
                    t,
                    step_size,
                    &state,
                    &mut increment,
                )
                .map_err(|failure| failure.at(k, t))?;
            compensated_add(&mut state.q, &mut compensation.q, &increment.q);
            compensated_add(&mut state.y, &mut compensation.y, &increment.y);
            if !state.is_finite() {
                return Err(Error::NonFinite {
                    what: "state".into(),
                    step: k,
                    t,
                });
            }
            statistics.steps += 1;
            statistics.iterations += report.iterations;
            statistics.evaluations += report.evaluations;
            t = if k + 1 == steps {
                t_end
            } else {
                t0 + (k + 1) as f64 * h
            };
            if observer.wants(k + 1) {
                let point = self.phase_point(t, &state, &guess)?;
                guess = point.v;
                if let ControlFlow::Break(()) = observer.observe(&self.model, k + 1, &point) {
                    stopped = k + 1 < steps;
                    break;
                }
            }
        }
        let last = self.phase_point(t, &state, &guess)?;
        Ok(Run {
            last,
            state,
            statistics,
            stopped,
        })
    }

    /// [`Integrator::run`] from (q0, q̇0).
    pub fn run_from_velocity<O: Observer<L, N>>(
        &self,
        t0: f64,
        q0: SVector<f64, N>,
        v0: SVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        self.run(t0, Initial::Velocity { q: q0, v: v0 }, h, t_end, observer)
    }

    /// [`Integrator::run`] from (q0, p0).
    pub fn run_from_momentum<O: Observer<L, N>>(
        &self,
        t0: f64,
        q0: SVector<f64, N>,
        p0: SVector<f64, N>,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<Run<N>, Error> {
        self.run(t0, Initial::Momentum { q: q0, p: p0 }, h, t_end, observer)
    }

    /// One step from `state` at time `t` with step `h`, and its exact Jacobian (the tangent
    /// map) with respect to the method's coordinates.
    pub fn tangent_map(
        &self,
        t: f64,
        state: &State<N>,
        h: f64,
    ) -> Result<(State<N>, TangentMap<N>), Error> {
        require_finite("t", t)?;
        require_positive("h", h)?;
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "state".into(),
                step: 0,
                t,
            });
        }
        let mut workspace = self.method.workspace(&self.model, h)?;
        let (increment, tangent) = self
            .method
            .tangent_map(&self.model, &mut workspace, t, h, state)
            .map_err(|failure| failure.at(0, t))?;
        let next = State {
            q: state.q + increment.q,
            y: state.y + increment.y,
        };
        Ok((next, tangent))
    }
}

/// Number of steps [`Integrator::run`] takes to cover `span` with steps of size at most `h`:
/// a span within round-off of a whole number of steps gets no extra sliver step, otherwise
/// the last step is shortened.
pub fn step_count(span: f64, h: f64) -> Result<usize, Error> {
    let ratio = span / h;
    if !ratio.is_finite() || ratio > 1e12 {
        return Err(Error::invalid(
            "h",
            format!("step {h} is too small for the span {span} (more than 10^12 steps)"),
        ));
    }
    let nearest = ratio.round();
    let count = if (ratio - nearest).abs() <= 1e-9 * ratio.max(1.0) {
        nearest
    } else {
        ratio.ceil()
    };
    Ok((count as usize).max(1))
}

/// Kahan-compensated `sum += increment`.
pub(crate) fn compensated_add<const N: usize>(
    sum: &mut SVector<f64, N>,
    compensation: &mut SVector<f64, N>,
    increment: &SVector<f64, N>,
) {
    for i in 0..N {
        let y = increment[i] - compensation[i];
        let t = sum[i] + y;
        compensation[i] = (t - sum[i]) - y;
        sum[i] = t;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_count_lands_on_the_horizon() {
        assert_eq!(step_count(100.0, 1.0).unwrap(), 100);
        assert_eq!(step_count(2000.0, 0.2).unwrap(), 10000);
        assert_eq!(step_count(1.0, 0.3).unwrap(), 4);
        assert_eq!(step_count(0.1, 1.0).unwrap(), 1);
        assert!(step_count(1.0, 1e-300).is_err());
    }

    #[test]
    fn compensated_summation_keeps_small_increments() {
        let mut sum = SVector::from([1.0]);
        let mut compensation = SVector::zeros();
        for _ in 0..1_000_000 {
            compensated_add(&mut sum, &mut compensation, &SVector::from([1e-16]));
        }
        assert!((sum[0] - (1.0 + 1e-10)).abs() < 1e-15);
    }
}
