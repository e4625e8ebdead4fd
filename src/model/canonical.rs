//! The Hamiltonian side of any model: H(t, q, p), its derivatives and the force f_H, for the
//! Hamiltonian methods ([`crate::method::hamiltonian`]).
//!
//! A model written as H ([`crate::model::hamiltonian::Canonical`]) answers from H itself, by
//! automatic differentiation ([`Lagrangian::hamiltonian_form`]). A model written as L is
//! run through the Legendre map: with q̇ = v(t, q, p) the solution of ∂L/∂q̇ = p (Newton's
//! method, [`LagrangianExt::velocity`]) and W = (∂²L/∂q̇²)⁻¹,
//!
//! - H = p·q̇ − L, ∂H/∂q = −∂L/∂q, ∂H/∂p = q̇;
//! - ∂²H/∂p² = W, ∂²H/∂q∂p = −L_qq̇ W (entry (i, j) = ∂²H/∂qᵢ∂pⱼ = ∂vⱼ/∂qᵢ, from
//!   differentiating ∂L/∂q̇(q, v(q, p)) = p), ∂²H/∂q² = −L_qq + L_qq̇ W L_qq̇ᵀ;
//! - f_H(t, q, p) = f_L(t, q, v(q, p)), ∂f_H/∂p = ∂f_L/∂q̇ W,
//!   ∂f_H/∂q = ∂f_L/∂q − ∂f_L/∂q̇ W L_qq̇ᵀ.
//!
//! so a hyperregular Lagrangian runs on the Hamiltonian methods unchanged.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::invert_small;
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::model::hamiltonian::{CanonicalSecond, HamiltonianStructure};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OMatrix, OVector};

/// The structure of H that a method may exploit: the declared one of a model written as H;
/// for a model written as L, [`HamiltonianStructure::QuadraticKinetic`] for a constant mass
/// and [`HamiltonianStructure::General`] otherwise.
pub fn structure<L: Lagrangian<N> + ?Sized, N: Dimension>(model: &L) -> HamiltonianStructure
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match model.hamiltonian_form() {
        Some(form) => form.structure(),
        None if L::STRUCTURE == crate::model::Structure::ConstantMass => {
            HamiltonianStructure::QuadraticKinetic
        }
        None => HamiltonianStructure::General,
    }
}

/// The velocity q̇ = ∂H/∂p at (t, q, p): H's gradient, or the inverse Legendre map of L
/// started at `guess`.
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge.
pub fn velocity<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<OVector<f64, N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match model.hamiltonian_form() {
        Some(form) => Ok(form.velocity(t, q, p)),
        None => model.velocity(t, q, p, guess),
    }
}

/// ∂H/∂q alone at (t, q, p): one sweep for a model written as H, else the first half of
/// [`gradient`].
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge.
pub fn position_gradient<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<OVector<f64, N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match model.hamiltonian_form() {
        Some(form) => Ok(form.position_gradient(t, q, p)),
        None => gradient(model, t, q, p, guess).map(|(hq, _)| hq),
    }
}

/// (∂H/∂q, ∂H/∂p) at (t, q, p); `guess` starts the inverse Legendre map of a model written
/// as L.
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge.
#[allow(clippy::type_complexity)]
pub fn gradient<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<(OVector<f64, N>, OVector<f64, N>), Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(form) = model.hamiltonian_form() {
        return Ok(form.gradient(t, q, p));
    }
    let v = model.velocity(t, q, p, guess)?;
    Ok((-model.force(t, q, &v), v))
}

/// H(t, q, p).
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge.
pub fn value<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<f64, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(form) = model.hamiltonian_form() {
        return Ok(form.value(t, q, p));
    }
    let v = model.velocity(t, q, p, guess)?;
    Ok(p.dot(&v) - model.lagrangian(t, q, &v))
}

/// H with its gradient and Hessian blocks at (t, q, p).
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge or its mass
/// matrix is singular.
pub fn second<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<CanonicalSecond<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(form) = model.hamiltonian_form() {
        return Ok(form.second(t, q, p));
    }
    let v = model.velocity(t, q, p, guess)?;
    let l = model.second_derivatives(t, q, &v);
    let w = invert_small(&l.vv).ok_or(Error::LegendreMap {
        t,
        iterations: 0,
        residual: f64::INFINITY,
    })?;
    let qp = -(&l.qv * &w);
    let qq = -&l.qq + &l.qv * &w * l.qv.transpose();
    Ok(CanonicalSecond {
        value: p.dot(&v) - l.value,
        hq: -l.q,
        hp: v,
        qq,
        qp,
        pp: w,
    })
}

/// Whether the model has a non-conservative force.
pub fn forced<L: Lagrangian<N> + ?Sized, N: Dimension>(model: &L) -> bool
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model
        .hamiltonian_form()
        .map_or(L::FORCED, |form| form.forced())
}

/// f_H(t, q, p).
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge.
pub fn force<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<OVector<f64, N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(form) = model.hamiltonian_form() {
        return Ok(form.force(t, q, p));
    }
    let v = model.velocity(t, q, p, guess)?;
    Ok(model.external_force_jacobian(t, q, &v).value)
}

/// f_H(t, q, p) with (∂f_H/∂q, ∂f_H/∂p).
///
/// # Errors
/// [`Error::LegendreMap`] where the inverse Legendre map of L does not converge or its mass
/// matrix is singular.
#[allow(clippy::type_complexity)]
pub fn force_jacobian<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    p: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Result<(OVector<f64, N>, OMatrix<f64, N, N>, OMatrix<f64, N, N>), Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(form) = model.hamiltonian_form() {
        let (fq, fp) = form.force_jacobian(t, q, p);
        return Ok((form.force(t, q, p), fq, fp));
    }
    let v = model.velocity(t, q, p, guess)?;
    let l = model.second_derivatives(t, q, &v);
    let w = invert_small(&l.vv).ok_or(Error::LegendreMap {
        t,
        iterations: 0,
        residual: f64::INFINITY,
    })?;
    let f = model.external_force_jacobian(t, q, &v);
    let fp = &f.v * &w;
    let fq = &f.q - &fp * l.qv.transpose();
    Ok((f.value, fq, fp))
}
