//! What a user writes when the system comes as a Hamiltonian H(t, q, p).
//!
//! [`Hamiltonian::hamiltonian`] is one function generic over [`Scalar`], like
//! [`Lagrangian::lagrangian`]; a non-conservative force enters as f_H(t, q, p) in Hamilton's
//! equations
//!
//! q̇ = ∂H/∂p,   ṗ = −∂H/∂q + f_H(t, q, p)
//!
//! (the forced Hamiltonian form of Porcù–Penati's package, `002`, "Forced mechanics").
//!
//! A Hamiltonian runs as a model through the adapter [`Canonical`], which is a [`Lagrangian`]:
//! every method of svi runs it, and so do the observers, the stepping loop and the front
//! doors. The adapter carries H to the methods without a detour, through
//! [`Lagrangian::hamiltonian_form`] ([`HamiltonianForm`]: H, its gradient and Hessian blocks
//! and f_H by automatic differentiation of the one function), so the Hamiltonian methods
//! ([`crate::method::hamiltonian`]) never solve a Legendre map on a model written as H. The
//! Lagrangian methods see L(t, q, q̇) = p·q̇ − H(t, q, p) with p the solution of
//! ∂H/∂p(t, q, p) = q̇ (the inverse Legendre map): for [`HamiltonianStructure::QuadraticKinetic`]
//! in closed form, L = ½ q̇ᵀMq̇ − H(t, q, 0) with M = (∂²H/∂p²)⁻¹ computed once; otherwise
//! p is solved by Newton's method at the real parts of (q, q̇) and refined in the scalar of the
//! call by chord steps with the real Jacobian ∂²H/∂p², each of which makes one more order of
//! the dual parts exact (the error's lowest ε-degree rises by one per step), so every
//! derivative the methods take of L — up to third order — is the derivative of the true
//! Legendre transform.
//!
//! The reverse direction, a model written as L run by the Hamiltonian methods, needs H's
//! derivatives from L's: [`crate::model::canonical`].

use crate::dimension::{Dimension, PhaseFunction, PhaseMap, Wrt};
use crate::error::Error;
use crate::linalg::{invert_small, solve_small};
use crate::model::{Defaults, ExactSolution, Invariants, Lagrangian, Structure, Symmetries};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OMatrix, OVector, U1};
use std::sync::OnceLock;

/// A Hamiltonian H(t, q, p) on T*ℝᴺ, written once, generic over the scalar type.
///
/// # Example
/// ```
/// use nalgebra::{SVector, U1};
/// use svi::model::hamiltonian::{Hamiltonian, HamiltonianStructure};
/// use svi::Scalar;
///
/// /// The pendulum, H = p²/2 − cos q.
/// struct Pendulum;
///
/// impl Hamiltonian<U1> for Pendulum {
///     const TIME_DEPENDENT: bool = false;
///     const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
///     fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
///         p[0] * p[0] * 0.5 - q[0].cos()
///     }
/// }
/// ```
pub trait Hamiltonian<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Whether H depends explicitly on t. The default (`true`) is always correct.
    const TIME_DEPENDENT: bool = true;

    /// Structure the integrators may exploit; the default ([`HamiltonianStructure::General`])
    /// is always correct. The declaration is checked at the initial state of an integrator's
    /// first run.
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::General;

    /// Whether the model has a non-conservative force f_H ([`Hamiltonian::external_force`]);
    /// with `false` (the default) no integrator evaluates it.
    const FORCED: bool = false;

    /// The number of coordinates (the default is right for a fixed dimension).
    fn dimension(&self) -> usize {
        N::try_to_usize().unwrap_or(0)
    }

    /// The structure of this H, at run time: [`Hamiltonian::STRUCTURE`] (the default), or a
    /// more specific one that only the value knows — a Hamiltonian written as text is
    /// [`HamiltonianStructure::Separable`] when its expression is T(p) + V(t, q). The methods
    /// on Hamilton's equations read it (a separable H steps explicitly); it is checked at the
    /// initial state like the declaration.
    fn structure(&self) -> HamiltonianStructure {
        Self::STRUCTURE
    }

    /// The value H(t, q, p). Mark it `#[inline]`, as a Lagrangian.
    fn hamiltonian<D: Scalar>(&self, t: D, q: &OVector<D, N>, p: &OVector<D, N>) -> D;

    /// The non-conservative force f_H(t, q, p) of ṗ = −∂H/∂p + f_H, read only when
    /// [`Hamiltonian::FORCED`] is `true`; zero by default.
    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        p: &OVector<D, N>,
    ) -> OVector<D, N> {
        let _ = (t, p);
        OVector::zeros_generic(q.shape_generic().0, U1)
    }
}

/// Structure of a Hamiltonian that integrators may exploit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HamiltonianStructure {
    /// No assumption beyond regularity (∂²H/∂p² invertible).
    General,
    /// H = T(p) + V(t, q): Störmer–Verlet and its compositions split it into explicit kicks
    /// and drifts, with any T (a relativistic kinetic energy included).
    Separable,
    /// H = ½ pᵀM⁻¹p + V(t, q) with a constant symmetric positive-definite M: separable, and
    /// its Lagrangian ½ q̇ᵀMq̇ − V is a [`Structure::ConstantMass`] one.
    QuadraticKinetic,
}

impl HamiltonianStructure {
    /// Whether H = T(p) + V(t, q).
    pub fn is_separable(self) -> bool {
        !matches!(self, HamiltonianStructure::General)
    }
}

/// H, its derivatives and f_H at (t, q, p) as plain numbers: what a model answers through
/// [`Lagrangian::hamiltonian_form`] when it was written as a Hamiltonian (object-safe, so
/// every generic method sees it, like [`crate::model::TermSum`]).
pub trait HamiltonianForm<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The declared structure.
    fn structure(&self) -> HamiltonianStructure;

    /// Whether f_H is present.
    fn forced(&self) -> bool;

    /// Whether the model has no Lagrangian: the right-hand side of Hamilton's equations alone
    /// ([`crate::model::rhs::HamiltonianRhs`]) or an H of local terms
    /// ([`crate::model::local_hamiltonian::LocalCanonical`]). Only the methods on Hamilton's
    /// equations run it, and a momentum from a velocity solves ∂H/∂p = q̇ with H's own
    /// derivatives.
    fn without_lagrangian(&self) -> bool {
        false
    }

    /// H(t, q, p).
    fn value(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> f64;

    /// (∂H/∂q, ∂H/∂p).
    fn gradient(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> (OVector<f64, N>, OVector<f64, N>);

    /// The velocity q̇ = ∂H/∂p alone (one sweep in p: what observers and the inverse
    /// Legendre map ask for).
    fn velocity(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> OVector<f64, N>;

    /// ∂H/∂q alone (the kicks of a separable H). By default the first half of
    /// [`HamiltonianForm::gradient`]; a model that can take it in one sweep does.
    fn position_gradient(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> OVector<f64, N> {
        self.gradient(t, q, p).0
    }

    /// H with its gradient and Hessian blocks.
    fn second(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> CanonicalSecond<N>;

    /// f_H(t, q, p) (zero for an unforced model).
    fn force(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> OVector<f64, N>;

    /// (∂f_H/∂q, ∂f_H/∂p), entry (i, j) = ∂fᵢ/∂xⱼ.
    fn force_jacobian(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> (OMatrix<f64, N, N>, OMatrix<f64, N, N>);

    /// Check H at (t, q, p): finite, ∂²H/∂p² invertible, and the declared structure.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite H or gradient, [`Error::InvalidParameter`]
    /// `model` for a singular ∂²H/∂p² or a structure H does not have.
    fn check(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> Result<(), Error>;
}

/// H with its gradient and Hessian blocks at one point.
#[derive(Debug, Clone)]
pub struct CanonicalSecond<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// H.
    pub value: f64,
    /// ∂H/∂q.
    pub hq: OVector<f64, N>,
    /// ∂H/∂p.
    pub hp: OVector<f64, N>,
    /// ∂²H/∂q², entry (i, j) = ∂²H/∂qᵢ∂qⱼ.
    pub qq: OMatrix<f64, N, N>,
    /// ∂²H/∂q∂p, entry (i, j) = ∂²H/∂qᵢ∂pⱼ.
    pub qp: OMatrix<f64, N, N>,
    /// ∂²H/∂p², entry (i, j) = ∂²H/∂pᵢ∂pⱼ.
    pub pp: OMatrix<f64, N, N>,
}

/// Most Newton iterations of the inverse Legendre map p(q, q̇) at the real parts.
const MOMENTUM_MAX_ITERATIONS: usize = 100;

/// Chord steps in the scalar of a call: the dual parts are exact to this order (the methods
/// take at most third derivatives of L).
const CHORD_STEPS: usize = 4;

/// A Hamiltonian model run as a [`Lagrangian`] (see the module docs): `Canonical::new(h)`.
///
/// ```
/// use nalgebra::{SVector, U1};
/// use svi::method::hamiltonian::galerkin::HamiltonianGalerkin;
/// use svi::{Canonical, Hamiltonian, HamiltonianStructure, Initial, Integrator, Scalar};
///
/// /// The pendulum, H = p²/2 − cos q.
/// struct Pendulum;
///
/// impl Hamiltonian<U1> for Pendulum {
///     const TIME_DEPENDENT: bool = false;
///     const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
///     fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
///         p[0] * p[0] * 0.5 - q[0].cos()
///     }
/// }
///
/// let integrator = Integrator::new(Canonical::new(Pendulum), HamiltonianGalerkin::new(7));
/// let initial = Initial::Momentum { q: SVector::from([1.0]), p: SVector::from([0.0]) };
/// let run = integrator.run(0.0, initial, 0.1, 10.0, &mut ())?;
/// let energy = run.last.p[0].powi(2) * 0.5 - run.last.q[0].cos();
/// assert!((energy + 1f64.cos()).abs() < 1e-13);
/// # Ok::<(), svi::Error>(())
/// ```
///
/// The companions of a Hamiltonian ([`HamiltonianDefaults`], [`HamiltonianSymmetries`],
/// [`HamiltonianInvariants`], [`HamiltonianExactSolution`]) become the Lagrangian ones, so a
/// model written as H runs wherever a model written as L does.
pub struct Canonical<H> {
    model: H,
    /// M = (∂²H/∂p²)⁻¹ of a [`HamiltonianStructure::QuadraticKinetic`] H, column-major,
    /// computed at the first point the model is evaluated at.
    mass: OnceLock<Mass>,
}

/// The constant mass matrix M of a [`HamiltonianStructure::QuadraticKinetic`] H, in the
/// cheapest form it takes (most models have M = m I): the force of a constant-mass method
/// differentiates ½ q̇ᵀMq̇ at every point even though it does not depend on q.
#[derive(Debug, Clone)]
enum Mass {
    /// M = m I.
    Scaled(f64),
    /// M = diag(mᵢ).
    Diagonal(Vec<f64>),
    /// Any M, column-major.
    Dense(Vec<f64>),
}

impl Mass {
    /// M from its entries (column-major n × n).
    fn new(entries: &[f64], n: usize) -> Self {
        let diagonal: Vec<f64> = (0..n).map(|i| entries[i * (n + 1)]).collect();
        let off_diagonal = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .any(|(i, j)| i != j && entries[i + n * j] != 0.0);
        if off_diagonal {
            Mass::Dense(entries.to_vec())
        } else if diagonal.iter().all(|&m| m == diagonal[0]) {
            Mass::Scaled(diagonal[0])
        } else {
            Mass::Diagonal(diagonal)
        }
    }

    /// M q̇.
    #[inline]
    fn apply<D: Scalar, N: Dimension>(&self, v: &OVector<D, N>) -> OVector<D, N>
    where
        DefaultAllocator: Allocator<N>,
    {
        match self {
            Mass::Scaled(m) => v * D::from(*m),
            Mass::Diagonal(m) => {
                OVector::from_fn_generic(v.shape_generic().0, U1, |i, _| v[i] * m[i])
            }
            Mass::Dense(m) => {
                let n = v.len();
                OVector::from_fn_generic(v.shape_generic().0, U1, |i, _| {
                    (0..n).fold(D::zero(), |sum, j| sum + v[j] * m[i + n * j])
                })
            }
        }
    }

    /// ½ q̇ᵀMq̇.
    #[inline]
    fn kinetic<D: Scalar, N: Dimension>(&self, v: &OVector<D, N>) -> D
    where
        DefaultAllocator: Allocator<N>,
    {
        match self {
            Mass::Scaled(m) => v.dot(v) * (0.5 * m),
            Mass::Diagonal(m) => {
                (0..v.len()).fold(D::zero(), |sum, i| sum + v[i] * v[i] * m[i]) * 0.5
            }
            Mass::Dense(_) => self.apply(v).dot(v) * 0.5,
        }
    }
}

impl<H: Clone> Clone for Canonical<H> {
    fn clone(&self) -> Self {
        Canonical {
            model: self.model.clone(),
            mass: self.mass.clone(),
        }
    }
}

impl<H: std::fmt::Debug> std::fmt::Debug for Canonical<H> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Canonical").field(&self.model).finish()
    }
}

impl<H> Canonical<H> {
    /// The Hamiltonian `model` as a model of svi.
    pub fn new(model: H) -> Self {
        Canonical {
            model,
            mass: OnceLock::new(),
        }
    }

    /// The Hamiltonian.
    pub fn hamiltonian(&self) -> &H {
        &self.model
    }

    /// The Hamiltonian, for changing its parameters (the cached mass matrix is dropped).
    pub fn hamiltonian_mut(&mut self) -> &mut H {
        self.mass = OnceLock::new();
        &mut self.model
    }

    /// The Hamiltonian back.
    pub fn into_inner(self) -> H {
        self.model
    }
}

/// H as a [`PhaseFunction`] of (t, q, p) (p in the slot of q̇).
struct Energy<'a, H>(&'a H);

impl<H: Hamiltonian<N>, N: Dimension> PhaseFunction<N> for Energy<'_, H>
where
    DefaultAllocator: Allocator<N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, p: &OVector<S, N>) -> S {
        self.0.hamiltonian(t, q, p)
    }
}

/// f_H as a [`PhaseMap`] of (t, q, p).
struct Force<'a, H>(&'a H);

impl<H: Hamiltonian<N>, N: Dimension> PhaseMap<N> for Force<'_, H>
where
    DefaultAllocator: Allocator<N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, t: S, q: &OVector<S, N>, p: &OVector<S, N>) -> OVector<S, N> {
        self.0.external_force(t, q, p)
    }
}

impl<H> Canonical<H> {
    /// M = (∂²H/∂p²)⁻¹, from its first evaluation (at the real parts of (t, q), p = 0); NaN
    /// if ∂²H/∂p² is singular there (a run then stops with a non-finite error, and
    /// [`HamiltonianForm::check`] names the cause).
    #[inline]
    fn mass<D: Scalar, N: Dimension>(&self, t: D, q: &OVector<D, N>) -> &Mass
    where
        H: Hamiltonian<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        match self.mass.get() {
            Some(mass) => mass,
            None => self.first_mass(t.re(), &q.map(|x| x.re())),
        }
    }

    /// [`Canonical::mass`] at its first evaluation.
    #[cold]
    #[inline(never)]
    fn first_mass<N: Dimension>(&self, t: f64, q: &OVector<f64, N>) -> &Mass
    where
        H: Hamiltonian<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        self.mass.get_or_init(|| {
            let zero = OVector::zeros_generic(q.shape_generic().0, U1);
            let (_, _, pp) = N::hessian(&Energy(&self.model), t, q, &zero, Wrt::Velocity);
            let n = q.len();
            match invert_small(&pp) {
                Some(mass) => Mass::new(mass.as_slice(), n),
                None => Mass::Dense(vec![f64::NAN; n * n]),
            }
        })
    }

    /// The momentum p with ∂H/∂p(t, q, p) = q̇ at real (t, q, q̇), by Newton's method from
    /// `p = 0` with each step halved until H's derivatives are finite again; NaN where it
    /// does not converge.
    fn real_momentum<N: Dimension>(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> OVector<f64, N>
    where
        H: Hamiltonian<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let energy = Energy(&self.model);
        let mut p = OVector::zeros_generic(q.shape_generic().0, U1);
        let derivatives = |p: &OVector<f64, N>| {
            let (_, hp, pp) = N::hessian(&energy, t, q, p, Wrt::Velocity);
            let finite = hp.iter().chain(pp.iter()).all(|x| x.is_finite());
            (hp, pp, finite)
        };
        let (mut hp, mut pp, _) = derivatives(&p);
        for _ in 0..MOMENTUM_MAX_ITERATIONS {
            let Some(delta) = solve_small(pp.clone(), v - &hp) else {
                break;
            };
            let size = delta.amax();
            let mut fraction = 1.0;
            loop {
                let trial = &p + &delta * fraction;
                let (next_hp, next_pp, finite) = derivatives(&trial);
                if finite || fraction < 1e-6 {
                    (p, hp, pp) = (trial, next_hp, next_pp);
                    break;
                }
                fraction *= 0.5;
            }
            if size * fraction <= 4.0 * f64::EPSILON * (1.0 + p.amax()) {
                return p;
            }
        }
        p.fill(f64::NAN);
        p
    }

    /// p(t, q, q̇) in the scalar of the call (see the module docs).
    #[inline]
    fn momentum<D: Scalar, N: Dimension>(
        &self,
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N>
    where
        H: Hamiltonian<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        if H::STRUCTURE == HamiltonianStructure::QuadraticKinetic {
            return self.mass(t, q).apply(v);
        }
        let (t_re, q_re) = (t.re(), q.map(|x| x.re()));
        let v_re = v.map(|x| x.re());
        let real = self.real_momentum(t_re, &q_re, &v_re);
        let energy = Energy(&self.model);
        let (_, _, jacobian) = N::hessian(&energy, t_re, &q_re, &real, Wrt::Velocity);
        let jacobian = jacobian.map(D::from);
        let mut p = real.map(D::from);
        for _ in 0..CHORD_STEPS {
            let (_, hp) = N::gradient(&energy, t, q, &p, Wrt::Velocity);
            match solve_small(jacobian.clone(), hp - v) {
                Some(correction) => p -= correction,
                None => {
                    p.fill(D::from(f64::NAN));
                    break;
                }
            }
        }
        p
    }
}

impl<H: Hamiltonian<N>, N: Dimension> Lagrangian<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const TIME_DEPENDENT: bool = H::TIME_DEPENDENT;
    const STRUCTURE: Structure = match H::STRUCTURE {
        HamiltonianStructure::QuadraticKinetic => Structure::ConstantMass,
        _ => Structure::General,
    };
    const FORCED: bool = H::FORCED;

    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &OVector<D, N>, v: &OVector<D, N>) -> D {
        if H::STRUCTURE == HamiltonianStructure::QuadraticKinetic {
            // ½ q̇ᵀMq̇ − V, V = H(t, q, 0): no Legendre map at all.
            let zero = OVector::zeros_generic(q.shape_generic().0, U1);
            return self.mass(t, q).kinetic(v) - self.model.hamiltonian(t, q, &zero);
        }
        let p = self.momentum(t, q, v);
        p.dot(v) - self.model.hamiltonian(t, q, &p)
    }

    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N> {
        let p = self.momentum(t, q, v);
        self.model.external_force(t, q, &p)
    }

    /// ∂L/∂q = −∂H/∂q(t, q, 0) of a quadratic kinetic energy, from H alone: the fixed point
    /// of a constant mass then differentiates neither ½ q̇ᵀMq̇ nor the Legendre map.
    #[inline]
    fn batch_force(
        &self,
        times: &[f64],
        positions: &[OVector<f64, N>],
        v: &OVector<f64, N>,
        forces: &mut [OVector<f64, N>],
    ) -> bool {
        if H::STRUCTURE != HamiltonianStructure::QuadraticKinetic {
            return false;
        }
        let zero = OVector::zeros_generic(v.shape_generic().0, U1);
        let energy = Energy(&self.model);
        for ((&t, q), force) in times.iter().zip(positions).zip(forces) {
            let (_, gradient) = N::gradient(&energy, t, q, &zero, Wrt::Position);
            *force = -gradient;
        }
        true
    }

    fn hamiltonian_form(&self) -> Option<&dyn HamiltonianForm<N>> {
        Some(self)
    }
}

impl<H: Hamiltonian<N>, N: Dimension> HamiltonianForm<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn structure(&self) -> HamiltonianStructure {
        self.model.structure()
    }

    fn forced(&self) -> bool {
        H::FORCED
    }

    fn value(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> f64 {
        self.model.hamiltonian(t, q, p)
    }

    fn gradient(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> (OVector<f64, N>, OVector<f64, N>) {
        // Two first-order sweeps: the mixed block of `N::mixed` is not needed here.
        let energy = Energy(&self.model);
        let (_, hq) = N::gradient(&energy, t, q, p, Wrt::Position);
        let (_, hp) = N::gradient(&energy, t, q, p, Wrt::Velocity);
        (hq, hp)
    }

    fn velocity(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> OVector<f64, N> {
        N::gradient(&Energy(&self.model), t, q, p, Wrt::Velocity).1
    }

    fn position_gradient(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> OVector<f64, N> {
        N::gradient(&Energy(&self.model), t, q, p, Wrt::Position).1
    }

    fn second(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> CanonicalSecond<N> {
        let energy = Energy(&self.model);
        let (value, hq, hp, qp) = N::mixed(&energy, t, q, p);
        let (_, _, qq) = N::hessian(&energy, t, q, p, Wrt::Position);
        let (_, _, pp) = N::hessian(&energy, t, q, p, Wrt::Velocity);
        CanonicalSecond {
            value,
            hq,
            hp,
            qq,
            qp,
            pp,
        }
    }

    fn force(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> OVector<f64, N> {
        if H::FORCED {
            self.model.external_force(t, q, p)
        } else {
            OVector::zeros_generic(q.shape_generic().0, U1)
        }
    }

    fn force_jacobian(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> (OMatrix<f64, N, N>, OMatrix<f64, N, N>) {
        let force = Force(&self.model);
        let (_, fq) = N::jacobian(&force, t, q, p, Wrt::Position);
        let (_, fp) = N::jacobian(&force, t, q, p, Wrt::Velocity);
        (fq, fp)
    }

    fn check(&self, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> Result<(), Error> {
        let second = self.second(t, q, p);
        let finite = std::iter::once(second.value)
            .chain(second.hq.iter().copied())
            .chain(second.hp.iter().copied())
            .all(f64::is_finite);
        if !finite {
            return Err(Error::NonFinite {
                what: "Hamiltonian H or its gradient at the initial state".into(),
                step: 0,
                t,
            });
        }
        if invert_small(&second.pp).is_none() {
            return Err(Error::invalid(
                "model",
                "∂²H/∂p² is singular at the initial state: the Hamiltonian is not regular \
                 there, so q̇ = ∂H/∂p does not determine p (no Lagrangian, and no implicit \
                 method's Newton system)",
            ));
        }
        let scale = 1.0 + second.pp.amax() + second.qq.amax();
        let coupling = second.qp.amax();
        if self.model.structure().is_separable() && coupling > 1e-12 * scale {
            return Err(Error::invalid(
                "model",
                format!(
                    "the Hamiltonian declares a separable structure H = T(p) + V(t, q), but \
                     ∂²H/∂q∂p = {coupling:e} at the initial state"
                ),
            ));
        }
        if H::STRUCTURE == HamiltonianStructure::QuadraticKinetic {
            let shifted = p.map(|x| 2.0 * x + 1.0);
            let other = self.second(t, q, &shifted);
            let change = (&other.pp - &second.pp).amax();
            let zero = OVector::zeros_generic(q.shape_generic().0, U1);
            let at_rest = self.velocity(t, q, &zero);
            if change > 1e-12 * scale || at_rest.amax() > 1e-12 * scale {
                return Err(Error::invalid(
                    "model",
                    format!(
                        "the Hamiltonian declares H = ½ pᵀM⁻¹p + V(t, q) with a constant M, \
                         but ∂²H/∂p² changes by {change:e} with p and ∂H/∂p at p = 0 is \
                         {:e} at the initial state",
                        at_rest.amax()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Named parameters and defaults of a Hamiltonian model ([`Defaults`] in (q, p)).
pub trait HamiltonianDefaults<N: Dimension>: Hamiltonian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Short name (as used by the CLI, e.g. `"kepler-h"`).
    fn name(&self) -> &'static str;
    /// Names of the configuration coordinates.
    fn coordinate_names(&self) -> Vec<String>;
    /// Current parameter values, by name.
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter ([`Error::InvalidParameter`] for an unknown name or a bad value).
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error>;
    /// Default initial state (t0, q0, p0).
    fn initial_state(&self) -> (f64, OVector<f64, N>, OVector<f64, N>);
    /// Default step size.
    fn default_step(&self) -> f64;
    /// Default final time.
    fn default_horizon(&self) -> f64;
}

/// Symmetry generators ξᵢ(q) of a Hamiltonian model (point symmetries: the Noether momenta
/// are Jᵢ = p·ξᵢ(q), as for [`Symmetries`]).
pub trait HamiltonianSymmetries<N: Dimension>: Hamiltonian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Number of generators (default: none).
    fn generator_count(&self) -> usize {
        0
    }
    /// Name of momentum `index`.
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn momentum_name(&self, index: usize) -> &'static str {
        panic!("no symmetry generator with index {index}")
    }
    /// The generator ξᵢ(q).
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn generator(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N> {
        let _ = q;
        panic!("no symmetry generator with index {index}")
    }
}

/// Known conserved quantities of a Hamiltonian model, as functions of (t, q, p).
pub trait HamiltonianInvariants<N: Dimension>: Hamiltonian<N>
where
    DefaultAllocator: Allocator<N>,
{
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
    /// Value of invariant `index` at (t, q, p).
    ///
    /// # Panics
    /// If `index >= invariant_count()` (the default panics for every index).
    fn invariant(&self, index: usize, t: f64, q: &OVector<f64, N>, p: &OVector<f64, N>) -> f64 {
        let _ = (t, q, p);
        panic!("no invariant with index {index}")
    }
}

/// A closed-form solution of Hamilton's equations, in (q, p).
pub trait HamiltonianExactSolution<N: Dimension>: Hamiltonian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// (q(t), p(t)) of the solution through (q0, p0) at t0, or `None` without a closed form.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &OVector<f64, N>,
        p0: &OVector<f64, N>,
        t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)>;
}

impl<H: HamiltonianDefaults<N>, N: Dimension> Defaults<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn name(&self) -> &'static str {
        self.model.name()
    }
    fn coordinate_names(&self) -> Vec<String> {
        self.model.coordinate_names()
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.model.parameters()
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        self.hamiltonian_mut().set_parameter(name, value)
    }
    /// (t0, q0, q̇0) with q̇0 = ∂H/∂p(t0, q0, p0).
    fn initial_state(&self) -> (f64, OVector<f64, N>, OVector<f64, N>) {
        let (t0, q0, p0) = self.model.initial_state();
        let v0 = self.velocity(t0, &q0, &p0);
        (t0, q0, v0)
    }
    fn default_step(&self) -> f64 {
        self.model.default_step()
    }
    fn default_horizon(&self) -> f64 {
        self.model.default_horizon()
    }
}

impl<H: HamiltonianSymmetries<N>, N: Dimension> Symmetries<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn generator_count(&self) -> usize {
        self.model.generator_count()
    }
    fn momentum_name(&self, index: usize) -> &'static str {
        self.model.momentum_name(index)
    }
    fn generator(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N> {
        self.model.generator(index, q)
    }
}

impl<H: HamiltonianInvariants<N>, N: Dimension> Invariants<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn invariant_count(&self) -> usize {
        self.model.invariant_count()
    }
    fn invariant_name(&self, index: usize) -> &'static str {
        self.model.invariant_name(index)
    }
    fn invariant(&self, index: usize, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64 {
        let p = self.momentum(t, q, v);
        self.model.invariant(index, t, q, &p)
    }
}

impl<H: HamiltonianExactSolution<N>, N: Dimension> ExactSolution<N> for Canonical<H>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn exact_solution(
        &self,
        t0: f64,
        q0: &OVector<f64, N>,
        v0: &OVector<f64, N>,
        t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        let p0 = self.momentum(t0, q0, v0);
        let (q, p) = self.model.exact_solution(t0, q0, &p0, t)?;
        let v = self.velocity(t, &q, &p);
        Some((q, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::canonical;
    use crate::model::derived::LagrangianExt;
    use crate::test_models::{VariableMass, VariableMassH};
    use nalgebra::{SVector, U1};

    /// A relativistic oscillator, H = √(1 + p²) + q²/2, whose L = −√(1 − q̇²) − q²/2.
    struct Relativistic;

    impl Hamiltonian<U1> for Relativistic {
        const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
        }
    }

    /// The pendulum H = p²/2 − cos q, declared quadratic in p.
    struct Pendulum;

    impl Hamiltonian<U1> for Pendulum {
        const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            p[0] * p[0] * 0.5 - q[0].cos()
        }
    }

    fn points() -> [(SVector<f64, 2>, SVector<f64, 2>); 3] {
        [
            (SVector::from([0.3, -0.7]), SVector::from([1.1, 0.4])),
            (SVector::from([-1.2, 0.5]), SVector::from([-0.2, 2.0])),
            (SVector::from([0.0, 1.5]), SVector::from([0.9, -1.3])),
        ]
    }

    #[test]
    fn the_legendre_transform_of_h_is_l_with_its_derivatives_to_third_order() {
        let model = Canonical::new(VariableMassH);
        for (q, v) in points() {
            let (a, b) = (
                model.second_derivatives(0.0, &q, &v),
                VariableMass.second_derivatives(0.0, &q, &v),
            );
            assert!((a.value - b.value).abs() < 1e-14, "{} {}", a.value, b.value);
            for (x, y) in [(&a.q, &b.q), (&a.v, &b.v)] {
                assert!((x - y).amax() < 1e-13, "{x} {y}");
            }
            for (x, y) in [(&a.qq, &b.qq), (&a.qv, &b.qv), (&a.vv, &b.vv)] {
                assert!((x - y).amax() < 1e-13, "{x} {y}");
            }
            // Third derivatives of L, through the chord steps in nested duals.
            let (a, b) = (
                model.acceleration_jacobian(0.0, &q, &v).unwrap(),
                VariableMass.acceleration_jacobian(0.0, &q, &v).unwrap(),
            );
            assert!((a.value - b.value).amax() < 1e-12);
            assert!((a.q - b.q).amax() < 1e-12, "{} {}", a.q, b.q);
            assert!((a.v - b.v).amax() < 1e-12, "{} {}", a.v, b.v);
        }
    }

    #[test]
    fn a_relativistic_h_gives_its_closed_form_lagrangian_and_velocity() {
        let model = Canonical::new(Relativistic);
        for (q, v) in [(0.3_f64, 0.5_f64), (-1.0, -0.9), (2.0, 0.999)] {
            let (q, v) = (SVector::from([q]), SVector::from([v]));
            let expected = -(1.0 - v[0] * v[0]).sqrt() - 0.5 * q[0] * q[0];
            let value = model.lagrangian(0.0, &q, &v);
            assert!((value - expected).abs() < 1e-13, "{value} {expected}");
            let p = model.momentum(0.0, &q, &v);
            let exact = v[0] / (1.0 - v[0] * v[0]).sqrt();
            assert!((p[0] - exact).abs() < 1e-12 * exact.abs().max(1.0));
            let back = canonical::velocity(&model, 0.0, &q, &p, &SVector::zeros()).unwrap();
            assert!((back[0] - v[0]).abs() < 1e-14);
        }
    }

    #[test]
    fn h_derived_from_l_by_the_legendre_map_matches_h_written_by_hand() {
        let written = Canonical::new(VariableMassH);
        for (q, v) in points() {
            let p = VariableMass.momentum(0.0, &q, &v);
            let from_l = canonical::second(&VariableMass, 0.0, &q, &p, &v).unwrap();
            let from_h = canonical::second(&written, 0.0, &q, &p, &v).unwrap();
            assert!((from_l.value - from_h.value).abs() < 1e-13);
            for (x, y) in [(&from_l.hq, &from_h.hq), (&from_l.hp, &from_h.hp)] {
                assert!((x - y).amax() < 1e-13, "{x} {y}");
            }
            for (x, y) in [
                (&from_l.qq, &from_h.qq),
                (&from_l.qp, &from_h.qp),
                (&from_l.pp, &from_h.pp),
            ] {
                assert!((x - y).amax() < 1e-13, "{x} {y}");
            }
            assert!((from_h.hp - v).amax() < 1e-14);
        }
    }

    #[test]
    fn a_quadratic_h_is_a_constant_mass_lagrangian_in_closed_form() {
        let model = Canonical::new(Pendulum);
        assert_eq!(
            <Canonical<Pendulum> as Lagrangian<U1>>::STRUCTURE,
            Structure::ConstantMass
        );
        let (q, v) = (SVector::from([0.4_f64]), SVector::from([-1.3_f64]));
        let expected = 0.5 * v[0] * v[0] + q[0].cos();
        assert!((model.lagrangian(0.0, &q, &v) - expected).abs() < 1e-15);
        assert!(model.check(0.0, &q, &SVector::from([0.7])).is_ok());
    }

    #[test]
    fn a_wrong_declaration_or_a_singular_h_is_a_typed_error() {
        /// Declared quadratic, but relativistic.
        struct Wrong;
        impl Hamiltonian<U1> for Wrong {
            const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0]
            }
        }
        /// Declared separable, but a charged particle's p − A(q).
        struct Coupled;
        impl Hamiltonian<U1> for Coupled {
            const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                (p[0] - q[0] * q[0]).powi(2) * 0.5
            }
        }
        /// H linear in p: no Legendre map.
        struct Singular;
        impl Hamiltonian<U1> for Singular {
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                p[0] * q[0]
            }
        }
        /// H infinite at the initial state.
        struct Pole;
        impl Hamiltonian<U1> for Pole {
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                p[0] * p[0] * 0.5 - q[0].recip()
            }
        }
        let (q, p) = (SVector::from([0.5]), SVector::from([0.3]));
        let message = |e: Error| e.to_string();
        let wrong = message(Canonical::new(Wrong).check(0.0, &q, &p).unwrap_err());
        assert!(wrong.contains("½ pᵀM⁻¹p"), "{wrong}");
        let coupled = message(Canonical::new(Coupled).check(0.0, &q, &p).unwrap_err());
        assert!(coupled.contains("separable"), "{coupled}");
        let singular = message(Canonical::new(Singular).check(0.0, &q, &p).unwrap_err());
        assert!(singular.contains("∂²H/∂p² is singular"), "{singular}");
        let pole = Canonical::new(Pole).check(0.0, &SVector::from([0.0]), &p);
        assert!(matches!(pole, Err(Error::NonFinite { .. })), "{pole:?}");
    }
}
