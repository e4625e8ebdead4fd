//! The planar double pendulum.
//!
//! # Lagrangian
//!
//! Two point masses m₁, m₂ on massless rods of lengths d₁, d₂; q = (α₁, α₂), the angles of
//! the rods from the downward vertical (Porcù, Penati 2013, last example):
//!
//! T = ((m₁ + m₂)/2) d₁² α̇₁² + (m₂/2) d₂² α̇₂² + m₂ d₁ d₂ α̇₁ α̇₂ cos(α₁ − α₂),
//! U = −(m₁ + m₂) g d₁ cos α₁ − m₂ g d₂ cos α₂,
//! L = T − U.
//!
//! # Equations of motion
//!
//! M(α) α̈ = f(α, α̇) with the mass matrix
//!
//! M = [[(m₁ + m₂) d₁², m₂ d₁ d₂ cos(α₁ − α₂)], [m₂ d₁ d₂ cos(α₁ − α₂), m₂ d₂²]]
//!
//! (positive definite: det M = m₂ d₁² d₂² (m₁ + m₂ sin²(α₁ − α₂)) > 0) and
//!
//! f₁ = −m₂ d₁ d₂ α̇₂² sin(α₁ − α₂) − (m₁ + m₂) g d₁ sin α₁,
//! f₂ = m₂ d₁ d₂ α̇₁² sin(α₁ − α₂) − m₂ g d₂ sin α₂.
//!
//! The energy T + U is the only known invariant; the motion is chaotic at large energies.
//!
//! # Defaults
//!
//! m₁ = m₂ = 1, d₁ = d₂ = 1, g = 9.81; α₀ = (1, 0.5), rates 0 (energetic enough to be
//! irregular, but both rods stay below the horizontal at first); step 0.01, horizon 20.
//!
//! # References
//!
//! M. Porcù, T. Penati, *Spectral variational integrators*, OctConf 2013 (slides), example.

use nalgebra::{SVector, U2};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Symmetries};

use crate::params;

/// The double pendulum of Porcù and Penati (2013), in the rod angles q = (α₁, α₂).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoublePendulum {
    /// Mass of the first bob m₁ (> 0).
    pub m1: f64,
    /// Mass of the second bob m₂ (> 0).
    pub m2: f64,
    /// Length of the first rod d₁ (> 0).
    pub d1: f64,
    /// Length of the second rod d₂ (> 0).
    pub d2: f64,
    /// Gravitational acceleration g (≥ 0).
    pub g: f64,
}

impl DoublePendulum {
    /// Registry name of the model.
    pub const NAME: &'static str = "double-pendulum";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 5] = ["m1", "m2", "d1", "d2", "g"];
}

impl Default for DoublePendulum {
    /// m₁ = m₂ = 1, d₁ = d₂ = 1, g = 9.81.
    fn default() -> Self {
        Self {
            m1: 1.0,
            m2: 1.0,
            d1: 1.0,
            d2: 1.0,
            g: 9.81,
        }
    }
}

impl Lagrangian<U2> for DoublePendulum {
    const TIME_DEPENDENT: bool = false;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let Self { m1, m2, d1, d2, g } = *self;
        let (alpha1, alpha2) = (q[0], q[1]);
        let (rate1, rate2) = (v[0], v[1]);
        let kinetic = rate1 * rate1 * (0.5 * (m1 + m2) * d1 * d1)
            + rate2 * rate2 * (0.5 * m2 * d2 * d2)
            + rate1 * rate2 * (alpha1 - alpha2).cos() * (m2 * d1 * d2);
        let potential = -(alpha1.cos() * ((m1 + m2) * g * d1) + alpha2.cos() * (m2 * g * d2));
        kinetic - potential
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U2> for DoublePendulum {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U2> for DoublePendulum {}

impl ExactSolution<U2> for DoublePendulum {
    /// Always `None`: the double pendulum is not integrable.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &SVector<f64, 2>,
        _v0: &SVector<f64, 2>,
        _t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        None
    }
}

impl Defaults<U2> for DoublePendulum {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["alpha1", "alpha2"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("m1", self.m1),
            ("m2", self.m2),
            ("d1", self.d1),
            ("d2", self.d2),
            ("g", self.g),
        ]
    }

    /// Masses and lengths must be finite and positive, `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m1" => self.m1 = params::positive(name, value)?,
            "m2" => self.m2 = params::positive(name, value)?,
            "d1" => self.d1 = params::positive(name, value)?,
            "d2" => self.d2 = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, α₀ = (1, 0.5), rates 0.
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        (0.0, SVector::from([1.0, 0.5]), SVector::zeros())
    }

    /// h = 0.01.
    fn default_step(&self) -> f64 {
        0.01
    }

    /// T = 20.
    fn default_horizon(&self) -> f64 {
        20.0
    }
}
