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
