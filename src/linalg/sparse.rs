//! The linear-solver seam of the large-system Newton iterations: a sparsity pattern fixed
//! once per run, and a solver that analyses it once (symbolic factorisation) and factors new
//! values as often as Newton needs (numeric factorisation), with two implementations —
//! [`DenseSolver`] (svi's [`DenseLu`], for moderate sizes and as a reference) and
//! [`SparseLu`] (faer's sparse LU with its fill-reducing column ordering, for 10⁵ unknowns
//! and more). Both reuse every buffer: after [`LinearSolver::analyse`] neither allocates
//! per factorisation nor per solve except inside faer's numeric factorisation, whose storage
//! is reused when the pattern's fill is unchanged.

use crate::error::Error;
use crate::linalg::{DenseLu, Singular};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{Pair, SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use nalgebra::DVector;

/// The nonzero pattern of a square matrix in compressed-column form, and where each entry's
/// value lives ([`Pattern::slot`]).
#[derive(Debug, Clone)]
pub struct Pattern {
    symbolic: SymbolicSparseColMat<usize>,
}

impl Pattern {
    /// The pattern of an n × n matrix with nonzeros at `entries` (row, column); repeated
    /// entries are one.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `pattern` for an index out of range (or when memory runs
    /// out).
    pub fn new(n: usize, entries: &[(usize, usize)]) -> Result<Self, Error> {
        let pairs: Vec<Pair<usize, usize>> = entries
            .iter()
            .map(|&(row, col)| Pair { row, col })
            .collect();
        if let Some(bad) = entries.iter().find(|(r, c)| *r >= n || *c >= n) {
            return Err(Error::invalid(
                "pattern",
                format!("entry {bad:?} lies outside an {n} × {n} matrix"),
            ));
        }
        let (symbolic, _) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| Error::invalid("pattern", format!("{e:?}")))?;
        Ok(Pattern { symbolic })
    }

    /// The size n.
    pub fn size(&self) -> usize {
        self.symbolic.nrows()
    }

    /// The number of stored entries.
    pub fn len(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// Whether the pattern stores no entry.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The position of entry (row, column) in the value array; `None` when it is not in the
    /// pattern.
    pub fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.symbolic.col_ptr()[col];
        let end = self.symbolic.col_ptr()[col + 1];
        self.symbolic.row_idx()[start..end]
            .binary_search(&row)
            .ok()
            .map(|offset| start + offset)
    }

    /// The slot of the first entry of column `col` (`col` = n: the number of entries).
    pub fn column_start(&self, col: usize) -> usize {
        self.symbolic.col_ptr()[col]
    }

    /// The rows of the entries of column `col`, ascending.
    pub fn column(&self, col: usize) -> impl Iterator<Item = usize> + '_ {
        self.symbolic.row_idx()[self.column_start(col)..self.column_start(col + 1)]
            .iter()
            .copied()
    }

    /// `out` = A `x` for the matrix A of this pattern whose values are `values`, in slot
    /// order.
    pub(crate) fn mul_into(&self, values: &[f64], x: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (row, col, slot) in self.entries() {
            out[row] += values[slot] * x[col];
        }
    }

    /// The entries column by column, as (row, column, slot).
    fn entries(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        let col_ptr = self.symbolic.col_ptr();
        (0..self.size()).flat_map(move |col| {
            (col_ptr[col]..col_ptr[col + 1])
                .map(move |slot| (self.symbolic.row_idx()[slot], col, slot))
        })
    }
}

/// Which implementation of the seam a Newton iteration uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearSolverKind {
    /// [`LinearSolverKind::Dense`] for a small pattern that stores many of its entries (size at
    /// most [`DENSE_SIZE`] and at least an eighth of the entries), else
    /// [`LinearSolverKind::Sparse`] (the default; see [`LinearSolverKind::resolve`]).
    #[default]
    Auto,
    /// faer's sparse LU.
    Sparse,
    /// svi's dense LU (moderate sizes; the reference in tests).
    Dense,
}

/// The largest size [`LinearSolverKind::Auto`] factors densely.
pub const DENSE_SIZE: usize = 128;

impl LinearSolverKind {
    /// The solver a run uses on `pattern`: [`LinearSolverKind::Auto`] resolved, the others
    /// as they are.
    ///
    /// The rule is the faster of the two on the stage Jacobians of the term-sum Newton
    /// iterations (`cargo bench --bench linear_solve -- linear_solve/pattern`, one numeric
    /// factorisation and one solve): faer's simplicial LU is 2–4× slower than the dense LU
    /// on dense patterns up to size 108 (an N-body system of 6 bodies with 6 stages: 672 µs
    /// against 155 µs) and on chains up to size 50, and faster on chains from size 100 on
    /// (size 1000: 0.29 ms against 3.3 ms) and on dense patterns from size 144 on, where it
    /// factors by dense supernodes (size 216: 0.50 ms against 1.07 ms).
    pub fn resolve(self, pattern: &Pattern) -> LinearSolverKind {
        match self {
            LinearSolverKind::Auto => {
                let size = pattern.size();
                if size <= DENSE_SIZE && 8 * pattern.len() >= size * size {
                    LinearSolverKind::Dense
                } else {
                    LinearSolverKind::Sparse
                }
            }
            kind => kind,
        }
    }
}

/// A solver of A x = b for matrices of one [`Pattern`], values given in the pattern's slot
/// order.
pub trait LinearSolver {
    /// Prepare for matrices of `pattern` (the symbolic analysis: once per run).
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), Error>;
    /// Factor the matrix with these values (the numeric factorisation). A singular matrix
    /// may be reported here or by the solve.
    fn factor(&mut self, pattern: &Pattern, values: &[f64]) -> Result<(), Singular>;
    /// Overwrite `b` with A⁻¹ b for the last factored A; [`Singular`] when the solution is
    /// not finite (faer's sparse LU does not stop at a zero pivot).
    fn solve_in_place(&mut self, b: &mut DVector<f64>) -> Result<(), Singular>;
}

/// Dense LU of the pattern's matrix (moderate sizes; the reference for [`SparseLu`]).
#[derive(Debug, Clone, Default)]
pub struct DenseSolver {
    lu: Option<DenseLu>,
}

impl LinearSolver for DenseSolver {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), Error> {
        self.lu = Some(DenseLu::new(pattern.size()));
        Ok(())
    }

    fn factor(&mut self, pattern: &Pattern, values: &[f64]) -> Result<(), Singular> {
        let Some(lu) = self.lu.as_mut() else {
            return Err(Singular);
        };
        let matrix = lu.matrix_mut();
        matrix.fill(0.0);
        for (row, col, slot) in pattern.entries() {
            matrix[(row, col)] = values[slot];
        }
        lu.factor()
    }

    fn solve_in_place(&mut self, b: &mut DVector<f64>) -> Result<(), Singular> {
        let Some(lu) = &self.lu else {
            return Err(Singular);
        };
        lu.solve_in_place(b);
        finite(b)
    }
}

/// faer's sparse LU (supernodal or simplicial, chosen by faer), sequential.
#[derive(Default)]
pub struct SparseLu {
    symbolic: Option<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    scratch: Option<MemBuffer>,
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("analysed", &self.symbolic.is_some())
            .finish_non_exhaustive()
    }
}

impl LinearSolver for SparseLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), Error> {
        let symbolic = factorize_symbolic_lu(pattern.symbolic.as_ref(), Default::default())
            .map_err(|e| Error::invalid("pattern", format!("symbolic factorisation: {e:?}")))?;
        let factor = symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let solve = symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        self.scratch = Some(
            MemBuffer::try_new(factor.or(solve))
                .map_err(|_| Error::invalid("pattern", "out of memory for the factorisation"))?,
        );
        self.symbolic = Some(symbolic);
        Ok(())
    }

    fn factor(&mut self, pattern: &Pattern, values: &[f64]) -> Result<(), Singular> {
        let (Some(symbolic), Some(scratch)) = (&self.symbolic, &mut self.scratch) else {
            return Err(Singular);
        };
        let matrix = SparseColMatRef::new(pattern.symbolic.as_ref(), values);
        symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                matrix,
                Par::Seq,
                MemStack::new(scratch),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|_| Singular)
    }

    fn solve_in_place(&mut self, b: &mut DVector<f64>) -> Result<(), Singular> {
        let (Some(symbolic), Some(scratch)) = (&self.symbolic, &mut self.scratch) else {
            return Err(Singular);
        };
        let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(symbolic, &self.numeric);
        let n = b.len();
        let rhs = MatMut::from_column_major_slice_mut(b.as_mut_slice(), n, 1);
        lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(scratch));
        finite(b)
    }
}

/// A linear solver of the [`LinearSolverKind`] a run asked for.
#[derive(Debug)]
pub(crate) enum AnySolver {
    Sparse(Box<SparseLu>),
    Dense(DenseSolver),
}

impl AnySolver {
    /// A solver of `kind` ([`LinearSolverKind::resolve`]d), analysed for `pattern`.
    pub(crate) fn analysed(kind: LinearSolverKind, pattern: &Pattern) -> Result<Self, Error> {
        let mut solver = match kind.resolve(pattern) {
            LinearSolverKind::Dense => AnySolver::Dense(DenseSolver::default()),
            LinearSolverKind::Sparse | LinearSolverKind::Auto => AnySolver::Sparse(Box::default()),
        };
        solver.get().analyse(pattern)?;
        Ok(solver)
    }

    /// The solver.
    pub(crate) fn get(&mut self) -> &mut dyn LinearSolver {
        match self {
            AnySolver::Sparse(solver) => solver.as_mut(),
            AnySolver::Dense(solver) => solver,
        }
    }
}

/// [`Singular`] unless every entry of a solution is finite.
fn finite(x: &DVector<f64>) -> Result<(), Singular> {
    if x.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Singular)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tridiagonal, diagonally dominant test matrix of size n with its pattern and values.
    fn tridiagonal(n: usize) -> (Pattern, Vec<f64>, nalgebra::DMatrix<f64>) {
        let mut entries = Vec::new();
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                entries.push((i, j));
            }
        }
        let pattern = Pattern::new(n, &entries).unwrap();
        let mut dense = nalgebra::DMatrix::zeros(n, n);
        let mut values = vec![0.0; pattern.len()];
        for &(i, j) in &entries {
            let value = if i == j {
                4.0 + i as f64 * 0.01
            } else {
                -1.0 - 0.1 * (i + 2 * j) as f64 / n as f64
            };
            dense[(i, j)] = value;
            values[pattern.slot(i, j).unwrap()] = value;
        }
        (pattern, values, dense)
    }

    #[test]
    fn sparse_and_dense_solvers_solve_the_same_system() {
        let n = 60;
        let (pattern, values, dense) = tridiagonal(n);
        let x = DVector::from_fn(n, |i, _| (i as f64 * 0.37).sin());
        let b = &dense * &x;
        for solver in [
            &mut DenseSolver::default() as &mut dyn LinearSolver,
            &mut SparseLu::default(),
        ] {
            solver.analyse(&pattern).unwrap();
            solver.factor(&pattern, &values).unwrap();
            let mut y = b.clone();
            solver.solve_in_place(&mut y).unwrap();
            assert!((&y - &x).amax() < 1e-14, "{}", (&y - &x).amax());
        }
        assert_eq!(pattern.slot(0, 5), None);
        assert!(Pattern::new(3, &[(0, 3)]).is_err());
    }

    #[test]
    fn a_singular_matrix_is_reported() {
        let (pattern, mut values, _) = tridiagonal(4);
        values.iter_mut().for_each(|v| *v = 0.0);
        for solver in [
            &mut DenseSolver::default() as &mut dyn LinearSolver,
            &mut SparseLu::default(),
        ] {
            solver.analyse(&pattern).unwrap();
            let mut b = DVector::from_element(4, 1.0);
            let singular =
                solver.factor(&pattern, &values).is_err() || solver.solve_in_place(&mut b).is_err();
            assert!(singular);
        }
    }

    /// `Auto` factors small dense patterns densely and chains and large patterns sparsely, at
    /// the edges of the rule; the others are kept as asked.
    #[test]
    fn auto_is_dense_for_small_dense_patterns_only() {
        let all = |n: usize| {
            let entries: Vec<_> = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).collect();
            Pattern::new(n, &entries).unwrap()
        };
        let auto = LinearSolverKind::Auto;
        assert_eq!(auto.resolve(&all(DENSE_SIZE)), LinearSolverKind::Dense);
        assert_eq!(auto.resolve(&all(DENSE_SIZE + 1)), LinearSolverKind::Sparse);
        // A tridiagonal pattern of size 23 stores 67 entries, more than 529/8; of size 24, 70,
        // fewer than 576/8.
        assert_eq!(auto.resolve(&tridiagonal(23).0), LinearSolverKind::Dense);
        assert_eq!(auto.resolve(&tridiagonal(24).0), LinearSolverKind::Sparse);
        for kind in [LinearSolverKind::Dense, LinearSolverKind::Sparse] {
            assert_eq!(kind.resolve(&all(200)), kind);
            assert_eq!(kind.resolve(&tridiagonal(4).0), kind);
        }
        assert!(matches!(
            AnySolver::analysed(auto, &all(6)).unwrap(),
            AnySolver::Dense(_)
        ));
        assert!(matches!(
            AnySolver::analysed(auto, &tridiagonal(60).0).unwrap(),
            AnySolver::Sparse(_)
        ));
    }
}
