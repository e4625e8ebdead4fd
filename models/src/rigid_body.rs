//! The free rigid body (Euler's top).
//!
//! # Lagrangian
//!
//! A rigid body with principal moments of inertia I₁, I₂, I₃ (body frame = principal axes),
//! attitude R ∈ SO(3) and body angular velocity Ω:
//!
//! L(R, Ω) = ½ Ωᵀ diag(I₁, I₂, I₃) Ω,
//!
//! independent of R (G-invariant: the reduced Euler–Poincaré form applies).
//!
//! # Equations of motion
//!
//! Euler's equations Π̇ = Π × Ω with Π = IΩ, and Ṙ = RΩ̂. Conserved: the energy
//! E = ½ Ω·IΩ, the spatial angular momentum π = RΠ (all three components, Noether for
//! R ↦ QR) and the body Casimir ‖Π‖².
//!
//! # Defaults
//!
//! I = diag(1, 2, 3) (asymmetric), R₀ = I, Ω₀ = (1, 0.5, −0.4), step 0.05, horizon 100.
//!
//! # References
//!
//! J. E. Marsden, T. S. Ratiu, *Introduction to Mechanics and Symmetry* (1999), ch. 15;
//! E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration* (2006), §VII.5.

use nalgebra::{SMatrix, SVector};
use svi::Error;
use svi::Scalar;
use svi::lie_group::{
    RigidBodyDefaults, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries,
};

use crate::params;

/// The free rigid body L = ½ Ωᵀ diag(I₁, I₂, I₃) Ω.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeRigidBody {
    /// Principal moments of inertia (> 0).
    pub inertia: [f64; 3],
}

impl FreeRigidBody {
    /// Registry name of the model.
    pub const NAME: &'static str = "rigid-body";
    /// Parameter names, in the order of [`RigidBodyDefaults::parameters`].
    pub const PARAMETERS: [&'static str; 3] = ["i1", "i2", "i3"];
}

impl Default for FreeRigidBody {
    /// I = diag(1, 2, 3).
    fn default() -> Self {
        FreeRigidBody {
            inertia: [1.0, 2.0, 3.0],
        }
    }
}

impl RigidBodyLagrangian for FreeRigidBody {
    const G_INVARIANT: bool = true;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _r: &SMatrix<D, 3, 3>, omega: &SVector<D, 3>) -> D {
        let [a, b, c] = self.inertia;
        (omega[0] * omega[0] * a + omega[1] * omega[1] * b + omega[2] * omega[2] * c) * 0.5
    }
}

/// Invariant under every rotation in space: all three components of π = RΠ are conserved.
impl RigidBodySymmetries for FreeRigidBody {
    fn axis_count(&self) -> usize {
        3
    }
    fn axis_name(&self, index: usize) -> &'static str {
        match index {
            0 => "angular momentum x",
            1 => "angular momentum y",
            2 => "angular momentum z",
            _ => params::no_such_index("symmetry axis", Self::NAME, index),
        }
    }
    fn axis(&self, index: usize) -> SVector<f64, 3> {
        match index {
            0..=2 => SVector::ith(index, 1.0),
            _ => params::no_such_index("symmetry axis", Self::NAME, index),
        }
    }
}

/// The body Casimir ‖Π‖².
impl RigidBodyInvariants for FreeRigidBody {
    fn invariant_count(&self) -> usize {
        1
    }
    fn invariant_name(&self, index: usize) -> &'static str {
        match index {
            0 => "casimir |Pi|^2",
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
    fn invariant(
        &self,
        index: usize,
        _r: &SMatrix<f64, 3, 3>,
        _omega: &SVector<f64, 3>,
        momentum: &SVector<f64, 3>,
    ) -> f64 {
        match index {
            0 => momentum.norm_squared(),
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
}

impl RigidBodyDefaults for FreeRigidBody {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Self::PARAMETERS.into_iter().zip(self.inertia).collect()
    }

    /// Every moment of inertia must be finite and positive.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match Self::PARAMETERS.iter().position(|p| *p == name) {
            Some(i) => self.inertia[i] = params::positive(name, value)?,
            None => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// R₀ = I, Ω₀ = (1, 0.5, −0.4).
    fn initial_state(&self) -> (SMatrix<f64, 3, 3>, SVector<f64, 3>) {
        (SMatrix::identity(), SVector::from([1.0, 0.5, -0.4]))
    }

    /// h = 0.05.
    fn default_step(&self) -> f64 {
        0.05
    }

    /// T = 100.
    fn default_horizon(&self) -> f64 {
        100.0
    }
}
