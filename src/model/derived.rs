//! Quantities derived from a [`Lagrangian`] by automatic differentiation.
//!
//! Nothing here is written per model: every quantity comes from the one generic function
//! [`Lagrangian::lagrangian`] evaluated with num-dual's dual numbers.
//!
//! Which dual numbers carry the derivatives is the dimension's choice
//! ([`crate::dimension::Dimension`]: vector duals for a fixed N, scalar sweeps for a run-time
//! one); what is derived, and how, is written here once for both:
//!
//! - first derivatives ∂L/∂q and p = ∂L/∂q̇ (one gradient each);
//! - the Hessian blocks L_qq, L_qv, L_vv: for N ≤ [`SCALAR_HESSIAN_UP_TO`], and for a
//!   run-time N, one sweep of the scalar `HyperDual64` per Hessian entry in (q, q̇) (three
//!   times faster for small N), else a Hessian in q, one in q̇ and the mixed block (`2N` is
//!   not a const expression on stable Rust, so the full second derivative is assembled from
//!   three N-sized sweeps; two for [`Structure::ConstantMass`], whose mixed block is zero);
//! - the energy E = p·q̇ − L and the inverse Legendre map q̇(q, p) (Newton with L_vv);
//! - the Euler–Lagrange acceleration q̈ = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L) (Li–Wu–Leok
//!   eq. 2 solved for q̈, the right-hand side f of eq. 12; the external force f_L of the
//!   Lagrange–d'Alembert principle enters only for [`Lagrangian::FORCED`] models) and its
//!   exact Jacobian in (q, q̇), obtained by evaluating the acceleration itself with dual
//!   numbers (third derivatives of L, and first derivatives of f_L, through nested duals).
//!   L_vt is computed only for time-dependent Lagrangians;
//! - the external force f_L and its Jacobian ∂f_L/∂q, ∂f_L/∂q̇ (two N-sized sweeps).
//!
//! The methods live on the blanket extension trait [`LagrangianExt`], implemented for every
//! [`Lagrangian`].

use crate::dimension::{Dimension, PhaseFunction, PhaseMap, Wrt};
use crate::error::Error;
use crate::linalg::solve_small;
use crate::model::mass_inverse::MassInverse;
use crate::model::{Lagrangian, Structure, Symmetries, TermSum};
use crate::model::{euler_lagrange, legendre};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OMatrix, OVector, U1};
use num_dual::{Dual64, HyperDual64};

/// Largest fixed dimension whose Hessian blocks are taken as one scalar hyper-dual sweep per
/// entry in (q, q̇), (2N)(2N + 1)/2 sweeps, rather than three vector sweeps: 138 ns against
/// 411 ns for the spring pendulum, 64 against 149 for Kepler, but 1.6 µs against 0.56 µs for
/// the coupled chain of three pendulums (`cargo bench --bench derivatives`, run with this
/// constant at 0, 2 and 4).
pub const SCALAR_HESSIAN_UP_TO: usize = 2;

/// L as a [`PhaseFunction`], for the sweeps of [`Dimension`].
struct Action<'a, L: ?Sized>(&'a L);

impl<L: Lagrangian<N> + ?Sized, N: Dimension> PhaseFunction<N> for Action<'_, L>
where
    DefaultAllocator: Allocator<N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> S {
        self.0.lagrangian(t, q, v)
    }
}

/// The external force f_L as a [`PhaseMap`].
struct ExternalForce<'a, L: ?Sized>(&'a L);

impl<L: Lagrangian<N> + ?Sized, N: Dimension> PhaseMap<N> for ExternalForce<'_, L>
where
    DefaultAllocator: Allocator<N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> OVector<S, N> {
        self.0.external_force(t, q, v)
    }
}

/// The Euler–Lagrange acceleration as a [`PhaseMap`] (NaN where L_vv is singular).
struct Acceleration<'a, L: ?Sized>(&'a L);

impl<L: Lagrangian<N> + ?Sized, N: Dimension> PhaseMap<N> for Acceleration<'_, L>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> OVector<S, N> {
        acceleration_generic(self.0, t, q, v).unwrap_or_else(|| {
            OVector::from_element_generic(q.shape_generic().0, U1, S::from(f64::NAN))
        })
    }
}

/// L, its gradients and Hessian blocks by (2N)(2N + 1)/2 sweeps of the scalar hyper-dual
/// number `HyperDual64`, one per entry (i ≤ j) of the Hessian in x = (q, q̇): the sweep seeded
/// with ε₁ on xᵢ and ε₂ on xⱼ carries ∂²L/∂xᵢ∂xⱼ in its ε₁ε₂ part, and with i = j also
/// ∂L/∂xᵢ in ε₁. Used for N ≤ [`SCALAR_HESSIAN_UP_TO`] and for run-time dimensions.
#[inline]
fn scalar_second_derivatives<L, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
) -> SecondDerivatives<N>
where
    L: Lagrangian<N> + ?Sized,
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (dim, _) = q.shape_generic();
    let n = dim.value();
    let mut d = SecondDerivatives::zeros(dim);
    let seed = |k: usize, x: f64, i: usize, j: usize| {
        HyperDual64::new(
            x,
            if k == i { 1.0 } else { 0.0 },
            if k == j { 1.0 } else { 0.0 },
            0.0,
        )
    };
    for i in 0..2 * n {
        for j in i..2 * n {
            let x = OVector::from_fn_generic(dim, U1, |k, _| seed(k, q[k], i, j));
            let y = OVector::from_fn_generic(dim, U1, |k, _| seed(k + n, v[k], i, j));
            let l = model.lagrangian(HyperDual64::from_re(t), &x, &y);
            let second = l.eps1eps2;
            if i == j {
                d.value = l.re;
                if i < n {
                    d.q[i] = l.eps1;
                } else {
                    d.v[i - n] = l.eps1;
                }
            }
            match (i < n, j < n) {
                (true, true) => {
                    d.qq[(i, j)] = second;
                    d.qq[(j, i)] = second;
                }
                (true, false) => d.qv[(i, j - n)] = second,
                _ => {
                    d.vv[(i - n, j - n)] = second;
                    d.vv[(j - n, i - n)] = second;
                }
            }
        }
    }
    d
}

/// Value and first derivatives of L at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstDerivatives<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// L(t, q, q̇).
    pub value: f64,
    /// ∂L/∂q.
    pub q: OVector<f64, N>,
    /// ∂L/∂q̇ (the momentum p).
    pub v: OVector<f64, N>,
}

/// Value, first derivatives and Hessian blocks of L at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct SecondDerivatives<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// L(t, q, q̇).
    pub value: f64,
    /// ∂L/∂q.
    pub q: OVector<f64, N>,
    /// ∂L/∂q̇.
    pub v: OVector<f64, N>,
    /// ∂²L/∂q².
    pub qq: OMatrix<f64, N, N>,
    /// ∂²L/∂q∂q̇ (entry (i, j) = ∂²L/∂qᵢ∂q̇ⱼ).
    pub qv: OMatrix<f64, N, N>,
    /// ∂²L/∂q̇² (the mass matrix).
    pub vv: OMatrix<f64, N, N>,
}

impl<N: Dimension> SecondDerivatives<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// All zeros (a buffer to be filled), of dimension `n`.
    pub fn zeros(n: N) -> Self {
        SecondDerivatives {
            value: 0.0,
            q: OVector::zeros_generic(n, U1),
            v: OVector::zeros_generic(n, U1),
            qq: OMatrix::zeros_generic(n, n),
            qv: OMatrix::zeros_generic(n, n),
            vv: OMatrix::zeros_generic(n, n),
        }
    }
}

/// The Euler–Lagrange acceleration and its Jacobian at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelerationJacobian<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// q̈ = f(t, q, q̇).
    pub value: OVector<f64, N>,
    /// ∂f/∂q.
    pub q: OMatrix<f64, N, N>,
    /// ∂f/∂q̇.
    pub v: OMatrix<f64, N, N>,
}

impl<N: Dimension> AccelerationJacobian<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The same numbers in the types of the dimension `n` (a run-time-size Jacobian, as the
    /// terms' path computes it, for a model whose `N` is [`crate::dimension::Dyn`] itself).
    pub(crate) fn of_run_time(jacobian: euler_lagrange::RunTimeJacobian, n: N) -> Self {
        AccelerationJacobian {
            value: OVector::from_column_slice_generic(n, U1, jacobian.value.as_slice()),
            q: OMatrix::from_column_slice_generic(n, n, jacobian.q.as_slice()),
            v: OMatrix::from_column_slice_generic(n, n, jacobian.v.as_slice()),
        }
    }
}

/// The external force f_L and its Jacobian at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceJacobian<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// f_L(t, q, q̇).
    pub value: OVector<f64, N>,
    /// ∂f_L/∂q.
    pub q: OMatrix<f64, N, N>,
    /// ∂f_L/∂q̇.
    pub v: OMatrix<f64, N, N>,
}

impl<N: Dimension> ForceJacobian<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The force of an unforced model: zero, with zero derivatives, of dimension `n`.
    pub fn zeros(n: N) -> Self {
        ForceJacobian {
            value: OVector::zeros_generic(n, U1),
            q: OMatrix::zeros_generic(n, n),
            v: OMatrix::zeros_generic(n, n),
        }
    }
}

/// Cap on Newton iterations of the inverse Legendre map.
const LEGENDRE_MAX_ITERATIONS: usize = 50;

/// Everything derived from a [`Lagrangian`] by automatic differentiation. Implemented for
/// every Lagrangian; import it to call these methods on a model.
pub trait LagrangianExt<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// L(t, q, q̇) in `f64`.
    #[inline]
    fn value(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64 {
        self.lagrangian(t, q, v)
    }

    /// L, ∂L/∂q and ∂L/∂q̇.
    #[inline]
    fn first_derivatives(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> FirstDerivatives<N> {
        let (value, force) = self.value_and_force(t, q, v);
        FirstDerivatives {
            value,
            q: force,
            v: self.momentum(t, q, v),
        }
    }

    /// The generalised force ∂L/∂q.
    #[inline]
    fn force(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> OVector<f64, N> {
        self.value_and_force(t, q, v).1
    }

    /// The generalised force ∂L/∂q, written into `out`: assembled in place for a sum of
    /// terms (no n-vector allocated in a step loop of a large system).
    #[inline]
    fn force_into(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        out: &mut OVector<f64, N>,
    ) {
        gradient_into(self, t, q, v, Wrt::Position, out);
    }

    /// The Jacobian of the generalised force, ∂²L/∂q² (only the position block of the
    /// Hessian: one second-order sweep in N directions).
    #[inline]
    fn force_jacobian(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> OMatrix<f64, N, N> {
        if let Some(terms) = self.terms() {
            return assembled_second_derivatives(terms, t, q, v).qq;
        }
        N::hessian(&Action(self), t, q, v, Wrt::Position).2
    }

    /// ∂L/∂q at the points (`times[μ]`, `positions[μ]`, `v`) into `forces[μ]`: all at once
    /// where the model offers it ([`Lagrangian::batch_force`]), else one by one.
    #[inline]
    fn forces_into(
        &self,
        times: &[f64],
        positions: &[OVector<f64, N>],
        v: &OVector<f64, N>,
        forces: &mut [OVector<f64, N>],
    ) {
        if !self.batch_force(times, positions, v, forces) {
            for ((&t, q), force) in times.iter().zip(positions).zip(forces) {
                self.force_into(t, q, v, force);
            }
        }
    }

    /// L and ∂L/∂q from one gradient.
    #[inline]
    fn value_and_force(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> (f64, OVector<f64, N>) {
        if let Some(terms) = self.terms() {
            return (
                terms.value(t, q, v),
                assembled_gradient(terms, t, q, v, Wrt::Position),
            );
        }
        N::gradient(&Action(self), t, q, v, Wrt::Position)
    }

    /// The momentum p = ∂L/∂q̇.
    #[inline]
    fn momentum(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> OVector<f64, N> {
        if let Some(terms) = self.terms() {
            return assembled_gradient(terms, t, q, v, Wrt::Velocity);
        }
        N::gradient(&Action(self), t, q, v, Wrt::Velocity).1
    }

    /// The momentum p = ∂L/∂q̇, written into `out` (in place, term by term, for a sum of
    /// terms).
    #[inline]
    fn momentum_into(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        out: &mut OVector<f64, N>,
    ) {
        gradient_into(self, t, q, v, Wrt::Velocity, out);
    }

    /// L, its gradients and the Hessian blocks L_qq, L_qv, L_vv.
    #[inline]
    fn second_derivatives(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> SecondDerivatives<N> {
        if let Some(terms) = self.terms() {
            return assembled_second_derivatives(terms, t, q, v);
        }
        if N::try_to_usize().is_none_or(|n| n <= SCALAR_HESSIAN_UP_TO) {
            scalar_second_derivatives(self, t, q, v)
        } else if matches!(Self::STRUCTURE, Structure::ConstantMass) {
            // L = ½ q̇ᵀMq̇ − V(t, q): the mixed block is zero by the declaration, and the
            // Hessian in q̇ brings ∂L/∂q̇ along (two sweeps instead of three).
            let (value, dq, qq) = N::hessian(&Action(self), t, q, v, Wrt::Position);
            let (_, dv, vv) = N::hessian(&Action(self), t, q, v, Wrt::Velocity);
            let (dim, _) = q.shape_generic();
            SecondDerivatives {
                value,
                q: dq,
                v: dv,
                qq,
                qv: OMatrix::zeros_generic(dim, dim),
                vv,
            }
        } else {
            let (value, dq, dv, qv) = N::mixed(&Action(self), t, q, v);
            let (_, _, qq) = N::hessian(&Action(self), t, q, v, Wrt::Position);
            let vv = self.mass_matrix(t, q, v);
            SecondDerivatives {
                value,
                q: dq,
                v: dv,
                qq,
                qv,
                vv,
            }
        }
    }

    /// The mass matrix ∂²L/∂q̇².
    #[inline]
    fn mass_matrix(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> OMatrix<f64, N, N> {
        if let Some(terms) = self.terms() {
            return assembled_second_derivatives(terms, t, q, v).vv;
        }
        N::hessian(&Action(self), t, q, v, Wrt::Velocity).2
    }

    /// M⁻¹ of the mass matrix ∂²L/∂q̇² at (t, q, q̇): from the terms' blocks for a sum of
    /// terms (diagonal or sparse LU, never an n × n matrix), else the dense inverse.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular (or, for a sum of terms,
    /// not positive on its diagonal).
    fn mass_inverse(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> Result<MassInverse<N>, Error> {
        match self.terms() {
            Some(terms) => MassInverse::of_terms(terms, t, q, v),
            None => MassInverse::of_dense(&self.mass_matrix(t, q, v)),
        }
    }

    /// The energy at a phase point (t, q, q̇, p) whose p and q̇ belong together: H(t, q, p)
    /// for a model written as H (no Legendre map is solved: a model without a Lagrangian has
    /// none, and a general H's adapter would solve one for L), else p·q̇ − L with the point's
    /// p (no allocation, also for a sum of terms of run-time size).
    #[inline]
    fn phase_energy(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> f64
    where
        DefaultAllocator: Allocator<N, N>,
    {
        match self.hamiltonian_form() {
            Some(form) => form.value(t, q, p),
            None => p.dot(v) - self.value(t, q, v),
        }
    }

    /// The energy E = p·q̇ − L.
    #[inline]
    fn energy(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64 {
        if let Some(terms) = self.terms() {
            let p = assembled_gradient(terms, t, q, v, Wrt::Velocity);
            return p.dot(v) - terms.value(t, q, v);
        }
        let (value, p) = N::gradient(&Action(self), t, q, v, Wrt::Velocity);
        p.dot(v) - value
    }

    /// The inverse Legendre map: the velocity q̇ with ∂L/∂q̇(t, q, q̇) = p, by Newton's method
    /// with the mass matrix, started at `guess` (for a sum of terms the sparse mass matrix of
    /// their blocks, assembled in O(n)).
    ///
    /// # Errors
    /// [`Error::LegendreMap`] if Newton's method does not converge (a singular mass matrix, or
    /// no velocity for this momentum); [`Error::InvalidParameter`] `width` for terms wider
    /// than sparse Newton takes.
    fn velocity(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        guess: &OVector<f64, N>,
    ) -> Result<OVector<f64, N>, Error> {
        // A model written as H: q̇ = ∂H/∂p, no Newton's method.
        if let Some(form) = self.hamiltonian_form() {
            return Ok(form.velocity(t, q, p));
        }
        if let Some(terms) = self.terms() {
            // A constant mass matrix of a sum of terms: M⁻¹p from the terms' blocks, in O(n).
            if Self::STRUCTURE == Structure::ConstantMass {
                let inverse = self
                    .mass_inverse(t, q, guess)
                    .map_err(|_| Error::LegendreMap {
                        t,
                        iterations: 0,
                        residual: f64::INFINITY,
                    })?;
                return Ok(inverse.apply(p));
            }
            // Any other sum of terms of run-time size: Newton with the sparse ∂²L/∂q̇², in O(n).
            if let Some(terms) = terms.as_run_time() {
                let mut v = guess.clone();
                legendre::velocity(terms, t, q.as_slice(), p.as_slice(), v.as_mut_slice())?;
                return Ok(v);
            }
        }
        // ∂L/∂q̇ and ∂²L/∂q̇² at v, and whether both are finite.
        let legendre = |v: &OVector<f64, N>| {
            let (_, momentum, mass) = N::hessian(&Action(self), t, q, v, Wrt::Velocity);
            let finite = momentum.iter().chain(mass.iter()).all(|x| x.is_finite());
            (momentum, mass, finite)
        };
        // A guess where ∂L/∂q̇ is not finite (p itself beyond the light cone) is replaced by
        // rest, q̇ = 0.
        let mut v = guess.clone();
        let (mut momentum, mut mass, finite) = legendre(&v);
        if !finite {
            v.fill(0.0);
            (momentum, mass, _) = legendre(&v);
        }
        let mut last = f64::INFINITY;
        for iteration in 1..=LEGENDRE_MAX_ITERATIONS {
            let delta = solve_small(mass, p - &momentum).ok_or(Error::LegendreMap {
                t,
                iterations: iteration,
                residual: f64::INFINITY,
            })?;
            let size = delta.amax();
            if !size.is_finite() {
                break;
            }
            let scale = 1.0 + (&v + &delta).amax();
            // Converged: at round-off, or the increment stopped decreasing near it.
            if size <= f64::EPSILON * scale || (size >= last && size <= 1e-10 * scale) {
                return Ok(v + delta);
            }
            // Otherwise the step is halved until ∂L/∂q̇ is finite again: a relativistic kinetic
            // energy is defined only inside the light cone, and a guess such as p itself may
            // lie outside.
            let mut fraction = 1.0;
            v = loop {
                let trial = &v + &delta * fraction;
                let (next_momentum, next_mass, finite) = legendre(&trial);
                if finite || fraction < 1e-6 {
                    (momentum, mass) = (next_momentum, next_mass);
                    break trial;
                }
                fraction *= 0.5;
            };
            last = size * fraction;
        }
        Err(Error::LegendreMap {
            t,
            iterations: LEGENDRE_MAX_ITERATIONS,
            residual: last,
        })
    }

    /// The Euler–Lagrange acceleration q̈ = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L); `None` where
    /// the mass matrix is singular.
    #[inline]
    fn acceleration(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> Option<OVector<f64, N>> {
        if let Some(terms) = sparse_terms(self) {
            // Term by term with the sparse mass matrix ([`euler_lagrange`]), in O(n).
            let mut out = q.clone();
            euler_lagrange::Acceleration::new(terms, q.len())
                .ok()?
                .acceleration(terms, t, (q.as_slice(), v.as_slice()), out.as_mut_slice())
                .ok()?;
            return Some(out);
        }
        acceleration_generic(self, t, q, v)
    }

    /// The external force f_L and its Jacobian in q and q̇ (zero, at no cost, for a model
    /// that is not [`Lagrangian::FORCED`]).
    #[inline]
    fn external_force_jacobian(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> ForceJacobian<N> {
        if !Self::FORCED {
            return ForceJacobian::zeros(q.shape_generic().0);
        }
        let (value, dq) = N::jacobian(&ExternalForce(self), t, q, v, Wrt::Position);
        let (_, dv) = N::jacobian(&ExternalForce(self), t, q, v, Wrt::Velocity);
        ForceJacobian {
            value,
            q: dq,
            v: dv,
        }
    }

    /// The Euler–Lagrange acceleration and its exact Jacobian in q and q̇ (third derivatives
    /// of L by nested duals); `None` where the mass matrix is singular.
    fn acceleration_jacobian(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> Option<AccelerationJacobian<N>> {
        if let Some(terms) = sparse_terms(self) {
            // −M⁻¹ J_q and −M⁻¹ J_y from the terms' blocks ([`euler_lagrange`]).
            let jacobian = euler_lagrange::Acceleration::new(terms, q.len())
                .ok()?
                .jacobian(terms, t, (q.as_slice(), v.as_slice()))
                .ok()?;
            return Some(AccelerationJacobian::of_run_time(
                jacobian,
                q.shape_generic().0,
            ));
        }
        let (value, dq) = N::jacobian(&Acceleration(self), t, q, v, Wrt::Position);
        let (_, dv) = N::jacobian(&Acceleration(self), t, q, v, Wrt::Velocity);
        value
            .iter()
            .all(|a| a.is_finite())
            .then_some(AccelerationJacobian {
                value,
                q: dq,
                v: dv,
            })
    }

    /// The Noether momentum J = p·ξ(q) of symmetry generator `index`.
    fn noether_momentum(
        &self,
        index: usize,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> f64
    where
        Self: Symmetries<N>,
    {
        self.momentum(t, q, v).dot(&self.generator(index, q))
    }

    /// How far generator `index` is from a symmetry of L at (t, q, q̇): the relative size of
    /// the derivative of L along the lifted vector field, |L_q·ξ + L_q̇·(Dξ q̇)| /
    /// (|L_q|·|ξ| + |L_q̇|·|Dξ q̇|), zero for a symmetry (Dξ q̇ by central differences).
    fn symmetry_defect(&self, index: usize, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64
    where
        Self: Symmetries<N>,
    {
        let derivatives = self.first_derivatives(t, q, v);
        let xi = self.generator(index, q);
        let s = 1e-4 * (1.0 + q.amax()) / (1.0 + v.amax());
        let lifted =
            (self.generator(index, &(q + v * s)) - self.generator(index, &(q - v * s))) / (2.0 * s);
        let (along_q, along_v) = (derivatives.q.dot(&xi), derivatives.v.dot(&lifted));
        let scale = derivatives.q.abs().dot(&xi.abs()) + derivatives.v.abs().dot(&lifted.abs());
        let defect = (along_q + along_v).abs();
        if defect == 0.0 { 0.0 } else { defect / scale }
    }
}

impl<L: Lagrangian<N> + ?Sized, N: Dimension> LagrangianExt<N> for L where
    DefaultAllocator: Allocator<N> + Allocator<N, N>
{
}

/// The terms of `model` where the methods take its equations term by term, with sparse
/// matrices (SVI's and the segment rules' stage equations, SC's collocation equations, the
/// Euler–Lagrange acceleration of [`euler_lagrange`]): an unforced sum of local terms of
/// run-time size (a forced model, or a fixed size, takes the dense path).
pub(crate) fn sparse_terms<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
) -> Option<&dyn TermSum<crate::dimension::Dyn>>
where
    DefaultAllocator: Allocator<N>,
{
    if L::FORCED {
        return None;
    }
    model.terms()?.as_run_time()
}

/// ∂L/∂q or ∂L/∂q̇ of a sum of local terms, assembled term by term.
fn assembled_gradient<N: Dimension>(
    terms: &dyn TermSum<N>,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
    wrt: Wrt,
) -> OVector<f64, N>
where
    DefaultAllocator: Allocator<N>,
{
    let mut out = OVector::zeros_generic(q.shape_generic().0, U1);
    terms.gradient_into(t, q, v, wrt, &mut out);
    out
}

/// L, its gradients and its Hessian blocks, dense, from a sum of local terms (the blocks'
/// triplets added into n × n matrices).
fn assembled_second_derivatives<N: Dimension>(
    terms: &dyn TermSum<N>,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
) -> SecondDerivatives<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = q.shape_generic().0;
    let mut blocks = [Vec::new(), Vec::new(), Vec::new()];
    terms.hessian_triplets(t, q, v, &mut blocks);
    let [qq, qv, vv] = blocks.map(|triplets| {
        let mut block = OMatrix::zeros_generic(n, n);
        for (i, j, value) in triplets {
            block[(i, j)] += value;
        }
        block
    });
    SecondDerivatives {
        value: terms.value(t, q, v),
        q: assembled_gradient(terms, t, q, v, Wrt::Position),
        v: assembled_gradient(terms, t, q, v, Wrt::Velocity),
        qq,
        qv,
        vv,
    }
}

/// The Euler–Lagrange acceleration at a point of any scalar type (dual numbers give its
/// Jacobian): q̈ = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L).
fn acceleration_generic<L, D, N: Dimension>(
    model: &L,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
) -> Option<OVector<D, N>>
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (_, _, vv) = N::hessian(&Action(model), t, q, v, Wrt::Velocity);
    let mut rhs = if matches!(L::STRUCTURE, Structure::ConstantMass) {
        // L = ½ q̇ᵀMq̇ − V(t, q): L_vq = 0 and L_vt = 0, only the gradient L_q is needed.
        N::gradient(&Action(model), t, q, v, Wrt::Position).1
    } else {
        // L_q, L_qv from the mixed derivatives and L_vv from the Hessian in q̇: L_qq is not
        // needed.
        let (_, lq, _, qv) = N::mixed(&Action(model), t, q, v);
        let mut rhs = lq - qv.transpose() * v;
        if L::TIME_DEPENDENT {
            rhs -= N::velocity_time(&Action(model), t, q, v);
        }
        rhs
    };
    if L::FORCED {
        rhs += model.external_force(t, q, v);
    }
    solve_small(vv, rhs)
}

/// ∂L/∂q or ∂L/∂q̇ (`wrt`) into `out`: in place, term by term, for a sum of terms.
#[inline]
fn gradient_into<L: Lagrangian<N> + ?Sized, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
    wrt: Wrt,
    out: &mut OVector<f64, N>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match model.terms() {
        Some(terms) => terms.gradient_into(t, q, v, wrt, out),
        None => *out = N::gradient(&Action(model), t, q, v, wrt).1,
    }
}

/// The gradients and Hessian blocks of `model` at a point of dual numbers in ε, typically
/// (t + ε, q + ε dq, q̇ + ε dv): ∂L/∂q, ∂L/∂q̇, ∂²L/∂q², ∂²L/∂q∂q̇, ∂²L/∂q̇² (column-major, in
/// the layout of [`crate::model::TermDerivatives`]), their values into `value` and their
/// ε-parts (third derivatives of L contracted with the direction) into `rate`.
pub(crate) fn second_derivatives_along<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    t: Dual64,
    (q, v): (&OVector<Dual64, N>, &OVector<Dual64, N>),
    (value, rate): (&mut [f64], &mut [f64]),
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (_, gq, gv, qv) = N::mixed(&Action(model), t, q, v);
    let (_, _, qq) = N::hessian(&Action(model), t, q, v, Wrt::Position);
    let (_, _, vv) = N::hessian(&Action(model), t, q, v, Wrt::Velocity);
    let blocks = [
        gq.as_slice(),
        gv.as_slice(),
        qq.as_slice(),
        qv.as_slice(),
        vv.as_slice(),
    ];
    for ((x, re), eps) in blocks.into_iter().flatten().zip(value).zip(rate) {
        (*re, *eps) = (x.re, x.eps);
    }
}

/// M⁻¹ of a [`crate::model::Structure::ConstantMass`] Lagrangian, computed at the first step
/// (at (t, q), with `y` standing in for q̇, which M does not depend on) and cached in `cache`:
/// dense, or from the terms' blocks for a sum of local terms ([`MassInverse`]).
pub(crate) fn cached_mass_inverse<'c, L: Lagrangian<N>, N: Dimension>(
    cache: &'c mut Option<MassInverse<N>>,
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    y: &OVector<f64, N>,
) -> Result<&'c MassInverse<N>, crate::error::StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match *cache {
        Some(ref inverse) => Ok(inverse),
        None => {
            let inverse = model
                .mass_inverse(t, q, y)
                .map_err(|_| crate::error::StepFailure::SingularMatrix)?;
            Ok(cache.insert(inverse))
        }
    }
}

/// M and M⁻¹ of a [`crate::model::Structure::ConstantMass`] Lagrangian, kept by a run of a
/// method in the coordinates (q, q̇): M⁻¹ for the accelerations, M for the observers'
/// momentum p = M q̇ (a sum of terms keeps only its inverse, which holds its diagonal or
/// sparse M). Both from one mass matrix at the first step.
#[derive(Debug, Clone)]
pub(crate) struct KeptMass<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    inverse: Option<MassInverse<N>>,
    mass: Option<OMatrix<f64, N, N>>,
}

impl<N: Dimension> Default for KeptMass<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn default() -> Self {
        KeptMass {
            inverse: None,
            mass: None,
        }
    }
}

impl<N: Dimension> KeptMass<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// M⁻¹, made at the first call (as [`cached_mass_inverse`]) with M kept beside it.
    pub(crate) fn inverse<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        y: &OVector<f64, N>,
    ) -> Result<&MassInverse<N>, crate::error::StepFailure> {
        if self.inverse.is_none() && model.terms().is_none() {
            let mass = model.mass_matrix(t, q, y);
            let inverse = MassInverse::of_dense(&mass)
                .map_err(|_| crate::error::StepFailure::SingularMatrix)?;
            self.mass = Some(mass);
            self.inverse = Some(inverse);
        }
        cached_mass_inverse(&mut self.inverse, model, t, q, y)
    }

    /// p = M `v` into `p` (for a sum of terms from the diagonal or sparse M its inverse was
    /// made of); `false` before M is kept.
    pub(crate) fn momentum_into(&self, v: &OVector<f64, N>, p: &mut OVector<f64, N>) -> bool {
        match (&self.mass, &self.inverse) {
            (Some(mass), _) => {
                mass.mul_to(v, p);
                true
            }
            (None, Some(inverse)) => inverse.mass_times_into(v, p),
            (None, None) => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_models::{AsDyn, Oscillator, VariableMass};
    use nalgebra::{Const, DVector, SMatrix, SVector, U2, U3};

    /// The closed forms of [`VariableMass`], derived by hand.
    mod variable_mass {
        use nalgebra::{SMatrix, SVector};
        pub fn value(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
            0.5 * (1.0 + q[1] * q[1]) * v[0] * v[0] + 0.5 * v[1] * v[1]
                - 0.5 * (q[0] * q[0] + q[1] * q[1])
                - 0.25 * q[0].powi(4)
        }
        /// ∂L/∂q = (−q₀ − q₀³, q₁ q̇₀² − q₁).
        pub fn lq(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
            SVector::from([-q[0] - q[0].powi(3), q[1] * v[0] * v[0] - q[1]])
        }
        /// p = ((1 + q₁²) q̇₀, q̇₁).
        pub fn momentum(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
            SVector::from([(1.0 + q[1] * q[1]) * v[0], v[1]])
        }
        /// L_qq = diag(−1 − 3q₀², q̇₀² − 1).
        pub fn lqq(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
            SMatrix::<f64, 2, 2>::new(-1.0 - 3.0 * q[0] * q[0], 0.0, 0.0, v[0] * v[0] - 1.0)
        }
        /// (L_qv)_ij = ∂²L/∂qᵢ∂q̇ⱼ: only (1, 0) = 2 q₁ q̇₀.
        pub fn lqv(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
            SMatrix::<f64, 2, 2>::new(0.0, 0.0, 2.0 * q[1] * v[0], 0.0)
        }
        /// L_vv = diag(1 + q₁², 1).
        pub fn lvv(q: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
            SMatrix::<f64, 2, 2>::new(1.0 + q[1] * q[1], 0.0, 0.0, 1.0)
        }
        /// E = T + V.
        pub fn energy(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
            0.5 * (1.0 + q[1] * q[1]) * v[0] * v[0]
                + 0.5 * v[1] * v[1]
                + 0.5 * (q[0] * q[0] + q[1] * q[1])
                + 0.25 * q[0].powi(4)
        }
        /// Euler–Lagrange: d/dt[(1 + q₁²) q̇₀] = −q₀ − q₀³ gives
        /// q̈₀ = (−q₀ − q₀³ − 2 q₁ q̇₁ q̇₀) / (1 + q₁²), and q̈₁ = q₁ q̇₀² − q₁.
        pub fn acceleration(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
            SVector::from([
                (-q[0] - q[0].powi(3) - 2.0 * q[1] * v[1] * v[0]) / (1.0 + q[1] * q[1]),
                q[1] * v[0] * v[0] - q[1],
            ])
        }
    }

    /// Time-dependent mass: L = ½ (2 + sin t) q̇² − ½ q², whose Euler–Lagrange equation
    /// (2 + sin t) q̈ + cos t · q̇ = −q needs the L_vt term.
    struct TimeDependentMass;
    impl Lagrangian<U1> for TimeDependentMass {
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            (t.sin() + 2.0) * v[0] * v[0] * 0.5 - q[0] * q[0] * 0.5
        }
    }

    /// Forced oscillator: L = q̇²/2 − q²/2, f_L = −c q̇ − b q³ + a cos t.
    struct Forced;
    const DAMPING: f64 = 0.3;
    const CUBIC: f64 = 0.2;
    const DRIVE: f64 = 0.5;
    impl Lagrangian<U1> for Forced {
        const TIME_DEPENDENT: bool = false;
        const FORCED: bool = true;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            (v[0] * v[0] - q[0] * q[0]) * 0.5
        }
        fn external_force<D: Scalar>(
            &self,
            t: D,
            q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            SVector::from([v[0] * (-DAMPING) - q[0].powi(3) * CUBIC + t.cos() * DRIVE])
        }
    }

    /// Relativistic particle in a well: L = −√(1 − q̇²) − q²/2, p = q̇/√(1 − q̇²), whose
    /// inverse Legendre map q̇ = p/√(1 + p²) needs several Newton iterations.
    struct Relativistic;
    impl Lagrangian<U1> for Relativistic {
        const TIME_DEPENDENT: bool = false;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            -(-(v[0] * v[0]) + 1.0).sqrt() - q[0] * q[0] * 0.5
        }
    }

    /// Singular mass matrix: L = ½ q̇₀² − ½ q₀² − ½ q₁² (q₁ has no kinetic term).
    struct Degenerate;
    impl Lagrangian<U2> for Degenerate {
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v[0] * v[0] - q[0] * q[0] - q[1] * q[1]) * 0.5
        }
    }

    /// Planar isotropic oscillator L = ½|q̇|² − ½|q|², invariant under rotations
    /// ξ(q) = (−q₁, q₀): the Noether momentum is the angular momentum q₀ q̇₁ − q₁ q̇₀.
    struct Planar;
    impl Lagrangian<U2> for Planar {
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v.dot(v) - q.dot(q)) * 0.5
        }
    }
    impl Symmetries<U2> for Planar {
        fn generator_count(&self) -> usize {
            1
        }
        fn momentum_name(&self, _index: usize) -> &'static str {
            "angular momentum"
        }
        fn generator(&self, _index: usize, q: &SVector<f64, 2>) -> SVector<f64, 2> {
            SVector::from([-q[1], q[0]])
        }
    }

    /// Constant, non-diagonal mass M = [[2, 1], [1, 3]]: L = ½ q̇ᵀMq̇ − ½|q|².
    struct ConstantMass;
    impl Lagrangian<U2> for ConstantMass {
        const STRUCTURE: Structure = Structure::ConstantMass;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v[0] * v[0] * 2.0 + v[0] * v[1] * 2.0 + v[1] * v[1] * 3.0 - q.dot(q)) * 0.5
        }
    }

    /// A few (q, q̇) points, away from any symmetry of the closed forms.
    fn points() -> [(SVector<f64, 2>, SVector<f64, 2>); 3] {
        [
            (SVector::from([0.3, -0.7]), SVector::from([1.1, 0.4])),
            (SVector::from([-1.2, 0.5]), SVector::from([-0.3, 2.0])),
            (SVector::from([2.0, 1.5]), SVector::from([0.8, -1.3])),
        ]
    }

    /// |a − b| ≤ tolerance · max(1, |b|), entry by entry.
    fn assert_close<const R: usize, const C: usize>(
        a: &SMatrix<f64, R, C>,
        b: &SMatrix<f64, R, C>,
        tolerance: f64,
    ) {
        for (x, y) in a.iter().zip(b.iter()) {
            assert!(
                (x - y).abs() <= tolerance * y.abs().max(1.0),
                "{a} differs from {b} by more than {tolerance:e}"
            );
        }
    }

    #[test]
    fn first_derivatives_match_hand_derived_gradients() {
        let model = VariableMass;
        for (q, v) in points() {
            let first = model.first_derivatives(0.0, &q, &v);
            let expected = variable_mass::value(&q, &v);
            assert!((first.value - expected).abs() <= 1e-15 * expected.abs().max(1.0));
            assert!((model.value(0.0, &q, &v) - expected).abs() <= 1e-15 * expected.abs().max(1.0));
            assert_close(&first.q, &variable_mass::lq(&q, &v), 1e-15);
            assert_close(&first.v, &variable_mass::momentum(&q, &v), 1e-15);
            // The scalar-sweep paths of the force and the momentum.
            assert_close(&model.force(0.0, &q, &v), &variable_mass::lq(&q, &v), 1e-15);
            assert_close(
                &model.momentum(0.0, &q, &v),
                &variable_mass::momentum(&q, &v),
                1e-15,
            );
        }
    }

    #[test]
    fn hessian_blocks_match_hand_derived_second_derivatives() {
        let model = VariableMass;
        for (q, v) in points() {
            let second = model.second_derivatives(0.0, &q, &v);
            assert!((second.value - variable_mass::value(&q, &v)).abs() <= 1e-14);
            assert_close(&second.q, &variable_mass::lq(&q, &v), 1e-15);
            assert_close(&second.v, &variable_mass::momentum(&q, &v), 1e-15);
            assert_close(&second.qq, &variable_mass::lqq(&q, &v), 1e-15);
            assert_close(&second.qv, &variable_mass::lqv(&q, &v), 1e-15);
            assert_close(&second.vv, &variable_mass::lvv(&q), 1e-15);
            // N = 2 takes the scalar hyper-dual sweeps; the vector sweeps of larger N agree.
            let (_, lq, lv, qv) = U2::mixed(&Action(&model), 0.0, &q, &v);
            let (_, _, qq) = U2::hessian(&Action(&model), 0.0, &q, &v, Wrt::Position);
            let (_, _, vv) = U2::hessian(&Action(&model), 0.0, &q, &v, Wrt::Velocity);
            assert_close(&lq, &second.q, 1e-15);
            assert_close(&lv, &second.v, 1e-15);
            assert_close(&qq, &second.qq, 1e-15);
            assert_close(&qv, &second.qv, 1e-15);
            assert_close(&vv, &second.vv, 1e-15);
            assert_close(
                &model.mass_matrix(0.0, &q, &v),
                &variable_mass::lvv(&q),
                1e-15,
            );
        }
    }

    /// L = ½ q̇ᵀMq̇ − V(q) on ℝ³ with a coupled M, declared constant-mass or not.
    struct Coupled3<const CONSTANT: bool>;
    impl<const CONSTANT: bool> Lagrangian<U3> for Coupled3<CONSTANT> {
        const STRUCTURE: Structure = if CONSTANT {
            Structure::ConstantMass
        } else {
            Structure::General
        };
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 3>, v: &SVector<D, 3>) -> D {
            let kinetic = v[0] * v[0]
                + v[1] * v[1] * 1.5
                + v[2] * v[2] * 0.5
                + v[0] * v[1]
                + v[1] * v[2] * 0.5;
            kinetic - q[0] * q[0] * q[1] - q[2].sin() - q[0] * q[2].powi(3)
        }
    }

    /// A constant-mass model of N = 3 takes two Hessian sweeps (no mixed block): the same
    /// blocks as the general path's three and as the scalar sweeps entry by entry.
    #[test]
    fn constant_mass_second_derivatives_skip_the_mixed_block() {
        let q = SVector::from([0.3, -0.7, 1.1]);
        let v = SVector::from([0.4, 0.2, -0.9]);
        let fast = Coupled3::<true>.second_derivatives(0.0, &q, &v);
        let general = Coupled3::<false>.second_derivatives(0.0, &q, &v);
        let reference = scalar_second_derivatives(&Coupled3::<true>, 0.0, &q, &v);
        for other in [&general, &reference] {
            assert!((fast.value - other.value).abs() <= 1e-15);
            assert_close(&fast.q, &other.q, 1e-15);
            assert_close(&fast.v, &other.v, 1e-15);
            assert_close(&fast.qq, &other.qq, 1e-15);
            assert_close(&fast.qv, &other.qv, 1e-15);
            assert_close(&fast.vv, &other.vv, 1e-15);
        }
        assert_eq!(fast.qv, SMatrix::<f64, 3, 3>::zeros());
        let mass = SMatrix::<f64, 3, 3>::new(2.0, 1.0, 0.0, 1.0, 3.0, 0.5, 0.0, 0.5, 1.0);
        assert_close(&fast.vv, &mass, 1e-15);
        assert_close(&fast.v, &(mass * v), 1e-15);
    }

    #[test]
    fn energy_is_kinetic_plus_potential() {
        for (q, v) in [(0.0, 1.0), (0.6, -0.8), (-2.5, 3.25)] {
            let energy = Oscillator::<false>.energy(0.0, &SVector::from([q]), &SVector::from([v]));
            assert!(
                (energy - 0.5 * (v * v + q * q)).abs() <= 1e-15 * energy,
                "{energy}"
            );
        }
        for (q, v) in points() {
            let expected = variable_mass::energy(&q, &v);
            let energy = VariableMass.energy(0.0, &q, &v);
            assert!(
                (energy - expected).abs() <= 1e-15 * expected,
                "{energy} {expected}"
            );
        }
    }

    #[test]
    fn acceleration_solves_the_hand_derived_euler_lagrange_equations() {
        for (q, v) in points() {
            let a = VariableMass.acceleration(0.0, &q, &v).unwrap();
            assert_close(&a, &variable_mass::acceleration(&q, &v), 1e-14);
        }
        // (2 + sin t) q̈ + cos t · q̇ + q = 0: the ∂²L/∂q̇∂t term.
        for (t, q, v) in [(0.0, 0.5, 1.0), (1.3, -0.4, 0.7), (4.0, 2.0, -1.5)] {
            let a = TimeDependentMass
                .acceleration(t, &SVector::from([q]), &SVector::from([v]))
                .unwrap()[0];
            let expected = (-q - t.cos() * v) / (2.0 + t.sin());
            assert!(
                (a - expected).abs() <= 1e-15 * expected.abs().max(1.0),
                "{a}"
            );
        }
        // q̈ = −q + f_L(t, q, q̇).
        for (t, q, v) in [(0.0, 0.5, 1.0), (2.1, -0.4, 0.7)] {
            let a = Forced
                .acceleration(t, &SVector::from([q]), &SVector::from([v]))
                .unwrap()[0];
            let expected = -q - DAMPING * v - CUBIC * q * q * q + DRIVE * t.cos();
            assert!(
                (a - expected).abs() <= 1e-15 * expected.abs().max(1.0),
                "{a}"
            );
        }
    }

    /// Central differences of the acceleration in q and q̇ with step δ = 1e-5: truncation
    /// error δ²/6 · |f'''| ≈ 1e-10 and round-off ε |f| / δ ≈ 1e-11 for these O(1) states,
    /// so the Jacobian must agree to 1e-8 (relative to max(1, |entry|)).
    fn assert_jacobian_matches_central_differences<L: Lagrangian<Const<N>>, const N: usize>(
        model: &L,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) {
        let delta = 1e-5;
        let jacobian = model.acceleration_jacobian(t, q, v).unwrap();
        assert_close(
            &jacobian.value,
            &model.acceleration(t, q, v).unwrap(),
            1e-15,
        );
        let mut dq = SMatrix::<f64, N, N>::zeros();
        let mut dv = SMatrix::<f64, N, N>::zeros();
        for j in 0..N {
            let mut e = SVector::<f64, N>::zeros();
            e[j] = delta;
            let column = (model.acceleration(t, &(q + e), v).unwrap()
                - model.acceleration(t, &(q - e), v).unwrap())
                / (2.0 * delta);
            dq.set_column(j, &column);
            let column = (model.acceleration(t, q, &(v + e)).unwrap()
                - model.acceleration(t, q, &(v - e)).unwrap())
                / (2.0 * delta);
            dv.set_column(j, &column);
        }
        assert_close(&jacobian.q, &dq, 1e-8);
        assert_close(&jacobian.v, &dv, 1e-8);
    }

    #[test]
    fn acceleration_jacobian_matches_central_differences() {
        for (q, v) in points() {
            assert_jacobian_matches_central_differences(&VariableMass, 0.0, &q, &v);
        }
        for (t, q, v) in [(0.4, 0.5, 1.0), (3.0, -1.1, 0.3)] {
            let (q, v) = (SVector::from([q]), SVector::from([v]));
            assert_jacobian_matches_central_differences(&TimeDependentMass, t, &q, &v);
            assert_jacobian_matches_central_differences(&Forced, t, &q, &v);
        }
    }

    #[test]
    fn velocity_inverts_momentum_to_round_off() {
        // Quadratic in q̇: one Newton step from a zero guess is exact.
        for (q, v) in points() {
            let p = variable_mass::momentum(&q, &v);
            let inverse = VariableMass
                .velocity(0.0, &q, &p, &SVector::zeros())
                .unwrap();
            assert_close(&inverse, &v, 2.0 * f64::EPSILON);
        }
        // Relativistic: q̇ = p/√(1 + p²) in closed form, several Newton iterations. The
        // guess 0.99 sign(p) lies beyond the root on the branch where p(q̇) is convex (concave
        // for p < 0), so Newton converges monotonically without leaving |q̇| < 1.
        // Started at p itself or at rest, the first Newton steps leave |q̇| < 1 and are halved
        // back inside.
        for p in [0.3f64, -1.7, 4.0] {
            let q = SVector::from([0.2]);
            let expected = p / (1.0 + p * p).sqrt();
            for guess in [0.99 * p.signum(), p, 0.0] {
                let v = Relativistic
                    .velocity(0.0, &q, &SVector::from([p]), &SVector::from([guess]))
                    .unwrap()[0];
                assert!(
                    (v - expected).abs() <= 2.0 * f64::EPSILON,
                    "guess {guess}: {v} vs {expected}"
                );
            }
            let v = expected;
            let back = Relativistic.momentum(0.0, &q, &SVector::from([v]))[0];
            assert!(
                (back - p).abs() <= 8.0 * f64::EPSILON * p.abs(),
                "{back} vs {p}"
            );
        }
    }

    #[test]
    fn external_force_jacobian_matches_hand_derived_derivatives() {
        let (t, q, v) = (0.7, SVector::from([0.9]), SVector::from([-0.4]));
        let force = Forced.external_force_jacobian(t, &q, &v);
        let expected = -DAMPING * v[0] - CUBIC * q[0].powi(3) + DRIVE * t.cos();
        assert!((force.value[0] - expected).abs() <= 1e-15);
        assert!((force.q[(0, 0)] + 3.0 * CUBIC * q[0] * q[0]).abs() <= 1e-15);
        assert!((force.v[(0, 0)] + DAMPING).abs() <= 1e-15);
        // Unforced models report an exact zero without evaluating anything.
        assert_eq!(
            Oscillator::<false>.external_force_jacobian(t, &q, &v),
            ForceJacobian::zeros(U1)
        );
    }

    #[test]
    fn singular_mass_matrix_gives_no_acceleration_and_a_legendre_map_error() {
        let (q, v) = (SVector::from([0.1, 0.2]), SVector::from([0.3, 0.4]));
        assert!(Degenerate.acceleration(0.0, &q, &v).is_none());
        assert!(Degenerate.acceleration_jacobian(0.0, &q, &v).is_none());
        let error = Degenerate.velocity(0.5, &q, &v, &v).unwrap_err();
        assert!(matches!(
            error,
            Error::LegendreMap {
                t: 0.5,
                iterations: 1,
                ..
            }
        ));
        // Named as what it is, not as an infinite increment.
        assert!(
            error
                .to_string()
                .contains("the mass matrix (the Hessian of L in the velocities) is singular"),
            "{error}"
        );
    }

    #[test]
    fn noether_momentum_of_rotations_is_the_angular_momentum() {
        let (q, v) = (SVector::from([0.3, -1.2]), SVector::from([0.7, 0.25]));
        let expected = q[0] * v[1] - q[1] * v[0];
        assert!((Planar.noether_momentum(0, 0.0, &q, &v) - expected).abs() <= 1e-15);
    }

    #[test]
    fn a_symmetry_has_no_defect_and_a_generator_that_is_none_has_one() {
        // Rotations are a symmetry of the planar isotropic oscillator; translations are not.
        struct Translated;
        impl Lagrangian<U2> for Translated {
            fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
                Planar.lagrangian(t, q, v)
            }
        }
        impl Symmetries<U2> for Translated {
            fn generator_count(&self) -> usize {
                1
            }
            fn momentum_name(&self, _index: usize) -> &'static str {
                "px"
            }
            fn generator(&self, _index: usize, _q: &SVector<f64, 2>) -> SVector<f64, 2> {
                SVector::from([1.0, 0.0])
            }
        }
        for (q, v) in points() {
            let rotation = Planar.symmetry_defect(0, 0.0, &q, &v);
            assert!(rotation <= 1e-9, "{rotation:e}");
            let translation = Translated.symmetry_defect(0, 0.0, &q, &v);
            assert!(translation > 0.5, "{translation:e}");
        }
    }

    #[test]
    fn cached_mass_inverse_is_the_inverse_and_is_computed_once() {
        // M = [[2, 1], [1, 3]], M⁻¹ = [[3, −1], [−1, 2]] / 5.
        let expected = SMatrix::<f64, 2, 2>::new(0.6, -0.2, -0.2, 0.4);
        let mut cache = None;
        let (q, y) = (SVector::from([0.3, 0.1]), SVector::from([1.0, -2.0]));
        let inverse = cached_mass_inverse(&mut cache, &ConstantMass, 0.0, &q, &y).unwrap();
        assert_close(inverse.dense().unwrap(), &expected, 1e-15);
        // A cached value is returned as is: a stale cache proves no recomputation.
        let stale = SMatrix::<f64, 2, 2>::identity();
        cache = Some(MassInverse::Dense(stale));
        let again = cached_mass_inverse(&mut cache, &ConstantMass, 1.0, &q, &y).unwrap();
        assert_eq!(again.dense(), Some(&stale));
    }

    /// Every derived quantity of a run-time-size model (scalar sweeps) equals the one of the
    /// same Lagrangian with a fixed size (vector duals), to round-off: the variable-mass model
    /// (third derivatives in the acceleration Jacobian) and the forced, time-dependent one.
    #[test]
    fn run_time_size_derivatives_match_the_fixed_size_ones() {
        let dynamic = |x: &SVector<f64, 2>| DVector::from_column_slice(x.as_slice());
        let close = |a: &[f64], b: &[f64]| {
            let gap = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(a.len() == b.len() && gap <= 1e-13, "{a:?} vs {b:?}");
        };
        let (fixed, run_time) = (VariableMass, AsDyn::<_, U2>::new(VariableMass));
        assert_eq!(run_time.dimension(), 2);
        for (q, v) in points() {
            let (qd, vd) = (dynamic(&q), dynamic(&v));
            let (a, b) = (
                fixed.second_derivatives(0.3, &q, &v),
                run_time.second_derivatives(0.3, &qd, &vd),
            );
            close(&[a.value], &[b.value]);
            for (x, y) in [
                (a.q.as_slice(), b.q.as_slice()),
                (a.v.as_slice(), b.v.as_slice()),
            ] {
                close(x, y);
            }
            for (x, y) in [(&a.qq, &b.qq), (&a.qv, &b.qv), (&a.vv, &b.vv)] {
                close(x.as_slice(), y.as_slice());
            }
            close(
                fixed.momentum(0.3, &q, &v).as_slice(),
                run_time.momentum(0.3, &qd, &vd).as_slice(),
            );
            close(
                &[fixed.energy(0.3, &q, &v)],
                &[run_time.energy(0.3, &qd, &vd)],
            );
            let (a, b) = (
                fixed.acceleration_jacobian(0.3, &q, &v).unwrap(),
                run_time.acceleration_jacobian(0.3, &qd, &vd).unwrap(),
            );
            close(a.value.as_slice(), b.value.as_slice());
            close(a.q.as_slice(), b.q.as_slice());
            close(a.v.as_slice(), b.v.as_slice());
            let p = fixed.momentum(0.3, &q, &v);
            close(
                fixed
                    .velocity(0.3, &q, &p, &SVector::zeros())
                    .unwrap()
                    .as_slice(),
                run_time
                    .velocity(0.3, &qd, &dynamic(&p), &DVector::zeros(2))
                    .unwrap()
                    .as_slice(),
            );
        }
        let (fixed, run_time) = (Forced, AsDyn::<_, U1>::new(Forced));
        let (q, v) = (SVector::from([0.4]), SVector::from([-0.7]));
        let (qd, vd) = (
            DVector::from_element(1, 0.4),
            DVector::from_element(1, -0.7),
        );
        let (a, b) = (
            fixed.external_force_jacobian(1.1, &q, &v),
            run_time.external_force_jacobian(1.1, &qd, &vd),
        );
        close(a.value.as_slice(), b.value.as_slice());
        close(a.q.as_slice(), b.q.as_slice());
        close(a.v.as_slice(), b.v.as_slice());
        close(
            fixed.acceleration(1.1, &q, &v).unwrap().as_slice(),
            run_time.acceleration(1.1, &qd, &vd).unwrap().as_slice(),
        );
    }
}
