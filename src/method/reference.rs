//! Non-symplectic reference methods on the Euler–Lagrange equations, for the comparisons of
//! Hairer, Lubich & Wanner, *Geometric Numerical Integration*, §I.1–I.2 (Fig. I.2.4: explicit
//! Euler's planets spiral out, symplectic Euler and Störmer–Verlet keep their orbits).
//!
//! Each integrates the first-order system y = (q, q̇), ẏ = F(t, y) = (q̇, f(t, q, q̇)), with the
//! acceleration f = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L) derived from L
//! ([`crate::LagrangianExt::acceleration`]), in the coordinates (q, q̇):
//!
//! | type | step | order |
//! | --- | --- | --- |
//! | [`ExplicitEuler`] | y' = y + h F(t, y) | 1 |
//! | [`ImplicitEuler`] | y' = y + h F(t + h, y') | 1 |
//! | [`RungeKutta4`] | the classical four-stage Runge–Kutta method | 4 |
//!
//! Implicit Euler writes y' = (q + h w, w) and solves w − q̇ − h f(t + h, q + h w, w) = 0 for
//! the new velocity w by Newton's method with the exact Jacobian I − h(h f_q + f_v) (the
//! acceleration Jacobian, [`crate::LagrangianExt::acceleration_jacobian`]). None of the three
//! is symplectic or symmetric; they are here to be compared with the methods that are.
//!
//! For a constant mass matrix ([`crate::Structure::ConstantMass`]) the acceleration is
//! f = M⁻¹(L_q + f_L): one gradient and M⁻¹ kept from the first step, no Hessian.
//! Otherwise, on an unforced sum of local terms of run-time size (a chain) the acceleration
//! is taken term by term, a = −M⁻¹R(0) with the sparse mass matrix, its Jacobian −M⁻¹(J_q, J_y)
//! (`crate::model::euler_lagrange`), and implicit Euler's equation multiplied by h M is solved
//! by sparse Newton (`sparse_newton`): O(n) a step instead of differentiating the whole L
//! (O(n³) for the acceleration, O(n⁴) for its Jacobian).
//!
//! Tangent maps: explicit Euler's is [[I, hI], [h f_q, I + h f_v]]; Runge–Kutta's follows its
//! stages, dkᵢ/dy = J(yᵢ)(I + cᵢ h dkᵢ₋₁/dy) with J = [[0, I], [f_q, f_v]]; implicit Euler's
//! is the implicit function theorem on its equation: dw/dq = K⁻¹ h f_q, dw/dq̇ = K⁻¹ with
//! K = I − h(h f_q + f_v).

use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure};
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::derived::{AccelerationJacobian, KeptMass, LagrangianExt, sparse_terms};
use crate::model::euler_lagrange::LazyAcceleration;
use crate::model::{ConstantMass, Lagrangian};
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};
use sparse_newton::LazySparseImplicitEuler;

mod sparse_newton;

/// Explicit Euler on the Euler–Lagrange equations (order 1, not symplectic).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExplicitEuler;

/// Implicit Euler on the Euler–Lagrange equations (order 1, not symplectic), by Newton's
/// method on the new velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImplicitEuler {
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for ImplicitEuler {
    fn default() -> Self {
        ImplicitEuler { max_iterations: 50 }
    }
}

/// The classical Runge–Kutta method of order 4 on the Euler–Lagrange equations (not
/// symplectic).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RungeKutta4;

/// The dimension of a run, for RK4 its stage buffers and for implicit Euler its Newton
/// buffers; for a sum of local terms the sparse mass matrix of the acceleration, and
/// implicit Euler's sparse Newton.
#[derive(Debug, Clone)]
pub struct ReferenceWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    n: N,
    stages: Option<Stages<N>>,
    newton: Option<(Newton, DVector<f64>)>,
    acceleration: LazyAcceleration,
    sparse_newton: LazySparseImplicitEuler,
    /// M⁻¹ and M of a constant-mass Lagrangian, from the first acceleration, and the force
    /// ∂L/∂q + f_L M⁻¹ is applied to.
    mass: KeptMass<N>,
    force: OVector<f64, N>,
}

/// RK4's stages, kept across steps (a step allocates nothing).
#[derive(Debug, Clone)]
struct Stages<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The accelerations a₁ … a₄ at the stages.
    accelerations: [OVector<f64, N>; 4],
    /// The velocities v₂, v₃, v₄ at the stages after the first.
    velocities: [OVector<f64, N>; 3],
    /// The position of the stage being evaluated.
    position: OVector<f64, N>,
}

/// Which buffers a reference method's workspace holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Buffers {
    /// None (explicit Euler).
    None,
    /// RK4's stages.
    Stages,
    /// Implicit Euler's Newton iteration, with at most this many iterations.
    Newton(usize),
}

/// The workspace of a reference method on `model`.
fn workspace<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    h: f64,
    buffers: Buffers,
) -> Result<ReferenceWorkspace<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if !(h.is_finite() && h != 0.0) {
        return Err(Error::invalid(
            "h",
            format!("{h} is not a finite non-zero step"),
        ));
    }
    let n =
        dimension_of::<N>(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
    let size = n.value();
    // A sum of terms takes its equations term by term, without an n × n matrix.
    let dense = sparse_terms(model).is_none();
    let zero = || OVector::zeros_generic(n, U1);
    Ok(ReferenceWorkspace {
        n,
        stages: (buffers == Buffers::Stages).then(|| Stages {
            accelerations: std::array::from_fn(|_| zero()),
            velocities: std::array::from_fn(|_| zero()),
            position: zero(),
        }),
        newton: match buffers {
            Buffers::Newton(iterations) if dense => {
                Some((Newton::new(size, iterations), DVector::zeros(size)))
            }
            _ => None,
        },
        acceleration: LazyAcceleration::default(),
        sparse_newton: LazySparseImplicitEuler::default(),
        mass: KeptMass::default(),
        force: zero(),
    })
}

/// The acceleration f(t, q, q̇) into `out` (term by term for a sum of terms, with the
/// run's sparse mass matrix), or the failure of a singular mass matrix. Returns the symbolic
/// analyses it made (the sparse mass matrix's, at a run's first call).
fn acceleration_into<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    workspace: &mut ReferenceWorkspace<N>,
    t: f64,
    (q, v): (&OVector<f64, N>, &OVector<f64, N>),
    out: &mut OVector<f64, N>,
) -> Result<usize, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if ConstantMass::<L, N>::DECLARED {
        // f = M⁻¹(∂L/∂q + f_L): one gradient, no Hessian.
        let inverse = workspace.mass.inverse(model, t, q, v)?;
        model.force_into(t, q, v, &mut workspace.force);
        if L::FORCED {
            workspace.force += model.external_force(t, q, v);
        }
        inverse.apply_into(&workspace.force, out);
        return Ok(0);
    }
    match sparse_terms(model) {
        Some(terms) => {
            let (acceleration, analyses) = workspace.acceleration.get(terms, q.len())?;
            let point = (q.as_slice(), v.as_slice());
            acceleration.acceleration(terms, t, point, out.as_mut_slice())?;
            Ok(analyses)
        }
        None => {
            *out = model
                .acceleration(t, q, v)
                .ok_or(StepFailure::SingularMatrix)?;
            Ok(0)
        }
    }
}

/// The acceleration f(t, q, q̇), as [`acceleration_into`], with the analyses it made.
fn acceleration<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    workspace: &mut ReferenceWorkspace<N>,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
) -> Result<(OVector<f64, N>, usize), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let mut out = OVector::zeros_generic(workspace.n, U1);
    let analyses = acceleration_into(model, workspace, t, (q, v), &mut out)?;
    Ok((out, analyses))
}

/// The acceleration and its Jacobian (term by term for a sum of terms), or the failure of a
/// singular mass matrix.
fn jacobian<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    workspace: &mut ReferenceWorkspace<N>,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
) -> Result<AccelerationJacobian<N>, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let Some(terms) = sparse_terms(model) else {
        return model
            .acceleration_jacobian(t, q, v)
            .ok_or(StepFailure::SingularMatrix);
    };
    let jacobian = workspace.acceleration.get(terms, q.len())?.0.jacobian(
        terms,
        t,
        (q.as_slice(), v.as_slice()),
    )?;
    Ok(AccelerationJacobian::of_run_time(jacobian, workspace.n))
}

/// The facts every reference method shares: coordinates (q, q̇), neither symmetric nor
/// symplectic.
fn info(name: &'static str, order: usize) -> MethodInfo {
    MethodInfo {
        name,
        order,
        symmetric: false,
        symplectic: false,
        coordinates: Coordinates::Velocity,
        equations: Equations::Lagrange,
    }
}

/// A 2N × 2N matrix in blocks.
fn blocks<N: Dimension>(matrix: &DMatrix<f64>, n: N) -> TangentMap<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let size = n.value();
    let block = |r: usize, c: usize| OMatrix::from_fn_generic(n, n, |i, j| matrix[(r + i, c + j)]);
    TangentMap {
        qq: block(0, 0),
        qy: block(0, size),
        yq: block(size, 0),
        yy: block(size, size),
    }
}

/// J = [[0, I], [f_q, f_v]], the Jacobian of F(t, y) = (q̇, f).
fn first_order_jacobian<N: Dimension>(a: &AccelerationJacobian<N>) -> DMatrix<f64>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = a.value.len();
    DMatrix::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => 0.0,
        (true, false) => f64::from(i == j - n),
        (false, true) => a.q[(i - n, j)],
        (false, false) => a.v[(i - n, j - n)],
    })
}

impl<N: Dimension> Method<N> for ExplicitEuler
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = ReferenceWorkspace<N>;

    fn info(&self) -> MethodInfo {
        info("explicit-euler", 1)
    }

    /// A sum of terms: the acceleration and implicit Euler's equation term by term.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        sparse_terms(model).is_some()
    }

    fn momentum_into(
        &self,
        workspace: &Self::Workspace,
        v: &OVector<f64, N>,
        p: &mut OVector<f64, N>,
    ) -> bool {
        workspace.mass.momentum_into(v, p)
    }

    fn workspace<L: Lagrangian<N>>(&self, model: &L, h: f64) -> Result<Self::Workspace, Error> {
        workspace(model, h, Buffers::None)
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let analyses =
            acceleration_into(model, workspace, t, (&state.q, &state.y), &mut increment.y)?;
        increment.q.copy_from(&state.y);
        increment.q *= h;
        increment.y *= h;
        Ok(StepReport {
            evaluations: 1,
            analyses,
            ..StepReport::default()
        })
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let a = jacobian(model, workspace, t, &state.q, &state.y)?;
        let mut increment = State::zeros(workspace.n);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let n = workspace.n;
        let identity = OMatrix::<f64, N, N>::identity_generic(n, n);
        let map = TangentMap {
            qq: identity.clone(),
            qy: &identity * h,
            yq: &a.q * h,
            yy: identity + &a.v * h,
        };
        Ok((increment, map, report))
    }
}

impl<N: Dimension> Method<N> for RungeKutta4
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = ReferenceWorkspace<N>;

    fn info(&self) -> MethodInfo {
        info("rk4", 4)
    }

    /// A sum of terms: the acceleration and implicit Euler's equation term by term.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        sparse_terms(model).is_some()
    }

    fn momentum_into(
        &self,
        workspace: &Self::Workspace,
        v: &OVector<f64, N>,
        p: &mut OVector<f64, N>,
    ) -> bool {
        workspace.mass.momentum_into(v, p)
    }

    fn workspace<L: Lagrangian<N>>(&self, model: &L, h: f64) -> Result<Self::Workspace, Error> {
        workspace(model, h, Buffers::Stages)
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        // Stage i at y + cᵢ h kᵢ₋₁ with k = (dq, dv) = (q̇ of the stage, f of the stage), in
        // the workspace's buffers.
        let mut stages = workspace.stages.take().ok_or(StepFailure::Unsupported {
            option: "workspace",
            reason: "not built for RK4",
        })?;
        let result = rk4(model, workspace, &mut stages, (t, h), state, increment);
        workspace.stages = Some(stages);
        let analyses = result?;
        Ok(StepReport {
            evaluations: 4,
            analyses,
            ..StepReport::default()
        })
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let n = workspace.n;
        let size = n.value();
        let identity = DMatrix::<f64>::identity(2 * size, 2 * size);
        // Stage points and the derivatives dkᵢ/dy of the stage slopes.
        let (mut q, mut v) = (state.q.clone(), state.y.clone());
        let mut sum = DMatrix::<f64>::zeros(2 * size, 2 * size);
        let mut previous: Option<DMatrix<f64>> = None;
        for (c, weight, shift) in [
            (0.0, 1.0, 0.5),
            (0.5, 2.0, 0.5),
            (0.5, 2.0, 1.0),
            (1.0, 1.0, 0.0),
        ] {
            let a = jacobian(model, workspace, t + c * h, &q, &v)?;
            let j = first_order_jacobian(&a);
            let slope = match &previous {
                None => j,
                Some(dk) => &j * (&identity + dk * (c * h)),
            };
            sum += &slope * weight;
            // The next stage's point y + shift·h·kᵢ.
            (q, v) = (
                &state.q + &v * (shift * h),
                &state.y + &a.value * (shift * h),
            );
            previous = Some(slope);
        }
        let map = blocks(&(identity + sum * (h / 6.0)), n);
        let mut increment = State::zeros(n);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        Ok((increment, map, report))
    }
}

/// RK4's step from `state` into `increment`, its four stages in `stages`; the analyses of
/// the first acceleration.
fn rk4<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    workspace: &mut ReferenceWorkspace<N>,
    stages: &mut Stages<N>,
    (t, h): (f64, f64),
    state: &State<N>,
    increment: &mut State<N>,
) -> Result<usize, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (q, v) = (&state.q, &state.y);
    let Stages {
        accelerations,
        velocities,
        position,
    } = stages;
    let analyses = acceleration_into(model, workspace, t, (q, v), &mut accelerations[0])?;
    // Stage i + 1 at time t + c h and at q + c h v_i, v + c h a_i (v₁ = v).
    for (i, c) in [0.5, 0.5, 1.0].into_iter().enumerate() {
        let (before, after) = accelerations.split_at_mut(i + 1);
        let (done, next) = velocities.split_at_mut(i);
        let velocity = if i == 0 { v } else { &done[i - 1] };
        for ((x, q), w) in position.iter_mut().zip(q.iter()).zip(velocity.iter()) {
            *x = q + w * (c * h);
        }
        let stage = &mut next[0];
        for ((w, v), a) in stage.iter_mut().zip(v.iter()).zip(before[i].iter()) {
            *w = v + a * (c * h);
        }
        acceleration_into(
            model,
            workspace,
            t + c * h,
            (position, stage),
            &mut after[0],
        )?;
    }
    let [a1, a2, a3, a4] = &*accelerations;
    let [v2, v3, v4] = &*velocities;
    let sixth = h / 6.0;
    let rates = increment.q.iter_mut().zip(increment.y.iter_mut());
    for (i, (dq, dv)) in rates.enumerate() {
        *dq = (v[i] + (v2[i] + v3[i]) * 2.0 + v4[i]) * sixth;
        *dv = (a1[i] + (a2[i] + a3[i]) * 2.0 + a4[i]) * sixth;
    }
    Ok(analyses)
}

impl ImplicitEuler {
    /// Solve for the new velocity w: w − q̇ − h f(t + h, q + h w, w) = 0, started from the
    /// explicit Euler velocity (for a sum of terms by sparse Newton from q̇,
    /// [`sparse_newton`]).
    /// Writes w to `w` (in place for a sum of terms: no allocation) and returns the work.
    fn solve<L: Lagrangian<N>, N: Dimension>(
        &self,
        model: &L,
        workspace: &mut ReferenceWorkspace<N>,
        (t, h): (f64, f64),
        state: &State<N>,
        w: &mut OVector<f64, N>,
    ) -> Result<StepReport, StepFailure>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let n = workspace.n;
        if let Some(terms) = sparse_terms(model) {
            // From q̇_k: the simplified Newton iteration needs no acceleration to start.
            w.copy_from(&state.y);
            let (solved, analyses) = workspace.sparse_newton.solve(
                terms,
                self.max_iterations,
                (t, h),
                (state.q.as_slice(), state.y.as_slice()),
                w.as_mut_slice(),
            )?;
            return Ok(StepReport {
                iterations: solved.iterations,
                evaluations: solved.iterations + 1,
                factorizations: solved.factorizations,
                analyses,
            });
        }
        let (a, _) = acceleration(model, workspace, t, &state.q, &state.y)?;
        let start = &state.y + a * h;
        let (newton, z) = workspace.newton.as_mut().ok_or(StepFailure::Unsupported {
            option: "workspace",
            reason: "not built for implicit Euler",
        })?;
        z.copy_from_slice(start.as_slice());
        let mut failed = None;
        let iterations = newton.solve(z, |z, jacobian, residual| {
            let w = OVector::<f64, N>::from_column_slice_generic(n, U1, z.as_slice());
            let q = &state.q + &w * h;
            match model.acceleration_jacobian(t + h, &q, &w) {
                Some(a) => {
                    let r = &w - &state.y - &a.value * h;
                    residual.copy_from_slice(r.as_slice());
                    let size = n.value();
                    for i in 0..size {
                        for j in 0..size {
                            jacobian[(i, j)] =
                                f64::from(i == j) - h * (h * a.q[(i, j)] + a.v[(i, j)]);
                        }
                    }
                }
                None => {
                    failed = Some(StepFailure::SingularMatrix);
                    residual.fill(f64::NAN);
                }
            }
        });
        if let Some(failure) = failed {
            return Err(failure);
        }
        let iterations = iterations?;
        w.copy_from_slice(z.as_slice());
        Ok(StepReport {
            iterations,
            evaluations: iterations + 1,
            factorizations: iterations,
            analyses: 0,
        })
    }
}

impl<N: Dimension> Method<N> for ImplicitEuler
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = ReferenceWorkspace<N>;

    fn info(&self) -> MethodInfo {
        info("implicit-euler", 1)
    }

    /// A sum of terms: the acceleration and implicit Euler's equation term by term.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        sparse_terms(model).is_some()
    }

    fn momentum_into(
        &self,
        workspace: &Self::Workspace,
        v: &OVector<f64, N>,
        p: &mut OVector<f64, N>,
    ) -> bool {
        workspace.mass.momentum_into(v, p)
    }

    fn workspace<L: Lagrangian<N>>(&self, model: &L, h: f64) -> Result<Self::Workspace, Error> {
        if self.max_iterations == 0 {
            return Err(Error::invalid(
                "max_iterations",
                "at least one Newton iteration",
            ));
        }
        workspace(model, h, Buffers::Newton(self.max_iterations))
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        // w into the velocity's increment, then dq = h w and dq̇ = w − q̇ in place.
        let report = self.solve(model, workspace, (t, h), state, &mut increment.y)?;
        increment.q.copy_from(&increment.y);
        increment.q *= h;
        increment.y -= &state.y;
        Ok(report)
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let mut w = OVector::zeros_generic(workspace.n, U1);
        let report = self.solve(model, workspace, (t, h), state, &mut w)?;
        let q = &state.q + &w * h;
        let a = jacobian(model, workspace, t + h, &q, &w)?;
        let n = workspace.n;
        let identity = OMatrix::<f64, N, N>::identity_generic(n, n);
        // K dw = h f_q dq + dq̇, K = I − h(h f_q + f_v).
        let k = &identity - (&a.q * h + &a.v) * h;
        let inverse = crate::linalg::invert_small(&k).ok_or(StepFailure::SingularMatrix)?;
        let dw_dq = &inverse * &a.q * h;
        let map = TangentMap {
            qq: &identity + &dw_dq * h,
            qy: &inverse * h,
            yq: dw_dq,
            yy: inverse,
        };
        let increment = State {
            q: q - &state.q,
            y: w - &state.y,
        };
        Ok((increment, map, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_models::{
        HenonHeiles, VariableMass, assert_tangent_matches_central_differences, state,
    };

    /// A constant mass takes f = M⁻¹(L_q + f_L) without a Hessian; the general path on the
    /// same L (declared [`crate::Structure::General`]) gives the same steps to round-off.
    #[test]
    fn a_constant_mass_gives_the_general_acceleration() {
        use crate::test_models::{Damped, advance, distance};
        let start = state([0.3, -0.2], [0.1, 0.4]);
        let (constant, _) = advance(&RungeKutta4, &HenonHeiles::<true>, 0.05, 100, start);
        let (general, _) = advance(&RungeKutta4, &HenonHeiles::<false>, 0.05, 100, start);
        assert!(distance(&constant, &general) < 1e-13);
        let (constant, workspace) = advance(&ExplicitEuler, &HenonHeiles::<true>, 0.05, 100, start);
        let (general, _) = advance(&ExplicitEuler, &HenonHeiles::<false>, 0.05, 100, start);
        assert!(distance(&constant, &general) < 1e-13);
        // The observers' momentum p = M q̇ from the kept M, without differentiating L.
        let mut p = constant.q;
        assert!(Method::<nalgebra::U2>::momentum_into(
            &ExplicitEuler,
            &workspace,
            &constant.y,
            &mut p
        ));
        let exact = HenonHeiles::<true>.momentum(0.0, &constant.q, &constant.y);
        assert!((p - exact).amax() < 1e-15);
        // With friction f_L = −c q̇.
        let start = state([0.8], [-0.4]);
        let (constant, _) = advance(&RungeKutta4, &Damped::<true> { c: 0.3 }, 0.05, 100, start);
        let (general, _) = advance(&RungeKutta4, &Damped::<false> { c: 0.3 }, 0.05, 100, start);
        assert!(distance(&constant, &general) < 1e-13);
        let implicit = ImplicitEuler::default();
        let (constant, _) = advance(&implicit, &Damped::<true> { c: 0.3 }, 0.05, 100, start);
        let (general, _) = advance(&implicit, &Damped::<false> { c: 0.3 }, 0.05, 100, start);
        assert!(distance(&constant, &general) < 1e-13);
    }

    #[test]
    fn the_tangent_maps_match_central_differences() {
        for start in [
            state([0.3, -0.2], [0.1, 0.4]),
            state([-0.5, 0.4], [0.6, -0.3]),
        ] {
            assert_tangent_matches_central_differences(&ExplicitEuler, &VariableMass, start);
            assert_tangent_matches_central_differences(&RungeKutta4, &VariableMass, start);
            assert_tangent_matches_central_differences(
                &ImplicitEuler::default(),
                &VariableMass,
                start,
            );
            assert_tangent_matches_central_differences(&RungeKutta4, &HenonHeiles::<false>, start);
        }
    }

    /// One step of each on q̈ = −q from (1, 0): explicit Euler (1, −h), implicit Euler
    /// (1, −h)/(1 + h²), and RK4 the Taylor polynomial of (cos h, −sin h) to h⁴.
    #[test]
    fn one_step_on_the_oscillator_is_the_closed_form() {
        use crate::test_models::Oscillator;
        let (h, start) = (0.1, state([1.0], [0.0]));
        let end = |method: &dyn Fn(&mut State<nalgebra::U1>)| {
            let mut increment = State::zeros(nalgebra::U1);
            method(&mut increment);
            (start.q[0] + increment.q[0], start.y[0] + increment.y[0])
        };
        let model = Oscillator::<false>;
        let explicit = end(&|inc| {
            let mut ws = Method::workspace(&ExplicitEuler, &model, h).unwrap();
            ExplicitEuler
                .step(&model, &mut ws, 0.0, h, &start, inc)
                .unwrap();
        });
        assert_eq!(explicit, (1.0, -h));
        let implicit = end(&|inc| {
            let method = ImplicitEuler::default();
            let mut ws = Method::workspace(&method, &model, h).unwrap();
            method.step(&model, &mut ws, 0.0, h, &start, inc).unwrap();
        });
        let d = 1.0 + h * h;
        assert!((implicit.0 - 1.0 / d).abs() < 1e-15 && (implicit.1 + h / d).abs() < 1e-15);
        let rk4 = end(&|inc| {
            let mut ws = Method::workspace(&RungeKutta4, &model, h).unwrap();
            RungeKutta4
                .step(&model, &mut ws, 0.0, h, &start, inc)
                .unwrap();
        });
        let (c, s) = (1.0 - h * h / 2.0 + h.powi(4) / 24.0, h - h.powi(3) / 6.0);
        assert!(
            (rk4.0 - c).abs() < 1e-15 && (rk4.1 + s).abs() < 1e-15,
            "{rk4:?}"
        );
    }
}
