//! Implicit Euler on a sum of local terms ([`crate::model::TermSum`]) of run-time size: the
//! new velocity w solves the Euler–Lagrange equations at the step's end,
//!
//! G(w) = h R(t + h, q_k + h w, w, (w − q̇_k)/h) = 0,
//!
//! with R the residual of [`crate::model::euler_lagrange`] (the dense path's
//! w − q̇_k − h f(t + h, q_k + h w, w) = 0 multiplied by h M, the same solution). Its Jacobian
//! h² J_q + h J_y + J_a has the pattern of L's Hessian and is assembled term by term;
//! [`BlockNewton`] with one node vector solves it by the simplified Newton method, the
//! factorisation kept across steps of one size: O(n) per iteration, no n × n matrix.

use crate::dimension::Dyn;
use crate::error::StepFailure;
use crate::linalg::sparse::LinearSolverKind;
use crate::method::block_newton::{BlockNewton, Blocks};
use crate::model::euler_lagrange::TermShare;
use crate::model::term_pattern::{MAX_WIDTH, PATTERN_MISMATCH};
use crate::model::{TermDerivatives, TermSum};
use crate::nonlinear::{Jacobian, Solved};
use nalgebra::DVector;

/// The solver of implicit Euler's equation for one run on a sum of terms.
#[derive(Debug)]
struct SparseImplicitEuler {
    newton: BlockNewton,
    /// The step size the kept factorisation is for.
    h: f64,
    /// The unknown w.
    w: DVector<f64>,
    /// One term's derivatives along (1, y, a): values, then ε-parts.
    derivatives: Vec<f64>,
}

impl SparseImplicitEuler {
    /// Solve G(w) = 0 at (t, q_k, q̇_k) for the step h, w on entry the starting value.
    fn solve(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        (t, h): (f64, f64),
        (q0, v0): (&[f64], &[f64]),
        w: &mut [f64],
    ) -> Result<Solved, StepFailure> {
        if self.h != h {
            self.newton.invalidate();
            self.h = h;
        }
        let SparseImplicitEuler {
            newton,
            w: unknown,
            derivatives,
            ..
        } = self;
        unknown.copy_from_slice(w);
        let q_size = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let time = t + h;
        let solved = newton.solve(
            unknown,
            q_size,
            Jacobian::Kept,
            |blocks, w, residual, mut values| {
                let Blocks { terms: pattern, .. } = blocks;
                let k = pattern.width();
                let mut local = [[0.0; MAX_WIDTH]; 3];
                residual.fill(0.0);
                for e in 0..pattern.term_count() {
                    let [ql, yl, al] = &mut local;
                    for (a, &c) in pattern.indices(e).iter().enumerate() {
                        ql[a] = q0[c] + h * w[c];
                        yl[a] = w[c];
                        al[a] = (w[c] - v0[c]) / h;
                    }
                    let point = (&ql[..k], &yl[..k], &al[..k]);
                    let share = TermShare::along(terms, e, time, point, derivatives);
                    for (a, &r) in pattern.indices(e).iter().enumerate() {
                        residual[r] += h * share.residual(a);
                    }
                    let Some(values) = values.as_deref_mut() else {
                        continue;
                    };
                    for b in 0..k {
                        for a in 0..k {
                            let [from_q, from_y, from_a] = share.jacobian(a, b);
                            let slot = blocks.slots(blocks.pair(e, a, b), 0).row(0);
                            values[slot] += h * (h * from_q + from_y) + from_a;
                        }
                    }
                }
            },
        )?;
        w.copy_from_slice(unknown.as_slice());
        Ok(solved)
    }
}

/// A run's [`SparseImplicitEuler`], made at its first use; a clone starts without one (it
/// holds a factorisation of its own run) and makes its own.
#[derive(Debug, Default)]
pub(super) struct LazySparseImplicitEuler(Option<Box<SparseImplicitEuler>>);

impl Clone for LazySparseImplicitEuler {
    fn clone(&self) -> Self {
        LazySparseImplicitEuler(None)
    }
}

impl LazySparseImplicitEuler {
    /// Solve implicit Euler's equation for the new velocity `w` (the starting value on entry),
    /// the solver made at the first call with `max_iterations` per step. Returns the solve's
    /// work and the symbolic analyses this call made (1 at the first, else 0).
    ///
    /// # Errors
    /// [`StepFailure::Unsupported`] when the terms' pattern does not fit, and the failures of
    /// [`BlockNewton::solve`].
    pub(super) fn solve(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        max_iterations: usize,
        step: (f64, f64),
        state: (&[f64], &[f64]),
        w: &mut [f64],
    ) -> Result<(Solved, usize), StepFailure> {
        let analyses = usize::from(self.0.is_none());
        let solver = match &mut self.0 {
            Some(solver) => solver,
            empty => {
                let n = w.len();
                let newton = BlockNewton::new(terms, n, 1, LinearSolverKind::Auto, max_iterations)
                    .map_err(|_| PATTERN_MISMATCH)?;
                let width = newton.blocks.terms.width();
                empty.insert(Box::new(SparseImplicitEuler {
                    newton,
                    h: f64::NAN,
                    w: DVector::zeros(n),
                    derivatives: vec![0.0; 2 * TermDerivatives { width }.len()],
                }))
            }
        };
        Ok((solver.solve(terms, step, state, w)?, analyses))
    }
}
