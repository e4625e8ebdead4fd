//! The circle group SO(2) ≅ S¹ on the [`LieGroup`] interface: an angle θ stored as
//! (cos θ, sin θ) (the first column of its rotation matrix), the algebra ℝ, g h the complex
//! product, exp x = (cos x, sin x). Abelian: ad = 0, Ad = 1, dexp = 1. As a factor it carries a
//! rotor, a wheel or any angle that wraps around (SO(3) × S¹ is the dual-spin satellite).

use super::LieGroup;
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};

/// SO(2), rotations of the plane (angles).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Circle;

impl Circle {
    /// The stored entries (cos θ, sin θ) of angle θ.
    pub fn element(angle: f64) -> SVector<f64, 2> {
        let (sin, cos) = angle.sin_cos();
        SVector::from([cos, sin])
    }
}

impl LieGroup<1, 2> for Circle {
    const NAME: &'static str = "SO(2)";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, 2> {
        SVector::from([D::from(1.0), D::from(0.0)])
    }

    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, 2>, h: &SVector<D, 2>) -> SVector<D, 2> {
        SVector::from([g[0] * h[0] - g[1] * h[1], g[0] * h[1] + g[1] * h[0]])
    }

    fn inverse(g: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::from([g[0], -g[1]])
    }

    /// (cos x − 1, sin x) = (−2 sin²(x/2), sin x).
    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, 1>) -> SVector<D, 2> {
        let half = (x[0] * 0.5).sin();
        SVector::from([half * half * -2.0, x[0].sin()])
    }

    fn log(g: &SVector<f64, 2>) -> SVector<f64, 1> {
        SVector::from([g[1].atan2(g[0])])
    }

    fn translate_difference(g: &SVector<f64, 2>, delta: &SVector<f64, 2>) -> SVector<f64, 2> {
        Self::compose(g, delta)
    }

    fn hat(x: &SVector<f64, 1>) -> SVector<f64, 2> {
        SVector::from([0.0, x[0]])
    }

    #[inline]
    fn ad<D: Scalar>(_x: &SVector<D, 1>) -> SMatrix<D, 1, 1> {
        SMatrix::zeros()
    }

    fn adjoint(_g: &SVector<f64, 2>) -> SMatrix<f64, 1, 1> {
        SMatrix::identity()
    }

    #[inline]
    fn dexp<D: Scalar>(_x: &SVector<D, 1>) -> SMatrix<D, 1, 1> {
        SMatrix::identity()
    }

    fn dexp_inverse(_x: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::identity()
    }

    #[inline]
    fn body_velocity<D: Scalar>(_x: &SVector<D, 1>, rate: &SVector<D, 1>) -> SVector<D, 1> {
        *rate
    }

    /// |cos²θ + sin²θ − 1|.
    fn defect(g: &SVector<f64, 2>) -> f64 {
        (g.norm_squared() - 1.0).abs()
    }

    fn chart_reach(x: &SVector<f64, 1>) -> f64 {
        x[0].abs() / std::f64::consts::PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_circle_satisfies_the_group_identities() {
        super::super::check::check_group::<Circle, 1, 2>(&[
            SVector::zeros(),
            SVector::from([1e-5]),
            SVector::from([2.5]),
            SVector::from([-1.2]),
        ])
        .unwrap();
    }
}
