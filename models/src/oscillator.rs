//! The simple harmonic oscillator.
//!
//! # Lagrangian
//!
//! L(q, q̇) = q̇²/2 − σ² q²/2, with frequency σ > 0 (Li, Wu, Leok 2018, §4, eq. 26).
//!
//! # Equations of motion
//!
//! q̈ = −σ² q; in Hamiltonian form q̇ = p, ṗ = −σ² q. The energy E = q̇²/2 + σ² q²/2 is
//! conserved, and the solution through (q₀, q̇₀) at t₀ is
//! q(t) = q₀ cos σ(t − t₀) + (q̇₀/σ) sin σ(t − t₀).
//!
//! # Defaults
//!
//! σ = 1, q₀ = 0, q̇₀ = p₀ = 1, step h = 1, horizon T = 100: the setting of Figs. 7–9 of
//! the paper. The oscillator is also the test equation of the linear stability analysis
//! (eqs. 26–37, z = σ²h²).
//!
//! # References
//!
//! J. Li, B. Wu, M. Leok, *Construction and comparison of multidimensional spectral
//! variational integrators and spectral collocation methods*, Appl. Numer. Math. (2018),
//! eq. (26) and §5.1.

use nalgebra::{SVector, U1};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::params;

/// The harmonic oscillator L = q̇²/2 − σ²q²/2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HarmonicOscillator {
    /// Angular frequency σ (> 0).
    pub sigma: f64,
}

impl HarmonicOscillator {
    /// Registry name of the model.
    pub const NAME: &'static str = "oscillator";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 1] = ["sigma"];

    /// An oscillator with frequency `sigma`.
    pub fn new(sigma: f64) -> Result<Self, Error> {
        let mut model = Self::default();
        model.set_parameter("sigma", sigma)?;
        Ok(model)
    }
}

impl Default for HarmonicOscillator {
    /// σ = 1 (Li, Wu, Leok 2018, Figs. 7–12).
    fn default() -> Self {
        Self { sigma: 1.0 }
    }
}

impl Lagrangian<U1> for HarmonicOscillator {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0] * (self.sigma * self.sigma)) * 0.5
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U1> for HarmonicOscillator {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U1> for HarmonicOscillator {}

impl ExactSolution<U1> for HarmonicOscillator {
    /// q(t) = q₀ cos στ + (q̇₀/σ) sin στ, q̇(t) = −σ q₀ sin στ + q̇₀ cos στ, τ = t − t₀;
    /// available for every initial state.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        v0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        let sigma = self.sigma;
        let (sin, cos) = (sigma * (t - t0)).sin_cos();
        let q = q0[0] * cos + v0[0] / sigma * sin;
        let v = -sigma * q0[0] * sin + v0[0] * cos;
        Some((SVector::from([q]), SVector::from([v])))
    }
}

impl Defaults<U1> for HarmonicOscillator {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["q"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("sigma", self.sigma)]
    }

    /// `sigma` must be finite and positive.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "sigma" => self.sigma = params::positive(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, q₀ = 0, q̇₀ = 1 (p₀ = 1, as in §5.1 of the paper).
    fn initial_state(&self) -> (f64, SVector<f64, 1>, SVector<f64, 1>) {
        (0.0, SVector::from([0.0]), SVector::from([1.0]))
    }

    /// h = 1 (Figs. 7–9).
    fn default_step(&self) -> f64 {
        1.0
    }

    /// T = 100 (Figs. 7–9).
    fn default_horizon(&self) -> f64 {
        100.0
    }
}
