//! Local constraints: many constraints, each reading a few coordinates, for a Jacobian stored
//! sparsely.
//!
//! The bonds of a polymer, the rods of a linkage, the incompressibility of a discretised body:
//! m constraints on ℝⁿ, m and n in the thousands, constraint i a function
//! g_i(q_{I(i)}) of the K coordinates of its index set I(i) only. Written as one dense
//! [`Constraints`] the Jacobian G = ∂g/∂q would be an m × n matrix of mostly zeros, and the
//! integrators' m × m systems with S = G M⁻¹ Gᵀ dense: O(n²) memory and O(n³) work per step.
//! A [`LocalConstraints`] writes one constraint, generic over [`Scalar`] and K =
//! [`LocalConstraints::Width`] slots wide, and says which coordinates each reads — the
//! pattern [`crate::model::local::LocalLagrangian`] follows for the terms of a Lagrangian.
//!
//! # Design
//! The user-facing API stays one: [`crate::method::constrained::ConstrainedIntegrator`] takes
//! any [`Constraints`]. The adapter [`SparseConstraints`]`(constraints)` — the counterpart of
//! [`crate::model::local::Terms`] — is a [`Constraints<Dyn>`] (its g(q) evaluates the K slots
//! of each constraint, so every dense code path runs it unchanged) and answers
//! [`Constraints::local`] with the constraints as [`ConstraintRows`], an object-safe view
//! whose loops over the rows are monomorphised. That provided method, `None` by default, is
//! the same seam as [`crate::Lagrangian::terms`]: a run asks once, at its start, and takes the
//! sparse path when the answer is `Some` and M⁻¹ is diagonal, the dense path otherwise — so a
//! small system of fixed size pays one branch per run and nothing per step, and no second
//! entry point or trait bound spreads through the integrators.
//!
//! # The sparse Jacobian
//! Row i of G holds the K partial derivatives ∂g_i/∂q_{I(i)_a}, each by one sweep of the dual
//! number [`Dual64`] through the constraint on its K slots: K evaluations per row and O(n) for
//! all of G, stored row by row (K entries a row, the column of each fixed once; a slot whose
//! index repeats another's adds to the same column). Products with G and Gᵀ, and the entries
//! of S = G M⁻¹ Gᵀ (whose pattern — rows that share a column — is computed once), are O(n):
//! see [`crate::model::constraint::sparse`].

use crate::dimension::Dyn;
use crate::model::constraint::Constraints;
use crate::model::local::TermWidth;
use crate::scalar::Scalar;
use nalgebra::DVector;
use num_dual::Dual64;

/// m constraints on ℝⁿ, each a function of K coordinates, written once, generic over the
/// scalar (run them as [`SparseConstraints`]).
///
/// A constraint that reads fewer than K coordinates repeats an index and ignores that slot.
///
/// # Example
/// ```
/// use nalgebra::{Const, SVector};
/// use svi::Scalar;
/// use svi::model::constraint::local::{LocalConstraints, SparseConstraints};
///
/// /// n points on a line at unit distances: q_{i+1} − q_i − 1 = 0.
/// struct Rods {
///     n: usize,
/// }
///
/// impl LocalConstraints for Rods {
///     type Width = Const<2>;
///     fn count(&self) -> usize {
///         self.n - 1
///     }
///     fn indices(&self, i: usize) -> [usize; 2] {
///         [i, i + 1]
///     }
///     fn constraint<D: Scalar>(&self, _i: usize, q: &SVector<D, 2>) -> D {
///         q[1] - q[0] - D::from(1.0)
///     }
/// }
///
/// let constraints = SparseConstraints(Rods { n: 100 });
/// ```
pub trait LocalConstraints {
    /// K, the number of coordinates one constraint reads, as `nalgebra::Const<K>`.
    type Width: TermWidth;

    /// The number m of constraints.
    fn count(&self) -> usize;

    /// The index set I(i) of constraint `constraint`: which coordinates its K slots read.
    fn indices(&self, constraint: usize) -> <Self::Width as TermWidth>::Indices;

    /// g_i(q_{I(i)}), written once, generic over the scalar (mark it `#[inline]`).
    fn constraint<D: Scalar>(
        &self,
        constraint: usize,
        q: &<Self::Width as TermWidth>::Vector<D>,
    ) -> D;

    /// The name of constraint `index` in messages: `g[index]` unless the model says better.
    fn constraint_name(&self, index: usize) -> String {
        format!("g[{index}]")
    }
}

/// Constraints as the rows of a sparse Jacobian, for the integrators' sparse path (object
/// safe; every [`LocalConstraints`] is one, and [`Constraints::local`] hands it over).
///
/// The rows are laid out K entries a row: entry i·K + a belongs to constraint i and slot a.
/// Coordinates outside q make a constraint's value and derivatives NaN (no panic); the sparse
/// path checks the indices once before it uses them.
pub trait ConstraintRows {
    /// K, the entries of one row.
    fn width(&self) -> usize;

    /// m, the number of rows.
    fn count(&self) -> usize;

    /// The column of every entry into `columns` (length m·K).
    fn columns_into(&self, columns: &mut [usize]);

    /// g(q) into `g` (length m).
    fn values_into(&self, q: &[f64], g: &mut [f64]);

    /// The entries of G = ∂g/∂q at q into `entries` (length m·K), by K sweeps of [`Dual64`]
    /// per row.
    fn jacobian_into(&self, q: &[f64], entries: &mut [f64]);

    /// The name of row `index` in messages.
    fn row_name(&self, index: usize) -> String;
}

/// The value of coordinate `index` of `q`, NaN outside it.
#[inline(always)]
fn coordinate<D: Scalar>(q: &[D], index: usize) -> D {
    q.get(index).copied().unwrap_or_else(|| D::from(f64::NAN))
}

impl<C: LocalConstraints + ?Sized> ConstraintRows for C {
    fn width(&self) -> usize {
        C::Width::WIDTH
    }

    fn count(&self) -> usize {
        LocalConstraints::count(self)
    }

    fn columns_into(&self, columns: &mut [usize]) {
        for (i, row) in columns.chunks_exact_mut(C::Width::WIDTH).enumerate() {
            row.copy_from_slice(self.indices(i).as_ref());
        }
    }

    fn values_into(&self, q: &[f64], g: &mut [f64]) {
        for (i, gi) in g.iter_mut().enumerate() {
            let indices = self.indices(i);
            let indices = indices.as_ref();
            let local = C::Width::vector(|a| coordinate(q, indices[a]));
            *gi = self.constraint(i, &local);
        }
    }

    fn jacobian_into(&self, q: &[f64], entries: &mut [f64]) {
        for (i, row) in entries.chunks_exact_mut(C::Width::WIDTH).enumerate() {
            let indices = self.indices(i);
            let indices = indices.as_ref();
            for (slot, entry) in row.iter_mut().enumerate() {
                let local = C::Width::vector(|a| {
                    Dual64::new(coordinate(q, indices[a]), f64::from(u8::from(a == slot)))
                });
                *entry = self.constraint(i, &local).eps;
            }
        }
    }

    fn row_name(&self, index: usize) -> String {
        self.constraint_name(index)
    }
}

/// Local constraints as [`Constraints`] on ℝⁿ of run-time size, taken sparsely by the
/// integrators (see the module docs): the counterpart of [`crate::model::local::Terms`].
///
/// ```
/// # use nalgebra::{Const, DVector, SVector};
/// # use svi::Scalar;
/// # use svi::model::constraint::local::{LocalConstraints, SparseConstraints};
/// use svi::model::constraint::{Constraints, ConstraintsExt};
/// # struct Rods;
/// # impl LocalConstraints for Rods {
/// #     type Width = Const<2>;
/// #     fn count(&self) -> usize { 2 }
/// #     fn indices(&self, i: usize) -> [usize; 2] { [i, i + 1] }
/// #     fn constraint<D: Scalar>(&self, _i: usize, q: &SVector<D, 2>) -> D {
/// #         q[1] - q[0] - D::from(1.0)
/// #     }
/// # }
/// let rods = SparseConstraints(Rods);
/// let q = DVector::from_vec(vec![0.0, 1.0, 2.5]);
/// assert_eq!(rods.values(&q).as_slice(), [0.0, 0.5]);
/// assert!(rods.local().is_some());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SparseConstraints<C>(pub C);

impl<C: LocalConstraints> Constraints<Dyn> for SparseConstraints<C> {
    fn count(&self) -> usize {
        self.0.count()
    }

    #[inline]
    fn constraints<D: Scalar>(&self, q: &DVector<D>, g: &mut [D]) {
        let q = q.as_slice();
        for (i, gi) in g.iter_mut().enumerate() {
            let indices = self.0.indices(i);
            let indices = indices.as_ref();
            let local = C::Width::vector(|a| coordinate(q, indices[a]));
            *gi = self.0.constraint(i, &local);
        }
    }

    fn constraint_name(&self, index: usize) -> String {
        self.0.constraint_name(index)
    }

    fn local(&self) -> Option<&dyn ConstraintRows> {
        Some(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::constraint::ConstraintsExt;
    use nalgebra::{Const, SVector};

    /// Distances of consecutive points of the plane, the last constraint repeating a slot.
    struct Links;

    impl LocalConstraints for Links {
        type Width = Const<4>;
        fn count(&self) -> usize {
            3
        }
        fn indices(&self, i: usize) -> [usize; 4] {
            if i == 2 {
                [0, 0, 5, 5]
            } else {
                [2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3]
            }
        }
        fn constraint<D: Scalar>(&self, i: usize, q: &SVector<D, 4>) -> D {
            if i == 2 {
                // x₀ y₂ − 1, reading slots 0 and 3 only.
                return q[0] * q[3] - D::from(1.0);
            }
            let (dx, dy) = (q[2] - q[0], q[3] - q[1]);
            dx * dx + dy * dy - D::from(1.0)
        }
    }

    /// The rows' values and Jacobian entries, scattered into a dense matrix (repeated slots
    /// adding up), equal the dense path's of the same constraints.
    #[test]
    fn rows_equal_the_dense_values_and_jacobian() {
        let constraints = SparseConstraints(Links);
        let q = DVector::from_vec(vec![0.1, 0.2, 0.9, -0.3, 1.4, 0.8]);
        let rows = constraints.local().unwrap();
        let (m, k) = (rows.count(), rows.width());
        let mut g = vec![0.0; m];
        rows.values_into(q.as_slice(), &mut g);
        assert_eq!(g.as_slice(), constraints.values(&q).as_slice());
        let (mut columns, mut entries) = (vec![0; m * k], vec![0.0; m * k]);
        rows.columns_into(&mut columns);
        rows.jacobian_into(q.as_slice(), &mut entries);
        let mut scattered = nalgebra::DMatrix::zeros(m, q.len());
        for (e, (&c, &value)) in columns.iter().zip(&entries).enumerate() {
            scattered[(e / k, c)] += value;
        }
        let dense = constraints.jacobian(&q);
        assert!((scattered - &dense).amax() < 1e-15, "{dense}");
        assert_eq!(dense[(2, 0)], 0.8);
        assert_eq!(dense[(2, 5)], 0.1);
    }

    /// A coordinate outside q makes the constraint NaN, not a panic.
    #[test]
    fn indices_outside_q_give_nan() {
        let q = DVector::from_vec(vec![0.0; 4]);
        let g = SparseConstraints(Links).values(&q);
        assert!(g[0].is_finite() && g[1].is_nan() && g[2].is_nan(), "{g}");
    }
}
