//! The planar pendulum with a stiff spring (an elastic pendulum with two time scales).
//!
//! # Lagrangian
//!
//! A point mass m hangs from a spring of rest length l and stiffness k; q = (a, θ), with a
//! the spring extension and θ the angle from the downward vertical. With the bob at
//! x = (l + a) sin θ, y = −(l + a) cos θ (Leok 2004, §5.7.2):
//!
//! L = (m/2)(ẋ² + ẏ²) − m g y − (k/2) a²
//!   = (m/2)(ȧ² + (l + a)² θ̇²) + m g (l + a) cos θ − (k/2) a².
//!
//! # Equations of motion
//!
//! With p_a = m ȧ and p_θ = m (l + a)² θ̇ (Hamilton's equations of §5.7.2):
//!
//! ȧ = p_a/m,  θ̇ = p_θ/(m (l + a)²),
//! ṗ_a = −k a + m g cos θ + m (l + a) θ̇²,  ṗ_θ = −m g (l + a) sin θ,
//!
//! that is ä = (l + a) θ̇² + g cos θ − (k/m) a and θ̈ = −(g sin θ + 2 ȧ θ̇)/(l + a). The
//! coordinates are singular at a = −l (the bob at the pivot).
//!
//! The spring oscillates with period 2π√(m/k), the pendulum with period ≈ 2π√(l/g); the
//! ratio of time scales is ε = √(m g/(k l)) ([`SpringPendulum::scale_ratio`]).
//!
//! # Defaults
//!
//! m = 1, g = 9.81, k = 10 000, l = 1 (ε ≈ 0.0313, the values of §5.7.2); a₀ = 0 (the
//! static stretch m g/k ≈ 10⁻³ then drives a small fast oscillation), θ₀ = 0.5, rates 0;
//! step 10⁻³ (about 63 steps per spring period), horizon 10.
//!
//! # References
//!
//! M. Leok, *Generalized Variational Integrators*, ch. 5 of *Foundations of Computational
//! Geometric Mechanics*, PhD thesis, Caltech (2004), §5.7.2.

use nalgebra::{SVector, U2};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Symmetries};

use crate::params;

/// The spring pendulum of Leok (2004), §5.7.2, in coordinates q = (a, θ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringPendulum {
    /// Mass m (> 0).
    pub m: f64,
    /// Gravitational acceleration g (≥ 0).
    pub g: f64,
    /// Spring stiffness k (> 0).
    pub k: f64,
    /// Rest length of the spring l (> 0).
    pub l: f64,
}

impl SpringPendulum {
    /// Registry name of the model.
    pub const NAME: &'static str = "spring-pendulum";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 4] = ["m", "g", "k", "l"];

    /// The ratio of time scales ε = √(m g/(k l)): the spring period 2π√(m/k) over the
    /// pendulum period 2π√(l/g).
    pub fn scale_ratio(&self) -> f64 {
        (self.m * self.g / (self.k * self.l)).sqrt()
    }

    /// Angular frequency of the spring, √(k/m).
    pub fn spring_frequency(&self) -> f64 {
        (self.k / self.m).sqrt()
    }

    /// Extension of the spring at rest hanging straight down, m g/k.
    pub fn static_extension(&self) -> f64 {
        self.m * self.g / self.k
    }
}

impl Default for SpringPendulum {
    /// m = 1, g = 9.81, k = 10 000, l = 1 (Leok 2004, §5.7.2).
    fn default() -> Self {
        Self {
            m: 1.0,
            g: 9.81,
            k: 10_000.0,
            l: 1.0,
        }
    }
}

impl Lagrangian<U2> for SpringPendulum {
    const TIME_DEPENDENT: bool = false;

    /// Written as in §5.7.2, through the Cartesian position and velocity of the bob.
    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let (a, theta) = (q[0], q[1]);
        let (a_dot, theta_dot) = (v[0], v[1]);
        let length = a + self.l;
        let (sin, cos) = theta.sin_cos();
        let x_dot = a_dot * sin + theta_dot * length * cos;
        let y_dot = -a_dot * cos + theta_dot * length * sin;
        let y = -length * cos;
        (x_dot * x_dot + y_dot * y_dot) * (0.5 * self.m)
            - y * (self.m * self.g)
            - a * a * (0.5 * self.k)
    }
}

/// No continuous symmetry: no conserved Noether momentum.
impl Symmetries<U2> for SpringPendulum {}

/// No known invariants besides (possibly) the energy.
impl Invariants<U2> for SpringPendulum {}

impl ExactSolution<U2> for SpringPendulum {
    /// Always `None`: the spring pendulum is not integrable.
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

impl Defaults<U2> for SpringPendulum {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["a", "theta"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("m", self.m), ("g", self.g), ("k", self.k), ("l", self.l)]
    }

    /// `m`, `k` and `l` must be finite and positive, `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m" => self.m = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            "k" => self.k = params::positive(name, value)?,
            "l" => self.l = params::positive(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0, (a₀, θ₀) = (0, 0.5), rates 0.
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        (0.0, SVector::from([0.0, 0.5]), SVector::zeros())
    }

    /// h = 10⁻³.
    fn default_step(&self) -> f64 {
        1e-3
    }

    /// T = 10.
    fn default_horizon(&self) -> f64 {
        10.0
    }
}
