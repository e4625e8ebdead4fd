//! The rotation group SO(3) on the [`LieGroup`] interface: R stored column by column (9
//! numbers), so(3) ≅ ℝ³ with the hat map x̂ y = x × y, ad_x = x̂, Ad_R = R; exp, log, dexp and
//! dexp⁻¹ are the closed forms of [`crate::model::so3`].

use super::LieGroup;
use crate::model::so3::{self, Matrix3, Vector3};
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};

/// SO(3), the attitudes of a rigid body (body to space).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rotations;

impl Rotations {
    /// The rotation matrix of stored entries.
    #[inline]
    pub fn matrix<D: Scalar>(g: &SVector<D, 9>) -> Matrix3<D> {
        Matrix3::from_column_slice(g.as_slice())
    }

    /// The stored entries of a rotation matrix.
    #[inline]
    pub fn element<D: Scalar>(r: &Matrix3<D>) -> SVector<D, 9> {
        SVector::from_column_slice(r.as_slice())
    }
}

impl LieGroup<3, 9> for Rotations {
    const NAME: &'static str = "SO(3)";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, 9> {
        Self::element(&Matrix3::identity())
    }

    /// The 3 × 3 product written out (nalgebra's general product is slow on dual numbers).
    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, 9>, h: &SVector<D, 9>) -> SVector<D, 9> {
        SVector::from_fn(|k, _| {
            let (i, j) = (k % 3, 3 * (k / 3));
            g[i] * h[j] + g[i + 3] * h[j + 1] + g[i + 6] * h[j + 2]
        })
    }

    fn inverse(g: &SVector<f64, 9>) -> SVector<f64, 9> {
        Self::element(&Self::matrix(g).transpose())
    }

    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &Vector3<D>) -> SVector<D, 9> {
        Self::element(&so3::exp_minus_identity(x))
    }

    /// I + x̂ + ½x̂², with x̂² = xxᵀ − |x|²I.
    #[inline]
    fn exp_second_order<D: Scalar>(x: &Vector3<D>) -> SVector<D, 9> {
        let diagonal = D::from(1.0) - x.dot(x) * 0.5;
        let h = so3::hat(x);
        SVector::from_fn(|k, _| {
            let (i, j) = (k % 3, k / 3);
            let square = x[i] * x[j] * 0.5;
            if i == j {
                diagonal + square
            } else {
                h[(i, j)] + square
            }
        })
    }

    fn log(g: &SVector<f64, 9>) -> Vector3<f64> {
        so3::log(&Self::matrix(g))
    }

    fn translate_difference(g: &SVector<f64, 9>, delta: &SVector<f64, 9>) -> SVector<f64, 9> {
        Self::element(&(Self::matrix(g) * Self::matrix(delta)))
    }

    fn hat(x: &Vector3<f64>) -> SVector<f64, 9> {
        Self::element(&so3::hat(x))
    }

    #[inline]
    fn ad<D: Scalar>(x: &Vector3<D>) -> SMatrix<D, 3, 3> {
        so3::hat(x)
    }

    fn adjoint(g: &SVector<f64, 9>) -> SMatrix<f64, 3, 3> {
        Self::matrix(g)
    }

    #[inline]
    fn dexp<D: Scalar>(x: &Vector3<D>) -> SMatrix<D, 3, 3> {
        so3::dexp(x)
    }

    fn dexp_inverse(x: &Vector3<f64>) -> SMatrix<f64, 3, 3> {
        so3::dexp_inverse(x)
    }

    #[inline]
    fn body_velocity<D: Scalar>(x: &Vector3<D>, rate: &Vector3<D>) -> Vector3<D> {
        so3::body_velocity(x, rate)
    }

    fn defect(g: &SVector<f64, 9>) -> f64 {
        let r = Self::matrix(g);
        if r.determinant() <= 0.0 {
            return f64::INFINITY;
        }
        so3::orthogonality_error(&r)
    }

    fn chart_reach(x: &Vector3<f64>) -> f64 {
        x.norm() / std::f64::consts::PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_satisfy_the_group_identities() {
        super::super::check::check_group::<Rotations, 3, 9>(&[
            Vector3::zeros(),
            Vector3::new(1e-4, -2e-4, 3e-5),
            Vector3::new(0.3, -0.7, 1.1),
            Vector3::new(-2.0, 1.0, 0.5),
        ])
        .unwrap();
    }
}
