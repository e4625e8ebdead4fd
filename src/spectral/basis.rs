//! Chebyshev–Gauss–Lobatto nodes and Lagrange interpolation in barycentric form.
//!
//! # Nodes
//!
//! The spectral variational integrators of Li, Wu and Leok (2018) interpolate each step on the
//! s + 1 Chebyshev–Gauss–Lobatto (CGL) points of [−1, 1], here in ascending order,
//!
//! ```text
//! x_ν = −cos(νπ/s) = sin(π(2ν − s)/(2s)),   ν = 0, …, s.
//! ```
//!
//! The sine form is used: it is exactly antisymmetric (x_{s−ν} = −x_ν), has x_0 = −1, x_s = 1
//! and, for even s, x_{s/2} = 0 exactly.
//!
//! # Barycentric interpolation
//!
//! The Lagrange basis l_j(x) = Π_{k≠j} (x − x_k)/(x_j − x_k) on distinct nodes is evaluated in
//! O(n) per point with the barycentric weights w_j = 1/Π_{k≠j}(x_j − x_k) (Berrut & Trefethen,
//! *Barycentric Lagrange interpolation*, SIAM Review 46, 2004):
//!
//! - on [min x_k, max x_k], by the formula of the second kind
//!   l_j(x) = (w_j/(x − x_j)) / Σ_k w_k/(x − x_k), which is stable there and indifferent to a
//!   common factor of the weights;
//! - outside, for extrapolation (a previous step's polynomial evaluated on the next step), by the
//!   formula of the first kind l_j(x) = ℓ(x) w_j/(x − x_j), ℓ(x) = Π_k (x − x_k). The second kind
//!   would cancel catastrophically there (its denominator is 1/ℓ(x), a tiny sum of terms of
//!   alternating sign), while the first kind is a product of factors each accurate to ε, so every
//!   l_j(x) is accurate to O(nε) relatively, however far out (until it overflows). The
//!   extrapolated polynomial Σ_j f_j l_j(x) itself is then as accurate as its conditioning
//!   Σ_j |f_j l_j(x)| allows, which grows like (|x| + √(x² − 1))^s outside [−1, 1].
//!
//! Differentiating ln l_j gives the derivative at a point x that is not a node,
//!
//! ```text
//! l_j'(x) = l_j(x) Σ_{k≠j} 1/(x − x_k),
//! ```
//!
//! (equivalently l_j(x) (Σ_k w_k/(x − x_k)² / Σ_k w_k/(x − x_k) − 1/(x − x_j)) in second-kind
//! terms); the sum for the node nearest to x is accumulated without its huge 1/(x − x_j) term, so
//! there is no cancellation next to a node. At the nodes the differentiation matrix is used,
//!
//! ```text
//! D_ij = l_j'(x_i) = (w_j/w_i)/(x_i − x_j)  (i ≠ j),     D_ii = −Σ_{j≠i} D_ij,
//! ```
//!
//! the diagonal by the "negative sum trick", so that D annihilates constants up to round-off.
//!
//! For the exact CGL points the weights have the closed form w_j = (−1)^j δ_j, δ_0 = δ_s = 1/2
//! and δ_j = 1 otherwise, up to a common factor (which the second-kind formula and D ignore). The
//! stored nodes are rounded, and their own weights differ from the closed form by O(s² ε); using
//! the closed form with rounded nodes would cost O(s⁴ ε) in derivatives, so
//! [`LagrangeBasis::chebyshev_gauss_lobatto`] computes the weights of the stored nodes (the tests
//! check them against the closed form). For ascending nodes the corners of D are
//! D_00 = −(2s² + 1)/6 and D_ss = (2s² + 1)/6. Li–Wu–Leok quote the Chebyshev differentiation
//! matrix (their eq. 17) for nodes ordered from 1 to −1, so its corner signs are flipped relative
//! to ours; this module builds everything from the barycentric formulas for the nodes as stored
//! instead of transcribing that matrix.

use nalgebra::DMatrix;

use crate::error::Error;
use crate::spectral::MAX_POINTS;

/// Two nodes x, x_k closer than this, relative to the node spread (ρ|x − x_k| < 2⁻³⁰⁰ ≈ 5e−91), are
/// treated as coincident when evaluating: the error made is O(2⁻³⁰⁰ n²), far below round-off, and
/// it keeps the barycentric terms away from overflow and the products away from underflow.
const COINCIDENT: f64 = 4.909_093_465_297_727e-91; // 2^-300

/// Chebyshev–Gauss–Lobatto nodes x_ν = −cos(νπ/s), ν = 0..s (s + 1 = `points` ≥ 2), ascending.
///
/// Computed as x_ν = sin(π(2ν − s)/(2s)), so they are exactly antisymmetric, the endpoints are
/// exactly ∓1 and, for odd `points`, the middle node is exactly 0.
///
/// # Errors
///
/// [`Error::InvalidParameter`] named `"points"` if `points` < 2 or `points` > [`MAX_POINTS`].
pub fn chebyshev_gauss_lobatto(points: usize) -> Result<Vec<f64>, Error> {
    if points < 2 {
        return Err(Error::invalid(
            "points",
            format!("Chebyshev–Gauss–Lobatto nodes need at least 2 points, got {points}"),
        ));
    }
    if points > MAX_POINTS {
        return Err(Error::invalid(
            "points",
            format!(
                "{points} Chebyshev–Gauss–Lobatto points requested, at most {MAX_POINTS} are supported"
            ),
        ));
    }
    let s = points - 1;
    let mut nodes = vec![0.0; points];
    for nu in 0..points / 2 {
        // 2ν − s < 0 here; the upper half is the exact mirror image.
        let k = (s - 2 * nu) as f64;
        let x = (std::f64::consts::FRAC_PI_2 * k / s as f64).sin();
        nodes[nu] = -x;
        nodes[s - nu] = x;
    }
    nodes[0] = -1.0;
    nodes[s] = 1.0;
    Ok(nodes)
}

/// Lagrange basis {l_j} on distinct nodes, evaluated with the barycentric formulas.
///
/// l_j is the polynomial of degree n − 1 (n = number of nodes) with l_j(x_k) = δ_jk, so
/// Σ_j f_j l_j is the interpolant of the values f_j. Evaluation at a point costs O(n) and does not
/// allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct LagrangeBasis {
    nodes: Vec<f64>,
    /// Barycentric weights up to a common factor, largest magnitude 1.
    weights: Vec<f64>,
    /// ρ = 4/(max x_k − min x_k) (1 for a single node): the scale of the node set, so that the
    /// products Π ρ(x − x_k) stay in range.
    rho: f64,
    /// The true weights of the scaled nodes ρx_k are `scale · weights`; used by the first-kind
    /// formula outside the nodes.
    scale: f64,
    /// Smallest node.
    lower: f64,
    /// Largest node.
    upper: f64,
}

impl LagrangeBasis {
    /// Basis on arbitrary distinct finite nodes, in any order (at least 1, at most
    /// [`MAX_POINTS`]).
    ///
    /// The weights w_j = 1/Π_{k≠j}(x_j − x_k) are accumulated with a separate binary exponent and
    /// then divided by the largest |w_j|, so they neither overflow nor underflow for any
    /// reasonable node set.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] named `"nodes"` if there are no nodes or more than
    /// [`MAX_POINTS`], if a node is not finite, if two nodes coincide, or if the nodes are so
    /// unevenly spread that their weights exceed the floating-point range.
    pub fn new(nodes: Vec<f64>) -> Result<Self, Error> {
        let n = nodes.len();
        if n == 0 {
            return Err(Error::invalid("nodes", "at least one node is needed"));
        }
        if n > MAX_POINTS {
            return Err(Error::invalid(
                "nodes",
                format!("{n} nodes given, at most {MAX_POINTS} are supported"),
            ));
        }
        if let Some(k) = nodes.iter().position(|x| !x.is_finite()) {
            return Err(Error::invalid(
                "nodes",
                format!("node {k} is {:?}, not a finite number", nodes[k]),
            ));
        }
        let lower = nodes.iter().copied().fold(f64::INFINITY, f64::min);
        let upper = nodes.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let rho = if n == 1 { 1.0 } else { 4.0 / (upper - lower) };
        if !(rho.is_finite() && rho > 0.0) {
            let reason = if lower == upper {
                "nodes must be distinct".to_string()
            } else {
                format!("the spread of the nodes, [{lower:?}, {upper:?}], is out of range")
            };
            return Err(Error::invalid("nodes", reason));
        }

        // Π_{k≠j} ρ(x_j − x_k) = mantissa · 2^exponent, renormalized into [2⁻²⁵⁶, 2²⁵⁶] as it goes.
        // Every factor is at most 4 in magnitude; factors below 2⁻⁶⁰⁰ are rejected, so nothing
        // under- or overflows.
        const STEP: i32 = 256;
        let (up, down) = (2f64.powi(STEP), 2f64.powi(-STEP));
        let mut products = Vec::with_capacity(n);
        for (j, &xj) in nodes.iter().enumerate() {
            let (mut mantissa, mut exponent) = (1.0f64, 0i32);
            for (k, &xk) in nodes.iter().enumerate() {
                if k == j {
                    continue;
                }
                let factor = rho * (xj - xk);
                if factor == 0.0 {
                    return Err(Error::invalid(
                        "nodes",
                        format!("nodes {k} and {j} coincide (both {xj:?}); nodes must be distinct"),
                    ));
                }
                if factor.abs() < 2f64.powi(-600) {
                    return Err(Error::invalid(
                        "nodes",
                        format!(
                            "nodes {k} and {j} are too close together relative to the spread of the nodes"
                        ),
                    ));
                }
                mantissa *= factor;
                while mantissa.abs() < down {
                    mantissa *= up;
                    exponent -= STEP;
                }
                while mantissa.abs() > up {
                    mantissa *= down;
                    exponent += STEP;
                }
            }
            products.push((mantissa, exponent));
        }
        // w_j = 2^(−exponent_j)/mantissa_j; normalize by the largest |w_j|, i.e. the smallest
        // |product|, compared through log₂ |product|.
        let log2 = |(m, e): (f64, i32)| m.abs().log2() + f64::from(e);
        let (mut smallest, mut smallest_log2) = (products[0], log2(products[0]));
        for &p in &products[1..] {
            if log2(p) < smallest_log2 {
                (smallest, smallest_log2) = (p, log2(p));
            }
        }
        let weights: Vec<f64> = products
            .iter()
            .map(|&(m, e)| times_power_of_two(smallest.0 / m, smallest.1 - e, up, down, STEP))
            .collect();
        let scale = times_power_of_two(1.0 / smallest.0, -smallest.1, up, down, STEP);
        if weights.iter().any(|w| !w.is_normal()) || !scale.is_normal() {
            return Err(Error::invalid(
                "nodes",
                "the nodes are so unevenly spread that their barycentric weights exceed the floating-point range",
            ));
        }
        Ok(Self {
            nodes,
            weights,
            rho,
            scale,
            lower,
            upper,
        })
    }

    /// Basis on the `points` Chebyshev–Gauss–Lobatto nodes of [`chebyshev_gauss_lobatto`].
    ///
    /// The exact CGL points have the closed-form weights (−1)^j δ_j (δ = 1/2 at both ends, 1
    /// otherwise; times the common factor (−1)^s 2^(s−1)/s for ascending nodes, s = `points` − 1).
    /// The stored nodes are rounded, though, and the weights of the rounded nodes differ from the
    /// closed form by O(s² ε) relatively (the outer nodes are only O(1/s²) apart). That mismatch
    /// makes the barycentric interpolant a rational function instead of the polynomial and costs
    /// O(s⁴ ε) in derivatives, about 100× the O(s² ε) round-off at s = 256. So the weights of the
    /// stored nodes are computed by products as in [`LagrangeBasis::new`] (O(s²) once); they agree
    /// with the closed form to O(s² ε). The upper half is mirrored from the lower half
    /// (w_{s−j} = (−1)^s w_j), which makes the off-diagonal differentiation matrix exactly
    /// centro-antisymmetric like the nodes.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] named `"points"` if `points` < 2 or `points` > [`MAX_POINTS`].
    pub fn chebyshev_gauss_lobatto(points: usize) -> Result<Self, Error> {
        let mut basis = Self::new(chebyshev_gauss_lobatto(points)?)?;
        let s = points - 1;
        let sign = if s.is_multiple_of(2) { 1.0 } else { -1.0 };
        for j in 0..points / 2 {
            basis.weights[s - j] = sign * basis.weights[j];
        }
        Ok(basis)
    }

    /// The nodes, in the order given (ascending for the CGL basis).
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Number of nodes (= number of basis functions = degree + 1).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always `false`: a basis has at least one node.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// `out[j] = l_j(x)`. Exactly the Kronecker delta when `x` is a node.
    ///
    /// # Panics
    ///
    /// If `out.len() != self.len()`.
    pub fn values_into(&self, x: f64, out: &mut [f64]) {
        assert_eq!(out.len(), self.len(), "values_into: output length");
        if let Some(i) = self.values_or_node(x, out) {
            out.fill(0.0);
            out[i] = 1.0;
        }
    }

    /// `out[j] = l_j'(x)`, at any point: at a node it is that row of the
    /// [differentiation matrix](Self::differentiation_matrix), elsewhere (including outside the
    /// nodes, for extrapolation) l_j'(x) = l_j(x) Σ_{k≠j} 1/(x − x_k).
    ///
    /// # Panics
    ///
    /// If `out.len() != self.len()`.
    pub fn derivatives_into(&self, x: f64, out: &mut [f64]) {
        assert_eq!(out.len(), self.len(), "derivatives_into: output length");
        if self.len() == 1 {
            out[0] = 0.0;
            return;
        }
        if let Some(i) = self.values_or_node(x, out) {
            self.differentiation_row(i, out);
            return;
        }
        // out holds l_j(x). Σ_{k≠j} 1/(x − x_k) = (Σ_{k≠m} 1/(x − x_k)) + 1/(x − x_m) − 1/(x − x_j)
        // with m the nearest node, whose large term is never added and subtracted again.
        let nearest = self.nearest(x);
        let mut others = 0.0;
        for (k, &xk) in self.nodes.iter().enumerate() {
            if k != nearest {
                others += 1.0 / (x - xk);
            }
        }
        let near_term = 1.0 / (x - self.nodes[nearest]);
        for (j, (l, &xj)) in out.iter_mut().zip(&self.nodes).enumerate() {
            let sum = if j == nearest {
                others
            } else {
                others + (near_term - 1.0 / (x - xj))
            };
            *l *= sum;
        }
    }

    /// The value matrix B with `B[(i, j)] = l_j(points[i])` (rows: evaluation points, columns:
    /// basis functions); B f interpolates the nodal values f at the points.
    pub fn value_matrix(&self, points: &[f64]) -> DMatrix<f64> {
        self.matrix(points, Self::values_into)
    }

    /// The derivative matrix B' with `B'[(i, j)] = l_j'(points[i])`.
    pub fn derivative_matrix(&self, points: &[f64]) -> DMatrix<f64> {
        self.matrix(points, Self::derivatives_into)
    }

    /// The differentiation matrix D with `D[(i, j)] = l_j'(x_i)` at the nodes: off the diagonal
    /// (w_j/w_i)/(x_i − x_j), on it minus the sum of the rest of the row, so every row sums to 0
    /// up to round-off.
    pub fn differentiation_matrix(&self) -> DMatrix<f64> {
        let n = self.len();
        let mut row = vec![0.0; n];
        let mut d = DMatrix::zeros(n, n);
        for i in 0..n {
            self.differentiation_row(i, &mut row);
            for (j, &v) in row.iter().enumerate() {
                d[(i, j)] = v;
            }
        }
        d
    }

    /// Fills a matrix row by row with `eval(self, points[i], row)`.
    fn matrix(&self, points: &[f64], eval: fn(&Self, f64, &mut [f64])) -> DMatrix<f64> {
        let n = self.len();
        let mut row = vec![0.0; n];
        let mut m = DMatrix::zeros(points.len(), n);
        for (i, &x) in points.iter().enumerate() {
            eval(self, x, &mut row);
            for (j, &v) in row.iter().enumerate() {
                m[(i, j)] = v;
            }
        }
        m
    }

    /// `out[j] = l_j'(x_i)`: row i of the differentiation matrix.
    fn differentiation_row(&self, i: usize, out: &mut [f64]) {
        let (xi, wi) = (self.nodes[i], self.weights[i]);
        let mut diagonal = 0.0;
        for (j, ((d, &xj), &wj)) in out
            .iter_mut()
            .zip(&self.nodes)
            .zip(&self.weights)
            .enumerate()
        {
            if j != i {
                *d = (wj / wi) / (xi - xj);
                diagonal -= *d;
            }
        }
        out[i] = diagonal;
    }

    /// Index of the node nearest to x.
    fn nearest(&self, x: f64) -> usize {
        let mut best = (0, f64::INFINITY);
        for (k, &xk) in self.nodes.iter().enumerate() {
            let d = (x - xk).abs();
            if d < best.1 {
                best = (k, d);
            }
        }
        best.0
    }

    /// Writes l_j(x) into `out` and returns `None`, or returns `Some(i)` (leaving `out` in an
    /// unspecified state) if x coincides with node i.
    fn values_or_node(&self, x: f64, out: &mut [f64]) -> Option<usize> {
        if self.len() == 1 {
            out[0] = 1.0;
            return (x == self.nodes[0]).then_some(0);
        }
        if (self.lower..=self.upper).contains(&x) {
            // Second kind: t_j = w_j/(ρ(x − x_j)), l_j = t_j / Σ t_k. With |ρ(x − x_j)| > 2⁻³⁰⁰
            // and |w_j| ≤ 1 the terms cannot overflow.
            let mut sum = 0.0;
            for (k, ((t, &xk), &wk)) in out
                .iter_mut()
                .zip(&self.nodes)
                .zip(&self.weights)
                .enumerate()
            {
                let d = self.rho * (x - xk);
                if d.abs() <= COINCIDENT {
                    return Some(k);
                }
                *t = wk / d;
                sum += *t;
            }
            for t in out.iter_mut() {
                *t /= sum;
            }
        } else {
            // First kind: l_j = ℓ(x) w_j/(x − x_j), with ℓ and w of the scaled nodes ρx_k.
            let mut ell = 1.0;
            for (k, &xk) in self.nodes.iter().enumerate() {
                let d = self.rho * (x - xk);
                if d.abs() <= COINCIDENT {
                    return Some(k);
                }
                ell *= d;
            }
            let common = self.scale * ell / self.rho;
            for ((l, &xk), &wk) in out.iter_mut().zip(&self.nodes).zip(&self.weights) {
                *l = common * (wk / (x - xk));
            }
        }
        None
    }
}

/// value · 2^exponent for an exponent that is a multiple of `step`, in steps of 2^±step so that no
/// intermediate overflows before the result does.
fn times_power_of_two(mut value: f64, mut exponent: i32, up: f64, down: f64, step: i32) -> f64 {
    while exponent >= step {
        value *= up;
        exponent -= step;
    }
    while exponent <= -step {
        value *= down;
        exponent += step;
    }
    value * 2f64.powi(exponent)
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f64 = f64::EPSILON;

    /// A fixed linear congruential generator, uniform in [−1, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// A polynomial of degree `degree` in Chebyshev form, with random coefficients.
    struct Poly(Vec<f64>);
    impl Poly {
        fn random(degree: usize, rng: &mut Lcg) -> Self {
            Poly((0..=degree).map(|_| rng.next()).collect())
        }
        /// (p(x), p'(x), Σ|c_k T_k(x)|, Σ|c_k T_k'(x)|): values and the scales of their rounding
        /// errors.
        fn eval(&self, x: f64) -> [f64; 4] {
            let (mut t0, mut t1, mut d0, mut d1) = (1.0, x, 0.0, 1.0);
            let c = &self.0;
            let mut acc = [c[0], 0.0, c[0].abs(), 0.0];
            for (k, &ck) in c.iter().enumerate().skip(1) {
                if k > 1 {
                    let (t2, d2) = (2.0 * x * t1 - t0, 2.0 * t1 + 2.0 * x * d1 - d0);
                    (t0, t1, d0, d1) = (t1, t2, d1, d2);
                }
                acc[0] += ck * t1;
                acc[1] += ck * d1;
                acc[2] += (ck * t1).abs();
                acc[3] += (ck * d1).abs();
            }
            acc
        }
        fn at_nodes(&self, nodes: &[f64]) -> Vec<f64> {
            nodes.iter().map(|&x| self.eval(x)[0]).collect()
        }
    }

    /// l_j(x) and l_j'(x) straight from the product definition, O(n³): an independent reference.
    /// Also returns |l_j(x)| Σ_{m≠j} 1/|x − x_m|, the scale of the rounding error in l_j'(x).
    fn product_basis(nodes: &[f64], x: f64, j: usize) -> (f64, f64, f64) {
        let others = || (0..nodes.len()).filter(move |&k| k != j);
        let l: f64 = others()
            .map(|k| (x - nodes[k]) / (nodes[j] - nodes[k]))
            .product();
        let (mut dl, mut scale) = (0.0, 0.0);
        for m in others() {
            let term: f64 = others()
                .filter(|&k| k != m)
                .map(|k| (x - nodes[k]) / (nodes[j] - nodes[k]))
                .product::<f64>()
                / (nodes[j] - nodes[m]);
            dl += term;
            scale += term.abs();
        }
        (l, dl, scale)
    }

    fn equispaced(points: usize) -> Vec<f64> {
        (0..points)
            .map(|k| -1.0 + 2.0 * k as f64 / (points - 1) as f64)
            .collect()
    }

    /// Evaluation points: random ones in [−1, 1], the ends, and points next to nodes.
    fn inside_points(nodes: &[f64], rng: &mut Lcg) -> Vec<f64> {
        let mut xs: Vec<f64> = (0..50).map(|_| rng.next()).collect();
        xs.extend([-1.0, 1.0, 0.0, 0.5]);
        for &x in &nodes[..nodes.len().min(3)] {
            xs.extend([x + 1e-12, x + 1e-300].map(|y| y.clamp(-1.0, 1.0)));
        }
        xs
    }

    fn assert_invalid<T: std::fmt::Debug>(result: Result<T, Error>, expected: &str) {
        match result {
            Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, expected),
            other => panic!("expected InvalidParameter({expected}), got {other:?}"),
        }
    }

    #[test]
    fn cgl_nodes_are_ascending_symmetric_with_exact_ends() {
        for points in (2..=200).chain([MAX_POINTS - 1, MAX_POINTS]) {
            let x = chebyshev_gauss_lobatto(points).unwrap();
            let s = points - 1;
            assert_eq!(x.len(), points);
            assert_eq!((x[0], x[s]), (-1.0, 1.0));
            assert!(x.windows(2).all(|p| p[0] < p[1]), "points = {points}");
            for k in 0..points {
                assert_eq!(x[k], -x[s - k], "points = {points}, k = {k}");
            }
            if s.is_multiple_of(2) {
                assert_eq!(x[s / 2], 0.0);
            }
        }
    }

    #[test]
    fn cgl_nodes_match_cosine_formula() {
        for points in 2..=200 {
            let s = (points - 1) as f64;
            for (nu, &x) in chebyshev_gauss_lobatto(points).unwrap().iter().enumerate() {
                // −cos(νπ/s) itself carries an absolute error of up to ~1.5 ε (argument rounding).
                let reference = -(nu as f64 * std::f64::consts::PI / s).cos();
                assert!(
                    (x - reference).abs() <= 2.0 * EPS,
                    "points = {points}, ν = {nu}"
                );
            }
        }
    }

    #[test]
    fn invalid_point_counts_are_rejected() {
        for points in [0, 1, MAX_POINTS + 1] {
            assert_invalid(chebyshev_gauss_lobatto(points), "points");
            assert_invalid(LagrangeBasis::chebyshev_gauss_lobatto(points), "points");
        }
    }

    #[test]
    fn invalid_nodes_are_rejected() {
        assert_invalid(LagrangeBasis::new(vec![]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![0.0, 1.0, 0.0]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![0.0, -0.0]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![2.0, 2.0]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![0.0, f64::NAN]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![f64::INFINITY, 0.0]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![-f64::MAX, f64::MAX]), "nodes");
        assert_invalid(LagrangeBasis::new(vec![0.0; MAX_POINTS + 1]), "nodes");
        assert!(LagrangeBasis::new(vec![0.0, 1e-300, 1.0]).is_err());
    }

    #[test]
    fn single_node_basis_is_the_constant_one() {
        let basis = LagrangeBasis::new(vec![0.25]).unwrap();
        assert_eq!(basis.len(), 1);
        let (mut l, mut dl) = ([0.0], [1.0]);
        for x in [0.25, -3.0, 0.0, 7.5] {
            basis.values_into(x, &mut l);
            basis.derivatives_into(x, &mut dl);
            assert_eq!((l[0], dl[0]), (1.0, 0.0), "x = {x}");
        }
        assert_eq!(basis.differentiation_matrix()[(0, 0)], 0.0);
    }

    #[test]
    fn kronecker_delta_at_nodes() {
        let bases = [
            LagrangeBasis::chebyshev_gauss_lobatto(9).unwrap(),
            LagrangeBasis::new(equispaced(9)).unwrap(),
            LagrangeBasis::new(vec![0.3, -2.0, 5.0, 1.0]).unwrap(),
        ];
        for basis in &bases {
            let mut l = vec![f64::NAN; basis.len()];
            for (i, &x) in basis.nodes().iter().enumerate() {
                basis.values_into(x, &mut l);
                for (j, &v) in l.iter().enumerate() {
                    assert_eq!(v, if i == j { 1.0 } else { 0.0 });
                }
            }
            let identity = basis.value_matrix(basis.nodes());
            assert_eq!(identity, DMatrix::identity(basis.len(), basis.len()));
        }
    }

    /// The weights of the (rounded) CGL nodes agree with the closed form
    /// (−1)^s 2^(s−1)/s · (−1)^j δ_j of the exact nodes, scaled to ρ = 2, up to the O(s² ε) effect
    /// of rounding the nodes; and they are exactly (anti)symmetric.
    #[test]
    fn cgl_weights_match_closed_form() {
        for points in [2, 3, 4, 5, 8, 17, 30, 64, 200, MAX_POINTS] {
            let basis = LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap();
            let s = points - 1;
            assert_eq!(basis.rho, 2.0);
            let sign = if s.is_multiple_of(2) { 1.0 } else { -1.0 };
            for j in 0..points {
                let delta = if j == 0 || j == s { 0.5 } else { 1.0 };
                let closed =
                    sign * if j.is_multiple_of(2) { delta } else { -delta } / (2 * s) as f64;
                let w = basis.scale * basis.weights[j];
                let tol = (s * s) as f64 * EPS * closed.abs();
                assert!(
                    (w - closed).abs() <= tol,
                    "points = {points}, j = {j}: {w} vs {closed}"
                );
                assert_eq!(basis.weights[s - j], sign * basis.weights[j]);
            }
        }
    }

    /// Every basis function and its derivative against the product definition, for CGL,
    /// equispaced and scattered unsorted nodes, inside and outside the nodes. The second-kind
    /// formula is accurate to O((n + Λ(x)) ε) relatively per entry (Λ = Σ|l_k(x)|, the Lebesgue
    /// function), the first-kind formula and the reference to O(n ε); the derivative to that times
    /// |l_j(x)| Σ_{k≠j} 1/|x − x_k| (the size of the terms of l_j'(x)).
    #[test]
    fn basis_functions_match_product_formula() {
        let mut rng = Lcg(7);
        let mut sets: Vec<(LagrangeBasis, Vec<f64>)> = Vec::new();
        for points in 2..=30 {
            sets.push((
                LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap(),
                vec![],
            ));
            sets.push((LagrangeBasis::new(equispaced(points)).unwrap(), vec![]));
        }
        let scattered = vec![0.7, -0.2, 3.0, 1.1, -1.9, 0.05, 2.2];
        sets.push((
            LagrangeBasis::new(scattered).unwrap(),
            vec![-2.5, 4.0, 0.0, 1.0],
        ));
        for (basis, extra) in &sets {
            let n = basis.len();
            let (mut l, mut dl) = (vec![0.0; n], vec![0.0; n]);
            let xs = inside_points(basis.nodes(), &mut rng)
                .into_iter()
                .chain([-3.0, -1.5, -1.0 - 1e-9, 1.0 + 1e-9, 1.5, 3.0])
                .chain(extra.iter().copied());
            for x in xs {
                basis.values_into(x, &mut l);
                basis.derivatives_into(x, &mut dl);
                let lebesgue: f64 = l.iter().map(|v| v.abs()).sum();
                let factor = (n as f64 + lebesgue) * EPS;
                // At a node the diagonal is a negative sum of the rest of the row.
                let at_node = basis.nodes().iter().position(|&xk| xk == x);
                let row_scale: f64 = dl.iter().map(|v| v.abs()).sum();
                for j in 0..n {
                    let (rl, rdl, mut dscale) = product_basis(basis.nodes(), x, j);
                    if at_node == Some(j) {
                        dscale += row_scale;
                    }
                    // Points within 2⁻³⁰⁰ of a node count as the node: allow for that.
                    let e0 = (l[j] - rl).abs() / (factor * rl.abs() + 1e-250);
                    let e1 = (dl[j] - rdl).abs() / (factor * dscale + 1e-250);
                    assert!(e0 <= 4.0, "n = {n}, x = {x}, j = {j}: l = {} vs {rl}", l[j]);
                    assert!(
                        e1 <= 4.0,
                        "n = {n}, x = {x}, j = {j}: l' = {} vs {rdl}",
                        dl[j]
                    );
                }
            }
        }
    }

    /// The interpolant Σ f_j l_j reproduces a random polynomial of degree ≤ s at 50+ points of
    /// [−1, 1] (including points next to nodes), and so does its derivative, both from
    /// `derivatives_into`/`derivative_matrix` and from `differentiation_matrix` at the nodes.
    #[test]
    fn reproduces_polynomials_on_cgl_nodes() {
        let mut rng = Lcg(42);
        for points in 2..=30 {
            let basis = LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap();
            let s = (points - 1) as f64;
            let poly = Poly::random(points - 1, &mut rng);
            let f = nalgebra::DVector::from_vec(poly.at_nodes(basis.nodes()));
            let scale = f.amax();
            let xs = inside_points(basis.nodes(), &mut rng);
            let values = basis.value_matrix(&xs) * &f;
            let derivatives = basis.derivative_matrix(&xs) * &f;
            let (mut l, mut dl) = (vec![0.0; points], vec![0.0; points]);
            for (i, &x) in xs.iter().enumerate() {
                let [p, dp, ..] = poly.eval(x);
                basis.values_into(x, &mut l);
                basis.derivatives_into(x, &mut dl);
                let value: f64 = l.iter().zip(f.iter()).map(|(a, b)| a * b).sum();
                let derivative: f64 = dl.iter().zip(f.iter()).map(|(a, b)| a * b).sum();
                let e0 = (value - p).abs().max((values[i] - p).abs()) / (scale * EPS);
                let e1 = (derivative - dp).abs().max((derivatives[i] - dp).abs())
                    / (s * s * scale * EPS);
                assert!(e0 <= 40.0, "points = {points}, x = {x}: {value} vs {p}");
                assert!(
                    e1 <= 10.0,
                    "points = {points}, x = {x}: {derivative} vs {dp}"
                );
            }
            let at_nodes = basis.differentiation_matrix() * &f;
            for (i, &x) in basis.nodes().iter().enumerate() {
                let e = (at_nodes[i] - poly.eval(x)[1]).abs() / (s * s * scale * EPS);
                assert!(e <= 10.0, "points = {points}, node {i}");
            }
        }
    }

    /// Extrapolation (x outside [−1, 1]) is exact for polynomials of degree ≤ s up to the
    /// conditioning of the problem, Σ_j |f_j l_j(x)| (and Σ_j |f_j l_j'(x)| for the derivative).
    #[test]
    fn extrapolates_polynomials_outside_the_interval() {
        let mut rng = Lcg(3);
        for points in 2..=30 {
            let basis = LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap();
            let n = points as f64;
            let poly = Poly::random(points - 1, &mut rng);
            let f = poly.at_nodes(basis.nodes());
            let (mut l, mut dl) = (vec![0.0; points], vec![0.0; points]);
            for x in [-3.0, -1.5, -1.0 - 1e-12, 1.0 + 1e-9, 1.25, 1.5, 2.0, 3.0] {
                let [p, dp, p_scale, dp_scale] = poly.eval(x);
                basis.values_into(x, &mut l);
                basis.derivatives_into(x, &mut dl);
                let dot = |a: &[f64]| -> (f64, f64) {
                    let sum = a.iter().zip(&f).map(|(a, b)| a * b).sum();
                    (sum, a.iter().zip(&f).map(|(a, b)| (a * b).abs()).sum())
                };
                let ((value, cond), (derivative, dcond)) = (dot(&l), dot(&dl));
                let e0 = (value - p).abs() / (n * EPS * (cond + p_scale));
                let e1 = (derivative - dp).abs() / (n * EPS * (dcond + dp_scale));
                assert!(e0 <= 2.0, "points = {points}, x = {x}: {value} vs {p}");
                assert!(
                    e1 <= 2.0,
                    "points = {points}, x = {x}: {derivative} vs {dp}"
                );
            }
        }
    }

    #[test]
    fn derivatives_at_nodes_are_differentiation_matrix_rows() {
        let bases = [
            LagrangeBasis::chebyshev_gauss_lobatto(12).unwrap(),
            LagrangeBasis::new(equispaced(7)).unwrap(),
            LagrangeBasis::new(vec![0.3, -2.0, 5.0, 1.0]).unwrap(),
        ];
        for basis in &bases {
            let d = basis.differentiation_matrix();
            assert_eq!(basis.derivative_matrix(basis.nodes()), d);
            let mut row = vec![0.0; basis.len()];
            for (i, &x) in basis.nodes().iter().enumerate() {
                basis.derivatives_into(x, &mut row);
                assert_eq!(row.as_slice(), d.row(i).iter().copied().collect::<Vec<_>>());
                let sum: f64 = row.iter().sum();
                let size: f64 = row.iter().map(|v| v.abs()).sum();
                assert!(sum.abs() <= 4.0 * EPS * size, "row {i} sums to {sum}");
            }
        }
    }

    /// Known entries of the first-order Chebyshev differentiation matrix for ascending nodes:
    /// D_00 = −(2s² + 1)/6 = −D_ss, D_0s = −(−1)^s/2 = −D_s0, and D_jj = −x_j/(2(1 − x_j²)) inside.
    #[test]
    fn chebyshev_differentiation_matrix_known_entries() {
        for points in 2..=64 {
            let s = points - 1;
            let sf = s as f64;
            let basis = LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap();
            let d = basis.differentiation_matrix();
            let corner = (2.0 * sf * sf + 1.0) / 6.0;
            let tol = 4.0 * sf * sf * EPS;
            assert!(
                (d[(0, 0)] + corner).abs() <= tol * corner,
                "points = {points}: {}",
                d[(0, 0)]
            );
            assert!(
                (d[(s, s)] - corner).abs() <= tol * corner,
                "points = {points}: {}",
                d[(s, s)]
            );
            let half = if s.is_multiple_of(2) { -0.5 } else { 0.5 };
            assert!((d[(0, s)] - half).abs() <= 4.0 * EPS, "points = {points}");
            assert!((d[(s, 0)] + half).abs() <= 4.0 * EPS, "points = {points}");
            // Inside, compare with the exact nodes' value cos(θ)/(2 sin²θ), θ = jπ/s. Rounding
            // x_k by ≤ ε/2 moves Σ_k 1/(x_j − x_k) by up to ε Σ_k 1/(x_j − x_k)², which near the
            // ends is O(s⁴ ε): that is the honest tolerance.
            let x = basis.nodes();
            for j in 1..s {
                let theta = j as f64 * std::f64::consts::PI / sf;
                let exact = theta.cos() / (2.0 * theta.sin().powi(2));
                let sensitivity: f64 = (0..points)
                    .filter(|&k| k != j)
                    .map(|k| (x[j] - x[k]).powi(-2))
                    .sum();
                let tol = 2.0 * EPS * sensitivity + 4.0 * sf * sf * EPS;
                assert!(
                    (d[(j, j)] - exact).abs() <= tol,
                    "points = {points}, j = {j}"
                );
            }
            // Centro-antisymmetry off the diagonal, inherited exactly from the nodes and weights.
            for i in 0..points {
                for j in (0..points).filter(|&j| j != i) {
                    assert_eq!(d[(s - i, s - j)], -d[(i, j)]);
                }
            }
        }
    }

    /// The general constructor on equispaced nodes interpolates the same polynomials as the CGL
    /// basis. Equispaced interpolation is ill-conditioned (Λ grows like 2^s), so the comparison is
    /// relative to the conditioning Σ_j |f_j l_j(x)| rather than to max |f|.
    #[test]
    fn equispaced_basis_agrees_with_cgl_basis() {
        let mut rng = Lcg(11);
        for points in 2..=30 {
            let cgl = LagrangeBasis::chebyshev_gauss_lobatto(points).unwrap();
            let equi = LagrangeBasis::new(equispaced(points)).unwrap();
            let poly = Poly::random(points - 1, &mut rng);
            let xs: Vec<f64> = (0..50)
                .map(|_| rng.next())
                .chain([-1.0, 1.0, 1.5, -2.0])
                .collect();
            let mut results = Vec::new();
            for basis in [&cgl, &equi] {
                let f = poly.at_nodes(basis.nodes());
                let (mut l, mut dl) = (vec![0.0; points], vec![0.0; points]);
                let mut per_point = Vec::new();
                for &x in &xs {
                    let [p, dp, p_scale, dp_scale] = poly.eval(x);
                    basis.values_into(x, &mut l);
                    basis.derivatives_into(x, &mut dl);
                    let lebesgue: f64 = l.iter().map(|v| v.abs()).sum();
                    let factor = 2.0 * (points as f64 + lebesgue) * EPS;
                    let inverse_distances: f64 =
                        basis.nodes().iter().map(|&xk| 1.0 / (x - xk).abs()).sum();
                    let (mut value, mut derivative, mut cond, mut dcond) =
                        (0.0, 0.0, p_scale, dp_scale);
                    for j in 0..points {
                        value += f[j] * l[j];
                        derivative += f[j] * dl[j];
                        cond += (f[j] * l[j]).abs();
                        dcond += (f[j] * dl[j]).abs()
                            + (f[j] * l[j]).abs() * inverse_distances.min(1e300);
                    }
                    let (e0, e1) = (
                        (value - p).abs() / (factor * cond),
                        (derivative - dp).abs() / (factor * dcond),
                    );
                    assert!(e0 <= 1.0, "points = {points}, x = {x}: {value} vs {p}");
                    assert!(
                        e1 <= 1.0,
                        "points = {points}, x = {x}: {derivative} vs {dp}"
                    );
                    per_point.push((value, derivative, factor * cond, factor * dcond));
                }
                results.push(per_point);
            }
            for (a, b) in results[0].iter().zip(&results[1]) {
                assert!((a.0 - b.0).abs() <= a.2 + b.2);
                assert!((a.1 - b.1).abs() <= a.3 + b.3);
            }
        }
    }

    /// Σ_j l_j(x) = 1 and Σ_j l_j'(x) = 0 everywhere (constants are reproduced), for unsorted
    /// nodes too; and a permutation of the nodes permutes the basis.
    #[test]
    fn partition_of_unity_and_node_order() {
        let mut rng = Lcg(5);
        let sorted = chebyshev_gauss_lobatto(9).unwrap();
        let order = [4, 0, 8, 2, 7, 1, 5, 3, 6];
        let shuffled: Vec<f64> = order.iter().map(|&k| sorted[k]).collect();
        let (a, b) = (
            LagrangeBasis::chebyshev_gauss_lobatto(9).unwrap(),
            LagrangeBasis::new(shuffled).unwrap(),
        );
        let (mut la, mut lb, mut da, mut db) = ([0.0; 9], [0.0; 9], [0.0; 9], [0.0; 9]);
        for x in (0..40).map(|_| 1.6 * rng.next()).chain([-1.0, 1.0, 0.0]) {
            a.values_into(x, &mut la);
            b.values_into(x, &mut lb);
            a.derivatives_into(x, &mut da);
            b.derivatives_into(x, &mut db);
            let size = |v: &[f64]| v.iter().map(|t| t.abs()).sum::<f64>();
            assert!(
                (la.iter().sum::<f64>() - 1.0).abs() <= 20.0 * EPS * size(&la),
                "x = {x}"
            );
            assert!(
                da.iter().sum::<f64>().abs() <= 20.0 * EPS * size(&da),
                "x = {x}"
            );
            for (k, &j) in order.iter().enumerate() {
                assert!(
                    (lb[k] - la[j]).abs() <= 40.0 * EPS * la[j].abs().max(1.0),
                    "x = {x}"
                );
                assert!((db[k] - da[j]).abs() <= 40.0 * EPS * size(&da), "x = {x}");
            }
        }
    }
}
