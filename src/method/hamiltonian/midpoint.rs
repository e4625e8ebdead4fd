//! The implicit midpoint rule on Hamilton's equations.
//!
//! # Discrete equations
//! With z = (q, p), F(t, z) = (∂H/∂p, −∂H/∂q + f_H)(t, z) and t̄ = t_k + h/2,
//!
//! z_{k+1} = z_k + h F(t̄, (z_k + z_{k+1})/2).
//!
//! The unknown is the half increment δ = z̄ − z_k of the midpoint z̄ = (z_k + z_{k+1})/2,
//! δ = (h/2) F(t̄, z_k + δ), solved by Newton's method on 2N unknowns from the explicit half
//! step δ = (h/2) F(t̄, z_k) with the Jacobian I − (h/2) ∂F/∂z,
//!
//! ∂F/∂z = [[(∂²H/∂q∂p)ᵀ, ∂²H/∂p²], [−∂²H/∂q² + ∂f_H/∂q, −∂²H/∂q∂p + ∂f_H/∂p]];
//!
//! the increment is 2δ. Through the Legendre map it is the variational integrator of the
//! midpoint discrete Lagrangian ([`crate::Midpoint`]), forces included.
//!
//! # Properties
//! Order 2; symmetric; symplectic without a force (HLW Theorem VI.3.5); implicit for every H,
//! separable or not.
//!
//! # References
//! Hairer, Lubich, Wanner, *Geometric numerical integration* (2006), §I.1.2 and §VI.3;
//! Marsden & West, Acta Numerica (2001), §2.7.

use super::{Derivatives, Linearised, offset, solve};
use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure, require_positive};
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector};

/// Options of the implicit midpoint rule on Hamilton's equations (see the module docs).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ImplicitMidpoint {
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for ImplicitMidpoint {
    fn default() -> Self {
        ImplicitMidpoint { max_iterations: 50 }
    }
}

impl ImplicitMidpoint {
    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }
}

/// Buffers of a run of the [`ImplicitMidpoint`] rule.
#[derive(Debug, Clone)]
pub struct ImplicitMidpointWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    derivatives: Derivatives<N>,
    /// Newton's method on the half increment (δq, δp), 2N unknowns.
    newton: Newton,
    unknown: DVector<f64>,
}

/// I − (h/2) ∂F/∂z of the field `field` (see the module docs) into the 2N × 2N `matrix`;
/// `weight` is −h/2 for the Newton matrix, +h/2 for I + (h/2) ∂F/∂z.
fn shifted_jacobian<N: Dimension>(field: &Linearised<N>, weight: f64, matrix: &mut DMatrix<f64>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = field.hp.len();
    for j in 0..n {
        for i in 0..n {
            let diagonal = if i == j { 1.0 } else { 0.0 };
            matrix[(i, j)] = diagonal + weight * field.qp[(j, i)];
            matrix[(i, n + j)] = weight * field.pp[(i, j)];
            matrix[(n + i, j)] = -weight * field.gq[(i, j)];
            matrix[(n + i, n + j)] = diagonal - weight * field.gp[(i, j)];
        }
    }
}

impl<N: Dimension> Method<N> for ImplicitMidpoint
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;

    type Workspace = ImplicitMidpointWorkspace<N>;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "midpoint-h",
            order: 2,
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Hamilton,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<ImplicitMidpointWorkspace<N>, Error> {
        require_positive("h", h)?;
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        Ok(ImplicitMidpointWorkspace {
            derivatives: Derivatives::new(model, n),
            newton: Newton::new(2 * n.value(), self.max_iterations),
            unknown: DVector::zeros(2 * n.value()),
        })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut ImplicitMidpointWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let ImplicitMidpointWorkspace {
            derivatives,
            newton,
            unknown,
        } = workspace;
        let (q0, p0) = (&state.q, &state.y);
        derivatives.start(model, t, q0, p0)?;
        let (half, middle) = (0.5 * h, t + 0.5 * h);
        let n = q0.len();
        let (g, hp) = derivatives.field(model, middle, q0, p0)?;
        for i in 0..n {
            unknown[i] = half * hp[i];
            unknown[n + i] = -half * g[i];
        }
        let iterations = solve(newton, unknown, |z, jacobian, residual| {
            let q = offset(q0, 1.0, &z.as_slice()[..n]);
            let p = offset(p0, 1.0, &z.as_slice()[n..]);
            let field = derivatives.linearised(model, middle, &q, &p)?;
            for i in 0..n {
                residual[i] = z[i] - half * field.hp[i];
                residual[n + i] = z[n + i] + half * field.g[i];
            }
            shifted_jacobian(&field, -half, jacobian);
            Ok(())
        })?;
        for i in 0..n {
            increment.q[i] = 2.0 * unknown[i];
            increment.y[i] = 2.0 * unknown[n + i];
        }
        Ok(StepReport {
            iterations,
            evaluations: derivatives.evaluations,
            factorizations: iterations,
            analyses: 0,
        })
    }

    /// q̇ = ∂H/∂p: H's gradient for a model written as H, the cached M⁻¹p for a constant
    /// mass.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &ImplicitMidpointWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        Ok(workspace.derivatives.velocity_into(model, t, q, p, v))
    }

    /// The Cayley transform (I − (h/2) A)⁻¹ (I + (h/2) A) of A = ∂F/∂z at the midpoint (the
    /// implicit function theorem on z_{k+1} − z_k = h F(t̄, z̄)).
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut ImplicitMidpointWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let dimension = state.dimension();
        let mut increment = State::zeros(dimension);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let n = state.q.len();
        let q = offset(&state.q, 0.5, increment.q.as_slice());
        let p = offset(&state.y, 0.5, increment.y.as_slice());
        let field = workspace
            .derivatives
            .linearised(model, t + 0.5 * h, &q, &p)?;
        let (mut left, mut right) = (DMatrix::zeros(2 * n, 2 * n), DMatrix::zeros(2 * n, 2 * n));
        shifted_jacobian(&field, -0.5 * h, &mut left);
        shifted_jacobian(&field, 0.5 * h, &mut right);
        let phi = left.lu().solve(&right).ok_or(StepFailure::SingularMatrix)?;
        let block = |i: usize, j: usize| {
            OMatrix::<f64, N, N>::from_fn_generic(dimension, dimension, |r, c| {
                phi[(i * n + r, j * n + c)]
            })
        };
        let tangent = TangentMap {
            qq: block(0, 0),
            qy: block(0, 1),
            yq: block(1, 0),
            yy: block(1, 1),
        };
        Ok((increment, tangent, report))
    }
}
