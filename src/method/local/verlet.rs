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
use crate::linalg::lane_extent;
use crate::method::local::MassInverse;
use crate::method::local::{LocalMethod, cold_velocity, constant_mass};
use crate::method::space::DynState;
use crate::method::{Coordinates, MethodInfo, StepReport};
use crate::model::local::LocalLagrangian;
use nalgebra::DVector;

/// Buffers of a Störmer–Verlet run on runtime-sized ℝⁿ.
#[derive(Debug)]
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
                    reason: "verlet and its compositions on a runtime-dimension model need a \
                             constant, invertible mass matrix",
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
        // The force at the end of the last step is the force at the start of this one when
        // the state is the one that step ended at (checked entry by entry inside the
        // kick–drift pass, which reads `cached_q` before overwriting it).
        let reuse = *cached
            && (!L::TIME_DEPENDENT
                || (*cached_t - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(cached_t.abs()));
        if reuse {
            std::mem::swap(start_force, end_force);
        } else {
            evaluations += 1;
            // ∂L/∂q of a constant-mass model does not depend on q̇.
            model.force_into(t, &state.q, &state.y, start_force);
        }
        let mut extent = kick_drift(
            mass_inverse,
            (dt, h),
            state,
            start_force,
            reuse.then_some(*cached_tolerance),
            (half, velocity),
            &mut increment.q,
            cached_q,
        );
        if extent.is_none() {
            // The state is not where the last step ended: its force is needed after all.
            evaluations += 1;
            model.force_into(t, &state.q, &state.y, start_force);
            extent = kick_drift(
                mass_inverse,
                (dt, h),
                state,
                start_force,
                None,
                (half, velocity),
                &mut increment.q,
                cached_q,
            );
        }
        // The second pass does not check, so it always returns the extent.
        let extent = extent.unwrap_or(f64::INFINITY);
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
        v: &mut DVector<f64>,
    ) -> Result<(), Error> {
        match &workspace.mass_inverse {
            Some(inverse) => {
                inverse.apply_into(p, v);
                Ok(())
            }
            None => cold_velocity(model, t, q, p, v),
        }
    }
}

/// The kick p_{k+½} = p_k + (h/2) F_k and the drift q_{k+1} = q_k + h M⁻¹p_{k+½} in one pass
/// (for a diagonal M⁻¹; a coupled one solves between the two): writes the velocity M⁻¹p_{k+½}
/// to `buffers.1`, the increment of q to `dq` and q_{k+1} to `end_q`, and returns
/// max |q| over both ends.
///
/// With `check = Some(tolerance)`, `end_q` holds the end of the last step on entry, and the
/// pass also checks that q_k is that point to within `tolerance` entry by entry; it returns
/// `None` if not (the force F_k it was given is then not the force at q_k).
#[allow(clippy::too_many_arguments)]
#[inline]
fn kick_drift(
    mass_inverse: &MassInverse,
    (dt, h): (f64, f64),
    state: &DynState,
    force: &DVector<f64>,
    check: Option<f64>,
    (half, velocity): (&mut DVector<f64>, &mut DVector<f64>),
    dq: &mut DVector<f64>,
    end_q: &mut DVector<f64>,
) -> Option<f64> {
    let tolerance = check.unwrap_or(f64::INFINITY);
    let q = state.q.as_slice();
    match mass_inverse {
        MassInverse::Diagonal(inverse) => {
            velocity
                .as_mut_slice()
                .iter_mut()
                .zip(state.y.as_slice())
                .zip(force.as_slice().iter().zip(inverse.as_slice()))
                .for_each(|((v, p), (f, m))| *v = (p + dt * f) * m);
        }
        MassInverse::Coupled(_) | MassInverse::Dense(_) => {
            for ((k, p), f) in half
                .as_mut_slice()
                .iter_mut()
                .zip(state.y.as_slice())
                .zip(force.as_slice())
            {
                *k = p + dt * f;
            }
            mass_inverse.apply_into(half, velocity);
        }
    }
    // The check reads q_k against the end of the last step before the drift overwrites it.
    let (_, same) = lane_extent([q, end_q.as_slice()], |[q, e]| {
        (0.0, (q - e).abs() <= tolerance)
    });
    for (((d, e), q), v) in dq
        .as_mut_slice()
        .iter_mut()
        .zip(end_q.as_mut_slice())
        .zip(q)
        .zip(velocity.as_slice())
    {
        *d = h * v;
        *e = q + *d;
    }
    let (extent, _) = lane_extent([q, end_q.as_slice()], |[q, e]| (q.abs().max(e.abs()), true));
    // NaN entries fail the check: a NaN state is never "where the last step ended".
    (check.is_none() || same).then_some(extent)
}
