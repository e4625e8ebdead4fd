//! The alignment indices SALI and GALI_k of deviation vectors.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::method::space::State;
use crate::stepping::tangent::{TangentObserver, TangentStep};
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::ops::ControlFlow;

use super::{
    Deviations, initial_deviations, lost, orthonormalize, phase_dimension, require_threshold,
};

/// Options of [`Sali`].
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct SaliOptions {
    /// The two initial deviation vectors (2N entries each, q then y); `None` (the
    /// default): two fixed pseudo-random orthonormal vectors (the first two of [`Gali`]'s).
    pub deviations: Option<[Vec<f64>; 2]>,
    /// Stop the run once SALI falls below this (positive, finite; the usual criterion of
    /// chaos is 10⁻⁸); `None` (the default): run to the horizon.
    pub stop_below: Option<f64>,
}

impl SaliOptions {
    /// Stop the run once SALI falls below `threshold`.
    pub fn with_stop_below(mut self, threshold: f64) -> Self {
        self.stop_below = Some(threshold);
        self
    }

    /// Start from the deviation vectors `deviations`.
    pub fn with_deviations(mut self, deviations: [Vec<f64>; 2]) -> Self {
        self.deviations = Some(deviations);
        self
    }
}

/// The Smaller Alignment Index of two deviation vectors (Skokos 2001).
///
/// # Mathematics
///
/// Propagate w₁, w₂ by the tangent maps and normalise them every step, ŵ = w/‖w‖:
///
/// ```text
/// SALI(t) = min(‖ŵ₁ + ŵ₂‖, ‖ŵ₁ − ŵ₂‖)  ∈ [0, √2]
/// ```
///
/// On a chaotic orbit both vectors align with the most unstable direction and
/// SALI ∝ e^{−(λ₁−λ₂) t} → 0 (to round-off, ~10⁻¹⁶); on a regular orbit of a system of 2
/// degrees of freedom they fall into the tangent space of the torus without aligning and SALI
/// fluctuates around a positive value.
///
/// # References
///
/// Skokos, J. Phys. A 34 (2001) 10029–10043; Skokos, Lect. Notes Phys. 790 (2010) §6.
#[derive(Debug, Clone)]
pub struct Sali {
    options: SaliOptions,
    deviations: Deviations,
    norms: [f64; 2],
    value: f64,
    t0: f64,
    time: f64,
}

impl Sali {
    /// The observer, after checking the threshold.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `stop_below` unless positive and finite.
    pub fn new(options: SaliOptions) -> Result<Self, Error> {
        require_threshold("stop_below", options.stop_below)?;
        Ok(Sali {
            options,
            deviations: Deviations::default(),
            norms: [0.0; 2],
            value: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &SaliOptions {
        &self.options
    }

    /// SALI after the last step (at the start of a run: of the initial vectors).
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// min(‖ŵ₁ + ŵ₂‖, ‖ŵ₁ − ŵ₂‖) of the current unit vectors.
    fn index(&self) -> f64 {
        let (a, b) = (self.deviations.column(0), self.deviations.column(1));
        let (mut plus, mut minus) = (0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            plus += (x + y) * (x + y);
            minus += (x - y) * (x - y);
        }
        plus.min(minus).sqrt()
    }
}

impl<N: Dimension> TangentObserver<N> for Sali
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviations` for vectors of the wrong length, zero or not
    /// finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let given = self.options.deviations.as_ref().map(|pair| pair.as_slice());
        let vectors = initial_deviations("deviations", given, phase_dimension(state), 2)?;
        self.deviations = Deviations::new(vectors);
        (self.t0, self.time) = (t0, 0.0);
        self.value = self.index();
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.norms) {
            return Err(lost("SALI", step));
        }
        self.value = self.index();
        self.time = step.t - self.t0;
        Ok(match self.options.stop_below {
            Some(threshold) if self.value < threshold => ControlFlow::Break(()),
            _ => ControlFlow::Continue(()),
        })
    }
}

/// Options of [`Gali`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct GaliOptions {
    /// The number k of deviation vectors, 1 ..= 2N (default 2; GALI₁ is always 1).
    pub k: usize,
    /// The k initial deviation vectors (2N entries each, q then y; linearly independent);
    /// `None` (the default): k fixed pseudo-random orthonormal vectors.
    pub deviations: Option<Vec<Vec<f64>>>,
    /// Stop the run once GALI_k falls below this (positive, finite); `None` (the default):
    /// run to the horizon.
    pub stop_below: Option<f64>,
}

impl Default for GaliOptions {
    fn default() -> Self {
        GaliOptions {
            k: 2,
            deviations: None,
            stop_below: None,
        }
    }
}

impl GaliOptions {
    /// GALI of order `k`.
    pub fn with_k(mut self, k: usize) -> Self {
        self.k = k;
        self
    }

    /// Stop the run once GALI_k falls below `threshold`.
    pub fn with_stop_below(mut self, threshold: f64) -> Self {
        self.stop_below = Some(threshold);
        self
    }

    /// Start from the deviation vectors `deviations`.
    pub fn with_deviations(mut self, deviations: Vec<Vec<f64>>) -> Self {
        self.deviations = Some(deviations);
        self
    }
}

/// The Generalized Alignment Index of order k (Skokos, Bountis & Antonopoulos 2007).
///
/// # Mathematics
///
/// Propagate k deviation vectors, normalise them every step, and take the volume of the
/// parallelepiped of the unit vectors:
///
/// ```text
/// GALI_k(t) = ‖ŵ₁ ∧ ŵ₂ ∧ … ∧ ŵ_k‖ = √det(ŴᵀŴ) = Π σ_i(Ŵ) = Π |r_ii|,   Ŵ = Q R
/// ```
///
/// computed from R's diagonal (modified Gram–Schmidt applied twice on a copy), which keeps
/// its relative accuracy where the Gram determinant 1 − cos²θ would cancel. On a chaotic
/// orbit GALI_k ∝ e^{−[(λ₁−λ₂) + (λ₁−λ₃) + … + (λ₁−λ_k)] t}; on a regular orbit on an
/// N-torus it stays O(1) for k ≤ N and decays like t^{−2(k−N)} for N < k ≤ 2N. With ŵ₁, ŵ₂ at
/// angle θ, GALI₂ = |sin θ| and SALI = 2 min(|sin θ/2|, |cos θ/2|), hence
/// SALI/√2 ≤ GALI₂ ≤ SALI (Skokos et al. 2007, eq. 9).
///
/// # References
///
/// Skokos, Bountis, Antonopoulos, Physica D 231 (2007) 30–54; Skokos, Lect. Notes Phys. 790
/// (2010) §6.
#[derive(Debug, Clone)]
pub struct Gali {
    options: GaliOptions,
    deviations: Deviations,
    /// A copy of the unit vectors for the QR, and its diagonal (the vectors' norms first).
    work: Vec<f64>,
    diagonal: Vec<f64>,
    value: f64,
    t0: f64,
    time: f64,
}

impl Gali {
    /// The observer, after checking the options that do not depend on the model (k is
    /// checked against 2N when the run begins).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `k` for zero, `stop_below` unless positive and finite.
    pub fn new(options: GaliOptions) -> Result<Self, Error> {
        if options.k == 0 {
            return Err(Error::invalid("k", "GALI_k takes k ≥ 1 deviation vectors"));
        }
        require_threshold("stop_below", options.stop_below)?;
        Ok(Gali {
            options,
            deviations: Deviations::default(),
            work: Vec::new(),
            diagonal: Vec::new(),
            value: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &GaliOptions {
        &self.options
    }

    /// GALI_k after the last step (at the start of a run: of the initial vectors).
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Π r_ii of the QR factorisation of the current unit vectors (0 if they are dependent
    /// to round-off).
    fn volume(&mut self) -> f64 {
        self.work
            .copy_from_slice(self.deviations.vectors.as_slice());
        let rows = self.deviations.vectors.nrows();
        if orthonormalize(&mut self.work, rows, &mut self.diagonal) {
            self.diagonal.iter().product()
        } else {
            0.0
        }
    }
}

impl<N: Dimension> TangentObserver<N> for Gali
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `k` beyond 2N; `deviations` for vectors of the wrong
    /// number or length, zero, not finite or linearly dependent.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let rows = phase_dimension(state);
        let k = self.options.k;
        if !(1..=rows).contains(&k) {
            return Err(Error::invalid(
                "k",
                format!("GALI_{k} in a phase space of {rows} dimensions (1 ..= 2N)"),
            ));
        }
        let vectors =
            initial_deviations("deviations", self.options.deviations.as_deref(), rows, k)?;
        self.work = vec![0.0; rows * k];
        self.diagonal = vec![0.0; k];
        self.deviations = Deviations::new(vectors);
        (self.t0, self.time) = (t0, 0.0);
        self.value = self.volume();
        if self.value == 0.0 {
            return Err(Error::invalid(
                "deviations",
                "the initial deviation vectors are linearly dependent",
            ));
        }
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.diagonal) {
            return Err(lost("GALI", step));
        }
        self.value = self.volume();
        self.time = step.t - self.t0;
        Ok(match self.options.stop_below {
            Some(threshold) if self.value < threshold => ControlFlow::Break(()),
            _ => ControlFlow::Continue(()),
        })
    }
}
