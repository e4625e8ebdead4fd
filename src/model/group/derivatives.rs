//! The derivatives a Lie-group variational step needs, split into the model's part and the
//! group's part so that a structured model or group can supply its own (the defaults here
//! differentiate the whole L or W densely with num-dual).
//!
//! - The model's part is the local Lagrangian L̂(ζ, w) = L(g exp(ζ), w) at ζ = 0: its gradient
//!   (λ = ∂L̂/∂ζ, the left-trivialised configuration gradient, and ν = ∂L̂/∂w = μ, the
//!   momentum) and its Hessian blocks ζζ, ζw and ww ([`LocalDerivatives`];
//!   [`super::GroupLagrangian::local_gradient`], [`super::GroupLagrangian::local_hessian`]).
//!   The curve e + x̂ + ½x̂² ([`LieGroup::exp_second_order`]) stands in for exp: it agrees to
//!   second order.
//! - The group's part is the body velocity W(a, b) = dexp_{−a} b of the curve exp(a(τ)):
//!   (∂W/∂a)ᵀν, the Jacobian ∂W/∂a, and the Hessians of ⟨ν, W(a + α, b)⟩ + ½⟨λ, W(a + α, α)⟩
//!   in α and of ⟨ν, W(a + α, b + β)⟩ in (α, β) ([`VelocityDerivatives`];
//!   [`LieGroup::velocity_derivatives`]), and the derivative of dexp_xᵀv in x
//!   ([`LieGroup::dexp_transpose_jacobian`]).
//!
//! The Lie-SVI step combines them by the chain rule (`crate::method::lie_svi`). Dense
//! defaults carry N + N dual directions per number, so their stack use grows like N³; a
//! power of a group ([`super::product::Power`]) splits the group's part by factor, and a
//! Lagrangian written as a sum of terms on pairs of factors
//! ([`super::pair_terms::PairTerms`]) splits the model's part by term.

use super::{GroupLagrangian, LieGroup};
use nalgebra::{Const, SMatrix, SVector};
use num_dual::{DualSVec64, DualVec, HyperDualVec, gradient, jacobian, partial_hessian};

/// A hyper-dual number with N first-derivative directions on each side.
pub(crate) type Mixed<const N: usize> = HyperDualVec<f64, Const<N>, Const<N>>;

/// The same variable seeded on both sides: x + y − x₀ has x's first directions, y's second
/// ones and the real part x₀.
#[inline]
pub(crate) fn both<const N: usize>(
    x: &SVector<Mixed<N>, N>,
    y: &SVector<Mixed<N>, N>,
    value: &SVector<f64, N>,
) -> SVector<Mixed<N>, N> {
    x + y - value.map(Mixed::from_re)
}

/// The gradient and Hessian blocks of the local Lagrangian L̂(ζ, w) = L(g exp(ζ), w) at ζ = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalDerivatives<const N: usize> {
    /// λ = ∂L̂/∂ζ (zero when the configuration is not asked for).
    pub lambda: SVector<f64, N>,
    /// ν = ∂L̂/∂w, the momentum.
    pub nu: SVector<f64, N>,
    /// ∂²L̂/∂ζ² (zero when the configuration is not asked for).
    pub zz: SMatrix<f64, N, N>,
    /// ∂²L̂/∂ζ∂w, rows ζ (zero when the configuration is not asked for).
    pub zw: SMatrix<f64, N, N>,
    /// ∂²L̂/∂w².
    pub ww: SMatrix<f64, N, N>,
}

impl<const N: usize> LocalDerivatives<N> {
    /// All zero.
    pub fn zeros() -> Self {
        LocalDerivatives {
            lambda: SVector::zeros(),
            nu: SVector::zeros(),
            zz: SMatrix::zeros(),
            zw: SMatrix::zeros(),
            ww: SMatrix::zeros(),
        }
    }
}

/// Derivatives of the body velocity W(a, b) = dexp_{−a} b, contracted with λ and ν (module
/// docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityDerivatives<const N: usize> {
    /// (∂W/∂a)ᵀν.
    pub pulled: SVector<f64, N>,
    /// ∂W/∂a (zero unless second derivatives are asked for).
    pub rate: SMatrix<f64, N, N>,
    /// The Hessian in α of ⟨ν, W(a + α, b)⟩ + ½⟨λ, W(a + α, α)⟩.
    pub curvature: SMatrix<f64, N, N>,
    /// The mixed Hessian in (α, β) of ⟨ν, W(a + α, b + β)⟩, rows α.
    pub twist: SMatrix<f64, N, N>,
}

impl<const N: usize> VelocityDerivatives<N> {
    /// All zero.
    pub fn zeros() -> Self {
        VelocityDerivatives {
            pulled: SVector::zeros(),
            rate: SMatrix::zeros(),
            curvature: SMatrix::zeros(),
            twist: SMatrix::zeros(),
        }
    }
}

/// λ and ν of L̂ at (0, w) by two first-order dual evaluations of L (λ = 0 without
/// `configuration`): the default of [`super::GroupLagrangian::local_gradient`].
pub fn dense_local_gradient<L: GroupLagrangian<N, E> + ?Sized, const N: usize, const E: usize>(
    model: &L,
    g: &SVector<f64, E>,
    w: &SVector<f64, N>,
    configuration: bool,
) -> (SVector<f64, N>, SVector<f64, N>) {
    type D<const N: usize> = DualSVec64<N>;
    let lifted = g.map(D::<N>::from_re);
    let (_, nu) = gradient(|x: SVector<D<N>, N>| model.lagrangian(&lifted, &x), w);
    if !configuration {
        return (SVector::zeros(), nu);
    }
    let velocity = w.map(D::<N>::from_re);
    let (_, lambda) = gradient(
        |z: SVector<D<N>, N>| {
            model.lagrangian(
                &L::Group::compose(&lifted, &L::Group::exp_second_order(&z)),
                &velocity,
            )
        },
        &SVector::zeros(),
    );
    (lambda, nu)
}

/// λ, ν and the blocks of L̂ at (0, w) by three hyper-dual evaluations of L (one, for ν and
/// ww, without `configuration`, the other fields then zero) into `out`: the default of
/// [`super::GroupLagrangian::local_hessian`].
pub fn dense_local_hessian<L: GroupLagrangian<N, E> + ?Sized, const N: usize, const E: usize>(
    model: &L,
    g: &SVector<f64, E>,
    w: &SVector<f64, N>,
    configuration: bool,
    out: &mut LocalDerivatives<N>,
) {
    let zero = SVector::<f64, N>::zeros();
    let lift = |v: &SVector<f64, N>| v.map(Mixed::from_re);
    let base = g.map(Mixed::<N>::from_re);
    let local = |z: &SVector<Mixed<N>, N>, v: &SVector<Mixed<N>, N>| {
        model.lagrangian(&L::Group::compose(&base, &L::Group::exp_second_order(z)), v)
    };
    let (_, nu, _, ww) = if configuration {
        partial_hessian(|(x, y)| local(&lift(&zero), &both(&x, &y, w)), (w, w))
    } else {
        partial_hessian(|(x, y)| model.lagrangian(&base, &both(&x, &y, w)), (w, w))
    };
    out.nu = nu;
    out.ww = ww;
    out.lambda.fill(0.0);
    out.zz.fill(0.0);
    out.zw.fill(0.0);
    if configuration {
        let (_, lambda, _, zz) = partial_hessian(
            |(x, y)| local(&both(&x, &y, &zero), &lift(w)),
            (&zero, &zero),
        );
        let (_, _, _, zw) = partial_hessian(|(x, y)| local(&x, &y), (&zero, w));
        out.lambda = lambda;
        out.zz = zz;
        out.zw = zw;
    }
}

/// The derivatives of W by num-dual (one first-order evaluation; with `second`, one more and
/// two hyper-dual ones) into `out` (the second-order fields only with `second`): the default
/// of [`LieGroup::velocity_derivatives`].
pub fn dense_velocity_derivatives<G: LieGroup<N, E>, const N: usize, const E: usize>(
    a: &SVector<f64, N>,
    b: &SVector<f64, N>,
    lambda: &SVector<f64, N>,
    nu: &SVector<f64, N>,
    second: bool,
    out: &mut VelocityDerivatives<N>,
) {
    type D<const N: usize> = DualSVec64<N>;
    let (b_dual, nu_dual) = (b.map(D::<N>::from_re), nu.map(D::<N>::from_re));
    out.pulled = gradient(
        |x: SVector<D<N>, N>| nu_dual.dot(&G::body_velocity(&x, &b_dual)),
        a,
    )
    .1;
    if !second {
        return;
    }
    out.rate = jacobian(|x: SVector<D<N>, N>| G::body_velocity(&x, &b_dual), a).1;
    let zero = SVector::<f64, N>::zeros();
    let lift = |v: &SVector<f64, N>| v.map(Mixed::<N>::from_re);
    let (a_lift, b_lift, lambda_lift, nu_lift) = (lift(a), lift(b), lift(lambda), lift(nu));
    out.curvature = partial_hessian(
        |(x, y)| {
            let alpha = x + y;
            let moved = a_lift + alpha;
            nu_lift.dot(&G::body_velocity(&moved, &b_lift))
                + lambda_lift.dot(&G::body_velocity(&moved, &alpha)) * 0.5
        },
        (&zero, &zero),
    )
    .3;
    out.twist = partial_hessian(
        |(x, y)| nu_lift.dot(&G::body_velocity(&(a_lift + x), &(b_lift + y))),
        (&zero, &zero),
    )
    .3;
}

/// ∂(dexp_xᵀ v)/∂x by one first-order dual evaluation: the default of
/// [`LieGroup::dexp_transpose_jacobian`].
pub fn dense_dexp_transpose_jacobian<G: LieGroup<N, E>, const N: usize, const E: usize>(
    x: &SVector<f64, N>,
    v: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    jacobian(
        |y: SVector<DualSVec64<N>, N>| G::dexp(&y).transpose() * v.map(DualVec::from_re),
        x,
    )
    .1
}
