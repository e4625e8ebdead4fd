//! Field theories in 1 + 1 dimensions: a Lagrangian density ℒ(x, t, u, u_t, u_x), written
//! once, generic over [`Scalar`], and everything derived from it by automatic
//! differentiation.
//!
//! A field u: [a, b] × ℝ → ℝᶜ (C real components) has the action
//!
//! S\[u\] = ∫∫ ℒ(x, t, u, u_t, u_x) dx dt
//!
//! (Leok, *Generalized Variational Integrators*, §5.1.2–5.1.3: the density is a map on the
//! first jet bundle J¹Y, here written in coordinates). Its Euler–Lagrange equation is
//! ∂_t ∂ℒ/∂u_t + ∂_x ∂ℒ/∂u_x = ∂ℒ/∂u. The multisymplectic integrators of
//! [`crate::field`] need, at a point of the jet, the gradient of ℒ in (u, u_t, u_x)
//! ([`LagrangianDensityExt::gradient`]: 3C scalar dual sweeps) and, for Newton's method
//! and the multisymplectic diagnostics, its Hessian ([`LagrangianDensityExt::hessian`]: one
//! scalar hyper-dual sweep per entry; 3C is not a const expression on stable Rust, so one
//! vector sweep over all 3C arguments is not available, and for the small C of field
//! theories the scalar sweeps are the cheaper ones).
//!
//! Companions, each optional: [`FieldDefaults`] (name, parameters, spatial domain, boundary
//! condition, initial field, mesh and horizon) and [`ExactField`] (a closed-form solution).
//!
//! # Example
//! ```
//! use nalgebra::SVector;
//! use svi::model::density::{DensityStructure, LagrangianDensity, LagrangianDensityExt, Jet};
//! use svi::Scalar;
//!
//! /// The Klein–Gordon field: ℒ = ½u_t² − ½u_x² − ½m²u².
//! struct KleinGordon {
//!     mass: f64,
//! }
//!
//! impl LagrangianDensity<1> for KleinGordon {
//!     const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;
//!     fn density<D: Scalar>(
//!         &self,
//!         _x: f64,
//!         _t: f64,
//!         u: &SVector<D, 1>,
//!         u_t: &SVector<D, 1>,
//!         u_x: &SVector<D, 1>,
//!     ) -> D {
//!         (u_t[0] * u_t[0] - u_x[0] * u_x[0] - u[0] * u[0] * (self.mass * self.mass)) * 0.5
//!     }
//! }
//!
//! let jet = Jet { u: SVector::from([2.0]), u_t: SVector::from([3.0]), u_x: SVector::from([5.0]) };
//! let g = KleinGordon { mass: 0.5 }.gradient(0.0, 0.0, &jet);
//! assert_eq!((g.u[0], g.u_t[0], g.u_x[0]), (-0.5, 3.0, -5.0));
//! ```

use crate::error::Error;
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};
use num_dual::{Dual64, HyperDual64};

/// A Lagrangian density ℒ(x, t, u, u_t, u_x) of a field with C real components, written once,
/// generic over the scalar type.
pub trait LagrangianDensity<const C: usize> {
    /// Structure the integrators may exploit; the default ([`DensityStructure::General`]) is
    /// always correct.
    const STRUCTURE: DensityStructure = DensityStructure::General;

    /// The value ℒ(x, t, u, u_t, u_x). Mark it `#[inline]`: the integrators evaluate it with
    /// dual numbers at every quadrature point of every cell.
    fn density<D: Scalar>(
        &self,
        x: f64,
        t: f64,
        u: &SVector<D, C>,
        u_t: &SVector<D, C>,
        u_x: &SVector<D, C>,
    ) -> D;
}

/// Structure of a Lagrangian density that integrators may exploit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DensityStructure {
    /// No assumption.
    General,
    /// ℒ = ½ u_tᵀ M u_t + f(x, t, u, u_x) with a constant symmetric positive-definite M: the
    /// momentum density ∂ℒ/∂u_t = M u_t depends on u_t only, linearly. With the trapezoidal
    /// cell quadrature the multisymplectic scheme is then explicit
    /// ([`crate::field::multisymplectic`]). The integrators check the declaration on the
    /// initial field and reject a density that breaks it.
    ConstantMass,
}

/// A point of the first jet: the field value and its two first derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jet<const C: usize> {
    /// u.
    pub u: SVector<f64, C>,
    /// ∂u/∂t.
    pub u_t: SVector<f64, C>,
    /// ∂u/∂x.
    pub u_x: SVector<f64, C>,
}

/// ℒ and its first derivatives at one point of the jet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensityGradient<const C: usize> {
    /// ℒ.
    pub value: f64,
    /// ∂ℒ/∂u.
    pub u: SVector<f64, C>,
    /// ∂ℒ/∂u_t (the momentum density π).
    pub u_t: SVector<f64, C>,
    /// ∂ℒ/∂u_x.
    pub u_x: SVector<f64, C>,
}

impl<const C: usize> DensityGradient<C> {
    /// The energy density π·u_t − ℒ at `jet` (the point this gradient was taken at).
    pub fn energy(&self, jet: &Jet<C>) -> f64 {
        self.u_t.dot(&jet.u_t) - self.value
    }

    /// The momentum density −π·u_x at `jet`: the Noether density of translations in x.
    pub fn momentum(&self, jet: &Jet<C>) -> f64 {
        -self.u_t.dot(&jet.u_x)
    }
}

/// The second derivatives of ℒ in the arguments (u, u_t, u_x), as 3 × 3 blocks of C × C.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensityHessian<const C: usize> {
    /// Block (a, b) is ∂²ℒ/∂a∂b for a, b ∈ (u, u_t, u_x), entry (i, j) ∂²ℒ/∂aᵢ∂bⱼ.
    pub blocks: [[SMatrix<f64, C, C>; 3]; 3],
}

/// Derived quantities of a Lagrangian density, by automatic differentiation. Implemented for
/// every [`LagrangianDensity`].
pub trait LagrangianDensityExt<const C: usize>: LagrangianDensity<C> {
    /// ℒ, ∂ℒ/∂u, ∂ℒ/∂u_t and ∂ℒ/∂u_x at (x, t, jet): 3C sweeps of the scalar dual number
    /// `Dual64`, one per argument (a vector dual `DualSVec64<C>` per argument group costs
    /// twice as much for C = 1, and 3C is not a const expression for one sweep of all).
    #[inline]
    fn gradient(&self, x: f64, t: f64, jet: &Jet<C>) -> DensityGradient<C> {
        let args = [jet.u, jet.u_t, jet.u_x];
        let mut derivatives = [SVector::<f64, C>::zeros(); 3];
        let mut value = 0.0;
        for (a, derivative) in derivatives.iter_mut().enumerate() {
            for c in 0..C {
                let mut lifted = args.map(|v| v.map(Dual64::from_re));
                lifted[a][c].eps = 1.0;
                let result = self.density(x, t, &lifted[0], &lifted[1], &lifted[2]);
                value = result.re;
                derivative[c] = result.eps;
            }
        }
        let [u, u_t, u_x] = derivatives;
        DensityGradient { value, u, u_t, u_x }
    }

    /// The Hessian of ℒ in (u, u_t, u_x) at (x, t, jet): one sweep of the scalar hyper-dual
    /// number `HyperDual64` per entry on and above the diagonal, 3C(3C + 1)/2 in all.
    fn hessian(&self, x: f64, t: f64, jet: &Jet<C>) -> DensityHessian<C> {
        let args = [jet.u, jet.u_t, jet.u_x];
        let mut blocks = [[SMatrix::<f64, C, C>::zeros(); 3]; 3];
        for first in 0..3 * C {
            for second in first..3 * C {
                let (a, i) = (first / C, first % C);
                let (b, j) = (second / C, second % C);
                let mut lifted = args.map(|v| v.map(HyperDual64::from_re));
                lifted[a][i].eps1 = 1.0;
                lifted[b][j].eps2 = 1.0;
                let entry = self
                    .density(x, t, &lifted[0], &lifted[1], &lifted[2])
                    .eps1eps2;
                blocks[a][b][(i, j)] = entry;
                blocks[b][a][(j, i)] = entry;
            }
        }
        DensityHessian { blocks }
    }
}

impl<F: LagrangianDensity<C> + ?Sized, const C: usize> LagrangianDensityExt<C> for F {}

/// The spatial domain [left, right] of a field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    left: f64,
    right: f64,
}

impl Domain {
    /// The interval [left, right].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `domain` for non-finite ends or an empty interval
    /// (right ≤ left).
    pub fn new(left: f64, right: f64) -> Result<Self, Error> {
        if !left.is_finite() || !right.is_finite() {
            return Err(Error::invalid(
                "domain",
                format!("[{left:?}, {right:?}] has a non-finite end"),
            ));
        }
        if right <= left {
            return Err(Error::invalid(
                "domain",
                format!("[{left:?}, {right:?}] is empty (the right end must exceed the left)"),
            ));
        }
        Ok(Domain { left, right })
    }

    /// The left end a.
    pub fn left(&self) -> f64 {
        self.left
    }

    /// The right end b.
    pub fn right(&self) -> f64 {
        self.right
    }

    /// The length b − a.
    pub fn length(&self) -> f64 {
        self.right - self.left
    }
}

/// The boundary condition of a field on its [`Domain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Boundary<const C: usize> {
    /// u(a, t) = u(b, t): the ends are one point (x_M ≡ x_0).
    Periodic,
    /// u(a, t) = left and u(b, t) = right at all times.
    Dirichlet {
        /// The value held at the left end.
        left: SVector<f64, C>,
        /// The value held at the right end.
        right: SVector<f64, C>,
    },
}

/// Named parameters and defaults of a field model.
pub trait FieldDefaults<const C: usize>: LagrangianDensity<C> {
    /// Short name (as the command line spells it, e.g. `"sine-gordon-kink"`).
    fn name(&self) -> &'static str;
    /// Current parameter values, by name.
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter; an unknown name or an out-of-range value is an
    /// [`Error::InvalidParameter`].
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error>;
    /// The spatial domain.
    fn domain(&self) -> Domain;
    /// The boundary condition.
    fn boundary(&self) -> Boundary<C>;
    /// The initial field (u, u_t) at x and t = 0.
    fn initial_field(&self, x: f64) -> (SVector<f64, C>, SVector<f64, C>);
    /// The default number of mesh points in space.
    fn default_points(&self) -> usize;
    /// The default time step Δt.
    fn default_step(&self) -> f64;
    /// The default final time.
    fn default_horizon(&self) -> f64;
}

/// A closed-form solution of the field equation, for error measurements.
pub trait ExactField<const C: usize>: LagrangianDensity<C> {
    /// u(x, t) of the solution whose initial field is [`FieldDefaults::initial_field`] (or of
    /// the model's one solution).
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, C>;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ℒ = ½|u_t|² − ½|u_x|² − u₀u₁ u_x₀ + sin(u₀) u_t₁ with two components: every block of
    /// the Hessian is non-trivial somewhere.
    struct Coupled;

    impl LagrangianDensity<2> for Coupled {
        fn density<D: Scalar>(
            &self,
            x: f64,
            _t: f64,
            u: &SVector<D, 2>,
            u_t: &SVector<D, 2>,
            u_x: &SVector<D, 2>,
        ) -> D {
            (u_t.dot(u_t) - u_x.dot(u_x)) * 0.5 - u[0] * u[1] * u_x[0] + u[0].sin() * u_t[1] * x
        }
    }

    #[test]
    fn gradient_and_hessian_match_the_hand_derivatives() {
        let x = 0.7;
        let jet = Jet {
            u: SVector::from([0.3, -1.1]),
            u_t: SVector::from([0.5, 2.0]),
            u_x: SVector::from([-0.4, 0.9]),
        };
        let g = Coupled.gradient(x, 0.0, &jet);
        let (u, ut, ux) = (jet.u, jet.u_t, jet.u_x);
        let expected_u = [-u[1] * ux[0] + u[0].cos() * ut[1] * x, -u[0] * ux[0]];
        assert!((g.u - SVector::from(expected_u)).amax() < 1e-15);
        assert!((g.u_t - SVector::from([ut[0], ut[1] + u[0].sin() * x])).amax() < 1e-15);
        assert!((g.u_x - SVector::from([-ux[0] - u[0] * u[1], -ux[1]])).amax() < 1e-15);
        let h = Coupled.hessian(x, 0.0, &jet).blocks;
        let uu = SMatrix::<f64, 2, 2>::new(-u[0].sin() * ut[1] * x, -ux[0], -ux[0], 0.0);
        assert!((h[0][0] - uu).amax() < 1e-15);
        // ∂²ℒ/∂u₀∂u_t₁ = cos(u₀) x; ∂²ℒ/∂u_i∂u_x₀ = −u_{1−i}.
        assert!(
            (h[0][1] - SMatrix::<f64, 2, 2>::new(0.0, u[0].cos() * x, 0.0, 0.0)).amax() < 1e-15
        );
        assert!((h[0][2] - SMatrix::<f64, 2, 2>::new(-u[1], 0.0, -u[0], 0.0)).amax() < 1e-15);
        assert_eq!(h[2][0], h[0][2].transpose());
        assert_eq!(h[1][1], SMatrix::<f64, 2, 2>::identity());
        assert_eq!(h[2][2], -SMatrix::<f64, 2, 2>::identity());
        assert_eq!(h[1][2], SMatrix::<f64, 2, 2>::zeros());
    }

    #[test]
    fn an_empty_or_non_finite_domain_is_an_error() {
        assert!(Domain::new(0.0, 1.0).is_ok());
        for (a, b) in [
            (1.0, 1.0),
            (2.0, 1.0),
            (f64::NAN, 1.0),
            (0.0, f64::INFINITY),
        ] {
            match Domain::new(a, b) {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "domain"),
                other => panic!("{other:?}"),
            }
        }
    }
}
