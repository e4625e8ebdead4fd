//! A chain of relativistic particles joined by linear springs, both ends fixed:
//!
//! L = Σᵢ −m c² √(1 − q̇ᵢ²/c²) − Σⱼ ½ k (q_{j+1} − q_j)²,  q₀ = q_{n+1} = 0.
//!
//! The kinetic energy is not quadratic in q̇ (the mass matrix ∂²L/∂q̇ᵢ² = m γᵢ³ changes with
//! the velocity, γ = 1/√(1 − q̇²/c²)), so SVI needs Newton's method with the Hessian of L,
//! assembled sparsely term by term ([`svi::model::local`]). The energy
//! E = Σ m c² γᵢ + Σ ½ k (q_{j+1} − q_j)² is conserved, and the inverse Legendre map has the
//! closed form q̇ = p/√(m² + p²/c²) (used in tests). A sum of local terms of width 2: term e
//! is spring e between particles e − 1 and e, carrying particle e's kinetic energy.
//!
//! [`RelativisticChainH`] is the same chain written as a Hamiltonian of the same local terms,
//!
//! H = Σᵢ c √(m²c² + pᵢ²) + Σⱼ ½ k (q_{j+1} − q_j)²,
//!
//! separable, so `verlet-h` and its compositions step it explicitly (drift
//! qᵢ ← qᵢ + h c pᵢ/√(m²c² + pᵢ²)), where the Lagrangian's kinetic energy makes every
//! Lagrangian method implicit.

use crate::chain::{spring_ends, spring_indices};
use crate::params::{positive, size, unknown};
use nalgebra::{Const, DVector, SVector};
use svi::Error;
use svi::HamiltonianStructure;
use svi::Scalar;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};
use svi::model::local_hamiltonian::LocalHamiltonian;

/// The relativistic spring chain (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RelativisticChain {
    /// Number of moving particles n.
    pub n: usize,
    /// Rest mass m.
    pub m: f64,
    /// Speed of light c.
    pub c: f64,
    /// Spring constant k.
    pub k: f64,
    /// Peak initial speed, a fraction of c (the profile q̇ᵢ = V sin(πi/(n+1)) from rest
    /// positions).
    pub speed: f64,
}

impl Default for RelativisticChain {
    fn default() -> Self {
        RelativisticChain {
            n: 32,
            m: 1.0,
            c: 1.0,
            k: 1.0,
            speed: 0.8,
        }
    }
}

impl RelativisticChain {
    /// The inverse Legendre map in closed form, q̇ = p/√(m² + p²/c²).
    pub fn velocity(&self, p: f64) -> f64 {
        p / (self.m * self.m + p * p / (self.c * self.c)).sqrt()
    }
}

impl LocalLagrangian for RelativisticChain {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;

    fn dimension(&self) -> usize {
        self.n
    }

    fn term_count(&self) -> usize {
        self.n + 1
    }

    #[inline]
    fn indices(&self, e: usize) -> [usize; 2] {
        spring_indices(e, self.n)
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let zero = D::from(0.0);
        let (left, right) = spring_ends(e, self.n, q, (0.0, 0.0));
        let c2 = self.c * self.c;
        let kinetic = if e < self.n {
            ((D::from(1.0) - v[1] * v[1] * (1.0 / c2)).sqrt()) * (-self.m * c2)
        } else {
            zero
        };
        let stretch = right - left;
        kinetic - stretch * stretch * (0.5 * self.k)
    }
}

impl LocalInvariants for RelativisticChain {}

impl LocalDefaults for RelativisticChain {
    fn name(&self) -> &'static str {
        "relativistic-chain"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("n", self.n as f64),
            ("m", self.m),
            ("c", self.c),
            ("k", self.k),
            ("speed", self.speed),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "n" => self.n = size(name, value, 1)?,
            "m" => self.m = positive(name, value)?,
            "c" => self.c = positive(name, value)?,
            "k" => self.k = positive(name, value)?,
            "speed" => {
                let speed = positive(name, value)?;
                if speed >= 1.0 {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} must be below 1 (a fraction of c)"),
                    ));
                }
                self.speed = speed;
            }
            _ => {
                return Err(unknown(
                    "relativistic-chain",
                    name,
                    &["n", "m", "c", "k", "speed"],
                ));
            }
        }
        Ok(())
    }

    /// Rest positions, velocities q̇ᵢ = V c sin(πi/(n+1)).
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let n = self.n;
        let v = DVector::from_fn(n, |i, _| {
            self.speed * self.c * (std::f64::consts::PI * (i + 1) as f64 / (n + 1) as f64).sin()
        });
        (0.0, DVector::zeros(n), v)
    }

    fn default_step(&self) -> f64 {
        0.1
    }

    fn default_horizon(&self) -> f64 {
        100.0
    }
}

/// The relativistic chain written as a Hamiltonian of local terms (see the module docs), run
/// through [`svi::model::local_hamiltonian::LocalCanonical`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RelativisticChainH(pub RelativisticChain);

impl RelativisticChainH {
    /// The default state of [`RelativisticChain`] in (q, p): rest positions and
    /// pᵢ = m γᵢ q̇ᵢ.
    pub fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let chain = &self.0;
        let (t0, q, v) = chain.initial_state();
        let p = v.map(|v| chain.m * v / (1.0 - v * v / (chain.c * chain.c)).sqrt());
        (t0, q, p)
    }
}

impl LocalHamiltonian for RelativisticChainH {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;

    fn dimension(&self) -> usize {
        self.0.n
    }

    fn term_count(&self) -> usize {
        self.0.n + 1
    }

    #[inline]
    fn indices(&self, e: usize) -> [usize; 2] {
        spring_indices(e, self.0.n)
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
        let RelativisticChain { n, m, c, k, .. } = self.0;
        let (left, right) = spring_ends(e, n, q, (0.0, 0.0));
        let kinetic = if e < n {
            (p[1] * p[1] + m * m * c * c).sqrt() * c
        } else {
            D::from(0.0)
        };
        let stretch = right - left;
        kinetic + stretch * stretch * (0.5 * k)
    }
}
