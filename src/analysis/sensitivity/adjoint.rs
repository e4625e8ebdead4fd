//! The discrete adjoint: the gradient of a loss of the trajectory by the transposed tangent
//! maps swept backwards, with the forward states kept at checkpoints (see the
//! [module](super) documentation).

use super::SensitivityRun;
use super::lifted::{Lifted, Walker, chosen_parameters, lift};
use crate::dimension::{Dimension, Dyn};
use crate::error::Error;
use crate::method::StepAdjoint;
use crate::method::space::PhasePoint;
use crate::method::{Euclidean, Method};
use crate::model::Lagrangian;
use crate::model::parametric::Parametric;
use crate::scalar::Scalar;
use crate::stepping::run::{Integrator, Statistics};
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator};
use num_dual::Dual64;

/// A scalar loss of a trajectory, J = Σ_j ℓ_j(t, q, q̇) over the run's outputs, written once
/// generic over the scalar: its gradient comes by automatic differentiation.
pub trait Loss {
    /// ℓ_j at output number `output` (0: the start), time `t`, configuration `q` and
    /// velocity `v` (n entries each).
    fn loss<D: Scalar>(&self, output: usize, t: f64, q: &[D], v: &[D]) -> D;
}

/// How many forward states the adjoint keeps ([`Integrator::gradient`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Checkpoints {
    /// ⌈√K⌉ checkpoints for K steps: every segment between two is run again once, and at
    /// most about 2√K states and steps' adjoints are held at once (the default).
    #[default]
    Sqrt,
    /// This many checkpoints (at least 1, the start; at most K): fewer keep less and hold
    /// longer segments.
    Budget(usize),
}

impl Checkpoints {
    /// The length of a segment between two checkpoints of a run of `steps` steps.
    fn segment(self, steps: usize) -> Result<usize, Error> {
        let count = match self {
            Checkpoints::Sqrt => (steps as f64).sqrt().ceil() as usize,
            Checkpoints::Budget(0) => {
                return Err(Error::invalid(
                    "checkpoints",
                    "a budget of 0 checkpoints: at least 1 (the start) is needed",
                ));
            }
            Checkpoints::Budget(count) => count,
        };
        Ok(steps.div_ceil(count.clamp(1, steps.max(1))))
    }
}

/// The gradient of a loss of a run ([`Integrator::gradient`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Gradient {
    /// J, the loss summed over the outputs.
    pub value: f64,
    /// ∂J/∂q₀ (n entries), then ∂J/∂q̇₀ (or ∂J/∂p₀ for a start given in momenta).
    pub initial: DVector<f64>,
    /// ∂J/∂θ for the parameters asked, in their order.
    pub parameters: DVector<f64>,
    /// The parameters' names, in order.
    pub names: Vec<String>,
    /// The most forward states (checkpoints) and steps' adjoints (of one segment,
    /// [`crate::StepAdjoint`]) held at once.
    pub peak_stored: usize,
    /// The memory they took at the peak, in bytes.
    pub peak_bytes: usize,
    /// The work of every step taken: the forward run and the segments run again by tangent
    /// maps.
    pub statistics: Statistics,
}

impl<L: Parametric<N>, M: Method<N> + Method<Dyn> + Clone, N: Dimension>
    Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The gradient of `loss`, summed over the outputs of `run`, with respect to the initial
    /// state and the parameters `run.parameters`, by the discrete adjoint: the exact
    /// gradient of the method's discrete map (see [`crate::analysis::sensitivity`]), with
    /// the forward states kept at `checkpoints`.
    ///
    /// # Errors
    /// Those of [`Integrator::sensitivities`]; a checkpoint budget of 0
    /// ([`Error::InvalidParameter`] `checkpoints`); a loss whose value or gradient is not
    /// finite ([`Error::NonFinite`] "loss at output j").
    pub fn gradient<F: Loss>(
        &self,
        run: &SensitivityRun<N>,
        loss: &F,
        checkpoints: Checkpoints,
    ) -> Result<Gradient, Error> {
        let (chosen, lifts) = chosen_parameters(self.model(), run)?;
        if lifts {
            let hat = lift(self, &chosen);
            adjoint::<_, _, _, Dyn>(
                &Lifted::<_, _, Dyn>::new(&hat, self.model(), &chosen, run)?,
                loss,
                checkpoints,
            )
        } else {
            adjoint::<_, _, _, N>(
                &Lifted::<_, _, N>::new(self, self.model(), &chosen, run)?,
                loss,
                checkpoints,
            )
        }
    }
}

/// The gradient of `loss` over the run `lifted` by the discrete adjoint.
fn adjoint<F: Loss, R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension>(
    lifted: &Lifted<'_, R, M, D>,
    loss: &F,
    checkpoints: Checkpoints,
) -> Result<Gradient, Error>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let (m, steps) = (lifted.m, lifted.grid.3);
    let segment = checkpoints.segment(steps)?;
    let mut walker = Walker::new(lifted)?;
    // The forward run, keeping the state at the start of every segment; the output
    // numbers j count the outputs from the start.
    let mut stored = Vec::with_capacity(steps.div_ceil(segment));
    let mut output_number = vec![0usize; steps + 1];
    let mut outputs = 0;
    for (k, number) in output_number.iter_mut().enumerate() {
        if lifted.is_output(k) {
            *number = outputs;
            outputs += 1;
        }
    }
    let start_cursor = walker.cursor.clone();
    for k in 0..steps {
        if k.is_multiple_of(segment) {
            stored.push((k, walker.cursor.clone()));
        }
        walker.step(k)?;
    }
    // Backwards, segment by segment: the segment's steps' adjoints from its checkpoint,
    // then λ_k = Φ_kᵀ λ_{k+1} + G_kᵀ∇ℓ_k through it.
    let mut lambda = DVector::zeros(2 * m);
    let mut scratch = DVector::zeros(2 * m);
    let mut value = 0.0;
    // One slot per step of a segment, reused from segment to segment.
    let mut kept: Vec<StepAdjoint<D>> = (0..segment.min(steps))
        .map(|_| StepAdjoint::empty())
        .collect();
    let mut terms: Vec<Option<DVector<f64>>> = Vec::with_capacity(segment);
    let mut peak_bytes = 0;
    for (a, cursor) in stored.iter().rev() {
        let b = (a + segment).min(steps);
        walker.restart_at(cursor.clone());
        terms.clear();
        for (k, slot) in (*a..b).zip(&mut kept) {
            walker.step_adjoint(k, slot)?;
            terms.push(if lifted.is_output(k + 1) {
                let point = walker.point(k + 1)?;
                let (ell, term) = loss_term(lifted, loss, output_number[k + 1], &point, k + 1)?;
                value += ell;
                Some(term)
            } else {
                None
            });
        }
        peak_bytes = peak_bytes.max(kept[..b - a].iter().map(StepAdjoint::bytes).sum());
        for ((k, slot), term) in (*a..b).zip(&kept).zip(&terms).rev() {
            if let Some(term) = term {
                lambda += term;
            }
            walker.apply_adjoint(k, slot, &mut lambda, &mut scratch)?;
        }
    }
    walker.restart_at(start_cursor);
    let point = walker.point(0)?;
    let (ell, term) = loss_term(lifted, loss, 0, &point, 0)?;
    value += ell;
    lambda += term;
    let gradient = lifted.start.tr_mul(&lambda);
    let n = lifted.n;
    let state_bytes = 2 * (2 * m) * std::mem::size_of::<f64>();
    Ok(Gradient {
        value,
        initial: gradient.rows(0, 2 * n).into_owned(),
        parameters: gradient.rows(2 * n, gradient.len() - 2 * n).into_owned(),
        names: lifted.names.clone(),
        peak_stored: stored.len() + segment,
        peak_bytes: stored.len() * state_bytes + peak_bytes,
        statistics: walker.statistics,
    })
}

/// ℓ_j at `point` and its gradient G_kᵀ∇ℓ_j in the lifted state's coordinates.
fn loss_term<F: Loss, R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension>(
    lifted: &Lifted<'_, R, M, D>,
    loss: &F,
    output: usize,
    point: &PhasePoint<D>,
    step: usize,
) -> Result<(f64, DVector<f64>), Error>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let n = lifted.n;
    let (q, v) = (&point.q.as_slice()[..n], &point.v.as_slice()[..n]);
    let value = loss.loss(output, point.t, q, v);
    let mut lifted_q: Vec<Dual64> = q.iter().map(|&x| Dual64::from(x)).collect();
    let mut lifted_v: Vec<Dual64> = v.iter().map(|&x| Dual64::from(x)).collect();
    let mut nabla = DVector::zeros(2 * n);
    for i in 0..2 * n {
        let seeded = if i < n {
            &mut lifted_q[i]
        } else {
            &mut lifted_v[i - n]
        };
        seeded.eps = 1.0;
        nabla[i] = loss.loss(output, point.t, &lifted_q, &lifted_v).eps;
        let seeded = if i < n {
            &mut lifted_q[i]
        } else {
            &mut lifted_v[i - n]
        };
        seeded.eps = 0.0;
    }
    if !(value.is_finite() && nabla.iter().all(|x| x.is_finite())) {
        return Err(Error::NonFinite {
            what: format!("loss at output {output} (its value or gradient)"),
            step,
            t: point.t,
        });
    }
    Ok((value, lifted.end(point)?.tr_mul(&nabla)))
}
