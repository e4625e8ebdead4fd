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

use crate::params;
use nalgebra::SVector;
use svi::lie_group::{
    Circle, GroupDefaults, GroupLagrangian, GroupSymmetries, Product, Rotations, so3,
};
use svi::{Error, Scalar};

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

impl DualSpin {
    /// The model's name.
    pub const NAME: &'static str = "dual-spin";
    /// The parameter names.
    pub const PARAMETERS: [&'static str; 4] = ["i1", "i2", "i3", "j"];
}

/// G-invariant: every generator is a symmetry. The three spatial rotations give the spatial
/// angular momentum, the rotor's turn its momentum p_φ.
impl GroupSymmetries<4, 11> for DualSpin {
    #[inline]
    fn generator_count(&self) -> usize {
        4
    }

    fn momentum_name(&self, index: usize) -> &'static str {
        match index {
            0 => "L_x",
            1 => "L_y",
            2 => "L_z",
            3 => "p_rotor",
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }

    #[inline]
    fn generator(&self, index: usize) -> SVector<f64, 4> {
        if index >= 4 {
            params::no_such_index("symmetry generator", Self::NAME, index)
        }
        SVector::from_fn(|i, _| if i == index { 1.0 } else { 0.0 })
    }
}

impl GroupDefaults<4, 11> for DualSpin {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        let [i1, i2, i3] = self.inertia;
        vec![("i1", i1), ("i2", i2), ("i3", i3), ("j", self.rotor)]
    }

    /// `i1`, `i2`, `i3`, `j` finite and positive, with `j` < `i3` (the platform's axial
    /// inertia I₃ − J stays positive).
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let value = params::positive(name, value)?;
        let (i3, rotor) = match name {
            "i3" => (value, self.rotor),
            "j" => (self.inertia[2], value),
            _ => (self.inertia[2], self.rotor),
        };
        if rotor >= i3 {
            return Err(Error::invalid(
                name,
                format!("{value:?}: the rotor's inertia j = {rotor:?} must stay below i3 = {i3:?}"),
            ));
        }
        match name {
            "i1" => self.inertia[0] = value,
            "i2" => self.inertia[1] = value,
            "i3" => self.inertia[2] = value,
            "j" => self.rotor = value,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// R₀ = exp(0.1, −0.2, 0.3), rotor angle 0.4; Ω₀ = (0.05, 1, 0.1) near the intermediate
    /// axis, rotor rate 5 (the rotor makes that rotation stable).
    fn initial_state(&self) -> (SVector<f64, 11>, SVector<f64, 4>) {
        let mut g0 = SVector::<f64, 11>::zeros();
        g0.fixed_rows_mut::<9>(0)
            .copy_from(&Rotations::element(&so3::exp(&SVector::from([
                0.1, -0.2, 0.3,
            ]))));
        g0.fixed_rows_mut::<2>(9).copy_from(&Circle::element(0.4));
        (g0, SVector::from([0.05, 1.0, 0.1, 5.0]))
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
