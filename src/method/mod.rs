//! The contract between an integration method and the stepping loop.
//!
//! A method is a small options struct plus an implementation of [`Method`]: [`Method::info`]
//! (name, order, symmetric, symplectic), [`Method::workspace`] (every buffer, sized once per
//! run) and [`Method::step`] (one step, returning a context-free [`StepFailure`]). The one
//! stepping loop, [`crate::Integrator`], does everything else: validation, time keeping,
//! compensated summation of the increments, observers and error context.

pub mod collocation;
pub mod lie_svi;
pub mod registry;
pub mod variational;

use crate::error::StepFailure;
use crate::{Error, Lagrangian};
use nalgebra::{DMatrix, SMatrix, SVector};

/// Which second coordinate a method carries besides q.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// (q, p): variational integrators (the discrete Hamiltonian map).
    Momentum,
    /// (q, q̇): collocation of the Euler–Lagrange equations.
    Velocity,
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
}

/// The state a method advances: configuration `q` and `y`, which is the momentum p for
/// [`Coordinates::Momentum`] methods and the velocity q̇ for [`Coordinates::Velocity`] ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State<const N: usize> {
    /// Configuration q.
    pub q: SVector<f64, N>,
    /// Momentum p or velocity q̇, according to the method's [`Coordinates`].
    pub y: SVector<f64, N>,
}

impl<const N: usize> State<N> {
    /// The zero state (used for increments).
    pub fn zeros() -> Self {
        State {
            q: SVector::zeros(),
            y: SVector::zeros(),
        }
    }

    /// `self += increment` with Kahan compensation carried in `compensation`.
    pub(crate) fn add_compensated(&mut self, compensation: &mut State<N>, increment: &State<N>) {
        use crate::linalg::compensated_add;
        compensated_add(
            self.q.as_mut_slice(),
            compensation.q.as_mut_slice(),
            increment.q.as_slice(),
        );
        compensated_add(
            self.y.as_mut_slice(),
            compensation.y.as_mut_slice(),
            increment.y.as_slice(),
        );
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.q.iter().chain(self.y.iter()).all(|x| x.is_finite())
    }
}

/// A complete phase-space point: time, configuration, velocity and momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhasePoint<const N: usize> {
    /// Time t.
    pub t: f64,
    /// Configuration q.
    pub q: SVector<f64, N>,
    /// Velocity q̇.
    pub v: SVector<f64, N>,
    /// Momentum p = ∂L/∂q̇.
    pub p: SVector<f64, N>,
}

/// Work reported by one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Nonlinear (Newton) iterations.
    pub iterations: usize,
    /// Points at which derivatives of L were evaluated.
    pub evaluations: usize,
}

/// The Jacobian Φ of one step (q, y) ↦ (q', y'), in blocks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentMap<const N: usize> {
    /// ∂q'/∂q.
    pub qq: SMatrix<f64, N, N>,
    /// ∂q'/∂y.
    pub qy: SMatrix<f64, N, N>,
    /// ∂y'/∂q.
    pub yq: SMatrix<f64, N, N>,
    /// ∂y'/∂y.
    pub yy: SMatrix<f64, N, N>,
}

impl<const N: usize> TangentMap<N> {
    /// The full 2N×2N matrix [[qq, qy], [yq, yy]].
    pub fn matrix(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(2 * N, 2 * N);
        m.view_mut((0, 0), (N, N)).copy_from(&self.qq);
        m.view_mut((0, N), (N, N)).copy_from(&self.qy);
        m.view_mut((N, 0), (N, N)).copy_from(&self.yq);
        m.view_mut((N, N), (N, N)).copy_from(&self.yy);
        m
    }

    /// ‖ΦᵀJΦ − J‖_max with J = [[0, I], [−I, 0]]: zero for a symplectic map in (q, p).
    pub fn symplecticity_error(&self) -> f64 {
        let phi = self.matrix();
        let mut j = DMatrix::zeros(2 * N, 2 * N);
        for i in 0..N {
            j[(i, N + i)] = 1.0;
            j[(N + i, i)] = -1.0;
        }
        (phi.transpose() * &j * &phi - j).amax()
    }
}

/// An integration method for Lagrangians on ℝᴺ.
pub trait Method<const N: usize> {
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
    ) -> Option<(SVector<f64, N>, SVector<f64, N>)> {
        let _ = (workspace, state, h, theta);
        None
    }

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
    fn node_offsets<'a>(&self, workspace: &'a Self::Workspace) -> Option<&'a [f64]> {
        let _ = workspace;
        None
    }

    /// Perform the step like [`Method::step`] and return its exact Jacobian with respect to
    /// `state` (implicit function theorem on the converged nonlinear system; derivatives of L
    /// by automatic differentiation).
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>), StepFailure>;
}
