//! The scalar type a Lagrangian is written in.
//!
//! A model is written once, generic over [`Scalar`]; `svi` calls it with `f64` and with
//! num-dual's dual numbers (first and second derivatives, and nested duals for third
//! derivatives such as the Jacobian of the Euler–Lagrange acceleration).
//!
//! `Scalar` is deliberately *not* bounded by nalgebra's `RealField`: num-dual implements
//! `RealField` only for duals over `f64`, not for nested duals. Write norms as
//! `q.dot(q).sqrt()` instead of `q.norm()`; everything else of num-dual's [`DualNum`]
//! (`sin`, `sqrt`, `powi`, `recip`, ...) and nalgebra's arithmetic (`dot`, `+`, `*`) is there.

use num_dual::DualNum;

/// A real number or a (possibly nested) dual number over `f64`.
///
/// This alias absorbs num-dual's API in one place; every generic function in `svi` and every
/// model is bounded by it.
pub trait Scalar: DualNum<Primitive = f64> + Copy + nalgebra::Scalar {}

impl<T: DualNum<Primitive = f64> + Copy + nalgebra::Scalar> Scalar for T {}

/// Convert an `f64` constant into any [`Scalar`].
#[inline]
pub fn constant<D: Scalar>(value: f64) -> D {
    D::from(value)
}
