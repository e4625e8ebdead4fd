//! The constrained discrete Euler–Lagrange equations of the segment discrete Lagrangians:
//! symplectic Euler (and its adjoint), midpoint and trapezoid with holonomic constraints.
//!
//! # Discrete equations
//! For a discrete Lagrangian L_d(q_k, q_{k+1}) ([`DiscreteLagrangian`]: the segment rules of
//! [`crate::method::variational::discrete_lagrangian`]) the discrete action with multipliers
//! Σ L_d(q_k, q_{k+1}) − Σ λ_kᵀ g(q_k) is stationary when (Marsden & West 2001, §3.5)
//!
//! p_k + D1 L_d(q_k, q_{k+1}) − G(q_k)ᵀ λ_k = 0,   g(q_{k+1}) = 0,
//! p̃_{k+1} = D2 L_d(q_k, q_{k+1}),
//!
//! and p_{k+1} = p̃_{k+1} − G(q_{k+1})ᵀ μ_k is the projection of p̃ onto the cotangent space
//! G(q_{k+1}) q̇(q_{k+1}, p_{k+1}) = 0 (the node's multiplier split between its two steps, as
//! in RATTLE). Each step solves the bordered system for (q_{k+1}, λ_k) by Newton's method,
//! with the matrix [[D12 L_d, −G(q_k)ᵀ], [G(q_{k+1}), 0]] from hyper-dual numbers (D1 L_d and
//! D12 L_d in one sweep per pair of coordinates) — first derivatives of g only.
//!
//! The trapezoidal rule with L = ½ q̇ᵀMq̇ − V(q) gives RATTLE's positions and momenta (the
//! tests check it to round-off); the midpoint rule is the constrained SVI with two nodes and
//! one Gauss point. All four are symplectic on the constraint manifold's cotangent bundle;
//! symplectic Euler and its adjoint are of order 1, midpoint and trapezoid of order 2.

use super::{
    ConstrainedIntegrator, ConstrainedPoint, ConstrainedRun, Flow, Projection, at_round_off,
    newton_correction, record,
};
use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::DenseLu;
use crate::method::variational::discrete_lagrangian::{
    AdjointSymplecticEuler, DiscreteLagrangian, Midpoint, SymplecticEuler, Trapezoid,
};
use crate::model::Lagrangian;
use crate::model::constraint::{
    ConstraintScratch, Constraints, ConstraintsExt, Projected, check_rank,
};
use crate::model::derived::LagrangianExt;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector};
use num_dual::{Dual64, HyperDual64};

/// A segment discrete Lagrangian with constraints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SegmentRule {
    /// L_d = h L(q_k, v): order 1.
    SymplecticEuler,
    /// L_d = h L(q_{k+1}, v): order 1.
    SymplecticEulerAdjoint,
    /// L_d = h L((q_k + q_{k+1})/2, v): order 2.
    Midpoint,
    /// L_d = ½h L(q_k, v) + ½h L(q_{k+1}, v): order 2.
    Trapezoid,
}

impl SegmentRule {
    /// Every rule.
    pub const ALL: [SegmentRule; 4] = [
        SegmentRule::SymplecticEuler,
        SegmentRule::SymplecticEulerAdjoint,
        SegmentRule::Midpoint,
        SegmentRule::Trapezoid,
    ];

    /// The name, as the unconstrained method's in the registry.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The order.
    pub fn order(self) -> usize {
        self.info().order
    }

    /// Whether the rule is symmetric (midpoint and trapezoid).
    pub fn symmetric(self) -> bool {
        self.info().symmetric
    }

    fn info(self) -> crate::method::variational::discrete_lagrangian::DiscreteLagrangianInfo {
        match self {
            SegmentRule::SymplecticEuler => SymplecticEuler.info(),
            SegmentRule::SymplecticEulerAdjoint => AdjointSymplecticEuler.info(),
            SegmentRule::Midpoint => Midpoint.info(),
            SegmentRule::Trapezoid => Trapezoid.info(),
        }
    }

    /// The rule called `name`.
    pub fn named(name: &str) -> Option<Self> {
        SegmentRule::ALL
            .into_iter()
            .find(|rule| rule.name() == name)
    }
}

/// The constrained discrete Euler–Lagrange equations of a segment rule.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ConstrainedDel {
    /// The discrete Lagrangian.
    pub rule: SegmentRule,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl ConstrainedDel {
    /// `rule` with the default cap on Newton iterations.
    pub fn new(rule: SegmentRule) -> Self {
        ConstrainedDel {
            rule,
            max_iterations: 50,
        }
    }
}

/// The run of [`ConstrainedIntegrator::run`] with a constrained segment rule.
pub(super) fn run<N: Dimension, L: Lagrangian<N>, C: Constraints<N>, R: Flow>(
    integrator: &ConstrainedIntegrator<L, C>,
    method: &ConstrainedDel,
    t0: f64,
    h: f64,
    steps: usize,
    initial: Projected<N>,
    observe: impl FnMut(&ConstrainedPoint<N>) -> R,
) -> Result<ConstrainedRun<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let run = Stepper {
        model: &integrator.model,
        constraints: &integrator.constraints,
        max_iterations: method.max_iterations,
    };
    match method.rule {
        SegmentRule::SymplecticEuler => run.run(&SymplecticEuler, t0, h, steps, initial, observe),
        SegmentRule::SymplecticEulerAdjoint => {
            run.run(&AdjointSymplecticEuler, t0, h, steps, initial, observe)
        }
        SegmentRule::Midpoint => run.run(&Midpoint, t0, h, steps, initial, observe),
        SegmentRule::Trapezoid => run.run(&Trapezoid, t0, h, steps, initial, observe),
    }
}

/// What a step reads.
struct Stepper<'a, L, C> {
    model: &'a L,
    constraints: &'a C,
    max_iterations: usize,
}

/// Buffers of a run, sized once.
struct Workspace<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    scratch: ConstraintScratch<N>,
    /// G(q_k) and G(q_{k+1}), g(q_{k+1}).
    start_jacobian: DMatrix<f64>,
    end_jacobian: DMatrix<f64>,
    values: DVector<f64>,
    /// q_{k+1} and λ_k, the residual, the Newton matrix.
    end: OVector<f64, N>,
    lambda: DVector<f64>,
    residual: DVector<f64>,
    newton: DenseLu,
    /// q_k, q_{k+1} as hyper-dual and dual numbers.
    hyper_start: OVector<HyperDual64, N>,
    hyper_end: OVector<HyperDual64, N>,
    dual_start: OVector<Dual64, N>,
    dual_end: OVector<Dual64, N>,
    momentum: OVector<f64, N>,
    projection: Projection<N>,
}

impl<L, C> Stepper<'_, L, C> {
    fn run<N: Dimension, Ld: DiscreteLagrangian, R: Flow>(
        &self,
        rule: &Ld,
        t0: f64,
        h: f64,
        steps: usize,
        initial: Projected<N>,
        mut observe: impl FnMut(&ConstrainedPoint<N>) -> R,
    ) -> Result<ConstrainedRun<N>, Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (n, m) = (initial.q.len(), self.constraints.count());
        let zero = initial.q.map(|_| 0.0);
        let mut w = Workspace {
            scratch: ConstraintScratch::new(&initial.q, m),
            start_jacobian: DMatrix::zeros(m, n),
            end_jacobian: DMatrix::zeros(m, n),
            values: DVector::zeros(m),
            end: zero.clone(),
            lambda: DVector::zeros(m),
            residual: DVector::zeros(n + m),
            newton: DenseLu::new(n + m),
            hyper_start: initial.q.map(HyperDual64::from_re),
            hyper_end: initial.q.map(HyperDual64::from_re),
            dual_start: initial.q.map(Dual64::from_re),
            dual_end: initial.q.map(Dual64::from_re),
            momentum: zero.clone(),
            projection: Projection::new(&zero, m),
        };
        let (mut point, mut run) = ConstrainedRun::start(t0, initial, m);
        self.constraints
            .jacobian_into(&point.q, &mut w.scratch, &mut w.start_jacobian);
        check_rank(self.constraints, &w.start_jacobian)?;
        let mut velocity = self.model.velocity(t0, &point.q, &point.p, &zero)?;
        run.stopped = observe(&point).stops();
        let (mut g, mut rate) = (DVector::zeros(m), DVector::zeros(m));
        for k in 0..steps {
            if run.stopped {
                break;
            }
            let t = t0 + k as f64 * h;
            run.iterations += self.step(rule, &mut w, t, h, k, &mut point, &mut velocity)?;
            point.t = t0 + (k + 1) as f64 * h;
            record(
                &mut run,
                self.constraints,
                &point,
                &w.start_jacobian,
                &velocity,
                (&mut g, &mut rate),
            );
            run.stopped = observe(&point).stops();
        }
        // One L_d per pair of coordinates per Newton iteration, one per coordinate for p̃.
        let points = rule.info().points;
        run.evaluations = (run.iterations * n * n + run.steps * n) * points;
        run.factorizations = run.iterations + w.projection.factorizations;
        run.last = point;
        Ok(run)
    }

    /// One step from `point` in place; the Newton iterations. On return `w.start_jacobian`
    /// is G(q_{k+1}) and `velocity` the velocity there.
    #[allow(clippy::too_many_arguments)]
    fn step<N: Dimension, Ld: DiscreteLagrangian>(
        &self,
        rule: &Ld,
        w: &mut Workspace<N>,
        t: f64,
        h: f64,
        step: usize,
        point: &mut ConstrainedPoint<N>,
        velocity: &mut OVector<f64, N>,
    ) -> Result<usize, Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (n, m) = (point.q.len(), self.constraints.count());
        w.end.copy_from(&point.q);
        w.end.axpy(h, velocity, 1.0);
        for (dual, &x) in w.hyper_start.iter_mut().zip(point.q.iter()) {
            *dual = HyperDual64::from_re(x);
        }
        let scale = point.q.amax().max(1.0);
        let (mut iterations, mut before) = (0, f64::INFINITY);
        let (th, hh) = (HyperDual64::from_re(t), HyperDual64::from_re(h));
        loop {
            // D1 L_d and D12 L_d at (q_k, q_{k+1}): ε₁ along q_k,a, ε₂ along q_{k+1},b.
            for (dual, &x) in w.hyper_end.iter_mut().zip(w.end.iter()) {
                *dual = HyperDual64::from_re(x);
            }
            let matrix = w.newton.matrix_mut();
            for a in 0..n {
                w.hyper_start[a].eps1 = 1.0;
                for b in 0..n {
                    w.hyper_end[b].eps2 = 1.0;
                    let value =
                        rule.discrete_lagrangian(self.model, th, hh, &w.hyper_start, &w.hyper_end);
                    w.hyper_end[b].eps2 = 0.0;
                    matrix[(a, b)] = value.eps1eps2;
                    w.residual[a] = value.eps1;
                }
                w.hyper_start[a].eps1 = 0.0;
            }
            for a in 0..n {
                w.residual[a] += point.p[a];
                for e in 0..m {
                    w.residual[a] -= w.start_jacobian[(e, a)] * w.lambda[e];
                    matrix[(a, n + e)] = -w.start_jacobian[(e, a)];
                }
            }
            self.constraints.values_into(&w.end, &mut w.values);
            self.constraints
                .jacobian_into(&w.end, &mut w.scratch, &mut w.end_jacobian);
            for e in 0..m {
                w.residual[n + e] = w.values[e];
                for b in 0..n {
                    matrix[(n + e, b)] = w.end_jacobian[(e, b)];
                }
                for f in 0..m {
                    matrix[(n + e, n + f)] = 0.0;
                }
            }
            newton_correction(&mut w.newton, &mut w.residual, (step, t, iterations))?;
            for a in 0..n {
                w.end[a] += w.residual[a];
            }
            for e in 0..m {
                w.lambda[e] += w.residual[n + e];
            }
            iterations += 1;
            let moved = w.residual.rows(0, n).amax();
            if at_round_off(moved, before, scale) {
                break;
            }
            if iterations == self.max_iterations {
                return Err(Error::NonConvergence {
                    step,
                    t,
                    iterations,
                    residual: moved,
                });
            }
            before = moved;
        }
        // p̃_{k+1} = D2 L_d(q_k, q_{k+1}), one dual sweep per coordinate of q_{k+1}.
        let (td, hd) = (Dual64::from_re(t), Dual64::from_re(h));
        for (dual, &x) in w.dual_start.iter_mut().zip(point.q.iter()) {
            *dual = Dual64::from_re(x);
        }
        for (dual, &x) in w.dual_end.iter_mut().zip(w.end.iter()) {
            *dual = Dual64::from_re(x);
        }
        for b in 0..n {
            w.dual_end[b].eps = 1.0;
            w.momentum[b] = rule
                .discrete_lagrangian(self.model, td, hd, &w.dual_start, &w.dual_end)
                .eps;
            w.dual_end[b].eps = 0.0;
        }
        point.q.copy_from(&w.end);
        point.multipliers.copy_from(&w.lambda);
        self.constraints
            .jacobian_into(&point.q, &mut w.scratch, &mut w.start_jacobian);
        *velocity = w.projection.project(
            self.model,
            t + h,
            &point.q,
            &w.start_jacobian,
            &mut w.momentum,
            velocity,
            (step, self.max_iterations),
        )?;
        point.p.copy_from(&w.momentum);
        Ok(iterations)
    }
}
