//! MEGNO, the mean exponential growth factor of nearby orbits.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::compensated_add;
use crate::method::space::State;
use crate::stepping::tangent::{TangentObserver, TangentStep};
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::ops::ControlFlow;

use super::{Deviations, lost, one_deviation, rate};

/// Options of [`Megno`].
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct MegnoOptions {
    /// The initial deviation vector (2N entries, q then y); `None` (the default): a fixed
    /// pseudo-random unit vector.
    pub deviation: Option<Vec<f64>>,
}

impl MegnoOptions {
    /// Start from the deviation vector `deviation`.
    pub fn with_deviation(mut self, deviation: Vec<f64>) -> Self {
        self.deviation = Some(deviation);
        self
    }
}

/// MEGNO, the Mean Exponential Growth factor of Nearby Orbits Y(t), and its time average
/// ⟨Y⟩(t) (Cincotta & Simó 2000), in the discrete form of Cincotta, Giordano & Simó (2003)
/// for maps — here the method's one-step map.
///
/// # Mathematics
///
/// Continuous time: Y(t) = (2/t) ∫₀ᵗ (δ̇/δ) s ds, ⟨Y⟩(t) = (1/t) ∫₀ᵗ Y(s) ds, δ = ‖w‖. For the
/// steps t_k (measured from t₀) with δ_k = ‖w_k‖, w renormalised every step:
///
/// ```text
/// Y_n = (2 / t_n) Σ_{k=1}^{n} t_k ln(δ_k / δ_{k−1}),     ⟨Y⟩_n = (1 / t_n) Σ_{k=1}^{n} h_k Y_k
/// ```
///
/// (with t_k = k h the map form (2/n) Σ k ln(δ_k/δ_{k−1}) and (1/n) Σ Y_k). If δ grows like
/// e^{λt}, Y_n ≈ λ t_n and ⟨Y⟩_n ≈ λ t_n / 2: ⟨Y⟩ grows linearly with slope λ₁/2 on a
/// chaotic orbit. If δ grows linearly (a quasi-periodic orbit on a torus with shear),
/// Y_n, ⟨Y⟩_n → 2; on a stable periodic orbit (no shear) → 0. ⟨Y⟩ separates the two faster
/// than the Lyapunov exponent, whose regular-orbit limit is approached only like ln t / t.
/// The running log growth gives λ₁ as a by-product ([`Megno::lyapunov`]).
///
/// # References
///
/// Cincotta & Simó, A&AS 147 (2000) 205–228; Cincotta, Giordano & Simó, Physica D 182 (2003)
/// 151–178, §2 (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct Megno {
    options: MegnoOptions,
    deviations: Deviations,
    norm: [f64; 1],
    /// Σ t_k ln(δ_k/δ_{k−1}), Σ h_k Y_k and Σ ln(δ_k/δ_{k−1}).
    sums: [f64; 3],
    compensation: [f64; 3],
    value: f64,
    mean: f64,
    t0: f64,
    time: f64,
}

impl Megno {
    /// The observer, after checking the options that do not depend on the model (none).
    ///
    /// # Errors
    /// None today; the deviation vector is checked when the run begins.
    pub fn new(options: MegnoOptions) -> Result<Self, Error> {
        Ok(Megno {
            options,
            deviations: Deviations::default(),
            norm: [0.0],
            sums: [0.0; 3],
            compensation: [0.0; 3],
            value: 0.0,
            mean: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &MegnoOptions {
        &self.options
    }

    /// Y(t) after the last step.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time average ⟨Y⟩(t) after the last step.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The maximal Lyapunov exponent estimate ln(δ(t)/δ(0)) / t of the same deviation vector.
    pub fn lyapunov(&self) -> f64 {
        rate(self.sums[2], self.compensation[2], self.time)
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }
}

impl<N: Dimension> TangentObserver<N> for Megno
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviation` for a vector of the wrong length, zero or
    /// not finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        self.deviations = one_deviation(self.options.deviation.as_ref(), state)?;
        (self.sums, self.compensation) = ([0.0; 3], [0.0; 3]);
        (self.value, self.mean, self.t0, self.time) = (0.0, 0.0, t0, 0.0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.norm) {
            return Err(lost("MEGNO", step));
        }
        let growth = self.norm[0].ln();
        let time = step.t - self.t0;
        compensated_add(
            &mut self.sums[..1],
            &mut self.compensation[..1],
            &[time * growth],
        );
        self.value = 2.0 * (self.sums[0] - self.compensation[0]) / time;
        compensated_add(
            &mut self.sums[1..],
            &mut self.compensation[1..],
            &[step.h * self.value, growth],
        );
        self.mean = (self.sums[1] - self.compensation[1]) / time;
        self.time = time;
        Ok(ControlFlow::Continue(()))
    }
}
