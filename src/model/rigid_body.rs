//! Rigid-body models: a Lagrangian on the rotation group, and optional companions.
//!
//! The only required piece is [`RigidBodyLagrangian::lagrangian`], one function L(R, Ω) of
//! the attitude R ∈ SO(3) and the body angular velocity Ω = (RᵀṘ)^∨, generic over
//! [`Scalar`]. Everything else is derived by automatic differentiation
//! ([`RigidBodyExt`]): the body angular momentum Π = ∂L/∂Ω, its inverse (the Legendre map
//! Ω(R, Π)), the energy E = Π·Ω − L, and the left-trivialised configuration gradient
//! τ = (d/dε) L(R exp(ε ·), Ω) (the torque of a potential).
//!
//! Companions, each optional and small:
//! - [`RigidBodySymmetries`]: spatial axes a with L(exp(θâ) R, Ω) = L(R, Ω); by Noether's
//!   theorem the spatial angular momentum about a, J_a = a·(R Π), is conserved (all three
//!   components for a free body, the vertical one for a heavy top).
//! - [`RigidBodyInvariants`]: other conserved quantities (a body-frame Casimir such as ‖Π‖²).
//! - [`RigidBodyDefaults`]: named parameters, default initial state, step and horizon.
//!
//! [`RigidBodyLagrangian::G_INVARIANT`] declares that L depends on Ω only
//! (L(R, Ω) = L(I, Ω), invariance under R ↦ QR); it unlocks the reduced Euler–Poincaré form
//! of [`crate::method::lie_svi::LieSvi`].
//!
//! # Example
//! ```
//! use nalgebra::{SMatrix, SVector};
//! use svi::Scalar;
//! use svi::lie_group::RigidBodyLagrangian;
//!
//! /// A free rigid body with principal moments of inertia I₁, I₂, I₃.
//! struct FreeBody([f64; 3]);
//!
//! impl RigidBodyLagrangian for FreeBody {
//!     const G_INVARIANT: bool = true;
//!     fn lagrangian<D: Scalar>(&self, _r: &SMatrix<D, 3, 3>, omega: &SVector<D, 3>) -> D {
//!         (0..3).fold(D::from(0.0), |sum, i| sum + omega[i] * omega[i] * (0.5 * self.0[i]))
//!     }
//! }
//! ```

use crate::error::Error;
use crate::model::group::invert_momentum;
use crate::model::so3::{Matrix3, Vector3, exp};
use crate::scalar::Scalar;
use nalgebra::Const;
use num_dual::{Dual2Vec, DualSVec64, DualVec, gradient, hessian};

/// A Lagrangian L(R, Ω) on the tangent bundle of SO(3), left-trivialised: R is the attitude
/// (body to space) and Ω the body angular velocity, Ṙ = R Ω̂.
pub trait RigidBodyLagrangian {
    /// Whether L(R, Ω) = L(I, Ω) for every R (the Lagrangian is invariant under the left
    /// action R ↦ QR of the whole group). The default (`false`) is always correct; `true`
    /// allows the reduced (Euler–Poincaré) form of the integrator, which never evaluates the
    /// configuration dependence. The stepping loop checks the declaration at the initial
    /// state.
    const G_INVARIANT: bool = false;

    /// The value L(R, Ω). Mark it `#[inline]`: the integrator evaluates it with dual numbers
    /// in its inner loop.
    fn lagrangian<D: Scalar>(&self, r: &Matrix3<D>, omega: &Vector3<D>) -> D;
}

/// Spatial symmetry axes of a rigid-body Lagrangian.
///
/// Axis `a` (a unit vector in space) generates the rotations exp(θâ) acting on the left,
/// R ↦ exp(θâ) R, which must leave L invariant. The conserved Noether momentum is the
/// spatial angular momentum about `a`, J_a = a·(R Π).
pub trait RigidBodySymmetries: RigidBodyLagrangian {
    /// Number of axes (default: none).
    fn axis_count(&self) -> usize {
        0
    }
    /// Name of the momentum about axis `index` (for reports).
    ///
    /// # Panics
    /// If `index >= axis_count()` (the default panics for every index).
    fn axis_name(&self, index: usize) -> &'static str {
        panic!("no symmetry axis with index {index}")
    }
    /// Axis `index`, a unit vector in space.
    ///
    /// # Panics
    /// If `index >= axis_count()` (the default panics for every index).
    fn axis(&self, index: usize) -> Vector3<f64> {
        panic!("no symmetry axis with index {index}")
    }
}

/// Other known conserved quantities of a rigid-body model, for example the body-frame
/// Casimir ‖Π‖² of the free rigid body.
pub trait RigidBodyInvariants: RigidBodyLagrangian {
    /// Number of invariants (default: none).
    fn invariant_count(&self) -> usize {
        0
    }
    /// Name of invariant `index`.
    ///
    /// # Panics
    /// If `index >= invariant_count()` (the default panics for every index).
    fn invariant_name(&self, index: usize) -> &'static str {
        panic!("no invariant with index {index}")
    }
    /// Value of invariant `index` at attitude `r`, body angular velocity `omega` and body
    /// angular momentum `momentum`.
    ///
    /// # Panics
    /// If `index >= invariant_count()` (the default panics for every index).
    fn invariant(
        &self,
        index: usize,
        r: &Matrix3<f64>,
        omega: &Vector3<f64>,
        momentum: &Vector3<f64>,
    ) -> f64 {
        let _ = (r, omega, momentum);
        panic!("no invariant with index {index}")
    }
}

/// Named parameters and defaults of a rigid-body model (the analogue of
/// [`crate::Defaults`]).
pub trait RigidBodyDefaults: RigidBodyLagrangian {
    /// Short name (as used by the CLI, e.g. `"rigid-body"`).
    fn name(&self) -> &'static str;
    /// Current parameter values, by name.
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter; an unknown name or an out-of-range value is an
    /// [`Error::InvalidParameter`].
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error>;
    /// Default initial state (R₀, Ω₀) for the current parameters.
    fn initial_state(&self) -> (Matrix3<f64>, Vector3<f64>);
    /// Default step size.
    fn default_step(&self) -> f64;
    /// Default final time (the start time is 0).
    fn default_horizon(&self) -> f64;
}

/// Quantities derived from a [`RigidBodyLagrangian`] by automatic differentiation.
/// Implemented for every rigid-body Lagrangian.
pub trait RigidBodyExt: RigidBodyLagrangian {
    /// L(R, Ω).
    #[inline]
    fn value(&self, r: &Matrix3<f64>, omega: &Vector3<f64>) -> f64 {
        self.lagrangian(r, omega)
    }

    /// The body angular momentum Π = ∂L/∂Ω (the left-trivialised momentum).
    #[inline]
    fn momentum(&self, r: &Matrix3<f64>, omega: &Vector3<f64>) -> Vector3<f64> {
        gradient(
            |w: Vector3<DualSVec64<3>>| self.lagrangian(&r.map(DualVec::from_re), &w),
            omega,
        )
        .1
    }

    /// The energy E = Π·Ω − L (Legendre transform, by automatic differentiation).
    #[inline]
    fn energy(&self, r: &Matrix3<f64>, omega: &Vector3<f64>) -> f64 {
        let (value, momentum) = gradient(
            |w: Vector3<DualSVec64<3>>| self.lagrangian(&r.map(DualVec::from_re), &w),
            omega,
        );
        momentum.dot(omega) - value
    }

    /// The left-trivialised configuration gradient τ with τ·ζ = d/dε L(R exp(εζ), Ω) at
    /// ε = 0 (for L = T(Ω) − V(R), the torque of the potential in the body frame). Computed
    /// through the dual exponential at ζ = 0.
    #[inline]
    fn torque(&self, r: &Matrix3<f64>, omega: &Vector3<f64>) -> Vector3<f64> {
        gradient(
            |z: Vector3<DualSVec64<3>>| {
                let rotated = r.map(DualVec::from_re) * exp(&z);
                self.lagrangian(&rotated, &omega.map(DualVec::from_re))
            },
            &Vector3::zeros(),
        )
        .1
    }

    /// The inverse Legendre map: Ω with ∂L/∂Ω(R, Ω) = Π, by Newton's method from `guess`
    /// (one iteration is exact for a Lagrangian quadratic in Ω).
    fn velocity(
        &self,
        r: &Matrix3<f64>,
        momentum: &Vector3<f64>,
        guess: &Vector3<f64>,
    ) -> Result<Vector3<f64>, Error> {
        invert_momentum(momentum, guess, |omega| {
            let (_, current, inertia) = hessian(
                |w: Vector3<Dual2Vec<f64, Const<3>>>| {
                    self.lagrangian(&r.map(Dual2Vec::from_re), &w)
                },
                omega,
            );
            (current, inertia)
        })
    }

    /// The right-hand side of the Euler–Poincaré equations with the reconstruction equation:
    /// (Ṙ, Π̇) = (R Ω̂, Π × Ω + τ(R, Ω)), with Ω = Ω(R, Π) from the inverse Legendre map.
    /// Useful for reference solutions (explicit Runge–Kutta); the Lie-group integrator does
    /// not use it.
    fn euler_poincare(
        &self,
        r: &Matrix3<f64>,
        momentum: &Vector3<f64>,
        guess: &Vector3<f64>,
    ) -> Result<(Vector3<f64>, Vector3<f64>), Error> {
        let omega = self.velocity(r, momentum, guess)?;
        let rate = momentum.cross(&omega) + self.torque(r, &omega);
        Ok((omega, rate))
    }
}

impl<T: RigidBodyLagrangian + ?Sized> RigidBodyExt for T {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::so3::hat;

    struct Top;
    impl RigidBodyLagrangian for Top {
        fn lagrangian<D: Scalar>(&self, r: &Matrix3<D>, omega: &Vector3<D>) -> D {
            let inertia = [1.0, 2.0, 3.0];
            let kinetic = (0..3).fold(D::from(0.0), |s, i| {
                s + omega[i] * omega[i] * (0.5 * inertia[i])
            });
            // V = m g e3·(R χ), χ = (0.1, 0.2, 0.5).
            let height = r[(2, 0)] * 0.1 + r[(2, 1)] * 0.2 + r[(2, 2)] * 0.5;
            kinetic - height * 9.81
        }
    }

    #[test]
    fn momentum_energy_and_legendre_map() {
        let r = crate::model::so3::exp(&Vector3::new(0.3, -0.4, 0.2));
        let omega = Vector3::new(0.5, -1.0, 2.0);
        let p = Top.momentum(&r, &omega);
        assert!((p - Vector3::new(0.5, -2.0, 6.0)).amax() < 1e-15);
        let back = Top.velocity(&r, &p, &Vector3::zeros()).unwrap();
        assert!((back - omega).amax() < 1e-15);
        let kinetic = 0.5 * (0.25 + 2.0 + 12.0);
        let height = r.row(2).dot(&Vector3::new(0.1, 0.2, 0.5).transpose());
        assert!((Top.energy(&r, &omega) - (kinetic + 9.81 * height)).abs() < 1e-13);
    }

    #[test]
    fn torque_is_the_heavy_top_torque() {
        // τ = m g Γ × χ with Γ = Rᵀ e3.
        let r = crate::model::so3::exp(&Vector3::new(0.3, -0.4, 0.2));
        let chi = Vector3::new(0.1, 0.2, 0.5);
        let gamma = r.transpose() * Vector3::z();
        let expected = gamma.cross(&chi) * 9.81;
        let torque = Top.torque(&r, &Vector3::new(0.5, -1.0, 2.0));
        assert!((torque - expected).amax() < 1e-14, "{torque} vs {expected}");
        let _ = hat(&chi);
    }
}
