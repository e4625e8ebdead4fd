//! The dual-spin satellite: a rigid platform carrying a symmetric rotor that spins about the
//! platform's third body axis, on SO(3) × S¹ ([`svi::lie_group::Product`] of
//! [`svi::lie_group::Rotations`] and [`svi::lie_group::Circle`]).
//!
//! # Lagrangian
//! Platform attitude R with body angular velocity Ω, rotor angle φ relative to the platform,
//! principal moments I₁, I₂, I₃ of the whole satellite about its centre of mass (the rotor's
//! transverse inertia included) and the rotor's axial inertia J:
//!
//! L = ½ (I₁Ω₁² + I₂Ω₂² + (I₃ − J)Ω₃²) + ½ J (Ω₃ + φ̇)².
//!
//! Torque-free and independent of (R, φ): G-invariant. Conserved: the energy, the spatial
//! angular momentum R Π with Π = (I₁Ω₁, I₂Ω₂, (I₃ − J)Ω₃ + J(Ω₃ + φ̇)) (all three components),
//! and the rotor's momentum p_φ = J(Ω₃ + φ̇). A fast rotor makes rotation about the
//! intermediate axis stable (gyrostat stabilisation). Hughes, *Spacecraft Attitude Dynamics*
//! (1986), ch. 7.

use nalgebra::SVector;
use svi::Scalar;
use svi::lie_group::{Circle, GroupLagrangian, Product, Rotations};

/// The platform's attitude and the rotor's angle.
pub type SatelliteGroup = Product<Rotations, Circle, 3, 9, 1, 2>;

/// The dual-spin satellite (a gyrostat) on SO(3) × S¹.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualSpin {
    /// Principal moments of inertia of the satellite (> 0).
    pub inertia: [f64; 3],
    /// The rotor's axial inertia J (0 < J < I₃).
    pub rotor: f64,
}

impl Default for DualSpin {
    /// I = diag(1, 2, 3), J = 0.5.
    fn default() -> Self {
        DualSpin {
            inertia: [1.0, 2.0, 3.0],
            rotor: 0.5,
        }
    }
}

impl GroupLagrangian<4, 11> for DualSpin {
    type Group = SatelliteGroup;
    const G_INVARIANT: bool = true;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _g: &SVector<D, 11>, xi: &SVector<D, 4>) -> D {
        let [i1, i2, i3] = self.inertia;
        let spin = xi[2] + xi[3];
        (xi[0] * xi[0] * i1 + xi[1] * xi[1] * i2 + xi[2] * xi[2] * (i3 - self.rotor)) * 0.5
            + spin * spin * (0.5 * self.rotor)
    }
}
