//! The size of a configuration space, fixed when the program is compiled or chosen at run
//! time, and the automatic differentiation that suits each.
//!
//! A model on ℝᴺ names its dimension as a type: nalgebra's `Const<N>` (`U2`, `U3`, …) when N
//! is known at compile time — vectors live on the stack and derivatives are taken with
//! num-dual's vector duals carrying N directions at once —, or [`Dyn`] when N is known only
//! at run time (a text model, a chain whose length is an option) — vectors live on the heap
//! and derivatives are taken by scalar sweeps, one dual direction at a time (num-dual's
//! run-time-sized duals are not `Copy`, which [`Scalar`] requires). Every method and every
//! quantity derived from a Lagrangian is written once, generic over [`Dimension`]; the
//! choice of dual numbers is the one thing that differs, and it lives here.
//!
//! The derivatives are of functions of (t, q, q̇) written generic over the scalar
//! ([`PhaseFunction`], [`PhaseMap`]), at points whose coordinates may themselves be dual
//! numbers (nested duals give the third derivatives of the Euler–Lagrange Jacobian).

use crate::linalg::combination::Combination;
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, U1};
use num_dual::{Dual, Dual2Vec, DualVec, HyperDual, HyperDualVec};

pub use nalgebra::Dyn;

/// A scalar function f(t, q, q̇) on ℝᴺ, written once, generic over the scalar.
pub trait PhaseFunction<N: Dim>
where
    DefaultAllocator: Allocator<N>,
{
    /// The value f(t, q, q̇).
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> S;
}

/// A vector function F(t, q, q̇) ∈ ℝᴺ on ℝᴺ, written once, generic over the scalar.
pub trait PhaseMap<N: Dim>
where
    DefaultAllocator: Allocator<N>,
{
    /// The value F(t, q, q̇).
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, v: &OVector<S, N>) -> OVector<S, N>;
}

/// Which argument a derivative is taken in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrt {
    /// The configuration q.
    Position,
    /// The velocity q̇.
    Velocity,
}

/// Largest fixed dimension whose gradients are taken as N scalar-dual sweeps rather than one
/// vector-dual sweep. Scalar sweeps are cheap where the compiler inlines L into each and
/// shares its transcendental functions between them (`cargo bench --bench derivatives --
/// chain`, run with this constant at 2, 3 and 4: on the coupled chain of pendulums the force
/// costs 50 ns by scalar sweeps against 81 ns by one vector sweep at N = 3, but 334 ns
/// against 189 ns at N = 4). Kepler's force costs 6.8 ns by two scalar sweeps against 16 ns
/// with one `DualSVec64<2>` sweep (`cargo bench --bench derivatives -- kepler/force`).
pub const SCALAR_SWEEPS_UP_TO: usize = 3;

/// Largest fixed dimension whose N × N Hessians (in q or in q̇) are taken as N(N + 1)/2 sweeps
/// of the scalar `HyperDual<D>`, one per entry, rather than one `Dual2Vec` sweep
/// (`cargo bench --bench derivatives -- force_jacobian`, L_qq with this constant at 0 and 4:
/// Kepler 17 ns against 52 ns, the double pendulum 50 ns against 119 ns, but the coupled
/// chain of pendulums 404 ns against 190 ns at N = 3 and 947 ns against 629 ns at N = 4).
pub const SCALAR_HESSIAN_SWEEPS_UP_TO: usize = 2;

/// The dimension of a configuration space: `Const<N>` or [`Dyn`]. Implemented for exactly
/// these; it chooses the dual numbers of every derivative in `svi` (and, through a
/// crate-internal supertrait, how SVI's stage sums run at each size).
///
/// Each function differentiates `f` at (t, q, q̇), whose coordinates are of any scalar type
/// `D` (nested duals for higher derivatives), and returns the value with the derivatives.
pub trait Dimension: Dim + Combination {
    /// f and ∂f/∂q (or ∂f/∂q̇).
    fn gradient<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>)
    where
        DefaultAllocator: Allocator<Self> + Allocator<Self, Self>;

    /// f, its gradient and its Hessian in q (or in q̇).
    fn hessian<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>, OMatrix<D, Self, Self>)
    where
        DefaultAllocator: Allocator<Self> + Allocator<Self, Self>;

    /// f, ∂f/∂q, ∂f/∂q̇ and the mixed block ∂²f/∂q∂q̇ (entry (i, j) = ∂²f/∂qᵢ∂q̇ⱼ).
    #[allow(clippy::type_complexity)]
    fn mixed<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> (
        D,
        OVector<D, Self>,
        OVector<D, Self>,
        OMatrix<D, Self, Self>,
    )
    where
        DefaultAllocator: Allocator<Self> + Allocator<Self, Self>;

    /// ∂²f/∂q̇∂t.
    fn velocity_time<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> OVector<D, Self>
    where
        DefaultAllocator: Allocator<Self> + Allocator<Self, Self>;

    /// F and its Jacobian ∂F/∂q (or ∂F/∂q̇), entry (i, j) = ∂Fᵢ/∂xⱼ.
    fn jacobian<D: Scalar, F: PhaseMap<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (OVector<D, Self>, OMatrix<D, Self, Self>)
    where
        DefaultAllocator: Allocator<Self> + Allocator<Self, Self>;
}

/// The dimension of a model of `size` coordinates whose dimension type is `N`, or a
/// description of why there is none (`N` fixed to another size, or no coordinate at all).
pub fn dimension_of<N: Dim>(size: usize) -> Result<N, String> {
    match N::try_to_usize() {
        Some(fixed) if fixed != size => Err(format!(
            "the model says it has {size} coordinates but its type fixes {fixed}"
        )),
        _ if size == 0 => Err(
            "the model has no coordinates (a run-time-size model must say its \
                               size through `Lagrangian::dimension`)"
                .into(),
        ),
        _ => Ok(N::from_usize(size)),
    }
}

/// [`Dimension::gradient`] by n sweeps of the scalar dual `Dual<D>`: (q, q̇) are lifted once,
/// and each sweep seeds one coordinate and clears it again.
pub fn scalar_gradient<N: Dim, D: Scalar, F: PhaseFunction<N> + ?Sized>(
    f: &F,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
    wrt: Wrt,
) -> (D, OVector<D, N>)
where
    DefaultAllocator: Allocator<N>,
{
    let (n, _) = q.shape_generic();
    let (mut x, mut y) = (q.map(Dual::from_re), v.map(Dual::from_re));
    let time = Dual::from_re(t);
    let mut value = D::zero();
    let mut gradient = OVector::zeros_generic(n, U1);
    for i in 0..n.value() {
        let seeded = match wrt {
            Wrt::Position => &mut x[i],
            Wrt::Velocity => &mut y[i],
        };
        seeded.eps = D::one();
        let result = f.eval(time, &x, &y);
        match wrt {
            Wrt::Position => x[i].eps = D::zero(),
            Wrt::Velocity => y[i].eps = D::zero(),
        }
        value = result.re;
        gradient[i] = result.eps;
    }
    (value, gradient)
}

/// [`Dimension::hessian`] by n(n + 1)/2 sweeps of the scalar hyper-dual `HyperDual<D>`, one
/// per entry i ≤ j: seeded with ε₁ on xᵢ and ε₂ on xⱼ it carries ∂²f/∂xᵢ∂xⱼ in ε₁ε₂ and, for
/// i = j, ∂f/∂xᵢ in ε₁.
#[allow(clippy::type_complexity)]
pub fn scalar_hessian<N: Dim, D: Scalar, F: PhaseFunction<N> + ?Sized>(
    f: &F,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
    wrt: Wrt,
) -> (D, OVector<D, N>, OMatrix<D, N, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (n, _) = q.shape_generic();
    let (mut x, mut y) = (q.map(HyperDual::from_re), v.map(HyperDual::from_re));
    let time = HyperDual::from_re(t);
    let mut value = D::zero();
    let mut gradient = OVector::zeros_generic(n, U1);
    let mut hessian = OMatrix::zeros_generic(n, n);
    for i in 0..n.value() {
        for j in i..n.value() {
            let seeded = match wrt {
                Wrt::Position => &mut x,
                Wrt::Velocity => &mut y,
            };
            seeded[i].eps1 = D::one();
            seeded[j].eps2 = D::one();
            let result = f.eval(time, &x, &y);
            let seeded = match wrt {
                Wrt::Position => &mut x,
                Wrt::Velocity => &mut y,
            };
            seeded[i].eps1 = D::zero();
            seeded[j].eps2 = D::zero();
            if i == j {
                value = result.re;
                gradient[i] = result.eps1;
            }
            hessian[(i, j)] = result.eps1eps2;
            hessian[(j, i)] = result.eps1eps2;
        }
    }
    (value, gradient, hessian)
}

/// [`Dimension::mixed`] by n² sweeps of `HyperDual<D>`: ε₁ on qᵢ, ε₂ on q̇ⱼ.
#[allow(clippy::type_complexity)]
pub fn scalar_mixed<N: Dim, D: Scalar, F: PhaseFunction<N> + ?Sized>(
    f: &F,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
) -> (D, OVector<D, N>, OVector<D, N>, OMatrix<D, N, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (n, _) = q.shape_generic();
    let (mut x, mut y) = (q.map(HyperDual::from_re), v.map(HyperDual::from_re));
    let time = HyperDual::from_re(t);
    let mut value = D::zero();
    let mut dq = OVector::zeros_generic(n, U1);
    let mut dv = OVector::zeros_generic(n, U1);
    let mut qv = OMatrix::zeros_generic(n, n);
    for i in 0..n.value() {
        x[i].eps1 = D::one();
        for j in 0..n.value() {
            y[j].eps2 = D::one();
            let result = f.eval(time, &x, &y);
            y[j].eps2 = D::zero();
            value = result.re;
            dq[i] = result.eps1;
            dv[j] = result.eps2;
            qv[(i, j)] = result.eps1eps2;
        }
        x[i].eps1 = D::zero();
    }
    (value, dq, dv, qv)
}

/// [`Dimension::velocity_time`] by n sweeps of `HyperDual<D>`: ε₁ on q̇ᵢ, ε₂ on t.
pub fn scalar_velocity_time<N: Dim, D: Scalar, F: PhaseFunction<N> + ?Sized>(
    f: &F,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
) -> OVector<D, N>
where
    DefaultAllocator: Allocator<N>,
{
    let (n, _) = q.shape_generic();
    let time = HyperDual::new(t, D::zero(), D::one(), D::zero());
    let (x, mut y) = (q.map(HyperDual::from_re), v.map(HyperDual::from_re));
    let mut mixed = OVector::zeros_generic(n, U1);
    for i in 0..n.value() {
        y[i].eps1 = D::one();
        mixed[i] = f.eval(time, &x, &y).eps1eps2;
        y[i].eps1 = D::zero();
    }
    mixed
}

/// [`Dimension::jacobian`] by n sweeps of the scalar dual `Dual<D>`, one column each.
pub fn scalar_jacobian<N: Dim, D: Scalar, F: PhaseMap<N> + ?Sized>(
    f: &F,
    t: D,
    q: &OVector<D, N>,
    v: &OVector<D, N>,
    wrt: Wrt,
) -> (OVector<D, N>, OMatrix<D, N, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (n, _) = q.shape_generic();
    let (mut x, mut y) = (q.map(Dual::from_re), v.map(Dual::from_re));
    let time = Dual::from_re(t);
    let mut value = OVector::zeros_generic(n, U1);
    let mut jacobian = OMatrix::zeros_generic(n, n);
    for j in 0..n.value() {
        match wrt {
            Wrt::Position => x[j].eps = D::one(),
            Wrt::Velocity => y[j].eps = D::one(),
        }
        let result = f.eval(time, &x, &y);
        match wrt {
            Wrt::Position => x[j].eps = D::zero(),
            Wrt::Velocity => y[j].eps = D::zero(),
        }
        for i in 0..n.value() {
            value[i] = result[i].re;
            jacobian[(i, j)] = result[i].eps;
        }
    }
    (value, jacobian)
}

impl Dimension for Dyn {
    #[inline]
    fn gradient<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>) {
        scalar_gradient(f, t, q, v, wrt)
    }

    #[inline]
    fn hessian<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>, OMatrix<D, Self, Self>) {
        scalar_hessian(f, t, q, v, wrt)
    }

    #[inline]
    fn mixed<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> (
        D,
        OVector<D, Self>,
        OVector<D, Self>,
        OMatrix<D, Self, Self>,
    ) {
        scalar_mixed(f, t, q, v)
    }

    #[inline]
    fn velocity_time<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> OVector<D, Self> {
        scalar_velocity_time(f, t, q, v)
    }

    #[inline]
    fn jacobian<D: Scalar, F: PhaseMap<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (OVector<D, Self>, OMatrix<D, Self, Self>) {
        scalar_jacobian(f, t, q, v, wrt)
    }
}

/// The two seeded arguments of num-dual's `partial_hessian`.
type Pair<T, A, B> = (OVector<T, A>, OVector<T, B>);

impl<const K: usize> Dimension for Const<K> {
    #[inline]
    fn gradient<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>) {
        if K <= SCALAR_SWEEPS_UP_TO {
            return scalar_gradient(f, t, q, v, wrt);
        }
        match wrt {
            Wrt::Position => num_dual::gradient(
                |x: OVector<DualVec<D, Self>, Self>| {
                    f.eval(DualVec::from_re(t), &x, &v.map(DualVec::from_re))
                },
                q,
            ),
            Wrt::Velocity => num_dual::gradient(
                |y: OVector<DualVec<D, Self>, Self>| {
                    f.eval(DualVec::from_re(t), &q.map(DualVec::from_re), &y)
                },
                v,
            ),
        }
    }

    #[inline]
    fn hessian<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (D, OVector<D, Self>, OMatrix<D, Self, Self>) {
        if K <= SCALAR_HESSIAN_SWEEPS_UP_TO {
            return scalar_hessian(f, t, q, v, wrt);
        }
        match wrt {
            Wrt::Position => num_dual::hessian(
                |x: OVector<Dual2Vec<D, Self>, Self>| {
                    f.eval(Dual2Vec::from_re(t), &x, &v.map(Dual2Vec::from_re))
                },
                q,
            ),
            Wrt::Velocity => num_dual::hessian(
                |y: OVector<Dual2Vec<D, Self>, Self>| {
                    f.eval(Dual2Vec::from_re(t), &q.map(Dual2Vec::from_re), &y)
                },
                v,
            ),
        }
    }

    #[inline]
    fn mixed<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> (
        D,
        OVector<D, Self>,
        OVector<D, Self>,
        OMatrix<D, Self, Self>,
    ) {
        num_dual::partial_hessian(
            |(x, y): Pair<HyperDualVec<D, Self, Self>, Self, Self>| {
                f.eval(HyperDualVec::from_re(t), &x, &y)
            },
            (q, v),
        )
    }

    #[inline]
    fn velocity_time<D: Scalar, F: PhaseFunction<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
    ) -> OVector<D, Self> {
        let (_, _, _, vt) = num_dual::partial_hessian(
            |(y, s): Pair<HyperDualVec<D, Self, U1>, Self, U1>| {
                f.eval(s[0], &q.map(HyperDualVec::from_re), &y)
            },
            (v, &OVector::<D, U1>::from_element(t)),
        );
        vt.column(0).into_owned()
    }

    #[inline]
    fn jacobian<D: Scalar, F: PhaseMap<Self> + ?Sized>(
        f: &F,
        t: D,
        q: &OVector<D, Self>,
        v: &OVector<D, Self>,
        wrt: Wrt,
    ) -> (OVector<D, Self>, OMatrix<D, Self, Self>) {
        match wrt {
            Wrt::Position => num_dual::jacobian(
                |x: OVector<DualVec<D, Self>, Self>| {
                    f.eval(DualVec::from_re(t), &x, &v.map(DualVec::from_re))
                },
                q,
            ),
            Wrt::Velocity => num_dual::jacobian(
                |y: OVector<DualVec<D, Self>, Self>| {
                    f.eval(DualVec::from_re(t), &q.map(DualVec::from_re), &y)
                },
                v,
            ),
        }
    }
}
