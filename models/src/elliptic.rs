//! Jacobi elliptic functions and elliptic integrals of the first kind, for the pendulum's
//! closed-form solution.
//!
//! Parameter convention: m = k² (Abramowitz & Stegun, ch. 16–17), 0 ≤ m < 1.
//!
//! - [`complete_first_kind`]: K(m) = π / (2 AGM(1, √(1 − m))) (A&S 17.6).
//! - [`first_kind`]: F(φ | m) = sin φ · R_F(cos²φ, 1 − m sin²φ, 1) for |φ| ≤ π/2 (Carlson
//!   1995, eq. 4.5), extended to every real φ by F(φ + jπ) = F(φ) + 2jK.
//! - [`amplitude`]: am(u | m), the inverse of F, by the descending AGM (A&S 16.4), after
//!   reducing u by multiples of 2K (am(u + 2jK) = am(u) + jπ) so that the result stays
//!   accurate for large u.
//!
//! References: M. Abramowitz, I. Stegun, *Handbook of Mathematical Functions*, §16.4 and
//! §17.6; B. C. Carlson, *Numerical computation of real or complex elliptic integrals*,
//! Numer. Algorithms 10 (1995).

use std::f64::consts::{FRAC_PI_2, PI};

/// Iteration cap of the AGM and duplication loops (each converges in well under 40 steps).
const MAX_ITERATIONS: usize = 64;

/// Carlson's symmetric integral R_F(x, y, z) = ½ ∫₀^∞ dt / √((t + x)(t + y)(t + z)) for
/// x, y, z ≥ 0, at most one of them zero (duplication algorithm of Carlson 1995, §2).
pub(crate) fn carlson_rf(x: f64, y: f64, z: f64) -> f64 {
    let (mut x, mut y, mut z) = (x, y, z);
    let mut mean = (x + y + z) / 3.0;
    // Carlson's stopping rule for a relative error below r = ε: stop when
    // 4⁻ⁿ (3r)^(−1/6) max|A₀ − x₀| < |Aₙ|.
    let mut spread = (3.0 * f64::EPSILON).powf(-1.0 / 6.0)
        * (mean - x).abs().max((mean - y).abs()).max((mean - z).abs());
    for _ in 0..MAX_ITERATIONS {
        if spread < mean.abs() {
            break;
        }
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sx * sz + sy * sz;
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
        mean = 0.25 * (mean + lambda);
        spread *= 0.25;
    }
    let dx = 1.0 - x / mean;
    let dy = 1.0 - y / mean;
    let dz = -dx - dy;
    let e2 = dx * dy - dz * dz;
    let e3 = dx * dy * dz;
    (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / mean.sqrt()
}

/// The arithmetic–geometric mean of `a` and `b` (both ≥ 0).
fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..MAX_ITERATIONS {
        if (a - b).abs() <= f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    0.5 * (a + b)
}

/// The complete elliptic integral of the first kind K(m), 0 ≤ m < 1.
pub(crate) fn complete_first_kind(m: f64) -> f64 {
    FRAC_PI_2 / agm(1.0, (1.0 - m).sqrt())
}

/// The incomplete elliptic integral of the first kind F(φ | m) for any real φ, 0 ≤ m < 1;
/// `quarter_period` is K(m).
pub(crate) fn first_kind(phi: f64, m: f64, quarter_period: f64) -> f64 {
    let turns = (phi / PI).round();
    let reduced = phi - turns * PI;
    let (sin, cos) = reduced.sin_cos();
    let principal = sin * carlson_rf(cos * cos, 1.0 - m * sin * sin, 1.0);
    principal + 2.0 * turns * quarter_period
}

/// The Jacobi amplitude am(u | m), 0 ≤ m < 1, continuous and increasing in u;
/// `quarter_period` is K(m). Then sn = sin am, cn = cos am, dn = √(1 − m sn²).
pub(crate) fn amplitude(u: f64, m: f64, quarter_period: f64) -> f64 {
    let half_periods = (u / (2.0 * quarter_period)).round();
    let reduced = u - half_periods * 2.0 * quarter_period;
    principal_amplitude(reduced, m) + half_periods * PI
}

/// am(u | m) by the descending AGM (A&S 16.4.1–3); accurate for |u| ≲ K(m).
fn principal_amplitude(u: f64, m: f64) -> f64 {
    if m == 0.0 {
        return u;
    }
    let mut a = [0.0; MAX_ITERATIONS + 1];
    let mut c = [0.0; MAX_ITERATIONS + 1];
    a[0] = 1.0;
    c[0] = m.sqrt();
    let mut b = (1.0 - m).sqrt();
    let mut last = 0;
    while last < MAX_ITERATIONS && c[last].abs() > f64::EPSILON * a[last] {
        a[last + 1] = 0.5 * (a[last] + b);
        c[last + 1] = 0.5 * (a[last] - b);
        b = (a[last] * b).sqrt();
        last += 1;
    }
    let mut phi = 2f64.powi(last as i32) * a[last] * u;
    for n in (1..=last).rev() {
        phi = 0.5 * (phi + (c[n] / a[n] * phi.sin()).asin());
    }
    phi
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn complete_integral_matches_tabulated_values() {
        // A&S Table 17.1 / DLMF 19.2: K(0) = π/2, K(1/2) = 1.854074677301372, K(0.9) =
        // 2.578092113348173.
        assert_relative_eq!(complete_first_kind(0.0), FRAC_PI_2, max_relative = 1e-16);
        assert_relative_eq!(
            complete_first_kind(0.5),
            1.854_074_677_301_372,
            max_relative = 1e-15
        );
        assert_relative_eq!(
            complete_first_kind(0.9),
            2.578_092_113_348_173,
            max_relative = 1e-15
        );
    }

    #[test]
    fn incomplete_integral_reaches_the_complete_one_and_is_odd() {
        for m in [0.0, 0.3, 0.9, 0.999] {
            let k = complete_first_kind(m);
            assert_relative_eq!(first_kind(FRAC_PI_2, m, k), k, max_relative = 1e-14);
            assert_relative_eq!(first_kind(-0.7, m, k), -first_kind(0.7, m, k));
            assert_relative_eq!(
                first_kind(0.7 + 3.0 * PI, m, k),
                first_kind(0.7, m, k) + 6.0 * k,
                max_relative = 1e-14
            );
        }
        // m = 0: F(φ | 0) = φ.
        assert_relative_eq!(first_kind(1.2, 0.0, FRAC_PI_2), 1.2, max_relative = 1e-15);
    }

    #[test]
    fn amplitude_inverts_the_incomplete_integral() {
        for m in [0.0, 0.1, 0.5, 0.9, 0.99] {
            let k = complete_first_kind(m);
            for phi in [-7.0, -1.5, -0.3, 0.0, 0.2, 1.0, 1.57, 2.5, 40.0] {
                let u = first_kind(phi, m, k);
                assert!(
                    (amplitude(u, m, k) - phi).abs() <= 1e-14 * phi.abs().max(1.0),
                    "m = {m}, φ = {phi}: am(F(φ)) = {}",
                    amplitude(u, m, k)
                );
            }
        }
    }

    #[test]
    fn amplitude_derivative_is_dn() {
        // d am / du = dn(u) = √(1 − m sn²), by central differences.
        let (m, h) = (0.7, 1e-5);
        let k = complete_first_kind(m);
        for u in [-3.0, 0.1, 1.3, 9.0] {
            let derivative = (amplitude(u + h, m, k) - amplitude(u - h, m, k)) / (2.0 * h);
            let dn = (1.0 - m * amplitude(u, m, k).sin().powi(2)).sqrt();
            assert_relative_eq!(derivative, dn, max_relative = 1e-9);
        }
    }
}
