//! Lie groups, and Lagrangians written on them (Leok, *Generalized Variational Integrators*,
//! §5.3–5.4, for any group G).
//!
//! # The interface a group implements once
//! A matrix Lie group G of dimension N is stored as E real numbers (the free entries of its
//! matrices: 9 for a rotation, 12 for a rigid motion (R, x), K for a translation of ℝᴷ), and
//! its Lie algebra 𝔤 ≅ ℝᴺ in a fixed basis. [`LieGroup`] asks for
//! - the group operation [`LieGroup::compose`] and the identity, the inverse;
//! - the exponential [`LieGroup::exp`] (and exp − e without cancellation,
//!   [`LieGroup::exp_minus_identity`]) and its chart inverse [`LieGroup::log`];
//! - the right-trivialised derivative of exp, [`LieGroup::dexp`]: with the series
//!   dexp_x = Σ ad_xⁿ/(n + 1)!, d/dt exp(x(t)) = (dexp_x ẋ)^ exp(x) (the paper's
//!   "T_ξ exp = T_e L_exp(ξ) · dexp_ad_ξ" up to the side of the trivialisation, see
//!   [`crate::model::so3`] for the sign), and its inverse [`LieGroup::dexp_inverse`];
//! - the adjoint actions: ad_x y = \[x, y\] ([`LieGroup::ad`]) and Ad_g x = g x̂ g⁻¹
//!   ([`LieGroup::adjoint`]); ad* and Ad* are their transposes;
//! - the hat map x ↦ x̂ into the stored entries ([`LieGroup::hat`]);
//! - [`LieGroup::defect`], how far stored entries are from the group (‖RᵀR − I‖), and
//!   [`LieGroup::chart_reach`], how far an algebra element is towards the edge of the natural
//!   chart (|ω|/π on a rotation factor: beyond 1, log no longer inverts exp).
//!
//! From these, the body velocity of a curve g₀ exp(ξ(t)) is ξ_body = dexp_{−ξ} ξ̇ (the
//! left-trivialised derivative, [`LieGroup::body_velocity`]), and the identities used by the
//! integrator hold on every group: dexp_x = Ad_{exp x} dexp_{−x}, and
//! Ad_{exp x} − I = ad_x dexp_x (both are power series in ad_x).
//!
//! The groups: [`rotations::Rotations`] (SO(3)), [`rigid_motions::RigidMotions`] (SE(3),
//! closed-form exp and dexp), [`translations::Translations`] (ℝᴷ under addition),
//! [`circle::Circle`] (SO(2) ≅ S¹), [`product::Product`] (G₁ × G₂ of any two groups, so
//! SO(3) × ℝ³ and SO(3) × S¹) and [`product::Power`] (Gᴷ, so SO(3)ᴷ).
//!
//! # Adding a group
//! Implement [`LieGroup`] for a marker type in one file (as [`rigid_motions`] does for SE(3);
//! a product or power of existing groups needs no file at all), and add one line to
//! [`registry::GROUPS`] (`entry::<RigidMotions, 6, 12>("…")`, or `named::<…>("SO(3) x S^1",
//! "…")` for a product). The registry's test then runs [`check::check_group`] on it, every
//! identity of the interface at [`check::sample_points`], and `svi list` shows it; a group of
//! one's own outside the crate is checked by calling [`check::check_group`] directly.
//!
//! # Lagrangians on a group
//! A [`GroupLagrangian`] is one function L(g, ξ) of the configuration g ∈ G and the body
//! velocity ξ = (g⁻¹ġ)^∨ ∈ 𝔤, generic over [`Scalar`]; [`GroupLagrangianExt`] derives the
//! momentum μ = ∂L/∂ξ (left-trivialised), its inverse (the Legendre map), the energy
//! μ·ξ − L and the configuration gradient d/dε L(g exp(εζ), ξ).

pub mod check;
pub mod circle;
pub mod defaults;
pub mod derivatives;
pub mod pair_terms;
pub mod product;
pub mod registry;
pub mod rigid_motions;
pub mod rotations;
pub mod symmetries;
pub mod translations;

use crate::error::Error;
use crate::linalg::solve_small;
use crate::scalar::Scalar;
pub use defaults::GroupDefaults;
pub use derivatives::{LocalDerivatives, VelocityDerivatives};
use nalgebra::{SMatrix, SVector};
use std::fmt::Debug;
pub use symmetries::GroupSymmetries;

/// A matrix Lie group of dimension `N` whose elements are stored as `E` numbers (see the
/// module docs for the conventions). Implemented by marker types; every function is an
/// associated function, generic over the scalar where the integrator differentiates through
/// it.
pub trait LieGroup<const N: usize, const E: usize>:
    Copy + Debug + Default + PartialEq + Send + Sync + 'static
{
    /// The group's name in reports (`"SO(3)"`).
    const NAME: &'static str;

    /// The identity element e.
    fn identity<D: Scalar>() -> SVector<D, E>;

    /// The product g h.
    fn compose<D: Scalar>(g: &SVector<D, E>, h: &SVector<D, E>) -> SVector<D, E>;

    /// The inverse g⁻¹.
    fn inverse(g: &SVector<f64, E>) -> SVector<f64, E>;

    /// exp(x) − e, without cancellation for small x.
    fn exp_minus_identity<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E>;

    /// The exponential map 𝔤 → G.
    #[inline]
    fn exp<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        Self::exp_minus_identity(x) + Self::identity()
    }

    /// A curve through e that agrees with exp to second order at 0 (e + x̂ + ½x̂² for a matrix
    /// group): the integrator differentiates L(g exp(ζ), ξ) twice at ζ = 0 through it, so a
    /// cheaper form than exp saves dual arithmetic. The default is exp itself.
    #[inline]
    fn exp_second_order<D: Scalar>(x: &SVector<D, N>) -> SVector<D, E> {
        Self::exp(x)
    }

    /// The chart inverse of exp at the identity: x with exp(x) = g and
    /// [`LieGroup::chart_reach`]`(x) ≤ 1`.
    fn log(g: &SVector<f64, E>) -> SVector<f64, N>;

    /// g (e + δ) − g for a difference δ of two elements: the increment of g under a step
    /// g ↦ g exp(x) with δ = exp(x) − e, formed without the cancellation of
    /// `compose(g, e + δ) − g` (linear in δ for a matrix group).
    fn translate_difference(g: &SVector<f64, E>, delta: &SVector<f64, E>) -> SVector<f64, E>;

    /// The hat map x ↦ x̂ into the stored entries (the derivative of exp at 0 in the
    /// direction x).
    fn hat(x: &SVector<f64, N>) -> SVector<f64, E>;

    /// ad_x, the matrix of y ↦ \[x, y\].
    fn ad<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N>;

    /// Ad_g, the matrix of x ↦ (g x̂ g⁻¹)^∨.
    fn adjoint(g: &SVector<f64, E>) -> SMatrix<f64, N, N>;

    /// dexp_x = Σ ad_xⁿ/(n + 1)!, the right-trivialised derivative of exp.
    fn dexp<D: Scalar>(x: &SVector<D, N>) -> SMatrix<D, N, N>;

    /// The inverse of [`LieGroup::dexp`] (inside the natural chart).
    fn dexp_inverse(x: &SVector<f64, N>) -> SMatrix<f64, N, N>;

    /// The body velocity dexp_{−x} ẋ of the curve exp(x(t)) (override where a product is
    /// cheaper than the matrix).
    #[inline]
    fn body_velocity<D: Scalar>(x: &SVector<D, N>, rate: &SVector<D, N>) -> SVector<D, N> {
        Self::dexp(&(-x)) * rate
    }

    /// How far the stored entries are from the group (‖RᵀR − I‖ in the Frobenius norm for
    /// each rotation factor, the largest of them; 0 for a translation); `f64::INFINITY`
    /// for entries that are not in the group's component of the identity (det R < 0).
    fn defect(g: &SVector<f64, E>) -> f64;

    /// How far x is towards the edge of the natural chart, as a fraction: below 1, exp is
    /// invertible by [`LieGroup::log`] near x (|ω|/π for each rotation part ω, the largest;
    /// 0 for a translation).
    fn chart_reach(x: &SVector<f64, N>) -> f64;

    /// The derivatives of the body velocity W(a, b) = dexp_{−a} b that a step's chain rule
    /// needs, contracted with λ and ν ([`derivatives`]), into `out`; only (∂W/∂a)ᵀν unless
    /// `second`.
    /// The default differentiates [`LieGroup::body_velocity`] densely; override it where the
    /// group has structure (a power does it factor by factor).
    #[inline]
    fn velocity_derivatives(
        a: &SVector<f64, N>,
        b: &SVector<f64, N>,
        lambda: &SVector<f64, N>,
        nu: &SVector<f64, N>,
        second: bool,
        out: &mut VelocityDerivatives<N>,
    ) {
        derivatives::dense_velocity_derivatives::<Self, N, E>(a, b, lambda, nu, second, out);
    }

    /// ∂(dexp_xᵀ v)/∂x. The default differentiates [`LieGroup::dexp`] densely.
    #[inline]
    fn dexp_transpose_jacobian(x: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        derivatives::dense_dexp_transpose_jacobian::<Self, N, E>(x, v)
    }
}

/// A Lagrangian L(g, ξ) on the tangent bundle of a Lie group `G`, left-trivialised: g ∈ G
/// is the configuration and ξ = (g⁻¹ġ)^∨ the body velocity.
///
/// ```
/// use nalgebra::SVector;
/// use svi::Scalar;
/// use svi::model::group::GroupLagrangian;
/// use svi::model::group::rigid_motions::RigidMotions;
///
/// /// A rigid body of mass 2 and inertia diag(1, 2, 3), falling freely (g = 9.81 along −z).
/// struct Falling;
/// impl GroupLagrangian<6, 12> for Falling {
///     type Group = RigidMotions;
///     fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
///         let kinetic = (xi[0] * xi[0] + xi[1] * xi[1] * 2.0 + xi[2] * xi[2] * 3.0) * 0.5
///             + (xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]);
///         kinetic - RigidMotions::position(g)[2] * (2.0 * 9.81)
///     }
/// }
/// ```
pub trait GroupLagrangian<const N: usize, const E: usize> {
    /// The group G.
    type Group: LieGroup<N, E>;

    /// Whether L(g, ξ) = L(e, ξ) for every g (invariance under the left action of the whole
    /// group); `true` allows the reduced Euler–Poincaré form (§5.4). The default (`false`) is
    /// always correct; the stepping loop checks a `true` at the initial state.
    const G_INVARIANT: bool = false;

    /// Whether the model supplies its own [`GroupLagrangian::local_gradient`] and
    /// [`GroupLagrangian::local_hessian`] (and its group its own
    /// [`LieGroup::velocity_derivatives`] and [`LieGroup::dexp_transpose_jacobian`]) without
    /// dense dual numbers of the group's dimension, as [`pair_terms`] does: then groups
    /// beyond [`crate::method::lie_svi::MAX_GROUP_DIMENSION`] run. Default `false`.
    const STRUCTURED: bool = false;

    /// Whether the model has a non-conservative force
    /// ([`GroupLagrangian::external_force`]); `false` (the default) skips it entirely.
    const FORCED: bool = false;

    /// The value L(g, ξ). Mark it `#[inline]`: the integrator evaluates it with dual numbers
    /// in its inner loop.
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, E>, xi: &SVector<D, N>) -> D;

    /// The non-conservative generalised force f(t, g, ξ) ∈ 𝔤* in the body frame (Lagrange–
    /// d'Alembert on the group): its virtual work on a variation g exp(εζ) is ⟨f, ζ⟩. On SO(3)
    /// it is the body torque; on SE(3) (ω, v) a torque and a force, both in the body frame (a
    /// spatial force F at the body origin is Rᵀ F in the force slots; a spatial torque T is
    /// Rᵀ T). Generic over the scalar: the integrator differentiates it. Read only when
    /// [`GroupLagrangian::FORCED`] is `true`; the default is zero.
    fn external_force<D: Scalar>(
        &self,
        t: D,
        g: &SVector<D, E>,
        xi: &SVector<D, N>,
    ) -> SVector<D, N> {
        let _ = (t, g, xi);
        SVector::zeros()
    }

    /// Checks the model's structure before a run (a [`pair_terms`] model's factor indices,
    /// [`pair_terms::check_factors`]); a wrong one is a typed error, not a panic in the
    /// step. The default has nothing to check.
    fn check_structure(&self) -> Result<(), Error> {
        Ok(())
    }

    /// λ = d/dε L(g exp(εζ), w) (the left-trivialised configuration gradient; zero without
    /// `configuration`) and ν = ∂L/∂ξ at (g, w) ([`derivatives`]). The default
    /// differentiates L densely; a Lagrangian with structure (terms on pairs of factors of a
    /// power, [`pair_terms`]) overrides this and [`GroupLagrangian::local_hessian`].
    #[inline]
    fn local_gradient(
        &self,
        g: &SVector<f64, E>,
        w: &SVector<f64, N>,
        configuration: bool,
    ) -> (SVector<f64, N>, SVector<f64, N>) {
        derivatives::dense_local_gradient(self, g, w, configuration)
    }

    /// The gradient and Hessian blocks of L̂(ζ, w) = L(g exp(ζ), w) at ζ = 0 into `out` (only
    /// ν and ww without `configuration`, the rest zero). The default differentiates L densely, with N + N dual
    /// directions per number: groups of dimension above
    /// [`crate::method::lie_svi::MAX_GROUP_DIMENSION`] need an override
    /// ([`GroupLagrangian::STRUCTURED`]).
    #[inline]
    fn local_hessian(
        &self,
        g: &SVector<f64, E>,
        w: &SVector<f64, N>,
        configuration: bool,
        out: &mut LocalDerivatives<N>,
    ) {
        derivatives::dense_local_hessian(self, g, w, configuration, out);
    }
}

/// Iteration cap of the inverse Legendre map.
const LEGENDRE_MAX_ITERATIONS: usize = 50;

/// Quantities derived from a [`GroupLagrangian`] by automatic differentiation. Implemented
/// for every Lagrangian on a group.
pub trait GroupLagrangianExt<const N: usize, const E: usize>: GroupLagrangian<N, E> {
    /// L(g, ξ).
    #[inline]
    fn value(&self, g: &SVector<f64, E>, xi: &SVector<f64, N>) -> f64 {
        self.lagrangian(g, xi)
    }

    /// The left-trivialised momentum μ = ∂L/∂ξ.
    #[inline]
    fn momentum(&self, g: &SVector<f64, E>, xi: &SVector<f64, N>) -> SVector<f64, N> {
        self.local_gradient(g, xi, false).1
    }

    /// The energy μ·ξ − L.
    #[inline]
    fn energy(&self, g: &SVector<f64, E>, xi: &SVector<f64, N>) -> f64 {
        self.momentum(g, xi).dot(xi) - self.lagrangian(g, xi)
    }

    /// The left-trivialised configuration gradient τ with τ·ζ = d/dε L(g exp(εζ), ξ) at
    /// ε = 0 (the generalised force of a potential, in the body frame).
    #[inline]
    fn configuration_gradient(&self, g: &SVector<f64, E>, xi: &SVector<f64, N>) -> SVector<f64, N> {
        self.local_gradient(g, xi, true).0
    }

    /// The inverse Legendre map: ξ with ∂L/∂ξ(g, ξ) = μ, by Newton's method from `guess`
    /// (one iteration is exact for a Lagrangian quadratic in ξ).
    fn velocity(
        &self,
        g: &SVector<f64, E>,
        momentum: &SVector<f64, N>,
        guess: &SVector<f64, N>,
    ) -> Result<SVector<f64, N>, Error> {
        let mut local = LocalDerivatives::zeros();
        invert_momentum(momentum, guess, |xi| {
            self.local_hessian(g, xi, false, &mut local);
            (local.nu, local.ww)
        })
    }
}

/// Solves ∂L/∂ξ = `momentum` for ξ by Newton's method from `guess`, where `derivatives(ξ)`
/// gives ∂L/∂ξ and ∂²L/∂ξ² (the inverse Legendre map of a Lagrangian on a group; SO(3)'s
/// rigid bodies use it too). It stops at an increment of ε relative, or when the increments
/// stop decreasing below 1e-10 relative; a singular ∂²L/∂ξ² or no convergence in
/// [`LEGENDRE_MAX_ITERATIONS`] is an [`Error::LegendreMap`] (with t = NaN: the caller knows
/// the time).
pub(crate) fn invert_momentum<const N: usize>(
    momentum: &SVector<f64, N>,
    guess: &SVector<f64, N>,
    mut derivatives: impl FnMut(&SVector<f64, N>) -> (SVector<f64, N>, SMatrix<f64, N, N>),
) -> Result<SVector<f64, N>, Error> {
    let mut xi = *guess;
    let mut last = f64::INFINITY;
    let failure = |iterations, residual| Error::LegendreMap {
        t: f64::NAN,
        iterations,
        residual,
    };
    for iteration in 1..=LEGENDRE_MAX_ITERATIONS {
        let (current, inertia) = derivatives(&xi);
        let delta = solve_small(inertia, momentum - current)
            .ok_or_else(|| failure(iteration, f64::INFINITY))?;
        xi += delta;
        let size = delta.amax();
        if !size.is_finite() {
            break;
        }
        let scale = 1.0 + xi.amax();
        if size <= f64::EPSILON * scale || (size >= last && size <= 1e-10 * scale) {
            return Ok(xi);
        }
        last = size;
    }
    Err(failure(LEGENDRE_MAX_ITERATIONS, last))
}

impl<const N: usize, const E: usize, T: GroupLagrangian<N, E> + ?Sized> GroupLagrangianExt<N, E>
    for T
{
}
