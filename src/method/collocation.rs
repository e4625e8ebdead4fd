//! Spectral collocation (SC) of the Euler–Lagrange equations.
//!
//! # Discrete equations
//! The Euler–Lagrange equations are solved for the acceleration, q̈ = f(t, q, q̇) with
//! f = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L) (derived from L by automatic differentiation,
//! [`crate::LagrangianExt::acceleration`]; the external force f_L of the Lagrange–d'Alembert
//! principle only for [`crate::Lagrangian::FORCED`] models, and its Jacobian comes with the
//! acceleration's), and written as the first-order system
//! q̇ = y, ẏ = f(t, q, y) (Li, Wu, Leok 2018, eqs. 12, 19). On each step both q and y are
//! polynomials of degree s through the s + 1 CGL nodes c_0, …, c_s of [t, t + h], with
//! q(c_0) = q_k, y(c_0) = q̇_k, and the equations are collocated at c_1, …, c_s
//! (eqs. 20–23): with Λ = (2/h) D̃⁽¹⁾(1:s, 0:s) = [λ_0, Λ*] (eq. 21),
//!
//! Λ*Q* + λ_0 q_k = Y*,   Λ*Y* + λ_0 q̇_k = F(t, Q*, Y*).
//!
//! Eliminating Y* gives eq. (24)–(25) for the s·N unknowns Q*, solved by Newton's method with
//! the exact Jacobian (Λ*)² ⊗ I − diag(∂f/∂q) − diag(∂f/∂q̇)(Λ* ⊗ I), where ∂f/∂q and ∂f/∂q̇
//! come from nested dual numbers. Then q_{k+1} = qˢ and q̇_{k+1} = yˢ.
//! On an unforced sum of local terms of run-time size ([`crate::model::TermSum`]) the same
//! equations are solved in implicit form, multiplied by the mass matrix, by sparse Newton
//! (`sparse_newton`): O(n) per iteration, no n × n matrix.
//! The differentiation matrix D̃⁽¹⁾ is built from barycentric formulas for ascending nodes
//! ([`crate::spectral::basis::LagrangeBasis::differentiation_matrix`]); eq. (17) of the paper is
//! quoted for descending nodes.
//!
//! # Properties
//! - an s-stage collocation method with nodes c_1, …, c_s; its order is the order of the
//!   interpolatory quadrature on those nodes, computed by `info()` from the moment
//!   conditions: s for every s (the CGL nodes without their first point are not symmetric, so
//!   there is no extra order; e.g. s = 2, nodes {1/2, 1}: order 2; the unit tests observe it);
//! - symmetric: no; symplectic: no (energy and momenta drift, Figs. 14–15 of the paper).
//!
//! # References
//! Li, Wu, Leok (2018), §3, eqs. (12)–(25).

pub(crate) mod sparse_newton;

use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::error::StepFailure;
use crate::linalg::invert;
use crate::method::Method;
use crate::method::{Coordinates, Equations, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::Structure;
use crate::model::derived::sparse_terms;
use crate::model::derived::{AccelerationJacobian, KeptMass, LagrangianExt};
use crate::nonlinear::{FixedPoint, Newton, Solved, after_fixed_point};
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::quadrature::GaussLegendre;
use crate::spectral::starting_values::StartingValues;
use crate::spectral::{MAX_POINTS, Scratch, check_options};
use nalgebra::allocator::Allocator;
use nalgebra::{
    DMatrix, DVector, DefaultAllocator, Dim, MatrixView, MatrixViewMut, OMatrix, OVector, U1,
};
use sparse_newton::LazySparseCollocation;
use std::ops::ControlFlow;
use std::sync::OnceLock;

/// Options of the spectral collocation method.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SpectralCollocation {
    /// Number of Chebyshev–Gauss–Lobatto points s + 1 (polynomial degree s), at least 2.
    pub points: usize,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for SpectralCollocation {
    fn default() -> Self {
        SpectralCollocation {
            points: 6,
            max_iterations: 50,
        }
    }
}

impl SpectralCollocation {
    /// SC with `points` CGL points.
    pub fn new(points: usize) -> Self {
        SpectralCollocation {
            points,
            ..SpectralCollocation::default()
        }
    }

    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }

    fn validate(&self) -> Result<(), Error> {
        check_options(self.points, None, self.max_iterations)
    }

    /// Order of the collocation method: the order of the interpolatory quadrature on the
    /// collocation nodes c_1, …, c_s (Hairer, Nørsett, Wanner I, Thm. II.7.9), computed once
    /// per number of points ([`Method::info`] is asked at every observed step).
    fn order(&self) -> usize {
        static ORDERS: [OnceLock<usize>; MAX_POINTS + 1] =
            [const { OnceLock::new() }; MAX_POINTS + 1];
        match ORDERS.get(self.points) {
            Some(order) => *order.get_or_init(|| collocation_order(self.points)),
            None => collocation_order(self.points),
        }
    }
}

/// The order of the interpolatory quadrature on the collocation nodes of `points` CGL points
/// (0 for an invalid number of points).
fn collocation_order(points: usize) -> usize {
    let Some((nodes, weights)) = collocation_quadrature(points) else {
        return 0;
    };
    let limit = points.saturating_mul(2);
    (0..limit)
        .find(|&k| {
            let sum: f64 = weights
                .iter()
                .zip(&nodes)
                .map(|(b, c)| b * c.powi(k as i32))
                .sum();
            (sum - 1.0 / (k as f64 + 1.0)).abs() > 1e-10
        })
        .unwrap_or(limit)
}

/// The collocation nodes c_1, …, c_s on [0, 1] and the weights b_i = ∫₀¹ ℓ_i of the
/// interpolatory quadrature on them; `None` for an invalid number of points.
fn collocation_quadrature(points: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let nodes = crate::spectral::basis::chebyshev_gauss_lobatto(points).ok()?;
    let collocation: Vec<f64> = nodes[1..].iter().map(|x| 0.5 * (x + 1.0)).collect();
    let basis = LagrangeBasis::new(collocation.clone()).ok()?;
    let gauss = GaussLegendre::new(points + 1).ok()?;
    let mut values = vec![0.0; basis.len()];
    let mut weights = vec![0.0; basis.len()];
    for (x, w) in gauss.nodes().iter().zip(gauss.weights()) {
        basis.values_into(0.5 * (x + 1.0), &mut values);
        for (b, l) in weights.iter_mut().zip(&values) {
            *b += 0.5 * w * l;
        }
    }
    Some((collocation, weights))
}

/// Tables and buffers of the fixed-point iteration for [`Structure::ConstantMass`]
/// Lagrangians, where f(t, q, q̇) = M⁻¹ (∂L/∂q(t, q) + f_L(t, q, q̇)) depends on q̇ only
/// through the external force f_L of a forced model.
///
/// With Λ* = (2/h) D* and λ_0 = (2/h) d_0, eq. (24) becomes the fixed point
///
/// Z_i = h e_i q̇_k + (h²/4) Σ_j E_ij M⁻¹ ∂L/∂q(t_j, q_k + Z_j),  E = (D*)⁻², e = −½ E d_0,
///
/// for the offsets Z_i = qⁱ − q_k (with an external force, f_L is evaluated at the node
/// velocities Y_i = Σ_j Λ*_ij Z_j of the current iterate; a velocity-dependent force makes
/// the iteration contract only by a factor O(h ‖M⁻¹ ∂f_L/∂q̇‖), so a forced model that does
/// not converge falls back to Newton's method for the rest of the run), and the velocity
/// update is the collocation quadrature
/// q̇_{k+1} − q̇_k = ∫ y′ = h Σ_i b_i f_i (y′ interpolates f at c_1..c_s), which, unlike
/// yˢ − q̇_k, has no cancellation.
#[derive(Debug, Clone)]
struct ConstantMass<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// E = (D*)⁻², row-major s × s.
    inverse: Vec<f64>,
    /// e_i.
    velocity_coefficients: Vec<f64>,
    /// Quadrature weights b_i on the collocation nodes.
    weights: Vec<f64>,
    /// M⁻¹ and M, from the first step.
    mass: KeptMass<N>,
    /// f at the collocation nodes.
    accelerations: Vec<OVector<f64, N>>,
    /// Offsets Z_i during the iteration.
    stages: Vec<OVector<f64, N>>,
}

impl<N: Dimension> ConstantMass<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn new(tables: &Tables, points: usize, n: N) -> Option<Self> {
        let s = tables.degree;
        let d = &tables.differentiation;
        let star = d.view((1, 1), (s, s)).into_owned();
        let inverse = invert(&(&star * &star)).ok()?;
        let (_, weights) = collocation_quadrature(points)?;
        let velocity_coefficients =
            (0..s).map(|i| -0.5 * (0..s).map(|j| inverse[(i, j)] * d[(j + 1, 0)]).sum::<f64>());
        Some(ConstantMass {
            inverse: (0..s * s).map(|k| inverse[(k / s, k % s)]).collect(),
            velocity_coefficients: velocity_coefficients.collect(),
            weights,
            mass: KeptMass::default(),
            accelerations: vec![OVector::zeros_generic(n, U1); s],
            stages: vec![OVector::zeros_generic(n, U1); s],
        })
    }
}

/// Tables of one SC configuration, scaled for the current step size.
#[derive(Debug, Clone)]
struct Tables {
    degree: usize,
    h: f64,
    /// CGL nodes on [−1, 1].
    nodes: Vec<f64>,
    /// D̃⁽¹⁾ at the nodes (unscaled).
    differentiation: DMatrix<f64>,
    /// Λ* = (2/h) D̃(1:s, 1:s).
    lambda: DMatrix<f64>,
    /// (Λ*)².
    lambda_squared: DMatrix<f64>,
    /// λ_0 = (2/h) D̃(1:s, 0).
    lambda0: DVector<f64>,
    /// Λ* λ_0.
    lambda_lambda0: DVector<f64>,
}

impl Tables {
    fn new(basis: &LagrangeBasis, h: f64) -> Self {
        let s = basis.len() - 1;
        let mut tables = Tables {
            degree: s,
            h: f64::NAN,
            nodes: basis.nodes().to_vec(),
            differentiation: basis.differentiation_matrix(),
            lambda: DMatrix::zeros(s, s),
            lambda_squared: DMatrix::zeros(s, s),
            lambda0: DVector::zeros(s),
            lambda_lambda0: DVector::zeros(s),
        };
        tables.rescale(h);
        tables
    }

    fn rescale(&mut self, h: f64) {
        let s = self.degree;
        self.h = h;
        self.lambda = self.differentiation.view((1, 1), (s, s)) * (2.0 / h);
        self.lambda0 = self.differentiation.view((1, 0), (s, 1)).column(0) * (2.0 / h);
        self.lambda_squared = &self.lambda * &self.lambda;
        self.lambda_lambda0 = &self.lambda * &self.lambda0;
    }

    fn time(&self, t: f64, i: usize) -> f64 {
        t + 0.5 * self.h * (self.nodes[i] + 1.0)
    }

    /// y at collocation node i (1-based) from node offsets z: Σ_j Λ*_ij z_j.
    fn velocity<N: Dimension>(&self, n: N, i: usize, z: &DVector<f64>) -> OVector<f64, N>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let mut y = OVector::zeros_generic(n, U1);
        for j in 1..=self.degree {
            y.axpy(self.lambda[(i - 1, j - 1)], &node(z, n, j - 1), 1.0);
        }
        y
    }
}

/// Node `index` (0-based: the offset of CGL node index + 1) of stacked node vectors `z`, N
/// numbers each.
fn node<N: Dim>(
    z: &DVector<f64>,
    n: N,
    index: usize,
) -> MatrixView<'_, f64, N, U1, U1, nalgebra::Dyn> {
    z.generic_view((index * n.value(), 0), (n, U1))
}

/// Node `index` of stacked node vectors `z`, to be written.
fn node_mut<N: Dim>(
    z: &mut DVector<f64>,
    n: N,
    index: usize,
) -> MatrixViewMut<'_, f64, N, U1, U1, nalgebra::Dyn> {
    z.generic_view_mut((index * n.value(), 0), (n, U1))
}

/// Placeholder node data before the first evaluation, of dimension `n`.
fn zero_node<N: Dimension>(n: N) -> AccelerationJacobian<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    AccelerationJacobian {
        value: OVector::zeros_generic(n, U1),
        q: OMatrix::zeros_generic(n, n),
        v: OMatrix::zeros_generic(n, n),
    }
}

/// Buffers of an SC run.
#[derive(Debug, Clone)]
pub struct CollocationWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    tables: Tables,
    /// Node offsets qⁱ − q_k, i = 1..s, stacked.
    offsets: DVector<f64>,
    start: StartingValues,
    /// Acceleration and its Jacobian at the collocation nodes.
    nodes: Vec<AccelerationJacobian<N>>,
    newton: Newton,
    /// Fixed-point data, for constant-mass Lagrangians.
    constant_mass: Option<ConstantMass<N>>,
    /// Set once the fixed-point iteration of a forced model failed to converge: the rest of
    /// the run takes Newton's method.
    newton_only: bool,
    /// Sparse Newton, for an unforced sum of terms of run-time size (made at its first use).
    sparse: LazySparseCollocation,
}

/// Acceleration data at every collocation node; `false` if the mass matrix is singular
/// somewhere.
fn evaluate_nodes<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    tables: &Tables,
    nodes: &mut [AccelerationJacobian<N>],
    t: f64,
    state: &State<N>,
    z: &DVector<f64>,
) -> bool
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = state.dimension();
    for (index, data) in nodes.iter_mut().enumerate() {
        let i = index + 1;
        let q = &state.q + node(z, n, index);
        let y = tables.velocity(n, i, z);
        match model.acceleration_jacobian(tables.time(t, i), &q, &y) {
            Some(value) => *data = value,
            None => return false,
        }
    }
    true
}

/// Assemble the residual of eq. (25) in offsets and its Jacobian.
fn assemble<N: Dimension>(
    tables: &Tables,
    nodes: &[AccelerationJacobian<N>],
    state: &State<N>,
    z: &DVector<f64>,
    jacobian: &mut DMatrix<f64>,
    residual: &mut DVector<f64>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = state.dimension();
    let size = n.value();
    let s = tables.degree;
    for (i, data) in nodes.iter().enumerate().take(s) {
        let mut r = &state.y * tables.lambda0[i] - &data.value;
        for j in 0..s {
            r.axpy(tables.lambda_squared[(i, j)], &node(z, n, j), 1.0);
            // −λ*_ij ∂f/∂q̇ − δ_ij ∂f/∂q + (Λ*²)_ij I, written in place.
            let mut block = jacobian.generic_view_mut((i * size, j * size), (n, n));
            for column in 0..size {
                for row in 0..size {
                    let mut entry = -data.v[(row, column)] * tables.lambda[(i, j)];
                    if i == j {
                        entry -= data.q[(row, column)];
                    }
                    if row == column {
                        entry += tables.lambda_squared[(i, j)];
                    }
                    block[(row, column)] = entry;
                }
            }
        }
        node_mut(residual, n, i).copy_from(&r);
    }
}

/// One step of a constant-mass Lagrangian by fixed-point iteration (no Jacobian).
fn fixed_point_step<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    max_iterations: usize,
    workspace: &mut CollocationWorkspace<N>,
    t: f64,
    h: f64,
    state: &State<N>,
    increment: &mut State<N>,
) -> Result<StepReport, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let CollocationWorkspace {
        tables,
        offsets,
        start,
        constant_mass,
        ..
    } = workspace;
    let Some(data) = constant_mass.as_mut() else {
        return Err(StepFailure::SingularMatrix);
    };
    let mass_inverse = data.mass.inverse(model, t, &state.q, &state.y)?;
    let n = state.dimension();
    let s = tables.degree;
    let quarter = 0.25 * h * h;
    for (i, stage) in data.stages.iter_mut().enumerate() {
        stage.copy_from(&node(offsets, n, i));
    }
    let position_scale = state.q.amax();
    let mut control = FixedPoint::new(max_iterations);
    loop {
        for (i, (acceleration, stage)) in
            data.accelerations.iter_mut().zip(&data.stages).enumerate()
        {
            let time = tables.time(t, i + 1);
            let position = &state.q + stage;
            let mut force = model.force(time, &position, &state.y);
            if L::FORCED {
                let mut velocity = OVector::zeros_generic(n, U1);
                for (j, other) in data.stages.iter().enumerate() {
                    velocity.axpy(tables.lambda[(i, j)], other, 1.0);
                }
                force += model.external_force(time, &position, &velocity);
            }
            mass_inverse.apply_into(&force, acceleration);
        }
        let mut change: f64 = 0.0;
        let mut size: f64 = 0.0;
        for (i, stage) in data.stages.iter_mut().enumerate() {
            let row = &data.inverse[i * s..(i + 1) * s];
            let mut sum = OVector::zeros_generic(n, U1);
            for (e, acceleration) in row.iter().zip(&data.accelerations) {
                sum.axpy(*e, acceleration, 1.0);
            }
            let next = &state.y * (h * data.velocity_coefficients[i]) + sum * quarter;
            change = change.max((&next - &*stage).amax());
            size = size.max(next.amax());
            *stage = next;
        }
        match control.converged(change, size + position_scale) {
            Ok(true) => break,
            Ok(false) => {}
            Err(failure) => {
                // Newton takes over from the last iterate (see `after_fixed_point`).
                for (i, stage) in data.stages.iter().enumerate() {
                    node_mut(offsets, n, i).copy_from(stage);
                }
                return Err(failure);
            }
        }
    }
    let mut dv = OVector::zeros_generic(n, U1);
    for (b, acceleration) in data.weights.iter().zip(&data.accelerations) {
        dv.axpy(h * b, acceleration, 1.0);
    }
    for (i, stage) in data.stages.iter().enumerate() {
        node_mut(offsets, n, i).copy_from(stage);
    }
    increment.q.copy_from(&data.stages[s - 1]);
    increment.y = dv;
    start.remember(offsets, h);
    let iterations = control.iterations();
    Ok(StepReport {
        iterations,
        evaluations: s * iterations,
        factorizations: 0,
        analyses: 0,
    })
}

impl<N: Dimension> Method<N> for SpectralCollocation
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = CollocationWorkspace<N>;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "sc",
            order: self.order(),
            symmetric: false,
            symplectic: false,
            coordinates: Coordinates::Velocity,
            equations: Equations::Lagrange,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<CollocationWorkspace<N>, Error> {
        self.validate()?;
        crate::error::require_positive("h", h)?;
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        let size = n.value();
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let s = self.points - 1;
        let tables = Tables::new(&basis, h);
        let constant_mass = match L::STRUCTURE {
            Structure::ConstantMass => ConstantMass::new(&tables, self.points, n),
            Structure::General => None,
        };
        // Newton's buffers exist for every model (a constant-mass model falls back to Newton
        // where the fixed point fails): dense, or for a sum of terms sparse and made at the
        // first use.
        let dense = if sparse_terms(model).is_some() { 0 } else { s };
        Ok(CollocationWorkspace {
            tables,
            offsets: DVector::zeros(s * size),
            start: StartingValues::new(&basis, size),
            nodes: vec![zero_node(n); dense],
            newton: Newton::new(dense * size, self.max_iterations),
            constant_mass,
            newton_only: false,
            sparse: LazySparseCollocation::default(),
        })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut CollocationWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        if workspace.tables.h != h {
            workspace.tables.rescale(h);
            workspace.sparse.invalidate();
        }
        let terms = sparse_terms(model);
        if workspace.start.prepare(h) {
            workspace.start.extrapolate::<N>(&mut workspace.offsets);
        } else {
            // A sum of terms starts from uniform motion: its acceleration is a dense solve.
            let a = match terms {
                Some(_) => OVector::zeros_generic(state.dimension(), U1),
                None => model
                    .acceleration(t, &state.q, &state.y)
                    .ok_or(StepFailure::SingularMatrix)?,
            };
            workspace
                .start
                .taylor(h, &state.y, &a, &mut workspace.offsets);
        }
        let mut spent = 0;
        if workspace.constant_mass.is_some() && !workspace.newton_only {
            let result = fixed_point_step(
                model,
                self.max_iterations,
                workspace,
                t,
                h,
                state,
                increment,
            );
            match after_fixed_point(result, L::FORCED, &mut workspace.newton_only) {
                ControlFlow::Break(result) => return result,
                ControlFlow::Continue(iterations) => spent = iterations,
            }
        }
        let CollocationWorkspace {
            tables,
            offsets,
            nodes,
            newton,
            start,
            sparse,
            ..
        } = workspace;
        let (solved, analyses) = match terms {
            Some(terms) => sparse.solve(
                terms,
                tables,
                t,
                (state.q.as_slice(), state.y.as_slice()),
                offsets,
                self.max_iterations,
            )?,
            None => {
                let mut singular = false;
                let iterations = newton.solve(offsets, |z, jacobian, residual| {
                    if evaluate_nodes(model, tables, nodes, t, state, z) {
                        assemble(tables, nodes, state, z, jacobian, residual);
                    } else {
                        singular = true;
                        residual.fill(f64::NAN);
                    }
                });
                if singular {
                    return Err(StepFailure::SingularMatrix);
                }
                let iterations = iterations?;
                // The dense Newton method factorises at every iteration.
                let solved = Solved {
                    iterations,
                    factorizations: iterations,
                };
                (solved, 0)
            }
        };
        let s = tables.degree;
        let size = state.dimension().value();
        // q_{k+1} − q_k = Z_s, q̇_{k+1} − q̇_k = yˢ − q̇_k (eq. 21), in place.
        increment
            .q
            .copy_from_slice(&offsets.as_slice()[(s - 1) * size..]);
        for (c, dy) in increment.y.iter_mut().enumerate() {
            *dy = (0..s)
                .map(|j| tables.lambda[(s - 1, j)] * offsets[j * size + c])
                .sum::<f64>()
                - state.y[c];
        }
        start.remember(offsets, h);
        let iterations = solved.iterations + spent;
        Ok(StepReport {
            iterations,
            evaluations: s * iterations,
            factorizations: solved.factorizations,
            analyses,
        })
    }

    fn restart(&self, workspace: &mut CollocationWorkspace<N>) {
        workspace.start.invalidate();
    }

    /// q(τ) = q_k + Σ_j l_j(τ) Z_j, and q̇(τ) from the velocity polynomial
    /// y(τ) = q̇_k l_0(τ) + Σ_j l_j(τ) yʲ with yʲ = (Λ*Z)_j (eq. 21), τ = 2θ − 1.
    fn dense_output(
        &self,
        workspace: &CollocationWorkspace<N>,
        state: &State<N>,
        _h: f64,
        theta: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        let mut values = Scratch::zeros(workspace.start.points());
        let n = state.dimension();
        let (offset, _) = workspace
            .start
            .last_step::<N>(2.0 * theta - 1.0, &mut values)?;
        let offsets = workspace.start.last_offsets()?;
        let lambda = &workspace.tables.lambda;
        let mut v = &state.y * values[0];
        for (j, node) in offsets.chunks_exact(n.value()).enumerate() {
            // Σ_i l_i(τ) Λ*_ij, i = 1..s: the weight of Z_j in y(τ).
            let weight: f64 = (0..lambda.nrows())
                .map(|i| values[i + 1] * lambda[(i, j)])
                .sum();
            for (x, z) in v.iter_mut().zip(node) {
                *x += z * weight;
            }
        }
        Some((&state.q + offset, v))
    }

    fn points(&self) -> Option<usize> {
        Some(self.points)
    }

    /// An unforced sum of terms: the fixed point (M⁻¹ from the terms' blocks) for a constant
    /// mass, and sparse Newton (`sparse_newton`) for every other one and wherever the fixed
    /// point fails.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        model.terms().is_some() && !L::FORCED
    }

    /// p = M q̇ from the fixed point's constant mass matrix.
    fn momentum_into(
        &self,
        workspace: &CollocationWorkspace<N>,
        v: &OVector<f64, N>,
        p: &mut OVector<f64, N>,
    ) -> bool {
        workspace
            .constant_mass
            .as_ref()
            .is_some_and(|data| data.mass.momentum_into(v, p))
    }

    fn with_points(&self, points: usize) -> Option<Self> {
        Some(SpectralCollocation {
            points,
            max_iterations: self.max_iterations,
        })
    }

    fn node_offsets<'a>(&self, workspace: &'a mut CollocationWorkspace<N>) -> Option<&'a [f64]> {
        workspace.start.last_offsets()
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut CollocationWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let n = state.dimension();
        let dimension = n.value();
        let mut increment = State::zeros(n);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let ws = &mut *workspace;
        let s = ws.tables.degree;
        // The fixed-point path keeps no Jacobians: evaluate them at the converged nodes.
        ws.nodes.resize(s, zero_node(n));
        if !evaluate_nodes(model, &ws.tables, &mut ws.nodes, t, state, &ws.offsets) {
            return Err(StepFailure::SingularMatrix);
        }
        let size = s * dimension;
        let mut lu = crate::linalg::DenseLu::new(size);
        let mut residual = DVector::zeros(size);
        assemble(
            &ws.tables,
            &ws.nodes,
            state,
            &ws.offsets,
            lu.matrix_mut(),
            &mut residual,
        );
        lu.factor().map_err(|_| StepFailure::SingularMatrix)?;
        // Columns: −∂R/∂q_k (N), then −∂R/∂q̇_k (N).
        let mut sensitivity = DMatrix::zeros(size, 2 * dimension);
        for i in 0..s {
            let from_q = &ws.nodes[i].v * ws.tables.lambda0[i]
                - OMatrix::<f64, N, N>::identity_generic(n, n) * ws.tables.lambda_lambda0[i];
            sensitivity
                .generic_view_mut((i * dimension, 0), (n, n))
                .copy_from(&from_q);
            for d in 0..dimension {
                sensitivity[(i * dimension + d, dimension + d)] = -ws.tables.lambda0[i];
            }
        }
        lu.solve_columns_in_place(&mut sensitivity);
        let last = sensitivity.view(((s - 1) * dimension, 0), (dimension, 2 * dimension));
        let mut velocity = DMatrix::zeros(dimension, 2 * dimension);
        for j in 0..s {
            velocity += sensitivity.view((j * dimension, 0), (dimension, 2 * dimension))
                * ws.tables.lambda[(s - 1, j)];
        }
        for d in 0..dimension {
            velocity[(d, d)] += ws.tables.lambda0[s - 1];
        }
        let tangent = TangentMap {
            qq: last.generic_view((0, 0), (n, n)).into_owned(),
            qy: last.generic_view((0, dimension), (n, n)).into_owned(),
            yq: velocity.generic_view((0, 0), (n, n)).into_owned(),
            yy: velocity.generic_view((0, dimension), (n, n)).into_owned(),
        };
        Ok((increment, tangent, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::verify::observed_order;
    use crate::spectral::MAX_POINTS;
    use crate::test_models::{
        Damped, HenonHeiles, Oscillator, VariableMass, advance,
        assert_tangent_matches_central_differences, distance, factorial, state,
    };
    use nalgebra::Complex;

    /// The stability function of the collocation method on the nodes c₁, …, c_s of [0, 1]
    /// (Nørsett; Hairer, Wanner II, Thm. IV.3.10):
    /// R(z) = Σⱼ M^{(s−j)}(1) zʲ / Σⱼ M^{(s−j)}(0) zʲ with M(x) = Π (x − cᵢ) / s!.
    fn collocation_stability(nodes: &[f64], z: Complex<f64>) -> Complex<f64> {
        let s = nodes.len();
        // Coefficients of M, ascending powers.
        let mut m = vec![1.0 / factorial(s)];
        for &c in nodes {
            let mut next = vec![0.0; m.len() + 1];
            for (k, a) in m.iter().enumerate() {
                next[k + 1] += a;
                next[k] -= c * a;
            }
            m = next;
        }
        let derivative = |k: usize, x: f64| -> f64 {
            (k..=s)
                .map(|n| m[n] * factorial(n) / factorial(n - k) * x.powi((n - k) as i32))
                .sum()
        };
        let polynomial = |x: f64| {
            (0..=s)
                .map(|j| z.powu(j as u32) * derivative(s - j, x))
                .sum::<Complex<f64>>()
        };
        polynomial(1.0) / polynomial(0.0)
    }

    /// The collocation nodes of SC with `points` CGL points: cᵢ = (1 − cos(iπ/s))/2,
    /// i = 1, …, s (Li, Wu, Leok 2018, x_ν = −cos(νπ/s) mapped to [0, 1]).
    fn cgl_collocation_nodes(points: usize) -> Vec<f64> {
        let s = points - 1;
        (1..=s)
            .map(|i| 0.5 * (1.0 - (i as f64 * std::f64::consts::PI / s as f64).cos()))
            .collect()
    }

    /// One step of the oscillator from (q0, q̇0): on q̇ = y, ẏ = −q the variable w = q − i y
    /// obeys ẇ = i w, so a collocation step maps w to R(ih) w.
    fn stability_step(points: usize, h: f64, q0: f64, v0: f64) -> (f64, f64) {
        let r = collocation_stability(&cgl_collocation_nodes(points), Complex::new(0.0, h));
        let w = r * Complex::new(q0, -v0);
        (w.re, -w.im)
    }

    fn assert_stability_step<L: Lagrangian<U1>>(model: &L, points: usize) {
        let method = SpectralCollocation::new(points);
        let (q0, v0) = (0.6f64, 0.8);
        // The fixed-point path updates q̇ by the collocation quadrature h Σ bᵢ fᵢ: a few ulps.
        // The Newton path takes q̇_{k+1} = Σⱼ Λ*_sj Zⱼ, the derivative of the node polynomial,
        // which amplifies the round-off of the offsets Zⱼ ≈ h q̇ by ‖Λ*‖ h ~ s²: up to
        // 4.9e-15 (44 ulps) at 7 points.
        let velocity_tolerance = match L::STRUCTURE {
            Structure::ConstantMass => 2e-15,
            Structure::General => 1e-14,
        };
        let mut errors = Vec::new();
        for h in [0.25f64, 0.125] {
            let (after, _) = advance(&method, model, h, 1, state([q0], [v0]));
            let (q, v) = stability_step(points, h, q0, v0);
            assert!(
                (after.q[0] - q).abs() <= 2e-15 && (after.y[0] - v).abs() <= velocity_tolerance,
                "points {points}, h = {h}: step ({}, {}), R(ih) ({q}, {v})",
                after.q[0],
                after.y[0]
            );
            let exact = [q0 * h.cos() + v0 * h.sin(), -q0 * h.sin() + v0 * h.cos()];
            errors.push((after.q[0] - exact[0]).hypot(after.y[0] - exact[1]));
        }
        // A method of order p has local error C h^{p+1}: halving h divides it by 2^{p+1}.
        let order = Method::<U1>::info(&method).order as f64;
        let slope = (errors[0] / errors[1]).log2();
        assert!(
            (slope - (order + 1.0)).abs() < 0.1,
            "points {points}: local error slope {slope:.3}, declared order {order}"
        );
    }

    /// On a constant mass the observers' momentum p = M q̇ comes from the kept M; on a
    /// variable mass the workspace keeps none.
    #[test]
    fn a_constant_mass_gives_the_observers_momentum() {
        let method = SpectralCollocation::new(5);
        let start = state([0.3, -0.2], [0.1, 0.4]);
        let (end, workspace) = advance(&method, &HenonHeiles::<true>, 0.1, 5, start);
        let mut p = end.q;
        assert!(method.momentum_into(&workspace, &end.y, &mut p));
        let exact = HenonHeiles::<true>.momentum(0.0, &end.q, &end.y);
        assert!((p - exact).amax() < 1e-15);
        let (end, workspace) = advance(&method, &VariableMass, 0.1, 5, start);
        assert!(!method.momentum_into(&workspace, &end.y, &mut p));
    }

    #[test]
    fn one_step_of_the_oscillator_is_the_collocation_stability_function() {
        for points in 2..=7 {
            assert_stability_step(&Oscillator::<false>, points);
            assert_stability_step(&Oscillator::<true>, points);
        }
    }

    #[test]
    fn tangent_map_of_the_oscillator_is_the_stability_matrix_and_not_symplectic() {
        // Φ = [[a, b], [−b, a]] with a + ib = R(ih); ΦᵀJΦ = det Φ · J, det Φ = |R(ih)|².
        let h = 0.5;
        for points in [3, 4, 6] {
            let method = SpectralCollocation::new(points);
            let mut workspace = method.workspace(&Oscillator::<false>, h).unwrap();
            let (_, tangent, _) = method
                .tangent_map(
                    &Oscillator::<false>,
                    &mut workspace,
                    0.0,
                    h,
                    &state([0.6], [0.8]),
                )
                .unwrap();
            let r = collocation_stability(&cgl_collocation_nodes(points), Complex::new(0.0, h));
            let expected = nalgebra::SMatrix::<f64, 2, 2>::new(r.re, r.im, -r.im, r.re);
            let difference = (tangent.matrix() - expected).amax();
            // Round-off amplified by ‖Λ*‖ h ~ s², as in the velocity update: 7e-15 at 6 points.
            assert!(difference <= 2e-14, "points {points}: {difference:e}");
            let determinant = r.norm_sqr();
            assert!((tangent.symplecticity_error() - (determinant - 1.0).abs()).abs() <= 1e-14);
            // |R(ih)|² − 1 = O(h^{p+1}): from −4e-3 (3 points) to −1e-7 (6 points).
            assert!((determinant - 1.0).abs() > 1e-8, "points {points}: |R| = 1");
        }
    }

    /// Observed order (least-squares slope) of `method` on the oscillator from (q, q̇) = (0, 1)
    /// over [0, 4], against the exact solution (sin t, cos t).
    fn oscillator_order<L: Lagrangian<U1>>(method: &SpectralCollocation, model: &L) -> f64 {
        let steps = [0.5, 0.25, 0.125, 0.0625];
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| {
                let n = (4.0 / h) as usize;
                let (end, _) = advance(method, model, h, n, state([0.0], [1.0]));
                distance(&end, &state([4f64.sin()], [4f64.cos()]))
            })
            .collect();
        observed_order(&steps, &errors, 1e-12).unwrap()
    }

    #[test]
    fn observed_order_on_the_oscillator_equals_declared_order() {
        for points in 3..=6 {
            let method = SpectralCollocation::new(points);
            let declared = Method::<U1>::info(&method).order as f64;
            for order in [
                oscillator_order(&method, &Oscillator::<false>),
                oscillator_order(&method, &Oscillator::<true>),
            ] {
                assert!(
                    (order - declared).abs() < 0.15,
                    "points {points}: observed {order:.3}, declared {declared}"
                );
            }
        }
    }

    #[test]
    fn fixed_point_and_newton_paths_agree_on_a_constant_mass_problem() {
        let start = state([0.3, -0.2], [0.1, 0.4]);
        for method in [SpectralCollocation::new(4), SpectralCollocation::new(6)] {
            let (fixed, workspace) = advance(&method, &HenonHeiles::<true>, 0.2, 20, start);
            assert!(workspace.constant_mass.is_some());
            let (newton, workspace) = advance(&method, &HenonHeiles::<false>, 0.2, 20, start);
            assert!(workspace.constant_mass.is_none());
            let difference = distance(&fixed, &newton);
            assert!(
                difference <= 1e-13,
                "{method:?}: paths differ by {difference:e}"
            );
        }
    }

    #[test]
    fn a_capped_fixed_point_hands_the_step_to_newton_from_its_last_iterate() {
        // Two fixed-point iterations per step are far from converged (h = 0.2); Newton takes
        // over from the last iterate and reaches the iteration's solution (the Newton path
        // loses up to ~40 ulps of velocity per step, see the test above).
        let start = state([0.3, -0.2], [0.1, 0.4]);
        let method = SpectralCollocation::new(6);
        let (converged, _) = advance(&method, &HenonHeiles::<true>, 0.2, 20, start);
        let capped = method.clone().with_max_iterations(2);
        let (fallback, workspace) = advance(&capped, &HenonHeiles::<true>, 0.2, 20, start);
        assert!(!workspace.newton_only);
        let difference = distance(&converged, &fallback);
        assert!(difference <= 1e-13, "paths differ by {difference:e}");
    }

    #[test]
    fn tangent_map_matches_central_differences_of_the_step_map() {
        let method = SpectralCollocation::new(5);
        let start = state([0.5, -0.3], [0.4, 0.6]);
        assert_tangent_matches_central_differences(&method, &VariableMass, start);
        // The fixed-point path keeps no Jacobians: the tangent map evaluates them itself.
        assert_tangent_matches_central_differences(&method, &HenonHeiles::<true>, start);
        assert_tangent_matches_central_differences(
            &method,
            &Damped::<false> { c: 0.7 },
            state([1.0], [-0.5]),
        );
    }

    #[test]
    fn invalid_options_are_invalid_parameters_named_after_the_option() {
        let cases = [
            (SpectralCollocation::new(1), "points"),
            (SpectralCollocation::new(MAX_POINTS + 1), "points"),
            (
                SpectralCollocation::new(4).with_max_iterations(0),
                "max_iterations",
            ),
        ];
        for (method, expected) in cases {
            match method.workspace(&Oscillator::<false>, 0.1) {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, expected),
                other => panic!("{method:?}: expected InvalidParameter, got {other:?}"),
            }
        }
        assert!(matches!(
            SpectralCollocation::new(4).workspace(&Oscillator::<false>, -0.1),
            Err(Error::InvalidParameter { name, .. }) if name == "h"
        ));
    }
}
