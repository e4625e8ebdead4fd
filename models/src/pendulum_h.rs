//! The planar pendulum written as a Hamiltonian.
//!
//! # Hamiltonian
//!
//! θ the angle from the downward vertical, p = m l² θ̇ its canonical momentum:
//!
//! H(θ, p) = p²/(2 m l²) − m g l cos θ,
//!
//! a [`HamiltonianStructure::QuadraticKinetic`] H with M = m l², so
//! [`Canonical`](svi::Canonical)`<PendulumH>` is exactly the Lagrangian
//! ½ m l² θ̇² + m g l cos θ of [`Pendulum`].
//!
//! # Equations of motion
//!
//! θ̇ = p/(m l²), ṗ = −m g l sin θ; H is conserved.
//!
//! # Exact solution and defaults
//!
//! Those of [`Pendulum`] with θ̇ = p/(m l²): the Jacobi elliptic solution for libration and
//! rotation; m = l = g = 1, θ₀ = 1, p₀ = 0, step 0.1, horizon 100.

use nalgebra::{SVector, U1};
use svi::model::hamiltonian::{
    HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants, HamiltonianStructure,
    HamiltonianSymmetries,
};
use svi::{Defaults, Error, ExactSolution, Hamiltonian, Scalar};

use crate::{Pendulum, params};

/// The pendulum H = p²/(2 m l²) − m g l cos θ: [`Pendulum`] in canonical variables, with its
/// parameters (m, l, g) and defaults.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PendulumH(pub Pendulum);

impl PendulumH {
    /// Registry name of the model.
    pub const NAME: &'static str = "pendulum-h";

    /// The moment of inertia m l² (p = m l² θ̇).
    pub fn inertia(&self) -> f64 {
        self.0.m * self.0.l * self.0.l
    }
}

impl Hamiltonian<U1> for PendulumH {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;

    #[inline]
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
        let Pendulum { m, l, g } = self.0;
        p[0] * p[0] * (0.5 / self.inertia()) - q[0].cos() * (m * g * l)
    }
}

/// No continuous symmetry.
impl HamiltonianSymmetries<U1> for PendulumH {}

/// No invariant besides H.
impl HamiltonianInvariants<U1> for PendulumH {}

impl HamiltonianExactSolution<U1> for PendulumH {
    /// [`Pendulum`]'s solution through (θ₀, p₀/(m l²)), with p = m l² θ̇; `None` where it has
    /// none (the separatrix, non-finite input).
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 1>,
        p0: &SVector<f64, 1>,
        t: f64,
    ) -> Option<(SVector<f64, 1>, SVector<f64, 1>)> {
        let inertia = self.inertia();
        let (q, v) = self.0.exact_solution(t0, q0, &(p0 / inertia), t)?;
        Some((q, v * inertia))
    }
}

impl HamiltonianDefaults<U1> for PendulumH {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn coordinate_names(&self) -> Vec<String> {
        self.0.coordinate_names()
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.0.parameters()
    }
    /// As [`Pendulum`]: `m` and `l` finite and positive, `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        if !Pendulum::PARAMETERS.contains(&name) {
            return Err(params::unknown(Self::NAME, name, &Pendulum::PARAMETERS));
        }
        self.0.set_parameter(name, value)
    }
    /// [`Pendulum`]'s θ₀ = 1, with p₀ = m l² θ̇₀ = 0.
    fn initial_state(&self) -> (f64, SVector<f64, 1>, SVector<f64, 1>) {
        let (t0, q0, v0) = self.0.initial_state();
        (t0, q0, v0 * self.inertia())
    }
    fn default_step(&self) -> f64 {
        self.0.default_step()
    }
    fn default_horizon(&self) -> f64 {
        self.0.default_horizon()
    }
}
