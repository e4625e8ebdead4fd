//! The tables of a Lie-SVI step, shared by every group: the Lagrange basis on the d + 1
//! Chebyshev–Gauss–Lobatto points, its values l_ν(τ_μ) and scaled derivatives (2/h) l̇_ν(τ_μ)
//! at the m Gauss points, the weights W_μ = (h/2) w_μ, and the extrapolation of the previous
//! step's curve to the new nodes (warm start).

use crate::error::Error;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::quadrature::GaussLegendre;
use nalgebra::{DMatrix, DVector, SVector};

/// Interpolation and quadrature tables of a step, scaled to its size h.
#[derive(Debug, Clone)]
pub(super) struct StepTables {
    /// Degree d of ξ(τ).
    pub(super) degree: usize,
    /// The step size the scaled tables are for.
    pub(super) h: f64,
    /// Gauss weights w_μ.
    reference_weights: Vec<f64>,
    /// W_μ = (h/2) w_μ.
    pub(super) weights: Vec<f64>,
    /// Gauss nodes τ_μ ∈ (−1, 1).
    gauss_nodes: Vec<f64>,
    /// l_ν(τ_μ), m × (d + 1).
    pub(super) values: DMatrix<f64>,
    /// l̇_ν(τ_μ), m × (d + 1).
    reference_derivatives: DMatrix<f64>,
    /// (2/h) l̇_ν(τ_μ), m × (d + 1).
    pub(super) derivatives: DMatrix<f64>,
    /// l_j(x_ν + 2), (d + 1) × (d + 1): the previous step's polynomial at the new nodes.
    pub(super) extrapolation: DMatrix<f64>,
    /// CGL nodes x_ν.
    pub(super) nodes: Vec<f64>,
    /// The Lagrange basis on the CGL nodes (dense output).
    basis: LagrangeBasis,
}

impl StepTables {
    /// Tables for `points` CGL points and `quadrature` Gauss points, scaled to `h`.
    pub(super) fn new(points: usize, quadrature: usize, h: f64) -> Result<Self, Error> {
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(points)?;
        let gauss = GaussLegendre::new(quadrature)?;
        let degree = points - 1;
        let shifted: Vec<f64> = basis.nodes().iter().map(|x| x + 2.0).collect();
        let mut tables = StepTables {
            degree,
            h: f64::NAN,
            reference_weights: gauss.weights().to_vec(),
            weights: vec![0.0; gauss.len()],
            gauss_nodes: gauss.nodes().to_vec(),
            values: basis.value_matrix(gauss.nodes()),
            reference_derivatives: basis.derivative_matrix(gauss.nodes()),
            derivatives: DMatrix::zeros(gauss.len(), degree + 1),
            extrapolation: basis.value_matrix(&shifted),
            nodes: basis.nodes().to_vec(),
            basis,
        };
        tables.rescale(h);
        Ok(tables)
    }

    /// The time t + (h/2)(τ_μ + 1) of Gauss point `mu` on the step from `t`.
    pub(super) fn time(&self, t: f64, mu: usize) -> f64 {
        t + 0.5 * self.h * (self.gauss_nodes[mu] + 1.0)
    }

    /// Number of Gauss points m.
    pub(super) fn len(&self) -> usize {
        self.weights.len()
    }

    /// Scale the weights and derivatives to a step of size `h`.
    pub(super) fn rescale(&mut self, h: f64) {
        self.h = h;
        for (w, r) in self.weights.iter_mut().zip(&self.reference_weights) {
            *w = 0.5 * h * r;
        }
        self.derivatives
            .zip_apply(&self.reference_derivatives, |d, r| *d = 2.0 / h * r);
    }

    /// a = ξ(τ_μ) and b = ξ̇(τ_μ) at Gauss point `mu` for the stacked nodes ξ¹…ξᵈ in `z`
    /// (ξ⁰ = 0), `K` numbers per node.
    #[inline]
    pub(super) fn point<const K: usize>(
        &self,
        mu: usize,
        z: &DVector<f64>,
    ) -> (SVector<f64, K>, SVector<f64, K>) {
        let mut a = SVector::zeros();
        let mut b = SVector::zeros();
        for nu in 1..=self.degree {
            let node = z.fixed_rows::<K>(K * (nu - 1));
            a += node * self.values[(mu, nu)];
            b += node * self.derivatives[(mu, nu)];
        }
        (a, b)
    }

    /// ξ(τ) and ξ̇(τ) on a step of size `h` at τ ∈ [−1, 1] (dense output), `K` numbers per
    /// node.
    pub(super) fn curve<const K: usize>(
        &self,
        tau: f64,
        h: f64,
        z: &DVector<f64>,
    ) -> (SVector<f64, K>, SVector<f64, K>) {
        let values = self.basis.value_matrix(&[tau]);
        let rates = self.basis.derivative_matrix(&[tau]);
        let mut xi = SVector::zeros();
        let mut rate = SVector::zeros();
        for nu in 1..=self.degree {
            let node = z.fixed_rows::<K>(K * (nu - 1));
            xi += node * values[(0, nu)];
            rate += node * (2.0 / h * rates[(0, nu)]);
        }
        (xi, rate)
    }

    /// The previous step's curve (nodes `previous`) at the new node ν, as an offset from the
    /// previous step's first point.
    pub(super) fn extrapolated<const K: usize>(
        &self,
        nu: usize,
        previous: &DVector<f64>,
    ) -> SVector<f64, K> {
        let mut zeta = SVector::zeros();
        for j in 1..=self.degree {
            zeta += previous.fixed_rows::<K>(K * (j - 1)) * self.extrapolation[(nu, j)];
        }
        zeta
    }
}
