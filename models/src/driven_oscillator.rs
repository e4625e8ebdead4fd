//! The driven, damped harmonic oscillator.
//!
//! # Lagrangian and force
//!
//! L(q, q̇) = q̇²/2 − σ² q²/2 with the force f_L(t, q̇) = −2ζσ q̇ + F cos(Ωt): viscous
//! friction and a harmonic drive of amplitude F ≥ 0 and angular frequency Ω > 0. The force
//! depends on t although L does not ([`Lagrangian::TIME_DEPENDENT`] is `false`).
//!
//! # Equations of motion
//!
//! q̈ + 2ζσ q̇ + σ² q = F cos(Ωt). For ζ > 0 every solution approaches the steady state
//! q_p(t) = A cos Ωt + B sin Ωt, A = F(σ² − Ω²)/Δ, B = 2ζσΩF/Δ,
//! Δ = (σ² − Ω²)² + (2ζσΩ)² (amplitude F/√Δ, largest near resonance Ω ≈ σ).
//!
//! # Exact solution
//!
//! q(t) = q_p(t) + the free response ([`crate::DampedOscillator`]) from
//! (q₀ − q_p(t₀), q̇₀ − q̇_p(t₀)); at exact resonance without damping (ζ = 0, Ω = σ) the
//! particular solution is q_p(t) = F t sin(σt)/(2σ).
//!
//! # Defaults
//!
//! σ = 1, ζ = 0.1, F = 0.5, Ω = 0.9 (close to resonance: steady amplitude F/√Δ ≈ 1.9), starting
//! at rest, q₀ = q̇₀ = 0, step 0.1, horizon 100 (the transient decays as e^{−0.1t}).
//!
//! # References
//!
//! Porcù & Penati, *Spectral variational integrators* (OctConf 2013), "Forced mechanics"
//! (Lagrange–d'Alembert principle); J. E. Marsden, M. West, *Discrete mechanics and
//! variational integrators*, Acta Numerica (2001), §3.2. The steady state: the textbook
//! solution of the forced linear oscillator.

use nalgebra::{SVector, U1};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::damped_oscillator::free_response;
use crate::params;

/// The driven damped oscillator: L = q̇²/2 − σ²q²/2, f_L = −2ζσ q̇ + F cos Ωt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrivenOscillator {
    /// Natural angular frequency σ (> 0).
    pub sigma: f64,
    /// Damping ratio ζ (≥ 0).
    pub zeta: f64,
    /// Drive amplitude F (≥ 0).
    pub amplitude: f64,
    /// Drive angular frequency Ω (> 0).
    pub drive: f64,
}

impl DrivenOscillator {
    /// Registry name of the model.
    pub const NAME: &'static str = "driven-oscillator";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 4] = ["sigma", "zeta", "amplitude", "drive"];

    /// The particular solution (q_p(t), q̇_p(t)).
    pub fn steady_state(&self, t: f64) -> (f64, f64) {
        let (sigma, omega, force) = (self.sigma, self.drive, self.amplitude);
        let detuning = sigma * sigma - omega * omega;
        let damping = 2.0 * self.zeta * sigma * omega;
        let denominator = detuning * detuning + damping * damping;
        if denominator == 0.0 {
            // Undamped resonance: q_p = F t sin(σt)/(2σ).
            let (sin, cos) = (sigma * t).sin_cos();
            let scale = force / (2.0 * sigma);
            return (scale * t * sin, scale * (sin + sigma * t * cos));
        }
        let a = force * detuning / denominator;
        let b = force * damping / denominator;
        let (sin, cos) = (omega * t).sin_cos();
        (a * cos + b * sin, omega * (b * cos - a * sin))
    }
}

impl Default for DrivenOscillator {
    /// σ = 1, ζ = 0.1, F = 0.5, Ω = 0.9.
    fn default() -> Self {
        Self {
            sigma: 1.0,
            zeta: 0.1,
            amplitude: 0.5,
            drive: 0.9,
        }
    }
}

impl Lagrangian<U1> for DrivenOscillator {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    const FORCED: bool = true;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0] * (self.sigma * self.sigma)) * 0.5
    }

    /// f_L = −2ζσ q̇ + F cos(Ωt).
    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        _q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        let friction = v[0] * (-2.0 * self.zeta * self.sigma);
        SVector::from([friction + (t * self.drive).cos() * self.amplitude])
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U1> for DrivenOscillator {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U1> for DrivenOscillator {}

impl ExactSolution<U1> for DrivenOscillator {
    /// Steady state plus free response (module documentation), for every initial state.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        v0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        let (qp0, vp0) = self.steady_state(t0);
        let (qh, vh) = free_response(self.sigma, self.zeta, q0[0] - qp0, v0[0] - vp0, t - t0);
        let (qp, vp) = self.steady_state(t);
        let (q, v) = (qp + qh, vp + vh);
        (q.is_finite() && v.is_finite()).then(|| (SVector::from([q]), SVector::from([v])))
    }
}

impl Defaults<U1> for DrivenOscillator {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["q"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("sigma", self.sigma),
            ("zeta", self.zeta),
            ("amplitude", self.amplitude),
            ("drive", self.drive),
        ]
    }

    /// `sigma` and `drive` must be finite and positive, `zeta` and `amplitude` finite and
    /// non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "sigma" => self.sigma = params::positive(name, value)?,
            "zeta" => self.zeta = params::non_negative(name, value)?,
            "amplitude" => self.amplitude = params::non_negative(name, value)?,
            "drive" => self.drive = params::positive(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, q₀ = 0, q̇₀ = 0 (at rest).
    fn initial_state(&self) -> (f64, SVector<f64, 1>, SVector<f64, 1>) {
        (0.0, SVector::from([0.0]), SVector::from([0.0]))
    }

    /// h = 0.1.
    fn default_step(&self) -> f64 {
        0.1
    }

    /// T = 100.
    fn default_horizon(&self) -> f64 {
        100.0
    }
}
