//! Constrained Galerkin variational integrators: the constrained SVI and the constrained
//! midpoint rule.
//!
//! # Discrete equations
//! On a step [t_k, t_k + h] the curve is the polynomial through s + 1 Chebyshev–Gauss–Lobatto
//! nodes Q_0 = q_k, Q_1, …, Q_s = q_{k+1} (basis φᵢ on τ ∈ [−1, 1], t = t_k + h(τ + 1)/2), and
//! the discrete action is the Gauss–Legendre sum A = Σⱼ (h/2) wⱼ L(tⱼ, q(cⱼ), q̇(cⱼ)) (the
//! SVI's, 8a–8c). The constraints are imposed at r *constraint points* τ_c inside the step
//! with multipliers Λ_c, and at the step's end, whose multiplier λ_0 belongs to the node Q_0
//! shared with the previous step. The discrete action with multipliers
//! Σ_k [A_k − Σ_c Λ_cᵀ g(q(τ_c))] − Σ_k λ_kᵀ g(q_k) is stationary when, with
//! ψᵢ(c) = φᵢ(τ_c) and G = ∂g/∂q,
//!
//! p_k + ∂A/∂Q_0 − Σ_c ψ_0(c) G(q_c)ᵀΛ_c − G(q_k)ᵀλ_0 = 0,
//! ∂A/∂Qᵢ − Σ_c ψᵢ(c) G(q_c)ᵀΛ_c = 0   (i = 1, …, s − 1),
//! g(q(τ_c)) = 0 for every c,   g(Q_s) = 0,
//!
//! s·n + (r + 1)·m equations in Q_1…Q_s, Λ and λ_0, solved together by Newton's method with
//! the exact Jacobian (the Hessian blocks of L and the Hessian of Λᵀg, by automatic
//! differentiation). Then p̃_{k+1} = ∂A/∂Q_s, and p_{k+1} = p̃_{k+1} − G(q_{k+1})ᵀμ is its
//! projection onto the cotangent space, G(q_{k+1}) q̇(q_{k+1}, p_{k+1}) = 0 (q̇ the inverse
//! Legendre map): the multiplier of the node q_{k+1} is split between the two steps it joins,
//! so the positions are those of the constrained discrete Euler–Lagrange equations and the
//! method is their position–momentum form (Marsden & West 2001, §3.5).
//!
//! # Where the constraints are imposed
//! At r = s − 1 points, so that with the end the s unknown nodes meet s constraints: a linear
//! constraint then holds along the whole curve, and no more points fit (with r ≥ s a linear
//! g would be over-determined and the multipliers not unique — the Newton matrix is singular).
//! [`ConstraintPoints::Quadrature`] (the default) takes the points of the (s − 1)-point
//! Gauss–Legendre rule, [`ConstraintPoints::Nodes`] the interior nodes (ψ a unit vector).
//! Either way the discrete Lagrangian is the constrained extremum of A over polynomials
//! pinned at q_k and q_{k+1} on the constraint manifold, so the method is symplectic on its
//! cotangent bundle and keeps the momenta of symmetries that respect the constraints. With
//! two nodes (s = 1, no interior constraint) it is the constrained midpoint rule
//! ([`super::discrete`], which the tests check it against).
//!
//! Between its constraint points the polynomial leaves the manifold, which costs order. On
//! the spherical pendulum (`cargo test --release --test integration constraints -- --nocapture`)
//! the Gauss points give 2, 4, 4, 6, 8, 10 for s = 1 … 6 — 2s − 2 from s = 3 on, two less
//! than the unconstrained SVI's 2s (the multipliers, like the velocities of an index-3
//! system, are a derivative order behind) — and the nodes give 2, 4, 4, 6, 4, 6: hence the
//! default.

use super::{
    ConstrainedIntegrator, ConstrainedPoint, ConstrainedRun, Flow, Projection, at_round_off,
    newton_correction, record,
};
use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::DenseLu;
use crate::model::Lagrangian;
use crate::model::constraint::{
    ConstraintScratch, Constraints, ConstraintsExt, Projected, check_rank,
};
use crate::model::derived::LagrangianExt;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::quadrature::GaussLegendre;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector};

/// Where the constrained Galerkin method imposes g = 0 inside a step of s + 1 nodes: at
/// s − 1 points either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintPoints {
    /// At the s − 1 interior Chebyshev–Gauss–Lobatto nodes.
    Nodes,
    /// At the s − 1 points of the Gauss–Legendre rule of that size.
    Quadrature,
}

/// The constrained SVI: `points` interpolation nodes, `quadrature` Gauss points.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ConstrainedSvi {
    /// Chebyshev–Gauss–Lobatto nodes per step (2 to [`crate::spectral::MAX_POINTS`]).
    pub points: usize,
    /// Gauss–Legendre points per step.
    pub quadrature: usize,
    /// Where g = 0 is imposed inside a step.
    pub at: ConstraintPoints,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl ConstrainedSvi {
    /// `points` nodes and `quadrature` Gauss points, constrained at the Gauss points.
    pub fn new(points: usize, quadrature: usize) -> Self {
        ConstrainedSvi {
            points,
            quadrature,
            at: ConstraintPoints::Quadrature,
            max_iterations: 50,
        }
    }

    /// The same method constrained at `at`.
    pub fn constrained_at(self, at: ConstraintPoints) -> Self {
        ConstrainedSvi { at, ..self }
    }

    /// The order on the constraint manifold, from the measurements of the guide's
    /// constraints chapter, for s = P − 1: at the Gauss points 2s for s ≤ 2 and 2s − 2 above
    /// (two less than the unconstrained SVI's 2s), at most 2Q; at the nodes 2 for the midpoint
    /// rule and at least 4 otherwise (the measured orders go 4, 4, 6, 4, 6 for s = 2 … 6: not
    /// a pattern to build on).
    pub fn order(&self) -> usize {
        let s = self.points.saturating_sub(1);
        match self.at {
            ConstraintPoints::Quadrature if s <= 2 => (2 * s).min(2 * self.quadrature),
            ConstraintPoints::Quadrature => (2 * s - 2).min(2 * self.quadrature),
            ConstraintPoints::Nodes if s <= 1 => 2,
            ConstraintPoints::Nodes => 4,
        }
    }

    /// The name: `svi:P/Q` (constrained at the Gauss points) or `svi:P/Q@nodes`.
    pub fn name(&self) -> String {
        match (self.points, self.quadrature, self.at) {
            (points, quadrature, ConstraintPoints::Quadrature) => {
                format!("svi:{points}/{quadrature}")
            }
            (points, quadrature, ConstraintPoints::Nodes) => {
                format!("svi:{points}/{quadrature}@nodes")
            }
        }
    }

    /// Whether the method's numbers can run: P from 2 to [`crate::spectral::MAX_POINTS`]
    /// nodes, Q from 1 to as many Gauss points (the checks of the run itself, which makes its
    /// tables from them).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `points` or `quadrature`.
    pub fn check(&self) -> Result<(), Error> {
        Tables::new(self).map(|_| ())
    }

    /// The method called `name` (`svi:P/Q`, `svi:P/Q@nodes`); its numbers are checked by
    /// [`ConstrainedSvi::check`] and when it runs.
    pub fn named(name: &str) -> Option<Self> {
        let rest = name.strip_prefix("svi:")?;
        let (rest, at) = match rest.strip_suffix("@nodes") {
            Some(rest) => (rest, ConstraintPoints::Nodes),
            None => (rest, ConstraintPoints::Quadrature),
        };
        let (points, quadrature) = rest.split_once('/')?;
        Some(ConstrainedSvi::new(points.parse().ok()?, quadrature.parse().ok()?).constrained_at(at))
    }
}

/// The tables of one step, computed once: basis values and derivatives at the Gauss points
/// and at the constraint points.
struct Tables {
    /// τⱼ, (h/2)-free weights wⱼ, φᵢ(τⱼ) and φᵢ'(τⱼ) (row j).
    gauss: Vec<f64>,
    weights: Vec<f64>,
    values: DMatrix<f64>,
    derivatives: DMatrix<f64>,
    /// τ_c and ψᵢ(c) = φᵢ(τ_c) (row c).
    constraint_points: Vec<f64>,
    constraint_values: DMatrix<f64>,
    /// The nodes τᵢ.
    nodes: Vec<f64>,
}

impl Tables {
    fn new(method: &ConstrainedSvi) -> Result<Self, Error> {
        let s = method.points.saturating_sub(1);
        let least = 2;
        if method.points < least {
            return Err(Error::invalid(
                "points",
                format!(
                    "{} needs at least {least} nodes (two: the midpoint rule), got {}",
                    method.name(),
                    method.points
                ),
            ));
        }
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(method.points)?;
        let rule = GaussLegendre::new(method.quadrature)?;
        let nodes = basis.nodes().to_vec();
        let constraint_points = match method.at {
            ConstraintPoints::Nodes => nodes[1..nodes.len() - 1].to_vec(),
            ConstraintPoints::Quadrature if s >= 2 => GaussLegendre::new(s - 1)?.nodes().to_vec(),
            ConstraintPoints::Quadrature => Vec::new(),
        };
        Ok(Tables {
            values: basis.value_matrix(rule.nodes()),
            derivatives: basis.derivative_matrix(rule.nodes()),
            constraint_values: basis.value_matrix(&constraint_points),
            gauss: rule.nodes().to_vec(),
            weights: rule.weights().to_vec(),
            constraint_points,
            nodes,
        })
    }
}

/// Buffers of a constrained Galerkin run, sized once.
struct Workspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    scratch: ConstraintScratch<N>,
    /// The nodes Q_0 … Q_s.
    nodes: Vec<OVector<f64, N>>,
    /// The unknowns (Q_1 … Q_s, Λ, λ_0), the residual and the Newton matrix.
    unknowns: DVector<f64>,
    residual: DVector<f64>,
    newton: DenseLu,
    /// G and g at the current constraint point, G(q_k), the Hessian of Λᵀg.
    jacobian: DMatrix<f64>,
    start_jacobian: DMatrix<f64>,
    values: DVector<f64>,
    hessian: DMatrix<f64>,
    /// The multipliers of one constraint point, and the projection's buffers.
    lambda: DVector<f64>,
    projection: Projection<N>,
    /// A point on the curve, its velocity, and p̃.
    q: OVector<f64, N>,
    v: OVector<f64, N>,
    momentum: OVector<f64, N>,
}

/// The run of [`ConstrainedIntegrator::run`] with a constrained Galerkin method.
#[allow(clippy::too_many_arguments)]
pub(super) fn run<N: Dimension, L: Lagrangian<N>, C: Constraints<N>, R: Flow>(
    integrator: &ConstrainedIntegrator<L, C>,
    method: &ConstrainedSvi,
    t0: f64,
    h: f64,
    steps: usize,
    initial: Projected<N>,
    mut observe: impl FnMut(&ConstrainedPoint<N>) -> R,
) -> Result<ConstrainedRun<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let tables = Tables::new(method)?;
    let (model, constraints) = (&integrator.model, &integrator.constraints);
    let m = constraints.count();
    let s = method.points - 1;
    let zero = initial.q.map(|_| 0.0);
    let n = zero.len();
    let size = s * n + (tables.constraint_points.len() + 1) * m;
    let mut w = Workspace {
        scratch: ConstraintScratch::new(&initial.q, m),
        nodes: vec![zero.clone(); s + 1],
        unknowns: DVector::zeros(size),
        residual: DVector::zeros(size),
        newton: DenseLu::new(size),
        jacobian: DMatrix::zeros(m, n),
        start_jacobian: DMatrix::zeros(m, n),
        values: DVector::zeros(m),
        hessian: DMatrix::zeros(n, n),
        lambda: DVector::zeros(m),
        projection: Projection::new(&zero, m),
        q: zero.clone(),
        v: zero.clone(),
        momentum: zero,
    };
    let (mut point, mut run) = ConstrainedRun::start(t0, initial, m);
    constraints.jacobian_into(&point.q, &mut w.scratch, &mut w.start_jacobian);
    check_rank(constraints, &w.start_jacobian)?;
    run.stopped = observe(&point).stops();
    let stepper = Stepper {
        model,
        constraints,
        method,
        tables: &tables,
        dimension: std::marker::PhantomData,
    };
    let (mut g, mut rate) = (DVector::zeros(m), DVector::zeros(m));
    let mut velocity = model.velocity(t0, &point.q, &point.p, &point.q.map(|_| 0.0))?;
    for k in 0..steps {
        if run.stopped {
            break;
        }
        let t = t0 + k as f64 * h;
        run.iterations += stepper.step(&mut w, t, h, k, &mut point, &mut velocity)?;
        point.t = t0 + (k + 1) as f64 * h;
        record(
            &mut run,
            constraints,
            &point,
            &w.start_jacobian,
            &velocity,
            (&mut g, &mut rate),
        );
        run.stopped = observe(&point).stops();
    }
    // Second derivatives at every Gauss point per Newton iteration, first derivatives for p̃.
    run.evaluations = (run.iterations + run.steps) * method.quadrature;
    run.factorizations = run.iterations + w.projection.factorizations;
    run.last = point;
    Ok(run)
}

/// What one step reads.
struct Stepper<'a, L, C, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: &'a L,
    constraints: &'a C,
    method: &'a ConstrainedSvi,
    tables: &'a Tables,
    dimension: std::marker::PhantomData<N>,
}

impl<L: Lagrangian<N>, C: Constraints<N>, N: Dimension> Stepper<'_, L, C, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// One step from `point` (with its velocity `velocity`) in place; the Newton iterations.
    /// On return `w.start_jacobian` is G(q_{k+1}).
    fn step(
        &self,
        w: &mut Workspace<N>,
        t: f64,
        h: f64,
        step: usize,
        point: &mut ConstrainedPoint<N>,
        velocity: &mut OVector<f64, N>,
    ) -> Result<usize, Error> {
        let tables = self.tables;
        let n = point.q.len();
        let s = tables.nodes.len() - 1;
        let m = self.constraints.count();
        let r = tables.constraint_points.len();
        // Starting values: the nodes along the tangent q_k + (t − t_k) q̇_k, the multipliers
        // of the last step.
        w.nodes[0].copy_from(&point.q);
        for i in 1..=s {
            let offset = 0.5 * h * (tables.nodes[i] + 1.0);
            for a in 0..n {
                w.unknowns[(i - 1) * n + a] = point.q[a] + offset * velocity[a];
            }
        }
        let scale = point.q.amax().max(1.0);
        let (mut iterations, mut before) = (0, f64::INFINITY);
        loop {
            self.assemble(w, t, h, &point.p)?;
            newton_correction(&mut w.newton, &mut w.residual, (step, t, iterations))?;
            w.unknowns += &w.residual;
            iterations += 1;
            let moved = w.residual.rows(0, s * n).amax();
            if at_round_off(moved, before, scale) {
                break;
            }
            if iterations == self.method.max_iterations {
                return Err(Error::NonConvergence {
                    step,
                    t,
                    iterations,
                    residual: moved,
                });
            }
            before = moved;
        }
        // p̃_{k+1} = ∂A/∂Q_s at the converged nodes, then the projection onto the cotangent
        // space at q_{k+1}.
        self.unpack_nodes(w);
        self.end_momentum(w, t, h);
        let end = t + h;
        point.q.copy_from(&w.nodes[s]);
        point
            .multipliers
            .copy_from(&w.unknowns.rows(s * n + r * m, m));
        self.constraints
            .jacobian_into(&point.q, &mut w.scratch, &mut w.start_jacobian);
        *velocity = w.projection.project(
            self.model,
            end,
            &point.q,
            &w.start_jacobian,
            &mut w.momentum,
            velocity,
            (step, self.method.max_iterations),
        )?;
        point.p.copy_from(&w.momentum);
        Ok(iterations)
    }

    /// Q_1 … Q_s from the unknowns into `w.nodes`.
    fn unpack_nodes(&self, w: &mut Workspace<N>) {
        let n = w.q.len();
        for i in 1..w.nodes.len() {
            for a in 0..n {
                w.nodes[i][a] = w.unknowns[(i - 1) * n + a];
            }
        }
    }

    /// The residual and the Newton matrix of the step's equations at the current unknowns.
    fn assemble(
        &self,
        w: &mut Workspace<N>,
        t: f64,
        h: f64,
        start_momentum: &OVector<f64, N>,
    ) -> Result<(), Error> {
        let tables = self.tables;
        let n = w.q.len();
        let s = tables.nodes.len() - 1;
        let m = self.constraints.count();
        let r = tables.constraint_points.len();
        self.unpack_nodes(w);
        w.residual.fill(0.0);
        let matrix = w.newton.matrix_mut();
        matrix.fill(0.0);
        // The action: rows 0 … s − 1 (the equations of Q_0 … Q_{s−1}), columns Q_1 … Q_s.
        for (j, (&tau, &weight)) in tables.gauss.iter().zip(&tables.weights).enumerate() {
            let half = 0.5 * h * weight;
            curve_point(&w.nodes, tables.values.row(j), &mut w.q);
            curve_point(&w.nodes, tables.derivatives.row(j), &mut w.v);
            w.v *= 2.0 / h;
            let d = self
                .model
                .second_derivatives(t + 0.5 * h * (tau + 1.0), &w.q, &w.v);
            for i in 0..s {
                let (phi, dphi) = (tables.values[(j, i)], tables.derivatives[(j, i)] * 2.0 / h);
                for a in 0..n {
                    w.residual[i * n + a] += half * (phi * d.q[a] + dphi * d.v[a]);
                }
                for l in 1..=s {
                    let (psi, dpsi) = (tables.values[(j, l)], tables.derivatives[(j, l)] * 2.0 / h);
                    let (row, col) = (i * n, (l - 1) * n);
                    for a in 0..n {
                        for b in 0..n {
                            matrix[(row + a, col + b)] += half
                                * (phi * psi * d.qq[(a, b)]
                                    + phi * dpsi * d.qv[(a, b)]
                                    + dphi * psi * d.qv[(b, a)]
                                    + dphi * dpsi * d.vv[(a, b)]);
                        }
                    }
                }
            }
        }
        for a in 0..n {
            w.residual[a] += start_momentum[a];
        }
        // The interior constraints: −Σ_c ψᵢ(c) G(q_c)ᵀΛ_c in the rows of Q_i, g(q_c) = 0.
        let multipliers = s * n;
        for c in 0..r {
            let psi = tables.constraint_values.row(c);
            curve_point(&w.nodes, psi, &mut w.q);
            self.constraints.values_into(&w.q, &mut w.values);
            self.constraints
                .jacobian_into(&w.q, &mut w.scratch, &mut w.jacobian);
            w.lambda.copy_from(&w.unknowns.rows(multipliers + c * m, m));
            let lambda = &w.lambda;
            self.constraints.weighted_hessian_into(
                &w.q,
                lambda.as_slice(),
                &mut w.scratch,
                &mut w.hessian,
            );
            let equation = multipliers + c * m;
            for i in 0..s {
                for a in 0..n {
                    let force: f64 = (0..m).map(|e| w.jacobian[(e, a)] * lambda[e]).sum();
                    w.residual[i * n + a] -= psi[i] * force;
                    for e in 0..m {
                        matrix[(i * n + a, equation + e)] = -psi[i] * w.jacobian[(e, a)];
                    }
                    for l in 1..=s {
                        for b in 0..n {
                            matrix[(i * n + a, (l - 1) * n + b)] -=
                                psi[i] * psi[l] * w.hessian[(a, b)];
                        }
                    }
                }
            }
            for e in 0..m {
                w.residual[equation + e] = w.values[e];
                for l in 1..=s {
                    for b in 0..n {
                        matrix[(equation + e, (l - 1) * n + b)] = psi[l] * w.jacobian[(e, b)];
                    }
                }
            }
        }
        // The ends: −G(q_k)ᵀλ_0 in the row of Q_0, g(Q_s) = 0.
        let start = multipliers + r * m;
        for a in 0..n {
            for e in 0..m {
                w.residual[a] -= w.start_jacobian[(e, a)] * w.unknowns[start + e];
                matrix[(a, start + e)] = -w.start_jacobian[(e, a)];
            }
        }
        self.constraints.values_into(&w.nodes[s], &mut w.values);
        self.constraints
            .jacobian_into(&w.nodes[s], &mut w.scratch, &mut w.jacobian);
        for e in 0..m {
            w.residual[start + e] = w.values[e];
            for b in 0..n {
                matrix[(start + e, (s - 1) * n + b)] = w.jacobian[(e, b)];
            }
        }
        Ok(())
    }

    /// p̃_{k+1} = ∂A/∂Q_s into `w.momentum` (minus the interior constraint forces on Q_s).
    fn end_momentum(&self, w: &mut Workspace<N>, t: f64, h: f64) {
        let tables = self.tables;
        let s = tables.nodes.len() - 1;
        let m = self.constraints.count();
        w.momentum.fill(0.0);
        for (j, (&tau, &weight)) in tables.gauss.iter().zip(&tables.weights).enumerate() {
            let half = 0.5 * h * weight;
            curve_point(&w.nodes, tables.values.row(j), &mut w.q);
            curve_point(&w.nodes, tables.derivatives.row(j), &mut w.v);
            w.v *= 2.0 / h;
            let d = self
                .model
                .first_derivatives(t + 0.5 * h * (tau + 1.0), &w.q, &w.v);
            let (phi, dphi) = (tables.values[(j, s)], tables.derivatives[(j, s)] * 2.0 / h);
            w.momentum.axpy(half * phi, &d.q, 1.0);
            w.momentum.axpy(half * dphi, &d.v, 1.0);
        }
        let multipliers = s * w.q.len();
        for c in 0..tables.constraint_points.len() {
            let psi = tables.constraint_values[(c, s)];
            if psi == 0.0 {
                continue;
            }
            curve_point(&w.nodes, tables.constraint_values.row(c), &mut w.q);
            self.constraints
                .jacobian_into(&w.q, &mut w.scratch, &mut w.jacobian);
            for a in 0..w.q.len() {
                let force: f64 = (0..m)
                    .map(|e| w.jacobian[(e, a)] * w.unknowns[multipliers + c * m + e])
                    .sum();
                w.momentum[a] -= psi * force;
            }
        }
    }
}

/// Σᵢ cᵢ Qᵢ into `out` (a point or, with derivative coefficients, a velocity of the curve).
fn curve_point<N: Dimension, S: nalgebra::Storage<f64, nalgebra::U1, nalgebra::Dyn>>(
    nodes: &[OVector<f64, N>],
    coefficients: nalgebra::Matrix<f64, nalgebra::U1, nalgebra::Dyn, S>,
    out: &mut OVector<f64, N>,
) where
    DefaultAllocator: Allocator<N>,
{
    out.fill(0.0);
    for (node, &c) in nodes.iter().zip(coefficients.iter()) {
        out.axpy(c, node, 1.0);
    }
}
