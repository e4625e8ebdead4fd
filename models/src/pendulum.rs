//! The planar mathematical pendulum.
//!
//! # Lagrangian
//!
//! A point mass m on a massless rod of length l, θ the angle from the downward vertical:
//!
//! L(θ, θ̇) = ½ m l² θ̇² + m g l cos θ.
//!
//! # Equations of motion
//!
//! θ̈ = −(g/l) sin θ; the energy E = ½ m l² θ̇² − m g l cos θ is conserved.
//!
//! # Exact solution
//!
//! With ω₀ = √(g/l) and k² = sin²(θ₀/2) + θ̇₀²/(4ω₀²) (k² = (E + m g l)/(2 m g l)):
//!
//! - libration (k < 1): sin(θ/2) = k sn(u | k²), θ̇ = 2kω₀ cn(u | k²),
//!   u = ω₀(t − t₀) + u₀, with sn(u₀) = sin(θ₀/2)/k and cn(u₀) of the sign of θ̇₀;
//! - rotation (k > 1): θ/2 = am(w | 1/k²), θ̇ = 2kω₀ dn(w | 1/k²) sign θ̇₀,
//!   w = kω₀(t − t₀) sign θ̇₀ + F(θ₀/2 | 1/k²).
//!
//! The separatrix k = 1 has no closed form here ([`ExactSolution::exact_solution`] returns
//! `None`); g = 0 is free rotation.
//!
//! # Defaults
//!
//! m = l = g = 1 (dimensionless, small-oscillation period 2π), θ₀ = 1, θ̇₀ = 0 (a large
//! amplitude, so the nonlinearity matters), step 0.1, horizon 100.
//!
//! # References
//!
//! M. Porcù, T. Penati, *Spectral variational integrators* (OctConf 2013): the (damped)
//! simple pendulum example. The elliptic-function solution: e.g. D. F. Lawden, *Elliptic
//! Functions and Applications* (1989), §5.2.

use std::f64::consts::TAU;

use nalgebra::{SVector, U1};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::{elliptic, params};

/// The pendulum L = ½ m l² θ̇² + m g l cos θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pendulum {
    /// Mass m (> 0).
    pub m: f64,
    /// Rod length l (> 0).
    pub l: f64,
    /// Gravitational acceleration g (≥ 0).
    pub g: f64,
}

impl Pendulum {
    /// Registry name of the model.
    pub const NAME: &'static str = "pendulum";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 3] = ["m", "l", "g"];

    /// The small-oscillation angular frequency ω₀ = √(g/l).
    pub fn frequency(&self) -> f64 {
        (self.g / self.l).sqrt()
    }
}

impl Default for Pendulum {
    /// m = l = g = 1.
    fn default() -> Self {
        Self {
            m: 1.0,
            l: 1.0,
            g: 1.0,
        }
    }
}

impl Lagrangian<U1> for Pendulum {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        let (m, l, g) = (self.m, self.l, self.g);
        v[0] * v[0] * (0.5 * m * l * l) + q[0].cos() * (m * g * l)
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U1> for Pendulum {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U1> for Pendulum {}

impl ExactSolution<U1> for Pendulum {
    /// The Jacobi elliptic solution (see the module documentation) for libration and
    /// rotation; `None` on the separatrix (k = 1 exactly, including the upright
    /// equilibrium) and for non-finite input.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        v0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        let (theta0, rate0, elapsed) = (q0[0], v0[0], t - t0);
        if !(theta0.is_finite() && rate0.is_finite() && elapsed.is_finite()) {
            return None;
        }
        let state = |theta: f64, rate: f64| Some((SVector::from([theta]), SVector::from([rate])));
        if self.g == 0.0 {
            return state(theta0 + rate0 * elapsed, rate0);
        }
        let omega = self.frequency();
        let half_sin = (0.5 * theta0).sin();
        let scaled_rate = rate0 / (2.0 * omega);
        let modulus_squared = half_sin * half_sin + scaled_rate * scaled_rate;
        if modulus_squared == 0.0 {
            // Resting at the bottom.
            return state(theta0, rate0);
        }
        let modulus = modulus_squared.sqrt();
        if modulus_squared < 1.0 {
            // Libration about θ = 2πj.
            let turns = (theta0 / TAU).round();
            let centred = theta0 - turns * TAU;
            let quarter_period = elliptic::complete_first_kind(modulus_squared);
            let phi0 = ((0.5 * centred).sin() / modulus).clamp(-1.0, 1.0).asin();
            let mut u0 = elliptic::first_kind(phi0, modulus_squared, quarter_period);
            if rate0 < 0.0 {
                // sn(2K − u) = sn(u), cn(2K − u) = −cn(u).
                u0 = 2.0 * quarter_period - u0;
            }
            let u = u0 + omega * elapsed;
            let (sn, cn) = elliptic::amplitude(u, modulus_squared, quarter_period).sin_cos();
            let dn = (1.0 - modulus_squared * sn * sn).sqrt();
            let theta = turns * TAU + 2.0 * (modulus * sn).atan2(dn);
            state(theta, 2.0 * modulus * omega * cn)
        } else if modulus_squared > 1.0 {
            // Rotation: θ/2 = am(w | 1/k²).
            let parameter = modulus_squared.recip();
            let direction = rate0.signum();
            let quarter_period = elliptic::complete_first_kind(parameter);
            let w0 = elliptic::first_kind(0.5 * theta0, parameter, quarter_period);
            let w = w0 + direction * modulus * omega * elapsed;
            let half_theta = elliptic::amplitude(w, parameter, quarter_period);
            let dn = (1.0 - parameter * half_theta.sin().powi(2)).sqrt();
            state(2.0 * half_theta, 2.0 * direction * modulus * omega * dn)
        } else {
            None
        }
    }
}

impl Defaults<U1> for Pendulum {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["theta"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("m", self.m), ("l", self.l), ("g", self.g)]
    }

    /// `m` and `l` must be finite and positive, `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m" => self.m = params::positive(name, value)?,
            "l" => self.l = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, θ₀ = 1, θ̇₀ = 0.
    fn initial_state(&self) -> (f64, SVector<f64, 1>, SVector<f64, 1>) {
        (0.0, SVector::from([1.0]), SVector::from([0.0]))
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
