//! Newton's method on s node vectors of a sum of local terms ([`crate::model::TermSum`]): the
//! s·n unknowns Z_1, …, Z_s are stored node-major (Z_j occupies entries (j − 1)n … jn − 1), and
//! every block (i, j) of the Jacobian has the pattern P of L's Hessian (the union of the terms'
//! index sets, [`TermPattern`]), so the (s n)² Jacobian has s² n·(nonzeros of P per row)
//! entries, assembled term by term into a pattern fixed once per run and solved through the
//! linear-solver seam ([`crate::linalg::sparse`]): O(n) memory and work per iteration for a
//! chain or lattice of any size. The residuals that use it: SVI's stage equations (8a)–(8b)
//! ([`crate::method::variational::stage_newton`]) and SC's collocation equations
//! ([`crate::method::collocation::sparse_newton`]).
//!
//! In node-major order the entry ((i, r), (j, c)) sits at slot
//! colptr((j − 1)n + c) + (i − 1)·|P column c| + rank of r in it, which each term's pair finds
//! from its slot in P ([`Blocks::pair`], [`Blocks::slots`]).
//!
//! # Simplified Newton
//! The factored Jacobian is kept across iterations and steps while the iteration contracts
//! (‖Δ_k‖ ≤ ½‖Δ_{k−1}‖), and refactored otherwise or when the step size changes
//! ([`BlockNewton::invalidate`]); only the residual defines the solution, so a stale Jacobian
//! costs iterations, never accuracy.

use crate::dimension::Dyn;
use crate::error::{Error, StepFailure};
use crate::linalg::sparse::{AnySolver, LinearSolverKind, Pattern};
use crate::model::TermSum;
use crate::model::term_pattern::TermPattern;
use crate::nonlinear::{Jacobian, Solved, stalled};
use nalgebra::DVector;

/// The terms' pattern P and the pattern of the s × s blocks built from it.
#[derive(Debug)]
pub(crate) struct Blocks {
    /// n, the number of coordinates.
    pub(crate) n: usize,
    /// s, the number of unknown node vectors.
    pub(crate) s: usize,
    /// P and the terms' index sets and slots.
    pub(crate) terms: TermPattern,
    /// The (s n)² pattern.
    pattern: Pattern,
}

impl Blocks {
    /// Where term `e`'s pair (local row `a`, local column `b`) goes in every block: its
    /// column c in ℝⁿ, the count of P's entries in that column, and the rank of its row
    /// among them.
    #[inline]
    pub(crate) fn pair(&self, e: usize, a: usize, b: usize) -> Pair {
        let column = self.terms.indices(e)[b];
        let small = &self.terms.pattern;
        let start = small.column_start(column);
        Pair {
            column,
            count: small.column_start(column + 1) - start,
            rank: self.terms.slot(e, a, b) - start,
        }
    }

    /// The slots of `pair` in the blocks of column block `column_block` (0-based): the
    /// entry of row block i is at `first + i·step`.
    #[inline]
    pub(crate) fn slots(&self, pair: Pair, column_block: usize) -> Slots {
        Slots {
            first: self
                .pattern
                .column_start(column_block * self.n + pair.column)
                + pair.rank,
            step: pair.count,
        }
    }
}

/// A term's pair of local coordinates located in P ([`Blocks::pair`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pair {
    column: usize,
    count: usize,
    rank: usize,
}

/// The slots of one pair down one column block ([`Blocks::slots`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Slots {
    first: usize,
    step: usize,
}

impl Slots {
    /// The slot in row block `row_block` (0-based).
    #[inline]
    pub(crate) fn row(self, row_block: usize) -> usize {
        self.first + row_block * self.step
    }
}

/// The pattern, solver and buffers of Newton's method on s node vectors of a sum of terms.
#[derive(Debug)]
pub(crate) struct BlockNewton {
    /// The pattern of the Jacobian and the terms'.
    pub(crate) blocks: Blocks,
    /// The Jacobian's values in the pattern's slot order.
    values: Vec<f64>,
    solver: AnySolver,
    /// Whether `solver` holds a factorisation for the current step size.
    factored: bool,
    /// Residual, then Newton correction.
    residual: DVector<f64>,
    max_iterations: usize,
}

impl BlockNewton {
    /// The solver of `terms` on `n` coordinates and `s` unknown nodes, its pattern analysed by
    /// a solver of `kind`.
    ///
    /// # Errors
    /// As [`TermPattern::new`], or when the symbolic analysis fails.
    pub(crate) fn new(
        terms: &dyn TermSum<Dyn>,
        n: usize,
        s: usize,
        kind: LinearSolverKind,
        max_iterations: usize,
    ) -> Result<Self, Error> {
        let terms = TermPattern::new(terms, n)?;
        let small = &terms.pattern;
        let mut entries = Vec::with_capacity(s * s * small.len());
        for j in 0..s {
            for col in 0..n {
                for i in 0..s {
                    for row in small.column(col) {
                        entries.push((i * n + row, j * n + col));
                    }
                }
            }
        }
        let pattern = Pattern::new(s * n, &entries)?;
        let solver = AnySolver::analysed(kind, &pattern)?;
        Ok(BlockNewton {
            values: vec![0.0; pattern.len()],
            blocks: Blocks {
                n,
                s,
                terms,
                pattern,
            },
            solver,
            factored: false,
            residual: DVector::zeros(s * n),
            max_iterations,
        })
    }

    /// Forget the factorisation (the step size changed).
    pub(crate) fn invalidate(&mut self) {
        self.factored = false;
    }

    /// Solve r(z) = 0 for the node vectors `z` (on entry the starting values), refactoring
    /// the Jacobian at every iteration ([`Jacobian::Exact`]) or as the simplified Newton method
    /// ([`Jacobian::Kept`]). `assemble(blocks, z, residual, values)` writes r(z) into
    /// `residual` and, when `values` is given, the Jacobian's values (zeroed on entry) in the
    /// slots of `blocks`. `q_size` (max |q_k|) scales the convergence test.
    pub(crate) fn solve(
        &mut self,
        z: &mut DVector<f64>,
        q_size: f64,
        jacobian: Jacobian,
        mut assemble: impl FnMut(&Blocks, &DVector<f64>, &mut DVector<f64>, Option<&mut [f64]>),
    ) -> Result<Solved, StepFailure> {
        let mut report = Solved {
            iterations: 0,
            factorizations: 0,
        };
        let mut previous = f64::INFINITY;
        loop {
            let refactor = !self.factored || jacobian == Jacobian::Exact;
            let values = if refactor {
                self.values.fill(0.0);
                Some(self.values.as_mut_slice())
            } else {
                None
            };
            assemble(&self.blocks, z, &mut self.residual, values);
            let solver = self.solver.get();
            if refactor {
                solver
                    .factor(&self.blocks.pattern, &self.values)
                    .map_err(|_| StepFailure::SingularMatrix)?;
                self.factored = true;
                report.factorizations += 1;
            }
            if solver.solve_in_place(&mut self.residual).is_err() {
                self.factored = false;
                return Err(StepFailure::SingularMatrix);
            }
            *z -= &self.residual;
            report.iterations += 1;
            let size = self.residual.amax();
            // The positions the offsets build, as they are now (from rest they start at 0).
            let scale = q_size + z.amax();
            if !size.is_finite() {
                self.factored = false;
                return Err(StepFailure::NonFinite);
            }
            if size <= 2.0 * f64::EPSILON * scale || stalled(size, previous, 1e-13, scale) {
                return Ok(report);
            }
            if report.iterations >= self.max_iterations {
                self.factored = false;
                return Err(StepFailure::NonConvergence {
                    iterations: report.iterations,
                    residual: size,
                });
            }
            // A stale Jacobian that contracts slowly is refreshed for the next iteration.
            if report.iterations > 1 && size > 0.5 * previous {
                self.factored = false;
            }
            previous = size;
        }
    }
}
