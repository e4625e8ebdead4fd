//! The sparse linear algebra of local constraints ([`crate::model::constraint::local`]): the
//! Jacobian G stored row by row, S = A M⁻¹ Bᵀ for Jacobians A, B of one pattern with a
//! diagonal M⁻¹, the rank check and the projection of initial data — each O(n).
//!
//! # S = A M⁻¹ Bᵀ
//! With M⁻¹ = diag(w) (particles with their own masses), S_ij = Σ_c A_ic w_c B_jc sums over
//! the columns c that rows i and j share. The pattern of S (the pairs of rows sharing a
//! column: the neighbouring bonds of a chain, a tridiagonal S) and the list of products
//! (slot of S_ij, entry of A, entry of B, column c) are built once, from the columns of G;
//! assembling S is then one pass over the products — for a chain of bonds, 12 products a
//! bond. RATTLE's Newton matrix G(q_{k+1}) M⁻¹ G(q_k)ᵀ and the velocity projection's
//! G M⁻¹ Gᵀ are both of this form, factored by faer's sparse LU on the fixed pattern
//! ([`SparseLu`]: symbolic analysis once, numeric factorisation per Newton iteration).
//!
//! # The rank check, in O(n)
//! Dense Gram–Schmidt ([`crate::model::constraint::check_rank`]) costs O(m² n). Here: every row
//! must be finite and nonzero (else the constraint is named); no two rows that share a column
//! may be parallel (angle under 10⁻⁶, from the Gram matrix G Gᵀ on S's pattern; the later of the two is named: a
//! constraint written twice, or contradicting another); and S = G M⁻¹ Gᵀ must be regular — its
//! sparse LU factors solve S x = S 1 to x = 1 within 10⁻⁴ (a relative error that a condition
//! number up to about 10¹² passes: a straight chain of 10⁵ bonds has one near 4·10⁹), else the
//! constraint where the solve is worst is named. A dependence among three or more rows passes
//! the pairwise test and is caught by the last.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::constraint::local::ConstraintRows;
use crate::model::constraint::{PROJECTION_STEPS, Projected};
use crate::model::mass_inverse::MassInverse;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector};

/// The diagonal of M⁻¹, when M⁻¹ is diagonal (the sparse path needs it; a coupled M has a
/// dense inverse, and its runs take the dense path).
pub(crate) fn diagonal<N: Dimension>(mass_inverse: &MassInverse<N>) -> Option<Vec<f64>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match mass_inverse {
        MassInverse::Diagonal(inverse) => Some(inverse.as_slice().to_vec()),
        MassInverse::Dense(inverse) => {
            let n = inverse.nrows();
            let coupled = (0..n).any(|i| (0..n).any(|j| i != j && inverse[(i, j)] != 0.0));
            (!coupled).then(|| (0..n).map(|i| inverse[(i, i)]).collect())
        }
        MassInverse::Coupled(_) => None,
    }
}

/// The Jacobian G of [`ConstraintRows`], K entries a row (entry i·K + a: row i, slot a).
#[derive(Debug, Clone)]
pub(crate) struct SparseJacobian {
    width: usize,
    columns: Vec<usize>,
    /// The entries' values at the last [`SparseJacobian::evaluate`].
    pub(crate) entries: Vec<f64>,
}

impl SparseJacobian {
    /// The layout of `rows` on n coordinates (entries zero until evaluated).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `constraints` for a row that reads a coordinate outside
    /// 0..n, naming it, or for as many constraints as coordinates or more.
    pub(crate) fn new(rows: &dyn ConstraintRows, n: usize) -> Result<Self, Error> {
        let (m, width) = (rows.count(), rows.width());
        if m >= n {
            return Err(Error::invalid(
                "constraints",
                format!("{m} constraints on {n} coordinates leave no motion: there must be fewer"),
            ));
        }
        let mut columns = vec![0; m * width];
        rows.columns_into(&mut columns);
        if let Some(entry) = columns.iter().position(|&c| c >= n) {
            return Err(Error::invalid(
                "constraints",
                format!(
                    "{} reads coordinate {}, outside the {n} coordinates",
                    rows.row_name(entry / width),
                    columns[entry]
                ),
            ));
        }
        Ok(SparseJacobian {
            width,
            entries: vec![0.0; columns.len()],
            columns,
        })
    }

    /// The number m of rows.
    pub(crate) fn rows(&self) -> usize {
        self.columns.len() / self.width.max(1)
    }

    /// G at `q`.
    pub(crate) fn evaluate(&mut self, rows: &dyn ConstraintRows, q: &[f64]) {
        rows.jacobian_into(q, &mut self.entries);
    }

    /// `out` = G `x` (length m).
    pub(crate) fn mul_into(&self, x: &[f64], out: &mut [f64]) {
        for ((o, entries), columns) in out
            .iter_mut()
            .zip(self.entries.chunks_exact(self.width))
            .zip(self.columns.chunks_exact(self.width))
        {
            *o = entries.iter().zip(columns).map(|(&g, &c)| g * x[c]).sum();
        }
    }

    /// `out` += `scale` Gᵀ `y` (length n).
    pub(crate) fn tr_mul_add(&self, scale: f64, y: &[f64], out: &mut [f64]) {
        for ((&yi, entries), columns) in y
            .iter()
            .zip(self.entries.chunks_exact(self.width))
            .zip(self.columns.chunks_exact(self.width))
        {
            let factor = scale * yi;
            for (&g, &c) in entries.iter().zip(columns) {
                out[c] += factor * g;
            }
        }
    }
}

/// One product of S_ij = Σ_c A_ic w_c B_jc: the entries of A and B and the column c (32-bit
/// indices: the list is streamed at every assembly, and its size decides the step's memory
/// traffic).
#[derive(Debug, Clone, Copy)]
struct Product {
    left: u32,
    right: u32,
    column: u32,
}

/// Matrices S = A M⁻¹ Bᵀ (m × m) of Jacobians of one layout: the pattern and products fixed
/// once, the values, and their sparse LU (analysed once).
#[derive(Debug)]
pub(crate) struct Schur {
    pattern: Pattern,
    /// The products of each slot: those of slot s are `products[starts[s]..starts[s + 1]]`.
    starts: Vec<usize>,
    products: Vec<Product>,
    /// The values of the last assembled S, in the pattern's slot order.
    values: Vec<f64>,
    lu: SparseLu,
}

impl Schur {
    /// The pattern and products of S for Jacobians laid out as `jacobian`, analysed for the
    /// sparse LU.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `constraints` when G has 2³² entries or more (the
    /// products' indices are 32-bit), or from the symbolic analysis.
    pub(crate) fn new(jacobian: &SparseJacobian, n: usize) -> Result<Self, Error> {
        let width = jacobian.width;
        let index = |i: usize| {
            u32::try_from(i)
                .map_err(|_| Error::invalid("constraints", "too many: G has 2³² entries or more"))
        };
        index(jacobian.columns.len().max(n))?;
        // The entries of each column (compressed: start offsets, then the entries).
        let mut column_starts = vec![0usize; n + 1];
        for &c in &jacobian.columns {
            column_starts[c + 1] += 1;
        }
        for c in 0..n {
            column_starts[c + 1] += column_starts[c];
        }
        let mut fill = column_starts.clone();
        let mut by_column = vec![0usize; jacobian.columns.len()];
        for (entry, &c) in jacobian.columns.iter().enumerate() {
            by_column[fill[c]] = entry;
            fill[c] += 1;
        }
        // Every pair of entries in one column: (left, right, column).
        let mut pairs = Vec::new();
        for c in 0..n {
            let entries = &by_column[column_starts[c]..column_starts[c + 1]];
            for &left in entries {
                for &right in entries {
                    pairs.push((left, right, c));
                }
            }
        }
        let places: Vec<(usize, usize)> = pairs
            .iter()
            .map(|&(left, right, _)| (left / width, right / width))
            .collect();
        let pattern = Pattern::new(jacobian.rows(), &places)?;
        // Sorted by slot, so that an assembly writes each value once, in order.
        let mut slotted: Vec<(usize, Product)> = Vec::with_capacity(pairs.len());
        for (&(left, right, column), &(i, j)) in pairs.iter().zip(&places) {
            if let Some(slot) = pattern.slot(i, j) {
                let product = Product {
                    left: index(left)?,
                    right: index(right)?,
                    column: index(column)?,
                };
                slotted.push((slot, product));
            }
        }
        slotted.sort_by_key(|&(slot, product)| (slot, product.column));
        let mut starts = vec![0usize; pattern.len() + 1];
        for &(slot, _) in &slotted {
            starts[slot + 1] += 1;
        }
        for s in 0..pattern.len() {
            starts[s + 1] += starts[s];
        }
        let mut lu = SparseLu::default();
        lu.analyse(&pattern)?;
        Ok(Schur {
            values: vec![0.0; pattern.len()],
            products: slotted.into_iter().map(|(_, product)| product).collect(),
            starts,
            pattern,
            lu,
        })
    }

    /// S = `scale` A diag(`weights`) Bᵀ with A = `left`, B = `right`.
    pub(crate) fn assemble(
        &mut self,
        scale: f64,
        left: &SparseJacobian,
        weights: &[f64],
        right: &SparseJacobian,
    ) {
        let (a, b) = (&left.entries, &right.entries);
        for (value, range) in self.values.iter_mut().zip(self.starts.windows(2)) {
            let sum: f64 = self.products[range[0]..range[1]]
                .iter()
                .map(|p| a[p.left as usize] * weights[p.column as usize] * b[p.right as usize])
                .sum();
            *value = scale * sum;
        }
    }

    /// Factor the assembled S; `false` when it is singular.
    #[must_use]
    pub(crate) fn factor(&mut self) -> bool {
        self.lu.factor(&self.pattern, &self.values).is_ok()
    }

    /// `b` ← S⁻¹ `b` for the last factored S; `false` when the solution is not finite.
    #[must_use]
    pub(crate) fn solve_in_place(&mut self, b: &mut DVector<f64>) -> bool {
        self.lu.solve_in_place(b).is_ok()
    }

    /// `out` = S `x` for the assembled S.
    fn mul_into(&self, x: &[f64], out: &mut [f64]) {
        self.pattern.mul_into(&self.values, x, out);
    }
}

/// The worst relative error of S's solve that still counts S as regular (module docs).
const SOLVE_TOLERANCE: f64 = 1e-4;

/// The squared sine of the angle below which two rows count as parallel: an angle under
/// 10⁻⁶ (the squared sine is computed as 1 − cos², with round-off near 10⁻¹⁶).
const PARALLEL_TOLERANCE: f64 = 1e-12;

/// Check that the constraints' Jacobian at `q` has full rank, in O(n) (module docs), with
/// `jacobian` and `schur` of their layout; on success `jacobian` holds G(q) and `schur` the
/// factored G M⁻¹ Gᵀ.
///
/// # Errors
/// [`Error::InvalidParameter`] `constraints` naming a constraint whose gradient is not
/// finite or zero, one parallel to a constraint it shares a coordinate with, or one where the
/// solve with a singular G M⁻¹ Gᵀ is worst.
pub(crate) fn check_rank(
    rows: &dyn ConstraintRows,
    q: &[f64],
    weights: &[f64],
    jacobian: &mut SparseJacobian,
    schur: &mut Schur,
) -> Result<(), Error> {
    jacobian.evaluate(rows, q);
    let width = jacobian.width;
    for (i, row) in jacobian.entries.chunks_exact(width).enumerate() {
        let why = if !row.iter().all(|g| g.is_finite()) {
            "is not finite"
        } else if row.iter().all(|&g| g == 0.0) {
            "is zero"
        } else {
            continue;
        };
        return Err(Error::invalid(
            "constraints",
            format!(
                "the gradient of {} {why} at the initial state{}",
                rows.row_name(i),
                if why == "is zero" {
                    " (it does not depend on q)"
                } else {
                    ""
                }
            ),
        ));
    }
    // The Gram matrix G Gᵀ on S's pattern: rows sharing a column must not be parallel.
    let ones = vec![1.0; weights.len()];
    schur.assemble(1.0, jacobian, &ones, jacobian);
    let mut diagonal = vec![0.0; jacobian.rows()];
    for (i, d) in diagonal.iter_mut().enumerate() {
        *d = schur.pattern.slot(i, i).map_or(0.0, |s| schur.values[s]);
    }
    for j in 0..schur.pattern.size() {
        let start = schur.pattern.column_start(j);
        for (offset, i) in schur.pattern.column(j).enumerate() {
            if i >= j {
                continue;
            }
            let gram = schur.values[start + offset];
            // 1 − (g_i·g_j)²/(|g_i|²|g_j|²): the squared sine of their angle.
            let sine_squared = 1.0 - gram * gram / (diagonal[i] * diagonal[j]);
            if sine_squared <= PARALLEL_TOLERANCE {
                return Err(Error::invalid(
                    "constraints",
                    format!(
                        "{} is redundant or contradicts {}: their gradients are parallel at \
                         the initial state",
                        rows.row_name(j),
                        rows.row_name(i)
                    ),
                ));
            }
        }
    }
    // S = G M⁻¹ Gᵀ must be regular: its factors solve S x = S 1 to x = 1.
    schur.assemble(1.0, jacobian, weights, jacobian);
    let m = jacobian.rows();
    let mut rhs = DVector::zeros(m);
    schur.mul_into(&vec![1.0; m], rhs.as_mut_slice());
    let solved = schur.factor() && schur.solve_in_place(&mut rhs);
    let worst = rhs
        .iter()
        .map(|x| {
            if x.is_finite() {
                (x - 1.0).abs()
            } else {
                f64::INFINITY
            }
        })
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (i, e)| if e > best.1 { (i, e) } else { best },
        );
    if !solved || worst.1 > SOLVE_TOLERANCE {
        return Err(Error::invalid(
            "constraints",
            format!(
                "G M⁻¹ Gᵀ is singular: the constraints' gradients are dependent at the initial \
                 state (the solve is worst at {})",
                rows.row_name(worst.0)
            ),
        ));
    }
    Ok(())
}

/// [`crate::model::constraint::project`] for local constraints with a diagonal M⁻¹ =
/// diag(`weights`), every step O(n): q ← q − M⁻¹Gᵀ S⁻¹ g(q) until g(q) = 0 to round-off,
/// then p ← p − Gᵀ S⁻¹ G M⁻¹ p, with S = G M⁻¹ Gᵀ by sparse LU.
///
/// # Errors
/// As [`crate::model::constraint::project`]; the rank by [`check_rank`].
pub(crate) fn project<N: Dimension>(
    rows: &dyn ConstraintRows,
    weights: &[f64],
    q0: &OVector<f64, N>,
    p0: &OVector<f64, N>,
) -> Result<Projected<N>, Error>
where
    DefaultAllocator: Allocator<N>,
{
    let n = q0.len();
    let m = rows.count();
    let mut jacobian = SparseJacobian::new(rows, n)?;
    let mut schur = Schur::new(&jacobian, n)?;
    check_rank(rows, q0.as_slice(), weights, &mut jacobian, &mut schur)?;
    let singular = || {
        Error::invalid(
            "constraints",
            "G M⁻¹ Gᵀ is singular: the constraints' gradients are dependent here",
        )
    };
    let mut q = q0.clone();
    let mut g = DVector::zeros(m);
    let mut shift = vec![0.0; n];
    rows.values_into(q.as_slice(), g.as_mut_slice());
    let scale = q0.amax().max(1.0);
    let mut converged = false;
    for _ in 0..PROJECTION_STEPS {
        jacobian.evaluate(rows, q.as_slice());
        schur.assemble(1.0, &jacobian, weights, &jacobian);
        if !(schur.factor() && schur.solve_in_place(&mut g)) {
            return Err(singular());
        }
        shift.fill(0.0);
        jacobian.tr_mul_add(1.0, g.as_slice(), &mut shift);
        let mut moved: f64 = 0.0;
        for ((x, s), w) in q.iter_mut().zip(&shift).zip(weights) {
            *x -= w * s;
            moved = moved.max((w * s).abs());
        }
        rows.values_into(q.as_slice(), g.as_mut_slice());
        if !g.iter().all(|x| x.is_finite()) {
            break;
        }
        if moved <= 4.0 * f64::EPSILON * scale {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(super::not_projected(g.amax()));
    }
    jacobian.evaluate(rows, q.as_slice());
    schur.assemble(1.0, &jacobian, weights, &jacobian);
    let rate: Vec<f64> = p0.iter().zip(weights).map(|(p, w)| p * w).collect();
    let mut multipliers = DVector::zeros(m);
    jacobian.mul_into(&rate, multipliers.as_mut_slice());
    if !(schur.factor() && schur.solve_in_place(&mut multipliers)) {
        return Err(singular());
    }
    let mut p = p0.clone();
    jacobian.tr_mul_add(-1.0, multipliers.as_slice(), p.as_mut_slice());
    Ok(Projected {
        moved_q: (&q - q0).norm(),
        moved_p: (&p - p0).norm(),
        q,
        p,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::constraint::local::{LocalConstraints, SparseConstraints};
    use crate::model::constraint::{Constraints, ConstraintsExt};
    use crate::scalar::Scalar;
    use nalgebra::{Const, DMatrix, SVector};

    /// Overlapping triples of 7 coordinates, one with a repeated index, nonlinear in each.
    struct Triples;

    impl LocalConstraints for Triples {
        type Width = Const<3>;
        fn count(&self) -> usize {
            4
        }
        fn indices(&self, i: usize) -> [usize; 3] {
            [[0, 1, 2], [2, 3, 4], [4, 4, 6], [1, 5, 6]][i]
        }
        fn constraint<D: Scalar>(&self, i: usize, q: &SVector<D, 3>) -> D {
            q[0] * q[1] + q[2].sin() * (i as f64 + 1.0) + q[0] * q[0] * q[2]
        }
    }

    /// S = s A W Bᵀ assembled from the products equals the dense product, for Jacobians A, B
    /// at two points and a repeated slot.
    #[test]
    fn assembly_equals_the_dense_product() {
        let constraints = SparseConstraints(Triples);
        let rows = constraints.local().unwrap();
        let (qa, qb) = (
            DVector::from_fn(7, |i, _| 0.3 + 0.1 * i as f64),
            DVector::from_fn(7, |i, _| (0.7 * i as f64).cos()),
        );
        let weights: Vec<f64> = (0..7).map(|i| 1.0 / (1.0 + i as f64)).collect();
        let mut a = SparseJacobian::new(rows, 7).unwrap();
        let mut b = a.clone();
        a.evaluate(rows, qa.as_slice());
        b.evaluate(rows, qb.as_slice());
        let mut schur = Schur::new(&a, 7).unwrap();
        schur.assemble(-0.5, &a, &weights, &b);
        let w = DMatrix::from_diagonal(&DVector::from_vec(weights.clone()));
        let expected = constraints.jacobian(&qa) * w * constraints.jacobian(&qb).transpose() * -0.5;
        let mut dense = DMatrix::zeros(4, 4);
        for col in 0..4 {
            let start = schur.pattern.column_start(col);
            for (offset, row) in schur.pattern.column(col).enumerate() {
                dense[(row, col)] = schur.values[start + offset];
            }
        }
        assert!((&dense - &expected).amax() < 1e-14, "{dense} vs {expected}");
        // Rows 0 and 2 share no coordinate: no entry.
        assert_eq!(schur.pattern.slot(0, 2), None);
        // G x and Gᵀ y against the dense Jacobian.
        let x = DVector::from_fn(7, |i, _| i as f64 - 2.0);
        let mut gx = vec![0.0; 4];
        a.mul_into(x.as_slice(), &mut gx);
        let dense_a = constraints.jacobian(&qa);
        assert!((DVector::from_vec(gx) - &dense_a * &x).amax() < 1e-14);
        let y = DVector::from_vec(vec![1.0, -2.0, 0.5, 3.0]);
        let mut gty = vec![1.0; 7];
        a.tr_mul_add(2.0, y.as_slice(), &mut gty);
        let expected = dense_a.tr_mul(&y) * 2.0 + DVector::from_element(7, 1.0);
        assert!((DVector::from_vec(gty) - expected).amax() < 1e-14);
    }

    /// The O(n) rank check passes independent rows and names a parallel one.
    #[test]
    fn the_rank_check_names_a_parallel_row() {
        let rows = SparseConstraints(Triples);
        let rows = rows.local().unwrap();
        let q = DVector::from_fn(7, |i, _| 0.3 + 0.1 * i as f64);
        let weights = vec![1.0; 7];
        let mut jacobian = SparseJacobian::new(rows, 7).unwrap();
        let mut schur = Schur::new(&jacobian, 7).unwrap();
        check_rank(rows, q.as_slice(), &weights, &mut jacobian, &mut schur).unwrap();

        /// The first triple twice.
        struct Twice;
        impl LocalConstraints for Twice {
            type Width = Const<3>;
            fn count(&self) -> usize {
                2
            }
            fn indices(&self, _: usize) -> [usize; 3] {
                [0, 1, 2]
            }
            fn constraint<D: Scalar>(&self, _: usize, q: &SVector<D, 3>) -> D {
                Triples.constraint(0, q)
            }
        }
        let twice = SparseConstraints(Twice);
        let rows = twice.local().unwrap();
        let mut jacobian = SparseJacobian::new(rows, 7).unwrap();
        let mut schur = Schur::new(&jacobian, 7).unwrap();
        let error = check_rank(rows, q.as_slice(), &weights, &mut jacobian, &mut schur)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("g[1] is redundant") && error.contains("g[0]"),
            "{error}"
        );
        let error = SparseJacobian::new(rows, 2).unwrap_err().to_string();
        assert!(error.contains("2 constraints on 2 coordinates"), "{error}");
        let error = SparseJacobian::new(SparseConstraints(Triples).local().unwrap(), 6)
            .unwrap_err()
            .to_string();
        assert!(error.contains("g[2] reads coordinate 6"), "{error}");
    }
}
