//! Störmer–Verlet on runtime-sized ℝⁿ for constant-mass [`LocalLagrangian`]s: the explicit
//! kick–drift–kick form of [`crate::StormerVerlet`] (see its module for the discrete
//! equations), with ∂L/∂q assembled term by term in O(n).
//!
//! One gradient ∂L/∂q per step: the force at q_{k+1} is kept and reused as the force at q_k
//! of the next step (recognised by time and position, to within the rounding of the stepping
//! loop's compensated summation, as on ℝᴺ). The momentum increment is (h/2)(F_k + F_{k+1}).
//! Order 2, symmetric, symplectic; the step equals the fixed-size path's to round-off.

use crate::StormerVerlet;
use crate::error::{Error, StepFailure};
use crate::method::local::mass::MassInverse;
use crate::method::local::{LocalMethod, cold_velocity, constant_mass};
use crate::method::space::DynState;
use crate::method::{Coordinates, MethodInfo, StepReport};
use crate::model::local::{LocalLagrangian, LocalLagrangianExt};
use nalgebra::DVector;

/// Buffers of a Störmer–Verlet run on runtime-sized ℝⁿ.
#[derive(Debug, Clone)]
pub struct LocalVerletWorkspace {
    /// M⁻¹, from the first step.
    mass_inverse: Option<MassInverse>,
    /// ∂L/∂q at the end of the last step, and where: `cached_t`, `cached_q` (valid when
    /// `cached` is set).
    cached: bool,
    cached_t: f64,
    cached_q: DVector<f64>,
    cached_tolerance: f64,
    end_force: DVector<f64>,
    /// ∂L/∂q at the start of the step.
    start_force: DVector<f64>,
    /// The half-step momentum, then the velocity M⁻¹p_{k+½}.
    half: DVector<f64>,
    velocity: DVector<f64>,
}

impl LocalMethod for StormerVerlet {
    type Workspace = LocalVerletWorkspace;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "verlet",
            order: 2,
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
        }
    }

    fn local_workspace<L: LocalLagrangian>(
        &self,
        model: &L,
        _h: f64,
    ) -> Result<LocalVerletWorkspace, Error> {
        let n = model.dimension();
        Ok(LocalVerletWorkspace {
            mass_inverse: None,
            cached: false,
            cached_t: f64::NAN,
            cached_q: DVector::zeros(n),
            cached_tolerance: 0.0,
            end_force: DVector::zeros(n),
            start_force: DVector::zeros(n),
            half: DVector::zeros(n),
            velocity: DVector::zeros(n),
        })
    }

    fn local_step<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &mut LocalVerletWorkspace,
        t: f64,
        h: f64,
        state: &DynState,
        increment: &mut DynState,
    ) -> Result<StepReport, StepFailure> {
        if workspace.mass_inverse.is_none() {
            let inverse = constant_mass(model, "verlet", t, &state.q).map_err(|_| {
                StepFailure::Unsupported {
                    option: "structure",
                    reason: "verlet on a runtime-dimension model needs a constant, invertible \
                             mass matrix",
                }
            })?;
            workspace.mass_inverse = Some(inverse);
        }
        let LocalVerletWorkspace {
            mass_inverse: Some(mass_inverse),
            cached,
            cached_t,
            cached_q,
            cached_tolerance,
            end_force,
            start_force,
            half,
            velocity,
        } = workspace
        else {
            return Err(StepFailure::SingularMatrix);
        };
        let dt = 0.5 * h;
        let mut evaluations = 1;
        let continues = *cached
            && (!L::TIME_DEPENDENT
                || (*cached_t - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(cached_t.abs()))
            && state
                .q
                .as_slice()
                .iter()
                .zip(cached_q.as_slice())
                .fold(true, |all, (a, b)| {
                    all & ((a - b).abs() <= *cached_tolerance)
                });
        if continues {
            std::mem::swap(start_force, end_force);
        } else {
            evaluations += 1;
            // ∂L/∂q of a constant-mass model does not depend on q̇.
            model.force_into(t, &state.q, &state.y, start_force);
        }
        // Kick, drift (loops over slices: nalgebra's element iterators do not vectorise).
        for ((k, p), f) in half
            .as_mut_slice()
            .iter_mut()
            .zip(state.y.as_slice())
            .zip(start_force.as_slice())
        {
            *k = p + dt * f;
        }
        mass_inverse.apply_into(half, velocity);
        let mut extent = 0.0f64;
        for (((d, e), q), v) in increment
            .q
            .as_mut_slice()
            .iter_mut()
            .zip(cached_q.as_mut_slice())
            .zip(state.q.as_slice())
            .zip(velocity.as_slice())
        {
            *d = h * v;
            *e = q + *d;
            let size = q.abs().max(e.abs());
            extent = if size > extent { size } else { extent };
        }
        let end_t = t + h;
        // Kick at the end.
        model.force_into(end_t, cached_q, velocity, end_force);
        for ((d, a), b) in increment
            .y
            .as_mut_slice()
            .iter_mut()
            .zip(start_force.as_slice())
            .zip(end_force.as_slice())
        {
            *d = dt * (a + b);
        }
        *cached = true;
        *cached_t = end_t;
        *cached_tolerance = 4.0 * f64::EPSILON * extent;
        Ok(StepReport {
            evaluations,
            ..StepReport::default()
        })
    }

    fn local_restart(&self, workspace: &mut LocalVerletWorkspace) {
        workspace.cached = false;
    }

    fn local_velocity<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &LocalVerletWorkspace,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        guess: &DVector<f64>,
    ) -> Result<DVector<f64>, Error> {
        match &workspace.mass_inverse {
            Some(inverse) => Ok(inverse.apply(p)),
            None => cold_velocity(model, t, q, p, guess),
        }
    }
}
