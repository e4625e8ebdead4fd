//! ℝᴷ as a Lie group under addition on the [`LieGroup`] interface: g h = g + h, exp x = x,
//! an abelian group (ad = 0, Ad = I, dexp = I). As a factor of a [`super::product::Product`] it
//! carries positions or shape coordinates beside a rotation (SO(3) × ℝ³).

use super::LieGroup;
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};

/// ℝᴷ under addition (translations of space, or shape coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Translations<const K: usize>;

impl<const K: usize> LieGroup<K, K> for Translations<K> {
    const NAME: &'static str = "R^K";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, K> {
        SVector::zeros()
    }

    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, K>, h: &SVector<D, K>) -> SVector<D, K> {
        g + h
    }

    fn inverse(g: &SVector<f64, K>) -> SVector<f64, K> {
        -g
    }

    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, K>) -> SVector<D, K> {
        *x
    }

    fn log(g: &SVector<f64, K>) -> SVector<f64, K> {
        *g
    }

    fn translate_difference(_g: &SVector<f64, K>, delta: &SVector<f64, K>) -> SVector<f64, K> {
        *delta
    }

    fn hat(x: &SVector<f64, K>) -> SVector<f64, K> {
        *x
    }

    #[inline]
    fn ad<D: Scalar>(_x: &SVector<D, K>) -> SMatrix<D, K, K> {
        SMatrix::zeros()
    }

    fn adjoint(_g: &SVector<f64, K>) -> SMatrix<f64, K, K> {
        SMatrix::identity()
    }

    #[inline]
    fn dexp<D: Scalar>(_x: &SVector<D, K>) -> SMatrix<D, K, K> {
        SMatrix::identity()
    }

    fn dexp_inverse(_x: &SVector<f64, K>) -> SMatrix<f64, K, K> {
        SMatrix::identity()
    }

    #[inline]
    fn body_velocity<D: Scalar>(_x: &SVector<D, K>, rate: &SVector<D, K>) -> SVector<D, K> {
        *rate
    }

    fn defect(_g: &SVector<f64, K>) -> f64 {
        0.0
    }

    fn chart_reach(_x: &SVector<f64, K>) -> f64 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn translations_satisfy_the_group_identities() {
        super::super::check::check_group::<Translations<2>, 2, 2>(&[
            SVector::zeros(),
            SVector::from([0.3, -4.0]),
        ])
        .unwrap();
    }
}
