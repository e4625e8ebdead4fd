//! Gauss–Legendre quadrature on [−1, 1].
//!
//! The m-point rule integrates polynomials of degree ≤ 2m − 1 exactly. Its nodes are the roots of
//! the Legendre polynomial P_m, found here by Newton's method on the three-term recurrence
//!
//! ```text
//! (k + 1) P_{k+1}(x) = (2k + 1) x P_k(x) − k P_{k−1}(x),   P_0 = 1, P_1 = x,
//! ```
//!
//! started from Tricomi's asymptotic guess x ≈ (1 − 1/(8m²) + 1/(8m³)) cos(π(4i − 1)/(4m + 2)),
//! with the derivative from (1 − x²) P_m'(x) = m (P_{m−1}(x) − x P_m(x)). The weights are
//! w = 2 / ((1 − x²) P_m'(x)²).
//!
//! Three details make the nodes correctly rounded and the weights accurate to a few ulps (checked
//! against 50-digit values for every m ≤ 64: nodes within 1 ulp, weights within 4 ulps, most within
//! 1):
//!
//! - Only the positive roots are computed; the negative ones are their exact mirror images, so the
//!   nodes are exactly antisymmetric, the weights exactly symmetric, and for odd m the middle node
//!   is exactly 0.
//! - The last Newton steps evaluate P_m and P_{m−1} with a compensated recurrence (the rounding
//!   error of every operation recovered exactly by fused multiply–adds and propagated alongside),
//!   as if in twice the working precision. The plain recurrence loses up to a few hundred ulps of
//!   P_{m−1} near the outer roots for m ≈ 60, and that would go straight into the weights.
//! - The weight formula is not stationary at a root: d(ln w)/dx = −2x/(1 − x²) there, which is
//!   large next to ±1, so rounding the root to the nearest `f64` alone would cost the outer weights
//!   tens of ulps. The last Newton correction δ = P_m/P_m' (the sub-ulp distance from the stored
//!   node x̂ to the true root) is used to evaluate the weight at the true root to first order:
//!   w ≈ w(x̂) (1 + 2 x̂ δ / (1 − x̂²)).

use crate::error::Error;
use crate::spectral::MAX_POINTS;

/// Gauss–Legendre quadrature on [−1, 1]: nodes ascending, positive weights.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `points`-point rule, exact for polynomials of degree ≤ 2 · `points` − 1.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] named `"quadrature"` if `points` is 0 or larger than
    /// [`MAX_POINTS`].
    pub fn new(points: usize) -> Result<Self, Error> {
        if points == 0 {
            return Err(Error::invalid(
                "quadrature",
                "a Gauss–Legendre rule needs at least 1 point, got 0",
            ));
        }
        if points > MAX_POINTS {
            return Err(Error::invalid(
                "quadrature",
                format!(
                    "{points} Gauss–Legendre points requested, at most {MAX_POINTS} are supported"
                ),
            ));
        }
        let m = points;
        let mut nodes = vec![0.0; m];
        let mut weights = vec![0.0; m];
        // The i-th largest root (i = 1, …, ⌊m/2⌋) is positive; store it and its mirror image.
        for i in 1..=m / 2 {
            let (x, w) = positive_root(m, i);
            nodes[m - i] = x;
            nodes[i - 1] = -x;
            weights[m - i] = w;
            weights[i - 1] = w;
        }
        if !m.is_multiple_of(2) {
            // x = 0 is a root of P_m for odd m; there (1 − x²) P_m' = m P_{m−1}.
            let (_, p_prev) = legendre_compensated(m, 0.0);
            let d = m as f64 * p_prev;
            nodes[m / 2] = 0.0;
            weights[m / 2] = 2.0 / (d * d);
        }
        Ok(Self { nodes, weights })
    }

    /// The nodes, ascending in (−1, 1).
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// The weights, positive, summing to 2.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Number of points m.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always `false`: a rule has at least one point.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Σᵢ wᵢ f(xᵢ), the rule applied to `f` on [−1, 1].
    pub fn integrate(&self, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(x))
            .sum()
    }
}

/// (P_m(x), P_{m−1}(x)) by the three-term recurrence; m ≥ 1. Plain floating point: accurate
/// enough to steer Newton's method towards a root.
fn legendre(m: usize, x: f64) -> (f64, f64) {
    let (mut p_prev, mut p) = (1.0, x);
    for k in 1..m {
        let k = k as f64;
        let next = ((2.0 * k + 1.0) * x * p - k * p_prev) / (k + 1.0);
        p_prev = p;
        p = next;
    }
    (p, p_prev)
}

/// (P_m(x), P_{m−1}(x)) by the compensated three-term recurrence, m ≥ 1: accurate to about one
/// rounding of the exact values, as if the recurrence ran in twice the working precision.
///
/// The rounding error of every operation of a step is recovered exactly with fused multiply–adds
/// and TwoSum (error-free transformations; the division's remainder is exact too), and the
/// accumulated error c_k is propagated by the same recurrence alongside p_k.
fn legendre_compensated(m: usize, x: f64) -> (f64, f64) {
    let (mut p_prev, mut p) = (1.0, x);
    let (mut c_prev, mut c) = (0.0, 0.0);
    for k in 1..m {
        let kf = k as f64;
        let (a, b, d) = (2.0 * kf + 1.0, kf, kf + 1.0);
        // a·x·p − b·p_prev with the rounding error of each operation.
        let ax = a * x;
        let ax_err = a.mul_add(x, -ax);
        let axp = ax * p;
        let axp_err = ax.mul_add(p, -axp);
        let bq = b * p_prev;
        let bq_err = b.mul_add(p_prev, -bq);
        let (num, num_err) = two_sum(axp, -bq);
        let next = num / d;
        let div_err = (-next).mul_add(d, num) / d;
        let local = div_err + (num_err + axp_err + ax_err * p - bq_err) / d;
        let c_next = (a * x * c - b * c_prev) / d + local;
        (p_prev, p) = (p, next);
        (c_prev, c) = (c, c_next);
    }
    (p + c, p_prev + c_prev)
}

/// s + e = a + b exactly, with s = fl(a + b) (Knuth's TwoSum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// Newton correction δ = P_m(x)/P_m'(x) and the weight formula 2(1 − x²)/(m(P_{m−1} − x P_m))²
/// (which equals 2/((1 − x²) P_m'(x)²)), for 0 ≤ x < 1, from the given (P_m(x), P_{m−1}(x)).
fn newton_and_weight(m: usize, x: f64, (p, p_prev): (f64, f64)) -> (f64, f64) {
    // 1 − x² with a single rounding.
    let one_minus_x2 = (-x).mul_add(x, 1.0);
    // (1 − x²) P_m'(x) = m (P_{m−1}(x) − x P_m(x)).
    let d = m as f64 * (p_prev - x * p);
    let delta = p * one_minus_x2 / d;
    let weight = 2.0 * one_minus_x2 / (d * d);
    (delta, weight)
}

/// The i-th largest root of P_m (1 ≤ i ≤ ⌊m/2⌋, so the root is positive) and its weight.
fn positive_root(m: usize, i: usize) -> (f64, f64) {
    let mf = m as f64;
    let theta = std::f64::consts::PI * (4 * i - 1) as f64 / (4 * m + 2) as f64;
    let mut x = (1.0 - (mf - 1.0) / (8.0 * mf * mf * mf)) * theta.cos();
    // Newton converges quadratically from Tricomi's guess; once the correction is below 1e-12 the
    // next step is at round-off level.
    for _ in 0..100 {
        let (delta, _) = newton_and_weight(m, x, legendre(m, x));
        x -= delta;
        if delta.abs() < 1e-12 {
            break;
        }
    }
    // Polish with accurate values of P_m, so that x is the root rounded to (about) the nearest
    // double.
    let (delta, _) = newton_and_weight(m, x, legendre_compensated(m, x));
    x -= delta;
    // δ is now the sub-ulp distance from x to the true root x*; evaluate the weight at x*.
    let (delta, weight) = newton_and_weight(m, x, legendre_compensated(m, x));
    let weight = weight * (1.0 + 2.0 * x * delta / (-x).mul_add(x, 1.0));
    (x, weight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, SymmetricEigen};

    /// Distance in ulps between two finite doubles of the same sign (or both zero).
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        (a - b).abs() / f64::EPSILON / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
    }

    /// Legendre polynomials P_0, …, P_n at x.
    fn legendre_all(n: usize, x: f64) -> Vec<f64> {
        let mut p = vec![1.0; n + 1];
        if n >= 1 {
            p[1] = x;
        }
        for k in 1..n {
            let kf = k as f64;
            p[k + 1] = ((2.0 * kf + 1.0) * x * p[k] - kf * p[k - 1]) / (kf + 1.0);
        }
        p
    }

    #[test]
    fn zero_points_is_an_error() {
        match GaussLegendre::new(0) {
            Err(Error::InvalidParameter { name, reason }) => {
                assert_eq!(name, "quadrature");
                assert!(reason.contains("at least 1 point"), "{reason}");
            }
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }

    #[test]
    fn too_many_points_is_an_error() {
        assert!(matches!(
            GaussLegendre::new(MAX_POINTS + 1),
            Err(Error::InvalidParameter { ref name, .. }) if name == "quadrature"
        ));
        assert_eq!(
            GaussLegendre::new(MAX_POINTS).map(|q| q.len()).ok(),
            Some(MAX_POINTS)
        );
    }

    #[test]
    fn known_rules_to_two_ulps() {
        let check = |m: usize, nodes: &[f64], weights: &[f64]| {
            let q = GaussLegendre::new(m).unwrap();
            assert_eq!(q.len(), m);
            assert!(!q.is_empty());
            for (k, (&x, &w)) in q.nodes().iter().zip(q.weights()).enumerate() {
                assert!(
                    ulps(x, nodes[k]) <= 2.0,
                    "m = {m}, node {k}: {x} vs {}",
                    nodes[k]
                );
                assert!(
                    ulps(w, weights[k]) <= 2.0,
                    "m = {m}, weight {k}: {w} vs {}",
                    weights[k]
                );
            }
        };
        check(1, &[0.0], &[2.0]);
        let a = 1.0 / 3f64.sqrt();
        check(2, &[-a, a], &[1.0, 1.0]);
        let b = (3.0f64 / 5.0).sqrt();
        check(3, &[-b, 0.0, b], &[5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]);
        // m = 5: x = ±(1/3)√(5 ∓ 2√(10/7)), w = (322 ± 13√70)/900, w₀ = 128/225.
        // Reference values rounded from 40-digit evaluations of these closed forms.
        let (x1, x2) = (0.538_469_310_105_683_1_f64, 0.906_179_845_938_664_f64);
        let (w1, w2) = (0.478_628_670_499_366_47_f64, 0.236_926_885_056_189_08_f64);
        assert!(ulps(x1, (5.0 - 2.0 * (10.0f64 / 7.0).sqrt()).sqrt() / 3.0) <= 2.0);
        assert!(ulps(w2, (322.0 - 13.0 * 70f64.sqrt()) / 900.0) <= 4.0);
        check(
            5,
            &[-x2, -x1, 0.0, x1, x2],
            &[w2, w1, 128.0 / 225.0, w1, w2],
        );
    }

    #[test]
    fn exactly_symmetric() {
        for m in 1..=64 {
            let q = GaussLegendre::new(m).unwrap();
            let (x, w) = (q.nodes(), q.weights());
            for k in 0..m {
                assert_eq!(x[k], -x[m - 1 - k]);
                assert_eq!(w[k], w[m - 1 - k]);
                assert!(w[k] > 0.0);
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]), "m = {m}: not ascending");
            assert!(x[0] > -1.0 && x[m - 1] < 1.0);
            if !m.is_multiple_of(2) {
                assert_eq!(x[m / 2].to_bits(), 0.0f64.to_bits(), "middle node is +0");
            }
        }
    }

    #[test]
    fn weights_sum_to_two() {
        for m in 1..=64 {
            let q = GaussLegendre::new(m).unwrap();
            let sum: f64 = q.weights().iter().sum();
            assert!((sum - 2.0).abs() <= 1e-14, "m = {m}: Σw = {sum}");
            assert!((q.integrate(|_| 1.0) - 2.0).abs() <= 1e-14);
        }
    }

    /// ∫₋₁¹ xᵏ dx for k ≤ 2m − 1. The error is bounded relative to Σᵢ wᵢ|xᵢ|ᵏ (which for even k
    /// is the integral itself): a few ε for the weights and `powi`, k/2 ε because rounding a node
    /// by half an ulp changes xᵏ by k/2 ε relatively, and up to m/2 ε for the summation.
    #[test]
    fn integrates_monomials_exactly() {
        for m in 1..=64 {
            let q = GaussLegendre::new(m).unwrap();
            for k in 0..2 * m {
                let exact = if k.is_multiple_of(2) {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                let got = q.integrate(|x| x.powi(k as i32));
                let scale = q.integrate(|x| x.abs().powi(k as i32));
                let bound = (6.0 + (k + m) as f64 / 2.0) * f64::EPSILON * scale;
                let err = (got - exact).abs();
                assert!(err <= bound, "m = {m}, k = {k}: {got} vs {exact}");
            }
        }
    }

    /// Discrete orthogonality Σᵢ wᵢ P_j(xᵢ) P_k(xᵢ) = 2/(2j + 1) δ_jk for j + k ≤ 2m − 1.
    #[test]
    fn legendre_orthogonality() {
        for m in 1..=64 {
            let q = GaussLegendre::new(m).unwrap();
            let n = 2 * m - 1;
            let table: Vec<Vec<f64>> = q.nodes().iter().map(|&x| legendre_all(n, x)).collect();
            for j in 0..=n {
                for k in j..=(2 * m - 1 - j) {
                    let got: f64 = q
                        .weights()
                        .iter()
                        .zip(&table)
                        .map(|(&w, p)| w * p[j] * p[k])
                        .sum();
                    let exact = if j == k {
                        2.0 / (2.0 * j as f64 + 1.0)
                    } else {
                        0.0
                    };
                    let err = (got - exact).abs();
                    assert!(
                        err <= 5e-15,
                        "m = {m}, (j, k) = ({j}, {k}): {got} vs {exact}"
                    );
                }
            }
        }
    }

    /// Golub–Welsch: nodes are the eigenvalues of the Jacobi matrix with off-diagonal
    /// k/√(4k² − 1), weights 2·(first eigenvector component)². An independent (and somewhat less
    /// accurate) computation.
    #[test]
    fn agrees_with_golub_welsch() {
        for m in 1..=64 {
            let jacobi = DMatrix::from_fn(m, m, |i, j| {
                if i.abs_diff(j) == 1 {
                    let k = i.max(j) as f64;
                    k / (4.0 * k * k - 1.0).sqrt()
                } else {
                    0.0
                }
            });
            let eigen = SymmetricEigen::new(jacobi);
            let mut pairs: Vec<(f64, f64)> = (0..m)
                .map(|c| {
                    (
                        eigen.eigenvalues[c],
                        2.0 * eigen.eigenvectors[(0, c)].powi(2),
                    )
                })
                .collect();
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let q = GaussLegendre::new(m).unwrap();
            for (k, &(x, w)) in pairs.iter().enumerate() {
                let (dx, dw) = ((q.nodes()[k] - x).abs(), (q.weights()[k] - w).abs());
                assert!(dx <= 2e-14, "m = {m}, node {k}: {} vs {x}", q.nodes()[k]);
                assert!(
                    dw <= 2e-14,
                    "m = {m}, weight {k}: {} vs {w}",
                    q.weights()[k]
                );
            }
        }
    }

    /// Reference values from 50-digit (mpmath) Newton iterations, rounded to the nearest double:
    /// the outermost node and weight (where the weight is most sensitive to the node) and the
    /// smallest positive node and its weight.
    #[test]
    fn matches_high_precision_references() {
        // (m, largest node, its weight, smallest positive node, its weight)
        let reference: [(usize, f64, f64, f64, f64); 5] = [
            (
                10,
                0.9739065285171717,
                0.06667134430868814,
                0.14887433898163122,
                0.29552422471475287,
            ),
            (
                20,
                0.9931285991850949,
                0.017614007139152118,
                0.07652652113349734,
                0.15275338713072584,
            ),
            (
                32,
                0.9972638618494816,
                0.007018610009470096,
                0.04830766568773832,
                0.0965400885147278,
            ),
            (
                48,
                0.9987710072524261,
                0.0031533460523058385,
                0.03238017096286936,
                0.06473769681268392,
            ),
            (
                64,
                0.9993050417357722,
                0.001783280721696433,
                0.024350292663424433,
                0.048690957009139724,
            ),
        ];
        for (m, x_out, w_out, x_in, w_in) in reference {
            let q = GaussLegendre::new(m).unwrap();
            let (x, w) = (q.nodes(), q.weights());
            assert!(
                ulps(x[m - 1], x_out) <= 1.0,
                "m = {m}: {} vs {x_out}",
                x[m - 1]
            );
            assert!(
                ulps(x[m / 2], x_in) <= 1.0,
                "m = {m}: {} vs {x_in}",
                x[m / 2]
            );
            assert!(
                ulps(w[m - 1], w_out) <= 4.0,
                "m = {m}: {} vs {w_out}",
                w[m - 1]
            );
            assert!(
                ulps(w[m / 2], w_in) <= 4.0,
                "m = {m}: {} vs {w_in}",
                w[m / 2]
            );
        }
    }

    /// Large rules stay well formed: ascending, inside (−1, 1), positive weights summing to 2,
    /// exact on a few moments.
    #[test]
    fn large_rules_are_well_formed() {
        for m in [100, 200, MAX_POINTS] {
            let q = GaussLegendre::new(m).unwrap();
            assert!(q.nodes().windows(2).all(|p| p[0] < p[1]), "m = {m}");
            assert!(q.nodes()[0] > -1.0 && q.nodes()[m - 1] < 1.0);
            assert!(q.weights().iter().all(|&w| w > 0.0));
            assert!((q.integrate(|_| 1.0) - 2.0).abs() <= 1e-13, "m = {m}");
            assert!(
                (q.integrate(|x| x * x) - 2.0 / 3.0).abs() <= 1e-13,
                "m = {m}"
            );
            let exact = 2.0 * 1f64.sin();
            assert!((q.integrate(f64::cos) - exact).abs() <= 1e-13, "m = {m}");
        }
    }
}
