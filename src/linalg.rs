//! Small dense linear solves without allocation.
//!
//! - [`solve_small`]: Gaussian elimination with partial pivoting on a fixed-size N×N system,
//!   generic over [`Scalar`] so it also runs on dual numbers (nalgebra's `.lu()` needs
//!   `RealField` and `DimMin` bounds that nested duals and generic code do not have).
//! - [`compensated_add`]: Kahan-compensated accumulation, for the stepping loop's sums of
//!   increments over long runs.
//! - `combination` (inside the crate): SVI's stage sums, many rows of linear combinations of
//!   vectors at once.
//! - [`DenseLu`]: an LU factorisation with partial pivoting of a runtime-sized matrix held in
//!   a buffer allocated once per run; factor and solve allocate nothing. The Newton systems of
//!   the spectral methods are (N·s)-sized, with s chosen at run time.

pub(crate) mod combination;
pub mod sparse;

use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DMatrixView, DVector, DefaultAllocator, Dim, OMatrix, OVector, U1};

/// Solve A x = b for a small system (of fixed or run-time size); `None` if A is singular (a
/// zero pivot) or the result is not finite.
pub fn solve_small<D: Scalar, N: Dim>(
    mut a: OMatrix<D, N, N>,
    mut b: OVector<D, N>,
) -> Option<OVector<D, N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = b.len();
    for k in 0..n {
        let mut pivot = k;
        let mut largest = a[(k, k)].re().abs();
        for i in k + 1..n {
            let size = a[(i, k)].re().abs();
            if size > largest {
                largest = size;
                pivot = i;
            }
        }
        if largest == 0.0 || !largest.is_finite() {
            return None;
        }
        if pivot != k {
            a.swap_rows(k, pivot);
            b.swap_rows(k, pivot);
        }
        let inverse = a[(k, k)].recip();
        for i in k + 1..n {
            let factor = a[(i, k)] * inverse;
            for j in k + 1..n {
                let update = factor * a[(k, j)];
                a[(i, j)] -= update;
            }
            let update = factor * b[k];
            b[i] -= update;
        }
    }
    for k in (0..n).rev() {
        let mut sum = b[k];
        for j in k + 1..n {
            sum -= a[(k, j)] * b[j];
        }
        b[k] = sum / a[(k, k)];
    }
    b.iter().all(|x| x.re().is_finite()).then_some(b)
}

/// The inverse of a small matrix (of fixed or run-time size), or `None` if it is singular.
pub fn invert_small<N: Dim>(a: &OMatrix<f64, N, N>) -> Option<OMatrix<f64, N, N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (n, _) = a.shape_generic();
    let mut inverse = OMatrix::zeros_generic(n, n);
    for j in 0..n.value() {
        let unit = OVector::from_fn_generic(n, U1, |i, _| f64::from(i == j));
        let column = solve_small(a.clone(), unit)?;
        inverse.set_column(j, &column);
    }
    Some(inverse)
}

/// The inverse of a square runtime-sized matrix (set-up work, not for inner loops).
pub fn invert(a: &DMatrix<f64>) -> Result<DMatrix<f64>, Singular> {
    let mut lu = DenseLu::new(a.nrows());
    lu.matrix_mut().copy_from(a);
    lu.factor()?;
    let mut inverse = DMatrix::identity(a.nrows(), a.nrows());
    lu.solve_columns_in_place(&mut inverse);
    Ok(inverse)
}

/// The matrix was singular to working precision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Singular;

/// LU factorisation with partial pivoting of a square runtime-sized matrix, in place.
#[derive(Debug, Clone)]
pub struct DenseLu {
    factors: DMatrix<f64>,
    pivots: Vec<usize>,
}

impl DenseLu {
    /// Workspace for `size`×`size` systems; the matrix is allocated at its first use
    /// ([`DenseLu::matrix_mut`]), so a Newton iteration that never runs costs no n² memory.
    pub fn new(size: usize) -> Self {
        DenseLu {
            factors: DMatrix::zeros(0, 0),
            pivots: vec![0; size],
        }
    }

    /// Size of the systems this workspace solves.
    pub fn size(&self) -> usize {
        self.pivots.len()
    }

    /// The matrix to be factored; fill it, then call [`DenseLu::factor`].
    pub fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        let n = self.size();
        if self.factors.nrows() != n {
            self.factors = DMatrix::zeros(n, n);
        }
        &mut self.factors
    }

    /// Factor the matrix previously written through [`DenseLu::matrix_mut`].
    pub fn factor(&mut self) -> Result<(), Singular> {
        let n = self.size();
        let a = &mut self.factors;
        for k in 0..n {
            let mut pivot = k;
            let mut largest = a[(k, k)].abs();
            for i in k + 1..n {
                let size = a[(i, k)].abs();
                if size > largest {
                    largest = size;
                    pivot = i;
                }
            }
            if largest == 0.0 || !largest.is_finite() {
                return Err(Singular);
            }
            self.pivots[k] = pivot;
            if pivot != k {
                a.swap_rows(k, pivot);
            }
            let inverse = 1.0 / a[(k, k)];
            for i in k + 1..n {
                a[(i, k)] *= inverse;
            }
            for j in k + 1..n {
                let akj = a[(k, j)];
                if akj != 0.0 {
                    for i in k + 1..n {
                        a[(i, j)] -= a[(i, k)] * akj;
                    }
                }
            }
        }
        Ok(())
    }

    /// Solve A x = b in place (`b` becomes x) with the current factors.
    pub fn solve_in_place(&self, b: &mut DVector<f64>) {
        let n = self.size();
        let a = &self.factors;
        for k in 0..n {
            b.swap_rows(k, self.pivots[k]);
        }
        for j in 0..n {
            let bj = b[j];
            if bj != 0.0 {
                for i in j + 1..n {
                    b[i] -= a[(i, j)] * bj;
                }
            }
        }
        for j in (0..n).rev() {
            b[j] /= a[(j, j)];
            let bj = b[j];
            for i in 0..j {
                b[i] -= a[(i, j)] * bj;
            }
        }
    }

    /// Solve A X = B in place for every column of `b`.
    pub fn solve_columns_in_place(&self, b: &mut DMatrix<f64>) {
        let mut column = DVector::zeros(self.size());
        for j in 0..b.ncols() {
            column.copy_from(&b.column(j));
            self.solve_in_place(&mut column);
            b.set_column(j, &column);
        }
    }
}

/// An owned matrix of any dimensions as a view of run-time size (for products with dynamic
/// matrices without copying it).
pub fn dynamic_view<R: Dim, C: Dim>(matrix: &OMatrix<f64, R, C>) -> DMatrixView<'_, f64>
where
    DefaultAllocator: Allocator<R, C>,
{
    DMatrixView::from_slice(matrix.as_slice(), matrix.nrows(), matrix.ncols())
}

/// Kahan-compensated `sum += increment`, entry by entry.
pub fn compensated_add(sum: &mut [f64], compensation: &mut [f64], increment: &[f64]) {
    for ((s, c), i) in sum.iter_mut().zip(compensation.iter_mut()).zip(increment) {
        let y = i - *c;
        let t = *s + y;
        *c = (t - *s) - y;
        *s = t;
    }
}

/// The largest `size` and whether every `ok` holds, over `(size, ok) = entry(xᵢ)` where xᵢ
/// holds the i-th entries of the M `slices` (of one length): the reductions of a read-only
/// pass over runtime-sized vectors (a step's extent and checks).
///
/// Runs over four independent lanes of fixed-size chunks, so that the maximum vectorises (a
/// single running maximum is a floating-point reduction the compiler may not reorder) and no
/// entry needs a bounds check. A NaN `size` is ignored by the maximum: let `ok` catch it.
#[inline(always)]
pub fn lane_extent<const M: usize>(
    slices: [&[f64]; M],
    entry: impl Fn([f64; M]) -> (f64, bool),
) -> (f64, bool) {
    const LANES: usize = 4;
    let n = slices.iter().map(|s| s.len()).min().unwrap_or(0);
    let chunks = slices.map(|s| s[..n].as_chunks::<LANES>().0);
    let (mut norm, mut all) = ([0.0f64; LANES], [true; LANES]);
    for c in 0..n / LANES {
        let block = chunks.map(|s| s[c]);
        for l in 0..LANES {
            let (size, ok) = entry(block.map(|b| b[l]));
            all[l] &= ok;
            norm[l] = if size > norm[l] { size } else { norm[l] };
        }
    }
    for i in n - n % LANES..n {
        let (size, ok) = entry(slices.map(|s| s[i]));
        all[0] &= ok;
        norm[0] = if size > norm[0] { size } else { norm[0] };
    }
    (
        norm.iter().fold(0.0, |m: f64, x| m.max(*x)),
        all.iter().all(|a| *a),
    )
}

/// The largest |s + (δ − c)| over the entries of a compensated addition
/// ([`compensated_add`]) not yet made, and whether every such sum is finite: the check
/// before a step's increment is added.
pub fn compensated_sum_extent(sum: &[f64], compensation: &[f64], increment: &[f64]) -> (f64, bool) {
    lane_extent([sum, compensation, increment], |[s, c, d]| {
        let t = (s + (d - c)).abs();
        (t, t <= f64::MAX)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{SMatrix, SVector};
    use num_dual::{DualNum, DualSVec64, jacobian};

    #[test]
    fn compensated_sum_extent_finds_the_largest_sum_and_any_non_finite_one_in_every_lane() {
        // Seven entries: four lanes and a tail of three.
        let s = [1.0, -2.0, 0.5, 0.0, 3.0, -1.0, 0.25];
        let c = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let d = [0.5, -1.0, 0.0, 0.1, -7.0, 0.0, 0.0];
        // s + (d − c): 1.5, −3, 0.5, 0.1, −4, −1, −0.75.
        assert_eq!(compensated_sum_extent(&s, &c, &d), (4.0, true));
        for i in 0..s.len() {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut d = d;
                d[i] = bad;
                assert!(!compensated_sum_extent(&s, &c, &d).1, "entry {i}, {bad}");
            }
        }
        assert_eq!(compensated_sum_extent(&[], &[], &[]), (0.0, true));
    }

    #[test]
    fn small_solve_matches_known_solution_and_needs_pivoting() {
        // First pivot is zero: partial pivoting is required.
        let a = SMatrix::<f64, 3, 3>::new(0.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0);
        let x = SVector::from([1.0, -2.0, 3.0]);
        let solved = solve_small(a, a * x).unwrap();
        assert_relative_eq!(solved, x, epsilon = 1e-14);
        assert!(solve_small(SMatrix::<f64, 2, 2>::zeros(), SVector::from([1.0, 1.0])).is_none());
    }

    #[test]
    fn small_solve_propagates_derivatives() {
        // d/dθ of A(θ)⁻¹ b equals −A⁻¹ A' A⁻¹ b.
        let theta = SVector::from([0.3]);
        let (_, derivative) = jacobian(
            |p: SVector<DualSVec64<1>, 1>| {
                let s = p[0];
                let a =
                    SMatrix::<DualSVec64<1>, 2, 2>::new(s.cos() + 2.0, s, s.sin(), (s * s) + 3.0);
                solve_small(a, SVector::from([1.0.into(), 2.0.into()])).unwrap()
            },
            &theta,
        );
        let s: f64 = 0.3;
        let a = SMatrix::<f64, 2, 2>::new(s.cos() + 2.0, s, s.sin(), s * s + 3.0);
        let da = SMatrix::<f64, 2, 2>::new(-s.sin(), 1.0, s.cos(), 2.0 * s);
        let ai = a.try_inverse().unwrap();
        let expected = -ai * da * ai * SVector::from([1.0, 2.0]);
        assert_relative_eq!(derivative.column(0).into_owned(), expected, epsilon = 1e-14);
    }

    #[test]
    fn dense_lu_solves_random_systems() {
        let n = 12;
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let a = DMatrix::from_fn(n, n, |_, _| next());
        let x = DVector::from_fn(n, |_, _| next());
        let mut lu = DenseLu::new(n);
        lu.matrix_mut().copy_from(&a);
        lu.factor().unwrap();
        let mut b = &a * &x;
        lu.solve_in_place(&mut b);
        assert_relative_eq!(b, x, epsilon = 1e-12);
        lu.matrix_mut().fill(0.0);
        assert_eq!(lu.factor(), Err(Singular));
        let inverse = invert(&a).unwrap();
        assert_relative_eq!(&a * inverse, DMatrix::identity(n, n), epsilon = 1e-12);
        let small = SMatrix::<f64, 2, 2>::new(2.0, 1.0, 1.0, 3.0);
        assert_relative_eq!(
            small * invert_small(&small).unwrap(),
            SMatrix::identity(),
            epsilon = 1e-15
        );
    }

    #[test]
    fn compensated_summation_keeps_small_increments() {
        let mut sum = [1.0];
        let mut compensation = [0.0];
        for _ in 0..1_000_000 {
            compensated_add(&mut sum, &mut compensation, &[1e-16]);
        }
        assert!((sum[0] - (1.0 + 1e-10)).abs() < 1e-15);
    }
}
