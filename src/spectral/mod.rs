//! Bases and quadrature shared by the spectral methods ([`crate::Svi`],
//! [`crate::SpectralCollocation`], [`crate::lie_group::LieSvi`]) and their one limit on the
//! number of points.
//!
//! - [`basis`]: Chebyshev–Gauss–Lobatto nodes and barycentric Lagrange interpolation (the
//!   interpolation and differentiation matrices of Li–Wu–Leok eqs. 6–7 and 17).
//! - [`quadrature`]: Gauss–Legendre rules (the quadrature of the discrete action, eq. 8).
//! - [`filon`]: Filon–Lobatto rules for ∫ f(x) e^{iθx} dx with θ-dependent weights (the
//!   oscillatory discrete action of the multiscale integrator, Leok 2004 §5.7.2).
//! - `starting_values`: the previous step's polynomial extrapolated to the next step's nodes,
//!   the start of every nonlinear iteration.

pub mod basis;
pub mod filon;
pub mod quadrature;
pub(crate) mod starting_values;

use crate::error::Error;

/// Largest number of interpolation points (CGL points, polynomial degree + 1) and of
/// Gauss–Legendre points anywhere in the library: the bases, the quadrature rules, every
/// spectral method, degree adaptivity and the stability analysis.
pub const MAX_POINTS: usize = 256;

/// Scratch numbers of one evaluation of a basis (at most [`MAX_POINTS`]): on the stack for the
/// point counts used in practice (up to [`Scratch::STACK`]), on the heap beyond — so that the
/// dense output, called K times per step, clears 256 bytes instead of a [`MAX_POINTS`] array.
pub(crate) struct Scratch {
    stack: [f64; Scratch::STACK],
    /// Empty (no allocation) unless more than [`Scratch::STACK`] numbers are asked for.
    heap: Vec<f64>,
    len: usize,
}

impl Scratch {
    /// The most numbers kept on the stack.
    pub(crate) const STACK: usize = 32;

    /// `len` zeros.
    pub(crate) fn zeros(len: usize) -> Self {
        Scratch {
            stack: [0.0; Self::STACK],
            heap: if len > Self::STACK {
                vec![0.0; len]
            } else {
                Vec::new()
            },
            len,
        }
    }
}

impl std::ops::Deref for Scratch {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        if self.len > Self::STACK {
            &self.heap
        } else {
            &self.stack[..self.len]
        }
    }
}

impl std::ops::DerefMut for Scratch {
    fn deref_mut(&mut self) -> &mut [f64] {
        if self.len > Self::STACK {
            &mut self.heap
        } else {
            &mut self.stack[..self.len]
        }
    }
}

/// Check a number of CGL points: 2 to [`MAX_POINTS`]. An error names `points`.
pub fn check_points(points: usize) -> Result<(), Error> {
    if (2..=MAX_POINTS).contains(&points) {
        Ok(())
    } else {
        Err(Error::invalid(
            "points",
            format!("{points} CGL points; need 2 to {MAX_POINTS}"),
        ))
    }
}

/// Check a number of Gauss points `m` for a Galerkin method with `points` CGL points: 1 to
/// [`MAX_POINTS`], and at least the degree s = points − 1. An error names `quadrature`.
///
/// Below the degree the discrete Lagrangian is degenerate: an internal variation δq(τ) of
/// degree s vanishes at τ = ±1, so its derivative (degree s − 1) has zero mean; with m = s − 1
/// Gauss points it can be c·P_{s−1}, the Legendre polynomial vanishing at all of them, and the
/// quadrature of the kinetic energy does not see it. The stage equations are then singular up
/// to the O(h²) potential terms, and fewer points make it worse.
pub fn check_quadrature(points: usize, m: usize) -> Result<(), Error> {
    if !(1..=MAX_POINTS).contains(&m) {
        return Err(Error::invalid(
            "quadrature",
            format!("{m} Gauss points; need 1 to {MAX_POINTS}"),
        ));
    }
    let degree = points.saturating_sub(1);
    if m < degree {
        return Err(Error::invalid(
            "quadrature",
            format!(
                "{m} Gauss points for {points} CGL points: below points − 1 = {degree} the \
                 discrete Lagrangian is degenerate (its kinetic term misses a variation of \
                 degree {degree}); use at least {degree}"
            ),
        ));
    }
    Ok(())
}

/// Check the options the spectral methods share: the CGL points ([`check_points`]), the Gauss
/// points of methods with a quadrature ([`check_quadrature`]) and at least one iteration.
pub(crate) fn check_options(
    points: usize,
    quadrature: Option<usize>,
    max_iterations: usize,
) -> Result<(), Error> {
    check_points(points)?;
    if let Some(m) = quadrature {
        check_quadrature(points, m)?;
    }
    if max_iterations == 0 {
        return Err(Error::invalid("max_iterations", "must be at least 1"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scratch of every size: zeros, writable, of the length asked for, on the stack up to
    /// `STACK` and on the heap beyond.
    #[test]
    fn scratch_has_the_length_asked_for_on_either_side_of_the_stack_size() {
        for len in [0, 1, Scratch::STACK, Scratch::STACK + 1, MAX_POINTS] {
            let mut scratch = Scratch::zeros(len);
            assert_eq!(scratch.len(), len);
            assert!(scratch.iter().all(|&x| x == 0.0));
            scratch
                .iter_mut()
                .enumerate()
                .for_each(|(i, x)| *x = i as f64);
            assert_eq!(
                scratch.last().copied(),
                len.checked_sub(1).map(|i| i as f64)
            );
            assert_eq!(scratch.heap.is_empty(), len <= Scratch::STACK);
        }
    }
}
