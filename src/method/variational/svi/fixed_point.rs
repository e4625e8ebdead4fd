//! One step of a constant-mass Lagrangian by the fixed-point iteration on the positions at
//! the quadrature points (no Hessian), from the previous step's polynomial extrapolated to
//! them (see [`NystromTables`](super::constant_mass::NystromTables)).

use super::add_scaled;
use super::constant_mass::ConstantMass;
use super::workspace::{SviWorkspace, starting_offsets};
use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::linalg::combination::{Rows, Start};
use crate::method::variational::tables::Tables;
use crate::method::{State, StepReport};
use crate::model::Lagrangian;
use crate::model::derived::{LagrangianExt, cached_mass_inverse};
use crate::nonlinear::FixedPoint;
use crate::spectral::starting_values::StartingValues;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector};

/// Positions at the quadrature points at the start of a step: the previous step's polynomial
/// extrapolated, straight from its velocity term and accelerations where its node offsets
/// are pending (Q_μ = q_k + γ_μ h M⁻¹p_{k−1} + Σ_ν E_μν a_ν, the cost of one product, as the
/// extrapolation of a Gauss–Legendre code), else from its node offsets (Q_μ = q_k + Σ_j W_μj
/// Z_j), or at a cold start from the starting values' offsets (the Taylor polynomial,
/// written to `offsets`). Returns whether the start was warm.
fn starting_positions<L: Lagrangian<N>, N: Dimension>(
    (start, tables, offsets): (&mut StartingValues, &Tables, &mut DVector<f64>),
    data: &mut ConstantMass<N>,
    model: &L,
    t: f64,
    state: &State<N>,
) -> bool
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let s = tables.degree;
    if !start.prepare(tables.h) {
        starting_offsets(start, tables.h, offsets, model, t, state);
        data.set_positions(&state.q, false, offsets.as_slice(), s);
        return false;
    }
    let (table, ratio) = start.table();
    if ratio != data.nystrom.extrapolation_ratio {
        data.nystrom.build_extrapolation(table, ratio, s);
    }
    if data.pending {
        data.extrapolate_positions(&state.q);
    } else if let Some(previous) = start.last_offsets() {
        data.set_positions(&state.q, true, previous, s);
    }
    true
}

/// One step of a constant-mass Lagrangian by fixed-point iteration (no Hessian; an external
/// force is evaluated at the quadrature points' positions and velocities).
pub(super) fn fixed_point_step<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    max_iterations: usize,
    workspace: &mut SviWorkspace<N>,
    t: f64,
    h: f64,
    state: &State<N>,
    increment: &mut State<N>,
) -> Result<StepReport, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    workspace.set_step(h);
    if L::FORCED {
        // The velocities at the quadrature points start from the extrapolated offsets.
        workspace.settle();
    }
    let SviWorkspace {
        tables,
        offsets,
        start,
        constant_mass,
        ..
    } = workspace;
    let Some(data) = constant_mass.as_mut() else {
        return Err(StepFailure::SingularMatrix);
    };
    let warm = starting_positions((start, tables, offsets), data, model, t, state);
    let mass_inverse = cached_mass_inverse(&mut data.mass_inverse, model, t, &state.q, &state.y)?;
    let m = tables.nodes.len();
    let width = state.q.len();
    mass_inverse.apply_into(&state.y, &mut data.velocity);
    data.velocity *= h;
    let velocity = &data.velocity;
    let kick_inverse = mass_inverse.scaled(h);
    if L::FORCED {
        // The velocities of the starting polynomial, from its offsets (the previous step's
        // polynomial extrapolated, as the positions).
        if warm {
            start.extrapolate::<N>(offsets);
        }
        for (mu, rate) in data.velocities.iter_mut().enumerate() {
            rate.fill(0.0);
            for (j, offset) in offsets.as_slice().chunks_exact(width).enumerate() {
                let c = tables.derivatives[(mu, j + 1)];
                for (r, x) in rate.as_mut_slice().iter_mut().zip(offset) {
                    *r += x * c;
                }
            }
        }
    }
    for (mu, time) in data.times.iter_mut().enumerate() {
        *time = tables.time(t, mu);
    }
    let mut size: f64 = 0.0;
    for (base, c) in data.bases.iter_mut().zip(&data.nystrom.stage_velocity) {
        base.copy_from(&state.q);
        add_scaled(base, *c, velocity);
        size = size.max(base.amax());
    }
    // Run to noise: an error correlated from step to step would make the symplectic step's
    // energy drift (see `FixedPoint::to_noise`).
    let mut control = FixedPoint::to_noise(max_iterations);
    loop {
        model.forces_into(&data.times, &data.positions, &state.y, &mut data.forces);
        if L::FORCED {
            for (mu, force) in data.forces.iter_mut().enumerate() {
                let time = data.times[mu];
                *force += model.external_force(time, &data.positions[mu], &data.velocities[mu]);
            }
        }
        // The kicks L_ν = h b_ν ∂L/∂q and h M⁻¹L_ν (see `NystromTables`).
        for (((load, kick), force), w) in data
            .loads
            .iter_mut()
            .zip(&mut data.kicks)
            .zip(&data.forces)
            .zip(&tables.weights)
        {
            load.copy_from(force);
            *load *= *w;
            kick_inverse.apply_into(load, kick);
        }
        let rows = Rows {
            start: Start::Rows(&data.bases),
            lead: None,
            matrix: &data.nystrom.kick_matrix,
            inputs: &data.kicks,
        };
        // The largest change ignores a NaN, which the finiteness check catches.
        let change = N::combine_rows(&mut data.positions, rows);
        if !change.finite {
            return Err(StepFailure::NonFinite);
        }
        if L::FORCED {
            accelerations_of_kicks(
                &mut data.accelerations,
                &data.kicks,
                &tables.reference_weights,
            );
            let rows = Rows {
                start: Start::Zero,
                lead: Some((&data.nystrom.stage_rate, velocity)),
                matrix: &data.nystrom.rate_matrix,
                inputs: &data.accelerations,
            };
            N::combine_rows(&mut data.velocities, rows);
            for rate in &mut data.velocities {
                *rate /= h;
            }
        }
        let converged = control.converged(change.largest, size);
        if converged == Ok(true) {
            break;
        }
        if let Err(failure) = converged {
            accelerations_of_kicks(
                &mut data.accelerations,
                &data.kicks,
                &tables.reference_weights,
            );
            // The node offsets of the last iterate, where Newton takes over from a capped
            // iteration (see `after_fixed_point`).
            for ((target, row), c) in offsets
                .as_mut_slice()
                .chunks_exact_mut(width)
                .zip(data.nystrom.propagation.chunks_exact(m))
                .zip(&data.nystrom.velocity_coefficients)
            {
                let mut offset = velocity * *c;
                for (p, acceleration) in row.iter().zip(&data.accelerations) {
                    add_scaled(&mut offset, *p, acceleration);
                }
                target.copy_from_slice(offset.as_slice());
            }
            return Err(failure);
        }
    }
    if !L::FORCED {
        // (A forced iteration made them from these kicks already.)
        accelerations_of_kicks(
            &mut data.accelerations,
            &data.kicks,
            &tables.reference_weights,
        );
    }
    // p_{k+1} − p_k = Σ_μ L_μ, and q_{k+1} − q_k = h M⁻¹p_k + Σ_μ d_μ h M⁻¹L_μ with the
    // small terms summed first.
    let dp = &mut increment.y;
    dp.copy_from(&data.loads[0]);
    for load in &data.loads[1..] {
        *dp += load;
    }
    let sum = &mut data.end_kick;
    sum.fill(0.0);
    for (d, kick) in data.nystrom.end_fractions.iter().zip(&data.kicks) {
        add_scaled(sum, *d, kick);
    }
    let dq = &mut increment.q;
    dq.copy_from(velocity);
    *dq += &*sum;
    // The step's polynomial is remembered by its velocity term and accelerations; its node
    // offsets are written only if something reads them (see `ConstantMass::pending`).
    std::mem::swap(&mut data.velocity, &mut data.last_velocity);
    std::mem::swap(&mut data.accelerations, &mut data.last_accelerations);
    data.pending = true;
    start.remember_size(h);
    let iterations = control.iterations();
    Ok(StepReport {
        iterations,
        evaluations: m * iterations,
        factorizations: 0,
        analyses: 0,
    })
}

/// The scaled accelerations h² M⁻¹ ∂L/∂q(τ_μ) = h M⁻¹L_μ / b_μ from the kicks, for the next
/// step's start and the node offsets (`w` the Gauss weights, b = w/2).
fn accelerations_of_kicks<N: Dimension>(
    accelerations: &mut [OVector<f64, N>],
    kicks: &[OVector<f64, N>],
    w: &[f64],
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    for ((acceleration, kick), w) in accelerations.iter_mut().zip(kicks).zip(w) {
        acceleration.copy_from(kick);
        *acceleration *= 2.0 / w;
    }
}
