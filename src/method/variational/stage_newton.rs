//! Sparse Newton on the stage equations (8a)–(8b) of a Galerkin variational integrator, for a
//! Lagrangian that is a sum of local terms ([`crate::model::TermSum`]): the Jacobian is
//! assembled term by term into a sparsity pattern fixed once per run and solved through the
//! linear-solver seam ([`crate::linalg::sparse`]), so a step costs O(n) memory and work for a
//! chain or lattice of any size.
//!
//! # The stage equations
//! The unknowns are the node offsets Z_j = qʲ − q_k, j = 1, …, s, stored node-major
//! (Z_j occupies entries (j − 1)n … jn − 1). With b_μν = l_ν(τ_μ), d_μν = (2/h) l̇_ν(τ_μ) and
//! W_μ = (h/2) w_μ, the residual of node ν = 0, …, s − 1 is
//!
//! r_ν = δ_ν0 p_k + Σ_μ W_μ (b_μν ∂L/∂q + d_μν ∂L/∂q̇)(t_μ, q_μ, q̇_μ),
//!
//! q_μ = q_k + Σ_j b_μj Z_j, q̇_μ = Σ_j d_μj Z_j, and its Jacobian block (ν, j) is
//!
//! ∂r_ν/∂Z_j = Σ_μ W_μ [b_μν (L_qq b_μj + L_qq̇ d_μj) + d_μν (L_q̇q b_μj + L_q̇q̇ d_μj)].
//!
//! The same equations with s = 1, the two-point linear basis and a segment quadrature rule
//! are the discrete Euler–Lagrange equations p_k = −D1 L_d(q_k, q_{k+1}) of the classic
//! variational integrators ([`crate::method::variational::discrete_lagrangian`]): symplectic
//! Euler, midpoint and trapezoid run on this solver too.
//!
//! Every block has the pattern P of L's Hessian; the pattern, the slots and the simplified
//! Newton iteration are [`BlockNewton`]'s. Assembly is O(m s² K² · terms).
//!
//! p_{k+1} − p_k = Σ_μ W_μ ∂L/∂q(t_μ, q_μ, q̇_μ) is the discrete momentum balance.

use crate::dimension::Dyn;
use crate::error::{Error, StepFailure};
use crate::linalg::sparse::LinearSolverKind;
use crate::method::block_newton::BlockNewton;
use crate::method::variational::tables::Tables;
use crate::model::term_pattern::{MAX_WIDTH, PATTERN_MISMATCH, TermPattern};
use crate::model::{TermDerivatives, TermSum};
use crate::nonlinear::{Jacobian, Solved};
use nalgebra::DVector;

/// A run's [`StageNewton`], made at its first use. A clone starts without one (it holds a
/// factorisation of its own run) and makes its own.
#[derive(Debug, Default)]
pub(crate) struct LazyStageNewton(pub(crate) Option<Box<StageNewton>>);

impl LazyStageNewton {
    /// One step by sparse Newton: the stage equations at (q_k, p_k) = (`q`, `p`) solved for the
    /// offsets `z` (on entry the starting values), then q_{k+1} − q_k = Z_s into `dq` and the
    /// discrete momentum balance into `dp`. The solver is made at the first step, with
    /// `solver` = (linear solver, iteration cap). Returns the solve's work and the symbolic
    /// analyses this step made (1 at the first step, else 0).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        tables: &Tables,
        (t, q, p): (f64, &[f64], &[f64]),
        z: &mut DVector<f64>,
        (dq, dp): (&mut [f64], &mut [f64]),
        jacobian: Jacobian,
        (kind, max_iterations): (LinearSolverKind, usize),
    ) -> Result<(Solved, usize), StepFailure> {
        let (n, s, m) = (q.len(), tables.degree, tables.weights.len());
        let analyses = usize::from(self.0.is_none());
        let stage = match &mut self.0 {
            Some(stage) => stage,
            empty => {
                let made = StageNewton::new(terms, n, (s, m), kind, max_iterations)
                    .map_err(|_| PATTERN_MISMATCH)?;
                empty.insert(Box::new(made))
            }
        };
        let solved = stage.solve(terms, tables, t, (q, p), z, jacobian)?;
        dq.copy_from_slice(&z.as_slice()[(s - 1) * n..s * n]);
        stage.momentum_increment(terms, tables, t, q, z, dp);
        Ok((solved, analyses))
    }

    /// Forget the factorisation, if there is one (the step size changed).
    pub(crate) fn invalidate(&mut self) {
        if let Some(stage) = self.0.as_mut() {
            stage.invalidate();
        }
    }
}

impl Clone for LazyStageNewton {
    fn clone(&self) -> Self {
        LazyStageNewton(None)
    }
}

/// The quadrature points of a step, q_μ and q̇_μ, and each term's derivatives there.
#[derive(Debug)]
struct Points {
    positions: Vec<DVector<f64>>,
    velocities: Vec<DVector<f64>>,
    derivatives: Vec<f64>,
}

impl Points {
    /// q_μ = q_k + Σ_j b_μj Z_j and q̇_μ = Σ_j d_μj Z_j from the `s` offsets `z` of length n.
    fn set(&mut self, tables: &Tables, q0: &[f64], z: &DVector<f64>, s: usize) {
        let n = q0.len();
        for (mu, (q, v)) in self
            .positions
            .iter_mut()
            .zip(&mut self.velocities)
            .enumerate()
        {
            q.as_mut_slice().copy_from_slice(q0);
            v.as_mut_slice().fill(0.0);
            for j in 1..=s {
                let node = z.rows((j - 1) * n, n);
                q.axpy(tables.values[(mu, j)], &node, 1.0);
                v.axpy(tables.derivatives[(mu, j)], &node, 1.0);
            }
        }
    }

    /// Each term's derivatives at each point (with `second` the Hessian blocks too), handed
    /// to `visit(μ, terms, e, derivatives)` in the layout of [`TermDerivatives`].
    #[allow(clippy::too_many_arguments)]
    fn visit_terms(
        &mut self,
        model: &dyn TermSum<Dyn>,
        terms: &TermPattern,
        tables: &Tables,
        t: f64,
        second: bool,
        mut visit: impl FnMut(usize, usize, &[f64]),
    ) {
        let k = terms.width();
        let (mut ql, mut vl) = ([0.0; MAX_WIDTH], [0.0; MAX_WIDTH]);
        for (mu, (q, v)) in self.positions.iter().zip(&self.velocities).enumerate() {
            let time = tables.time(t, mu);
            for e in 0..terms.term_count() {
                terms.gather(e, q.as_slice(), v.as_slice(), &mut ql, &mut vl);
                model.term_derivatives(e, time, &ql[..k], &vl[..k], second, &mut self.derivatives);
                visit(mu, e, &self.derivatives);
            }
        }
    }
}

/// The stage equations' solver and buffers.
#[derive(Debug)]
pub(crate) struct StageNewton {
    points: Points,
    newton: BlockNewton,
}

impl StageNewton {
    /// The solver of `terms` on `n` coordinates, for `s` unknown nodes and `m` quadrature
    /// points, its pattern analysed by a solver of `kind`.
    ///
    /// # Errors
    /// As [`BlockNewton::new`].
    pub(crate) fn new(
        terms: &dyn TermSum<Dyn>,
        n: usize,
        (s, m): (usize, usize),
        kind: LinearSolverKind,
        max_iterations: usize,
    ) -> Result<Self, Error> {
        let newton = BlockNewton::new(terms, n, s, kind, max_iterations)?;
        let width = newton.blocks.terms.width();
        Ok(StageNewton {
            points: Points {
                positions: vec![DVector::zeros(n); m],
                velocities: vec![DVector::zeros(n); m],
                derivatives: vec![0.0; TermDerivatives { width }.len()],
            },
            newton,
        })
    }

    /// Forget the factorisation (the step size changed).
    pub(crate) fn invalidate(&mut self) {
        self.newton.invalidate();
    }

    /// Solve the stage equations at the state (q_k, p_k) = `state` for the offsets `z` (on
    /// entry the starting values), refactoring the Jacobian at every iteration
    /// ([`Jacobian::Exact`]) or as the simplified Newton method ([`Jacobian::Kept`]).
    pub(crate) fn solve(
        &mut self,
        model: &dyn TermSum<Dyn>,
        tables: &Tables,
        t: f64,
        (q0, p0): (&[f64], &[f64]),
        z: &mut DVector<f64>,
        jacobian: Jacobian,
    ) -> Result<Solved, StepFailure> {
        let StageNewton { points, newton } = self;
        let q_size = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        newton.solve(z, q_size, jacobian, |blocks, z, residual, mut values| {
            let (n, s) = (blocks.n, blocks.s);
            points.set(tables, q0, z, s);
            residual.as_mut_slice().fill(0.0);
            residual.as_mut_slice()[..n].copy_from_slice(p0);
            let terms = &blocks.terms;
            let k = terms.width();
            let layout = TermDerivatives { width: k };
            let second = values.is_some();
            let visit = |mu: usize, e: usize, derivatives: &[f64]| {
                let w = tables.weights[mu];
                let indices = terms.indices(e);
                for nu in 0..s {
                    let (b, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
                    for (a, &i) in indices.iter().enumerate() {
                        residual[nu * n + i] +=
                            w * (b * layout.q(derivatives, a) + c * layout.v(derivatives, a));
                    }
                }
                let Some(values) = values.as_deref_mut() else {
                    return;
                };
                for bb in 0..k {
                    for a in 0..k {
                        let pair = blocks.pair(e, a, bb);
                        let (qq, qv) =
                            (layout.qq(derivatives, a, bb), layout.qv(derivatives, a, bb));
                        let (vq, vv) =
                            (layout.qv(derivatives, bb, a), layout.vv(derivatives, a, bb));
                        for j in 1..=s {
                            let (bj, cj) = (tables.values[(mu, j)], tables.derivatives[(mu, j)]);
                            let from_q = w * (qq * bj + qv * cj);
                            let from_v = w * (vq * bj + vv * cj);
                            let slots = blocks.slots(pair, j - 1);
                            for nu in 0..s {
                                values[slots.row(nu)] += from_q * tables.values[(mu, nu)]
                                    + from_v * tables.derivatives[(mu, nu)];
                            }
                        }
                    }
                }
            };
            points.visit_terms(model, terms, tables, t, second, visit);
        })
    }

    /// p_{k+1} − p_k = Σ_μ W_μ ∂L/∂q(t_μ, q_μ, q̇_μ) at the offsets `z`, into `dp`.
    pub(crate) fn momentum_increment(
        &mut self,
        model: &dyn TermSum<Dyn>,
        tables: &Tables,
        t: f64,
        q0: &[f64],
        z: &DVector<f64>,
        dp: &mut [f64],
    ) {
        let terms = &self.newton.blocks.terms;
        self.points.set(tables, q0, z, self.newton.blocks.s);
        dp.fill(0.0);
        let layout = TermDerivatives {
            width: terms.width(),
        };
        let visit = |mu: usize, e: usize, derivatives: &[f64]| {
            let w = tables.weights[mu];
            for (a, &i) in terms.indices(e).iter().enumerate() {
                dp[i] += w * layout.q(derivatives, a);
            }
        };
        self.points
            .visit_terms(model, terms, tables, t, false, visit);
    }
}
