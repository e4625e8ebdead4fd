//! The stepping loop for rigid bodies on SO(3).
//!
//! [`RigidBodyIntegrator::run`] is [`crate::Integrator::run`] on the group: it validates its
//! inputs (finite values, an orthogonal initial attitude, a positive step, the model's
//! G-invariance declaration), keeps t_k = t₀ + k·h, shortens the last step to land on the
//! horizon, adds the increments R_k(F − I) and μ_{k+1} − μ_k with compensated (Kahan)
//! summation, drives [`Observer`]s of [`RigidPoint`]s, and attaches the step index and time to failures.
//! The attitude is never re-orthonormalised: its orthogonality comes from an accurate
//! exponential and compensated summation, and [`crate::stepping::rigid_observer::OrthogonalityError`] measures it.

use crate::error::{require_finite, require_finite_entries, require_positive};
use crate::method::StepReport;
use crate::method::lie_svi::{LieSvi, LieWorkspace, RigidState};
use crate::model::rigid_body::{RigidBodyExt, RigidBodyLagrangian};
use crate::model::so3::{Matrix3, Vector3, orthogonality_error};
use crate::stepping::grid::{grid_step, step_count};
use crate::stepping::observer::Observer;
use crate::stepping::rigid_observer::RigidPoint;
use crate::{Error, Statistics};
use nalgebra::SMatrix;
use std::ops::ControlFlow;

/// Largest ‖R₀ᵀR₀ − I‖ accepted for an initial attitude.
pub const ORTHOGONALITY_TOLERANCE: f64 = 1e-10;

/// An initial rigid-body state: attitude with either angular velocity or momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigidInitial {
    /// (R₀, Ω₀).
    Velocity {
        /// Attitude.
        r: Matrix3<f64>,
        /// Body angular velocity.
        omega: Vector3<f64>,
    },
    /// (R₀, Π₀).
    Momentum {
        /// Attitude.
        r: Matrix3<f64>,
        /// Body angular momentum.
        momentum: Vector3<f64>,
    },
}

/// The result of a rigid-body run.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidRun {
    /// The last point reached.
    pub last: RigidPoint,
    /// The last state in the method's coordinates (R, Π).
    pub state: RigidState,
    /// Work done.
    pub statistics: Statistics,
    /// Whether an observer stopped the run before the horizon.
    pub stopped: bool,
}

/// A rigid-body model and a [`LieSvi`] method, ready to run.
#[derive(Debug, Clone)]
pub struct RigidBodyIntegrator<L> {
    model: L,
    method: LieSvi,
}

impl<L: RigidBodyLagrangian> RigidBodyIntegrator<L> {
    /// Pair a model with a method.
    pub fn new(model: L, method: LieSvi) -> Self {
        RigidBodyIntegrator { model, method }
    }

    /// The model.
    pub fn model(&self) -> &L {
        &self.model
    }

    /// The method.
    pub fn method(&self) -> &LieSvi {
        &self.method
    }

    /// Complete a state to a point (Ω from Π by the inverse Legendre map started at
    /// `guess`).
    pub fn point(
        &self,
        t: f64,
        state: &RigidState,
        guess: &Vector3<f64>,
    ) -> Result<RigidPoint, Error> {
        let omega = self
            .model
            .velocity(&state.r, &state.momentum, guess)
            .map_err(|error| match error {
                Error::LegendreMap {
                    iterations,
                    residual,
                    ..
                } => Error::LegendreMap {
                    t,
                    iterations,
                    residual,
                },
                other => other,
            })?;
        Ok(RigidPoint {
            t,
            r: state.r,
            omega,
            momentum: state.momentum,
        })
    }

    /// Validate an initial condition and convert it to (R₀, Π₀).
    pub fn initial_state(&self, initial: &RigidInitial) -> Result<RigidState, Error> {
        let (r, second, name) = match initial {
            RigidInitial::Velocity { r, omega } => (r, omega, "initial angular velocity"),
            RigidInitial::Momentum { r, momentum } => (r, momentum, "initial angular momentum"),
        };
        require_finite_entries("initial attitude", r)?;
        require_finite_entries(name, second)?;
        let error = orthogonality_error(r);
        if error > ORTHOGONALITY_TOLERANCE || r.determinant() <= 0.0 {
            return Err(Error::invalid(
                "initial attitude",
                format!(
                    "not a rotation: ‖RᵀR − I‖ = {error:e}, det R = {}",
                    r.determinant()
                ),
            ));
        }
        let momentum = match initial {
            RigidInitial::Momentum { momentum, .. } => *momentum,
            RigidInitial::Velocity { r, omega } => self.model.momentum(r, omega),
        };
        let state = RigidState { r: *r, momentum };
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: 0.0,
            });
        }
        Ok(state)
    }

    /// Check a G-invariance declaration at the initial state: L(R, Ω) = L(I, Ω) and a zero
    /// configuration gradient.
    fn check_invariance(&self, t0: f64, state: &RigidState) -> Result<(), Error> {
        if !L::G_INVARIANT {
            return Ok(());
        }
        let omega = self.point(t0, state, &Vector3::zeros())?.omega;
        let here = self.model.value(&state.r, &omega);
        let identity = self.model.value(&Matrix3::identity(), &omega);
        let torque = self.model.torque(&state.r, &omega).amax();
        let scale = 1.0 + here.abs() + state.momentum.amax() * (1.0 + omega.amax());
        if (here - identity).abs() > 1e-12 * scale || torque > 1e-12 * scale {
            return Err(Error::invalid(
                "G_INVARIANT",
                format!(
                    "the model declares L(R, Ω) = L(I, Ω), but the values differ by {:e} and \
                     the configuration gradient is {torque:e}",
                    (here - identity).abs()
                ),
            ));
        }
        Ok(())
    }

    /// A workspace for steps of size `h` (for driving [`LieSvi::step`] directly).
    pub fn workspace(&self, h: f64) -> Result<LieWorkspace, Error> {
        self.method.workspace::<L>(h)
    }

    /// A fresh workspace for one step of size `h` from `state`, after checking both.
    fn cold_workspace(&self, state: &RigidState, h: f64) -> Result<LieWorkspace, Error> {
        require_positive("h", h)?;
        if !state.is_finite() {
            return Err(Error::NonFinite {
                what: "state".into(),
                step: 0,
                t: 0.0,
            });
        }
        self.workspace(h)
    }

    /// One step of size `h` from `state` with a fresh workspace (cold start), returning the
    /// new state without compensated summation: for tangent maps by finite differences and
    /// for tests.
    pub fn step(&self, state: &RigidState, h: f64) -> Result<(RigidState, StepReport), Error> {
        let mut workspace = self.cold_workspace(state, h)?;
        let mut increment = RigidState::zeros();
        let report = self
            .method
            .step(&self.model, &mut workspace, h, state, &mut increment)
            .map_err(|failure| failure.at(0, 0.0))?;
        Ok((state.plus(&increment), report))
    }

    /// One step of size `h` from `state` (fresh workspace) and its exact Jacobian in the
    /// canonical coordinates (η, p) of T*SO(3) about the input and the output (see
    /// [`LieSvi::tangent_map`]): a symplectic step satisfies ΦᵀJΦ = J with
    /// J = [[0, I], [−I, 0]].
    pub fn tangent_map(
        &self,
        state: &RigidState,
        h: f64,
    ) -> Result<(RigidState, SMatrix<f64, 6, 6>), Error> {
        let mut workspace = self.cold_workspace(state, h)?;
        let (increment, tangent) = self
            .method
            .tangent_map(&self.model, &mut workspace, h, state)
            .map_err(|failure| failure.at(0, 0.0))?;
        Ok((state.plus(&increment), tangent))
    }

    /// Integrate from `t0` to `t_end` with step `h`, reporting to `observer`.
    pub fn run<O: Observer<L, RigidPoint>>(
        &self,
        t0: f64,
        initial: RigidInitial,
        h: f64,
        t_end: f64,
        observer: &mut O,
    ) -> Result<RigidRun, Error> {
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
        let mut workspace = self.workspace(h)?;
        let mut state = self.initial_state(&initial)?;
        self.check_invariance(t0, &state)?;
        let mut guess = match initial {
            RigidInitial::Velocity { omega, .. } => omega,
            RigidInitial::Momentum { .. } => Vector3::zeros(),
        };
        let mut statistics = Statistics::default();
        let mut stopped = false;
        if observer.wants(0) {
            let point = self.point(t0, &state, &guess)?;
            guess = point.omega;
            stopped = observer.observe(&self.model, 0, &point).is_break();
        }
        let mut compensation = RigidState::zeros();
        let mut increment = RigidState::zeros();
        let mut t = t0;
        for k in 0..steps {
            if stopped {
                break;
            }
            let (start, step_size, end) = grid_step(t0, t_end, h, steps, k);
            t = start;
            let report = self
                .method
                .step(
                    &self.model,
                    &mut workspace,
                    step_size,
                    &state,
                    &mut increment,
                )
                .map_err(|failure| failure.at(k, t))?;
            state.add_compensated(&mut compensation, &increment);
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
            t = end;
            if observer.wants(k + 1) {
                let point = self.point(t, &state, &guess)?;
                guess = point.omega;
                if let ControlFlow::Break(()) = observer.observe(&self.model, k + 1, &point) {
                    stopped = k + 1 < steps;
                    break;
                }
            }
        }
        let last = self.point(t, &state, &guess)?;
        Ok(RigidRun {
            last,
            state,
            statistics,
            stopped,
        })
    }
}
