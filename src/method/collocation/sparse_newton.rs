//! Sparse Newton on SC's collocation equations for a Lagrangian that is a sum of local terms
//! ([`crate::model::TermSum`]) of run-time size: O(n) memory and work per iteration, no n × n
//! matrix, no inverse of the mass matrix.
//!
//! # The equations in implicit form
//! With the node offsets Z_i = qⁱ − q_k, i = 1, …, s, the node velocities and accelerations of
//! eq. (21) are y_i = Σ_j Λ*_ij Z_j and a_i = Σ_j (Λ*²)_ij Z_j + λ_0,i q̇_k, and SC's equations
//! a_i = f(t_i, q_i, y_i) (eqs. 24–25, q_i = q_k + Z_i) are taken multiplied by the mass matrix
//! ∂²L/∂q̇² at the node, so that no inverse appears: the Euler–Lagrange equations
//!
//! R_i = L_q̇q̇ a_i + L_q̇q y_i + L_q̇t − L_q = d/dε ∂L/∂q̇(t_i + ε, q_i + ε y_i, y_i + ε a_i)|₀ − ∂L/∂q
//!
//! (the same solution as the dense path, whose mass matrix is invertible), the Euler–Lagrange
//! residual of [`crate::model::euler_lagrange`] at node i. The Jacobian block (i, j) is
//! δ_ij J_q + Λ*_ij J_y + (Λ*²)_ij J_a with that module's blocks J_q, J_y, J_a, term by term
//! ([`TermShare`]); each block has the pattern of L's Hessian, and the iteration is
//! [`BlockNewton`]'s simplified Newton method.

use super::Tables;
use crate::dimension::Dyn;
use crate::error::{Error, StepFailure};
use crate::linalg::sparse::LinearSolverKind;
use crate::method::block_newton::{BlockNewton, Blocks};
use crate::model::euler_lagrange::TermShare;
use crate::model::term_pattern::{MAX_WIDTH, PATTERN_MISMATCH};
use crate::model::{TermDerivatives, TermSum};
use crate::nonlinear::{Jacobian, Solved};
use nalgebra::DVector;

/// The solver of SC's equations for one run on a sum of terms.
#[derive(Debug)]
pub(super) struct SparseCollocation {
    newton: BlockNewton,
    /// q_i, y_i and a_i at the node being assembled.
    position: DVector<f64>,
    velocity: DVector<f64>,
    acceleration: DVector<f64>,
    /// One term's derivatives at the dual point: values, then ε-parts.
    derivatives: Vec<f64>,
}

impl SparseCollocation {
    /// The solver of `terms` on `n` coordinates and `s` collocation nodes.
    ///
    /// # Errors
    /// As [`BlockNewton::new`].
    pub(super) fn new(
        terms: &dyn TermSum<Dyn>,
        n: usize,
        s: usize,
        max_iterations: usize,
    ) -> Result<Self, Error> {
        let newton = BlockNewton::new(terms, n, s, LinearSolverKind::Auto, max_iterations)?;
        let width = newton.blocks.terms.width();
        Ok(SparseCollocation {
            newton,
            position: DVector::zeros(n),
            velocity: DVector::zeros(n),
            acceleration: DVector::zeros(n),
            derivatives: vec![0.0; 2 * TermDerivatives { width }.len()],
        })
    }

    /// Forget the factorisation (the step size changed).
    pub(super) fn invalidate(&mut self) {
        self.newton.invalidate();
    }

    /// Solve the collocation equations at (q_k, q̇_k) = `state` for the offsets `z` (on entry
    /// the starting values).
    pub(super) fn solve(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        tables: &Tables,
        t: f64,
        (q0, v0): (&[f64], &[f64]),
        z: &mut DVector<f64>,
    ) -> Result<Solved, StepFailure> {
        let SparseCollocation {
            newton,
            position,
            velocity,
            acceleration,
            derivatives,
        } = self;
        let q_size = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        newton.solve(
            z,
            q_size,
            Jacobian::Kept,
            |blocks, z, residual, mut values| {
                let Blocks {
                    n,
                    s,
                    terms: pattern,
                    ..
                } = blocks;
                let (n, s) = (*n, *s);
                let k = pattern.width();
                let mut local = [[0.0; MAX_WIDTH]; 3];
                residual.fill(0.0);
                for i in 0..s {
                    // q_i, y_i and a_i (eq. 21).
                    for (c, ((q, y), a)) in position
                        .iter_mut()
                        .zip(velocity.iter_mut())
                        .zip(acceleration.iter_mut())
                        .enumerate()
                    {
                        *q = q0[c] + z[i * n + c];
                        *a = tables.lambda0[i] * v0[c];
                        *y = 0.0;
                        for j in 0..s {
                            let zj = z[j * n + c];
                            *y += tables.lambda[(i, j)] * zj;
                            *a += tables.lambda_squared[(i, j)] * zj;
                        }
                    }
                    let time = tables.time(t, i + 1);
                    for e in 0..pattern.term_count() {
                        let [ql, yl, al] = &mut local;
                        pattern.gather(e, position.as_slice(), velocity.as_slice(), ql, yl);
                        for (a, &c) in pattern.indices(e).iter().enumerate() {
                            al[a] = acceleration[c];
                        }
                        let node = (&ql[..k], &yl[..k], &al[..k]);
                        let share = TermShare::along(terms, e, time, node, derivatives);
                        for (a, &r) in pattern.indices(e).iter().enumerate() {
                            residual[i * n + r] += share.residual(a);
                        }
                        let Some(values) = values.as_deref_mut() else {
                            continue;
                        };
                        for b in 0..k {
                            for a in 0..k {
                                // Row a (the equation of coordinate a), column b.
                                let [from_q, from_y, from_a] = share.jacobian(a, b);
                                let pair = blocks.pair(e, a, b);
                                for j in 0..s {
                                    let mut entry = tables.lambda[(i, j)] * from_y
                                        + tables.lambda_squared[(i, j)] * from_a;
                                    if i == j {
                                        entry += from_q;
                                    }
                                    values[blocks.slots(pair, j).row(i)] += entry;
                                }
                            }
                        }
                    }
                }
            },
        )
    }
}

/// A run's [`SparseCollocation`], made at its first use. A clone starts without one (it holds
/// a factorisation of its own run) and makes its own.
#[derive(Debug, Default)]
pub(super) struct LazySparseCollocation(Option<Box<SparseCollocation>>);

impl Clone for LazySparseCollocation {
    fn clone(&self) -> Self {
        LazySparseCollocation(None)
    }
}

impl LazySparseCollocation {
    /// [`SparseCollocation::solve`], the solver made at the first call (`n` coordinates,
    /// `s` nodes, `max_iterations` per step). Returns the solve's work and the symbolic
    /// analyses this call made (1 at the first, else 0).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        tables: &Tables,
        t: f64,
        state: (&[f64], &[f64]),
        z: &mut DVector<f64>,
        max_iterations: usize,
    ) -> Result<(Solved, usize), StepFailure> {
        let analyses = usize::from(self.0.is_none());
        let solver = match &mut self.0 {
            Some(solver) => solver,
            empty => {
                let made =
                    SparseCollocation::new(terms, state.0.len(), tables.degree, max_iterations)
                        .map_err(|_| PATTERN_MISMATCH)?;
                empty.insert(Box::new(made))
            }
        };
        Ok((solver.solve(terms, tables, t, state, z)?, analyses))
    }

    /// Forget the factorisation, if there is one (the step size changed).
    pub(super) fn invalidate(&mut self) {
        if let Some(solver) = self.0.as_mut() {
            solver.invalidate();
        }
    }
}
