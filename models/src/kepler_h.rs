//! The Kepler problem written as a Hamiltonian in canonical variables.
//!
//! # Hamiltonian
//!
//! H(q, p) = |p|²/2 − μ/|q| on T*ℝ², with μ = G M = 1 (the units of [`Kepler`]): a
//! [`HamiltonianStructure::QuadraticKinetic`] H with M = 1, so the canonical momentum is the
//! velocity, p = q̇, and [`Canonical`](svi::Canonical)`<KeplerH>` is exactly the Lagrangian
//! ½|q̇|² + 1/|q| of [`Kepler`].
//!
//! # Equations of motion
//!
//! q̇ = p, ṗ = −q/|q|³. Conserved: H, the angular momentum q₁p₂ − q₂p₁ (the Noether
//! momentum of the rotation generator ξ(q) = (−q₂, q₁)) and the Runge–Lenz vector.
//!
//! # Exact solution and defaults
//!
//! Those of [`Kepler`], read with p in place of q̇: the orbit through any bound state by
//! Kepler's equation ([`KeplerOrbit`](crate::KeplerOrbit)); e = 0.5, (q, p) at the pericentre
//! (1 − e, 0), (0, √((1 + e)/(1 − e))), step 0.2, horizon 2000 (Li, Wu, Leok 2018, §5.2).

use nalgebra::{SVector, U2};
use svi::model::hamiltonian::{
    HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants, HamiltonianStructure,
    HamiltonianSymmetries,
};
use svi::{Defaults, Error, ExactSolution, Hamiltonian, Invariants, Scalar, Symmetries};

use crate::{Kepler, params};

/// The planar Kepler problem H = |p|²/2 − 1/|q|: [`Kepler`] in canonical variables, with
/// its parameter (the eccentricity `e` of the default orbit) and companions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KeplerH(pub Kepler);

impl KeplerH {
    /// Registry name of the model.
    pub const NAME: &'static str = "kepler-h";
}

impl Hamiltonian<U2> for KeplerH {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;

    #[inline]
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
        // 1/|q| as |q|·|q|⁻², as in `Kepler::lagrangian` (one division fewer with duals).
        let r2 = q.dot(q);
        p.dot(p) * 0.5 - r2.sqrt() * r2.recip()
    }
}

/// Rotations about the origin: the angular momentum q₁p₂ − q₂p₁ ([`Kepler`]'s generator).
impl HamiltonianSymmetries<U2> for KeplerH {
    #[inline]
    fn generator_count(&self) -> usize {
        self.0.generator_count()
    }
    fn momentum_name(&self, index: usize) -> &'static str {
        self.0.momentum_name(index)
    }
    #[inline]
    fn generator(&self, index: usize, q: &SVector<f64, 2>) -> SVector<f64, 2> {
        self.0.generator(index, q)
    }
}

/// The Runge–Lenz vector's length and components ([`Kepler`]'s invariants at q̇ = p).
impl HamiltonianInvariants<U2> for KeplerH {
    fn invariant_count(&self) -> usize {
        self.0.invariant_count()
    }
    fn invariant_name(&self, index: usize) -> &'static str {
        self.0.invariant_name(index)
    }
    fn invariant(&self, index: usize, t: f64, q: &SVector<f64, 2>, p: &SVector<f64, 2>) -> f64 {
        self.0.invariant(index, t, q, p)
    }
}

impl HamiltonianExactSolution<U2> for KeplerH {
    /// [`Kepler`]'s solution with q̇ = p.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 2>,
        p0: &SVector<f64, 2>,
        t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        self.0.exact_solution(t0, q0, p0, t)
    }
}

impl HamiltonianDefaults<U2> for KeplerH {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn coordinate_names(&self) -> Vec<String> {
        self.0.coordinate_names()
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.0.parameters()
    }
    /// As [`Kepler`]: `e` finite and in [0, 1).
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        if !Kepler::PARAMETERS.contains(&name) {
            return Err(params::unknown(Self::NAME, name, &Kepler::PARAMETERS));
        }
        self.0.set_parameter(name, value)
    }
    /// [`Kepler`]'s pericentre, with p₀ = q̇₀.
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        self.0.initial_state()
    }
    fn default_step(&self) -> f64 {
        self.0.default_step()
    }
    fn default_horizon(&self) -> f64 {
        self.0.default_horizon()
    }
}
