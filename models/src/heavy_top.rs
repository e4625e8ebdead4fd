//! The heavy symmetric top (Lagrange top) about a fixed point.
//!
//! # Lagrangian
//!
//! A rigid body fixed at a point, symmetric about its body axis e₃ (moments of inertia about
//! the fixed point I₁ = I₂, I₃), with mass m and centre of mass at distance l along e₃, in
//! gravity g along −e₃ (space):
//!
//! L(R, Ω) = ½ Ωᵀ diag(I₁, I₁, I₃) Ω − m g l e₃·(R e₃).
//!
//! # Equations of motion
//!
//! Π̇ = Π × Ω + m g l Γ × e₃ with Γ = Rᵀe₃ (the vertical in the body frame), Ṙ = RΩ̂.
//! Conserved: the energy, the vertical angular momentum e₃·(RΠ) = Π·Γ (Noether for rotations
//! about the vertical, R ↦ exp(θê₃)R) and, for the symmetric top, the spin Π₃ = I₃Ω₃
//! (Lagrange's integral).
//!
//! # Defaults
//!
//! I₁ = 1, I₃ = 0.5, m = 1, g = 9.81, l = 0.5; tilted by 0.5 rad about e₁, spinning at
//! Ω₀ = (0, 0, 10) (a fast top: precession with nutation); step 0.01, horizon 20.
//!
//! # On SE(3)
//!
//! [`HeavyTopOnRigidMotions`] writes the same top on SE(3): configuration (R, x), x the
//! position of the pivot, body velocity (Ω, v) with ẋ = R v, and
//!
//! L(R, x, Ω, v) = ½ Ωᵀ diag(I₁, I₁, I₃) Ω + ½ M |v|² − m g l e₃·(R e₃),
//!
//! a pivot frame of mass M in uniform motion (|v| = |ẋ|: the translation does not couple to the
//! rotation, as for a top carried by a support in uniform motion, where the coupling
//! m ẋ·Ṙ l e₃ is a total derivative). Its rotation is the Lagrange top's, and x moves uniformly;
//! the discretisations differ — SE(3)'s screw steps carry ẋ in the rotating body frame — so
//! the two integrators agree to the method's order, which the tests measure.
//!
//! # References
//!
//! Marsden & Ratiu, *Introduction to Mechanics and Symmetry* (1999), §15.10; Hairer,
//! Lubich, Wanner, *Geometric Numerical Integration* (2006), §VII.5 (heavy top);
//! Leok, *Generalized Variational Integrators*, §5.3.

use nalgebra::{SMatrix, SVector};
use svi::Error;
use svi::Scalar;
use svi::lie_group::so3::exp;
use svi::lie_group::{
    GroupLagrangian, RigidBodyDefaults, RigidBodyInvariants, RigidBodyLagrangian,
    RigidBodySymmetries, RigidMotions,
};

use crate::params;

/// The Lagrange top L = ½ Ωᵀ diag(I₁, I₁, I₃) Ω − m g l e₃·(R e₃).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeavyTop {
    /// Moment of inertia about the fixed point, perpendicular to the symmetry axis (> 0).
    pub i1: f64,
    /// Moment of inertia about the symmetry axis (> 0).
    pub i3: f64,
    /// Mass (> 0).
    pub m: f64,
    /// Gravitational acceleration (≥ 0).
    pub g: f64,
    /// Distance from the fixed point to the centre of mass (≥ 0).
    pub l: f64,
}

impl HeavyTop {
    /// Registry name of the model.
    pub const NAME: &'static str = "heavy-top";
    /// Parameter names, in the order of [`RigidBodyDefaults::parameters`].
    pub const PARAMETERS: [&'static str; 5] = ["i1", "i3", "m", "g", "l"];
}

impl Default for HeavyTop {
    /// I₁ = 1, I₃ = 0.5, m = 1, g = 9.81, l = 0.5.
    fn default() -> Self {
        HeavyTop {
            i1: 1.0,
            i3: 0.5,
            m: 1.0,
            g: 9.81,
            l: 0.5,
        }
    }
}

/// The Lagrange top on SE(3) with its pivot frame in uniform motion (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeavyTopOnRigidMotions {
    /// The top.
    pub top: HeavyTop,
    /// The mass M of the pivot frame (> 0).
    pub frame_mass: f64,
}

impl Default for HeavyTopOnRigidMotions {
    /// The default top, M = 1.
    fn default() -> Self {
        HeavyTopOnRigidMotions {
            top: HeavyTop::default(),
            frame_mass: 1.0,
        }
    }
}

impl GroupLagrangian<6, 12> for HeavyTopOnRigidMotions {
    type Group = RigidMotions;

    #[inline]
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
        let omega = SVector::<D, 3>::from([xi[0], xi[1], xi[2]]);
        let translation = (xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]) * (0.5 * self.frame_mass);
        self.top.lagrangian(&RigidMotions::rotation(g), &omega) + translation
    }
}

impl RigidBodyLagrangian for HeavyTop {
    #[inline]
    fn lagrangian<D: Scalar>(&self, r: &SMatrix<D, 3, 3>, omega: &SVector<D, 3>) -> D {
        let kinetic = ((omega[0] * omega[0] + omega[1] * omega[1]) * self.i1
            + omega[2] * omega[2] * self.i3)
            * 0.5;
        // e₃·(R e₃) = R₃₃.
        kinetic - r[(2, 2)] * (self.m * self.g * self.l)
    }
}

/// Rotations about the vertical: the vertical angular momentum e₃·(RΠ) is conserved.
impl RigidBodySymmetries for HeavyTop {
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

/// Lagrange's integral: the spin Π₃ about the symmetry axis.
impl RigidBodyInvariants for HeavyTop {
    fn invariant_count(&self) -> usize {
        1
    }
    fn invariant_name(&self, index: usize) -> &'static str {
        match index {
            0 => "spin Pi_3",
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
            0 => momentum[2],
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
}

impl RigidBodyDefaults for HeavyTop {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("i1", self.i1),
            ("i3", self.i3),
            ("m", self.m),
            ("g", self.g),
            ("l", self.l),
        ]
    }

    /// `i1`, `i3`, `m` finite and positive; `g`, `l` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "i1" => self.i1 = params::positive(name, value)?,
            "i3" => self.i3 = params::positive(name, value)?,
            "m" => self.m = params::positive(name, value)?,
            "g" => self.g = params::non_negative(name, value)?,
            "l" => self.l = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// R₀ = exp(0.5 ê₁) (tilted 0.5 rad), Ω₀ = (0, 0, 10).
    fn initial_state(&self) -> (SMatrix<f64, 3, 3>, SVector<f64, 3>) {
        (
            exp(&SVector::from([0.5, 0.0, 0.0])),
            SVector::from([0.0, 0.0, 10.0]),
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
