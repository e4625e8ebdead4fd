//! A numerical check of every identity of the [`LieGroup`] interface, for a group of one's
//! own: [`check_group`] at chosen algebra elements (or at [`sample_points`]) returns the first
//! identity that fails as a [`GroupCheckFailure`], naming the group, the identity, the algebra
//! element and the measured defect against its tolerance.
//!
//! ```
//! use svi::lie_group::Rotations;
//! use svi::model::group::check::{check_group, sample_points};
//!
//! check_group::<Rotations, 3, 9>(&sample_points::<3>()).unwrap();
//! ```
//!
//! The identities: the group axioms (g g⁻¹ = e, exp(−x) = exp(x)⁻¹, associativity), log exp
//! x = x, exp(x) in G, [`LieGroup::translate_difference`], dexp against its series
//! Σ ad_xⁿ/(n + 1)!, dexp⁻¹ dexp = I, Ad_{exp x} = exp(ad_x), the derivative of exp against
//! central differences, [`LieGroup::body_velocity`] = dexp_{−x} ẋ, exp_second_order = exp +
//! O(x³) and Ad_{gh} = Ad_g Ad_h.

use super::LieGroup;
use nalgebra::{SMatrix, SVector};

/// An identity of the [`LieGroup`] interface that does not hold numerically at one algebra
/// element (the result of [`check_group`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{group}: {identity} fails at x = {x:?}: defect {defect:e} above the tolerance {tolerance:e}"
)]
pub struct GroupCheckFailure {
    /// The group's name, [`LieGroup::NAME`].
    pub group: &'static str,
    /// The identity that failed (`"dexp = Σ adⁿ/(n + 1)!"`).
    pub identity: &'static str,
    /// The algebra element x at which it failed.
    pub x: Vec<f64>,
    /// The measured defect (the largest entry of the difference of the two sides; NaN when a
    /// side is not finite).
    pub defect: f64,
    /// The tolerance the defect exceeded.
    pub tolerance: f64,
}

/// Checks every identity of the interface numerically on the group `G` at the algebra
/// elements `xs` (see the module docs); the first that fails is the error. The elements should
/// lie well inside the natural chart ([`LieGroup::chart_reach`] below about ½), as
/// [`sample_points`] do.
pub fn check_group<G: LieGroup<N, E>, const N: usize, const E: usize>(
    xs: &[SVector<f64, N>],
) -> Result<(), GroupCheckFailure> {
    let e = G::identity::<f64>();
    for x in xs {
        // A NaN defect fails too (it is not ≤ the tolerance).
        let close = |defect: f64, tolerance: f64, identity: &'static str| {
            if defect <= tolerance {
                Ok(())
            } else {
                Err(GroupCheckFailure {
                    group: G::NAME,
                    identity,
                    x: x.iter().copied().collect(),
                    defect,
                    tolerance,
                })
            }
        };
        let g = G::exp(x);
        let y = -x * 0.7 + SVector::from_fn(|i, _| 0.1 * (i as f64 + 1.0).sin());
        let h = G::exp(&y);
        // Group axioms and the exponential.
        close(
            (G::compose(&g, &G::inverse(&g)) - e).amax(),
            1e-14,
            "g g⁻¹ = e",
        )?;
        close(
            (G::exp(&(-x)) - G::inverse(&g)).amax(),
            1e-14,
            "exp(−x) = exp(x)⁻¹",
        )?;
        close((G::log(&g) - x).amax(), 1e-12, "log exp x = x")?;
        close(G::defect(&g), 1e-14, "exp(x) in G")?;
        close(
            (G::translate_difference(&g, &(h - e)) - (G::compose(&g, &h) - g)).amax(),
            1e-14,
            "translate_difference",
        )?;
        let third = G::exp(&(x * 0.3 + y));
        close(
            (G::compose(&G::compose(&g, &h), &third) - G::compose(&g, &G::compose(&h, &third)))
                .amax(),
            1e-13,
            "associativity",
        )?;
        // dexp against the series Σ adⁿ/(n + 1)!, its inverse, and central differences of exp.
        let ad = G::ad(x);
        let mut term = SMatrix::<f64, N, N>::identity();
        let mut series = term;
        let mut adjoint_series = term;
        for n in 1..40 {
            term = term * ad / n as f64;
            adjoint_series += term;
            series += term / (n + 1) as f64;
        }
        close((G::dexp(x) - series).amax(), 1e-13, "dexp = Σ adⁿ/(n + 1)!")?;
        close(
            (G::dexp_inverse(x) * G::dexp(x) - SMatrix::identity()).amax(),
            1e-12,
            "dexp⁻¹ dexp = I",
        )?;
        close(
            (G::adjoint(&g) - adjoint_series).amax(),
            1e-12,
            "Ad_exp x = exp(ad_x)",
        )?;
        let step = 1e-5;
        for j in 0..N {
            let unit = SVector::<f64, N>::from_fn(|i, _| if i == j { step } else { 0.0 });
            let derivative = (G::exp(&(x + unit)) - G::exp(&(x - unit))) / (2.0 * step);
            // d/ds exp(x + s e_j) = (dexp_x e_j)^ exp(x) = g (dexp_{−x} e_j)^.
            let body = G::dexp(&(-x)).column(j).into_owned();
            let expected = G::translate_difference(&g, &G::hat(&body));
            close(
                (derivative - expected).amax(),
                1e-8,
                "d exp = g (dexp_{−x} ẋ)^",
            )?;
            close(
                (G::body_velocity(x, &(unit / step)) - body).amax(),
                1e-14,
                "body_velocity = dexp_{−x} ẋ",
            )?;
        }
        // exp_second_order agrees with exp to second order: the difference is O(s³).
        let s = 1e-2;
        close(
            (G::exp_second_order(&(x * s)) - G::exp(&(x * s))).amax(),
            (1.0 + x.amax()).powi(3) * s.powi(3),
            "exp_second_order = exp + O(x³)",
        )?;
        // Ad is a homomorphism.
        close(
            (G::adjoint(&G::compose(&g, &h)) - G::adjoint(&g) * G::adjoint(&h)).amax(),
            1e-12,
            "Ad_gh = Ad_g Ad_h",
        )?;
    }
    Ok(())
}

/// The (amplitude, frequency) of each of [`sample_points`]: x_i = a sin(k i + 1).
const SAMPLES: [(f64, f64); 5] = [(0.0, 1.0), (1e-4, 1.0), (0.3, 1.0), (0.3, 2.0), (0.8, 3.0)];

/// A deterministic set of algebra elements of ℝᴺ for [`check_group`]: zero, a small element
/// (1e-4, the series branches of closed forms) and three of moderate size, x_i = a sin(k i + 1)
/// for a ≤ 0.8. Every entry is at most 0.8 in size, so every 3-block (an SO(3) factor) has
/// norm below 0.8·√3 ≈ 1.39 < 0.45π: inside the natural chart of every group built from
/// SO(3), SE(3), SO(2) and ℝᴷ.
pub fn sample_points<const N: usize>() -> Vec<SVector<f64, N>> {
    SAMPLES
        .iter()
        .map(|&(a, k)| SVector::from_fn(|i, _| a * (k * i as f64 + 1.0).sin()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::product::Power;
    use super::super::rotations::Rotations;
    use super::*;
    use crate::scalar::Scalar;

    #[test]
    fn the_sample_points_are_inside_every_chart() {
        let points = sample_points::<24>();
        assert_eq!(points.len(), SAMPLES.len());
        for x in &points {
            for k in 0..8 {
                let block = x.fixed_rows::<3>(3 * k).norm();
                assert!(block < 0.45 * std::f64::consts::PI, "{block}");
            }
            assert!(<Power<Rotations, 8, 3, 9> as LieGroup<24, 72>>::chart_reach(x) < 0.45);
        }
        assert!(points.iter().any(|x| x.amax() > 0.5));
    }

    /// SO(3) with a wrong dexp (that of −x, the transpose): every other identity holds.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    struct WrongDexp;

    impl LieGroup<3, 9> for WrongDexp {
        const NAME: &'static str = "SO(3) with a wrong dexp";
        fn identity<D: Scalar>() -> SVector<D, 9> {
            Rotations::identity()
        }
        fn compose<D: Scalar>(g: &SVector<D, 9>, h: &SVector<D, 9>) -> SVector<D, 9> {
            Rotations::compose(g, h)
        }
        fn inverse(g: &SVector<f64, 9>) -> SVector<f64, 9> {
            Rotations::inverse(g)
        }
        fn exp_minus_identity<D: Scalar>(x: &SVector<D, 3>) -> SVector<D, 9> {
            Rotations::exp_minus_identity(x)
        }
        fn log(g: &SVector<f64, 9>) -> SVector<f64, 3> {
            Rotations::log(g)
        }
        fn translate_difference(g: &SVector<f64, 9>, delta: &SVector<f64, 9>) -> SVector<f64, 9> {
            Rotations::translate_difference(g, delta)
        }
        fn hat(x: &SVector<f64, 3>) -> SVector<f64, 9> {
            Rotations::hat(x)
        }
        fn ad<D: Scalar>(x: &SVector<D, 3>) -> SMatrix<D, 3, 3> {
            Rotations::ad(x)
        }
        fn adjoint(g: &SVector<f64, 9>) -> SMatrix<f64, 3, 3> {
            Rotations::adjoint(g)
        }
        fn dexp<D: Scalar>(x: &SVector<D, 3>) -> SMatrix<D, 3, 3> {
            Rotations::dexp(&(-x))
        }
        fn dexp_inverse(x: &SVector<f64, 3>) -> SMatrix<f64, 3, 3> {
            Rotations::dexp_inverse(&(-x))
        }
        fn defect(g: &SVector<f64, 9>) -> f64 {
            Rotations::defect(g)
        }
        fn chart_reach(x: &SVector<f64, 3>) -> f64 {
            Rotations::chart_reach(x)
        }
    }

    #[test]
    fn a_broken_group_fails_naming_the_identity() {
        let points = sample_points::<3>();
        check_group::<Rotations, 3, 9>(&points).unwrap();
        let failure = check_group::<WrongDexp, 3, 9>(&points).unwrap_err();
        assert_eq!(failure.group, "SO(3) with a wrong dexp");
        assert_eq!(failure.identity, "dexp = Σ adⁿ/(n + 1)!");
        assert!(failure.defect > failure.tolerance, "{failure}");
        assert_eq!(failure.x.len(), 3);
        // The small element is the first at which the transpose differs beyond 1e-13.
        assert_eq!(failure.x, points[1].iter().copied().collect::<Vec<_>>());
        let text = failure.to_string();
        assert!(
            text.starts_with("SO(3) with a wrong dexp: dexp = Σ adⁿ/(n + 1)! fails at x = ["),
            "{text}"
        );
        // At zero alone the wrong dexp is right: nothing to report.
        check_group::<WrongDexp, 3, 9>(&points[..1]).unwrap();
    }

    #[test]
    fn a_nan_defect_fails() {
        let nan = [SVector::from([f64::NAN, 0.0, 0.0])];
        let failure = check_group::<Rotations, 3, 9>(&nan).unwrap_err();
        assert!(failure.defect.is_nan(), "{failure}");
    }
}
