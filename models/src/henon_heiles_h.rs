//! The Hénon–Heiles system written as a Hamiltonian.
//!
//! # Hamiltonian
//!
//! H(x, y, p_x, p_y) = ½(p_x² + p_y²) + ½(x² + y²) + λ(x² y − y³/3), λ > 0 (λ = 1 is the
//! system of Hénon & Heiles 1964): a [`HamiltonianStructure::QuadraticKinetic`] H with
//! M = 1, so p = q̇ and [`Canonical`](svi::Canonical)`<HenonHeilesH>` is exactly the
//! Lagrangian of [`HenonHeiles`].
//!
//! # Equations of motion
//!
//! ẋ = p_x, ẏ = p_y, ṗ_x = −x − 2λ x y, ṗ_y = −y − λ(x² − y²); H is the only integral (the
//! orbit of the defaults lies in the chaotic sea of E = 1/8, see [`HenonHeiles`]).
//!
//! # Defaults
//!
//! Those of [`HenonHeiles`] with p = q̇: λ = 1, the point (0, y₀, p_x, p_y) of the surface of
//! section x = 0 set by the parameters `energy` = 1/8, `y0` = −0.2, `vy0` = p_y = 0, p_x > 0
//! from the energy; step 0.1, horizon 1000.
//!
//! # References
//!
//! M. Hénon, C. Heiles, *The applicability of the third integral of motion: some numerical
//! experiments*, Astron. J. 69 (1964) 73–79.

use nalgebra::{SVector, U2};
use svi::model::hamiltonian::{
    HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants, HamiltonianStructure,
    HamiltonianSymmetries,
};
use svi::{Defaults, Error, Hamiltonian, Scalar};

use crate::{HenonHeiles, params};

/// The Hénon–Heiles Hamiltonian H = ½|p|² + ½|q|² + λ(x²y − y³/3): [`HenonHeiles`] in
/// canonical variables, with its parameters and defaults.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HenonHeilesH(pub HenonHeiles);

impl HenonHeilesH {
    /// Registry name of the model.
    pub const NAME: &'static str = "henon-heiles-h";
}

impl Hamiltonian<U2> for HenonHeilesH {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;

    #[inline]
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
        let (x, y) = (q[0], q[1]);
        let kinetic = (p[0] * p[0] + p[1] * p[1]) * 0.5;
        let potential = (x * x + y * y) * 0.5 + (x * x * y - y * y * y / 3.0) * self.0.lambda;
        kinetic + potential
    }
}

/// No continuous symmetry (the potential's symmetry group is finite).
impl HamiltonianSymmetries<U2> for HenonHeilesH {}

/// No integral besides H.
impl HamiltonianInvariants<U2> for HenonHeilesH {}

impl HamiltonianExactSolution<U2> for HenonHeilesH {
    /// Always `None`: the system is not integrable.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &SVector<f64, 2>,
        _p0: &SVector<f64, 2>,
        _t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        None
    }
}

impl HamiltonianDefaults<U2> for HenonHeilesH {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn coordinate_names(&self) -> Vec<String> {
        self.0.coordinate_names()
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.0.parameters()
    }
    /// As [`HenonHeiles`]: `lambda` finite and positive, the default point on its energy
    /// surface.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        if !HenonHeiles::PARAMETERS.contains(&name) {
            return Err(params::unknown(Self::NAME, name, &HenonHeiles::PARAMETERS));
        }
        self.0.set_parameter(name, value)
    }
    /// [`HenonHeiles`]'s point (0, y₀) with p₀ = q̇₀.
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
