//! The discrete Fourier series of a periodic field on M equispaced nodes (Leok §5.8.2): the
//! FFT plans (`rustfft`, planned once), the wavenumbers and the spectral derivative, with every
//! buffer allocated once and an FFT counter for work statistics.
//!
//! On the periodic domain [a, a + ℓ) with nodes x_j = a + jΔx, Δx = ℓ/M (M even), the
//! trigonometric interpolant of the nodal values v_j is
//!
//! v(x) = (1/M) Σ'_{k} v̂_k e^{iκ_k (x − a)}, v̂_k = Σ_j v_j e^{−iκ_k (x_j − a)},
//! κ_k = 2πk/ℓ, k = −M/2 + 1, …, M/2
//!
//! (the seed's normalisation 1/2π and h/2π is this one for ℓ = 2π; the primed sum splits the
//! Nyquist mode k = M/2 evenly between ±M/2, which makes the interpolant of real data real).
//! The spectral derivative D takes v to the nodal values of v′: multiply v̂_k by iκ_k, with the
//! Nyquist mode's derivative set to zero (its ±M/2 halves cancel). So D is a real matrix, it
//! is antisymmetric (Dᵀ = −D: the transpose of the spectral derivative is minus itself, which
//! turns Σ_j ∂ℒ/∂u_x · (Du)_j into −D ∂ℒ/∂u_x in the gradient of the semi-discrete action), it
//! commutes with the shift, and D² has the eigenvalues −κ_k² (0 at Nyquist).

use std::sync::Arc;

pub use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

use crate::error::Error;
use crate::model::density::Domain;

/// The smallest number of Fourier modes (nodes) of a [`Fourier`] grid.
pub const MIN_MODES: usize = 4;

/// The largest number of Fourier modes (2²⁴: 256 MB per complex buffer).
pub const MAX_MODES: usize = 1 << 24;

/// FFT plans, wavenumbers and scratch for the nodes of a periodic domain.
pub struct Fourier {
    domain: Domain,
    modes: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    scratch: Vec<Complex64>,
    wavenumbers: Vec<f64>,
    ffts: usize,
}

impl std::fmt::Debug for Fourier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fourier")
            .field("domain", &self.domain)
            .field("modes", &self.modes)
            .field("ffts", &self.ffts)
            .finish_non_exhaustive()
    }
}

impl Clone for Fourier {
    fn clone(&self) -> Self {
        Fourier {
            domain: self.domain,
            modes: self.modes,
            forward: Arc::clone(&self.forward),
            inverse: Arc::clone(&self.inverse),
            scratch: self.scratch.clone(),
            wavenumbers: self.wavenumbers.clone(),
            ffts: self.ffts,
        }
    }
}

impl Fourier {
    /// The Fourier grid of `modes` nodes on the periodic `domain`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `modes` if the count is odd, below [`MIN_MODES`] or above
    /// [`MAX_MODES`].
    pub fn new(domain: Domain, modes: usize) -> Result<Self, Error> {
        if !(MIN_MODES..=MAX_MODES).contains(&modes) || !modes.is_multiple_of(2) {
            return Err(Error::invalid(
                "modes",
                format!(
                    "{modes} Fourier modes: need an even number from {MIN_MODES} to {MAX_MODES}"
                ),
            ));
        }
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(modes);
        let inverse = planner.plan_fft_inverse(modes);
        let scratch_len = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        let base = 2.0 * std::f64::consts::PI / domain.length();
        let wavenumbers = (0..modes)
            .map(|k| {
                let k = k as isize;
                let m = modes as isize;
                let signed = if k < m / 2 { k } else { k - m };
                base * signed as f64
            })
            .collect();
        Ok(Fourier {
            domain,
            modes,
            forward,
            inverse,
            scratch: vec![Complex64::default(); scratch_len],
            wavenumbers,
            ffts: 0,
        })
    }

    /// The number of modes (= nodes) M.
    pub fn modes(&self) -> usize {
        self.modes
    }

    /// The node spacing Δx = ℓ/M.
    pub fn dx(&self) -> f64 {
        self.domain.length() / self.modes as f64
    }

    /// The node x_j = a + jΔx.
    pub fn x(&self, node: usize) -> f64 {
        self.domain.left() + node as f64 * self.dx()
    }

    /// The wavenumber κ_k of the FFT's output slot k (slots k ≥ M/2 hold −M + k; the Nyquist
    /// slot M/2 holds −πM/ℓ).
    pub fn wavenumber(&self, slot: usize) -> f64 {
        self.wavenumbers[slot]
    }

    /// The wavenumber of the first derivative in slot k: κ_k, and 0 for the Nyquist mode.
    pub fn derivative_wavenumber(&self, slot: usize) -> f64 {
        if slot == self.modes / 2 {
            0.0
        } else {
            self.wavenumbers[slot]
        }
    }

    /// The FFTs computed so far (forward and inverse alike).
    pub fn ffts(&self) -> usize {
        self.ffts
    }

    /// v ↦ v̂ in place (unnormalised).
    ///
    /// # Panics
    /// If `values` does not hold [`Fourier::modes`] entries (or a multiple of it, which
    /// transforms each block; [`Fourier::ffts`] then counts one): rustfft refuses other lengths.
    pub fn forward_in_place(&mut self, values: &mut [Complex64]) {
        self.forward.process_with_scratch(values, &mut self.scratch);
        self.ffts += 1;
    }

    /// v̂ ↦ v in place (with the 1/M of the inverse transform).
    ///
    /// # Panics
    /// As [`Fourier::forward_in_place`], for a length other than a multiple of the modes.
    pub fn inverse_in_place(&mut self, values: &mut [Complex64]) {
        self.inverse.process_with_scratch(values, &mut self.scratch);
        let scale = 1.0 / self.modes as f64;
        for value in values.iter_mut() {
            *value *= scale;
        }
        self.ffts += 1;
    }

    /// v ↦ Dv in place: the nodal values of the derivative of the trigonometric interpolant
    /// (two FFTs). D acts on real and imaginary parts separately (it is a real matrix).
    ///
    /// # Panics
    /// If `values` does not hold exactly [`Fourier::modes`] entries.
    pub fn derivative_in_place(&mut self, values: &mut [Complex64]) {
        self.forward_in_place(values);
        for (slot, value) in values.iter_mut().enumerate() {
            *value *= Complex64::new(0.0, self.derivative_wavenumber(slot));
        }
        self.inverse_in_place(values);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spectral_derivative_is_exact_on_trigonometric_polynomials_and_antisymmetric() {
        let domain = Domain::new(-1.0, 3.0).unwrap();
        let mut fourier = Fourier::new(domain, 16).unwrap();
        let kappa = 2.0 * std::f64::consts::PI / 4.0;
        let mut values: Vec<Complex64> = (0..16)
            .map(|j| {
                let x = fourier.x(j) + 1.0;
                Complex64::new((3.0 * kappa * x).sin(), (7.0 * kappa * x).cos())
            })
            .collect();
        fourier.derivative_in_place(&mut values);
        for (j, value) in values.iter().enumerate() {
            let x = fourier.x(j) + 1.0;
            let expected = Complex64::new(
                3.0 * kappa * (3.0 * kappa * x).cos(),
                -7.0 * kappa * (7.0 * kappa * x).sin(),
            );
            assert!((value - expected).norm() < 1e-12, "{j}");
        }
        assert_eq!(fourier.ffts(), 2);
        // Dᵀ = −D: the matrix of D, column by column, is antisymmetric.
        let columns: Vec<Vec<Complex64>> = (0..16)
            .map(|c| {
                let mut e = vec![Complex64::default(); 16];
                e[c] = Complex64::new(1.0, 0.0);
                fourier.derivative_in_place(&mut e);
                e
            })
            .collect();
        for (i, column) in columns.iter().enumerate() {
            for (j, entry) in column.iter().enumerate() {
                assert!(entry.im.abs() < 1e-15);
                assert!((entry.re + columns[j][i].re).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn odd_or_tiny_mode_counts_are_errors() {
        let domain = Domain::new(0.0, 1.0).unwrap();
        for modes in [0, 2, 7, 33] {
            match Fourier::new(domain, modes) {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "modes"),
                other => panic!("{other:?}"),
            }
        }
    }
}
