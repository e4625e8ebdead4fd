//! The special Euclidean group SE(3) on the [`LieGroup`] interface: rigid motions g = (R, x)
//! acting as X ↦ R X + x (body to space), stored as R column by column and then x (12
//! numbers); the algebra se(3) ≅ ℝ⁶ with coordinates ξ = (ω, v): ω the body angular velocity
//! and v the velocity of the body origin in the body frame, ξ̂ = [[ω̂, v], [0, 0]].
//!
//! # Closed forms
//! With ad_ξ = [[ω̂, 0], [v̂, ω̂]] (since \[ξ₁, ξ₂\] = (ω₁ × ω₂, ω₁ × v₂ − ω₂ × v₁)) every series
//! in ad_ξ is block lower-triangular with the SO(3) series on the diagonal:
//! - exp(ξ) = (exp ω̂, A(ω) v) with A = dexp_ω of SO(3) (the "V matrix");
//! - dexp_ξ = [[A, 0], [Q, A]], Q = Σ_{n≥1} Σ_{k<n} ω̂ᵏ v̂ ω̂ⁿ⁻¹⁻ᵏ/(n + 1)!, in closed form
//!   (Barfoot, *State Estimation for Robotics*, 2017, eq. 7.86, in this coordinate order)
//!
//!   Q = ½ v̂ + c₁ (ω̂v̂ + v̂ω̂ + ω̂v̂ω̂) + c₂ (ω̂²v̂ + v̂ω̂² − 3 ω̂v̂ω̂) + ½ (c₂ + 3 c₃)(ω̂v̂ω̂² + ω̂²v̂ω̂),
//!
//!   c₁ = (θ − sin θ)/θ³, c₂ = (θ²/2 + cos θ − 1)/θ⁴, c₃ = (θ − sin θ − θ³/6)/θ⁵, θ = |ω|
//!   (Taylor polynomials in θ² below θ = 1/2, where the closed forms cancel);
//! - dexp_ξ⁻¹ = [[A⁻¹, 0], [−A⁻¹QA⁻¹, A⁻¹]];
//! - Ad_(R, x) = [[R, 0], [x̂R, R]]; log(R, x) = (log R, A(ω)⁻¹ x).
//!
//! The tests check every one against its series and exp against central differences.

use super::LieGroup;
use crate::model::so3::{self, Matrix3, Vector3, horner};
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};

/// SE(3), the positions and attitudes of a rigid body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RigidMotions;

/// θ² below which c₁, c₂, c₃ use their Taylor polynomials (θ = 1/2: the first omitted term
/// is below 10⁻¹⁸ relative).
const SERIES_THRESHOLD: f64 = 0.25;

/// c₁ = (θ − sin θ)/θ³ = Σ (−1)ᵏ tᵏ/(2k + 3)! in t = θ².
const C1_SERIES: [f64; 7] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
    -1.0 / 6_227_020_800.0,
    1.0 / 1_307_674_368_000.0,
];
/// c₂ = (θ²/2 + cos θ − 1)/θ⁴ = Σ (−1)ᵏ tᵏ/(2k + 4)!.
const C2_SERIES: [f64; 7] = [
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];
/// c₃ = (θ − sin θ − θ³/6)/θ⁵ = −Σ (−1)ᵏ tᵏ/(2k + 5)!.
const C3_SERIES: [f64; 7] = [
    -1.0 / 120.0,
    1.0 / 5040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
    -1.0 / 6_227_020_800.0,
    1.0 / 1_307_674_368_000.0,
    -1.0 / 355_687_428_096_000.0,
];

impl RigidMotions {
    /// The attitude R of stored entries.
    #[inline]
    pub fn rotation<D: Scalar>(g: &SVector<D, 12>) -> Matrix3<D> {
        Matrix3::from_column_slice(&g.as_slice()[..9])
    }

    /// The position x of stored entries.
    #[inline]
    pub fn position<D: Scalar>(g: &SVector<D, 12>) -> Vector3<D> {
        Vector3::from_column_slice(&g.as_slice()[9..])
    }

    /// The stored entries of (R, x).
    #[inline]
    pub fn element<D: Scalar>(r: &Matrix3<D>, x: &Vector3<D>) -> SVector<D, 12> {
        SVector::from_iterator(r.iter().chain(x.iter()).copied())
    }

    /// The coefficients c₁, c₂ and ½(c₂ + 3c₃) of Q at θ² = `t` (module docs).
    fn coefficients<D: Scalar>(t: D) -> (D, D, D) {
        let (c1, c2, c3) = if t.re() < SERIES_THRESHOLD {
            (
                horner(t, &C1_SERIES),
                horner(t, &C2_SERIES),
                horner(t, &C3_SERIES),
            )
        } else {
            let theta = t.sqrt();
            let (sin, cos) = theta.sin_cos();
            (
                (theta - sin) / (t * theta),
                (t * 0.5 + cos - 1.0) / (t * t),
                (theta - sin - t * theta / 6.0) / (t * t * theta),
            )
        };
        (c1, c2, (c2 + c3 * 3.0) * 0.5)
    }

    /// The block Q of dexp_(ω, v) (module docs).
    fn coupling<D: Scalar>(omega: &Vector3<D>, v: &Vector3<D>) -> Matrix3<D> {
        let (c1, c2, c4) = Self::coefficients(omega.dot(omega));
        let w = so3::hat(omega);
        let u = so3::hat(v);
        let wu = w * u;
        let uw = u * w;
        let wuw = wu * w;
        let ww = w * w;
        u * D::from(0.5)
            + (wu + uw + wuw) * c1
            + (ww * u + uw * w - wuw * D::from(3.0)) * c2
            + (wuw * w + w * wuw) * c4
    }

    /// Q(ω, v) y by cross products (ten of them, against eight 3 × 3 products for Q).
    fn coupling_times<D: Scalar>(omega: &Vector3<D>, v: &Vector3<D>, y: &Vector3<D>) -> Vector3<D> {
        let (c1, c2, c4) = Self::coefficients(omega.dot(omega));
        let (p, u) = (omega, v);
        let py = so3::cross(p, y);
        let ppy = so3::cross(p, &py);
        let uy = so3::cross(u, y);
        let upy = so3::cross(u, &py);
        let puy = so3::cross(p, &uy);
        let pupy = so3::cross(p, &upy);
        let ppuy = so3::cross(p, &puy);
        let uppy = so3::cross(u, &ppy);
        let puppy = so3::cross(p, &uppy);
        let ppupy = so3::cross(p, &pupy);
        uy * D::from(0.5)
            + (puy + upy + pupy) * c1
            + (ppuy + uppy - pupy * D::from(3.0)) * c2
            + (puppy + ppupy) * c4
    }

    /// Splits ξ into (ω, v).
    #[inline]
    fn parts<D: Scalar>(x: &SVector<D, 6>) -> (Vector3<D>, Vector3<D>) {
        (
            x.fixed_rows::<3>(0).into_owned(),
            x.fixed_rows::<3>(3).into_owned(),
        )
    }

    /// The block matrix [[a, 0], [c, a]].
    #[inline]
    fn lower<D: Scalar>(a: &Matrix3<D>, c: &Matrix3<D>) -> SMatrix<D, 6, 6> {
        let mut m = SMatrix::<D, 6, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(a);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(a);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(c);
        m
    }
}

impl LieGroup<6, 12> for RigidMotions {
    const NAME: &'static str = "SE(3)";

    #[inline]
    fn identity<D: Scalar>() -> SVector<D, 12> {
        Self::element(&Matrix3::identity(), &Vector3::zeros())
    }

    #[inline]
    fn compose<D: Scalar>(g: &SVector<D, 12>, h: &SVector<D, 12>) -> SVector<D, 12> {
        let r = Self::rotation(g);
        Self::element(
            &(r * Self::rotation(h)),
            &(r * Self::position(h) + Self::position(g)),
        )
    }

    fn inverse(g: &SVector<f64, 12>) -> SVector<f64, 12> {
        let back = Self::rotation(g).transpose();
        Self::element(&back, &(-(back * Self::position(g))))
    }

    #[inline]
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, 6>) -> SVector<D, 12> {
        let (omega, v) = Self::parts(x);
        Self::element(&so3::exp_minus_identity(&omega), &(so3::dexp(&omega) * v))
    }

    /// (I + ω̂ + ½ω̂², v + ½ ω × v): the entries of I + ξ̂ + ½ξ̂².
    #[inline]
    fn exp_second_order<D: Scalar>(x: &SVector<D, 6>) -> SVector<D, 12> {
        let (omega, v) = Self::parts(x);
        let h = so3::hat(&omega);
        Self::element(
            &(Matrix3::identity() + h + h * h * D::from(0.5)),
            &(v + so3::cross(&omega, &v) * D::from(0.5)),
        )
    }

    fn log(g: &SVector<f64, 12>) -> SVector<f64, 6> {
        let omega = so3::log(&Self::rotation(g));
        let v = so3::dexp_inverse(&omega) * Self::position(g);
        SVector::from_iterator(omega.iter().chain(v.iter()).copied())
    }

    fn translate_difference(g: &SVector<f64, 12>, delta: &SVector<f64, 12>) -> SVector<f64, 12> {
        let r = Self::rotation(g);
        Self::element(&(r * Self::rotation(delta)), &(r * Self::position(delta)))
    }

    fn hat(x: &SVector<f64, 6>) -> SVector<f64, 12> {
        let (omega, v) = Self::parts(x);
        Self::element(&so3::hat(&omega), &v)
    }

    #[inline]
    fn ad<D: Scalar>(x: &SVector<D, 6>) -> SMatrix<D, 6, 6> {
        let (omega, v) = Self::parts(x);
        Self::lower(&so3::hat(&omega), &so3::hat(&v))
    }

    fn adjoint(g: &SVector<f64, 12>) -> SMatrix<f64, 6, 6> {
        let r = Self::rotation(g);
        Self::lower(&r, &(so3::hat(&Self::position(g)) * r))
    }

    #[inline]
    fn dexp<D: Scalar>(x: &SVector<D, 6>) -> SMatrix<D, 6, 6> {
        let (omega, v) = Self::parts(x);
        Self::lower(&so3::dexp(&omega), &Self::coupling(&omega, &v))
    }

    /// dexp_{−ξ} ξ̇ = (A(−ω) ω̇, Q(−ω, −v) ω̇ + A(−ω) v̇) by cross products.
    #[inline]
    fn body_velocity<D: Scalar>(x: &SVector<D, 6>, rate: &SVector<D, 6>) -> SVector<D, 6> {
        let (omega, v) = Self::parts(x);
        let (omega_rate, v_rate) = Self::parts(rate);
        let angular = so3::body_velocity(&omega, &omega_rate);
        let linear = Self::coupling_times(&(-omega), &(-v), &omega_rate)
            + so3::body_velocity(&omega, &v_rate);
        SVector::from_iterator(angular.iter().chain(linear.iter()).copied())
    }

    fn dexp_inverse(x: &SVector<f64, 6>) -> SMatrix<f64, 6, 6> {
        let (omega, v) = Self::parts(x);
        let inverse = so3::dexp_inverse(&omega);
        Self::lower(
            &inverse,
            &(-(inverse * Self::coupling(&omega, &v) * inverse)),
        )
    }

    fn defect(g: &SVector<f64, 12>) -> f64 {
        let r = Self::rotation(g);
        if r.determinant() <= 0.0 {
            return f64::INFINITY;
        }
        so3::orthogonality_error(&r)
    }

    fn chart_reach(x: &SVector<f64, 6>) -> f64 {
        x.fixed_rows::<3>(0).norm() / std::f64::consts::PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_motions_satisfy_the_group_identities() {
        super::super::check::check_group::<RigidMotions, 6, 12>(&[
            SVector::zeros(),
            SVector::from([1e-4, -2e-4, 3e-5, 0.5, -1.0, 2.0]),
            SVector::from([0.2, -0.1, 0.3, 0.5, -1.0, 2.0]),
            SVector::from([0.3, -0.7, 1.1, -0.4, 0.2, 0.9]),
            SVector::from([-2.0, 1.0, 0.5, 3.0, 0.0, -1.0]),
        ])
        .unwrap();
    }
}
