//! RATTLE on local constraints ([`crate::model::constraint::local`]) with a diagonal mass
//! matrix: the same discrete equations as [`super`], every piece O(n).
//!
//! The dense path holds G (m × n) and M⁻¹Gᵀ (n × m) and factors m × m matrices by dense LU:
//! O(n²) memory, O(n³) work per step for a chain of n bonds. Here G is stored row by row (K
//! entries a row, [`SparseJacobian`]), M⁻¹ = diag(w) is applied entry by entry, and the two
//! m × m matrices of a step — Newton's −(h²/2) G(q_{k+1}) M⁻¹ G(q_k)ᵀ and the velocity
//! projection's S = G M⁻¹ Gᵀ at q_{k+1} — share one pattern (rows that share a coordinate),
//! fixed once per run, assembled from a precomputed list of products and factored by faer's
//! sparse LU (symbolic analysis once, numeric factorisation per Newton iteration: [`Schur`]).
//! Nothing is allocated per step. The rank of G is checked at the start in O(n)
//! ([`crate::model::constraint::sparse::check_rank`]).
//!
//! With the same iteration and stopping rule as the dense path, the two agree to round-off.

use super::{Rattle, compensated_add};
use crate::dimension::Dimension;
use crate::error::Error;
use crate::method::constrained::{
    ConstrainedIntegrator, ConstrainedPoint, ConstrainedRun, Flow, at_round_off,
};
use crate::model::Lagrangian;
use crate::model::constraint::Projected;
use crate::model::constraint::local::ConstraintRows;
use crate::model::constraint::sparse::{Schur, SparseJacobian, check_rank};
use crate::model::derived::LagrangianExt;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector};

/// Buffers of a sparse constrained run, sized once (no allocation per step).
struct Workspace<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The diagonal of M⁻¹.
    weights: Vec<f64>,
    /// F = ∂L/∂q and G at the current point, and at the end of the (sub-)step.
    force: OVector<f64, N>,
    jacobian: SparseJacobian,
    end_force: OVector<f64, N>,
    end_jacobian: SparseJacobian,
    /// Newton's matrix and the velocity projection's S, on one pattern.
    schur: Schur,
    /// Multipliers (warm start of the next sub-step's) and Newton's buffers (length m).
    lambda: DVector<f64>,
    residual: DVector<f64>,
    correction: DVector<f64>,
    /// As in the dense path: q̃ − q_k (with the carry), q_{k+1} − q_k, p_{k+1} − p_k,
    /// q_{k+1}, the carries of compensated summation, and buffers of n.
    drift: OVector<f64, N>,
    increment: OVector<f64, N>,
    kick: OVector<f64, N>,
    end: OVector<f64, N>,
    carry_q: OVector<f64, N>,
    carry_p: OVector<f64, N>,
    shift: Vec<f64>,
    zero: OVector<f64, N>,
}

/// What one step reads: the model, the constraints' rows and the Newton cap.
struct Stepper<'a, L> {
    model: &'a L,
    rows: &'a dyn ConstraintRows,
    max_iterations: usize,
}

/// The run of [`ConstrainedIntegrator::run`] with RATTLE on the sparse path, from the
/// projected `initial` data, with M⁻¹ = diag(`weights`).
#[allow(clippy::too_many_arguments)]
pub(super) fn run<N: Dimension, L: Lagrangian<N>, C, R: Flow>(
    integrator: &ConstrainedIntegrator<L, C>,
    rattle: &Rattle,
    rows: &dyn ConstraintRows,
    weights: Vec<f64>,
    t0: f64,
    h: f64,
    steps: usize,
    initial: Projected<N>,
    mut observe: impl FnMut(&ConstrainedPoint<N>) -> R,
) -> Result<ConstrainedRun<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let stepper = Stepper {
        model: &integrator.model,
        rows,
        max_iterations: rattle.max_iterations,
    };
    let zero = initial.q.map(|_| 0.0);
    let n = zero.len();
    let m = rows.count();
    let jacobian = SparseJacobian::new(rows, n)?;
    let schur = Schur::new(&jacobian, n)?;
    let mut workspace = Workspace {
        weights,
        force: zero.clone(),
        end_jacobian: jacobian.clone(),
        jacobian,
        end_force: zero.clone(),
        schur,
        lambda: DVector::zeros(m),
        residual: DVector::zeros(m),
        correction: DVector::zeros(m),
        drift: zero.clone(),
        increment: zero.clone(),
        kick: zero.clone(),
        end: zero.clone(),
        carry_q: zero.clone(),
        carry_p: zero.clone(),
        shift: vec![0.0; n],
        zero,
    };
    let (mut point, mut run) = ConstrainedRun::start(t0, initial, m);
    {
        let w = &mut workspace;
        check_rank(
            rows,
            point.q.as_slice(),
            &w.weights,
            &mut w.jacobian,
            &mut w.schur,
        )?;
        stepper
            .model
            .force_into(0.0, &point.q, &w.zero, &mut w.force);
    }
    run.stopped = observe(&point).stops();
    let fractions = rattle.fractions();
    let (mut g, mut rate) = (vec![0.0; m], vec![0.0; m]);
    for k in 0..steps {
        if run.stopped {
            break;
        }
        for &fraction in &fractions {
            run.iterations += stepper.substep(&mut workspace, fraction * h, k, &mut point)?;
        }
        point.t = t0 + (k + 1) as f64 * h;
        point.multipliers.copy_from(&workspace.lambda);
        // The constraint violations at the new point: |g(q)| and |G M⁻¹ p|.
        let w = &mut workspace;
        rows.values_into(point.q.as_slice(), &mut g);
        for ((s, p), weight) in w.shift.iter_mut().zip(point.p.iter()).zip(&w.weights) {
            *s = weight * p;
        }
        w.jacobian.mul_into(&w.shift, &mut rate);
        run.constraint_error_max = run.constraint_error_max.max(amax(&g));
        run.velocity_constraint_error_max = run.velocity_constraint_error_max.max(amax(&rate));
        run.steps += 1;
        run.stopped = observe(&point).stops();
    }
    // The force once at the start and once per sub-step; a matrix per Newton iteration and
    // per sub-step's velocity projection.
    let substeps = run.steps * fractions.len();
    run.evaluations = 1 + substeps;
    run.factorizations = run.iterations + substeps;
    run.last = point;
    Ok(run)
}

/// max |xᵢ| (NaN wins, so a non-finite violation shows).
fn amax(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |max: f64, v| {
        if v.abs() > max || v.is_nan() {
            v.abs()
        } else {
            max
        }
    })
}

impl<L> Stepper<'_, L> {
    /// One RATTLE step of size `h` from `point` (whose F and G are the workspace's), in
    /// place; the Newton iterations it took. `step` is the step's index, for errors. The
    /// dense path's [`super::Stepper::substep`], line for line, with sparse products.
    fn substep<N: Dimension>(
        &self,
        w: &mut Workspace<N>,
        h: f64,
        step: usize,
        point: &mut ConstrainedPoint<N>,
    ) -> Result<usize, Error>
    where
        L: Lagrangian<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let half_step = 0.5 * h;
        let singular = || Error::SingularMatrix { step, t: point.t };
        // The drift q̃ − q_k = h M⁻¹ (p_k + (h/2) F), with the carry of q.
        for (((d, &c), &p), (&f, &weight)) in w
            .drift
            .iter_mut()
            .zip(w.carry_q.iter())
            .zip(point.p.iter())
            .zip(w.force.iter().zip(&w.weights))
        {
            *d = c + h * (weight * (p + half_step * f));
        }
        // Newton on λ: g(q̃ − (h²/2) M⁻¹G_kᵀ λ) = 0, from the last step's λ.
        let reach = -h * half_step;
        let scale = point.q.amax().max(1.0);
        let (mut iterations, mut moved, mut before) = (0, f64::INFINITY, f64::INFINITY);
        loop {
            self.scaled_directions(w, reach, Multipliers::Lambda);
            for (((x, i), d), (&q, &s)) in w
                .end
                .iter_mut()
                .zip(w.increment.iter_mut())
                .zip(w.drift.iter())
                .zip(point.q.iter().zip(&w.shift))
            {
                *i = d + s;
                *x = q + *i;
            }
            self.rows
                .values_into(w.end.as_slice(), w.residual.as_mut_slice());
            let floor = at_round_off(moved, before, scale);
            if floor {
                break;
            }
            if iterations == self.max_iterations || !w.residual.iter().all(|x| x.is_finite()) {
                return Err(Error::NonConvergence {
                    step,
                    t: point.t,
                    iterations,
                    residual: moved,
                });
            }
            w.end_jacobian.evaluate(self.rows, w.end.as_slice());
            w.schur
                .assemble(reach, &w.end_jacobian, &w.weights, &w.jacobian);
            w.correction.copy_from(&w.residual);
            if !(w.schur.factor() && w.schur.solve_in_place(&mut w.correction)) {
                return Err(singular());
            }
            w.lambda -= &w.correction;
            self.scaled_directions(w, reach, Multipliers::Correction);
            (before, moved) = (moved, amax(&w.shift));
            iterations += 1;
        }
        // The end: F and G.
        self.model
            .force_into(0.0, &w.end, &w.zero, &mut w.end_force);
        w.end_jacobian.evaluate(self.rows, w.end.as_slice());
        // p_{k+1} − p_k = (h/2)(F_k + F_{k+1}) − (h/2) G_kᵀλ − G_{k+1}ᵀμ, with μ = S⁻¹ G M⁻¹ r
        // for r = p_k + the rest (the projection onto the cotangent space at q_{k+1}).
        for ((k, &f), &e) in w
            .kick
            .iter_mut()
            .zip(w.force.iter())
            .zip(w.end_force.iter())
        {
            *k = half_step * (f + e);
        }
        w.jacobian
            .tr_mul_add(-half_step, w.lambda.as_slice(), w.kick.as_mut_slice());
        for (((s, &p), &k), &weight) in w
            .shift
            .iter_mut()
            .zip(point.p.iter())
            .zip(w.kick.iter())
            .zip(&w.weights)
        {
            *s = weight * (p + k);
        }
        w.schur
            .assemble(1.0, &w.end_jacobian, &w.weights, &w.end_jacobian);
        w.end_jacobian
            .mul_into(&w.shift, w.correction.as_mut_slice());
        if !(w.schur.factor() && w.schur.solve_in_place(&mut w.correction)) {
            return Err(singular());
        }
        w.end_jacobian
            .tr_mul_add(-1.0, w.correction.as_slice(), w.kick.as_mut_slice());
        w.kick += &w.carry_p;
        compensated_add(&mut point.q, &w.increment, &mut w.carry_q);
        compensated_add(&mut point.p, &w.kick, &mut w.carry_p);
        std::mem::swap(&mut w.force, &mut w.end_force);
        std::mem::swap(&mut w.jacobian, &mut w.end_jacobian);
        Ok(iterations)
    }

    /// `shift` = `reach` M⁻¹ G_kᵀ x for x = λ or Newton's correction.
    fn scaled_directions<N: Dimension>(
        &self,
        w: &mut Workspace<N>,
        reach: f64,
        multipliers: Multipliers,
    ) where
        DefaultAllocator: Allocator<N>,
    {
        let x = match multipliers {
            Multipliers::Lambda => &w.lambda,
            Multipliers::Correction => &w.correction,
        };
        w.shift.fill(0.0);
        w.jacobian.tr_mul_add(1.0, x.as_slice(), &mut w.shift);
        for (s, &weight) in w.shift.iter_mut().zip(&w.weights) {
            *s *= reach * weight;
        }
    }
}

/// Which multipliers [`Stepper::scaled_directions`] maps.
#[derive(Clone, Copy)]
enum Multipliers {
    Lambda,
    Correction,
}
