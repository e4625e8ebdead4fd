//! Starting values for the Newton iteration of the spectral methods.
//!
//! As in Hairer's GNI codes, step k + 1 starts from the polynomial of step k evaluated at the
//! new step's nodes: on the reference interval of step k the new nodes sit at x_ν + 2, so the
//! guess is a fixed matrix l_j(x_ν + 2) applied to the previous node values. The first step
//! (or the first after a change of step size) starts from the Taylor polynomial
//! q_k + q̇ (t − t_k) + q̈ (t − t_k)²/2.
//!
//! Node values are stored as offsets qᵛ − q_k (ν = 1, …, s; q⁰ − q_k = 0 is implicit).

use crate::basis::LagrangeBasis;
use nalgebra::{DVector, SVector};

/// Extrapolation table and the previous step's node offsets.
#[derive(Debug, Clone)]
pub(crate) struct StartingValues {
    /// CGL nodes x_ν on [−1, 1].
    nodes: Vec<f64>,
    /// X_νj = l_j(x_ν + 2) − δ_js, ν, j = 1..s, row-major: by Σ_j l_j = 1 the new offsets
    /// are Σ_j X_νj Z_j from the previous offsets Z_j.
    extrapolation: Vec<f64>,
    /// Node offsets of the previous step (ν = 1..s, stacked).
    previous: DVector<f64>,
    /// Whether `previous` belongs to a step of the current size.
    valid: bool,
}

impl StartingValues {
    pub(crate) fn new(basis: &LagrangeBasis, dimension: usize) -> Self {
        let shifted: Vec<f64> = basis.nodes().iter().map(|x| x + 2.0).collect();
        let values = basis.value_matrix(&shifted);
        let s = basis.len() - 1;
        let extrapolation = (0..s * s)
            .map(|k| {
                let (nu, j) = (k / s + 1, k % s + 1);
                values[(nu, j)] - f64::from(j == s)
            })
            .collect();
        StartingValues {
            nodes: basis.nodes().to_vec(),
            extrapolation,
            previous: DVector::zeros((basis.len() - 1) * dimension),
            valid: false,
        }
    }

    /// Forget the previous step (after a change of step size).
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Whether a previous step is available to extrapolate.
    pub(crate) fn has_previous(&self) -> bool {
        self.valid
    }

    /// Remember the converged offsets of this step.
    pub(crate) fn remember(&mut self, offsets: &DVector<f64>) {
        self.previous.copy_from(offsets);
        self.valid = true;
    }

    /// Offsets from the previous step's polynomial, relative to the new start q_{k+1}.
    pub(crate) fn extrapolate<const N: usize>(&self, offsets: &mut DVector<f64>) {
        let s = self.nodes.len() - 1;
        let previous = self.previous.as_slice();
        for (nu, target) in offsets.as_mut_slice().chunks_exact_mut(N).enumerate() {
            let row = &self.extrapolation[nu * s..(nu + 1) * s];
            target.fill(0.0);
            for (x, node) in row.iter().zip(previous.chunks_exact(N)) {
                for (t, z) in target.iter_mut().zip(node) {
                    *t += x * z;
                }
            }
        }
    }

    /// Offsets of the Taylor polynomial with velocity `v` and acceleration `a`.
    pub(crate) fn taylor<const N: usize>(
        &self,
        h: f64,
        v: &SVector<f64, N>,
        a: &SVector<f64, N>,
        offsets: &mut DVector<f64>,
    ) {
        for (nu, x) in self.nodes.iter().enumerate().skip(1) {
            let dt = 0.5 * h * (x + 1.0);
            let guess = v * dt + a * (0.5 * dt * dt);
            offsets.fixed_rows_mut::<N>((nu - 1) * N).copy_from(&guess);
        }
    }
}
