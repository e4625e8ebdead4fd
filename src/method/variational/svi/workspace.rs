//! The buffers of an SVI run ([`SviWorkspace`]) and the starting values of a step: the
//! previous step's polynomial extrapolated to the new nodes, or at the first step the Taylor
//! polynomial.

use super::constant_mass::ConstantMass;
use crate::dimension::Dimension;
use crate::linalg::DenseLu;
use crate::method::State;
use crate::method::variational::stage_newton::LazyStageNewton;
use crate::method::variational::tables::Tables;
use crate::model::Lagrangian;
use crate::model::derived::{ForceJacobian, LagrangianExt, SecondDerivatives};
use crate::model::legendre::LazyLegendre;
use crate::nonlinear::Newton;
use crate::spectral::starting_values::StartingValues;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector, U1};

/// Buffers of an SVI run.
#[derive(Debug, Clone)]
pub struct SviWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    pub(super) tables: Tables,
    /// Node offsets qᵛ − q_k, ν = 1..s, stacked.
    pub(super) offsets: DVector<f64>,
    /// Warm start from the previous step.
    pub(super) start: StartingValues,
    /// Second derivatives of L at the quadrature points.
    pub(super) points: Vec<SecondDerivatives<N>>,
    /// External force and its Jacobian at the quadrature points (forced models).
    pub(super) forces: Vec<ForceJacobian<N>>,
    pub(super) newton: Newton,
    /// Sparse Newton for an unforced sum of terms of run-time size, made at its first use.
    pub(super) sparse: LazyStageNewton,
    /// The inverse Legendre map of such a sum of terms, made at its first use.
    pub(super) legendre: LazyLegendre,
    /// Fixed-point data, for constant-mass Lagrangians.
    pub(super) constant_mass: Option<ConstantMass<N>>,
    /// Set once the fixed-point iteration of a forced model failed to converge: the rest of
    /// the run takes Newton's method.
    pub(super) newton_only: bool,
    /// Buffers of the tangent map, made at its first use.
    pub(super) tangent: Option<TangentBuffers>,
    /// Buffers of the adjoint by the Nyström form, made at its first use.
    pub(super) adjoint: Option<StageVectors<N>>,
}

/// Buffers of [`crate::method::Method::tangent_map`] for SVI: the block Hessian of the
/// discrete action in the nodes, the LU factors of its interior block and the sensitivities.
#[derive(Debug, Clone)]
pub(super) struct TangentBuffers {
    /// H_{νj} = ∂(g_ν + f_ν)/∂qʲ, ν, j = 0..s.
    pub(super) hessian: DMatrix<f64>,
    /// The block ν = 0..s−1, j = 1..s, factorised.
    pub(super) lu: DenseLu,
    /// The interior nodes' derivatives in (q_k, p_k).
    pub(super) sensitivity: DMatrix<f64>,
    /// p_{k+1}'s derivatives in (q_k, p_k).
    pub(super) momentum: DMatrix<f64>,
}

impl TangentBuffers {
    /// Buffers for `degree` s and `width` N coordinates.
    pub(super) fn new(degree: usize, width: usize) -> Self {
        let (size, inner) = ((degree + 1) * width, degree * width);
        TangentBuffers {
            hessian: DMatrix::zeros(size, size),
            lu: DenseLu::new(inner),
            sensitivity: DMatrix::zeros(inner, 2 * width),
            momentum: DMatrix::zeros(width, 2 * width),
        }
    }
}

/// The vectors of the stage iterations of kept stage matrices (`super::adjoint`): the
/// adjoint's transposed one on covectors and the forward one on tangent vectors, made at
/// their first use, N entries each.
#[derive(Debug, Clone)]
pub(super) struct StageVectors<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// r_ν (adjoint).
    pub(super) fixed: Vec<OVector<f64, N>>,
    /// The iterate at each quadrature point: the sums s_ν = Σ_μ K_μν z_μ (adjoint), δQ_μ
    /// (forward).
    pub(super) iterate: Vec<OVector<f64, N>>,
    /// The sums' constant part s⁰ = Kᵀr (adjoint).
    pub(super) constant: Vec<OVector<f64, N>>,
    /// The iterate's images: C_νᵀ s_ν, then z_ν (adjoint); C_ν δQ_ν (forward).
    pub(super) images: Vec<OVector<f64, N>>,
    /// The vector's q and p halves: (λ_q, λ_p) or (δq, δp).
    pub(super) upper: OVector<f64, N>,
    pub(super) lower: OVector<f64, N>,
    /// hM⁻¹ applied: g = hG λ_q (adjoint), hG δp (forward).
    pub(super) kicked: OVector<f64, N>,
    /// One more N-vector.
    pub(super) work: OVector<f64, N>,
}

impl<N: Dimension> StageVectors<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Buffers for N coordinates and m quadrature points.
    pub(super) fn new(n: N, m: usize) -> Self {
        let zero = OVector::zeros_generic(n, U1);
        StageVectors {
            fixed: vec![zero.clone(); m],
            iterate: vec![zero.clone(); m],
            constant: vec![zero.clone(); m],
            images: vec![zero.clone(); m],
            upper: zero.clone(),
            lower: zero.clone(),
            kicked: zero.clone(),
            work: zero,
        }
    }
}

impl<N: Dimension> SviWorkspace<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Rescale the tables for a new step size (the kept Newton factors scale with it).
    pub(super) fn set_step(&mut self, h: f64) {
        if self.tables.h != h {
            self.tables.rescale(h);
            self.invalidate_newton();
        }
    }

    /// Drop Newton's kept factors, dense and sparse.
    pub(super) fn invalidate_newton(&mut self) {
        self.newton.invalidate();
        self.sparse.invalidate();
    }

    /// Starting values: the previous step's polynomial extrapolated to the new nodes, or at
    /// the first step the Taylor polynomial with q̇ from the inverse Legendre map.
    pub(super) fn start<L: Lagrangian<N>>(&mut self, model: &L, t: f64, state: &State<N>) {
        self.settle();
        starting_offsets(
            &mut self.start,
            self.tables.h,
            &mut self.offsets,
            model,
            t,
            state,
        );
    }

    /// Write the last step's node offsets where the fixed-point iteration left them pending.
    pub(super) fn settle(&mut self) {
        if let Some(data) = self.constant_mass.as_mut() {
            data.settle(&mut self.start);
        }
    }

    /// Remember the node offsets in `offsets` as the last step's, of size `h`.
    pub(super) fn remember(&mut self, h: f64) {
        self.start.remember(&self.offsets, h);
        if let Some(data) = self.constant_mass.as_mut() {
            data.pending = false;
        }
    }
}

/// [`SviWorkspace::start`] on the workspace's parts.
pub(super) fn starting_offsets<L: Lagrangian<N>, N: Dimension>(
    start: &mut StartingValues,
    h: f64,
    offsets: &mut DVector<f64>,
    model: &L,
    t: f64,
    state: &State<N>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if start.prepare(h) {
        start.extrapolate::<N>(offsets);
    } else {
        let n = state.dimension();
        let v = model
            .velocity(t, &state.q, &state.y, &state.y)
            .unwrap_or_else(|_| OVector::zeros_generic(n, U1));
        // A sum of terms starts from uniform motion: its acceleration is a dense solve.
        let a = model
            .terms()
            .is_none()
            .then(|| model.acceleration(t, &state.q, &v))
            .flatten()
            .unwrap_or_else(|| OVector::zeros_generic(n, U1));
        start.taylor(h, &v, &a, offsets);
    }
}
