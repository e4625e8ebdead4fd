//! The discrete adjoint of one step: λ ↦ Φᵀλ for the step's tangent map Φ, the backward
//! sweep of [`crate::Integrator::gradient`].
//!
//! Every method keeps its step's tangent map Φ ([`crate::Method::tangent_map`]) and applies
//! its transpose ([`StepAdjoint::Map`]): exact, but Φ costs a Jacobian of the step equations,
//! its factorisation and 2N solves. A method whose step equations have more structure may keep
//! less and apply Φᵀ from it: constant-mass SVI keeps the force Jacobians at its quadrature
//! points and applies Φᵀ by the transposed fixed-point iteration of its Nyström form
//! ([`StepAdjoint::Stages`]), with no factorisation at all. What a step keeps serves the
//! forward sensitivities as well: X ↦ ΦX ([`crate::Method::tangent_apply`]).

use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::linalg::dynamic_view;
use crate::method::space::{State, TangentMap};
use crate::method::{Method, StepReport};
use crate::model::Lagrangian;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, Dim, Dyn, OMatrix};

/// What a step keeps for the adjoint sweep ([`Method::adjoint_step`]), applied by the method
/// that made it ([`Method::adjoint_apply`]).
#[derive(Debug, Clone, PartialEq)]
pub enum StepAdjoint<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The step's tangent map Φ (every method's default).
    Map(TangentMap<N>),
    /// Matrices at the step's stages and the step's size, which only the method that kept
    /// them applies (constant-mass SVI: the weighted force Jacobians W_μ ∂²L/∂q² at its
    /// quadrature points and hM⁻¹ times them, see [`crate::method::variational::svi`]).
    Stages {
        /// The step's size.
        h: f64,
        /// The matrices, in the order of their stages.
        matrices: Vec<OMatrix<f64, N, N>>,
    },
}

impl<N: Dimension> StepAdjoint<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// An empty slot, for [`Method::adjoint_step`] to fill.
    pub fn empty() -> Self {
        StepAdjoint::Stages {
            h: 0.0,
            matrices: Vec::new(),
        }
    }

    /// The bytes of the numbers it keeps.
    pub fn bytes(&self) -> usize {
        let floats = match self {
            StepAdjoint::Map(map) => 4 * map.qq.len(),
            StepAdjoint::Stages { matrices, .. } => {
                1 + matrices.iter().map(|matrix| matrix.len()).sum::<usize>()
            }
        };
        floats * std::mem::size_of::<f64>()
    }
}

/// [`Method::adjoint_step`] by the tangent map: the step, its tangent map Φ kept in
/// `adjoint` (the default of every method).
///
/// # Errors
/// Those of [`Method::tangent_map`].
#[allow(clippy::too_many_arguments)]
pub fn adjoint_by_tangent_map<M: Method<N> + ?Sized, L: Lagrangian<N>, N: Dimension>(
    method: &M,
    model: &L,
    workspace: &mut M::Workspace,
    t: f64,
    h: f64,
    state: &State<N>,
    increment: &mut State<N>,
    adjoint: &mut StepAdjoint<N>,
) -> Result<StepReport, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (step, map, report) = method.tangent_map(model, workspace, t, h, state)?;
    *increment = step;
    *adjoint = StepAdjoint::Map(map);
    Ok(report)
}

/// λ ← Φᵀλ for a kept tangent map ([`StepAdjoint::Map`]; the default of
/// [`Method::adjoint_apply`]), with `scratch` of λ's length.
///
/// # Errors
/// [`StepFailure::Unsupported`] for stage Jacobians (another method's).
pub fn apply_tangent_map<N: Dimension>(
    adjoint: &StepAdjoint<N>,
    lambda: &mut DVector<f64>,
    scratch: &mut DVector<f64>,
) -> Result<(), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    multiply(adjoint, true, lambda, scratch)
}

/// X ← ΦX for a kept tangent map ([`StepAdjoint::Map`]; the default of
/// [`Method::tangent_apply`]), with `scratch` of X's shape.
///
/// # Errors
/// [`StepFailure::Unsupported`] for stage Jacobians (another method's).
pub fn compose_tangent_map<N: Dimension>(
    adjoint: &StepAdjoint<N>,
    columns: &mut DMatrix<f64>,
    scratch: &mut DMatrix<f64>,
) -> Result<(), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    multiply(adjoint, false, columns, scratch)
}

/// X ← ΦX, or ΦᵀX with `transpose`, for a kept tangent map Φ in blocks
/// [[qq, qy], [yq, yy]], through `scratch` of X's shape.
fn multiply<N: Dimension, C: Dim>(
    adjoint: &StepAdjoint<N>,
    transpose: bool,
    x: &mut OMatrix<f64, Dyn, C>,
    scratch: &mut OMatrix<f64, Dyn, C>,
) -> Result<(), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N> + Allocator<Dyn, C>,
{
    let StepAdjoint::Map(tangent) = adjoint else {
        return Err(FOREIGN_ADJOINT);
    };
    let m = tangent.qq.nrows();
    // Row blocks of the result: (upper-left, upper-right) and (lower-left, lower-right).
    let (upper, lower) = if transpose {
        ([&tangent.qq, &tangent.yq], [&tangent.qy, &tangent.yy])
    } else {
        ([&tangent.qq, &tangent.qy], [&tangent.yq, &tangent.yy])
    };
    let (top, bottom) = (x.rows(0, m), x.rows(m, m));
    for (row, blocks) in [(0, upper), (m, lower)] {
        let mut out = scratch.rows_mut(row, m);
        for (input, block, beta) in [(&top, blocks[0], 0.0), (&bottom, blocks[1], 1.0)] {
            if transpose {
                out.gemm_tr(1.0, &dynamic_view(block), input, beta);
            } else {
                out.gemm(1.0, &dynamic_view(block), input, beta);
            }
        }
    }
    std::mem::swap(x, scratch);
    Ok(())
}

/// The failure of an adjoint applied by a method that did not keep it.
pub(crate) const FOREIGN_ADJOINT: StepFailure = StepFailure::Unsupported {
    option: "adjoint",
    reason: "the step's adjoint was kept by another method",
};
