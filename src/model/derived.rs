//! Quantities derived from a [`Lagrangian`] by automatic differentiation.
//!
//! Nothing here is written per model: every quantity comes from the one generic function
//! [`Lagrangian::lagrangian`] evaluated with num-dual's dual numbers.
//!
//! - first derivatives ∂L/∂q and p = ∂L/∂q̇: one gradient sweep each with `DualSVec64<N>`,
//!   or for N ≤ [`SCALAR_SWEEPS_UP_TO`] N sweeps of the scalar `Dual64` (whose derivative is a
//!   plain f64, not an optional vector: Kepler's force costs 6.8 ns that way against 16 ns
//!   with one `DualSVec64<2>` sweep and 5.5 ns by hand, `cargo bench --bench derivatives --
//!   kepler/force`);
//! - the Hessian blocks L_qq, L_qv, L_vv: for N ≤ [`SCALAR_HESSIAN_UP_TO`] one sweep of the
//!   scalar `HyperDual64` per Hessian entry in (q, q̇) (three times faster there),
//!   else `hessian` in q, `hessian` in q̇ and one `partial_hessian` (`2N` is not a const
//!   expression on stable Rust, so the full second derivative is assembled from three
//!   N-sized sweeps);
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

use crate::error::Error;
use crate::linalg::solve_small;
use crate::model::{Lagrangian, Symmetries};
use crate::scalar::Scalar;
use nalgebra::{Const, SMatrix, SVector};
use num_dual::{
    Dual2Vec, Dual64, DualSVec64, DualVec, HyperDual64, HyperDualVec, gradient, hessian, jacobian,
    partial_hessian,
};

/// Largest dimension whose gradients are taken as N scalar-dual sweeps rather than one
/// vector-dual sweep. Scalar sweeps are cheap where the compiler inlines L into each and
/// shares its transcendental functions between them (`cargo bench --bench derivatives --
/// chain`, run with this constant at 2, 3 and 4: on the coupled chain of pendulums the force
/// costs 50 ns by scalar sweeps against 81 ns by one vector sweep at N = 3, but 334 ns
/// against 189 ns at N = 4).
pub const SCALAR_SWEEPS_UP_TO: usize = 3;

/// Largest dimension whose Hessian blocks are taken as one scalar hyper-dual sweep per entry
/// in (q, q̇), (2N)(2N + 1)/2 sweeps, rather than three vector sweeps: 138 ns against 411 ns
/// for the spring pendulum, 64 against 149 for Kepler, but 1.6 µs against 0.56 µs for the
/// coupled chain of three pendulums (`cargo bench --bench derivatives`, run with this
/// constant at 0, 2 and 4).
pub const SCALAR_HESSIAN_UP_TO: usize = 2;

/// f(x) and ∇f(x) for f: ℝᴺ → ℝ: N forward sweeps with `Dual64` for small N, else one
/// `DualSVec64<N>` sweep. `f` receives the seeded argument.
#[inline]
fn gradient_of<const N: usize>(
    f_scalar: impl Fn(SVector<Dual64, N>) -> Dual64,
    f_vector: impl Fn(SVector<DualSVec64<N>, N>) -> DualSVec64<N>,
    x: &SVector<f64, N>,
) -> (f64, SVector<f64, N>) {
    if N <= SCALAR_SWEEPS_UP_TO {
        scalar_gradient(f_scalar, x)
    } else {
        gradient(f_vector, x)
    }
}

/// f(x) and ∇f(x) by N forward sweeps with the scalar `Dual64` (N ≥ 1).
#[inline]
fn scalar_gradient<const N: usize>(
    f: impl Fn(SVector<Dual64, N>) -> Dual64,
    x: &SVector<f64, N>,
) -> (f64, SVector<f64, N>) {
    let mut value = 0.0;
    let mut gradient = SVector::zeros();
    for i in 0..N {
        let y = f(SVector::from_fn(|j, _| {
            Dual64::new(x[j], if i == j { 1.0 } else { 0.0 })
        }));
        value = y.re;
        gradient[i] = y.eps;
    }
    (value, gradient)
}

/// L, its gradients and Hessian blocks by (2N)(2N + 1)/2 sweeps of the scalar hyper-dual
/// number `HyperDual64`, one per entry (i ≤ j) of the Hessian in x = (q, q̇): the sweep seeded
/// with ε₁ on xᵢ and ε₂ on xⱼ carries ∂²L/∂xᵢ∂xⱼ in its ε₁ε₂ part, and with i = j also
/// ∂L/∂xᵢ in ε₁. Used for N ≤ [`SCALAR_HESSIAN_UP_TO`].
#[inline]
fn scalar_second_derivatives<L, const N: usize>(
    model: &L,
    t: f64,
    q: &SVector<f64, N>,
    v: &SVector<f64, N>,
) -> SecondDerivatives<N>
where
    L: Lagrangian<N> + ?Sized,
{
    let mut d = SecondDerivatives::zeros();
    let seed = |k: usize, x: f64, i: usize, j: usize| {
        HyperDual64::new(
            x,
            if k == i { 1.0 } else { 0.0 },
            if k == j { 1.0 } else { 0.0 },
            0.0,
        )
    };
    for i in 0..2 * N {
        for j in i..2 * N {
            let x = SVector::from_fn(|k, _| seed(k, q[k], i, j));
            let y = SVector::from_fn(|k, _| seed(k + N, v[k], i, j));
            let l = model.lagrangian(HyperDual64::from_re(t), &x, &y);
            let second = l.eps1eps2;
            if i == j {
                d.value = l.re;
                if i < N {
                    d.q[i] = l.eps1;
                } else {
                    d.v[i - N] = l.eps1;
                }
            }
            match (i < N, j < N) {
                (true, true) => {
                    d.qq[(i, j)] = second;
                    d.qq[(j, i)] = second;
                }
                (true, false) => d.qv[(i, j - N)] = second,
                _ => {
                    d.vv[(i - N, j - N)] = second;
                    d.vv[(j - N, i - N)] = second;
                }
            }
        }
    }
    d
}

/// Value and first derivatives of L at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstDerivatives<const N: usize> {
    /// L(t, q, q̇).
    pub value: f64,
    /// ∂L/∂q.
    pub q: SVector<f64, N>,
    /// ∂L/∂q̇ (the momentum p).
    pub v: SVector<f64, N>,
}

/// Value, first and second derivatives of L at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondDerivatives<const N: usize> {
    /// L(t, q, q̇).
    pub value: f64,
    /// ∂L/∂q.
    pub q: SVector<f64, N>,
    /// ∂L/∂q̇ (the momentum p).
    pub v: SVector<f64, N>,
    /// ∂²L/∂q∂q.
    pub qq: SMatrix<f64, N, N>,
    /// ∂²L/∂q∂q̇: entry (i, j) is ∂²L/∂qᵢ∂q̇ⱼ.
    pub qv: SMatrix<f64, N, N>,
    /// ∂²L/∂q̇∂q̇ (the mass matrix of a mechanical Lagrangian).
    pub vv: SMatrix<f64, N, N>,
}

impl<const N: usize> SecondDerivatives<N> {
    /// All zeros (a buffer's initial value).
    pub fn zeros() -> Self {
        SecondDerivatives {
            value: 0.0,
            q: SVector::zeros(),
            v: SVector::zeros(),
            qq: SMatrix::zeros(),
            qv: SMatrix::zeros(),
            vv: SMatrix::zeros(),
        }
    }
}

/// The Euler–Lagrange acceleration and its Jacobian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelerationJacobian<const N: usize> {
    /// q̈ = f(t, q, q̇).
    pub value: SVector<f64, N>,
    /// ∂q̈/∂q.
    pub q: SMatrix<f64, N, N>,
    /// ∂q̈/∂q̇.
    pub v: SMatrix<f64, N, N>,
}

/// The external force f_L of a [`Lagrangian::FORCED`] model and its Jacobian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceJacobian<const N: usize> {
    /// f_L(t, q, q̇).
    pub value: SVector<f64, N>,
    /// ∂f_L/∂q: entry (i, j) is ∂f_i/∂q_j.
    pub q: SMatrix<f64, N, N>,
    /// ∂f_L/∂q̇: entry (i, j) is ∂f_i/∂q̇_j.
    pub v: SMatrix<f64, N, N>,
}

impl<const N: usize> ForceJacobian<N> {
    /// The zero force (the value for unforced models).
    pub fn zeros() -> Self {
        ForceJacobian {
            value: SVector::zeros(),
            q: SMatrix::zeros(),
            v: SMatrix::zeros(),
        }
    }
}

/// Iteration cap of the inverse Legendre map.
const LEGENDRE_MAX_ITERATIONS: usize = 50;

/// Derived quantities of a Lagrangian, by automatic differentiation.
///
/// Implemented for every [`Lagrangian`]; the methods are provided defaults. All arguments
/// are `f64` time, configuration q and velocity q̇.
pub trait LagrangianExt<const N: usize>: Lagrangian<N> {
    /// L(t, q, q̇).
    #[inline]
    fn value(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> f64 {
        self.lagrangian(t, q, v)
    }

    /// L, ∂L/∂q and p = ∂L/∂q̇.
    #[inline]
    fn first_derivatives(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> FirstDerivatives<N> {
        let (value, force) = self.value_and_force(t, q, v);
        FirstDerivatives {
            value,
            q: force,
            v: self.momentum(t, q, v),
        }
    }

    /// The generalised force ∂L/∂q alone (one gradient).
    #[inline]
    fn force(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N> {
        self.value_and_force(t, q, v).1
    }

    /// L and ∂L/∂q from the same sweeps (one gradient).
    #[inline]
    fn value_and_force(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> (f64, SVector<f64, N>) {
        gradient_of(
            |x| self.lagrangian(Dual64::from_re(t), &x, &v.map(Dual64::from_re)),
            |x| self.lagrangian(DualVec::from_re(t), &x, &v.map(DualVec::from_re)),
            q,
        )
    }

    /// The canonical momentum p = ∂L/∂q̇.
    #[inline]
    fn momentum(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N> {
        gradient_of(
            |y| self.lagrangian(Dual64::from_re(t), &q.map(Dual64::from_re), &y),
            |y| self.lagrangian(DualVec::from_re(t), &q.map(DualVec::from_re), &y),
            v,
        )
        .1
    }

    /// L, its gradients and its Hessian blocks.
    #[inline]
    fn second_derivatives(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> SecondDerivatives<N> {
        if N <= SCALAR_HESSIAN_UP_TO {
            scalar_second_derivatives(self, t, q, v)
        } else {
            second_derivatives_generic(self, t, q, v).into()
        }
    }

    /// The mass matrix ∂²L/∂q̇².
    #[inline]
    fn mass_matrix(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        velocity_hessian(self, t, q, v)
    }

    /// The energy E = p·q̇ − L.
    #[inline]
    fn energy(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> f64 {
        let (value, p) = gradient(
            |y: SVector<DualSVec64<N>, N>| {
                self.lagrangian(DualVec::from_re(t), &q.map(DualVec::from_re), &y)
            },
            v,
        );
        p.dot(v) - value
    }

    /// The inverse Legendre map: the velocity q̇ with ∂L/∂q̇(t, q, q̇) = p, by Newton's method
    /// started at `guess` (for a Lagrangian quadratic in q̇ one iteration is exact).
    fn velocity(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        p: &SVector<f64, N>,
        guess: &SVector<f64, N>,
    ) -> Result<SVector<f64, N>, Error> {
        let mut v = *guess;
        let mut last = f64::INFINITY;
        for iteration in 1..=LEGENDRE_MAX_ITERATIONS {
            let (_, momentum, mass) = hessian(
                |y: SVector<Dual2Vec<f64, Const<N>>, N>| {
                    self.lagrangian(Dual2Vec::from_re(t), &q.map(Dual2Vec::from_re), &y)
                },
                &v,
            );
            let delta = solve_small(mass, p - momentum).ok_or(Error::LegendreMap {
                t,
                iterations: iteration,
                residual: f64::INFINITY,
            })?;
            v += delta;
            let size = delta.amax();
            if !size.is_finite() {
                break;
            }
            let scale = 1.0 + v.amax();
            // Converged: at round-off, or the increment stopped decreasing near it.
            if size <= f64::EPSILON * scale || (size >= last && size <= 1e-10 * scale) {
                return Ok(v);
            }
            last = size;
        }
        Err(Error::LegendreMap {
            t,
            iterations: LEGENDRE_MAX_ITERATIONS,
            residual: last,
        })
    }

    /// The Euler–Lagrange acceleration q̈ = L_vv⁻¹ (L_q − L_vq q̇ − L_vt + f_L), or `None`
    /// where the mass matrix L_vv is singular (f_L only for [`Lagrangian::FORCED`] models).
    #[inline]
    fn acceleration(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> Option<SVector<f64, N>> {
        acceleration_generic(self, t, q, v)
    }

    /// The external force f_L and its Jacobian ∂f_L/∂q, ∂f_L/∂q̇ (two N-sized dual sweeps);
    /// all zero, without evaluating anything, unless the model is [`Lagrangian::FORCED`].
    #[inline]
    fn external_force_jacobian(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> ForceJacobian<N> {
        if !Self::FORCED {
            return ForceJacobian::zeros();
        }
        let (value, dq) = jacobian(
            |x: SVector<DualSVec64<N>, N>| {
                self.external_force(DualVec::from_re(t), &x, &v.map(DualVec::from_re))
            },
            q,
        );
        let (_, dv) = jacobian(
            |y: SVector<DualSVec64<N>, N>| {
                self.external_force(DualVec::from_re(t), &q.map(DualVec::from_re), &y)
            },
            v,
        );
        ForceJacobian {
            value,
            q: dq,
            v: dv,
        }
    }

    /// The acceleration and its exact Jacobian ∂q̈/∂q, ∂q̈/∂q̇ (third derivatives of L, and
    /// first derivatives of the external force of a [`Lagrangian::FORCED`] model, by nested
    /// dual numbers), or `None` where L_vv is singular.
    fn acceleration_jacobian(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> Option<AccelerationJacobian<N>> {
        let (value, dq) = jacobian(
            |x: SVector<DualSVec64<N>, N>| {
                acceleration_generic(self, DualVec::from_re(t), &x, &v.map(DualVec::from_re))
                    .unwrap_or_else(|| SVector::from_element(DualVec::from_re(f64::NAN)))
            },
            q,
        );
        let (_, dv) = jacobian(
            |y: SVector<DualSVec64<N>, N>| {
                acceleration_generic(self, DualVec::from_re(t), &q.map(DualVec::from_re), &y)
                    .unwrap_or_else(|| SVector::from_element(DualVec::from_re(f64::NAN)))
            },
            v,
        );
        value
            .iter()
            .all(|a| a.is_finite())
            .then_some(AccelerationJacobian {
                value,
                q: dq,
                v: dv,
            })
    }

    /// The Noether momentum Jᵢ = p·ξᵢ(q) of symmetry generator `index`.
    fn noether_momentum(
        &self,
        index: usize,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> f64
    where
        Self: Symmetries<N>,
    {
        self.momentum(t, q, v).dot(&self.generator(index, q))
    }

    /// How far generator `index` is from a symmetry of L at (t, q, q̇): the variation
    /// δL = ∂L/∂q·ξ(q) + ∂L/∂q̇·(Dξ(q) q̇) of L along the lifted generator, relative to the
    /// size of its two terms (0 for a symmetry, up to round-off; of order 1 for a generator
    /// that is none, whose "Noether momentum" is then not conserved and measures nothing).
    /// Dξ q̇ is a central difference of ξ along q̇ (ξ is given in `f64` only), accurate to
    /// about 1e-10 relative.
    fn symmetry_defect(&self, index: usize, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> f64
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

impl<L: Lagrangian<N> + ?Sized, const N: usize> LagrangianExt<N> for L {}

/// L, ∂L/∂q, ∂L/∂q̇ and ∂²L/∂q∂q̇ in any scalar type (one partial-Hessian sweep).
#[allow(clippy::type_complexity)]
fn mixed_derivatives<L, D, const N: usize>(
    model: &L,
    t: D,
    q: &SVector<D, N>,
    v: &SVector<D, N>,
) -> (D, SVector<D, N>, SVector<D, N>, SMatrix<D, N, N>)
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
{
    partial_hessian(
        |(x, y): (
            SVector<HyperDualVec<D, Const<N>, Const<N>>, N>,
            SVector<HyperDualVec<D, Const<N>, Const<N>>, N>,
        )| model.lagrangian(HyperDualVec::from_re(t), &x, &y),
        (q, v),
    )
}

/// ∂²L/∂q̇² in any scalar type (one Hessian sweep in q̇).
fn velocity_hessian<L, D, const N: usize>(
    model: &L,
    t: D,
    q: &SVector<D, N>,
    v: &SVector<D, N>,
) -> SMatrix<D, N, N>
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
{
    hessian(
        |y: SVector<Dual2Vec<D, Const<N>>, N>| {
            model.lagrangian(Dual2Vec::from_re(t), &q.map(Dual2Vec::from_re), &y)
        },
        v,
    )
    .2
}

/// Value, gradients and Hessian blocks of L in any scalar type (three N-sized sweeps).
fn second_derivatives_generic<L, D, const N: usize>(
    model: &L,
    t: D,
    q: &SVector<D, N>,
    v: &SVector<D, N>,
) -> SecondDerivativesOf<D, N>
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
{
    let (value, dq, dv, qv) = mixed_derivatives(model, t, q, v);
    let (_, _, qq) = hessian(
        |x: SVector<Dual2Vec<D, Const<N>>, N>| {
            model.lagrangian(Dual2Vec::from_re(t), &x, &v.map(Dual2Vec::from_re))
        },
        q,
    );
    let vv = velocity_hessian(model, t, q, v);
    SecondDerivativesOf {
        value,
        q: dq,
        v: dv,
        qq,
        qv,
        vv,
    }
}

/// [`SecondDerivatives`] in a generic scalar type.
struct SecondDerivativesOf<D: Scalar, const N: usize> {
    value: D,
    q: SVector<D, N>,
    v: SVector<D, N>,
    qq: SMatrix<D, N, N>,
    qv: SMatrix<D, N, N>,
    vv: SMatrix<D, N, N>,
}

impl<const N: usize> From<SecondDerivativesOf<f64, N>> for SecondDerivatives<N> {
    fn from(d: SecondDerivativesOf<f64, N>) -> Self {
        SecondDerivatives {
            value: d.value,
            q: d.q,
            v: d.v,
            qq: d.qq,
            qv: d.qv,
            vv: d.vv,
        }
    }
}

/// ∂²L/∂q̇∂t in any scalar type.
#[allow(clippy::type_complexity)]
fn velocity_time_derivative<L, D, const N: usize>(
    model: &L,
    t: D,
    q: &SVector<D, N>,
    v: &SVector<D, N>,
) -> SVector<D, N>
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
{
    let (_, _, _, vt) = partial_hessian(
        |(y, s): (
            SVector<HyperDualVec<D, Const<N>, Const<1>>, N>,
            SVector<HyperDualVec<D, Const<N>, Const<1>>, 1>,
        )| model.lagrangian(s[0], &q.map(HyperDualVec::from_re), &y),
        (v, &SVector::from([t])),
    );
    vt.column(0).into_owned()
}

/// The (forced) Euler–Lagrange acceleration in any scalar type.
fn acceleration_generic<L, D, const N: usize>(
    model: &L,
    t: D,
    q: &SVector<D, N>,
    v: &SVector<D, N>,
) -> Option<SVector<D, N>>
where
    L: Lagrangian<N> + ?Sized,
    D: Scalar,
{
    // L_q, L_qv from one partial Hessian and L_vv from the Hessian in q̇: L_qq is not needed.
    let (_, lq, _, qv) = mixed_derivatives(model, t, q, v);
    let vv = velocity_hessian(model, t, q, v);
    let mut rhs = lq - qv.transpose() * v;
    if L::TIME_DEPENDENT {
        rhs -= velocity_time_derivative(model, t, q, v);
    }
    if L::FORCED {
        rhs += model.external_force(t, q, v);
    }
    solve_small(vv, rhs)
}

/// M⁻¹ of a [`crate::model::Structure::ConstantMass`] Lagrangian, computed at the first step
/// (at (t, q), with `y` standing in for q̇, which M does not depend on) and cached in `cache`.
pub(crate) fn cached_mass_inverse<L: Lagrangian<N>, const N: usize>(
    cache: &mut Option<SMatrix<f64, N, N>>,
    model: &L,
    t: f64,
    q: &SVector<f64, N>,
    y: &SVector<f64, N>,
) -> Result<SMatrix<f64, N, N>, crate::error::StepFailure> {
    if let Some(inverse) = cache {
        return Ok(*inverse);
    }
    let mass = model.mass_matrix(t, q, y);
    let inverse =
        crate::linalg::invert_small(&mass).ok_or(crate::error::StepFailure::SingularMatrix)?;
    Ok(*cache.insert(inverse))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Structure;
    use crate::test_models::{Oscillator, VariableMass};

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
    impl Lagrangian<1> for TimeDependentMass {
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            (t.sin() + 2.0) * v[0] * v[0] * 0.5 - q[0] * q[0] * 0.5
        }
    }

    /// Forced oscillator: L = q̇²/2 − q²/2, f_L = −c q̇ − b q³ + a cos t.
    struct Forced;
    const DAMPING: f64 = 0.3;
    const CUBIC: f64 = 0.2;
    const DRIVE: f64 = 0.5;
    impl Lagrangian<1> for Forced {
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
    impl Lagrangian<1> for Relativistic {
        const TIME_DEPENDENT: bool = false;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            -(-(v[0] * v[0]) + 1.0).sqrt() - q[0] * q[0] * 0.5
        }
    }

    /// Singular mass matrix: L = ½ q̇₀² − ½ q₀² − ½ q₁² (q₁ has no kinetic term).
    struct Degenerate;
    impl Lagrangian<2> for Degenerate {
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v[0] * v[0] - q[0] * q[0] - q[1] * q[1]) * 0.5
        }
    }

    /// Planar isotropic oscillator L = ½|q̇|² − ½|q|², invariant under rotations
    /// ξ(q) = (−q₁, q₀): the Noether momentum is the angular momentum q₀ q̇₁ − q₁ q̇₀.
    struct Planar;
    impl Lagrangian<2> for Planar {
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v.dot(v) - q.dot(q)) * 0.5
        }
    }
    impl Symmetries<2> for Planar {
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
    impl Lagrangian<2> for ConstantMass {
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
            let vector: SecondDerivatives<2> =
                second_derivatives_generic(&model, 0.0, &q, &v).into();
            assert_close(&vector.q, &second.q, 1e-15);
            assert_close(&vector.v, &second.v, 1e-15);
            assert_close(&vector.qq, &second.qq, 1e-15);
            assert_close(&vector.qv, &second.qv, 1e-15);
            assert_close(&vector.vv, &second.vv, 1e-15);
            assert_close(
                &model.mass_matrix(0.0, &q, &v),
                &variable_mass::lvv(&q),
                1e-15,
            );
        }
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
    fn assert_jacobian_matches_central_differences<L: Lagrangian<N>, const N: usize>(
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
        for p in [0.3f64, -1.7, 4.0] {
            let q = SVector::from([0.2]);
            let guess = SVector::from([0.99 * p.signum()]);
            let v = Relativistic
                .velocity(0.0, &q, &SVector::from([p]), &guess)
                .unwrap()[0];
            let expected = p / (1.0 + p * p).sqrt();
            assert!(
                (v - expected).abs() <= 2.0 * f64::EPSILON,
                "{v} vs {expected}"
            );
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
            ForceJacobian::zeros()
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
        impl Lagrangian<2> for Translated {
            fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
                Planar.lagrangian(t, q, v)
            }
        }
        impl Symmetries<2> for Translated {
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
        assert_close(&inverse, &expected, 1e-15);
        // A cached value is returned as is: a stale cache proves no recomputation.
        let stale = SMatrix::<f64, 2, 2>::identity();
        cache = Some(stale);
        let again = cached_mass_inverse(&mut cache, &ConstantMass, 1.0, &q, &y).unwrap();
        assert_eq!(again, stale);
    }
}
