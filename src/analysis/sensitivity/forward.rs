//! Forward sensitivities: the product of the steps' tangent maps along the run
//! (see the [module](super) documentation).

use super::SensitivityRun;
use super::lifted::{Lifted, Walker, chosen_parameters, lift};
use crate::dimension::{Dimension, Dyn};
use crate::error::Error;
use crate::method::{Euclidean, Method, StepAdjoint};
use crate::model::Lagrangian;
use crate::model::parametric::Parametric;
use crate::stepping::run::{Integrator, Statistics};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator};

/// The state and its derivatives at one output of a differentiated run.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityPoint {
    /// The number of steps taken (0: the start).
    pub step: usize,
    /// The time.
    pub t: f64,
    /// The configuration q.
    pub q: DVector<f64>,
    /// The velocity q̇.
    pub v: DVector<f64>,
    /// ∂(q, q̇)/∂(q₀, q̇₀ or p₀, θ): 2n rows (q, then q̇), 2n + P columns (q₀, then q̇₀ — or p₀
    /// for a start given in momenta —, then the parameters in the order asked).
    pub jacobian: DMatrix<f64>,
}

/// The forward sensitivities of a run ([`Integrator::sensitivities`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivities {
    /// The parameters of the last P columns, in order.
    pub parameters: Vec<String>,
    /// The outputs: the start, every `every`-th step, and the last step.
    pub outputs: Vec<SensitivityPoint>,
    /// The work of the run's steps (taken by their tangent maps).
    pub statistics: Statistics,
}

impl<L: Parametric<N>, M: Method<N> + Method<Dyn> + Clone, N: Dimension>
    Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The forward sensitivities of `run`: at each output the state and its Jacobian with
    /// respect to the initial state and the parameters `run.parameters`, the exact
    /// derivative of the method's discrete map (the product of its steps' tangent maps,
    /// see [`crate::analysis::sensitivity`]).
    ///
    /// # Errors
    /// A parameter the model does not have, or named twice
    /// ([`Error::InvalidParameter`] `parameters`); a bad grid or `every` = 0; a start the
    /// model cannot give ([`super::Start::Model`] without
    /// [`Parametric::initial_state_with`]); a failed step, as its typed error with its index
    /// and time; a singular mass matrix where velocities are recovered from momenta.
    pub fn sensitivities(&self, run: &SensitivityRun<N>) -> Result<Sensitivities, Error> {
        let (chosen, lifts) = chosen_parameters(self.model(), run)?;
        if lifts {
            let hat = lift(self, &chosen);
            forward::<_, _, Dyn>(&Lifted::<_, _, Dyn>::new(&hat, self.model(), &chosen, run)?)
        } else {
            forward::<_, _, N>(&Lifted::<_, _, N>::new(self, self.model(), &chosen, run)?)
        }
    }
}

/// The forward sensitivities of the run `lifted`.
fn forward<R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension>(
    lifted: &Lifted<'_, R, M, D>,
) -> Result<Sensitivities, Error>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let (m, steps) = (lifted.m, lifted.grid.3);
    let mut walker = Walker::new(lifted)?;
    let mut total = DMatrix::identity(2 * m, 2 * m);
    let mut next = DMatrix::zeros(2 * m, 2 * m);
    let mut outputs = Vec::new();
    outputs.push(output(lifted, &mut walker, 0, &total)?);
    // What each step keeps for its tangent (its tangent map, or less: constant-mass SVI's
    // stage matrices), applied to the product so far.
    let mut kept = StepAdjoint::empty();
    for k in 0..steps {
        walker.step_adjoint(k, &mut kept)?;
        walker.apply_tangent(k, &kept, &mut total, &mut next)?;
        if lifted.is_output(k + 1) {
            outputs.push(output(lifted, &mut walker, k + 1, &total)?);
        }
    }
    Ok(Sensitivities {
        parameters: lifted.names.clone(),
        outputs,
        statistics: walker.statistics,
    })
}

/// The output after `step` steps: the point, and G Φ C with Φ = `total`.
fn output<R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension>(
    lifted: &Lifted<'_, R, M, D>,
    walker: &mut Walker<'_, '_, R, M, D>,
    step: usize,
    total: &DMatrix<f64>,
) -> Result<SensitivityPoint, Error>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let point = walker.point(step)?;
    let end = lifted.end(&point)?;
    let n = lifted.n;
    Ok(SensitivityPoint {
        step,
        t: point.t,
        q: DVector::from_column_slice(&point.q.as_slice()[..n]),
        v: DVector::from_column_slice(&point.v.as_slice()[..n]),
        jacobian: end * total * &lifted.start,
    })
}
