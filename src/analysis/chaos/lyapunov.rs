//! The Lyapunov spectrum by QR re-orthonormalisation and the maximal exponent alone.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::compensated_add;
use crate::method::space::State;
use crate::stepping::tangent::{TangentObserver, TangentStep};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator};
use std::ops::ControlFlow;

use super::{
    Deviations, lost, one_deviation, orthonormalize, phase_dimension, rate, require_interval,
};

/// Options of [`LyapunovSpectrum`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SpectrumOptions {
    /// How many exponents, the largest first: 1 ..= 2N (`None`, the default: all 2N).
    pub count: Option<usize>,
    /// Re-orthonormalise the deviation vectors every `every` steps (and after the last
    /// step); at least 1 (the default). Between re-orthonormalisations the vectors grow like
    /// e^{λ₁ t} and align with the most expanding direction: keep e^{(λ₁ − λ_k) every·h}
    /// well below 1/ε ≈ 10¹⁶.
    pub every: usize,
}

impl Default for SpectrumOptions {
    fn default() -> Self {
        SpectrumOptions {
            count: None,
            every: 1,
        }
    }
}

impl SpectrumOptions {
    /// Compute the `count` largest exponents.
    pub fn with_count(mut self, count: usize) -> Self {
        self.count = Some(count);
        self
    }

    /// Re-orthonormalise every `every` steps.
    pub fn with_every(mut self, every: usize) -> Self {
        self.every = every;
        self
    }
}

/// The Lyapunov spectrum λ₁ ≥ λ₂ ≥ … ≥ λ_{2N} of the numerical flow, by the standard method
/// of Benettin et al. (1980): QR re-orthonormalisation of a propagated basis.
///
/// # Mathematics
///
/// Start from the orthonormal basis W₀ = I (its first `count` columns). Propagate by the
/// tangent maps, W ← Φ_k W, and every `every` steps (and after the last) factor
/// W = Q R (modified Gram–Schmidt, applied twice), keep Q as the new basis and accumulate
/// ln r_jj. At a re-orthonormalisation at time t,
///
/// ```text
/// λ_j(t) = (1 / (t − t₀)) Σ ln r_jj        (j = 1, …, count)
/// ```
///
/// which converges to the j-th Lyapunov exponent (Oseledec). The logs are summed with
/// compensation, so that Σ_j λ_j(t) = ln |det(Φ_{k−1} ⋯ Φ_0)| / (t − t₀) holds to round-off:
/// zero for a symplectic method. The exponents come in the basis' order, which is the order
/// of decreasing exponents once the flow has sorted the directions; for t → ∞ a Hamiltonian
/// flow's exponents pair as λ_j + λ_{2N+1−j} = 0, finite-time values up to O(1/t).
///
/// # References
///
/// Benettin, Galgani, Giorgilli, Strelcyn, Meccanica 15 (1980) 9–30; Skokos, Lect. Notes
/// Phys. 790 (2010) 63–135, §4.3 (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct LyapunovSpectrum {
    options: SpectrumOptions,
    deviations: Deviations,
    /// Σ ln r_jj and its compensation.
    logs: Vec<f64>,
    compensation: Vec<f64>,
    /// The last step's ln r_jj (and R's diagonal before the log).
    step_logs: Vec<f64>,
    exponents: Vec<f64>,
    t0: f64,
    time: f64,
    since: usize,
    orthonormalizations: usize,
}

impl LyapunovSpectrum {
    /// The observer, after checking the options that do not depend on the model (the
    /// count is checked against 2N when the run begins).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `every` for a zero interval, `count` for zero.
    pub fn new(options: SpectrumOptions) -> Result<Self, Error> {
        require_interval(options.every)?;
        if options.count == Some(0) {
            return Err(Error::invalid("count", "at least one exponent"));
        }
        Ok(LyapunovSpectrum {
            options,
            deviations: Deviations::default(),
            logs: Vec::new(),
            compensation: Vec::new(),
            step_logs: Vec::new(),
            exponents: Vec::new(),
            t0: 0.0,
            time: 0.0,
            since: 0,
            orthonormalizations: 0,
        })
    }

    /// The options.
    pub fn options(&self) -> &SpectrumOptions {
        &self.options
    }

    /// The running exponents λ_j(t) at the last re-orthonormalisation (empty before the
    /// run; zeros before the first re-orthonormalisation).
    pub fn exponents(&self) -> &[f64] {
        &self.exponents
    }

    /// Σ_j λ_j(t): ln |det| of the propagated flow over t − t₀ when all 2N exponents are
    /// computed.
    pub fn sum(&self) -> f64 {
        let total: f64 = self
            .logs
            .iter()
            .zip(&self.compensation)
            .map(|(s, c)| s - c)
            .sum();
        if self.time > 0.0 {
            total / self.time
        } else {
            0.0
        }
    }

    /// The time t − t₀ of the last re-orthonormalisation.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The number of re-orthonormalisations so far.
    pub fn orthonormalizations(&self) -> usize {
        self.orthonormalizations
    }
}

impl<N: Dimension> TangentObserver<N> for LyapunovSpectrum
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `count` beyond 2N.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let rows = phase_dimension(state);
        let count = self.options.count.unwrap_or(rows);
        if !(1..=rows).contains(&count) {
            return Err(Error::invalid(
                "count",
                format!("{count} exponents of a phase space of {rows} dimensions (1 ..= 2N)"),
            ));
        }
        self.deviations = Deviations::new(DMatrix::identity(rows, count));
        for buffer in [
            &mut self.logs,
            &mut self.compensation,
            &mut self.step_logs,
            &mut self.exponents,
        ] {
            buffer.clear();
            buffer.resize(count, 0.0);
        }
        (self.t0, self.time, self.since, self.orthonormalizations) = (t0, 0.0, 0, 0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        self.since += 1;
        if self.since < self.options.every && !step.last {
            return Ok(ControlFlow::Continue(()));
        }
        self.since = 0;
        let rows = self.deviations.vectors.nrows();
        if !orthonormalize(
            self.deviations.vectors.as_mut_slice(),
            rows,
            &mut self.step_logs,
        ) {
            return Err(lost("Lyapunov spectrum", step));
        }
        self.step_logs.iter_mut().for_each(|r| *r = r.ln());
        compensated_add(&mut self.logs, &mut self.compensation, &self.step_logs);
        self.time = step.t - self.t0;
        self.orthonormalizations += 1;
        for ((exponent, sum), compensation) in self
            .exponents
            .iter_mut()
            .zip(&self.logs)
            .zip(&self.compensation)
        {
            *exponent = (sum - compensation) / self.time;
        }
        Ok(ControlFlow::Continue(()))
    }
}

/// Options of [`MaximalLyapunov`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MaximalOptions {
    /// Renormalise the deviation vector every `every` steps (and after the last); at least 1
    /// (the default). Keep e^{λ₁ every·h} far from overflow.
    pub every: usize,
    /// The initial deviation vector (2N entries, q then y, scaled to unit length); `None`
    /// (the default): a fixed pseudo-random unit vector.
    pub deviation: Option<Vec<f64>>,
}

impl Default for MaximalOptions {
    fn default() -> Self {
        MaximalOptions {
            every: 1,
            deviation: None,
        }
    }
}

impl MaximalOptions {
    /// Renormalise every `every` steps.
    pub fn with_every(mut self, every: usize) -> Self {
        self.every = every;
        self
    }

    /// Start from the deviation vector `deviation`.
    pub fn with_deviation(mut self, deviation: Vec<f64>) -> Self {
        self.deviation = Some(deviation);
        self
    }
}

/// The maximal Lyapunov exponent alone: one deviation vector, renormalised every `every`
/// steps (Benettin et al. 1980; Skokos 2010, §4.2).
///
/// # Mathematics
///
/// w ← Φ_k w; at a renormalisation, accumulate ln ‖w‖ and set w ← w/‖w‖. At a
/// renormalisation at time t,
///
/// ```text
/// λ(t) = (1 / (t − t₀)) Σ ln ‖w‖  →  λ₁
/// ```
///
/// for almost every initial w. For a regular orbit λ(t) → 0 like ln t / t (the deviation
/// grows linearly); for a chaotic one it levels off at λ₁ > 0. One matrix–vector product per
/// step instead of [`LyapunovSpectrum`]'s 2N.
#[derive(Debug, Clone)]
pub struct MaximalLyapunov {
    options: MaximalOptions,
    deviations: Deviations,
    log: [f64; 1],
    compensation: [f64; 1],
    norm: [f64; 1],
    t0: f64,
    time: f64,
    since: usize,
}

impl MaximalLyapunov {
    /// The observer, after checking the options that do not depend on the model.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `every` for a zero interval.
    pub fn new(options: MaximalOptions) -> Result<Self, Error> {
        require_interval(options.every)?;
        Ok(MaximalLyapunov {
            options,
            deviations: Deviations::default(),
            log: [0.0],
            compensation: [0.0],
            norm: [0.0],
            t0: 0.0,
            time: 0.0,
            since: 0,
        })
    }

    /// The options.
    pub fn options(&self) -> &MaximalOptions {
        &self.options
    }

    /// The running exponent λ(t) at the last renormalisation (0 before the first).
    pub fn exponent(&self) -> f64 {
        rate(self.log[0], self.compensation[0], self.time)
    }

    /// The time t − t₀ of the last renormalisation.
    pub fn time(&self) -> f64 {
        self.time
    }
}

impl<N: Dimension> TangentObserver<N> for MaximalLyapunov
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviation` for a vector of the wrong length, zero or
    /// not finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        self.deviations = one_deviation(self.options.deviation.as_ref(), state)?;
        (self.log, self.compensation) = ([0.0], [0.0]);
        (self.t0, self.time, self.since) = (t0, 0.0, 0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        self.since += 1;
        if self.since < self.options.every && !step.last {
            return Ok(ControlFlow::Continue(()));
        }
        self.since = 0;
        if !self.deviations.normalize(&mut self.norm) {
            return Err(lost("maximal Lyapunov exponent", step));
        }
        compensated_add(&mut self.log, &mut self.compensation, &[self.norm[0].ln()]);
        self.time = step.t - self.t0;
        Ok(ControlFlow::Continue(()))
    }
}
