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
//! - the Hessian blocks L_qq, L_qv, L_vv (`hessian` in q, `hessian` in q̇ and one
//!   `partial_hessian`: `2N` is not a const expression on stable Rust, so the full
//!   second derivative is assembled from three N-sized sweeps);
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

use crate::linalg::solve_small;
use crate::model::{Lagrangian, Symmetries};
use crate::{Error, Scalar};
use nalgebra::{Const, SMatrix, SVector};
use num_dual::{
    Dual2Vec, Dual64, DualSVec64, DualVec, HyperDualVec, gradient, hessian, jacobian,
    partial_hessian,
};

/// Largest dimension whose gradients are taken as N scalar-dual sweeps rather than one
/// vector-dual sweep.
pub const SCALAR_SWEEPS_UP_TO: usize = 4;

/// ∇f(x) for f: ℝᴺ → ℝ: N forward sweeps with `Dual64` for small N, else one `DualSVec64<N>`
/// sweep. `f` receives the seeded argument.
#[inline]
fn gradient_of<const N: usize>(
    f_scalar: impl Fn(SVector<Dual64, N>) -> Dual64,
    f_vector: impl Fn(SVector<DualSVec64<N>, N>) -> DualSVec64<N>,
    x: &SVector<f64, N>,
) -> SVector<f64, N> {
    if N <= SCALAR_SWEEPS_UP_TO {
        SVector::from_fn(|i, _| {
            f_scalar(SVector::from_fn(|j, _| {
                Dual64::new(x[j], if i == j { 1.0 } else { 0.0 })
            }))
            .eps
        })
    } else {
        gradient(f_vector, x).1
    }
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
        let (value, dq) = gradient(
            |x: SVector<DualSVec64<N>, N>| {
                self.lagrangian(DualVec::from_re(t), &x, &v.map(DualVec::from_re))
            },
            q,
        );
        let (_, dv) = gradient(
            |y: SVector<DualSVec64<N>, N>| {
                self.lagrangian(DualVec::from_re(t), &q.map(DualVec::from_re), &y)
            },
            v,
        );
        FirstDerivatives {
            value,
            q: dq,
            v: dv,
        }
    }

    /// The generalised force ∂L/∂q alone (one gradient).
    #[inline]
    fn force(&self, t: f64, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N> {
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
    }

    /// L, its gradients and its Hessian blocks.
    #[inline]
    fn second_derivatives(
        &self,
        t: f64,
        q: &SVector<f64, N>,
        v: &SVector<f64, N>,
    ) -> SecondDerivatives<N> {
        second_derivatives_generic(self, t, q, v).into()
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

/// M⁻¹ of a [`crate::Structure::ConstantMass`] Lagrangian, computed at the first step (at
/// the state's (t, q), with its second coordinate standing in for q̇, which M does not depend
/// on) and cached in `cache`.
pub(crate) fn cached_mass_inverse<L: Lagrangian<N>, const N: usize>(
    cache: &mut Option<SMatrix<f64, N, N>>,
    model: &L,
    t: f64,
    state: &crate::State<N>,
) -> Result<SMatrix<f64, N, N>, crate::error::StepFailure> {
    if let Some(inverse) = cache {
        return Ok(*inverse);
    }
    let mass = model.mass_matrix(t, &state.q, &state.y);
    let inverse =
        crate::linalg::invert_small(&mass).ok_or(crate::error::StepFailure::SingularMatrix)?;
    Ok(*cache.insert(inverse))
}
