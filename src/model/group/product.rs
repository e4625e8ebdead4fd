//! The direct product G₁ × G₂ of two groups ([`Product`]) and the power Gᴷ of one
//! ([`Power`]) on the [`LieGroup`] interface: elements (g₁, g₂)
//! stored one after the other, algebra elements (x₁, x₂), and every map acting factor by
//! factor (exp, log, dexp, ad and Ad are block diagonal). Products nest, so SO(3) × ℝ³
//! ([`RotationsAndTranslations`]) and SO(3)ᴺ or (G × ℝᴷ) × H are all products.
//!
//! The dimensions are spelled out as parameters (stable Rust cannot add them in a type):
//! `Product<A, B, NA, EA, NB, EB>` implements `LieGroup<NA + NB, EA + EB>`, and asking it for
//! any other shape is a compile-time error.

use super::rotations::Rotations;
use super::translations::Translations;
use super::{LieGroup, VelocityDerivatives};
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};
use std::marker::PhantomData;

/// G₁ × G₂ for G₁ = `A` (dimension `NA`, `EA` stored numbers) and G₂ = `B` (`NB`, `EB`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Product<A, B, const NA: usize, const EA: usize, const NB: usize, const EB: usize>(
    PhantomData<(A, B)>,
);

/// SO(3) × ℝ³: a rigid body whose attitude and position are separate factors (compare SE(3),
/// [`super::rigid_motions::RigidMotions`], where the position is translated with the body).
pub type RotationsAndTranslations = Product<Rotations, Translations<3>, 3, 9, 3, 3>;

/// Splits a vector of the product into its two factors.
#[inline]
fn split<D: Scalar, const M: usize, const MA: usize, const MB: usize>(
    x: &SVector<D, M>,
) -> (SVector<D, MA>, SVector<D, MB>) {
    (
        x.fixed_rows::<MA>(0).into_owned(),
        x.fixed_rows::<MB>(MA).into_owned(),
    )
}

/// Joins two factors' vectors.
#[inline]
fn join<D: Scalar, const M: usize, const MA: usize, const MB: usize>(
    a: &SVector<D, MA>,
    b: &SVector<D, MB>,
) -> SVector<D, M> {
    SVector::from_iterator(a.iter().chain(b.iter()).copied())
}

/// The block-diagonal matrix diag(a, b).
#[inline]
fn diagonal<D: Scalar, const M: usize, const MA: usize, const MB: usize>(
    a: &SMatrix<D, MA, MA>,
    b: &SMatrix<D, MB, MB>,
) -> SMatrix<D, M, M> {
    let mut m = SMatrix::<D, M, M>::zeros();
    m.fixed_view_mut::<MA, MA>(0, 0).copy_from(a);
    m.fixed_view_mut::<MB, MB>(MA, MA).copy_from(b);
    m
}

impl<
    A,
    B,
    const NA: usize,
    const EA: usize,
    const NB: usize,
    const EB: usize,
    const N: usize,
    const E: usize,
> LieGroup<N, E> for Product<A, B, NA, EA, NB, EB>
where
    A: LieGroup<NA, EA>,
    B: LieGroup<NB, EB>,
{
    const NAME: &'static str = "product of groups";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, E> {
        const {
            assert!(
                N == NA + NB && E == EA + EB,
                "a product's shape is the sum of its factors'"
            )
        };
        join(&A::identity::<D>(), &B::identity::<D>())
    }

    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, E>, h: &SVector<D, E>) -> SVector<D, E> {
        let (g1, g2) = split::<D, E, EA, EB>(g);
        let (h1, h2) = split::<D, E, EA, EB>(h);
        join(&A::compose(&g1, &h1), &B::compose(&g2, &h2))
    }

    fn inverse(g: &SVector<f64, E>) -> SVector<f64, E> {
        let (g1, g2) = split::<f64, E, EA, EB>(g);
        join(&A::inverse(&g1), &B::inverse(&g2))
    }

    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        const {
            assert!(
                N == NA + NB && E == EA + EB,
                "a product's shape is the sum of its factors'"
            )
        };
        let (x1, x2) = split::<D, N, NA, NB>(x);
        join(&A::exp_minus_identity(&x1), &B::exp_minus_identity(&x2))
    }

    #[inline]
    fn exp_second_order<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        let (x1, x2) = split::<D, N, NA, NB>(x);
        join(&A::exp_second_order(&x1), &B::exp_second_order(&x2))
    }

    fn log(g: &SVector<f64, E>) -> SVector<f64, N> {
        let (g1, g2) = split::<f64, E, EA, EB>(g);
        join(&A::log(&g1), &B::log(&g2))
    }

    fn translate_difference(g: &SVector<f64, E>, delta: &SVector<f64, E>) -> SVector<f64, E> {
        let (g1, g2) = split::<f64, E, EA, EB>(g);
        let (d1, d2) = split::<f64, E, EA, EB>(delta);
        join(
            &A::translate_difference(&g1, &d1),
            &B::translate_difference(&g2, &d2),
        )
    }

    fn hat(x: &SVector<f64, N>) -> SVector<f64, E> {
        let (x1, x2) = split::<f64, N, NA, NB>(x);
        join(&A::hat(&x1), &B::hat(&x2))
    }

    #[inline]
    fn ad<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N> {
        let (x1, x2) = split::<D, N, NA, NB>(x);
        diagonal(&A::ad(&x1), &B::ad(&x2))
    }

    fn adjoint(g: &SVector<f64, E>) -> SMatrix<f64, N, N> {
        let (g1, g2) = split::<f64, E, EA, EB>(g);
        diagonal(&A::adjoint(&g1), &B::adjoint(&g2))
    }

    #[inline]
    fn dexp<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N> {
        let (x1, x2) = split::<D, N, NA, NB>(x);
        diagonal(&A::dexp(&x1), &B::dexp(&x2))
    }

    fn dexp_inverse(x: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        let (x1, x2) = split::<f64, N, NA, NB>(x);
        diagonal(&A::dexp_inverse(&x1), &B::dexp_inverse(&x2))
    }

    #[inline]
    fn body_velocity<D: Scalar>(x: &SVector<D, N>, rate: &SVector<D, N>) -> SVector<D, N> {
        let (x1, x2) = split::<D, N, NA, NB>(x);
        let (r1, r2) = split::<D, N, NA, NB>(rate);
        join(&A::body_velocity(&x1, &r1), &B::body_velocity(&x2, &r2))
    }

    fn defect(g: &SVector<f64, E>) -> f64 {
        let (g1, g2) = split::<f64, E, EA, EB>(g);
        A::defect(&g1).max(B::defect(&g2))
    }

    fn chart_reach(x: &SVector<f64, N>) -> f64 {
        let (x1, x2) = split::<f64, N, NA, NB>(x);
        A::chart_reach(&x1).max(B::chart_reach(&x2))
    }
}

/// Gᴷ, the product of `K` copies of one group G = `G` (dimension `NG`, `EG` stored numbers):
/// chains of identical links, such as SO(3)ᴷ for K rigid links or spherical pendulums.
/// Implements `LieGroup<K·NG, K·EG>` (checked at compile time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Power<G, const K: usize, const NG: usize, const EG: usize>(PhantomData<G>);

/// Factor `k` of a vector of Gᴷ, `M` numbers per factor.
#[inline]
fn factor<D: Scalar, const L: usize, const M: usize>(x: &SVector<D, L>, k: usize) -> SVector<D, M> {
    x.fixed_rows::<M>(M * k).into_owned()
}

impl<G, const K: usize, const NG: usize, const EG: usize, const N: usize, const E: usize>
    LieGroup<N, E> for Power<G, K, NG, EG>
where
    G: LieGroup<NG, EG>,
{
    const NAME: &'static str = "power of a group";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, E> {
        const {
            assert!(
                N == K * NG && E == K * EG,
                "a power's shape is K times its group's"
            )
        };
        let mut g = SVector::<D, E>::zeros();
        for k in 0..K {
            g.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::identity::<D>());
        }
        g
    }

    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, E>, h: &SVector<D, E>) -> SVector<D, E> {
        let mut out = SVector::<D, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k).copy_from(&G::compose(
                &factor::<D, E, EG>(g, k),
                &factor::<D, E, EG>(h, k),
            ));
        }
        out
    }

    fn inverse(g: &SVector<f64, E>) -> SVector<f64, E> {
        let mut out = SVector::<f64, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::inverse(&factor::<f64, E, EG>(g, k)));
        }
        out
    }

    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        const {
            assert!(
                N == K * NG && E == K * EG,
                "a power's shape is K times its group's"
            )
        };
        let mut out = SVector::<D, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::exp_minus_identity(&factor::<D, N, NG>(x, k)));
        }
        out
    }

    #[inline]
    fn exp_second_order<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        let mut out = SVector::<D, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::exp_second_order(&factor::<D, N, NG>(x, k)));
        }
        out
    }

    fn log(g: &SVector<f64, E>) -> SVector<f64, N> {
        let mut out = SVector::<f64, N>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<NG>(NG * k)
                .copy_from(&G::log(&factor::<f64, E, EG>(g, k)));
        }
        out
    }

    fn translate_difference(g: &SVector<f64, E>, delta: &SVector<f64, E>) -> SVector<f64, E> {
        let mut out = SVector::<f64, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::translate_difference(
                    &factor::<f64, E, EG>(g, k),
                    &factor::<f64, E, EG>(delta, k),
                ));
        }
        out
    }

    fn hat(x: &SVector<f64, N>) -> SVector<f64, E> {
        let mut out = SVector::<f64, E>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<EG>(EG * k)
                .copy_from(&G::hat(&factor::<f64, N, NG>(x, k)));
        }
        out
    }

    #[inline]
    fn ad<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N> {
        let mut m = SMatrix::<D, N, N>::zeros();
        for k in 0..K {
            m.fixed_view_mut::<NG, NG>(NG * k, NG * k)
                .copy_from(&G::ad(&factor::<D, N, NG>(x, k)));
        }
        m
    }

    fn adjoint(g: &SVector<f64, E>) -> SMatrix<f64, N, N> {
        let mut m = SMatrix::<f64, N, N>::zeros();
        for k in 0..K {
            m.fixed_view_mut::<NG, NG>(NG * k, NG * k)
                .copy_from(&G::adjoint(&factor::<f64, E, EG>(g, k)));
        }
        m
    }

    #[inline]
    fn dexp<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N> {
        let mut m = SMatrix::<D, N, N>::zeros();
        for k in 0..K {
            m.fixed_view_mut::<NG, NG>(NG * k, NG * k)
                .copy_from(&G::dexp(&factor::<D, N, NG>(x, k)));
        }
        m
    }

    fn dexp_inverse(x: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        let mut m = SMatrix::<f64, N, N>::zeros();
        for k in 0..K {
            m.fixed_view_mut::<NG, NG>(NG * k, NG * k)
                .copy_from(&G::dexp_inverse(&factor::<f64, N, NG>(x, k)));
        }
        m
    }

    #[inline]
    fn body_velocity<D: Scalar>(x: &SVector<D, N>, rate: &SVector<D, N>) -> SVector<D, N> {
        let mut out = SVector::<D, N>::zeros();
        for k in 0..K {
            out.fixed_rows_mut::<NG>(NG * k)
                .copy_from(&G::body_velocity(
                    &factor::<D, N, NG>(x, k),
                    &factor::<D, N, NG>(rate, k),
                ));
        }
        out
    }

    fn defect(g: &SVector<f64, E>) -> f64 {
        (0..K).fold(0.0, |worst: f64, k| {
            worst.max(G::defect(&factor::<f64, E, EG>(g, k)))
        })
    }

    fn chart_reach(x: &SVector<f64, N>) -> f64 {
        (0..K).fold(0.0, |worst: f64, k| {
            worst.max(G::chart_reach(&factor::<f64, N, NG>(x, k)))
        })
    }

    /// Factor by factor (W acts on each factor alone): the blocks are diagonal.
    fn velocity_derivatives(
        a: &SVector<f64, N>,
        b: &SVector<f64, N>,
        lambda: &SVector<f64, N>,
        nu: &SVector<f64, N>,
        second: bool,
        out: &mut VelocityDerivatives<N>,
    ) {
        if second {
            out.rate.fill(0.0);
            out.curvature.fill(0.0);
            out.twist.fill(0.0);
        }
        let mut part = VelocityDerivatives::<NG>::zeros();
        for k in 0..K {
            G::velocity_derivatives(
                &factor::<f64, N, NG>(a, k),
                &factor::<f64, N, NG>(b, k),
                &factor::<f64, N, NG>(lambda, k),
                &factor::<f64, N, NG>(nu, k),
                second,
                &mut part,
            );
            out.pulled
                .fixed_rows_mut::<NG>(NG * k)
                .copy_from(&part.pulled);
            if second {
                let at = NG * k;
                out.rate
                    .fixed_view_mut::<NG, NG>(at, at)
                    .copy_from(&part.rate);
                out.curvature
                    .fixed_view_mut::<NG, NG>(at, at)
                    .copy_from(&part.curvature);
                out.twist
                    .fixed_view_mut::<NG, NG>(at, at)
                    .copy_from(&part.twist);
            }
        }
    }

    /// Factor by factor: the Jacobian is block diagonal.
    fn dexp_transpose_jacobian(x: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        let mut m = SMatrix::<f64, N, N>::zeros();
        for k in 0..K {
            m.fixed_view_mut::<NG, NG>(NG * k, NG * k)
                .copy_from(&G::dexp_transpose_jacobian(
                    &factor::<f64, N, NG>(x, k),
                    &factor::<f64, N, NG>(v, k),
                ));
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::super::rigid_motions::RigidMotions;
    use super::*;

    #[test]
    fn products_satisfy_the_group_identities() {
        super::super::check::check_group::<RotationsAndTranslations, 6, 12>(&[
            SVector::zeros(),
            SVector::from([0.3, -0.7, 1.1, -0.4, 0.2, 0.9]),
        ])
        .unwrap();
        // Nested: SE(3) × SO(3) × ℝ².
        type Nested =
            Product<RigidMotions, Product<Rotations, Translations<2>, 3, 9, 2, 2>, 6, 12, 5, 11>;
        super::super::check::check_group::<Nested, 11, 23>(&[SVector::from([
            0.3, -0.7, 1.1, -0.4, 0.2, 0.9, 0.1, 0.2, -0.3, 1.0, -2.0,
        ])])
        .unwrap();
        // SO(3)³.
        super::super::check::check_group::<Power<Rotations, 3, 3, 9>, 9, 27>(&[SVector::from([
            0.3, -0.7, 1.1, -0.4, 0.2, 0.9, 0.1, 0.2, -0.3,
        ])])
        .unwrap();
    }

    /// A power's factor-by-factor derivatives of W and of dexpᵀ are the dense ones.
    #[test]
    fn power_derivatives_are_the_dense_ones() {
        use super::super::derivatives::{
            dense_dexp_transpose_jacobian, dense_velocity_derivatives,
        };
        type Squared = Power<RigidMotions, 2, 6, 12>;
        let vector =
            |shift: f64| SVector::<f64, 12>::from_fn(|i, _| (0.7 * i as f64 + shift).sin());
        let (a, b, lambda, nu) = (vector(0.1), vector(1.3), vector(2.2), vector(-0.4));
        for second in [false, true] {
            let (mut fast, mut dense) =
                (VelocityDerivatives::zeros(), VelocityDerivatives::zeros());
            <Squared as LieGroup<12, 24>>::velocity_derivatives(
                &a, &b, &lambda, &nu, second, &mut fast,
            );
            dense_velocity_derivatives::<Squared, 12, 24>(&a, &b, &lambda, &nu, second, &mut dense);
            assert!((fast.pulled - dense.pulled).amax() < 1e-14);
            assert!((fast.rate - dense.rate).amax() < 1e-14);
            assert!((fast.curvature - dense.curvature).amax() < 1e-13);
            assert!((fast.twist - dense.twist).amax() < 1e-13);
        }
        let mut dense = VelocityDerivatives::zeros();
        dense_velocity_derivatives::<Squared, 12, 24>(&a, &b, &lambda, &nu, true, &mut dense);
        assert!(dense.curvature.amax() > 0.1);
        let difference = <Squared as LieGroup<12, 24>>::dexp_transpose_jacobian(&a, &nu)
            - dense_dexp_transpose_jacobian::<Squared, 12, 24>(&a, &nu);
        assert!(difference.amax() < 1e-14);
    }
}
