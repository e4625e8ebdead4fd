//! The rotation group SO(3) and its Lie algebra so(3) ≅ ℝ³, generic over the scalar.
//!
//! # Conventions
//! - The hat map x̂ = \[x\]× is the skew matrix with x̂ y = x × y; vee is its inverse. The
//!   adjoint action of the algebra on itself is ad_x y = x × y = x̂ y, and the adjoint action
//!   of the group is Ad_R x = R x.
//! - [`exp`] is Rodrigues' formula exp(x) = I + A(θ) x̂ + B(θ) x̂², θ = |x|, with
//!   A = sin θ/θ and B = (1 − cos θ)/θ².
//! - The derivative of the exponential (Leok, *Generalized Variational Integrators*, §5.3.2,
//!   "T_ξ exp = T_e L_exp(ξ) · dexp_ad_ξ" with dexp_w = Σ wⁿ/(n + 1)!) is used here in the
//!   series convention of Iserles et al.: [`dexp`]`(x)` = Σ ad_xⁿ/(n + 1)! = I + B x̂ + C x̂²,
//!   C = (θ − sin θ)/θ³, which is the *right*-trivialised derivative,
//!   d/dt exp(x(t)) = (dexp_x ẋ)^ exp(x).
//!   The *left*-trivialised derivative, the body angular velocity of a curve
//!   R(t) = R₀ exp(x(t)), is
//!
//!   Ω = (R⁻¹Ṙ)^∨ = (exp(−x) d/dt exp(x))^∨ = dexp_{−x} ẋ = (I − B x̂ + C x̂²) ẋ,
//!
//!   because exp(−x) (dexp_x ẋ)^ exp(x) = Ad_{exp(−x)} dexp_x ẋ and
//!   e^{−ad}(e^{ad} − 1)/ad = (1 − e^{−ad})/ad. The paper's formula leaves this sign
//!   implicit; the tests check it against finite differences of exp. Also dexp_xᵀ = dexp_{−x}
//!   (x̂ᵀ = −x̂, (x̂²)ᵀ = x̂²) and dexp_x = Ad_{exp x} dexp_{−x}.
//! - [`dexp_inverse`]`(x)` = I − ½ x̂ + D(θ) x̂², D = (1 − (θ/2) cot(θ/2))/θ², valid for θ < 2π.
//! - [`log`] returns the rotation vector with |x| ≤ π.
//!
//! # Dual numbers
//! Every function is generic over [`Scalar`], so num-dual can differentiate through it. The
//! coefficient functions A, B, C, D are even in θ: near θ = 0 they are evaluated as Taylor
//! polynomials in θ² (the branch is chosen on the *real* part of θ²), which keeps the dual
//! parts exact at and near x = 0. (nalgebra's `Rotation3::new` returns an exact identity for
//! small angles and would drop the derivative; it is not used here.) Away from zero the
//! closed forms are evaluated without cancellation (1 − cos θ = 2 sin²(θ/2)).

use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};

/// A 3×3 matrix over `D`.
pub type Matrix3<D> = SMatrix<D, 3, 3>;
/// A 3-vector over `D` (an element of ℝ³ ≅ so(3) or of its dual).
pub type Vector3<D> = SVector<D, 3>;

/// θ² below which the coefficient functions use their Taylor polynomials in θ² (degree 4; at
/// the threshold, θ = 0.1, the first omitted term is below 3·10⁻¹⁸ relative).
const SERIES_THRESHOLD: f64 = 1e-2;

/// Evaluate Σ_k c_k tᵏ by Horner's rule.
pub(crate) fn horner<D: Scalar>(t: D, coefficients: &[f64]) -> D {
    let mut sum = D::from(0.0);
    for c in coefficients.iter().rev() {
        sum = sum * t + *c;
    }
    sum
}

/// Taylor coefficients of A = sin θ/θ in t = θ² (degree 4: for t < 10⁻² the first omitted
/// term is below 3·10⁻¹⁸ relative).
const A_SERIES: [f64; 5] = [1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362_880.0];
/// Taylor coefficients of B = (1 − cos θ)/θ² in t = θ².
const B_SERIES: [f64; 5] = [
    0.5,
    -1.0 / 24.0,
    1.0 / 720.0,
    -1.0 / 40_320.0,
    1.0 / 3_628_800.0,
];
/// Taylor coefficients of C = (θ − sin θ)/θ³ in t = θ².
const C_SERIES: [f64; 5] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
];

/// (A, B) near zero.
fn rodrigues_series<D: Scalar>(t: D) -> (D, D) {
    (horner(t, &A_SERIES), horner(t, &B_SERIES))
}

/// A and B of Rodrigues' formula at θ² = t (what [`exp`] needs).
fn rodrigues_coefficients<D: Scalar>(t: D) -> (D, D) {
    if t.re() < SERIES_THRESHOLD {
        rodrigues_series(t)
    } else {
        let theta = t.sqrt();
        let (half_sin, half_cos) = (theta * 0.5).sin_cos();
        // sin θ = 2 sin(θ/2) cos(θ/2), 1 − cos θ = 2 sin²(θ/2).
        (
            half_sin * half_cos * 2.0 / theta,
            half_sin * half_sin * 2.0 / t,
        )
    }
}

/// B and C of dexp at θ² = t (what [`dexp`] and [`body_velocity`] need).
fn dexp_coefficients<D: Scalar>(t: D) -> (D, D) {
    if t.re() < SERIES_THRESHOLD {
        (horner(t, &B_SERIES), horner(t, &C_SERIES))
    } else {
        let theta = t.sqrt();
        let (half_sin, half_cos) = (theta * 0.5).sin_cos();
        let sin = half_sin * half_cos * 2.0;
        (half_sin * half_sin * 2.0 / t, (theta - sin) / (t * theta))
    }
}

/// The coefficient functions of Rodrigues' formula and of dexp at the rotation vector x.
///
/// The fields are even functions of θ = |x|, exact to a few ulps for all θ (series near 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients<D> {
    /// θ² = x·x.
    pub theta_squared: D,
    /// A = sin θ/θ.
    pub a: D,
    /// B = (1 − cos θ)/θ².
    pub b: D,
    /// C = (θ − sin θ)/θ³.
    pub c: D,
}

impl<D: Scalar> Coefficients<D> {
    /// The coefficients at x.
    pub fn new(x: &Vector3<D>) -> Self {
        let t = x.dot(x);
        if t.re() < SERIES_THRESHOLD {
            Self::series(t)
        } else {
            Self::closed(t)
        }
    }

    /// Taylor polynomials in t = θ²: sin θ/θ = Σ (−t)ᵏ/(2k+1)!,
    /// (1 − cos θ)/θ² = Σ (−t)ᵏ/(2k+2)!, (θ − sin θ)/θ³ = Σ (−t)ᵏ/(2k+3)!.
    fn series(t: D) -> Self {
        let (a, b) = rodrigues_series(t);
        Coefficients {
            theta_squared: t,
            a,
            b,
            c: horner(t, &C_SERIES),
        }
    }

    /// Closed forms, with 1 − cos θ = 2 sin²(θ/2).
    fn closed(t: D) -> Self {
        let theta = t.sqrt();
        let (half_sin, half_cos) = (theta * 0.5).sin_cos();
        let sin = half_sin * half_cos * 2.0;
        let a = sin / theta;
        let b = half_sin * half_sin * 2.0 / t;
        let c = (theta - sin) / (t * theta);
        Coefficients {
            theta_squared: t,
            a,
            b,
            c,
        }
    }
}

/// The skew matrix x̂ with x̂ y = x × y.
#[inline]
pub fn hat<D: Scalar>(x: &Vector3<D>) -> Matrix3<D> {
    let zero = D::from(0.0);
    Matrix3::new(zero, -x[2], x[1], x[2], zero, -x[0], -x[1], x[0], zero)
}

/// The vector of the skew part of m: vee(x̂) = x, and vee(M) = ½ vee(M − Mᵀ) in general.
#[inline]
pub fn vee<D: Scalar>(m: &Matrix3<D>) -> Vector3<D> {
    Vector3::new(
        (m[(2, 1)] - m[(1, 2)]) * 0.5,
        (m[(0, 2)] - m[(2, 0)]) * 0.5,
        (m[(1, 0)] - m[(0, 1)]) * 0.5,
    )
}

/// The cross product x × y.
#[inline]
pub fn cross<D: Scalar>(x: &Vector3<D>, y: &Vector3<D>) -> Vector3<D> {
    Vector3::new(
        x[1] * y[2] - x[2] * y[1],
        x[2] * y[0] - x[0] * y[2],
        x[0] * y[1] - x[1] * y[0],
    )
}

/// exp(x) − I = A x̂ + B x̂², computed without forming I + (small): adding this increment to
/// a rotation keeps its round-off proportional to |x|.
#[inline]
pub fn exp_minus_identity<D: Scalar>(x: &Vector3<D>) -> Matrix3<D> {
    let (a, b) = rodrigues_coefficients(x.dot(x));
    let h = hat(x);
    h * a + h * h * b
}

/// The exponential map so(3) → SO(3) (Rodrigues' formula), exact to a few ulps for all x and
/// differentiable through dual numbers at and near x = 0.
#[inline]
pub fn exp<D: Scalar>(x: &Vector3<D>) -> Matrix3<D> {
    exp_minus_identity(x) + Matrix3::identity()
}

/// The right-trivialised derivative of exp: dexp_x = Σ ad_xⁿ/(n + 1)! = I + B x̂ + C x̂², with
/// d/dt exp(x(t)) = (dexp_x ẋ)^ exp(x). The left-trivialised derivative is `dexp(-x)`.
#[inline]
pub fn dexp<D: Scalar>(x: &Vector3<D>) -> Matrix3<D> {
    let (b, c) = dexp_coefficients(x.dot(x));
    let h = hat(x);
    Matrix3::identity() + h * b + h * h * c
}

/// The body angular velocity Ω = (exp(−x) d/dt exp(x))^∨ = dexp_{−x} ẋ of the curve exp(x(t)),
/// at x with rate ẋ (without forming the matrix).
#[inline]
pub fn body_velocity<D: Scalar>(x: &Vector3<D>, rate: &Vector3<D>) -> Vector3<D> {
    let (b, c) = dexp_coefficients(x.dot(x));
    let first = cross(x, rate);
    let second = cross(x, &first);
    rate - first * b + second * c
}

/// The inverse of [`dexp`]: dexp_x⁻¹ = I − ½ x̂ + D x̂², D = (1 − (θ/2) cot(θ/2))/θ², for
/// |x| < 2π.
#[inline]
pub fn dexp_inverse<D: Scalar>(x: &Vector3<D>) -> Matrix3<D> {
    let t = x.dot(x);
    let d = if t.re() < SERIES_THRESHOLD {
        // D = Σ_k (−1)^k B_{2k+2} 4^{k+1} tᵏ/(2k+2)! … = 1/12 + t/720 + t²/30240 + …
        horner(
            t,
            &[
                1.0 / 12.0,
                1.0 / 720.0,
                1.0 / 30_240.0,
                1.0 / 1_209_600.0,
                1.0 / 47_900_160.0,
                691.0 / 1_307_674_368_000.0,
            ],
        )
    } else {
        let theta = t.sqrt();
        let (half_sin, half_cos) = (theta * 0.5).sin_cos();
        (D::from(1.0) - theta * 0.5 * half_cos / half_sin) / t
    };
    let h = hat(x);
    Matrix3::identity() - h * D::from(0.5) + h * h * d
}

/// The logarithm SO(3) → so(3): the rotation vector x with exp(x) = r and |x| ≤ π.
///
/// The angle is θ = atan2(|vee(r − rᵀ)|, (tr r − 1)/2), accurate at all angles; the axis
/// comes from the skew part of r except near θ = π, where it is read from the symmetric part
/// r + rᵀ = 2 cos θ I + 2(1 − cos θ) n nᵀ. `r` is assumed orthogonal.
pub fn log<D: Scalar>(r: &Matrix3<D>) -> Vector3<D> {
    let skew = vee(r);
    let s2 = skew.dot(&skew);
    let cos = (r[(0, 0)] + r[(1, 1)] + r[(2, 2)] - 1.0) * 0.5;
    if s2.re() < 1e-6 && cos.re() > 0.0 {
        // θ small: x = skew · θ/sin θ, with θ/sin θ a series in sin²θ:
        // θ/sin θ = 1 + s²/6 + 3s⁴/40 + 5s⁶/112 + 35s⁸/1152 + …
        let factor = horner(
            s2,
            &[1.0, 1.0 / 6.0, 3.0 / 40.0, 5.0 / 112.0, 35.0 / 1152.0],
        );
        return skew * factor;
    }
    let sin = s2.sqrt();
    let theta = sin.atan2(cos);
    if cos.re() > -0.5 {
        return skew * (theta / sin);
    }
    // Near θ = π: n nᵀ = (S − cos θ I)/(1 − cos θ), S = (r + rᵀ)/2; take the column with the
    // largest diagonal entry, and the sign from the skew part (sin θ n).
    let one_minus_cos = D::from(1.0) - cos;
    let diagonal = |i: usize| (r[(i, i)] - cos) / one_minus_cos;
    let mut k = 0;
    for i in 1..3 {
        if diagonal(i).re() > diagonal(k).re() {
            k = i;
        }
    }
    let nk = diagonal(k).sqrt();
    let mut n = Vector3::zeros();
    for i in 0..3 {
        n[i] = if i == k {
            nk
        } else {
            (r[(i, k)] + r[(k, i)]) * 0.5 / one_minus_cos / nk
        };
    }
    if n.dot(&skew).re() < 0.0 {
        n = -n;
    }
    n * theta
}

/// ‖rᵀr − I‖ in the Frobenius norm: the distance of `r` from orthogonality.
pub fn orthogonality_error(r: &Matrix3<f64>) -> f64 {
    (r.transpose() * r - Matrix3::identity()).norm()
}

/// The unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix (Shepperd's method: the
/// largest of the four squared components is taken first, so no division by a small number).
pub fn quaternion(r: &Matrix3<f64>) -> [f64; 4] {
    let trace = r[(0, 0)] + r[(1, 1)] + r[(2, 2)];
    let candidates = [trace, r[(0, 0)], r[(1, 1)], r[(2, 2)]];
    let mut k = 0;
    for i in 1..4 {
        if candidates[i] > candidates[k] {
            k = i;
        }
    }
    let mut q = match k {
        0 => {
            let w = 0.5 * (1.0 + trace).max(0.0).sqrt();
            let f = 0.25 / w;
            [
                w,
                (r[(2, 1)] - r[(1, 2)]) * f,
                (r[(0, 2)] - r[(2, 0)]) * f,
                (r[(1, 0)] - r[(0, 1)]) * f,
            ]
        }
        1 => {
            let x = 0.5 * (1.0 + 2.0 * r[(0, 0)] - trace).max(0.0).sqrt();
            let f = 0.25 / x;
            [
                (r[(2, 1)] - r[(1, 2)]) * f,
                x,
                (r[(0, 1)] + r[(1, 0)]) * f,
                (r[(0, 2)] + r[(2, 0)]) * f,
            ]
        }
        2 => {
            let y = 0.5 * (1.0 + 2.0 * r[(1, 1)] - trace).max(0.0).sqrt();
            let f = 0.25 / y;
            [
                (r[(0, 2)] - r[(2, 0)]) * f,
                (r[(0, 1)] + r[(1, 0)]) * f,
                y,
                (r[(1, 2)] + r[(2, 1)]) * f,
            ]
        }
        _ => {
            let z = 0.5 * (1.0 + 2.0 * r[(2, 2)] - trace).max(0.0).sqrt();
            let f = 0.25 / z;
            [
                (r[(1, 0)] - r[(0, 1)]) * f,
                (r[(0, 2)] + r[(2, 0)]) * f,
                (r[(1, 2)] + r[(2, 1)]) * f,
                z,
            ]
        }
    };
    if q[0] < 0.0 {
        q.iter_mut().for_each(|c| *c = -*c);
    }
    q
}

/// The rotation matrix of a unit quaternion (w, x, y, z), the inverse of [`quaternion`] (q and
/// −q give the same rotation).
pub fn rotation(q: &[f64; 4]) -> Matrix3<f64> {
    let [w, x, y, z] = *q;
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{DualSVec64, jacobian};

    fn vectors() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(1e-9, 2e-9, -1e-9),
            Vector3::new(0.05, 0.04, -0.06),
            Vector3::new(0.06, 0.05, -0.07),
            Vector3::new(1.2, 2.0, -0.4),
            Vector3::new(0.0, 0.0, 3.1),
            Vector3::new(-1.7, 1.1, 2.2),
        ]
    }

    #[test]
    fn hat_and_vee_are_inverse_and_give_the_cross_product() {
        let x = Vector3::new(1.0, -2.0, 0.5);
        let y = Vector3::new(0.3, 0.7, -1.1);
        assert_eq!(vee(&hat(&x)), x);
        assert!((hat(&x) * y - x.cross(&y)).amax() < 1e-15);
        assert!((cross(&x, &y) - x.cross(&y)).amax() < 1e-15);
    }

    #[test]
    fn exp_is_orthogonal_and_matches_the_matrix_series() {
        for x in vectors() {
            let r = exp(&x);
            assert!(orthogonality_error(&r) <= 4.0 * f64::EPSILON, "{x:?}");
            // The increment M = exp(x) − I is orthogonal in the sense (I + M)ᵀ(I + M) = I,
            // i.e. M + Mᵀ + MᵀM = 0, to round-off relative to |x|: adding it to a rotation
            // does not carry the round-off of 1 + small.
            let m = exp_minus_identity(&x);
            let defect = (m + m.transpose() + m.transpose() * m).norm();
            let bound = 4.0 * f64::EPSILON * x.norm().min(1.0);
            assert!(defect <= bound, "{x:?}: {defect:e}");
            assert!((r.determinant() - 1.0).abs() < 1e-15);
            // Matrix Taylor series with many terms.
            let h = hat(&x);
            let mut term = Matrix3::identity();
            let mut sum = Matrix3::identity();
            for n in 1..60 {
                term = term * h / n as f64;
                sum += term;
            }
            assert!((r - sum).amax() < 1e-14, "{x:?}");
        }
    }

    #[test]
    fn log_inverts_exp_at_all_angles() {
        for x in vectors() {
            let y = log(&exp(&x));
            assert!((y - x).amax() < 1e-14 * (1.0 + x.norm()), "{x:?} -> {y:?}");
        }
        // Exactly π and just below.
        for angle in [std::f64::consts::PI - 1e-7, std::f64::consts::PI - 1e-3] {
            let x = Vector3::new(0.6, 0.0, 0.8) * angle;
            let y = log(&exp(&x));
            assert!((y - x).amax() < 1e-8, "{x:?} -> {y:?}");
        }
        assert_eq!(log(&Matrix3::<f64>::identity()), Vector3::zeros());
    }

    #[test]
    fn series_and_closed_forms_agree_at_the_branch_point() {
        for t in [
            SERIES_THRESHOLD * 0.5,
            SERIES_THRESHOLD,
            SERIES_THRESHOLD * 2.0,
        ] {
            let series = Coefficients::<f64>::series(t);
            let closed = Coefficients::<f64>::closed(t);
            assert!((series.a - closed.a).abs() < 3e-16, "{t}");
            assert!((series.b - closed.b).abs() < 2e-16, "{t}");
            let x = Vector3::new(0.0, 0.0, t.sqrt());
            let (a, b) = rodrigues_coefficients(x.dot(&x));
            let (b2, c) = dexp_coefficients(x.dot(&x));
            let k = Coefficients::new(&x);
            assert!((a - k.a).abs() < 3e-16 && (b - k.b).abs() < 2e-16);
            assert!((b2 - k.b).abs() < 2e-16 && (c - k.c).abs() < 1e-13);
            // C's closed form loses ~eps/θ² to cancellation.
            assert!((series.c - closed.c).abs() < 1e-13, "{t}");
            let x = Vector3::new(0.0, 0.0, t.sqrt());
            let inverse = dexp_inverse(&x) * dexp(&x);
            assert!((inverse - Matrix3::identity()).amax() < 1e-15);
        }
    }

    /// Central difference of t ↦ exp(x + t v) at t = 0.
    fn exp_derivative(x: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
        let e = 1e-5;
        let f = |t: f64| exp(&(x + v * t));
        // Fourth-order central difference.
        (f(-2.0 * e) - f(-e) * 8.0 + f(e) * 8.0 - f(2.0 * e)) / (12.0 * e)
    }

    #[test]
    fn dexp_is_the_right_and_dexp_of_minus_x_the_left_trivialised_derivative() {
        let v = Vector3::new(0.4, -1.3, 0.9);
        for x in vectors() {
            let derivative = exp_derivative(&x, &v);
            let r = exp(&x);
            let right = vee(&(derivative * r.transpose()));
            let left = vee(&(r.transpose() * derivative));
            assert!((right - dexp(&x) * v).amax() < 1e-10, "{x:?}");
            assert!((left - dexp(&(-x)) * v).amax() < 1e-10, "{x:?}");
            assert!((left - body_velocity(&x, &v)).amax() < 1e-10, "{x:?}");
            // Identities: dexp_xᵀ = dexp_{−x}, dexp_x = Ad_exp(x) dexp_{−x}, dexp⁻¹.
            assert!((dexp(&x).transpose() - dexp(&(-x))).amax() < 1e-15);
            assert!((dexp(&x) - r * dexp(&(-x))).amax() < 1e-14);
            assert!((dexp_inverse(&x) * dexp(&x) - Matrix3::identity()).amax() < 1e-14);
        }
    }

    #[test]
    fn dual_parts_survive_at_and_near_zero() {
        // d/dx exp(x)·y at x = 0 is −ŷ (exp(x)y ≈ y + x × y), and at small x the Jacobian
        // agrees with finite differences.
        let y = Vector3::new(0.2, -0.7, 1.1);
        for x in [Vector3::zeros(), Vector3::new(1e-6, -2e-6, 3e-7)] {
            let (_, jac) = jacobian(
                |z: Vector3<DualSVec64<3>>| exp(&z) * y.map(DualSVec64::<3>::from),
                &x,
            );
            assert!((jac + hat(&y)).amax() < 1e-5, "{jac}");
            let e = 1e-6;
            for j in 0..3 {
                let mut step = Vector3::zeros();
                step[j] = e;
                let column = (exp(&(x + step)) * y - exp(&(x - step)) * y) / (2.0 * e);
                assert!((jac.column(j) - column).amax() < 1e-9);
            }
        }
        // The Jacobian of the body velocity at x = 0 in x is ½ ŷ for rate y.
        let (_, jac) = jacobian(
            |z: Vector3<DualSVec64<3>>| body_velocity(&z, &y.map(DualSVec64::<3>::from)),
            &Vector3::zeros(),
        );
        assert!((jac - hat(&y) * 0.5).amax() < 1e-15);
        // log through duals: d log(exp(x))/dx = I at small x.
        let x = Vector3::new(1e-5, 2e-5, -1e-5);
        let (_, jac) = jacobian(|z: Vector3<DualSVec64<3>>| log(&exp(&z)), &x);
        assert!((jac - Matrix3::identity()).amax() < 1e-9);
    }

    #[test]
    fn dual_derivatives_match_finite_differences_away_from_zero() {
        let rate = Vector3::new(0.4, -1.3, 0.9);
        for x in vectors() {
            let (_, jac) = jacobian(
                |z: Vector3<DualSVec64<3>>| body_velocity(&z, &rate.map(DualSVec64::<3>::from)),
                &x,
            );
            let e = 1e-6;
            for j in 0..3 {
                let mut step = Vector3::zeros();
                step[j] = e;
                let column = (body_velocity(&(x + step), &rate)
                    - body_velocity(&(x - step), &rate))
                    / (2.0 * e);
                assert!((jac.column(j) - column).amax() < 1e-8, "{x:?}");
            }
        }
    }

    #[test]
    fn quaternion_matches_the_rotation_vector() {
        for x in [
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(0.0, 3.0, 0.1),
            Vector3::new(2.9, 0.0, 0.0),
            Vector3::new(0.0, 0.0, -3.1),
        ] {
            let q = quaternion(&exp(&x));
            let angle = x.norm();
            let mut expected = [
                (0.5 * angle).cos(),
                x[0] / angle * (0.5 * angle).sin(),
                x[1] / angle * (0.5 * angle).sin(),
                x[2] / angle * (0.5 * angle).sin(),
            ];
            if expected[0] < 0.0 {
                expected.iter_mut().for_each(|c| *c = -*c);
            }
            for i in 0..4 {
                assert!(
                    (q[i] - expected[i]).abs() < 1e-14,
                    "{x:?}: {q:?} vs {expected:?}"
                );
            }
        }
    }

    #[test]
    fn rotation_inverts_quaternion() {
        for x in [Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.0, 3.0, 0.1)] {
            let r = exp(&x);
            assert!((rotation(&quaternion(&r)) - r).amax() < 1e-15);
            let q = quaternion(&r).map(|c| -c);
            assert!((rotation(&q) - r).amax() < 1e-15);
        }
    }
}
