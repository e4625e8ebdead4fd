//! The damped harmonic oscillator.
//!
//! # Lagrangian and force
//!
//! L(q, q̇) = q̇²/2 − σ² q²/2 (the [`crate::HarmonicOscillator`]'s, written identically) with
//! the viscous friction force f_L = −2ζσ q̇ of the Lagrange–d'Alembert principle
//! (natural frequency σ > 0, damping ratio ζ ≥ 0).
//!
//! # Equations of motion
//!
//! q̈ + 2ζσ q̇ + σ² q = 0. The energy E = q̇²/2 + σ² q²/2 decays as dE/dt = −2ζσ q̇².
//!
//! # Exact solution
//!
//! With γ = ζσ, κ = σ²(1 − ζ²) and τ = t − t₀:
//! q(t) = e^{−γτ} [q₀ C(τ) + (q̇₀ + γ q₀) S(τ)], where C = cos(√κ τ), S = sin(√κ τ)/√κ for
//! the under-damped case (ζ < 1), C = 1, S = τ for critical damping (ζ = 1), and
//! C = cosh(√−κ τ), S = sinh(√−κ τ)/√−κ for the over-damped case (ζ > 1), evaluated as
//! sums of decaying exponentials so that long times neither overflow nor cancel.
//!
//! # Defaults
//!
//! σ = 1, ζ = 0.1 (lightly damped: the amplitude falls by e^{−0.1 t}), q₀ = 1, q̇₀ = 0,
//! step h = 0.1, horizon T = 50 (about eight periods, the energy falls by e^{−10}).
//!
//! # References
//!
//! Porcù & Penati, *Spectral variational integrators* (OctConf 2013), "Forced mechanics";
//! J. E. Marsden, M. West, *Discrete mechanics and variational integrators*, Acta Numerica
//! (2001), §3.2 (the discrete Lagrange–d'Alembert principle). The closed form is the
//! textbook solution of a linear second-order ODE with constant coefficients.

use nalgebra::{SVector, U1};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::params;

/// The damped harmonic oscillator: L = q̇²/2 − σ²q²/2, f_L = −2ζσ q̇.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampedOscillator {
    /// Natural (undamped) angular frequency σ (> 0).
    pub sigma: f64,
    /// Damping ratio ζ (≥ 0): under-damped below 1, critically damped at 1, over-damped
    /// above.
    pub zeta: f64,
}

impl DampedOscillator {
    /// Registry name of the model.
    pub const NAME: &'static str = "damped-oscillator";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 2] = ["sigma", "zeta"];

    /// An oscillator with natural frequency `sigma` and damping ratio `zeta`.
    pub fn new(sigma: f64, zeta: f64) -> Result<Self, Error> {
        let mut model = Self::default();
        model.set_parameter("sigma", sigma)?;
        model.set_parameter("zeta", zeta)?;
        Ok(model)
    }

    /// The friction coefficient c = 2ζσ of f_L = −c q̇.
    pub fn friction(&self) -> f64 {
        2.0 * self.zeta * self.sigma
    }

    /// The energy q̇²/2 + σ²q²/2.
    pub fn energy(&self, q: f64, v: f64) -> f64 {
        0.5 * (v * v + self.sigma * self.sigma * q * q)
    }
}

impl Default for DampedOscillator {
    /// σ = 1, ζ = 0.1.
    fn default() -> Self {
        Self {
            sigma: 1.0,
            zeta: 0.1,
        }
    }
}

impl Lagrangian<U1> for DampedOscillator {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    const FORCED: bool = true;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0] * (self.sigma * self.sigma)) * 0.5
    }

    /// f_L = −2ζσ q̇.
    #[inline]
    fn external_force<D: Scalar>(
        &self,
        _t: D,
        _q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        SVector::from([v[0] * (-self.friction())])
    }
}

/// The free response of q̈ + 2ζσ q̇ + σ² q = 0 after time τ from (q₀, q̇₀): (q, q̇).
pub(crate) fn free_response(sigma: f64, zeta: f64, q0: f64, v0: f64, tau: f64) -> (f64, f64) {
    let gamma = zeta * sigma;
    let kappa = sigma * sigma * (1.0 - zeta * zeta);
    let b = v0 + gamma * q0;
    // e^{−γτ} C, e^{−γτ} S and their derivatives e^{−γτ}(−κS), e^{−γτ}C.
    let (decayed_c, decayed_s) = if zeta < 1.0 {
        let omega = kappa.sqrt();
        let decay = (-gamma * tau).exp();
        let (sin, cos) = (omega * tau).sin_cos();
        (decay * cos, decay * sin / omega)
    } else if zeta == 1.0 {
        let decay = (-gamma * tau).exp();
        (decay, decay * tau)
    } else {
        let omega = (-kappa).sqrt();
        if (omega * tau).abs() <= 1.0 {
            // Near critical damping: sinh(ω_o τ)/ω_o without cancellation.
            let decay = (-gamma * tau).exp();
            let x = omega * tau;
            (decay * x.cosh(), decay * x.sinh() / omega)
        } else {
            // Roots −γ ± ω_o, the slow one without cancellation; no overflow for long times.
            let slow = -sigma * sigma / (gamma + omega);
            let fast = -gamma - omega;
            let (e_slow, e_fast) = ((slow * tau).exp(), (fast * tau).exp());
            (0.5 * (e_slow + e_fast), 0.5 * (e_slow - e_fast) / omega)
        }
    };
    let q = q0 * decayed_c + b * decayed_s;
    let v = -gamma * q + (-q0 * kappa * decayed_s + b * decayed_c);
    (q, v)
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U1> for DampedOscillator {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U1> for DampedOscillator {}

impl ExactSolution<U1> for DampedOscillator {
    /// The closed form of the module documentation, for every initial state (also backwards
    /// in time, where it grows).
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        v0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        let (q, v) = free_response(self.sigma, self.zeta, q0[0], v0[0], t - t0);
        (q.is_finite() && v.is_finite()).then(|| (SVector::from([q]), SVector::from([v])))
    }
}

impl Defaults<U1> for DampedOscillator {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["q"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("sigma", self.sigma), ("zeta", self.zeta)]
    }

    /// `sigma` must be finite and positive, `zeta` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "sigma" => self.sigma = params::positive(name, value)?,
            "zeta" => self.zeta = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, q₀ = 1, q̇₀ = 0.
    fn initial_state(&self) -> (f64, SVector<f64, 1>, SVector<f64, 1>) {
        (0.0, SVector::from([1.0]), SVector::from([0.0]))
    }

    /// h = 0.1.
    fn default_step(&self) -> f64 {
        0.1
    }

    /// T = 50.
    fn default_horizon(&self) -> f64 {
        50.0
    }
}
