//! The planar pendulum damped by friction (the example of the slides' "Forced mechanics").
//!
//! # Lagrangian and force
//!
//! L(θ, θ̇) = ½ m l² θ̇² + m g l cos θ (the [`crate::Pendulum`]'s) with the friction torque
//! f_L = −c θ̇, c ≥ 0, of the Lagrange–d'Alembert principle
//! δ∫L dt + ∫ f_L δθ dt = 0.
//!
//! # Equations of motion
//!
//! m l² θ̈ = −m g l sin θ − c θ̇; the energy E = ½ m l² θ̇² − m g l cos θ decays as
//! dE/dt = −c θ̇² towards the rest state θ = 2πj.
//!
//! # Exact solution
//!
//! None in closed form for c > 0; for c = 0 the undamped pendulum's Jacobi elliptic
//! solution ([`crate::Pendulum`]).
//!
//! # Defaults
//!
//! m = l = g = 1, c = 0.1 (the small oscillations decay as e^{−0.05t}), θ₀ = 1, θ̇₀ = 0,
//! step 0.1, horizon 100.
//!
//! # References
//!
//! M. Porcù, T. Penati, *Spectral variational integrators* (OctConf 2013), "Forced
//! mechanics": the simple pendulum damped with friction-type forcing; J. E. Marsden,
//! M. West, *Discrete mechanics and variational integrators*, Acta Numerica (2001), §3.2.

use nalgebra::{SVector, U1};
use svi::{
    Defaults, Error, ExactSolution, Invariants, Lagrangian, Parametric, Scalar, Structure,
    Symmetries,
};

use crate::{Pendulum, params};

/// The damped pendulum: L = ½ m l² θ̇² + m g l cos θ, f_L = −c θ̇.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampedPendulum {
    /// Mass m (> 0).
    pub m: f64,
    /// Rod length l (> 0).
    pub l: f64,
    /// Gravitational acceleration g (≥ 0).
    pub g: f64,
    /// Friction coefficient c (≥ 0) of the torque −c θ̇.
    pub c: f64,
}

impl DampedPendulum {
    /// Registry name of the model.
    pub const NAME: &'static str = "damped-pendulum";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 4] = ["m", "l", "g", "c"];

    /// The undamped pendulum with the same m, l, g.
    pub fn undamped(&self) -> Pendulum {
        Pendulum {
            m: self.m,
            l: self.l,
            g: self.g,
        }
    }
}

impl Default for DampedPendulum {
    /// m = l = g = 1, c = 0.1.
    fn default() -> Self {
        Self {
            m: 1.0,
            l: 1.0,
            g: 1.0,
            c: 0.1,
        }
    }
}

impl Lagrangian<U1> for DampedPendulum {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    const FORCED: bool = true;

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        self.lagrangian_with(&self.theta(), t, q, v)
    }

    /// f_L = −c θ̇.
    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        self.external_force_with(&self.theta(), t, q, v)
    }
}

impl DampedPendulum {
    /// θ = (m, l, g, c) as scalars.
    fn theta<D: Scalar>(&self) -> [D; 4] {
        [self.m, self.l, self.g, self.c].map(D::from)
    }
}

/// θ = (m, l, g, c), the order of [`DampedPendulum::PARAMETERS`].
impl Parametric<U1> for DampedPendulum {
    fn parameter_names(&self) -> Vec<String> {
        Self::PARAMETERS.map(String::from).to_vec()
    }

    fn parameter_values(&self) -> Vec<f64> {
        self.theta().to_vec()
    }

    #[inline]
    fn lagrangian_with<D: Scalar>(
        &self,
        theta: &[D],
        _t: D,
        q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> D {
        let (m, l, g) = (theta[0], theta[1], theta[2]);
        v[0] * v[0] * (m * l * l * 0.5) + q[0].cos() * (m * g * l)
    }

    #[inline]
    fn external_force_with<D: Scalar>(
        &self,
        theta: &[D],
        _t: D,
        _q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        SVector::from([-(v[0] * theta[3])])
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U1> for DampedPendulum {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U1> for DampedPendulum {}

impl ExactSolution<U1> for DampedPendulum {
    /// The undamped pendulum's solution when c = 0; `None` otherwise.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        v0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        if self.c == 0.0 {
            self.undamped().exact_solution(t0, q0, v0, t)
        } else {
            None
        }
    }
}

impl Defaults<U1> for DampedPendulum {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["theta"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("m", self.m), ("l", self.l), ("g", self.g), ("c", self.c)]
    }

    /// `m` and `l` must be finite and positive, `g` and `c` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m" => self.m = params::positive(name, value)?,
            "l" => self.l = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            "c" => self.c = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, θ₀ = 1, θ̇₀ = 0 (the undamped pendulum's default).
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
