//! The 3D pendulum: an asymmetric rigid body swinging about a fixed point.
//!
//! # Lagrangian
//!
//! A rigid body fixed at a frictionless pivot, with moments of inertia about the pivot
//! I₁, I₂, I₃ (body axes = principal axes), mass m and centre of mass at the body vector χ
//! from the pivot, in gravity g along −e₃:
//!
//! L(R, Ω) = ½ Ωᵀ diag(I₁, I₂, I₃) Ω − m g e₃·(R χ).
//!
//! # Equations of motion
//!
//! Π̇ = Π × Ω + m g Γ × χ, Γ = Rᵀe₃, Ṙ = RΩ̂. Conserved: the energy and the vertical angular
//! momentum e₃·(RΠ). (Chaotic for generic data.)
//!
//! # Defaults
//!
//! I = diag(1, 1.5, 2), m = 1, g = 9.81, χ = (0.1, 0.05, −0.5) (hanging below the pivot);
//! R₀ = exp((0.6, −0.3, 0)), Ω₀ = (0.5, −1, 2); step 0.01, horizon 20.
//!
//! # References
//!
//! Chaturvedi, Lee, Leok, McClamroch, *Nonlinear dynamics of the 3D pendulum*, J. Nonlinear
//! Sci. 21 (2011); Lee, Leok, McClamroch, *Lie group variational integrators for the full
//! body problem*, CMAME 196 (2007).

use nalgebra::{SMatrix, SVector};
use svi::Error;
use svi::Scalar;
use svi::lie_group::so3::exp;
use svi::lie_group::{
    RigidBodyDefaults, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries,
};

use crate::params;

/// The 3D pendulum L = ½ Ωᵀ diag(I₁, I₂, I₃) Ω − m g e₃·(R χ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pendulum3d {
    /// Principal moments of inertia about the pivot (> 0).
    pub inertia: [f64; 3],
    /// Mass (> 0).
    pub m: f64,
    /// Gravitational acceleration (≥ 0).
    pub g: f64,
    /// Centre of mass in the body frame, relative to the pivot.
    pub centre: [f64; 3],
}

impl Pendulum3d {
    /// Registry name of the model.
    pub const NAME: &'static str = "pendulum-3d";
    /// Parameter names, in the order of [`RigidBodyDefaults::parameters`].
    pub const PARAMETERS: [&'static str; 8] = ["i1", "i2", "i3", "m", "g", "cx", "cy", "cz"];
}

impl Default for Pendulum3d {
    /// I = diag(1, 1.5, 2), m = 1, g = 9.81, χ = (0.1, 0.05, −0.5).
    fn default() -> Self {
        Pendulum3d {
            inertia: [1.0, 1.5, 2.0],
            m: 1.0,
            g: 9.81,
            centre: [0.1, 0.05, -0.5],
        }
    }
}

impl RigidBodyLagrangian for Pendulum3d {
    #[inline]
    fn lagrangian<D: Scalar>(&self, r: &SMatrix<D, 3, 3>, omega: &SVector<D, 3>) -> D {
        let [a, b, c] = self.inertia;
        let kinetic =
            (omega[0] * omega[0] * a + omega[1] * omega[1] * b + omega[2] * omega[2] * c) * 0.5;
        // e₃·(R χ) = Σ_j R₃ⱼ χⱼ.
        let [x, y, z] = self.centre;
        let height = r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z;
        kinetic - height * (self.m * self.g)
    }
}

/// Rotations about the vertical: the vertical angular momentum e₃·(RΠ) is conserved.
impl RigidBodySymmetries for Pendulum3d {
    fn axis_count(&self) -> usize {
        1
    }
    fn axis_name(&self, index: usize) -> &'static str {
        match index {
            0 => "vertical angular momentum",
            _ => params::no_such_index("symmetry axis", Self::NAME, index),
        }
    }
    fn axis(&self, index: usize) -> SVector<f64, 3> {
        match index {
            0 => SVector::z(),
            _ => params::no_such_index("symmetry axis", Self::NAME, index),
        }
    }
}

/// No known invariants besides the energy and the vertical momentum.
impl RigidBodyInvariants for Pendulum3d {}

impl RigidBodyDefaults for Pendulum3d {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        let [a, b, c] = self.inertia;
        let [x, y, z] = self.centre;
        Self::PARAMETERS
            .into_iter()
            .zip([a, b, c, self.m, self.g, x, y, z])
            .collect()
    }

    /// Moments of inertia and `m` finite and positive, `g` finite and non-negative, the
    /// centre of mass finite.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "i1" => self.inertia[0] = params::positive(name, value)?,
            "i2" => self.inertia[1] = params::positive(name, value)?,
            "i3" => self.inertia[2] = params::positive(name, value)?,
            "m" => self.m = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            "cx" => self.centre[0] = params::finite(name, value)?,
            "cy" => self.centre[1] = params::finite(name, value)?,
            "cz" => self.centre[2] = params::finite(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// R₀ = exp((0.6, −0.3, 0)), Ω₀ = (0.5, −1, 2).
    fn initial_state(&self) -> (SMatrix<f64, 3, 3>, SVector<f64, 3>) {
        (
            exp(&SVector::from([0.6, -0.3, 0.0])),
            SVector::from([0.5, -1.0, 2.0]),
        )
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
