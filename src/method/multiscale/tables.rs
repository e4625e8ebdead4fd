//! The tables of a multiscale run: the basis functions of the function space — the Lagrange
//! basis l_ν on the CGL points and the oscillatory φ^A_e, φ^B_e — and their rates at the
//! quadrature points (x_j, ψ_κ), the Filon–Lobatto weights Ω_jκ of the discrete action for
//! the current h and ω (Leok 2004, §5.7.2), and the extrapolation of a step's curve to the
//! next step's starting values.

use super::Multiscale;
use crate::dimension::Dimension;
use crate::error::Error;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::filon::FilonLobatto;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector, U1};

/// Tables of one run: basis functions at the quadrature points (x_j, ψ_κ) for the current
/// h and ω.
#[derive(Debug, Clone)]
pub(super) struct Tables {
    /// Polynomial degree s.
    pub(super) degree: usize,
    /// Envelope degree d.
    envelope: usize,
    /// Number of basis functions, s + 1 + 2(d + 1).
    pub(super) basis: usize,
    /// Number of phase points K.
    phases: usize,
    /// The (h, ω) the scaled tables are built for (NaN before the first step).
    pub(super) h: f64,
    pub(super) omega: f64,
    /// Filon–Lobatto rule in x.
    filon: FilonLobatto,
    /// l_ν(x_j), row-major n × (s + 1).
    values: Vec<f64>,
    /// l̇_ν(x_j), row-major n × (s + 1).
    slopes: Vec<f64>,
    /// Filon cosine and sine weights for mθ, m = 0..=M, row-major (M + 1) × n.
    cosine: Vec<f64>,
    sine: Vec<f64>,
    /// (h/2) Ω_jκ at point p = j·K + κ.
    pub(super) weights: Vec<f64>,
    /// φ_b and φ̇_b at point p, row-major (n·K) × basis.
    pub(super) point_values: Vec<f64>,
    pub(super) point_rates: Vec<f64>,
    /// Filon node x_p of point p (for its time).
    point_nodes: Vec<f64>,
    /// The CGL nodes x_ν of the polynomial part.
    pub(super) nodes: Vec<f64>,
    /// l_μ(x_ν + 2), row-major (s + 1) × (s + 1): the last step's Lagrange basis at this
    /// step's nodes (extrapolation).
    extrapolation: Vec<f64>,
}

impl Tables {
    pub(super) fn new(options: &Multiscale) -> Result<Self, Error> {
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(options.points)?;
        let filon = FilonLobatto::new(options.filon_points())?;
        let n = filon.len();
        let s = options.points - 1;
        let phases = 2 * options.harmonics + 1;
        let count = s + 1 + 2 * (options.envelope + 1);
        let values = basis.value_matrix(filon.nodes());
        let slopes = basis.derivative_matrix(filon.nodes());
        let shifted: Vec<f64> = basis.nodes().iter().map(|x| x + 2.0).collect();
        let extrapolation = basis.value_matrix(&shifted);
        let row_major = |m: &DMatrix<f64>| -> Vec<f64> {
            (0..m.nrows() * m.ncols())
                .map(|k| m[(k / m.ncols(), k % m.ncols())])
                .collect()
        };
        let points = n * phases;
        Ok(Tables {
            degree: s,
            envelope: options.envelope,
            basis: count,
            phases,
            h: f64::NAN,
            omega: f64::NAN,
            values: row_major(&values),
            slopes: row_major(&slopes),
            cosine: vec![0.0; (options.harmonics + 1) * n],
            sine: vec![0.0; (options.harmonics + 1) * n],
            weights: vec![0.0; points],
            point_values: vec![0.0; points * count],
            point_rates: vec![0.0; points * count],
            point_nodes: (0..points).map(|p| filon.nodes()[p / phases]).collect(),
            nodes: basis.nodes().to_vec(),
            extrapolation: row_major(&extrapolation),
            filon,
        })
    }

    /// Number of quadrature points n·K.
    pub(super) fn points(&self) -> usize {
        self.weights.len()
    }

    /// Build the weights and basis tables for steps of size `h` and frequency `omega` (no
    /// allocation).
    pub(super) fn rebuild(&mut self, h: f64, omega: f64) {
        self.h = h;
        self.omega = omega;
        let n = self.filon.len();
        let k_count = self.phases;
        let harmonics = (k_count - 1) / 2;
        let theta = 0.5 * h * omega;
        for m in 0..=harmonics {
            let (cos_row, sin_row) = (
                &mut self.cosine[m * n..(m + 1) * n],
                &mut self.sine[m * n..(m + 1) * n],
            );
            // θ is finite and positive (checked by the caller), so this cannot fail.
            let _ = self.filon.weights(m as f64 * theta, cos_row, sin_row);
        }
        let s = self.degree;
        let count = self.basis;
        let (sin_end, cos_end) = (2.0 * theta).sin_cos();
        for j in 0..n {
            let x = self.filon.nodes()[j];
            for kappa in 0..k_count {
                let p = j * k_count + kappa;
                let psi = 2.0 * std::f64::consts::PI * kappa as f64 / k_count as f64;
                let mut omega_jk = self.cosine[j];
                for m in 1..=harmonics {
                    let alpha = m as f64 * (theta - psi);
                    let (sa, ca) = alpha.sin_cos();
                    omega_jk += 2.0 * (self.cosine[m * n + j] * ca - self.sine[m * n + j] * sa);
                }
                self.weights[p] = 0.5 * h * omega_jk / k_count as f64;
                let value = &mut self.point_values[p * count..(p + 1) * count];
                let rate = &mut self.point_rates[p * count..(p + 1) * count];
                for nu in 0..=s {
                    value[nu] = self.values[j * (s + 1) + nu];
                    rate[nu] = 2.0 / h * self.slopes[j * (s + 1) + nu];
                }
                let (l_end, dl_end) = (self.values[j * (s + 1) + s], self.slopes[j * (s + 1) + s]);
                let (sin_psi, cos_psi) = psi.sin_cos();
                for e in 0..=self.envelope {
                    let envelope = x.powi(e as i32);
                    let slope = if e == 0 {
                        0.0
                    } else {
                        e as f64 * x.powi(e as i32 - 1)
                    };
                    let a = s + 1 + e;
                    let b = s + 1 + self.envelope + 1 + e;
                    value[a] = sin_psi * envelope - sin_end * l_end;
                    rate[a] =
                        2.0 / h * (sin_psi * slope - sin_end * dl_end) + omega * cos_psi * envelope;
                    value[b] = (cos_psi - 1.0) * envelope - (cos_end - 1.0) * l_end;
                    rate[b] = 2.0 / h * ((cos_psi - 1.0) * slope - (cos_end - 1.0) * dl_end)
                        - omega * sin_psi * envelope;
                }
            }
        }
    }

    /// Starting values of the next step from the converged unknowns `z` of the last one,
    /// written into `next`: the last step's curve continued to the next step (x′ = x − 2,
    /// ψ′ = ψ − 2θ) and written in the next step's basis. With c = cos 2θ, s = sin 2θ, the
    /// oscillation Σ_e xᵉ (A_e sin ψ + B_e cos ψ) is Σ_j x′ʲ (Â_j sin ψ′ + B̂_j cos ψ′),
    /// Â_j = Σ_{e≥j} C(e, j) 2^{e−j} (A_e c − B_e s), B̂_j = Σ_{e≥j} C(e, j) 2^{e−j}
    /// (A_e s + B_e c), and the polynomial part P(x) = q_k + Σ_ν z_ν l_ν(x) − Σ_e (A_e s +
    /// B_e (c − 1)) l_s(x) − Σ_e B_e xᵉ of the last step gives the new offsets
    /// z′_ν = P(x_ν + 2) + Σ_j B̂_j x_νʲ + δ_νs Σ_j (Â_j s + B̂_j (c − 1)) − q_{k+1}.
    pub(super) fn extrapolate<N: Dimension>(&self, n: N, z: &DVector<f64>, next: &mut DVector<f64>)
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let s = self.degree;
        let amplitudes = self.envelope + 1;
        let theta = 0.5 * self.h * self.omega;
        let (sin_end, cos_end) = (2.0 * theta).sin_cos();
        let size = n.value();
        let block =
            |v: &DVector<f64>, c: usize| v.generic_view((c * size, 0), (n, U1)).into_owned();
        let (a_col, b_col) = (|e: usize| s + e, |e: usize| s + amplitudes + e);
        next.fill(0.0);
        // Â and B̂ (binomial re-expansion of the envelopes about x′ = x − 2).
        for j in 0..amplitudes {
            let mut a_hat = OVector::<f64, N>::zeros_generic(n, U1);
            let mut b_hat = OVector::<f64, N>::zeros_generic(n, U1);
            let mut binomial = 1.0;
            for e in j..amplitudes {
                // C(e, j) 2^{e−j}, built up from e = j.
                if e > j {
                    binomial *= e as f64 / (e - j) as f64 * 2.0;
                }
                let (a, b) = (block(z, a_col(e)), block(z, b_col(e)));
                a_hat += (&a * cos_end - &b * sin_end) * binomial;
                b_hat += (a * sin_end + b * cos_end) * binomial;
            }
            next.generic_view_mut((a_col(j) * size, 0), (n, U1))
                .copy_from(&a_hat);
            next.generic_view_mut((b_col(j) * size, 0), (n, U1))
                .copy_from(&b_hat);
        }
        let end = block(z, s - 1);
        let mut end_shift = OVector::<f64, N>::zeros_generic(n, U1);
        for j in 0..amplitudes {
            let (a_hat, b_hat) = (block(next, a_col(j)), block(next, b_col(j)));
            end_shift += a_hat * sin_end + b_hat * (cos_end - 1.0);
        }
        let mut last_shift = OVector::<f64, N>::zeros_generic(n, U1);
        for e in 0..amplitudes {
            last_shift += block(z, a_col(e)) * sin_end + block(z, b_col(e)) * (cos_end - 1.0);
        }
        for nu in 1..=s {
            let x = self.nodes[nu];
            let row = &self.extrapolation[nu * (s + 1)..(nu + 1) * (s + 1)];
            // P(x_ν + 2) − q_{k+1}, with P relative to q_k.
            let mut value = -&end - &last_shift * row[s];
            for (mu, &l) in row.iter().enumerate().skip(1) {
                value += block(z, mu - 1) * l;
            }
            let mut power = 1.0;
            for e in 0..amplitudes {
                value -= block(z, b_col(e)) * (x + 2.0).powi(e as i32);
                value += block(next, b_col(e)) * power;
                power *= x;
            }
            if nu == s {
                value += &end_shift;
            }
            next.generic_view_mut(((nu - 1) * size, 0), (n, U1))
                .copy_from(&value);
        }
    }

    /// The basis function of unknown column c: Z_1, …, Z_s, then the oscillatory ones.
    pub(super) fn column_basis(&self, c: usize) -> usize {
        c + 1
    }

    /// The basis function of equation row r: g_0, …, g_{s−1}, then the oscillatory ones.
    pub(super) fn row_basis(&self, r: usize) -> usize {
        if r < self.degree { r } else { r + 1 }
    }

    /// q and q̇ at point p for the unknowns z (offsets Z_ν − q_k, then amplitudes).
    pub(super) fn point<N: Dimension>(
        &self,
        p: usize,
        q0: &OVector<f64, N>,
        z: &DVector<f64>,
    ) -> (OVector<f64, N>, OVector<f64, N>)
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let count = self.basis;
        let value = &self.point_values[p * count..(p + 1) * count];
        let rate = &self.point_rates[p * count..(p + 1) * count];
        let (n, _) = q0.shape_generic();
        let mut q = q0.clone();
        let mut v = OVector::<f64, N>::zeros_generic(n, U1);
        // Unknown column c multiplies basis function c + 1 (`column_basis`).
        for ((zc, &value), &rate) in z
            .as_slice()
            .chunks_exact(n.value())
            .zip(&value[1..])
            .zip(&rate[1..])
        {
            for d in 0..n.value() {
                q[d] += value * zc[d];
                v[d] += rate * zc[d];
            }
        }
        (q, v)
    }

    pub(super) fn time(&self, t: f64, p: usize) -> f64 {
        t + 0.5 * self.h * (self.point_nodes[p] + 1.0)
    }
}
