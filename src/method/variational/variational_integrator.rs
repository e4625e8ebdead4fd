//! The variational integrator of any discrete Lagrangian.
//!
//! # Discrete equations
//! For a discrete Lagrangian L_d ([`DiscreteLagrangian`]) with discrete forces f_d^±, the
//! step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) solves the implicit discrete Euler–Lagrange
//! equations (Li, Wu, Leok 2018, eq. 5; forced: Marsden & West 2001, eq. 3.2.6)
//!
//! p_k = −D1 L_d(q_k, q_{k+1}) − f_d⁻(q_k, q_{k+1}),
//! p_{k+1} = D2 L_d(q_k, q_{k+1}) + f_d⁺(q_k, q_{k+1}).
//!
//! The first is solved for q_{k+1} by Newton's method with the exact Jacobian
//! D12 L_d + ∂f_d⁻/∂q_{k+1} (automatic differentiation by the dimension's sweeps,
//! [`crate::dimension::Dimension`]: one mixed second derivative gives D1 L_d, D2 L_d and
//! D12 L_d together; one Jacobian gives f_d⁻ and its derivative), iterated to
//! round-off with the stopping rule shared by all implicit methods of `svi`. The unknown is
//! the increment q_{k+1} − q_k. The first step starts from the Taylor predictor
//! q_k + h q̇ + (h²/2) q̈ (q̇ from the inverse Legendre map of p_k, q̈ from the forced
//! Euler–Lagrange equations); later steps extrapolate the increments of the two previous
//! steps linearly, 2Δ_{k−1} − Δ_{k−2} (an O(h³) guess, at no cost).
//!
//! The momentum is updated without cancellation: adding the two equations,
//!
//! p_{k+1} − p_k = (D1 + D2) L_d(q_k, q_{k+1}) + f_d⁻ + f_d⁺,
//!
//! and (D1 + D2) L_d is the derivative of ε ↦ L_d(q_k + ε, q_{k+1} + ε), computed by one
//! gradient sweep in which the discrete velocity carries no derivative at all: for the
//! segment rules of [`crate::method::variational::discrete_lagrangian`] it is h Σ_i b_i ∂L/∂q(τ_i), the discrete
//! momentum balance, whereas D2 L_d + D1 L_d term by term cancels O(|p|) each step.
//!
//! # Sums of local terms
//! For an unforced sum of local terms of run-time size ([`Lagrangian::terms`]) the discrete
//! Euler–Lagrange equations of a segment rule are the stage equations of a degree-1 Galerkin
//! integrator (the two-point basis with the rule as its quadrature), solved by sparse Newton
//! with the Jacobian assembled term by term (`stage_newton`): O(n) work and memory per step
//! for a chain of any size, and p_{k+1} − p_k = h Σ_i b_i ∂L/∂q(τ_i) as above.
//!
//! # Properties
//! The order and symmetry of the discrete Lagrangian ([`DiscreteLagrangianInfo`]);
//! symplectic (L_d is a type-I generating function of the step), and Noether momenta of
//! symmetries of L_d are conserved. With an external force the step is the discrete
//! Lagrange–d'Alembert map: not symplectic, same order.
//!
//! # References
//! Li, Wu, Leok (2018), eqs. (4)–(5); Marsden & West, *Discrete mechanics and variational
//! integrators*, Acta Numerica (2001), §1.2, §2.7 and §3.2; Porcù & Penati (OctConf 2013),
//! "Discrete mechanics" and "Forced mechanics".

use crate::dimension::{Dimension, PhaseFunction, PhaseMap, Wrt, dimension_of};
use crate::error::Error;
use crate::error::StepFailure;
use crate::linalg::invert_small;
use crate::linalg::sparse::LinearSolverKind;
use crate::method::Method;
use crate::method::variational::discrete_lagrangian::{
    DiscreteLagrangian, DiscreteLagrangianInfo, Kicks,
};
use crate::method::variational::kick_drift_kick::Explicit;
use crate::method::variational::stage_newton::LazyStageNewton;
use crate::method::variational::tables::Tables;
use crate::method::{Coordinates, Equations, MethodInfo, State, StepReport, TangentMap};
use crate::model::derived::sparse_terms;
use crate::model::derived::{LagrangianExt, cached_mass_inverse};
use crate::model::legendre::LazyLegendre;
use crate::model::mass_inverse::MassInverse;
use crate::model::term_pattern::check_width;
use crate::model::{ConstantMass, Lagrangian, Structure};
use crate::nonlinear::{Jacobian, Newton};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Options of the variational integrator of a discrete Lagrangian.
///
/// ```
/// use nalgebra::{SVector, U1};
/// use svi::{Integrator, Lagrangian, Midpoint, Scalar, VariationalIntegrator};
///
/// struct Oscillator;
/// impl Lagrangian<U1> for Oscillator {
///     const TIME_DEPENDENT: bool = false;
///     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
///         (v[0] * v[0] - q[0] * q[0]) * 0.5
///     }
/// }
///
/// let integrator = Integrator::new(Oscillator, VariationalIntegrator::new(Midpoint));
/// let run = integrator
///     .run_from_velocity(0.0, SVector::from([1.0]), SVector::from([0.0]), 0.01, 1.0, &mut ())
///     .unwrap();
/// assert!((run.last.q[0] - 1f64.cos()).abs() < 1e-5);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct VariationalIntegrator<Ld> {
    /// The discrete Lagrangian (and with it the discrete forces).
    pub discrete_lagrangian: Ld,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl<Ld: Default> Default for VariationalIntegrator<Ld> {
    fn default() -> Self {
        VariationalIntegrator::new(Ld::default())
    }
}

impl<Ld> VariationalIntegrator<Ld> {
    /// The variational integrator of `discrete_lagrangian`.
    pub fn new(discrete_lagrangian: Ld) -> Self {
        VariationalIntegrator {
            discrete_lagrangian,
            max_iterations: 50,
        }
    }

    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }
}

/// The increments of the previous steps, for the predictor.
#[derive(Debug, Clone)]
struct History<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Step size of the recorded steps (NaN before the first step: nothing continues it).
    h: f64,
    /// Where the last step ended: the next step continues the run if it starts there.
    end: OVector<f64, N>,
    /// Round-off tolerance for recognising `end`.
    tolerance: f64,
    /// Δ_{k−1}.
    last: OVector<f64, N>,
    /// Δ_{k−2}, if `has_before` (the step before the last one was recorded too).
    before: OVector<f64, N>,
    /// Whether `before` holds Δ_{k−2}.
    has_before: bool,
}

impl<N: Dimension> History<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// No step recorded yet (buffers of dimension `n`).
    fn empty(n: N) -> Self {
        History {
            h: f64::NAN,
            end: OVector::zeros_generic(n, U1),
            tolerance: 0.0,
            last: OVector::zeros_generic(n, U1),
            before: OVector::zeros_generic(n, U1),
            has_before: false,
        }
    }

    /// Whether a step of size `h` from `q` continues the recorded steps.
    fn continued_by(&self, h: f64, q: &OVector<f64, N>) -> bool {
        self.h == h && largest_difference(q, &self.end) <= self.tolerance
    }
}

/// ‖a − b‖∞, as `(a − b).amax()` (the same maximum, NaN handling included) without the
/// difference vector.
#[inline]
fn largest_difference<N: Dimension>(a: &OVector<f64, N>, b: &OVector<f64, N>) -> f64
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let mut differences = a
        .as_slice()
        .iter()
        .zip(b.as_slice())
        .map(|(x, y)| (x - y).abs());
    let first = differences.next().unwrap_or(0.0);
    differences.fold(first, f64::max)
}

/// A tolerance for recognising a position after the stepping loop's compensated summation:
/// its result differs from the plain sum q + Δ by the rounding of the two additions.
pub(crate) fn continuation_tolerance<N: Dimension>(
    start: &OVector<f64, N>,
    end: &OVector<f64, N>,
) -> f64
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    4.0 * f64::EPSILON * start.amax().max(end.amax())
}

/// Buffers of a run of a [`VariationalIntegrator`] (and of [`crate::StormerVerlet`]): the
/// explicit kick–drift–kick path of a constant-mass Lagrangian under a discrete Lagrangian
/// with [`Kicks`], or Newton's method on the discrete Euler–Lagrange equations.
#[derive(Debug, Clone)]
pub struct VariationalWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    path: Path<N>,
}

/// The path of a run, chosen once by the model's structure.
#[derive(Debug, Clone)]
enum Path<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Both boxed: a workspace is made once per run, and the two differ in size.
    Explicit(Box<Explicit<N>>),
    Implicit(Box<Implicit<N>>),
}

/// Buffers of the implicit path.
#[derive(Debug, Clone)]
struct Implicit<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The unknown increment q_{k+1} − q_k.
    offset: DVector<f64>,
    newton: Newton,
    history: History<N>,
    /// Sparse Newton, for an unforced sum of terms of run-time size and a segment rule.
    sparse: Option<SparseSegment>,
    /// M⁻¹ of a constant-mass Lagrangian, from the first step: the observers' q̇ = M⁻¹p.
    mass_inverse: Option<MassInverse<N>>,
}

/// The stage tables of a segment rule and the sparse Newton solver of its equations.
#[derive(Debug, Clone)]
struct SparseSegment {
    tables: Tables,
    stage: LazyStageNewton,
    /// The inverse Legendre map of the sum of terms, made at its first use.
    legendre: LazyLegendre,
}

impl<N: Dimension> Implicit<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Buffers for a configuration space of dimension `n`.
    fn new(n: N, max_iterations: usize) -> Self {
        Implicit {
            offset: DVector::zeros(n.value()),
            newton: Newton::new(n.value(), max_iterations),
            history: History::empty(n),
            sparse: None,
            mass_inverse: None,
        }
    }

    /// Write the predicted increment into `offset`: extrapolated from the previous steps
    /// when this step continues them, else the Taylor polynomial of the continuous flow.
    fn predict<L: Lagrangian<N>>(&mut self, model: &L, t: f64, h: f64, state: &State<N>) {
        let history = &self.history;
        let offset = self.offset.as_mut_slice();
        if history.continued_by(h, &state.q) {
            if history.has_before {
                for ((target, last), before) in offset
                    .iter_mut()
                    .zip(history.last.as_slice())
                    .zip(history.before.as_slice())
                {
                    *target = last * 2.0 - before;
                }
            } else {
                offset.copy_from_slice(history.last.as_slice());
            }
            return;
        }
        let n = state.dimension();
        let v = model
            .velocity(t, &state.q, &state.y, &state.y)
            .unwrap_or_else(|_| OVector::zeros_generic(n, U1));
        // A sum of terms starts from uniform motion: its acceleration is a dense solve.
        let a = model
            .terms()
            .is_none()
            .then(|| model.acceleration(t, &state.q, &v))
            .flatten()
            .unwrap_or_else(|| OVector::zeros_generic(n, U1));
        let half_square = 0.5 * h * h;
        for ((target, v), a) in offset.iter_mut().zip(v.as_slice()).zip(a.as_slice()) {
            *target = v * h + a * half_square;
        }
    }

    /// Record a completed step.
    fn remember(&mut self, h: f64, state: &State<N>, increment: &OVector<f64, N>) {
        let history = &mut self.history;
        let continued = history.continued_by(h, &state.q);
        if continued {
            history.before.copy_from(&history.last);
        }
        history.has_before = continued;
        history.h = h;
        for ((end, q), dq) in history
            .end
            .as_mut_slice()
            .iter_mut()
            .zip(state.q.as_slice())
            .zip(increment.as_slice())
        {
            *end = q + dq;
        }
        history.tolerance = continuation_tolerance(&state.q, &history.end);
        history.last.copy_from(increment);
    }
}

impl<Ld: DiscreteLagrangian> VariationalIntegrator<Ld> {
    /// The workspace of a run: the explicit path with `kicks` for a constant-mass Lagrangian,
    /// else Newton's method (sparse for an unforced sum of terms and a segment rule).
    pub(crate) fn workspace_with<L: Lagrangian<N>, N: Dimension>(
        &self,
        model: &L,
        h: f64,
        kicks: Option<Kicks>,
    ) -> Result<VariationalWorkspace<N>, Error>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        crate::error::require_positive("h", h)?;
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        let n = dimension_of::<N>(model.dimension())
            .map_err(|reason| Error::invalid("model", reason))?;
        if let (Some(kicks), Structure::ConstantMass) = (kicks, L::STRUCTURE) {
            let explicit = Explicit::new(kicks, n, L::FORCED, self.max_iterations);
            return Ok(VariationalWorkspace {
                path: Path::Explicit(Box::new(explicit)),
            });
        }
        let mut implicit = Implicit::new(n, self.max_iterations);
        if let (Some(terms), Some(nodes)) =
            (sparse_terms(model), self.discrete_lagrangian.segment())
        {
            check_width(terms.width())?;
            implicit.sparse = Some(SparseSegment {
                tables: Tables::segment(nodes, h)?,
                stage: LazyStageNewton::default(),
                legendre: LazyLegendre::default(),
            });
        }
        Ok(VariationalWorkspace {
            path: Path::Implicit(Box::new(implicit)),
        })
    }
}

impl<Ld: DiscreteLagrangian, N: Dimension> Method<N> for VariationalIntegrator<Ld>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;

    type Workspace = VariationalWorkspace<N>;

    fn info(&self) -> MethodInfo {
        let DiscreteLagrangianInfo {
            name,
            order,
            symmetric,
            ..
        } = self.discrete_lagrangian.info();
        MethodInfo {
            name,
            order,
            symmetric,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Lagrange,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<VariationalWorkspace<N>, Error> {
        self.workspace_with(model, h, self.discrete_lagrangian.kicks())
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut VariationalWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let workspace = match &mut workspace.path {
            Path::Explicit(explicit) => return explicit.step(model, t, h, state, increment),
            Path::Implicit(implicit) => &mut **implicit,
        };
        if ConstantMass::<L, N>::DECLARED {
            cached_mass_inverse(&mut workspace.mass_inverse, model, t, &state.q, &state.y)?;
        }
        if let Some(terms) = sparse_terms(model)
            && workspace.sparse.is_some()
        {
            // Sparse Newton on the segment rule's stage equations (see the module docs).
            workspace.predict(model, t, h, state);
            let Implicit { offset, sparse, .. } = workspace;
            let Some(SparseSegment { tables, stage, .. }) = sparse.as_mut() else {
                return Err(StepFailure::SingularMatrix);
            };
            if tables.h != h {
                tables.rescale(h);
                stage.invalidate();
            }
            let points = tables.weights.len();
            let (solved, analyses) = stage.step(
                terms,
                tables,
                (t, state.q.as_slice(), state.y.as_slice()),
                offset,
                (increment.q.as_mut_slice(), increment.y.as_mut_slice()),
                Jacobian::Kept,
                (LinearSolverKind::Auto, self.max_iterations),
            )?;
            workspace.remember(h, state, &increment.q);
            return Ok(StepReport {
                iterations: solved.iterations,
                evaluations: points * (solved.iterations + 1),
                factorizations: solved.factorizations,
                analyses,
            });
        }
        let iterations = solve_position(&self.discrete_lagrangian, model, workspace, t, h, state)?;
        let offset = &workspace.offset;
        let q1 = OVector::from_fn_generic(state.dimension(), U1, |i, _| state.q[i] + offset[i]);
        increment.q = OVector::from_column_slice_generic(state.dimension(), U1, offset.as_slice());
        increment.y = momentum_increment(&self.discrete_lagrangian, model, t, h, &state.q, &q1);
        workspace.remember(h, state, &increment.q);
        let points = self.discrete_lagrangian.info().points;
        Ok(StepReport {
            iterations,
            evaluations: points * (iterations + 1),
            factorizations: iterations,
            analyses: 0,
        })
    }

    /// q̇ = M⁻¹p from the cached inverse of a constant mass matrix (checked by the
    /// integrator's first run), or the sparse inverse Legendre map a run on a sum of terms
    /// keeps (sparse Newton's runs).
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &VariationalWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        let sparse = match &workspace.path {
            Path::Explicit(explicit) => {
                return Ok(match explicit.mass_inverse() {
                    Some(inverse) => {
                        inverse.apply_into(p, v);
                        true
                    }
                    None => false,
                });
            }
            Path::Implicit(implicit) => {
                if let Some(inverse) = &implicit.mass_inverse {
                    inverse.apply_into(p, v);
                    return Ok(true);
                }
                &implicit.sparse
            }
        };
        let (Some(segment), Some(terms)) = (sparse, sparse_terms(model)) else {
            return Ok(false);
        };
        segment
            .legendre
            .solve(terms, t, q.as_slice(), p.as_slice(), v.as_mut_slice())?;
        Ok(true)
    }

    /// A segment rule on an unforced sum of terms: sparse Newton.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        model.terms().is_some() && !L::FORCED && self.discrete_lagrangian.segment().is_some()
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut VariationalWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let mut increment = State::zeros(state.dimension());
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let q1 = &state.q + &increment.q;
        let tangent = discrete_tangent_map(&self.discrete_lagrangian, model, t, h, &state.q, &q1)?;
        Ok((increment, tangent, report))
    }
}

/// L_d(t, q0, q1) of a step of size `h` as a [`PhaseFunction`] of (t, q, q̇) = (t, q0, q1),
/// for the sweeps of [`Dimension`]: ∂/∂q is D1 L_d, ∂/∂q̇ is D2 L_d, the mixed block D12 L_d.
struct StepAction<'a, Ld, L> {
    discrete: &'a Ld,
    model: &'a L,
    h: f64,
}

impl<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension> PhaseFunction<N>
    for StepAction<'_, Ld, L>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    #[inline(always)]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> S {
        self.discrete
            .discrete_lagrangian(self.model, t, S::from(self.h), q, v)
    }
}

/// L_d(t, q0 + ε, q1 + ε) as a function of the common shift ε (passed as q; q̇ is unused):
/// its gradient at ε = 0 is (D1 + D2) L_d(q0, q1).
struct ShiftedAction<'a, Ld, L, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    discrete: &'a Ld,
    model: &'a L,
    h: f64,
    q0: &'a OVector<f64, N>,
    q1: &'a OVector<f64, N>,
}

impl<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension> PhaseFunction<N>
    for ShiftedAction<'_, Ld, L, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    #[inline(always)]
    fn eval<S: Scalar>(&self, t: S, shift: &OVector<S, N>, _v: &OVector<S, N>) -> S {
        let start = self.q0.map(S::from) + shift;
        let end = self.q1.map(S::from) + shift;
        self.discrete
            .discrete_lagrangian(self.model, t, S::from(self.h), &start, &end)
    }
}

/// One of the discrete forces f_d⁺ (`plus`) or f_d⁻ of a step of size `h` as a [`PhaseMap`]
/// of (t, q, q̇) = (t, q0, q1).
struct StepForce<'a, Ld, L> {
    discrete: &'a Ld,
    model: &'a L,
    h: f64,
    plus: bool,
}

impl<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension> PhaseMap<N> for StepForce<'_, Ld, L>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    #[inline(always)]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> OVector<S, N> {
        let forces = self
            .discrete
            .discrete_forces(self.model, t, S::from(self.h), q, v);
        if self.plus { forces.plus } else { forces.minus }
    }
}

/// Solve p_k + D1 L_d(q_k, q_k + Δ) + f_d⁻ = 0 for Δ (left in `workspace.offset`); returns
/// the Newton iterations.
fn solve_position<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension>(
    discrete: &Ld,
    model: &L,
    workspace: &mut Implicit<N>,
    t: f64,
    h: f64,
    state: &State<N>,
) -> Result<usize, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    workspace.predict(model, t, h, state);
    let (q0, p0) = (&state.q, &state.y);
    let n = state.dimension();
    let minus = StepForce {
        discrete,
        model,
        h,
        plus: false,
    };
    workspace
        .newton
        .solve(&mut workspace.offset, |z, matrix, residual| {
            let q1 = OVector::from_fn_generic(n, U1, |i, _| q0[i] + z[i]);
            let (d1, _, d12) = mixed_derivatives(discrete, model, t, h, q0, &q1);
            let mut value = p0 + d1;
            let mut jacobian_matrix = d12;
            if L::FORCED {
                let (force, d_force) = N::jacobian(&minus, t, q0, &q1, Wrt::Velocity);
                value += force;
                jacobian_matrix += d_force;
            }
            residual.copy_from_slice(value.as_slice());
            matrix
                .as_mut_slice()
                .copy_from_slice(jacobian_matrix.as_slice());
        })
}

/// D1 L_d, D2 L_d and D12 L_d (entry (i, j) = ∂²L_d/∂q0_i∂q1_j) in one sweep.
#[allow(clippy::type_complexity)]
fn mixed_derivatives<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &OVector<f64, N>,
    q1: &OVector<f64, N>,
) -> (OVector<f64, N>, OVector<f64, N>, OMatrix<f64, N, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let action = StepAction { discrete, model, h };
    let (_, d1, d2, d12) = N::mixed(&action, t, q0, q1);
    (d1, d2, d12)
}

/// p_{k+1} − p_k = (D1 + D2) L_d(q0, q1) + f_d⁻ + f_d⁺, with (D1 + D2) L_d the derivative of
/// L_d along the common shift (q0 + ε, q1 + ε): no O(|p|) cancellation.
pub(crate) fn momentum_increment<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &OVector<f64, N>,
    q1: &OVector<f64, N>,
) -> OVector<f64, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let zero = OVector::zeros_generic(q0.shape_generic().0, U1);
    let shifted = ShiftedAction {
        discrete,
        model,
        h,
        q0,
        q1,
    };
    let (_, mut increment) = N::gradient(&shifted, t, &zero, &zero, Wrt::Position);
    if L::FORCED {
        let forces = discrete.discrete_forces(model, t, h, q0, q1);
        increment += forces.minus + forces.plus;
    }
    increment
}

/// The exact Jacobian of the step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) of a discrete Lagrangian at
/// a solved step (implicit function theorem on the discrete Euler–Lagrange equations):
///
/// ∂q_{k+1}/∂q_k = −J⁻¹ (D11 L_d + ∂f_d⁻/∂q_k),  ∂q_{k+1}/∂p_k = −J⁻¹,
/// ∂p_{k+1}/∂(·) = (D21 L_d + ∂f_d⁺/∂q_k) ∂q_k/∂(·) + (D22 L_d + ∂f_d⁺/∂q_{k+1}) ∂q_{k+1}/∂(·),
///
/// with J = D12 L_d + ∂f_d⁻/∂q_{k+1}.
pub(crate) fn discrete_tangent_map<Ld: DiscreteLagrangian, L: Lagrangian<N>, N: Dimension>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &OVector<f64, N>,
    q1: &OVector<f64, N>,
) -> Result<TangentMap<N>, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (_, _, d12) = mixed_derivatives(discrete, model, t, h, q0, q1);
    let action = StepAction { discrete, model, h };
    let (_, _, d11) = N::hessian(&action, t, q0, q1, Wrt::Position);
    let (_, _, d22) = N::hessian(&action, t, q0, q1, Wrt::Velocity);
    let n = q0.shape_generic().0;
    let mut minus_q0 = OMatrix::zeros_generic(n, n);
    let mut minus_q1 = OMatrix::zeros_generic(n, n);
    let mut plus_q0 = OMatrix::zeros_generic(n, n);
    let mut plus_q1 = OMatrix::zeros_generic(n, n);
    if L::FORCED {
        let forces = |plus: bool, wrt: Wrt| {
            let force = StepForce {
                discrete,
                model,
                h,
                plus,
            };
            N::jacobian(&force, t, q0, q1, wrt).1
        };
        minus_q0 = forces(false, Wrt::Position);
        minus_q1 = forces(false, Wrt::Velocity);
        plus_q0 = forces(true, Wrt::Position);
        plus_q1 = forces(true, Wrt::Velocity);
    }
    let inverse = invert_small(&(&d12 + &minus_q1)).ok_or(StepFailure::SingularMatrix)?;
    let qq = -(&inverse * (d11 + minus_q0));
    let qy = -inverse;
    let end = d22 + plus_q1;
    let yq = d12.transpose() + plus_q0 + &end * &qq;
    let yy = &end * &qy;
    Ok(TangentMap { qq, qy, yq, yy })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::variational::discrete_lagrangian::{Midpoint, SymplecticEuler, Trapezoid};
    use crate::test_models::{AsDyn, Damped, HenonHeiles, VariableMass, advance, state};
    use nalgebra::{Const, Dyn};

    /// `state` as a state of a run-time-size model.
    fn run_time<const K: usize>(state: &State<Const<K>>) -> State<Dyn> {
        State {
            q: DVector::from_column_slice(state.q.as_slice()),
            y: DVector::from_column_slice(state.y.as_slice()),
        }
    }

    /// Steps and tangent map of `method` on `model` and on the same model seen as a
    /// run-time-size one agree to round-off (the derivatives are taken by other sweeps).
    fn assert_run_time_size_agrees<Ld, L, const K: usize>(
        method: &VariationalIntegrator<Ld>,
        model: L,
        start: State<Const<K>>,
    ) where
        Ld: DiscreteLagrangian + std::fmt::Debug,
        L: Lagrangian<Const<K>>,
    {
        let h = 0.1;
        let (fixed, _) = advance(method, &model, h, 10, start);
        let mut workspace = method.workspace(&model, h).unwrap();
        let (_, tangent, _) = method
            .tangent_map(&model, &mut workspace, 0.0, h, &start)
            .unwrap();
        let dynamic = AsDyn::<L, Const<K>>::new(model);
        let (other, _) = advance(method, &dynamic, h, 10, run_time(&start));
        let fixed = fixed.q.iter().chain(fixed.y.iter());
        let difference = fixed
            .zip(other.q.iter().chain(other.y.iter()))
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(difference <= 1e-13, "{method:?}: {difference:e}");
        let mut workspace = method.workspace(&dynamic, h).unwrap();
        let (_, other_tangent, _) = method
            .tangent_map(&dynamic, &mut workspace, 0.0, h, &run_time(&start))
            .unwrap();
        let difference = (tangent.matrix() - other_tangent.matrix()).amax();
        assert!(
            difference <= 1e-12,
            "{method:?}: tangent maps differ by {difference:e}"
        );
    }

    #[test]
    fn a_run_time_size_model_takes_the_same_steps() {
        let start = state([0.5, -0.3], [0.4, 0.6]);
        let forced = state([1.0], [0.2]);
        assert_run_time_size_agrees(&VariationalIntegrator::new(Midpoint), VariableMass, start);
        assert_run_time_size_agrees(
            &VariationalIntegrator::new(Trapezoid),
            HenonHeiles::<false>,
            start,
        );
        assert_run_time_size_agrees(
            &VariationalIntegrator::new(SymplecticEuler),
            VariableMass,
            start,
        );
        assert_run_time_size_agrees(
            &VariationalIntegrator::new(Midpoint),
            Damped::<false> { c: 0.3 },
            forced,
        );
        assert_run_time_size_agrees(
            &VariationalIntegrator::new(Trapezoid),
            Damped::<false> { c: 0.3 },
            forced,
        );
    }

    /// On a constant mass the implicit path keeps M⁻¹ from its first step: the observers'
    /// q̇ = M⁻¹p needs no Newton solve of the Legendre map; a variable mass keeps none.
    #[test]
    fn a_constant_mass_gives_the_observers_velocity_without_a_solve() {
        let start = state([0.3, -0.2], [0.1, 0.25]);
        let model = HenonHeiles::<true>;
        let method = VariationalIntegrator::new(Midpoint);
        let (end, workspace) = advance(&method, &model, 0.1, 3, start);
        let mut v = end.q;
        assert!(
            method
                .velocity_into(&model, &workspace, 0.3, &end.q, &end.y, &mut v)
                .unwrap()
        );
        let mass = nalgebra::Matrix2::new(2.0, 1.0, 1.0, 3.0);
        assert!((mass * v - end.y).amax() < 1e-15);
        let (end, workspace) = advance(&method, &VariableMass, 0.1, 3, start);
        assert!(
            !method
                .velocity_into(&VariableMass, &workspace, 0.3, &end.q, &end.y, &mut v)
                .unwrap()
        );
    }

    #[test]
    fn the_predictor_continues_only_the_recorded_steps() {
        // Two steps recorded: the next one from the end of the last is predicted by linear
        // extrapolation of the increments; one from elsewhere, or of another size, by the
        // Taylor polynomial.
        let method = VariationalIntegrator::new(Midpoint);
        let model = VariableMass;
        let h = 0.1;
        let (end, mut workspace) = advance(&method, &model, h, 2, state([0.5, -0.3], [0.4, 0.6]));
        let Path::Implicit(workspace) = &mut workspace.path else {
            panic!("a variable mass takes the implicit path");
        };
        assert!(workspace.history.has_before);
        let expected = workspace.history.last * 2.0 - workspace.history.before;
        workspace.predict(&model, 0.2, h, &end);
        assert_eq!(workspace.offset.as_slice(), expected.as_slice());
        workspace.predict(&model, 0.2, 0.5 * h, &end);
        assert_ne!(workspace.offset.as_slice(), expected.as_slice());
        let elsewhere = state([0.1, 0.2], [0.4, 0.6]);
        workspace.predict(&model, 0.2, h, &elsewhere);
        assert_ne!(workspace.offset.as_slice(), expected.as_slice());
        // A fresh workspace has no history.
        let fresh = Method::<nalgebra::U2>::workspace(&method, &model, h).unwrap();
        let Path::Implicit(fresh) = fresh.path else {
            panic!("a variable mass takes the implicit path");
        };
        assert!(fresh.history.h.is_nan() && !fresh.history.has_before);
    }
}
