//! Variational integrators: methods defined by a discrete Lagrangian L_d(q_k, q_{k+1}) ≈ ∫ L dt
//! through the discrete Euler–Lagrange equations (Li–Wu–Leok eq. 5), so every one of them is
//! symplectic and conserves the Noether momenta of the symmetries of L.
//!
//! - [`svi`]: the Galerkin spectral variational integrator (eqs. 6–11), L_d from a polynomial
//!   on Chebyshev–Gauss–Lobatto points and Gauss–Legendre quadrature.
//! - `tables`: a Galerkin integrator's basis and quadrature tables, shared by SVI and the
//!   sparse Newton of the classic discrete Lagrangians.
//! - [`discrete_lagrangian`]: the classic discrete Lagrangians (symplectic Euler and its
//!   adjoint, midpoint, trapezoid) as plain data.
//! - [`variational_integrator`]: one discrete Euler–Lagrange solver for any of them, implicit
//!   (Newton) or, for a constant mass and a rule on the end points, explicit:
//! - [`kick_drift_kick`]: the explicit step of symplectic Euler, its adjoint and
//!   Störmer–Verlet on a constant-mass Lagrangian.
//! - `stage_newton`: sparse Newton on the stage equations of a sum of local terms, for SVI
//!   and the classic variational integrators.
//! - [`stormer_verlet`]: the trapezoidal rule, explicit (kick–drift–kick) for a constant mass.
//! - [`composition`]: symmetric compositions of Störmer–Verlet of orders 4, 6 and 8.

pub mod composition;
pub mod discrete_lagrangian;
pub mod kick_drift_kick;
pub(crate) mod stage_newton;
pub mod stormer_verlet;
pub mod svi;
pub(crate) mod tables;
pub mod variational_integrator;
