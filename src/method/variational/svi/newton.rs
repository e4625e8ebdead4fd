//! The stage equations (8a)–(8b) solved by Newton's method: their residual, written relative
//! to p_k, and its Jacobian in the node offsets, assembled from the Hessian blocks of L (and
//! the force Jacobian) at the quadrature points.

use super::add_block;
use super::workspace::SviWorkspace;
use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::method::State;
use crate::method::variational::tables::Tables;
use crate::model::Lagrangian;
use crate::model::derived::{ForceJacobian, LagrangianExt, SecondDerivatives};
use crate::nonlinear::{Jacobian, Solved};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix};

/// Assemble the residual of (8a)–(8b) and, when `jacobian` is `Some`, its Jacobian with
/// respect to the offsets (the residual alone needs only first derivatives of L).
#[allow(clippy::too_many_arguments)]
fn assemble<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    tables: &Tables,
    points: &mut [SecondDerivatives<N>],
    forces: &mut [ForceJacobian<N>],
    t: f64,
    state: &State<N>,
    z: &DVector<f64>,
    jacobian: Option<&mut DMatrix<f64>>,
    residual: &mut DVector<f64>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let s = tables.degree;
    let width = state.q.len();
    for (mu, point) in points.iter_mut().enumerate() {
        let (q, v) = tables.point(mu, &state.q, z);
        let time = tables.time(t, mu);
        if jacobian.is_some() {
            *point = model.second_derivatives(time, &q, &v);
            if L::FORCED {
                forces[mu] = model.external_force_jacobian(time, &q, &v);
            }
        } else {
            // Only ∂L/∂q, ∂L/∂q̇ (and f_L) are read below; the Hessian blocks are stale.
            let first = model.first_derivatives(time, &q, &v);
            point.q = first.q;
            point.v = first.v;
            if L::FORCED {
                forces[mu].value = model.external_force(time, &q, &v);
            }
        }
    }
    // Relative to p_k: Σ_μ (h/2) w_μ (2/h) l̇_ν(τ_μ) = l_ν(1) − l_ν(−1) = δ_νs − δ_ν0 (the
    // quadrature is exact on l̇_ν, of degree s − 1 ≤ 2m − 1, since the options require
    // m ≥ s), so the rows ν < s of p_k δ_ν0 + Σ_μ (h/2) w_μ l̇_ν p(τ_μ) equal
    // Σ_μ (h/2) w_μ l̇_ν (p(τ_μ) − p_k): the O(|p|) terms, which cancel through the
    // differentiation weights, are left out exactly instead of in floating point.
    residual.fill(0.0);
    for (mu, d) in points.iter().enumerate() {
        let w = tables.weights[mu];
        // ∂L/∂q + f_L.
        let forced;
        let lq = if L::FORCED {
            forced = &d.q + &forces[mu].value;
            &forced
        } else {
            &d.q
        };
        let momentum = &d.v - &state.y;
        for nu in 0..s {
            let b = tables.values[(mu, nu)];
            let c = tables.derivatives[(mu, nu)];
            let row = &mut residual.as_mut_slice()[nu * width..(nu + 1) * width];
            for ((target, lq), momentum) in
                row.iter_mut().zip(lq.as_slice()).zip(momentum.as_slice())
            {
                *target += (lq * b + momentum * c) * w;
            }
        }
    }
    let Some(jacobian) = jacobian else {
        return;
    };
    jacobian.fill(0.0);
    for (mu, d) in points.iter().enumerate() {
        let w = tables.weights[mu];
        let qv_t = d.qv.transpose();
        // The derivatives of ∂L/∂q + f_L in q and q̇.
        let forced;
        let (lqq, lqv) = if L::FORCED {
            let f = &forces[mu];
            forced = (&d.qq + &f.q, &d.qv + &f.v);
            (&forced.0, &forced.1)
        } else {
            (&d.qq, &d.qv)
        };
        for j in 1..=s {
            let bj = tables.values[(mu, j)];
            let cj = tables.derivatives[(mu, j)];
            let from_q: OMatrix<f64, N, N> = (lqq * bj + lqv * cj) * w;
            let from_v: OMatrix<f64, N, N> = (&qv_t * bj + &d.vv * cj) * w;
            for nu in 0..s {
                let block =
                    &from_q * tables.values[(mu, nu)] + &from_v * tables.derivatives[(mu, nu)];
                add_block(jacobian, nu * width, (j - 1) * width, &block);
            }
        }
    }
}

/// Solve (8a)–(8b) for the node offsets by Newton's method with `jacobian`.
pub(super) fn solve<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    workspace: &mut SviWorkspace<N>,
    t: f64,
    h: f64,
    state: &State<N>,
    warm: bool,
    jacobian: Jacobian,
) -> Result<Solved, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if !warm {
        workspace.set_step(h);
        workspace.start(model, t, state);
    }
    let SviWorkspace {
        tables,
        offsets,
        points,
        forces,
        newton,
        ..
    } = workspace;
    if points.is_empty() {
        *points = vec![SecondDerivatives::zeros(state.dimension()); tables.weights.len()];
    }
    newton.iterate(offsets, jacobian, |z, matrix, residual| {
        assemble(model, tables, points, forces, t, state, z, matrix, residual)
    })
}
