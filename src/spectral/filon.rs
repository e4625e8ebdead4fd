//! Filon–Lobatto quadrature of oscillatory integrals on [−1, 1].
//!
//! # The rule
//!
//! A Filon-type method (Leok 2004, §5.7.2, summarising Iserles 2003a, §3) integrates
//!
//! ```text
//! I[f](θ) = ∫₋₁¹ f(x) e^{iθx} dx ≈ Σⱼ wⱼ(θ) f(xⱼ),   wⱼ(θ) = ∫₋₁¹ lⱼ(x) e^{iθx} dx,
//! ```
//!
//! interpolating the smooth factor f at nodes xⱼ by the Lagrange basis lⱼ and integrating the
//! interpolant times the oscillatory factor exactly; the weights depend on θ. (The thesis
//! calls the lⱼ "Legendre polynomials"; they are the Lagrange polynomials of the nodes.) The
//! cosine and sine parts of the weights, Re wⱼ and Im wⱼ, integrate f cos θx and f sin θx.
//!
//! **Scaling.** On a step [t_k, t_k + h] with t = t_k + (h/2)(1 + x),
//!
//! ```text
//! ∫_{t_k}^{t_k+h} g(t) e^{iωt} dt = (h/2) e^{iω(t_k + h/2)} ∫₋₁¹ g(t(x)) e^{iθx} dx,   θ = hω/2,
//! ```
//!
//! so the issue's range hω ∈ [0, 10⁴] is θ ∈ [0, 5·10³].
//!
//! **Nodes: Gauss–Lobatto–Legendre.** The n nodes are ±1 and the n − 2 roots of P′_{n−1}.
//! With both end points among the nodes the error decays like O(θ⁻²) as θ → ∞ (the leading
//! terms of the asymptotic expansion of I(f), f(±1) e^{±iθ}/(±iθ), are reproduced exactly),
//! against O(θ⁻¹) without them (Leok's table after the Filon rule, after Iserles). Among node
//! sets with end points, the Lobatto ones (rather than Chebyshev–Gauss–Lobatto) are chosen
//! because at θ = 0 the rule is then the Lobatto rule, exact for degree 2n − 3 (the
//! O(h^{p+1}) regime of hω ≪ 1 with the best p), and because the Legendre coefficients of the
//! lⱼ have a closed form by the discrete orthogonality of the Lobatto rule.
//!
//! # Computing the weights
//!
//! The monomial moments ∫ xᵏ e^{iθx} dx by upward recurrence (integration by parts) lose
//! about k·log₁₀(1/θ) digits for small θ; instead the weights are expanded in the Legendre
//! basis, whose moments are spherical Bessel functions (DLMF 18.17.19 with 10.47.3):
//!
//! ```text
//! ∫₋₁¹ P_k(x) e^{iθx} dx = 2 iᵏ j_k(θ),
//! lⱼ(x) = Σ_{k<n} C_kj P_k(x),   C_kj = ρⱼ P_k(xⱼ)/γ_k,
//! wⱼ(θ) = Σ_{k<n} C_kj 2 iᵏ j_k(θ),
//! ```
//!
//! with ρⱼ the Lobatto weights and γ_k = Σⱼ ρⱼ P_k(xⱼ)² = 2/(2k + 1) for k < n − 1 and
//! 2/(n − 1) for k = n − 1 (the Lobatto rule is exact for P_k² up to k = n − 2; for k = n − 1
//! see Canuto et al., *Spectral Methods*, eq. 2.3.13). At θ = 0 only j₀ = 1 survives and
//! wⱼ = ρⱼ: the Lobatto rule.
//!
//! The j_k(θ), k < n, are computed without loss for every θ ≥ 0:
//!
//! - j₀ = sin θ/θ (1 at θ = 0), and for θ ≥ 1, j₁ = (j₀ − cos θ)/θ and the upward recurrence
//!   j_{k+1} = ((2k + 1)/θ) j_k − j_{k−1} up to k₀ = ⌊θ⌋, where it is stable (the
//!   recurrence's dominant solution is j_k itself while k ≲ θ);
//! - beyond k₀ (and for every k ≥ 1 when θ < 1, where the upward recurrence loses everything)
//!   the ratios r_k = j_k/j_{k−1} from the downward continued fraction
//!   r_k = θ/((2k + 1) − θ r_{k+1}), started with r = 0 forty-odd orders higher (the ratios
//!   there are below 1/2, so the starting error is damped below round-off), and
//!   j_k = r_k j_{k−1}. The denominators are positive for k > θ, and j_{k₀} > 0 because the
//!   first zero of j_k lies beyond k + 1.
//!
//! In the small-θ limit j_k(θ) = θᵏ/(2k + 1)!! (1 + O(θ²)) comes out of the ratios to full
//! relative accuracy, so nothing is lost as θ → 0.
//!
//! **Accuracy.** Each weight is a sum of n terms of size up to |C_kj| |j_k|; the rounding
//! error is about n² ε relative to Σⱼ|wⱼ| at large θ (where the interior weights are O(θ⁻²)
//! and the end-point weights O(θ⁻¹)). The tests check 1e-14 for n ≤ 12 and n = 16 over
//! θ ∈ [0, 5·10³] (measured: 3.2e-15 up to n = 12, the reference's own level; 6.1e-15 at
//! n = 16; 1.2e-14 at n = 24).

use crate::error::Error;
use crate::spectral::MAX_POINTS;

/// The Filon–Lobatto rule with n Gauss–Lobatto–Legendre nodes for ∫₋₁¹ f(x) e^{iθx} dx (see
/// the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct FilonLobatto {
    /// Gauss–Lobatto–Legendre nodes, ascending, x₀ = −1, x_{n−1} = 1.
    nodes: Vec<f64>,
    /// The Lobatto weights ρⱼ (the rule at θ = 0).
    lobatto: Vec<f64>,
    /// C_kj = ρⱼ P_k(xⱼ)/γ_k, row k, stored at `k * n + j`: the Legendre coefficients of lⱼ.
    coefficients: Vec<f64>,
    /// j_k(θ), k < n, of the last [`FilonLobatto::weights`] call.
    bessel: Vec<f64>,
}

impl FilonLobatto {
    /// The rule with `points` Gauss–Lobatto–Legendre nodes (2 to [`MAX_POINTS`]).
    ///
    /// The interior nodes are the roots of (1 − x²)P′_{n−1}(x) = (n − 1)(P_{n−2}(x) − x P_{n−1}(x)),
    /// found by Newton's method from the Chebyshev–Gauss–Lobatto points (the derivative of
    /// that function is −(n − 1) n P_{n−1}); only the positive ones are computed and mirrored,
    /// so the rule is exactly symmetric. ρⱼ = 2/((n − 1) n P_{n−1}(xⱼ)²).
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] named `"points"` if `points` < 2 or > [`MAX_POINTS`].
    pub fn new(points: usize) -> Result<Self, Error> {
        if !(2..=MAX_POINTS).contains(&points) {
            return Err(Error::invalid(
                "points",
                format!("a Filon–Lobatto rule needs 2 to {MAX_POINTS} nodes, got {points}"),
            ));
        }
        let n = points;
        let degree = n - 1;
        let nf = degree as f64;
        let mut nodes = vec![0.0; n];
        let mut table = vec![0.0; n];
        nodes[0] = -1.0;
        nodes[degree] = 1.0;
        for i in 1..=(n - 2) / 2 {
            // The i-th largest interior node, from the CGL point cos(iπ/(n − 1)).
            let mut x = (std::f64::consts::PI * i as f64 / nf).cos();
            for _ in 0..100 {
                legendre_table(x, &mut table);
                let (p, p_prev) = (table[degree], table[degree - 1]);
                let delta = (p_prev - x * p) / ((nf + 1.0) * p);
                x += delta;
                if delta.abs() <= 1e-15 {
                    break;
                }
            }
            nodes[degree - i] = x;
            nodes[i] = -x;
        }
        // Odd n: the middle node is 0 (P′_{n−1} is odd).
        let mut lobatto = vec![0.0; n];
        let mut coefficients = vec![0.0; n * n];
        for (j, &x) in nodes.iter().enumerate() {
            legendre_table(x, &mut table);
            let rho = 2.0 / (nf * (nf + 1.0) * table[degree] * table[degree]);
            lobatto[j] = rho;
            for (k, &p) in table.iter().enumerate() {
                let gamma = if k == degree {
                    2.0 / nf
                } else {
                    2.0 / (2.0 * k as f64 + 1.0)
                };
                coefficients[k * n + j] = rho * p / gamma;
            }
        }
        Ok(Self {
            nodes,
            lobatto,
            coefficients,
            bessel: vec![0.0; n],
        })
    }

    /// Number of nodes n.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always `false`: a rule has at least two nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The Gauss–Lobatto–Legendre nodes, ascending from −1 to 1.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// The Lobatto weights: the rule at θ = 0, exact for polynomials of degree ≤ 2n − 3.
    pub fn lobatto_weights(&self) -> &[f64] {
        &self.lobatto
    }

    /// Write the weights for the frequency `theta` into `cosine` and `sine` (each of length
    /// n): Σⱼ cosineⱼ f(xⱼ) ≈ ∫₋₁¹ f(x) cos θx dx and Σⱼ sineⱼ f(xⱼ) ≈ ∫₋₁¹ f(x) sin θx dx,
    /// exact for polynomials f of degree < n. Any finite θ (the sine weights are odd in θ).
    /// Does not allocate.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] named `"theta"` if `theta` is not finite, or named
    /// `"weights"` if a slice does not have n elements.
    ///
    /// ```
    /// use svi::spectral::filon::FilonLobatto;
    ///
    /// // ∫₋₁¹ x sin(20x) dx = (sin 20 − 20 cos 20)/200, exactly by the 2-node rule.
    /// let mut rule = FilonLobatto::new(2).unwrap();
    /// let (mut c, mut s) = ([0.0; 2], [0.0; 2]);
    /// rule.weights(20.0, &mut c, &mut s).unwrap();
    /// let exact = (20f64.sin() - 20.0 * 20f64.cos()) / 200.0;
    /// assert!((s[1] - s[0] - exact).abs() < 1e-16);
    /// ```
    pub fn weights(
        &mut self,
        theta: f64,
        cosine: &mut [f64],
        sine: &mut [f64],
    ) -> Result<(), Error> {
        if !theta.is_finite() {
            return Err(Error::invalid(
                "theta",
                format!("the frequency of a Filon rule must be finite, got {theta:?}"),
            ));
        }
        let n = self.nodes.len();
        if cosine.len() != n || sine.len() != n {
            return Err(Error::invalid(
                "weights",
                format!(
                    "{} cosine and {} sine weights for a rule with {n} nodes",
                    cosine.len(),
                    sine.len()
                ),
            ));
        }
        spherical_bessel(theta.abs(), &mut self.bessel);
        cosine.fill(0.0);
        sine.fill(0.0);
        for (k, &bessel) in self.bessel.iter().enumerate() {
            // 2 iᵏ j_k: real for even k, imaginary for odd k, sign (−1)^⌊k/2⌋.
            let moment = if (k / 2) % 2 == 0 { 2.0 } else { -2.0 } * bessel;
            let row = &self.coefficients[k * n..(k + 1) * n];
            let target = if k % 2 == 0 { &mut *cosine } else { &mut *sine };
            for (w, &c) in target.iter_mut().zip(row) {
                *w += c * moment;
            }
        }
        if theta < 0.0 {
            sine.iter_mut().for_each(|w| *w = -*w);
        }
        Ok(())
    }
}

/// P₀(x), …, P_{n−1}(x) into `table` (n ≥ 2) by the three-term recurrence.
fn legendre_table(x: f64, table: &mut [f64]) {
    table[0] = 1.0;
    table[1] = x;
    for k in 1..table.len() - 1 {
        let kf = k as f64;
        table[k + 1] = ((2.0 * kf + 1.0) * x * table[k] - kf * table[k - 1]) / (kf + 1.0);
    }
}

/// Spherical Bessel functions j_k(θ), k < `out.len()`, for θ ≥ 0 (see the module
/// documentation: upward recurrence up to ⌊θ⌋, continued-fraction ratios beyond).
fn spherical_bessel(theta: f64, out: &mut [f64]) {
    let n = out.len();
    out.fill(0.0);
    if theta == 0.0 {
        out[0] = 1.0;
        return;
    }
    out[0] = theta.sin() / theta;
    // Highest order reached by the upward recurrence.
    let upward = if theta < 1.0 {
        0
    } else {
        (theta.floor() as usize).min(n - 1)
    };
    if upward >= 1 {
        out[1] = (out[0] - theta.cos()) / theta;
        for k in 1..upward {
            out[k + 1] = (2.0 * k as f64 + 1.0) / theta * out[k] - out[k - 1];
        }
    }
    if upward + 1 >= n {
        return;
    }
    // Ratios r_k = j_k/j_{k−1} for k > upward, from far above down; stored in out[k].
    let start = n.max(theta.ceil() as usize) + 48;
    let mut ratio = 0.0;
    for k in (upward + 1..=start).rev() {
        ratio = theta / ((2.0 * k as f64 + 1.0) - theta * ratio);
        if k < n {
            out[k] = ratio;
        }
    }
    for k in upward + 1..n {
        out[k] *= out[k - 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::quadrature::GaussLegendre;

    /// (a·b rounded, its rounding error): a·b = p + e exactly.
    fn two_product(a: f64, b: f64) -> (f64, f64) {
        let p = a * b;
        (p, a.mul_add(b, -p))
    }

    /// ∫₋₁¹ f(x) (cos θx, sin θx) dx by composite 20-point Gauss–Legendre on 2^m panels with
    /// θ·(panel width) ≤ 1, independent of the Filon rule. The phase θx is kept to twice the
    /// working precision (the dyadic panel centre c times θ by an exact product, the offset
    /// u/P exact), so rounding of θx (up to θε) does not pollute the reference; panel sums
    /// are added with Kahan compensation.
    fn reference(theta: f64, f: impl Fn(f64) -> f64) -> (f64, f64) {
        let gauss = GaussLegendre::new(20).unwrap();
        let mut panels = 4usize;
        while (panels as f64) < 2.0 * theta {
            panels *= 2;
        }
        let half_width = 1.0 / panels as f64;
        let (mut cos_sum, mut cos_c, mut sin_sum, mut sin_c) = (0.0, 0.0, 0.0, 0.0);
        let kahan = |sum: &mut f64, comp: &mut f64, term: f64| {
            let y = term - *comp;
            let t = *sum + y;
            *comp = (t - *sum) - y;
            *sum = t;
        };
        for p in 0..panels {
            let centre = -1.0 + (2 * p + 1) as f64 * half_width;
            let (phase, phase_err) = two_product(theta, centre);
            let (sin_p, cos_p) = phase.sin_cos();
            let (mut c_panel, mut s_panel) = (0.0, 0.0);
            for (&u, &w) in gauss.nodes().iter().zip(gauss.weights()) {
                let offset = u * half_width; // exact: half_width is a power of 2
                let delta = theta * offset + phase_err;
                let (sin_d, cos_d) = delta.sin_cos();
                let value = w * half_width * f(centre + offset);
                c_panel += value * (cos_p * cos_d - sin_p * sin_d);
                s_panel += value * (sin_p * cos_d + cos_p * sin_d);
            }
            kahan(&mut cos_sum, &mut cos_c, c_panel);
            kahan(&mut sin_sum, &mut sin_c, s_panel);
        }
        (cos_sum, sin_sum)
    }

    /// θ = hω/2 on a log grid: 0, then hω = 10⁻¹⁰, 10⁻⁸, …, 10⁴ with intermediate points.
    fn theta_grid() -> Vec<f64> {
        let mut grid = vec![0.0];
        for e in -10..=4 {
            for m in [1.0, 2.0, 5.0] {
                let h_omega = m * 10f64.powi(e);
                if h_omega <= 1e4 {
                    grid.push(h_omega / 2.0);
                }
            }
        }
        grid.extend([0.999, 1.0, 1.001, 4.4934, 7.5, 12.3]);
        grid
    }

    fn apply(weights: &[f64], nodes: &[f64], f: impl Fn(f64) -> f64) -> f64 {
        weights.iter().zip(nodes).map(|(&w, &x)| w * f(x)).sum()
    }

    #[test]
    fn invalid_input_is_a_typed_error() {
        for points in [0, 1, MAX_POINTS + 1] {
            assert!(matches!(
                FilonLobatto::new(points),
                Err(Error::InvalidParameter { ref name, .. }) if name == "points"
            ));
        }
        let mut rule = FilonLobatto::new(4).unwrap();
        let (mut c, mut s) = ([0.0; 4], [0.0; 4]);
        for theta in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(matches!(
                rule.weights(theta, &mut c, &mut s),
                Err(Error::InvalidParameter { ref name, .. }) if name == "theta"
            ));
        }
        let mut short = [0.0; 3];
        assert!(matches!(
            rule.weights(1.0, &mut short, &mut s),
            Err(Error::InvalidParameter { ref name, .. }) if name == "weights"
        ));
    }

    /// The nodes and weights of the 5-point Lobatto rule: 0, ±√(3/7); 32/45, 49/90, 1/10.
    #[test]
    fn lobatto_nodes_and_weights() {
        let rule = FilonLobatto::new(5).unwrap();
        let a = (3.0f64 / 7.0).sqrt();
        let expected = [-1.0, -a, 0.0, a, 1.0];
        let weights = [0.1, 49.0 / 90.0, 32.0 / 45.0, 49.0 / 90.0, 0.1];
        for j in 0..5 {
            assert!((rule.nodes()[j] - expected[j]).abs() <= 2e-16, "node {j}");
            assert!(
                (rule.lobatto_weights()[j] - weights[j]).abs() <= 4e-16,
                "weight {j}"
            );
        }
        // Exact for degree 2n − 3 at θ = 0, for every n up to 40.
        for n in 2..=40 {
            let rule = FilonLobatto::new(n).unwrap();
            for k in 0..=2 * n - 3 {
                let exact = if k % 2 == 0 {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                let got = apply(rule.lobatto_weights(), rule.nodes(), |x| x.powi(k as i32));
                assert!((got - exact).abs() <= 1e-14, "n = {n}, k = {k}: {got}");
            }
        }
    }

    /// (a) The weights integrate xᵏ cos θx and xᵏ sin θx, k < n, as the composite
    /// Gauss–Legendre reference does, to 1e-14 relative to Σⱼ|wⱼ| (|xᵏ| ≤ 1), for
    /// hω = 2θ from 0 through 10⁻¹⁰, …, 10⁴.
    /// Measured: largest error 6.1e-15 (n = 16), 3.2e-15 for n ≤ 12.
    #[test]
    fn weights_match_composite_gauss_legendre() {
        let mut worst: f64 = 0.0;
        for n in (2..=12).chain([16]) {
            let mut rule = FilonLobatto::new(n).unwrap();
            let (mut c, mut s) = (vec![0.0; n], vec![0.0; n]);
            for theta in theta_grid() {
                rule.weights(theta, &mut c, &mut s).unwrap();
                let scale: f64 = c.iter().chain(&s).map(|w| w.abs()).sum();
                for k in 0..n {
                    let f = |x: f64| x.powi(k as i32);
                    let (rc, rs) = reference(theta, f);
                    let (gc, gs) = (apply(&c, rule.nodes(), f), apply(&s, rule.nodes(), f));
                    let err = (gc - rc).abs().max((gs - rs).abs()) / scale;
                    worst = worst.max(err);
                    assert!(
                        err <= 1e-14,
                        "n = {n}, θ = {theta:e}, k = {k}: ({gc:e}, {gs:e}) vs ({rc:e}, {rs:e}), {err:e}"
                    );
                }
            }
        }
        eprintln!("largest error relative to Σ|w|: {worst:e}");
    }

    /// (b) θ → 0: the weights tend to the Lobatto weights, with the expected O(θ²) cosine
    /// and O(θ) sine deviations (∫ lⱼ (1 − θ²x²/2) and ∫ lⱼ θx), and exactly at θ = 0.
    #[test]
    fn small_theta_reduces_to_lobatto() {
        for n in [2, 3, 5, 9] {
            let mut rule = FilonLobatto::new(n).unwrap();
            let (mut c, mut s) = (vec![0.0; n], vec![0.0; n]);
            rule.weights(0.0, &mut c, &mut s).unwrap();
            assert_eq!(c, rule.lobatto_weights());
            assert!(s.iter().all(|&w| w == 0.0));
            for theta in [1e-300, 1e-12, 1e-8, 1e-4] {
                rule.weights(theta, &mut c, &mut s).unwrap();
                for j in 0..n {
                    let (x, rho) = (rule.nodes()[j], rule.lobatto_weights()[j]);
                    // ∫ lⱼ x² = ρⱼ xⱼ² when the Lobatto rule is exact for degree n + 1 (n ≥ 4),
                    // ∫ lⱼ x = ρⱼ xⱼ for degree n (n ≥ 3).
                    let cos_expected = rho * (1.0 - theta * theta * x * x / 2.0);
                    let sin_expected = rho * theta * x;
                    if n >= 4 {
                        assert!(
                            (c[j] - cos_expected).abs() <= 1e-16 + theta.powi(4),
                            "n = {n}, θ = {theta:e}, j = {j}"
                        );
                    }
                    if n >= 3 {
                        assert!(
                            (s[j] - sin_expected).abs() <= 1e-16 * theta + theta.powi(3),
                            "n = {n}, θ = {theta:e}, j = {j}: {} vs {sin_expected}",
                            s[j]
                        );
                    }
                }
            }
        }
    }

    /// (c) On f = eˣ (exact: ∫ e^{(1+iθ)x} dx = 2 sinh(1 + iθ)/(1 + iθ)) the 3-node
    /// Filon–Lobatto error falls like θ⁻²: it is I[g] for g = f − p (p the interpolant, g(±1) = 0),
    /// whose asymptotic expansion starts with (g′(1) e^{iθ} − g′(−1) e^{−iθ})/θ², and the
    /// remainder is O(θ⁻³). The Lobatto rule's error does not fall at all.
    #[test]
    fn error_on_exp_falls_like_theta_squared() {
        let exact = |theta: f64| {
            // 2 sinh(1 + iθ)/(1 + iθ), sinh(1 + iθ) = sinh 1 cos θ + i cosh 1 sin θ.
            let (re, im) = (1f64.sinh() * theta.cos(), 1f64.cosh() * theta.sin());
            let d = 1.0 + theta * theta;
            (2.0 * (re + im * theta) / d, 2.0 * (im - re * theta) / d)
        };
        // p(x) = 1 + sinh(1) x + (cosh(1) − 1) x², so g′(±1) = e^{±1} − sinh 1 ∓ 2(cosh 1 − 1).
        let slope = |x: f64| x.exp() - 1f64.sinh() - 2.0 * (1f64.cosh() - 1.0) * x;
        let n = 3;
        let mut rule = FilonLobatto::new(n).unwrap();
        let (mut c, mut s) = (vec![0.0; n], vec![0.0; n]);
        for theta in [10.0, 100.0, 1000.0, 10000.0] {
            rule.weights(theta, &mut c, &mut s).unwrap();
            let (ec, es) = exact(theta);
            let got = (
                apply(&c, rule.nodes(), f64::exp),
                apply(&s, rule.nodes(), f64::exp),
            );
            let error = (ec - got.0, es - got.1);
            let (sin, cos) = theta.sin_cos();
            let (g_plus, g_minus) = (slope(1.0), slope(-1.0));
            let lead = (
                (g_plus - g_minus) * cos / (theta * theta),
                (g_plus + g_minus) * sin / (theta * theta),
            );
            let remainder = (error.0 - lead.0).hypot(error.1 - lead.1);
            let size = error.0.hypot(error.1);
            let lobatto = apply(rule.lobatto_weights(), rule.nodes(), |x| {
                x.exp() * (theta * x).cos()
            });
            eprintln!(
                "θ = {theta:e}: Filon–Lobatto error {size:.3e}, θ²·error {:.3}, θ³·(error − lead) {:.3}; Lobatto error {:.3e}",
                size * theta * theta,
                remainder * theta.powi(3),
                (lobatto - ec).abs()
            );
            assert!(remainder * theta.powi(3) <= 4.0, "θ = {theta}");
            assert!(
                size * theta * theta <= 1.0 && size * theta * theta >= 0.2,
                "θ = {theta}"
            );
            assert!((lobatto - ec).abs() >= 0.1, "θ = {theta}");
        }
    }
}
