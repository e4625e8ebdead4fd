//! RATTLE and its symmetric compositions.
//!
//! # Discrete equations
//! For L = ½ q̇ᵀMq̇ − V(q) ([`crate::model::Structure::ConstantMass`]) and holonomic constraints g(q) = 0
//! with Jacobian G = ∂g/∂q ([`Constraints`]), the discrete variational principle with
//! multipliers over the trapezoidal discrete Lagrangian (Marsden & West 2001, §3.5; Hairer,
//! Lubich & Wanner 2006, §VII.1.4, eq. (1.26)) gives RATTLE, with F = ∂L/∂q = −∇V:
//!
//! p_{k+½} = p_k + (h/2) (F(q_k) − G(q_k)ᵀ λ_k),
//! q_{k+1} = q_k + h M⁻¹ p_{k+½},        g(q_{k+1}) = 0,
//! p_{k+1} = p_{k+½} + (h/2) (F(q_{k+1}) − G(q_{k+1})ᵀ μ_k),   G(q_{k+1}) M⁻¹ p_{k+1} = 0.
//!
//! The position constraint fixes λ_k: q_{k+1}(λ) = q̃ − (h²/2) M⁻¹G(q_k)ᵀ λ is linear in λ, so
//! Newton's method on g(q_{k+1}(λ)) = 0 has the m × m Jacobian −(h²/2) G(q_{k+1}) M⁻¹G(q_k)ᵀ
//! and needs only first derivatives of g (no Hessian of g or of L). The velocity constraint
//! fixes μ_k linearly: with r = p_{k+½} + (h/2) F(q_{k+1}), p_{k+1} = r − Gᵀ S⁻¹ G M⁻¹ r,
//! S = G M⁻¹ Gᵀ at q_{k+1} — the M⁻¹-orthogonal projection of r onto the cotangent space.
//! One gradient of L and one Jacobian of g per step: the end's are the next step's start.
//!
//! # Properties
//! Order 2, symmetric and symplectic on the constraint manifold's cotangent bundle; every step
//! ends on g = 0 and G M⁻¹ p = 0 to the Newton tolerance (round-off), and momenta of
//! symmetries that respect the constraints are conserved exactly. Being symmetric, RATTLE
//! composes like Störmer–Verlet: the compositions of [`Scheme`] (yoshida4, kahan-li6,
//! kahan-li8) give orders 4, 6 and 8 on the manifold (Reich 1996; Hairer, Lubich & Wanner,
//! §V.3 and §VII.1.4).
//!
//! # Dense and sparse
//! This file holds G as a dense m × n matrix: right for a few constraints. Local constraints
//! ([`Constraints::local`], [`crate::model::constraint::local::SparseConstraints`]) with a
//! diagonal mass matrix take the sparse path instead (`rattle/sparse.rs`) — the same
//! equations, iteration and stopping rule with G stored sparsely and sparse LU, O(n) per step
//! — chosen once at the start of the run.

mod sparse;

use super::{ConstrainedIntegrator, ConstrainedPoint, ConstrainedRun, Flow, at_round_off, record};
use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::DenseLu;
use crate::method::variational::composition::Scheme;
use crate::model::Lagrangian;
use crate::model::constraint::sparse::diagonal;
use crate::model::constraint::{
    ConstraintScratch, Constraints, ConstraintsExt, Projected, check_rank,
};
use crate::model::derived::LagrangianExt;
use crate::model::mass_inverse::MassInverse;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DVectorView, DVectorViewMut, DefaultAllocator, OVector};

/// RATTLE, alone or composed.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Rattle {
    /// The composition of RATTLE steps (`None`: RATTLE itself, order 2).
    pub scheme: Option<Scheme>,
    /// Cap on Newton iterations for the multipliers of one (sub-)step.
    pub max_iterations: usize,
}

impl Default for Rattle {
    fn default() -> Self {
        Rattle {
            scheme: None,
            max_iterations: 50,
        }
    }
}

impl Rattle {
    /// RATTLE composed by `scheme` (order 4, 6 or 8).
    pub fn composed(scheme: Scheme) -> Self {
        Rattle {
            scheme: Some(scheme),
            ..Rattle::default()
        }
    }

    /// The order of the method.
    pub fn order(&self) -> usize {
        self.scheme.map_or(2, Scheme::order)
    }

    /// The name: `rattle`, or `rattle-yoshida4`, ...
    pub fn name(&self) -> String {
        match self.scheme {
            None => "rattle".into(),
            Some(scheme) => format!("rattle-{}", scheme.name()),
        }
    }

    /// The step fractions of one step.
    fn fractions(&self) -> Vec<f64> {
        self.scheme.map_or_else(|| vec![1.0], Scheme::fractions)
    }
}

/// Buffers of a constrained run, sized once (no allocation per step).
struct Workspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    mass_inverse: MassInverse<N>,
    scratch: ConstraintScratch<N>,
    /// F = ∂L/∂q, G and M⁻¹Gᵀ at the current point.
    force: OVector<f64, N>,
    jacobian: DMatrix<f64>,
    directions: DMatrix<f64>,
    /// The same at the end of the (sub-)step.
    end_force: OVector<f64, N>,
    end_jacobian: DMatrix<f64>,
    end_directions: DMatrix<f64>,
    /// Multipliers (warm start of the next sub-step's) and Newton's buffers (m × m; also the
    /// velocity projection's S = G M⁻¹ Gᵀ).
    lambda: DVector<f64>,
    residual: DVector<f64>,
    correction: DVector<f64>,
    newton: DenseLu,
    /// The increments of one (sub-)step: q̃ − q_k (with the carry), q_{k+1} − q_k and
    /// p_{k+1} − p_k; q_{k+1}; the shift (h²/2) M⁻¹Gᵀλ; and buffers of n.
    drift: OVector<f64, N>,
    increment: OVector<f64, N>,
    kick: OVector<f64, N>,
    end: OVector<f64, N>,
    shift: DVector<f64>,
    /// The round-off of q and p lost in their last update (compensated summation).
    carry_q: OVector<f64, N>,
    carry_p: OVector<f64, N>,
    row: OVector<f64, N>,
    buffer: OVector<f64, N>,
    zero: OVector<f64, N>,
}

/// The run of [`ConstrainedIntegrator::run`] with RATTLE, from the projected `initial` data.
#[allow(clippy::too_many_arguments)]
pub(super) fn run<N: Dimension, L: Lagrangian<N>, C: Constraints<N>, R: Flow>(
    integrator: &ConstrainedIntegrator<L, C>,
    rattle: &Rattle,
    t0: f64,
    h: f64,
    steps: usize,
    mass_inverse: MassInverse<N>,
    initial: Projected<N>,
    mut observe: impl FnMut(&ConstrainedPoint<N>) -> R,
) -> Result<ConstrainedRun<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(rows) = integrator.constraints.local()
        && let Some(weights) = diagonal(&mass_inverse)
    {
        return sparse::run(
            integrator, rattle, rows, weights, t0, h, steps, initial, observe,
        );
    }
    let stepper = Stepper {
        model: &integrator.model,
        constraints: &integrator.constraints,
        max_iterations: rattle.max_iterations,
    };
    let zero = initial.q.map(|_| 0.0);
    let n = zero.len();
    let q0 = &initial.q;
    let m = stepper.constraints.count();
    let mut workspace = Workspace {
        scratch: ConstraintScratch::new(q0, m),
        force: zero.clone(),
        jacobian: DMatrix::zeros(m, n),
        directions: DMatrix::zeros(n, m),
        end_force: zero.clone(),
        end_jacobian: DMatrix::zeros(m, n),
        end_directions: DMatrix::zeros(n, m),
        lambda: DVector::zeros(m),
        residual: DVector::zeros(m),
        correction: DVector::zeros(m),
        newton: DenseLu::new(m),
        drift: zero.clone(),
        increment: zero.clone(),
        kick: zero.clone(),
        end: zero.clone(),
        shift: DVector::zeros(n),
        carry_q: zero.clone(),
        carry_p: zero.clone(),
        row: zero.clone(),
        buffer: zero.clone(),
        zero,
        mass_inverse,
    };
    let (mut point, mut run) = ConstrainedRun::start(t0, initial, m);
    stepper.evaluate_start(&mut workspace, &point.q)?;
    run.stopped = observe(&point).stops();
    let fractions = rattle.fractions();
    let mut g = DVector::zeros(m);
    let mut rate = DVector::zeros(m);
    for k in 0..steps {
        if run.stopped {
            break;
        }
        for &fraction in &fractions {
            run.iterations += stepper.substep(&mut workspace, fraction * h, k, &mut point)?;
        }
        point.t = t0 + (k + 1) as f64 * h;
        point.multipliers.copy_from(&workspace.lambda);
        workspace
            .mass_inverse
            .apply_into(&point.p, &mut workspace.buffer);
        record(
            &mut run,
            stepper.constraints,
            &point,
            &workspace.jacobian,
            &workspace.buffer,
            (&mut g, &mut rate),
        );
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

/// What one RATTLE step reads: the model, the constraints and the Newton cap.
struct Stepper<'a, L, C> {
    model: &'a L,
    constraints: &'a C,
    max_iterations: usize,
}

impl<L, C> Stepper<'_, L, C> {
    /// F, G and M⁻¹Gᵀ at `q`, the start of the next step.
    fn evaluate_start<N: Dimension>(
        &self,
        workspace: &mut Workspace<N>,
        q: &OVector<f64, N>,
    ) -> Result<(), Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let Workspace {
            mass_inverse,
            scratch,
            force,
            jacobian,
            directions,
            zero,
            row,
            buffer,
            ..
        } = workspace;
        self.model.force_into(0.0, q, zero, force);
        self.constraints.jacobian_into(q, scratch, jacobian);
        check_rank(self.constraints, jacobian)?;
        directions_into(mass_inverse, jacobian, row, buffer, directions);
        Ok(())
    }

    /// One RATTLE step of size `h` from `point` (whose F, G and M⁻¹Gᵀ are the workspace's),
    /// in place; the Newton iterations it took. `step` is the step's index, for errors.
    fn substep<N: Dimension>(
        &self,
        w: &mut Workspace<N>,
        h: f64,
        step: usize,
        point: &mut ConstrainedPoint<N>,
    ) -> Result<usize, Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let half_step = 0.5 * h;
        // The drift q̃ − q_k = h M⁻¹ (p_k + (h/2) F) without the constraint force. q and p are
        // updated by their increments with compensated summation (Kahan): over 10⁶ steps the
        // round-off of adding a small increment to q and p would otherwise drift the
        // conserved momenta by ~1e-12.
        w.kick.copy_from(&point.p);
        w.kick.axpy(half_step, &w.force, 1.0);
        w.mass_inverse.apply_into(&w.kick, &mut w.buffer);
        w.drift.copy_from(&w.carry_q);
        w.drift.axpy(h, &w.buffer, 1.0);
        // Newton on λ: g(q̃ − (h²/2) M⁻¹Gᵀ λ) = 0, from the last step's λ. It stops when the
        // correction to q_{k+1} is at round-off, or stops shrinking near it.
        let reach = -h * half_step;
        let scale = point.q.amax().max(1.0);
        let (mut iterations, mut moved, mut before) = (0, f64::INFINITY, f64::INFINITY);
        loop {
            w.shift.gemv(reach, &w.directions, &w.lambda, 0.0);
            for (((x, i), d), (&q, &s)) in w
                .end
                .iter_mut()
                .zip(w.increment.iter_mut())
                .zip(w.drift.iter())
                .zip(point.q.iter().zip(w.shift.iter()))
            {
                *i = d + s;
                *x = q + *i;
            }
            self.constraints.values_into(&w.end, &mut w.residual);
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
            self.constraints
                .jacobian_into(&w.end, &mut w.scratch, &mut w.end_jacobian);
            let matrix = w.newton.matrix_mut();
            w.end_jacobian.mul_to(&w.directions, matrix);
            matrix.scale_mut(reach);
            w.newton
                .factor()
                .map_err(|_| Error::SingularMatrix { step, t: point.t })?;
            w.correction.copy_from(&w.residual);
            w.newton.solve_in_place(&mut w.correction);
            w.lambda -= &w.correction;
            w.shift.gemv(reach, &w.directions, &w.correction, 0.0);
            (before, moved) = (moved, w.shift.amax());
            iterations += 1;
        }
        // The end: F, G, M⁻¹Gᵀ.
        self.model
            .force_into(0.0, &w.end, &w.zero, &mut w.end_force);
        self.constraints
            .jacobian_into(&w.end, &mut w.scratch, &mut w.end_jacobian);
        directions_into(
            &w.mass_inverse,
            &w.end_jacobian,
            &mut w.row,
            &mut w.buffer,
            &mut w.end_directions,
        );
        // p_{k+1} − p_k = (h/2)(F_k + F_{k+1}) − (h/2) G_kᵀλ − G_{k+1}ᵀμ, with μ = S⁻¹ G M⁻¹ r
        // for r = p_k + the rest (the projection onto the cotangent space at q_{k+1}).
        w.kick.copy_from(&w.force);
        w.kick += &w.end_force;
        w.kick.scale_mut(half_step);
        view_mut(&mut w.kick).gemv_tr(-half_step, &w.jacobian, &w.lambda, 1.0);
        w.buffer.copy_from(&point.p);
        w.buffer += &w.kick;
        w.end_jacobian
            .mul_to(&w.end_directions, w.newton.matrix_mut());
        w.newton
            .factor()
            .map_err(|_| Error::SingularMatrix { step, t: point.t })?;
        w.correction
            .gemv_tr(1.0, &w.end_directions, &view(&w.buffer), 0.0);
        w.newton.solve_in_place(&mut w.correction);
        view_mut(&mut w.kick).gemv_tr(-1.0, &w.end_jacobian, &w.correction, 1.0);
        w.kick += &w.carry_p;
        compensated_add(&mut point.q, &w.increment, &mut w.carry_q);
        compensated_add(&mut point.p, &w.kick, &mut w.carry_p);
        std::mem::swap(&mut w.force, &mut w.end_force);
        std::mem::swap(&mut w.jacobian, &mut w.end_jacobian);
        std::mem::swap(&mut w.directions, &mut w.end_directions);
        Ok(iterations)
    }
}

/// x ← x + increment, with the round-off lost in the sum kept in `carry` (Kahan): the
/// increment already holds the previous carry, so the next step adds it back.
fn compensated_add<N: Dimension>(
    x: &mut OVector<f64, N>,
    increment: &OVector<f64, N>,
    carry: &mut OVector<f64, N>,
) where
    DefaultAllocator: Allocator<N>,
{
    for ((x, &dx), c) in x.iter_mut().zip(increment.iter()).zip(carry.iter_mut()) {
        let sum = *x + dx;
        *c = dx - (sum - *x);
        *x = sum;
    }
}

/// M⁻¹Gᵀ (n × m) into `directions`, column by column (`row` and `buffer` are scratch).
pub(super) fn directions_into<N: Dimension>(
    mass_inverse: &MassInverse<N>,
    jacobian: &DMatrix<f64>,
    row: &mut OVector<f64, N>,
    buffer: &mut OVector<f64, N>,
    directions: &mut DMatrix<f64>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    for i in 0..jacobian.nrows() {
        for (x, &g) in row.iter_mut().zip(jacobian.row(i).iter()) {
            *x = g;
        }
        mass_inverse.apply_into(row, buffer);
        directions.column_mut(i).copy_from(&view(buffer));
    }
}

/// `v` as a vector of run-time size (no copy), for products with the m × n Jacobian.
pub(super) fn view<N: Dimension>(v: &OVector<f64, N>) -> DVectorView<'_, f64>
where
    DefaultAllocator: Allocator<N>,
{
    DVectorView::from_slice(v.as_slice(), v.len())
}

/// `v` as a mutable vector of run-time size (no copy).
pub(super) fn view_mut<N: Dimension>(v: &mut OVector<f64, N>) -> DVectorViewMut<'_, f64>
where
    DefaultAllocator: Allocator<N>,
{
    let len = v.len();
    DVectorViewMut::from_slice(v.as_mut_slice(), len)
}
