//! Bases and quadrature shared by the spectral methods ([`crate::Svi`],
//! [`crate::SpectralCollocation`], [`crate::lie_group::LieSvi`]) and their one limit on the
//! number of points.
//!
//! - [`basis`]: Chebyshev–Gauss–Lobatto nodes and barycentric Lagrange interpolation (the
//!   interpolation and differentiation matrices of Li–Wu–Leok eqs. 6–7 and 17).
//! - [`quadrature`]: Gauss–Legendre rules (the quadrature of the discrete action, eq. 8).
//! - `starting_values`: the previous step's polynomial extrapolated to the next step's nodes,
//!   the start of every nonlinear iteration.

pub mod basis;
pub mod quadrature;
pub(crate) mod starting_values;

use crate::error::Error;

/// Largest number of interpolation points (CGL points, polynomial degree + 1) and of
/// Gauss–Legendre points anywhere in the library: the bases, the quadrature rules, every
/// spectral method, degree adaptivity and the stability analysis.
pub const MAX_POINTS: usize = 256;

/// Check the options the spectral methods share: 2 to [`MAX_POINTS`] CGL points, 1 to
/// [`MAX_POINTS`] Gauss points (for methods with a quadrature) and at least one iteration.
pub(crate) fn check_options(
    points: usize,
    quadrature: Option<usize>,
    max_iterations: usize,
) -> Result<(), Error> {
    if !(2..=MAX_POINTS).contains(&points) {
        return Err(Error::invalid(
            "points",
            format!("{points} CGL points; need 2 to {MAX_POINTS}"),
        ));
    }
    if let Some(m) = quadrature.filter(|m| !(1..=MAX_POINTS).contains(m)) {
        return Err(Error::invalid(
            "quadrature",
            format!("{m} Gauss points; need 1 to {MAX_POINTS}"),
        ));
    }
    if max_iterations == 0 {
        return Err(Error::invalid("max_iterations", "must be at least 1"));
    }
    Ok(())
}
