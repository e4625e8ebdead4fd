//! The run behind the derivatives: the model itself, or, when a parameter differentiated
//! enters L, the lifted Lagrangian L̂ of the chosen parameters ([`WithParameters`]); its
//! start X_0 with C = ∂X_0/∂(q₀, q̇₀ or p₀, θ), the end maps G = ∂(q, q̇)/∂X, and a walker
//! that takes the grid's steps one at a time, plain, with their tangent maps or with their
//! adjoints.

use super::{SensitivityRun, Start};
use crate::dimension::{Dimension, Dyn};
use crate::error::{Error, StepFailure};
use crate::linalg::{dynamic_view, invert_small};
use crate::method::space::{Initial, PhasePoint, State, StepState};
use crate::method::step::Step;
use crate::method::{Coordinates, Euclidean, Method, StepAdjoint, StepReport};
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::model::parametric::{Parametric, WithParameters, parameter_indices};
use crate::stepping::grid::{grid_step, grid_steps};
use crate::stepping::run::{Cursor, Integrator, Statistics};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector, U1};
use num_dual::Dual;

/// The parameters of `run` among the model's, and whether any of them enters L or the force
/// (then the run is lifted to [`WithParameters`]; else it runs on the model itself).
pub(super) fn chosen_parameters<L: Parametric<N>, N: Dimension>(
    model: &L,
    run: &SensitivityRun<N>,
) -> Result<(Vec<usize>, bool), Error>
where
    DefaultAllocator: Allocator<N>,
{
    let names: Vec<&str> = run.parameters.iter().map(String::as_str).collect();
    let chosen = parameter_indices(model, &names)?;
    let lift = chosen.iter().any(|&index| model.enters_lagrangian(index));
    Ok((chosen, lift))
}

/// The integrator of L̂ for the `chosen` parameters of `integrator`'s model.
pub(super) fn lift<'a, L: Parametric<N>, M: Method<N> + Method<Dyn> + Clone, N: Dimension>(
    integrator: &'a Integrator<L, M, Euclidean<N>>,
    chosen: &[usize],
) -> Integrator<WithParameters<'a, L, N>, M, Euclidean<Dyn>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let model = integrator.model();
    let hat = WithParameters::new(model, model.dimension(), chosen.to_vec());
    Integrator::new(hat, integrator.method().clone())
}

/// A vector of dimension `D` with the entries of `values`.
fn vector<D: Dimension>(values: &DVector<f64>) -> OVector<f64, D>
where
    DefaultAllocator: Allocator<D>,
{
    OVector::from_column_slice_generic(D::from_usize(values.len()), U1, values.as_slice())
}

/// The run of a [`SensitivityRun`] (see the [module](self) documentation): on the model
/// itself (R = L, D = N, m = n) or on L̂ (R = [`WithParameters`], D = [`Dyn`], m = n + P,
/// z = (q, θ)).
pub(super) struct Lifted<'i, R, M, D: Dimension>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// The integrator of the run's model with the run's method.
    pub(super) integrator: &'i Integrator<R, M, Euclidean<D>>,
    /// n, the model's coordinates.
    pub(super) n: usize,
    /// m, the run's coordinates: n, or n + P on L̂.
    pub(super) m: usize,
    /// The method's second coordinate (p or q̇).
    coordinates: Coordinates,
    /// (z₀, ż₀).
    pub(super) initial: Initial<D>,
    /// C = ∂X_0/∂(q₀, q̇₀ or p₀, θ): 2m × (2n + P).
    pub(super) start: DMatrix<f64>,
    /// The names of the parameters differentiated.
    pub(super) names: Vec<String>,
    /// (t₀, h, t_end, K).
    pub(super) grid: (f64, f64, f64, usize),
    /// Every how many steps an output is taken.
    every: usize,
}

impl<'i, R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension> Lifted<'i, R, M, D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// The run of `run` for `model`, whose parameters `chosen` are differentiated, by
    /// `integrator`: of `model` itself, or of its L̂ when its dimension is n + P.
    pub(super) fn new<L: Parametric<N>, N: Dimension>(
        integrator: &'i Integrator<R, M, Euclidean<D>>,
        model: &L,
        chosen: &[usize],
        run: &SensitivityRun<N>,
    ) -> Result<Self, Error>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let steps = grid_steps(run.t0, run.t_end, run.h)?;
        if run.every == 0 {
            return Err(Error::invalid(
                "every",
                "0 steps between outputs (at least 1)",
            ));
        }
        let n = model.dimension();
        let p = chosen.len();
        let m = integrator.model().dimension();
        // On L̂ the θ rows follow q's; on the model itself there are none.
        let theta_rows = m - n;
        let values = model.parameter_values();
        let columns = 2 * n + p;
        let t0 = run.t0;
        // z₀ and ż₀ (or p̂₀), and their derivatives with respect to (q₀, q̇₀ or p₀, θ).
        let mut z0 = DVector::zeros(m);
        let mut dz0 = DMatrix::zeros(m, columns);
        let mut dzdot0 = DMatrix::zeros(m, columns);
        for k in 0..theta_rows {
            z0[n + k] = values[chosen[k]];
            dz0[(n + k, 2 * n + k)] = 1.0;
        }
        for i in 0..n {
            dz0[(i, i)] = 1.0;
        }
        let mut zdot0 = DVector::zeros(m);
        let given_momentum = match &run.start {
            Start::Given(Initial::Velocity { q, v }) => {
                z0.rows_mut(0, n).copy_from_slice(q.as_slice());
                zdot0.rows_mut(0, n).copy_from_slice(v.as_slice());
                None
            }
            Start::Given(Initial::Momentum { q, p: momentum }) => {
                z0.rows_mut(0, n).copy_from_slice(q.as_slice());
                let mut p_hat = DVector::zeros(m);
                p_hat.rows_mut(0, n).copy_from_slice(momentum.as_slice());
                Some(p_hat)
            }
            Start::Model => {
                let (q, v) = model.initial_state_with(&values).ok_or_else(|| {
                    Error::invalid(
                        "start",
                        "the model's parameters do not choose its initial state: give one",
                    )
                })?;
                z0.rows_mut(0, n).copy_from_slice(q.as_slice());
                zdot0.rows_mut(0, n).copy_from_slice(v.as_slice());
                // ∂(q₀, q̇₀)/∂θ: one dual sweep per chosen parameter.
                for (k, &index) in chosen.iter().enumerate() {
                    let (dq, dv) = model
                        .initial_state_with(&seeded(&values, index))
                        .expect("the model chose its initial state at these values");
                    for i in 0..n {
                        dz0[(i, 2 * n + k)] = dq[i].eps;
                        dzdot0[(i, 2 * n + k)] = dv[i].eps;
                    }
                }
                None
            }
        };
        let (z0, mut zdot0) = (vector::<D>(&z0), vector::<D>(&zdot0));
        let hat = integrator.model();
        if let Some(p_hat) = &given_momentum {
            let guess = zdot0.clone();
            zdot0 = hat.velocity(t0, &z0, &vector::<D>(p_hat), &guess)?;
        }
        if !(z0.iter().all(|x| x.is_finite()) && zdot0.iter().all(|x| x.is_finite())) {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: t0,
            });
        }
        if theta_rows == 0 {
            check_outside_lagrangian(model, chosen, t0, &z0, &zdot0)?;
        }
        let coordinates = integrator.method().info().coordinates;
        let needs_hessian = given_momentum.is_some() || coordinates == Coordinates::Momentum;
        let second = needs_hessian.then(|| hat.second_derivatives(t0, &z0, &zdot0));
        if let (Some(_), Some(d)) = (&given_momentum, &second) {
            // ż₀ = M̂⁻¹(p̂₀ − …): ∂ż₀ = M̂⁻¹(∂p̂₀ − L̂_{żz} ∂z₀), ∂p̂₀ the columns of p₀.
            let inverse = invert(
                &dynamic_view(&d.vv).into_owned(),
                "mass matrix at the initial state",
            )?;
            let mut dp = DMatrix::zeros(m, columns);
            for i in 0..n {
                dp[(i, n + i)] = 1.0;
            }
            dzdot0 = &inverse * (dp - dynamic_view(&d.qv).transpose() * &dz0);
        } else {
            // ż₀ = (q̇₀, 0): the columns of q̇₀.
            for i in 0..n {
                dzdot0[(i, n + i)] = 1.0;
            }
        }
        let dy0 = match (coordinates, &second) {
            (Coordinates::Momentum, Some(d)) => {
                dynamic_view(&d.qv).transpose() * &dz0 + dynamic_view(&d.vv) * &dzdot0
            }
            _ => dzdot0,
        };
        let mut start = DMatrix::zeros(2 * m, columns);
        start.rows_mut(0, m).copy_from(&dz0);
        start.rows_mut(m, m).copy_from(&dy0);
        Ok(Lifted {
            integrator,
            n,
            m,
            coordinates,
            initial: Initial::Velocity { q: z0, v: zdot0 },
            start,
            names: run.parameters.clone(),
            grid: (run.t0, run.h, run.t_end, steps),
            every: run.every,
        })
    }

    /// Whether the state after `step` steps is an output.
    pub(super) fn is_output(&self, step: usize) -> bool {
        step.is_multiple_of(self.every) || step == self.grid.3
    }

    /// G = ∂(q, q̇)/∂(z, y) at a point of the run: 2n × 2m.
    pub(super) fn end(&self, point: &PhasePoint<D>) -> Result<DMatrix<f64>, Error> {
        let (n, m) = (self.n, self.m);
        let mut g = DMatrix::zeros(2 * n, 2 * m);
        for i in 0..n {
            g[(i, i)] = 1.0;
        }
        match self.coordinates {
            Coordinates::Velocity => {
                for i in 0..n {
                    g[(n + i, m + i)] = 1.0;
                }
            }
            Coordinates::Momentum => {
                // ż = M̂⁻¹(p̂ − …): ∂ż = M̂⁻¹ ∂p̂ − M̂⁻¹ L̂_{żz} ∂z.
                let model = self.integrator.model();
                let d = model.second_derivatives(point.t, &point.q, &point.v);
                let inverse = invert(&dynamic_view(&d.vv).into_owned(), "mass matrix")?;
                let by_z = -(&inverse * dynamic_view(&d.qv).transpose());
                g.view_mut((n, 0), (n, m)).copy_from(&by_z.rows(0, n));
                g.view_mut((n, m), (n, m)).copy_from(&inverse.rows(0, n));
            }
        }
        Ok(g)
    }
}

/// θ at `values` as dual numbers with the derivative seeded at `index`.
fn seeded(values: &[f64], index: usize) -> Vec<Dual<f64>> {
    values
        .iter()
        .enumerate()
        .map(|(i, &x)| Dual::new(x, if i == index { 1.0 } else { 0.0 }))
        .collect()
}

/// Largest |∂L/∂θ| and |∂f/∂θ| at the initial state accepted from a parameter declared not to
/// enter L ([`Parametric::enters_lagrangian`]), relative to the scale of L's terms.
const OUTSIDE_LAGRANGIAN: f64 = 1e-12;

/// The declaration of [`Parametric::enters_lagrangian`] checked at the initial state
/// (q₀, q̇₀): ∂L/∂θ and ∂f/∂θ vanish for every chosen parameter, else a typed error naming it.
fn check_outside_lagrangian<L: Parametric<N>, N: Dimension, D: Dimension>(
    model: &L,
    chosen: &[usize],
    t0: f64,
    q: &OVector<f64, D>,
    v: &OVector<f64, D>,
) -> Result<(), Error>
where
    DefaultAllocator: Allocator<N> + Allocator<D>,
{
    let values = model.parameter_values();
    let names = model.parameter_names();
    let n = model.dimension();
    let lift = |x: &OVector<f64, D>| {
        OVector::<Dual<f64>, N>::from_iterator_generic(
            N::from_usize(n),
            U1,
            x.iter().map(|&x| Dual::from(x)),
        )
    };
    let (q, v, t) = (lift(q), lift(v), Dual::from(t0));
    let scale = model.lagrangian_with(&values, t0, &q.map(|x| x.re), &v.map(|x| x.re));
    for &index in chosen {
        let theta = seeded(&values, index);
        let mut moved = model.lagrangian_with(&theta, t, &q, &v).eps.abs();
        if L::FORCED {
            let force = model.external_force_with(&theta, t, &q, &v);
            moved = force.iter().fold(moved, |worst, f| worst.max(f.eps.abs()));
        }
        // NaN fails too.
        if moved.is_nan() || moved > OUTSIDE_LAGRANGIAN * scale.abs().max(1.0) {
            return Err(Error::invalid(
                "parameters",
                format!(
                    "'{}' is declared not to enter L or the force (Parametric::enters_lagrangian), \
                     but at the initial state they change with it by {moved:.1e}",
                    names[index]
                ),
            ));
        }
    }
    Ok(())
}

/// The inverse of a mass matrix, or a typed error naming `what`.
fn invert(matrix: &DMatrix<f64>, what: &str) -> Result<DMatrix<f64>, Error> {
    invert_small(matrix)
        .filter(|inverse| inverse.iter().all(|x| x.is_finite()))
        .ok_or_else(|| {
            Error::invalid(
                "model",
                format!("the {what} of the run's model is singular"),
            )
        })
}

/// Takes the grid's steps of a run one at a time from a cursor.
pub(super) struct Walker<'l, 'i, R, M: Method<D>, D: Dimension>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    lifted: &'l Lifted<'i, R, M, D>,
    workspace: <M as Method<D>>::Workspace,
    /// The state and its compensation.
    pub(super) cursor: Cursor<Euclidean<D>>,
    increment: State<D>,
    /// The Newton start of the next completion.
    guess: OVector<f64, D>,
    /// The work of every step taken.
    pub(super) statistics: Statistics,
}

impl<'l, 'i, R: Lagrangian<D>, M: Method<D> + Clone, D: Dimension> Walker<'l, 'i, R, M, D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// A walker at the start of `lifted`.
    pub(super) fn new(lifted: &'l Lifted<'i, R, M, D>) -> Result<Self, Error> {
        let integrator = lifted.integrator;
        let (model, method) = (integrator.model(), integrator.method());
        let workspace = Step::<_, Euclidean<D>>::workspace(method, model, lifted.grid.1)?;
        let state = integrator.initial_state(lifted.grid.0, &lifted.initial)?;
        Step::<_, Euclidean<D>>::check_model(method, model, lifted.grid.0, &state)?;
        let guess = match &lifted.initial {
            Initial::Velocity { v, .. } => v.clone(),
            Initial::Momentum { p, .. } => p.clone(),
        };
        Ok(Walker {
            lifted,
            workspace,
            increment: state.zeros_like(),
            cursor: Cursor::new(state),
            guess,
            statistics: Statistics::default(),
        })
    }

    /// Move to `cursor`, forgetting the warm start of the last step.
    pub(super) fn restart_at(&mut self, cursor: Cursor<Euclidean<D>>) {
        self.cursor = cursor;
        Step::<R, Euclidean<D>>::restart(self.lifted.integrator.method(), &mut self.workspace);
    }

    /// Take step `k` of the grid.
    pub(super) fn step(&mut self, k: usize) -> Result<(), Error> {
        let integrator = self.lifted.integrator;
        self.advance(k, |workspace, t, size, state, increment| {
            Step::<_, Euclidean<D>>::step(
                integrator.method(),
                integrator.model(),
                workspace,
                t,
                size,
                state,
                increment,
            )
        })
    }

    /// Take step `k` of the grid by `take(workspace, t, h, state, increment)`, record its
    /// report and add its increment to the state.
    fn advance(
        &mut self,
        k: usize,
        take: impl FnOnce(
            &mut <M as Method<D>>::Workspace,
            f64,
            f64,
            &State<D>,
            &mut State<D>,
        ) -> Result<StepReport, StepFailure>,
    ) -> Result<(), Error> {
        let (t0, h, t_end, steps) = self.lifted.grid;
        let (t, size, _) = grid_step(t0, t_end, h, steps, k);
        let report = take(
            &mut self.workspace,
            t,
            size,
            &self.cursor.state,
            &mut self.increment,
        )
        .map_err(|failure| failure.at(k, t))?;
        self.statistics.record(report);
        self.add(k, t)
    }

    /// Take step `k` of the grid keeping what its adjoint needs in `adjoint`
    /// ([`Method::adjoint_step`]).
    pub(super) fn step_adjoint(
        &mut self,
        k: usize,
        adjoint: &mut StepAdjoint<D>,
    ) -> Result<(), Error> {
        let integrator = self.lifted.integrator;
        self.advance(k, |workspace, t, size, state, increment| {
            Method::adjoint_step(
                integrator.method(),
                integrator.model(),
                workspace,
                t,
                size,
                state,
                increment,
                adjoint,
            )
        })
    }

    /// X ← Φ_k X for step `k`, kept in `adjoint` ([`Method::tangent_apply`]), with `scratch`
    /// of X's shape.
    pub(super) fn apply_tangent(
        &mut self,
        k: usize,
        adjoint: &StepAdjoint<D>,
        columns: &mut DMatrix<f64>,
        scratch: &mut DMatrix<f64>,
    ) -> Result<(), Error> {
        Method::tangent_apply(
            self.lifted.integrator.method(),
            &mut self.workspace,
            adjoint,
            columns,
            scratch,
        )
        .map_err(|failure| self.failed(k, failure))
    }

    /// λ ← Φ_kᵀλ for step `k`, kept in `adjoint` ([`Method::adjoint_apply`]).
    pub(super) fn apply_adjoint(
        &mut self,
        k: usize,
        adjoint: &StepAdjoint<D>,
        lambda: &mut DVector<f64>,
        scratch: &mut DVector<f64>,
    ) -> Result<(), Error> {
        Method::adjoint_apply(
            self.lifted.integrator.method(),
            &mut self.workspace,
            adjoint,
            lambda,
            scratch,
        )
        .map_err(|failure| self.failed(k, failure))
    }

    /// The run's error for a failure of step `k`, with its index and start time.
    fn failed(&self, k: usize, failure: StepFailure) -> Error {
        let (t0, h, t_end, steps) = self.lifted.grid;
        failure.at(k, grid_step(t0, t_end, h, steps, k).0)
    }

    /// Add the last increment to the state (compensated, checked finite).
    fn add(&mut self, k: usize, t: f64) -> Result<(), Error> {
        let cursor = &mut self.cursor;
        cursor
            .state
            .add_checked(&mut cursor.compensation, &self.increment, None)
            .map_err(|failure| failure.at(k, t))?;
        self.statistics.steps += 1;
        Ok(())
    }

    /// The state after `step` steps completed to a point (t, z, ż, p̂).
    pub(super) fn point(&mut self, step: usize) -> Result<PhasePoint<D>, Error> {
        let (t0, h, t_end, steps) = self.lifted.grid;
        let t = if step == 0 {
            t0
        } else {
            grid_step(t0, t_end, h, steps, step - 1).2
        };
        let integrator = self.lifted.integrator;
        let point = Step::<_, Euclidean<D>>::complete(
            integrator.method(),
            integrator.model(),
            Some(&self.workspace),
            t,
            &self.cursor.state,
            &self.guess,
        )?;
        self.guess.copy_from(&point.v);
        Ok(point)
    }
}
