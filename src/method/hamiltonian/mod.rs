//! Methods on Hamilton's equations, for any model: written as H (no Legendre transform at run
//! time) or as L (H's derivatives through the Legendre map, [`crate::model::canonical`]).
//!
//! With g(t, q, p) = ∂H/∂q − f_H(t, q, p), the equations are q̇ = ∂H/∂p, ṗ = −g (the forced
//! Hamiltonian form of [`crate::model::hamiltonian`]). Every method takes H's derivatives
//! through [`crate::model::canonical`] only, so it runs a model written as L on the same
//! equations (the inverse Legendre map started at the last velocity), and states are (q, p)
//! ([`crate::Coordinates::Momentum`]). Each is written once over the dimension N.
//!
//! | method | name | equations | order | symmetric | explicit |
//! | --- | --- | --- | --- | --- | --- |
//! | [`HamiltonianCollocation`] | `sc-h[:P]` | SC's CGL collocation of z' = (∂H/∂p, −g) ([`collocation`]) | P − 1 | no | never |
//! | [`HamiltonianGalerkin`] | `svi-h[:P[/M]]` | the Galerkin discrete right Hamiltonian on SVI's curve and Gauss rule ([`galerkin`]) | 2·min(P − 1, M) | yes | never (SVI's fixed point for H = ½pᵀM⁻¹p + V) |
//! | [`Partitioned::symplectic_euler`] | `symplectic-euler-h` | p_{k+1} = p_k − h g(t_k, q_k, p_{k+1}), q_{k+1} = q_k + h ∂H/∂p(t_k, q_k, p_{k+1}) | 1 | no | separable H, unforced |
//! | [`Partitioned::adjoint_symplectic_euler`] | `symplectic-euler-adjoint-h` | q_{k+1} = q_k + h ∂H/∂p(t_{k+1}, q_{k+1}, p_k), p_{k+1} = p_k − h g(t_{k+1}, q_{k+1}, p_k) | 1 | no | separable H |
//! | [`ImplicitMidpoint`] | `midpoint-h` | z_{k+1} = z_k + h (∂H/∂p, −g)(t_k + h/2, (z_k + z_{k+1})/2), z = (q, p) | 2 | yes | never |
//! | [`Partitioned::stormer_verlet`] | `verlet-h` | the kick–drift–kick below with a = b = ½ | 2 | yes | separable H, unforced |
//! | [`Composition::hamiltonian`] | `yoshida4-h`, `kahan-li6-h`, `kahan-li8-h` | symmetric compositions of `verlet-h` ([`Scheme`]) | 4, 6, 8 | yes | as `verlet-h` |
//!
//! The three partitioned methods are one step with the weights (a, b) of [`Kicks`] (a = 1:
//! symplectic Euler, b = 1: its adjoint, a = b = ½: Störmer–Verlet), t' = t_k + h:
//!
//! P = p_k − a h g(t_k, q_k, P),
//! q_{k+1} = q_k + a h ∂H/∂p(t_k, q_k, P) + b h ∂H/∂p(t', q_{k+1}, P),
//! p_{k+1} = P − b h g(t', q_{k+1}, P)
//!
//! (Hairer, Lubich, Wanner, *Geometric numerical integration*, 2nd ed. 2006, eqs. VI.3.1,
//! VI.3.2 and VI.3.4; Störmer–Verlet is the adjoint symplectic Euler method of step h/2 after
//! the symplectic Euler method of step h/2, §II.3, and the Lobatto IIIA–IIIB pair, §II.2).
//! The first line is implicit in P and the second in q_{k+1}, each solved by Newton's method on
//! N unknowns with H's Hessian blocks (I + a h (∂²H/∂q∂p − ∂f_H/∂p), I − b h (∂²H/∂q∂p)ᵀ).
//! For a separable H = T(p) + V(t, q) ([`crate::model::canonical::structure`]) ∂H/∂q does not
//! depend on p and ∂H/∂p = T′(p) not on (t, q): the step is the explicit kick, drift
//! q_{k+1} = q_k + h T′(P), kick, with any kinetic energy T (a relativistic √(1 + |p|²)
//! included, whose drift is not linear in p), and no Newton iteration and no Hessian without
//! a force. The implicit midpoint rule is implicit in both (Newton's method on 2N unknowns).
//!
//! # Symplecticity
//! Symplectic Euler is the map of the type II generating function (the discrete right
//! Hamiltonian of Leok & Zhang 2011, §2–3) H_d⁺(q_k, p_{k+1}) = p_{k+1}ᵀq_k + h H(t_k, q_k,
//! p_{k+1}), by p_k = ∂H_d⁺/∂q_k, q_{k+1} = ∂H_d⁺/∂p_{k+1}; its adjoint is the map of the
//! discrete left Hamiltonian H_d⁻(p_k, q_{k+1}) = −p_kᵀq_{k+1} + h H(t_{k+1}, q_{k+1}, p_k)
//! (type III); Störmer–Verlet and the compositions are compositions of them; the implicit
//! midpoint rule is symplectic (HLW Theorems VI.3.3–VI.3.5). The tests check JᵀΩJ = Ω on a
//! non-separable H.
//!
//! # Forces
//! f_H enters where ∂H/∂q does, with the same weights: at the kick points (t_k, q_k, P) with a h
//! and (t', q_{k+1}, P) with b h, at the midpoint with h. Through the Legendre map these are
//! the discrete forces f_d^± of the discrete Lagrange–d'Alembert principle of the
//! corresponding segment rules (Marsden & West, *Discrete mechanics and variational
//! integrators*, Acta Numerica 2001, §3.2): symplectic Euler's f_d⁻ = h f_L(t_k, q_k, v), the
//! adjoint's f_d⁺ = h f_L(t', q_{k+1}, v), the midpoint's f_d^± = (h/2) f_L at the midpoint, and
//! Störmer–Verlet's composition of the two half steps — for a constant mass exactly the
//! discrete forces of the trapezoidal L_d that [`crate::StormerVerlet`] uses. A force that
//! depends on p makes the first kick of a separable H implicit in P through f_H alone. With a
//! force no method is symplectic; the orders are unchanged.
//!
//! # Coincidences (tested to round-off)
//! Through the Legendre map v = ∂H/∂p: `symplectic-euler-h` is the variational
//! `symplectic-euler` (L_d = h L(t_k, q_k, v)), `symplectic-euler-adjoint-h` the variational
//! `symplectic-euler-adjoint`, and `midpoint-h` the variational `midpoint`, for every regular
//! L; `verlet-h` is the variational `symplectic-euler-adjoint` of step h/2 after the variational
//! `symplectic-euler` of step h/2, and for a constant mass also the variational `verlet`
//! (trapezoid). For a mass matrix that depends on q the trapezoid's L_d, which holds one
//! velocity on the whole step, gives another map: an O(h³) difference per step.
//!
//! # References
//! Hairer, Lubich, Wanner, *Geometric numerical integration* (2006), §II.2–II.4, §VI.3 and
//! §VI.6; Leok & Zhang, *Discrete Hamiltonian variational integrators*, IMA J. Numer. Anal. 31
//! (2011) 1497–1532; Marsden & West, Acta Numerica (2001), §3.2.
//!
//! [`Composition::hamiltonian`]: crate::method::variational::composition::Composition::hamiltonian
//! [`Scheme`]: crate::method::variational::composition::Scheme
//! [`Kicks`]: crate::method::variational::discrete_lagrangian::Kicks

pub mod collocation;
pub mod galerkin;
pub mod midpoint;
pub mod partitioned;

pub use collocation::HamiltonianCollocation;
pub use galerkin::HamiltonianGalerkin;
pub use midpoint::ImplicitMidpoint;
pub use partitioned::Partitioned;

#[cfg(test)]
mod tests;

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::model::canonical;
use crate::model::derived::cached_mass_inverse;
use crate::model::hamiltonian::CanonicalSecond;
use crate::model::mass_inverse::MassInverse;
use crate::model::{ConstantMass, Lagrangian};
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Two vectors of ℝᴺ: (∂H/∂q, ∂H/∂p), or (g, ∂H/∂p).
type Pair<N> = (OVector<f64, N>, OVector<f64, N>);

/// A derivative of H that could not be taken — the inverse Legendre map of a model written as
/// L did not converge, or its mass matrix is singular — as the failure of the step.
fn failure(error: Error) -> StepFailure {
    match error {
        Error::LegendreMap {
            iterations,
            residual,
            ..
        } if residual.is_finite() => StepFailure::NonConvergence {
            iterations,
            residual,
        },
        Error::LegendreMap { .. } => StepFailure::SingularMatrix,
        _ => StepFailure::NonFinite,
    }
}

/// H's derivatives and f_H at the points of a step, through [`canonical`], counted; the last
/// velocity ∂H/∂p starts the next inverse Legendre map of a model written as L.
#[derive(Debug, Clone)]
struct Derivatives<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Whether the model has a force f_H.
    forced: bool,
    /// ∂H/∂p at the last point: the guess of the next inverse Legendre map.
    velocity: OVector<f64, N>,
    /// Points at which H was differentiated in this step.
    evaluations: usize,
    /// M⁻¹ of a constant-mass model written as L, from the first step: the observers'
    /// q̇ = M⁻¹p.
    mass_inverse: Option<MassInverse<N>>,
}

impl<N: Dimension> Derivatives<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// For `model`, of dimension `n`.
    fn new<L: Lagrangian<N>>(model: &L, n: N) -> Self {
        Derivatives {
            forced: canonical::forced(model),
            velocity: OVector::zeros_generic(n, U1),
            evaluations: 0,
            mass_inverse: None,
        }
    }

    /// Start a step from `(t, q, p)`: the evaluation count reset, M⁻¹ of a constant-mass
    /// model written as L made once.
    fn start<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<(), StepFailure> {
        self.evaluations = 0;
        if ConstantMass::<L, N>::DECLARED && model.hamiltonian_form().is_none() {
            cached_mass_inverse(&mut self.mass_inverse, model, t, q, p)?;
        }
        Ok(())
    }

    /// (∂H/∂q, ∂H/∂p) at (t, q, p).
    fn gradient<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Pair<N>, StepFailure> {
        let (hq, hp) = canonical::gradient(model, t, q, p, &self.velocity).map_err(failure)?;
        self.velocity.copy_from(&hp);
        self.evaluations += 1;
        Ok((hq, hp))
    }

    /// g = ∂H/∂q − f_H and ∂H/∂p at (t, q, p).
    fn field<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Pair<N>, StepFailure> {
        let (mut g, hp) = self.gradient(model, t, q, p)?;
        if self.forced {
            g -= canonical::force(model, t, q, p, &hp).map_err(failure)?;
        }
        Ok((g, hp))
    }

    /// H's gradient and Hessian blocks at (t, q, p).
    fn second<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<CanonicalSecond<N>, StepFailure> {
        let second = canonical::second(model, t, q, p, &self.velocity).map_err(failure)?;
        self.velocity.copy_from(&second.hp);
        self.evaluations += 1;
        Ok(second)
    }

    /// The field (g, ∂H/∂p) at (t, q, p) and its derivatives.
    fn linearised<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Linearised<N>, StepFailure> {
        let CanonicalSecond {
            hq, hp, qq, qp, pp, ..
        } = self.second(model, t, q, p)?;
        let mut field = Linearised {
            g: hq,
            hp,
            gq: qq,
            gp: qp.clone(),
            qp,
            pp,
        };
        if self.forced {
            let (f, fq, fp) =
                canonical::force_jacobian(model, t, q, p, &field.hp).map_err(failure)?;
            field.g -= f;
            field.gq -= fq;
            field.gp -= fp;
        }
        Ok(field)
    }

    /// q̇ = ∂H/∂p into `v` without a solve: H's gradient for a model written as H, M⁻¹p for a
    /// constant-mass one written as L; `false` for any other model.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> bool {
        if let Some(form) = model.hamiltonian_form() {
            v.copy_from(&form.velocity(t, q, p));
            return true;
        }
        match &self.mass_inverse {
            Some(inverse) => {
                inverse.apply_into(p, v);
                true
            }
            None => false,
        }
    }
}

/// The field of Hamilton's equations at a point, q̇ = ∂H/∂p, ṗ = −g with g = ∂H/∂q − f_H,
/// and its derivatives (entry (i, j) = ∂/∂xⱼ of component i, as [`CanonicalSecond`]).
#[derive(Debug, Clone)]
struct Linearised<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// g = ∂H/∂q − f_H.
    g: OVector<f64, N>,
    /// ∂H/∂p.
    hp: OVector<f64, N>,
    /// ∂g/∂q = ∂²H/∂q² − ∂f_H/∂q.
    gq: OMatrix<f64, N, N>,
    /// ∂g/∂p = ∂²H/∂q∂p − ∂f_H/∂p.
    gp: OMatrix<f64, N, N>,
    /// ∂²H/∂q∂p: ∂(∂H/∂p)/∂q is its transpose.
    qp: OMatrix<f64, N, N>,
    /// ∂²H/∂p² = ∂(∂H/∂p)/∂p.
    pp: OMatrix<f64, N, N>,
}

/// Newton's method on `unknown` whose residual may fail: `assemble(z, jacobian, residual)`
/// writes F(z) and F'(z) or returns the failure that stops the solve. Returns the iterations.
fn solve<F>(
    newton: &mut Newton,
    unknown: &mut DVector<f64>,
    mut assemble: F,
) -> Result<usize, StepFailure>
where
    F: FnMut(&DVector<f64>, &mut DMatrix<f64>, &mut DVector<f64>) -> Result<(), StepFailure>,
{
    let mut stopped = None;
    let result = newton.solve(unknown, |z, jacobian, residual| {
        if let Err(failure) = assemble(z, jacobian, residual) {
            stopped.get_or_insert(failure);
            residual.fill(f64::NAN);
        }
    });
    match stopped {
        Some(failure) => Err(failure),
        None => result,
    }
}

/// `a + weight · z` for a vector `z` of Newton's unknowns (the offset of a point from `a`).
fn offset<N: Dimension>(a: &OVector<f64, N>, weight: f64, z: &[f64]) -> OVector<f64, N>
where
    DefaultAllocator: Allocator<N>,
{
    OVector::from_fn_generic(a.shape_generic().0, U1, |i, _| a[i] + weight * z[i])
}

/// The N × N identity plus `weight` times `block`, into the column-major slice `target`.
fn identity_plus<N: Dimension>(weight: f64, block: &OMatrix<f64, N, N>, target: &mut [f64])
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = block.nrows();
    for (k, (target, entry)) in target.iter_mut().zip(block.as_slice()).enumerate() {
        *target = weight * entry + if k % (n + 1) == 0 { 1.0 } else { 0.0 };
    }
}
