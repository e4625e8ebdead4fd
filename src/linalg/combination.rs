//! Rows of linear combinations of vectors, all at once: `targets[μ]` = start_μ + c_μ x +
//! Σ_ν A_μν `inputs[ν]` — SVI's stage sums (the positions, velocities and extrapolated
//! positions at the quadrature points from the accelerations there), a small matrix product
//! whose "entries" are vectors of the configuration space.
//!
//! # How
//!
//! A row summed on its own is a chain of additions, each waiting on the one before. The rows
//! are summed [`TILE`] at a time instead, each input read once for all of them: independent
//! chains that the processor runs side by side (`cargo bench --bench text`,
//! `kepler_T2000`: 12 rows of 2 coordinates). A fixed size, or a run-time size up to
//! [`MAX_REGISTER_WIDTH`], keeps the sums in registers (one kernel, compiled for each width);
//! a larger run-time size sums row by row in blocks of [`SUM_BLOCK`] coordinates in a buffer
//! that stays in the first-level cache (`fput_chain/svi`: n = 10⁵). Every way adds in the
//! same order (the start, the lead term, then ν = 0, 1, …), so all give the same digits.
//!
//! The kernel is chosen by the dimension type ([`crate::dimension::Dimension`] requires
//! [`Combination`]): compiled once for every run-time-size model, not once per model.

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, Dyn, OVector};

/// Where each row of a [`Combination::combine_rows`] starts.
#[derive(Debug, Clone, Copy)]
pub enum Start<'a, N: Dim>
where
    DefaultAllocator: Allocator<N>,
{
    /// Zero.
    Zero,
    /// The same vector for every row.
    Common(&'a OVector<f64, N>),
    /// One vector per row.
    Rows(&'a [OVector<f64, N>]),
}

impl<'a, N: Dim> Start<'a, N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Row `row`'s start, as a slice (`None`: zero).
    #[inline(always)]
    fn row(self, row: usize) -> Option<&'a [f64]> {
        match self {
            Start::Zero => None,
            Start::Common(x) => Some(x.as_slice()),
            Start::Rows(rows) => Some(rows[row].as_slice()),
        }
    }
}

/// The operands of a [`Combination::combine_rows`]: row μ is start_μ + c_μ x + Σ_ν A_μν
/// `inputs[ν]`.
#[derive(Debug, Clone, Copy)]
pub struct Rows<'a, N: Dim>
where
    DefaultAllocator: Allocator<N>,
{
    /// Where each row starts.
    pub start: Start<'a, N>,
    /// The lead term: the coefficients c_μ and the vector x (optional).
    pub lead: Option<(&'a [f64], &'a OVector<f64, N>)>,
    /// A, row-major, one column per input, at least one row per target.
    pub matrix: &'a [f64],
    /// The vectors combined.
    pub inputs: &'a [OVector<f64, N>],
}

/// The largest change of any coordinate of a [`Combination::combine_rows`] (NaN ignored), and
/// whether every new value is finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// max |new − old| over the coordinates of every row.
    pub largest: f64,
    /// Whether every new value is finite.
    pub finite: bool,
}

impl Change {
    /// No change yet.
    const NONE: Change = Change {
        largest: 0.0,
        finite: true,
    };

    /// Take the change of one coordinate from `old` to `new` into account (plain comparisons:
    /// a NaN is caught by `finite`).
    #[inline(always)]
    fn record(&mut self, old: f64, new: f64) {
        let difference = (new - old).abs();
        if difference > self.largest {
            self.largest = difference;
        }
        self.finite &= new.is_finite();
    }
}

/// The stage sums at a dimension (see the [module docs](self)).
pub trait Combination: Dim {
    /// `targets[μ]` = row μ of `rows` for every μ; returns the change from the old targets.
    fn combine_rows(targets: &mut [OVector<f64, Self>], rows: Rows<'_, Self>) -> Change
    where
        DefaultAllocator: Allocator<Self>;
}

/// Rows summed together.
pub const TILE: usize = 4;

/// The largest run-time size summed in registers.
pub const MAX_REGISTER_WIDTH: usize = 8;

/// The coordinates of a block of a larger run-time size.
pub const SUM_BLOCK: usize = 1024;

impl<const K: usize> Combination for Const<K> {
    #[inline(always)]
    fn combine_rows(targets: &mut [OVector<f64, Self>], rows: Rows<'_, Self>) -> Change {
        in_registers::<Self, K>(targets, rows)
    }
}

impl Combination for Dyn {
    fn combine_rows(targets: &mut [OVector<f64, Self>], rows: Rows<'_, Self>) -> Change {
        let n = targets.first().map_or(0, |target| target.len());
        if n > MAX_REGISTER_WIDTH {
            return in_blocks(targets, rows);
        }
        // One arm per width up to `MAX_REGISTER_WIDTH` (the unit test runs the largest).
        match n {
            1 => in_registers::<Self, 1>(targets, rows),
            2 => in_registers::<Self, 2>(targets, rows),
            3 => in_registers::<Self, 3>(targets, rows),
            4 => in_registers::<Self, 4>(targets, rows),
            5 => in_registers::<Self, 5>(targets, rows),
            6 => in_registers::<Self, 6>(targets, rows),
            7 => in_registers::<Self, 7>(targets, rows),
            8 => in_registers::<Self, 8>(targets, rows),
            _ => Change::NONE,
        }
    }
}

/// The first `K` entries of `x` as an array (every vector of a combination has `K`).
#[inline(always)]
fn entries<const K: usize>(x: &[f64]) -> [f64; K] {
    std::array::from_fn(|i| x[i])
}

/// [`Combination::combine_rows`] on vectors of `K` coordinates: [`TILE`] rows at a time,
/// their sums in registers, then the rows left over two at a time and one.
#[inline(always)]
fn in_registers<N: Dim, const K: usize>(
    targets: &mut [OVector<f64, N>],
    rows: Rows<'_, N>,
) -> Change
where
    DefaultAllocator: Allocator<N>,
{
    let mut change = Change::NONE;
    let whole = targets.len() / TILE * TILE;
    let (tiles, rest) = targets.split_at_mut(whole);
    for (tile, targets) in tiles.chunks_exact_mut(TILE).enumerate() {
        tile_in_registers::<N, K, TILE>(targets, tile * TILE, rows, &mut change);
    }
    // The rows left over in pairs, then one.
    let pairs = rest.len() / 2 * 2;
    let (rest, last) = rest.split_at_mut(pairs);
    for (pair, targets) in rest.chunks_exact_mut(2).enumerate() {
        tile_in_registers::<N, K, 2>(targets, whole + 2 * pair, rows, &mut change);
    }
    if let [target] = last {
        let target = std::slice::from_mut(target);
        tile_in_registers::<N, K, 1>(target, whole + pairs, rows, &mut change);
    }
    change
}

/// The `T` rows `first..first + T` (`targets`) of vectors of `K` coordinates, their sums
/// in registers.
#[inline(always)]
fn tile_in_registers<N: Dim, const K: usize, const T: usize>(
    targets: &mut [OVector<f64, N>],
    first: usize,
    rows: Rows<'_, N>,
    change: &mut Change,
) where
    DefaultAllocator: Allocator<N>,
{
    let Rows {
        start,
        lead,
        matrix,
        inputs,
    } = rows;
    let m = inputs.len();
    let coefficients: [&[f64]; T] = std::array::from_fn(|r| &matrix[(first + r) * m..][..m]);
    let mut sums: [[f64; K]; T] =
        std::array::from_fn(|r| start.row(first + r).map_or([0.0; K], entries));
    if let Some((c, x)) = lead {
        let x = entries::<K>(x.as_slice());
        for (r, sum) in sums.iter_mut().enumerate() {
            let c = c[first + r];
            for (total, x) in sum.iter_mut().zip(x) {
                *total += c * x;
            }
        }
    }
    for (nu, x) in inputs.iter().enumerate() {
        let x = entries::<K>(x.as_slice());
        for (sum, row) in sums.iter_mut().zip(coefficients) {
            let c = row[nu];
            for (total, x) in sum.iter_mut().zip(x) {
                *total += c * x;
            }
        }
    }
    for (target, sum) in targets.iter_mut().zip(sums) {
        for (old, new) in target.as_mut_slice().iter_mut().zip(sum) {
            change.record(*old, new);
            *old = new;
        }
    }
}

/// [`Combination::combine_rows`] on vectors of many coordinates: row by row, in blocks of
/// [`SUM_BLOCK`], each summed input by input in a buffer on the stack (apart, so that the
/// smaller sizes do not set up its stack frame).
#[inline(never)]
fn in_blocks(targets: &mut [OVector<f64, Dyn>], rows: Rows<'_, Dyn>) -> Change {
    let mut change = Change::NONE;
    let m = rows.inputs.len();
    let mut buffer = [0.0; SUM_BLOCK];
    for (row, target) in targets.iter_mut().enumerate() {
        let coefficients = &rows.matrix[row * m..][..m];
        let lead = rows.lead.map(|(c, x)| (c[row], x));
        let n = target.len();
        for begin in (0..n).step_by(SUM_BLOCK) {
            let block = begin..(begin + SUM_BLOCK).min(n);
            let sum = &mut buffer[..block.len()];
            match rows.start.row(row) {
                None => sum.fill(0.0),
                Some(x) => sum.copy_from_slice(&x[block.clone()]),
            }
            for (c, x) in lead
                .into_iter()
                .chain(coefficients.iter().copied().zip(rows.inputs))
            {
                for (total, x) in sum.iter_mut().zip(&x.as_slice()[block.clone()]) {
                    *total += c * x;
                }
            }
            for (old, new) in target.as_mut_slice()[block].iter_mut().zip(sum.iter()) {
                change.record(*old, *new);
                *old = *new;
            }
        }
    }
    change
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::U1;

    /// The stage sums add in one order whichever way they run (a fixed size, a few run-time
    /// coordinates in registers, many in blocks with a partial last one; rows in tiles and
    /// one by one): the digits of the plain loop start + c x + A₁x₁ + A₂x₂ + …, and the
    /// change is the largest of the plain differences.
    #[test]
    fn stage_sums_have_the_plain_loops_digits_at_every_size() {
        fn vector<N: Dim>(n: N, seed: f64) -> OVector<f64, N>
        where
            DefaultAllocator: Allocator<N>,
        {
            OVector::from_fn_generic(n, U1, |i, _| (seed * (i as f64 + 1.0)).sin() / 3.0)
        }
        fn check<N: Combination>(n: N)
        where
            DefaultAllocator: Allocator<N>,
        {
            // Seven rows: a whole tile, a pair and a row alone; twelve inputs.
            let (rows, m) = (TILE + 3, 12);
            let inputs: Vec<_> = (0..m).map(|j| vector(n, 1.3 + j as f64)).collect();
            let matrix: Vec<f64> = (0..rows * m).map(|k| 0.1 / (k as f64 + 1.0)).collect();
            let starts: Vec<_> = (0..rows).map(|r| vector(n, 0.7 + r as f64)).collect();
            let c: Vec<f64> = (0..rows).map(|r| 0.3 - r as f64).collect();
            let x = vector(n, 5.1);
            let plain = |row: usize, mut sum: OVector<f64, N>, lead: bool| {
                if lead {
                    for (total, x) in sum.iter_mut().zip(&x) {
                        *total += c[row] * x;
                    }
                }
                for (a, input) in matrix[row * m..(row + 1) * m].iter().zip(&inputs) {
                    for (total, x) in sum.iter_mut().zip(input) {
                        *total += a * x;
                    }
                }
                sum
            };
            let zero = &starts[0] * 0.0;
            let cases = [
                (Start::Rows(&starts), false),
                (Start::Common(&starts[1]), true),
                (Start::Zero, true),
            ];
            for (start, lead) in cases {
                let expected: Vec<_> = (0..rows)
                    .map(|r| match start {
                        Start::Rows(starts) => plain(r, starts[r].clone(), lead),
                        Start::Common(x) => plain(r, x.clone(), lead),
                        Start::Zero => plain(r, zero.clone(), lead),
                    })
                    .collect();
                let mut targets: Vec<_> = (0..rows).map(|r| vector(n, 2.9 + r as f64)).collect();
                let largest = targets
                    .iter()
                    .zip(&expected)
                    .map(|(old, new)| (new - old).amax())
                    .fold(0.0, f64::max);
                let rows = Rows {
                    start,
                    lead: lead.then_some((c.as_slice(), &x)),
                    matrix: &matrix,
                    inputs: &inputs,
                };
                let change = N::combine_rows(&mut targets, rows);
                assert_eq!(targets, expected, "n = {}", n.value());
                assert_eq!(
                    change,
                    Change {
                        largest,
                        finite: true
                    }
                );
            }
            // A non-finite input is reported, whatever the size.
            let mut inputs = inputs;
            inputs[3][n.value() - 1] = f64::NAN;
            let mut targets = starts.clone();
            let rows = Rows {
                start: Start::Zero,
                lead: None,
                matrix: &matrix,
                inputs: &inputs,
            };
            let change = N::combine_rows(&mut targets, rows);
            assert!(!change.finite);
        }
        check(Const::<3>);
        for n in [
            1,
            MAX_REGISTER_WIDTH,
            MAX_REGISTER_WIDTH + 1,
            2 * SUM_BLOCK + 37,
        ] {
            check(Dyn(n));
        }
    }
}
