//! Integration methods, and their contract with the stepping loop.
//!
//! A method on ℝᴺ is a small options struct plus an implementation of [`Method`]:
//! [`Method::info`] (name, order, symmetric, symplectic), [`Method::workspace`] (every buffer,
//! sized once per run) and [`Method::step`] (one step, returning a context-free
//! [`StepFailure`]). The one stepping loop, [`crate::Integrator`], does everything else:
//! validation, time keeping, compensated summation of the increments, observers, recovery and
//! error context. It drives any method through [`Step`], the space-generic form of the
//! contract ([`space`]: ℝᴺ and SO(3)); every [`Method`] is a [`Step`] on [`Euclidean`] by a
//! blanket implementation, and the Lie-group integrator [`lie_svi::LieSvi`] implements
//! [`Step`] on [`SO3`] directly.
//!
//! A method chosen at run time is one value, [`any::AnyMethod`]. Families, one folder or file
//! each: [`variational`] (SVI and the classic variational
//! integrators), [`hamiltonian`] (symplectic Euler, midpoint, Störmer–Verlet and its
//! compositions on Hamilton's equations), [`collocation`] (spectral collocation), [`lie_svi`] (SO(3)), [`multiscale`]
//! (the multiscale variational integrator for stiff oscillations), [`reference`](mod@reference) (explicit
//! and implicit Euler and RK4 on the Euler–Lagrange equations: non-symplectic references).
//! Each is written once for every dimension, fixed (`Const<N>`) or chosen at run time
//! ([`crate::Dyn`]); on a sum of local terms of run-time size (chains, lattices, 10⁵ degrees
//! of freedom and beyond) the methods that keep its sparsity ([`Method::keeps_sparsity`])
//! run in O(n) per step.

pub mod adjoint;
pub mod any;
pub(crate) mod block_newton;
pub mod collocation;
pub mod constrained;
pub mod group_space;
pub mod hamiltonian;
pub mod lie_svi;
pub mod multiscale;
pub mod reference;
pub mod registry;
pub mod space;
pub mod step;
pub mod variational;

pub use adjoint::StepAdjoint;
pub use space::{
    Euclidean, Initial, PhasePoint, RigidInitial, RigidPoint, RigidState, SO3, Space, State,
    StepState, TangentMap,
};
pub use step::Step;

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::model::Lagrangian;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector};

/// Which second coordinate a method carries besides q.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// (q, p): variational integrators (the discrete Hamiltonian map).
    Momentum,
    /// (q, q̇): collocation of the Euler–Lagrange equations.
    Velocity,
}

/// Which equations of motion a method discretises, and so which description of the model it
/// reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Equations {
    /// The Euler–Lagrange equations or the discrete action: L and its derivatives.
    Lagrange,
    /// Hamilton's equations ([`crate::method::hamiltonian`]): H's derivatives only, so they
    /// also run a model given as the right-hand side of Hamilton's equations alone
    /// ([`crate::model::rhs::HamiltonianRhs`]).
    Hamilton,
}

/// Static facts about a configured method.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodInfo {
    /// Short name, e.g. `"svi"`.
    pub name: &'static str,
    /// Classical order of the one-step map.
    pub order: usize,
    /// Whether the step map satisfies Φ₋ₕ ∘ Φₕ = id.
    pub symmetric: bool,
    /// Whether the step map is symplectic.
    pub symplectic: bool,
    /// The state coordinates the method works in.
    pub coordinates: Coordinates,
    /// The equations it discretises.
    pub equations: Equations,
}

/// Work reported by one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Nonlinear (Newton) iterations.
    pub iterations: usize,
    /// Points at which derivatives of L were evaluated.
    pub evaluations: usize,
    /// Jacobians of the nonlinear solve assembled and LU-factorised (Newton's method
    /// factorises at every iteration, the simplified Newton method only when its iteration
    /// stops contracting well).
    pub factorizations: usize,
    /// Symbolic analyses (fill-reducing orderings) of a sparse linear solver's pattern: one
    /// per pattern and run, reported with the first step.
    pub analyses: usize,
}

impl std::ops::AddAssign for StepReport {
    /// The work of two steps (or stages) together.
    fn add_assign(&mut self, other: StepReport) {
        self.iterations += other.iterations;
        self.evaluations += other.evaluations;
        self.factorizations += other.factorizations;
        self.analyses += other.analyses;
    }
}

/// An integration method for Lagrangians on ℝᴺ, of fixed or run-time dimension: written once,
/// generic over the [`Dimension`].
pub trait Method<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Buffers and precomputed tables of one run.
    type Workspace;

    /// Name, order and geometric properties.
    fn info(&self) -> MethodInfo;

    /// Validate the options and build every buffer and table for steps of size `h`.
    fn workspace<L: Lagrangian<N>>(&self, model: &L, h: f64) -> Result<Self::Workspace, Error>;

    /// Advance `state` from `t` to `t + h`, writing the increment (q' − q, y' − y) into
    /// `increment`. The step may use and update warm-start data in the workspace.
    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure>;

    /// Drop warm-start data: the next step does not continue the last one (it starts
    /// elsewhere than where the last step ended, as after a rejected adaptive step).
    fn restart(&self, workspace: &mut Self::Workspace) {
        let _ = workspace;
    }

    /// Dense output of the last step taken, from `state` with size `h`: (q, q̇) at t + θh,
    /// θ ∈ [0, 1], from the step's interpolating polynomial. `None` for methods without a
    /// step polynomial (callers then interpolate the step's end points).
    fn dense_output(
        &self,
        workspace: &Self::Workspace,
        state: &State<N>,
        h: f64,
        theta: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        let _ = (workspace, state, h, theta);
        None
    }

    /// The velocity q̇ for the momentum `p` of a state at (t, q) this run's steps reached,
    /// into `v` (a guess on entry), from what the workspace already holds: a constant mass
    /// matrix's cached inverse (q̇ = M⁻¹p), or the sparse inverse Legendre map a run on a sum
    /// of terms keeps. `Ok(false)` where it holds neither and the caller solves the map.
    ///
    /// # Errors
    /// [`Error::LegendreMap`] if the kept map does not converge.
    #[allow(clippy::too_many_arguments)]
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &Self::Workspace,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        let _ = (model, workspace, t, q, p, v);
        Ok(false)
    }

    /// The momentum p = M q̇ of a velocity `v` from the constant mass matrix M the workspace
    /// keeps (methods in the coordinates (q, q̇) on a constant-mass model, once a step has
    /// run), into `p`. `false` where it keeps none and the caller differentiates L.
    fn momentum_into(
        &self,
        workspace: &Self::Workspace,
        v: &OVector<f64, N>,
        p: &mut OVector<f64, N>,
    ) -> bool {
        let _ = (workspace, v, p);
        false
    }

    /// Whether the method runs `model` without any dense n × n matrix: `model` is a sum of
    /// local terms ([`Lagrangian::terms`]) and the method's path for it keeps their sparsity
    /// (O(n) memory and work per step). Such a run takes a model of any size; every other
    /// run-time-size run is capped by [`crate::method::step::dense_size`]. The default
    /// (`false`) is always correct.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        let _ = model;
        false
    }

    /// `false` promises that [`Method::verlet_fractions`] is always `None` (the method is not
    /// Störmer–Verlet or a composition of it): the logarithmic-Hamiltonian splitting is then
    /// not compiled for the method. `true` is always correct.
    const COMPOSES_VERLET: bool = false;

    /// The step fractions γ_1, …, γ_s if the method is a symmetric composition of
    /// Störmer–Verlet steps of sizes γ_i h (Störmer–Verlet itself: `[1.0]`); `None` otherwise.
    /// The logarithmic-Hamiltonian splitting ([`crate::stepping::logh`]) composes its own
    /// leapfrog with them.
    fn verlet_fractions(&self) -> Option<&[f64]> {
        None
    }

    /// `true` promises that [`Method::points`] is always `None` (a method without a degree):
    /// degree adaptivity is then not compiled for the method. The default (`false`) is
    /// always correct.
    const WITHOUT_POINTS: bool = false;

    /// Number of interpolation points of a spectral method (polynomial degree + 1); `None`
    /// for methods without a degree.
    fn points(&self) -> Option<usize> {
        None
    }

    /// The same method with `points` interpolation points (degree adaptivity); `None` for
    /// methods without a degree.
    fn with_points(&self, points: usize) -> Option<Self>
    where
        Self: Sized,
    {
        let _ = points;
        None
    }

    /// Node values of the last step's polynomial, as offsets qᵛ − q_k at the CGL nodes
    /// ν = 1, …, s (stacked, N numbers per node); `None` for methods without a degree.
    fn node_offsets<'a>(&self, workspace: &'a mut Self::Workspace) -> Option<&'a [f64]> {
        let _ = workspace;
        None
    }

    /// The discrete energy E_d = −∂L_d/∂h of the last step taken (from `state` at `t` with
    /// size `h`) for Galerkin methods, whose L_d is the action of the step polynomial by
    /// quadrature (see [`crate::stepping::sem`]); `None` for other methods.
    fn discrete_energy<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Option<f64> {
        let _ = (model, workspace, t, h, state);
        None
    }

    /// Perform the step like [`Method::step`] and return the increment, its exact Jacobian
    /// with respect to `state` (implicit function theorem on the converged nonlinear system;
    /// derivatives of L by automatic differentiation) and the work of the step's solve (the
    /// Jacobian's own derivative evaluations are not counted).
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure>;

    /// Perform the step like [`Method::step`], writing the increment into `increment`, and
    /// keep in `adjoint` what [`Method::adjoint_apply`] needs to apply the transpose of the
    /// step's tangent map (`adjoint`'s storage is reused where it can be). By default the
    /// tangent map itself ([`adjoint::adjoint_by_tangent_map`]).
    #[allow(clippy::too_many_arguments)]
    fn adjoint_step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
        adjoint: &mut StepAdjoint<N>,
    ) -> Result<StepReport, StepFailure> {
        adjoint::adjoint_by_tangent_map(self, model, workspace, t, h, state, increment, adjoint)
    }

    /// λ ← Φᵀλ for the step `adjoint` was kept for ([`Method::adjoint_step`]): `lambda` holds
    /// (λ_q, λ_y), 2N entries, and `scratch` as many. By default from the tangent map
    /// ([`adjoint::apply_tangent_map`]).
    ///
    /// # Errors
    /// [`StepFailure::Unsupported`] for an `adjoint` another method kept; a method that
    /// iterates fails as its iteration does.
    fn adjoint_apply(
        &self,
        workspace: &mut Self::Workspace,
        adjoint: &StepAdjoint<N>,
        lambda: &mut DVector<f64>,
        scratch: &mut DVector<f64>,
    ) -> Result<(), StepFailure> {
        let _ = workspace;
        adjoint::apply_tangent_map(adjoint, lambda, scratch)
    }

    /// X ← ΦX for the step `adjoint` was kept for ([`Method::adjoint_step`]): the columns of
    /// `columns` are tangent vectors (δq, δy), 2N rows, and `scratch` has its shape. By
    /// default from the tangent map ([`adjoint::compose_tangent_map`]).
    ///
    /// # Errors
    /// [`StepFailure::Unsupported`] for an `adjoint` another method kept; a method that
    /// iterates fails as its iteration does.
    fn tangent_apply(
        &self,
        workspace: &mut Self::Workspace,
        adjoint: &StepAdjoint<N>,
        columns: &mut DMatrix<f64>,
        scratch: &mut DMatrix<f64>,
    ) -> Result<(), StepFailure> {
        let _ = workspace;
        adjoint::compose_tangent_map(adjoint, columns, scratch)
    }
}
