//! The run behind the derivatives: the lifted Lagrangian L̂ of the chosen parameters
//! ([`WithParameters`]), its start X_0 with C = ∂X_0/∂(q₀, q̇₀ or p₀, θ), the end maps
//! G = ∂(q, q̇)/∂X, and a walker that takes the grid's steps one at a time, plain or with
//! their tangent maps.

use super::{SensitivityRun, Start};
use crate::dimension::{Dimension, Dyn};
use crate::error::Error;
use crate::linalg::invert_small;
use crate::method::space::{Initial, PhasePoint, State, StepState, TangentMap};
use crate::method::step::Step;
use crate::method::{Coordinates, Euclidean, Method};
use crate::model::derived::LagrangianExt;
use crate::model::parametric::{Parametric, WithParameters, parameter_indices};
use crate::stepping::grid::{grid_step, grid_steps};
use crate::stepping::run::{Cursor, Integrator, Statistics};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator};
use num_dual::Dual;

/// The lifted run of a [`SensitivityRun`] (see the [module](self) documentation).
pub(super) struct Lifted<'a, L, M, N> {
    /// The integrator of L̂ with the run's method.
    pub(super) integrator: Integrator<WithParameters<'a, L, N>, M, Euclidean<Dyn>>,
    /// n, the model's coordinates.
    pub(super) n: usize,
    /// m = n + P, the lifted coordinates.
    pub(super) m: usize,
    /// The method's second coordinate (p or q̇).
    coordinates: Coordinates,
    /// (z₀, ż₀).
    pub(super) initial: Initial<Dyn>,
    /// C = ∂X_0/∂(q₀, q̇₀ or p₀, θ): 2m × (2n + P).
    pub(super) start: DMatrix<f64>,
    /// The names of the parameters differentiated.
    pub(super) names: Vec<String>,
    /// (t₀, h, t_end, K).
    pub(super) grid: (f64, f64, f64, usize),
    /// Every how many steps an output is taken.
    every: usize,
}

impl<'a, L: Parametric<N>, M: Method<N> + Method<Dyn> + Clone, N: Dimension> Lifted<'a, L, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The lifted run of `run` for `model` by `method`.
    pub(super) fn new(model: &'a L, method: &M, run: &SensitivityRun<N>) -> Result<Self, Error> {
        let steps = grid_steps(run.t0, run.t_end, run.h)?;
        if run.every == 0 {
            return Err(Error::invalid(
                "every",
                "0 steps between outputs (at least 1)",
            ));
        }
        let names: Vec<&str> = run.parameters.iter().map(String::as_str).collect();
        let chosen = parameter_indices(model, &names)?;
        let n = model.dimension();
        let hat = WithParameters::new(model, n, chosen.clone());
        let p = hat.parameter_count();
        let m = n + p;
        let theta = hat.chosen_values();
        let columns = 2 * n + p;
        let t0 = run.t0;
        // z₀ and ż₀ (or p̂₀), and their derivatives with respect to (q₀, q̇₀ or p₀, θ).
        let mut z0 = DVector::zeros(m);
        let mut dz0 = DMatrix::zeros(m, columns);
        let mut dzdot0 = DMatrix::zeros(m, columns);
        z0.rows_mut(n, p).copy_from_slice(&theta);
        for k in 0..p {
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
                let (q, v) = model
                    .initial_state_with(&model.parameter_values())
                    .ok_or_else(|| {
                        Error::invalid(
                            "start",
                            "the model's parameters do not choose its initial state: give one",
                        )
                    })?;
                z0.rows_mut(0, n).copy_from_slice(q.as_slice());
                zdot0.rows_mut(0, n).copy_from_slice(v.as_slice());
                // ∂(q₀, q̇₀)/∂θ: one dual sweep per chosen parameter.
                let values = model.parameter_values();
                for (k, &index) in chosen.iter().enumerate() {
                    let theta: Vec<Dual<f64>> = values
                        .iter()
                        .enumerate()
                        .map(|(i, &x)| Dual::new(x, if i == index { 1.0 } else { 0.0 }))
                        .collect();
                    let (dq, dv) = model
                        .initial_state_with(&theta)
                        .expect("the model chose its initial state at these values");
                    for i in 0..n {
                        dz0[(i, 2 * n + k)] = dq[i].eps;
                        dzdot0[(i, 2 * n + k)] = dv[i].eps;
                    }
                }
                None
            }
        };
        let guess = zdot0.clone();
        if let Some(p_hat) = &given_momentum {
            zdot0 = LagrangianExt::<Dyn>::velocity(&hat, t0, &z0, p_hat, &guess)?;
        }
        if !(z0.iter().all(|x| x.is_finite()) && zdot0.iter().all(|x| x.is_finite())) {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: t0,
            });
        }
        let coordinates = Method::<Dyn>::info(method).coordinates;
        let needs_hessian = given_momentum.is_some() || coordinates == Coordinates::Momentum;
        let second =
            needs_hessian.then(|| LagrangianExt::<Dyn>::second_derivatives(&hat, t0, &z0, &zdot0));
        if let (Some(_), Some(d)) = (&given_momentum, &second) {
            // ż₀ = M̂⁻¹(p̂₀ − …): ∂ż₀ = M̂⁻¹(∂p̂₀ − L̂_{żz} ∂z₀), ∂p̂₀ the columns of p₀.
            let inverse = invert(&d.vv, "mass matrix at the initial state")?;
            let mut dp = DMatrix::zeros(m, columns);
            for i in 0..n {
                dp[(i, n + i)] = 1.0;
            }
            dzdot0 = &inverse * (dp - d.qv.transpose() * &dz0);
        } else {
            // ż₀ = (q̇₀, 0): the columns of q̇₀.
            for i in 0..n {
                dzdot0[(i, n + i)] = 1.0;
            }
        }
        let dy0 = match (coordinates, &second) {
            (Coordinates::Momentum, Some(d)) => d.qv.transpose() * &dz0 + &d.vv * &dzdot0,
            _ => dzdot0,
        };
        let mut start = DMatrix::zeros(2 * m, columns);
        start.rows_mut(0, m).copy_from(&dz0);
        start.rows_mut(m, m).copy_from(&dy0);
        Ok(Lifted {
            integrator: Integrator::new(hat, method.clone()),
            n,
            m,
            coordinates,
            initial: Initial::<Dyn>::Velocity { q: z0, v: zdot0 },
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

    /// G = ∂(q, q̇)/∂(z, y) at a point of L̂: 2n × 2m.
    pub(super) fn end(&self, point: &PhasePoint<Dyn>) -> Result<DMatrix<f64>, Error> {
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
                let d =
                    LagrangianExt::<Dyn>::second_derivatives(model, point.t, &point.q, &point.v);
                let inverse = invert(&d.vv, "mass matrix")?;
                let by_z = -(&inverse * d.qv.transpose());
                g.view_mut((n, 0), (n, m)).copy_from(&by_z.rows(0, n));
                g.view_mut((n, m), (n, m)).copy_from(&inverse.rows(0, n));
            }
        }
        Ok(g)
    }
}

/// The inverse of a mass matrix, or a typed error naming `what`.
fn invert(matrix: &DMatrix<f64>, what: &str) -> Result<DMatrix<f64>, Error> {
    invert_small(matrix)
        .filter(|inverse| inverse.iter().all(|x| x.is_finite()))
        .ok_or_else(|| Error::invalid("model", format!("the {what} of L̂ is singular")))
}

/// Takes the grid's steps of a lifted run one at a time from a cursor.
pub(super) struct Walker<'l, 'a, L, M: Method<Dyn>, N> {
    lifted: &'l Lifted<'a, L, M, N>,
    workspace: <M as Method<Dyn>>::Workspace,
    /// The state and its compensation.
    pub(super) cursor: Cursor<Euclidean<Dyn>>,
    increment: State<Dyn>,
    /// The Newton start of the next completion.
    guess: DVector<f64>,
    /// The work of every step taken.
    pub(super) statistics: Statistics,
}

impl<'l, 'a, L: Parametric<N>, M: Method<N> + Method<Dyn> + Clone, N: Dimension>
    Walker<'l, 'a, L, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// A walker at the start of `lifted`.
    pub(super) fn new(lifted: &'l Lifted<'a, L, M, N>) -> Result<Self, Error> {
        let integrator = &lifted.integrator;
        let (model, method) = (integrator.model(), integrator.method());
        let workspace = Step::<_, Euclidean<Dyn>>::workspace(method, model, lifted.grid.1)?;
        let state = integrator.initial_state(lifted.grid.0, &lifted.initial)?;
        Step::<_, Euclidean<Dyn>>::check_model(method, model, lifted.grid.0, &state)?;
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
    pub(super) fn restart_at(&mut self, cursor: Cursor<Euclidean<Dyn>>) {
        self.cursor = cursor;
        Step::<WithParameters<'a, L, N>, Euclidean<Dyn>>::restart(
            self.lifted.integrator.method(),
            &mut self.workspace,
        );
    }

    /// Take step `k` of the grid.
    pub(super) fn step(&mut self, k: usize) -> Result<(), Error> {
        let (t0, h, t_end, steps) = self.lifted.grid;
        let (t, size, _) = grid_step(t0, t_end, h, steps, k);
        let integrator = &self.lifted.integrator;
        let report = Step::<_, Euclidean<Dyn>>::step(
            integrator.method(),
            integrator.model(),
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

    /// Take step `k` of the grid by its tangent map, and return the map.
    pub(super) fn step_tangent(&mut self, k: usize) -> Result<TangentMap<Dyn>, Error> {
        let (t0, h, t_end, steps) = self.lifted.grid;
        let (t, size, _) = grid_step(t0, t_end, h, steps, k);
        let integrator = &self.lifted.integrator;
        let (increment, tangent, report) = Step::<_, Euclidean<Dyn>>::tangent_map(
            integrator.method(),
            integrator.model(),
            &mut self.workspace,
            t,
            size,
            &self.cursor.state,
        )
        .map_err(|failure| failure.at(k, t))?;
        self.increment = increment;
        self.statistics.record(report);
        self.add(k, t)?;
        Ok(tangent)
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
    pub(super) fn point(&mut self, step: usize) -> Result<PhasePoint<Dyn>, Error> {
        let (t0, h, t_end, steps) = self.lifted.grid;
        let t = if step == 0 {
            t0
        } else {
            grid_step(t0, t_end, h, steps, step - 1).2
        };
        let integrator = &self.lifted.integrator;
        let point = Step::<_, Euclidean<Dyn>>::complete(
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
