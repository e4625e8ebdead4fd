//! The shared layout of the chains with both ends held (`fput`, `relativistic-chain`,
//! `sine-gordon-chain`): n moving particles 0..n−1 and n + 1 springs, spring e joining
//! particles e − 1 and e, the walls standing in for particles −1 and n. Term e of such a
//! chain is spring e and particle e (the last spring carries no particle).

use nalgebra::SVector;
use svi::Scalar;

/// The index set of spring e: its two particles, a wall's slot repeating its neighbour's
/// index (and ignored by [`spring_ends`]).
#[inline]
pub(crate) fn spring_indices(e: usize, n: usize) -> [usize; 2] {
    [e.saturating_sub(1), e.min(n - 1)]
}

/// The positions (left, right) of spring e's ends from its term's coordinates `q`, with the
/// walls at `walls` = (left wall, right wall).
#[inline]
pub(crate) fn spring_ends<D: Scalar>(
    e: usize,
    n: usize,
    q: &SVector<D, 2>,
    walls: (f64, f64),
) -> (D, D) {
    if e == 0 {
        (D::from(walls.0), q[1])
    } else if e == n {
        (q[0], D::from(walls.1))
    } else {
        (q[0], q[1])
    }
}
