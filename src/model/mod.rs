//! What a user writes: a Lagrangian, and optional companions.
//!
//! The only required piece is [`Lagrangian::lagrangian`], one function generic over
//! [`Scalar`]. Everything an integrator needs (∂L/∂q, p = ∂L/∂q̇, the Hessian blocks, the
//! energy, the Euler–Lagrange acceleration and its Jacobian) is derived from it by automatic
//! differentiation in [`crate::model::derived`].
//!
//! A non-conservative force f_L(t, q, q̇) (friction, actuation, driving) is part of the model
//! too: [`Lagrangian::external_force`], switched on by [`Lagrangian::FORCED`]. It lives on the
//! `Lagrangian` trait rather than a companion trait so that every generic integrator can see
//! it (a separate trait could not be detected without specialisation), and a model without
//! force pays nothing for it.
//!
//! Companion traits, each optional and small:
//! - [`Symmetries`]: infinitesimal generators ξ(q) of symmetries of L; the Noether momenta
//!   J = p·ξ(q) follow automatically ([`crate::model::derived::LagrangianExt::noether_momentum`]).
//! - [`Invariants`]: other known conserved quantities (as functions of t, q, q̇).
//! - [`ExactSolution`]: a closed-form solution, for error measurements.
//! - [`Defaults`]: named parameters, a default initial state, step and horizon.
//!
//! A Lagrangian may also be written as text, parsed at run time: [`text`].
//!
//! # Example
//! ```
//! use nalgebra::{SVector, U1};
//! use svi::{Lagrangian, Scalar};
//!
//! /// A particle in a quartic well: L = q̇²/2 − q⁴/4.
//! struct Quartic;
//!
//! impl Lagrangian<U1> for Quartic {
//!     const TIME_DEPENDENT: bool = false;
//!     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
//!         v[0] * v[0] * 0.5 - q[0].powi(4) * 0.25
//!     }
//! }
//! ```

pub mod canonical;
pub mod constraint;
pub mod density;
pub mod derived;
pub(crate) mod euler_lagrange;
pub mod group;
pub mod hamiltonian;
pub(crate) mod legendre;
pub mod local;
pub mod local_hamiltonian;
pub mod mass_inverse;
pub mod parametric;
pub mod reparametrized;
pub mod rhs;
pub mod rigid_body;
pub mod so3;
pub(crate) mod term_pattern;
pub mod text;

use crate::dimension::{Dimension, Wrt};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

/// The derivatives of a Lagrangian that is a sum of local terms, L = Σₑ ℓₑ, assembled term
/// by term ([`crate::model::local`]): what [`Lagrangian::terms`] hands the integrators so
/// that no derivative of L costs more than O(n) and the Hessian blocks keep their sparsity.
pub trait TermSum<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// L(t, q, q̇).
    fn value(&self, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64;

    /// ∂L/∂q (`Wrt::Position`) or p = ∂L/∂q̇ (`Wrt::Velocity`) at (t, q, q̇), written into
    /// `out`.
    fn gradient_into(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        wrt: Wrt,
        out: &mut OVector<f64, N>,
    );

    /// K, the number of coordinates one term reads.
    fn width(&self) -> usize;

    /// The number of terms.
    fn term_count(&self) -> usize;

    /// The coordinates term `e` reads, written into `out` (length [`TermSum::width`]).
    fn term_indices(&self, e: usize, out: &mut [usize]);

    /// Term `e`'s derivatives at its own (t, q, q̇) (slices of length K), flattened into
    /// `out` in the layout of [`TermDerivatives`]: ∂ℓ/∂q and ∂ℓ/∂q̇
    /// only (`second == false`, the first 2K entries), or with the Hessian blocks as well
    /// (2K + 3K² entries).
    fn term_derivatives(
        &self,
        e: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        second: bool,
        out: &mut [f64],
    );

    /// Term `e`'s first and second derivatives (as [`TermSum::term_derivatives`] with the
    /// Hessian blocks) at the dual point (t + ε, q + ε dq, q̇ + ε dv): their values into the
    /// first 2K + 3K² entries of `out` and their ε-parts — third derivatives of ℓ contracted
    /// with (1, dq, dv) — into the next 2K + 3K² (the implicit collocation equations of
    /// [`crate::SpectralCollocation`] on a sum of terms).
    #[allow(clippy::too_many_arguments)]
    fn term_derivatives_along(
        &self,
        e: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        direction: (&[f64], &[f64]),
        out: &mut [f64],
    );

    /// Check that every term reads coordinates below `n` (once per run, before anything
    /// is evaluated).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] `indices`, naming the term and the coordinate.
    fn check_indices(&self, n: usize) -> Result<(), crate::Error> {
        let mut indices = vec![0; self.width()];
        for e in 0..self.term_count() {
            self.term_indices(e, &mut indices);
            if let Some(i) = indices.iter().find(|&&i| i >= n) {
                return Err(crate::Error::invalid(
                    "indices",
                    format!("term {e} reads coordinate {i}, but the model has {n}"),
                ));
            }
        }
        Ok(())
    }

    /// These terms as the terms of a run-time-size model (`Some` for every
    /// [`crate::model::local::LocalLagrangian`]; the default `None` for a fixed size, whose
    /// models the methods run densely): the sparse paths are compiled once, for
    /// [`crate::dimension::Dyn`], not once per size.
    fn as_run_time(&self) -> Option<&dyn TermSum<crate::dimension::Dyn>> {
        None
    }

    /// The mass matrix ∂²L/∂q̇² at (t, q, q̇) as (row, column, value) triplets appended to
    /// `out` (entries of one place add up), term by term: by default the third block of
    /// [`TermSum::hessian_triplets`]; a sum of local terms takes the mass block alone.
    fn mass_triplets(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        out: &mut Vec<(usize, usize, f64)>,
    ) {
        let mut blocks = [Vec::new(), Vec::new(), std::mem::take(out)];
        self.hessian_triplets(t, q, v, &mut blocks);
        let [_, _, mass] = blocks;
        *out = mass;
    }

    /// The Hessian blocks ∂²L/∂q², ∂²L/∂q∂q̇ (row q, column q̇) and ∂²L/∂q̇² at (t, q, q̇) as
    /// (row, column, value) triplets, appended to `blocks[0]`, `blocks[1]` and `blocks[2]`
    /// (entries of one place add up), term by term.
    fn hessian_triplets(
        &self,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
        blocks: &mut [Vec<(usize, usize, f64)>; 3],
    ) {
        let k = self.width();
        let (mut indices, mut ql, mut vl) = (vec![0; k], vec![0.0; k], vec![0.0; k]);
        let mut local = vec![0.0; 2 * k + 3 * k * k];
        for e in 0..self.term_count() {
            self.term_indices(e, &mut indices);
            for (a, &i) in indices.iter().enumerate() {
                ql[a] = q[i];
                vl[a] = v[i];
            }
            self.term_derivatives(e, t, &ql, &vl, true, &mut local);
            let hessians = &local[2 * k..];
            for (block, values) in blocks.iter_mut().zip(hessians.chunks_exact(k * k)) {
                // Column-major K × K: entry (a, b) at a + K b.
                for (b, &j) in indices.iter().enumerate() {
                    for (a, &i) in indices.iter().enumerate() {
                        let value = values[a + k * b];
                        if value != 0.0 {
                            block.push((i, j, value));
                        }
                    }
                }
            }
        }
    }
}

/// The layout of one term's derivatives as
/// [`crate::model::local::TermWidth::second_derivatives`] and [`TermSum::term_derivatives`]
/// write them: ∂ℓ/∂q (K), ∂ℓ/∂q̇ (K), then the column-major K × K blocks ∂²ℓ/∂q∂q, ∂²ℓ/∂q∂q̇ (entry
/// (a, b) = ∂²ℓ/∂q_a∂q̇_b) and ∂²ℓ/∂q̇∂q̇.
#[derive(Debug, Clone, Copy)]
pub struct TermDerivatives {
    /// K.
    pub width: usize,
}

impl TermDerivatives {
    /// The length 2K + 3K² of the flattened derivatives.
    pub fn len(&self) -> usize {
        2 * self.width + 3 * self.width * self.width
    }
    /// Whether the layout is empty (K = 0).
    pub fn is_empty(&self) -> bool {
        self.width == 0
    }
    /// ∂ℓ/∂q_a.
    pub fn q(&self, d: &[f64], a: usize) -> f64 {
        d[a]
    }
    /// ∂ℓ/∂q̇_a.
    pub fn v(&self, d: &[f64], a: usize) -> f64 {
        d[self.width + a]
    }
    /// ∂²ℓ/∂q_a∂q_b.
    pub fn qq(&self, d: &[f64], a: usize, b: usize) -> f64 {
        d[2 * self.width + a + self.width * b]
    }
    /// ∂²ℓ/∂q_a∂q̇_b.
    pub fn qv(&self, d: &[f64], a: usize, b: usize) -> f64 {
        let k = self.width;
        d[2 * k + k * k + a + k * b]
    }
    /// ∂²ℓ/∂q̇_a∂q̇_b.
    pub fn vv(&self, d: &[f64], a: usize, b: usize) -> f64 {
        let k = self.width;
        d[2 * k + 2 * k * k + a + k * b]
    }
}

/// A Lagrangian L(t, q, q̇) on ℝᴺ, written once, generic over the scalar type.
///
/// The dimension `N` is a type ([`Dimension`]): `U1`, `U2`, … (nalgebra's `Const<N>`) when it
/// is fixed at compile time — the signatures then read `&SVector<D, N>` —, or
/// [`crate::dimension::Dyn`] when it is chosen at run time (the signatures read
/// `&DVector<D>`, and [`Lagrangian::dimension`] says the size). Every method runs on both.
pub trait Lagrangian<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Whether L depends explicitly on t.
    ///
    /// The default (`true`) is always correct; a model that sets it to `false` lets the
    /// integrators skip ∂/∂t (for example the ∂²L/∂q̇∂t term of the Euler–Lagrange
    /// acceleration).
    const TIME_DEPENDENT: bool = true;

    /// Structure the integrators may exploit. The default ([`Structure::General`]) is always
    /// correct; [`Structure::ConstantMass`] lets the spectral methods replace Newton's method
    /// by a fixed-point iteration that needs only ∂L/∂q (no Hessian at all), and
    /// [`crate::StormerVerlet`] run explicitly (kick–drift–kick). The declaration is about L
    /// only: a constant-mass model may have any external force. The stepping loop checks the
    /// declaration at the initial state of an integrator's first run and rejects a model
    /// that breaks it.
    const STRUCTURE: Structure = Structure::General;

    /// Whether the model has a non-conservative force ([`Lagrangian::external_force`]).
    ///
    /// With the default (`false`) no integrator ever evaluates the force: the unforced code
    /// paths are compiled without it, at zero cost. With `true`, every integrator solves the
    /// Lagrange–d'Alembert equations; a model with `FORCED = true` whose force is zero gives
    /// results equal, bit for bit, to the same model with `FORCED = false`.
    const FORCED: bool = false;

    /// The number of coordinates. The default is right for a fixed dimension; a run-time-size
    /// model ([`crate::dimension::Dyn`]) returns its size.
    fn dimension(&self) -> usize {
        N::try_to_usize().unwrap_or(0)
    }

    /// L as a sum of local terms, when it is one: the integrators then take ∂L/∂q, ∂L/∂q̇ and
    /// the Hessian blocks from [`TermSum`], assembled term by term in O(n), instead of
    /// differentiating the whole L. `None` (the default) for every other Lagrangian; every
    /// [`crate::model::local::LocalLagrangian`] answers `Some` (its blanket implementation of
    /// `Lagrangian<Dyn>`).
    #[inline]
    fn terms(&self) -> Option<&dyn TermSum<N>> {
        None
    }

    /// H itself, when the model was written as a Hamiltonian
    /// ([`crate::model::hamiltonian::Canonical`] answers `Some`): the Hamiltonian methods then
    /// take H's derivatives by automatic differentiation of H, where for a model written as L
    /// they derive them from L's through the Legendre map ([`crate::model::canonical`]).
    /// `None` (the default) for every Lagrangian.
    #[inline]
    fn hamiltonian_form(&self) -> Option<&dyn hamiltonian::HamiltonianForm<N>>
    where
        DefaultAllocator: Allocator<N, N>,
    {
        None
    }

    /// The value L(t, q, q̇).
    ///
    /// Mark it `#[inline]`: the integrators evaluate it (with dual numbers) in their inner
    /// loops, and letting the compiler inline it there is worth a factor of two on small
    /// models.
    fn lagrangian<D: Scalar>(&self, t: D, q: &OVector<D, N>, v: &OVector<D, N>) -> D;

    /// The non-conservative generalised force f_L(t, q, q̇) of the Lagrange–d'Alembert
    /// principle
    ///
    /// δ∫ L(t, q, q̇) dt + ∫ f_L(t, q, q̇)·δq dt = 0,
    ///
    /// whose Euler–Lagrange equations are d/dt ∂L/∂q̇ − ∂L/∂q = f_L (friction, actuation,
    /// time-dependent driving; Porcù–Penati, *Spectral variational integrators*, "Forced
    /// mechanics"; Marsden & West 2001, §3.2). Read only when [`Lagrangian::FORCED`] is
    /// `true`; the default is zero. Like the Lagrangian it is written once, generic over
    /// [`Scalar`]: the integrators differentiate it (∂f_L/∂q, ∂f_L/∂q̇) by automatic
    /// differentiation. It may depend on t even when L does not
    /// ([`Lagrangian::TIME_DEPENDENT`] is about L only), and [`Structure`] is about L only:
    /// a constant-mass model may have a velocity-dependent force.
    ///
    /// # Example
    /// ```
    /// use nalgebra::{SVector, U1};
    /// use svi::{Lagrangian, Scalar};
    ///
    /// /// A damped oscillator: L = q̇²/2 − q²/2 with friction f = −c q̇.
    /// struct Damped {
    ///     c: f64,
    /// }
    ///
    /// impl Lagrangian<U1> for Damped {
    ///     const TIME_DEPENDENT: bool = false;
    ///     const FORCED: bool = true;
    ///     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
    ///         (v[0] * v[0] - q[0] * q[0]) * 0.5
    ///     }
    ///     fn external_force<D: Scalar>(
    ///         &self,
    ///         _t: D,
    ///         _q: &SVector<D, 1>,
    ///         v: &SVector<D, 1>,
    ///     ) -> SVector<D, 1> {
    ///         v.map(|x| x * (-self.c))
    ///     }
    /// }
    /// ```
    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N> {
        let _ = (t, v);
        OVector::zeros_generic(q.shape_generic().0, U1)
    }

    /// ∂L/∂q at several points of one velocity at once, `forces[μ]` at
    /// (`times[μ]`, `positions[μ]`, `v`), for a model that evaluates many points faster than
    /// one at a time (a Lagrangian written as text runs its compiled force program with the
    /// points as lanes). The integrators ask for it where the velocity does not matter
    /// (SVI's fixed point on a constant-mass L, whose ∂L/∂q = −∂V/∂q is free of q̇). Returns
    /// `false` (the default) to have them evaluate the points one by one; a model that
    /// returns `true` has written every point.
    #[inline]
    fn batch_force(
        &self,
        times: &[f64],
        positions: &[OVector<f64, N>],
        v: &OVector<f64, N>,
        forces: &mut [OVector<f64, N>],
    ) -> bool {
        let _ = (times, positions, v, forces);
        false
    }
}

/// Structure of a Lagrangian that integrators may exploit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Structure {
    /// No assumption beyond regularity (L_vv invertible).
    General,
    /// L(t, q, q̇) = ½ q̇ᵀ M q̇ − V(t, q) with a constant symmetric positive-definite mass
    /// matrix M: p = M q̇, ∂L/∂q = −∂V/∂q does not depend on q̇, and q̈ = M⁻¹ ∂L/∂q.
    ConstantMass,
}

/// Whether `L` declares [`Structure::ConstantMass`], as a boolean constant: a branch on it
/// is decided when the code is instantiated for `L`, so a path that only constant-mass
/// models take is not compiled for the others.
pub(crate) struct ConstantMass<L, N>(std::marker::PhantomData<(L, N)>);

impl<L: Lagrangian<N>, N: Dimension> ConstantMass<L, N>
where
    DefaultAllocator: Allocator<N>,
{
    /// `L::STRUCTURE == Structure::ConstantMass`.
    pub(crate) const DECLARED: bool = matches!(L::STRUCTURE, Structure::ConstantMass);
}

/// Infinitesimal symmetry generators of a Lagrangian.
///
/// Generator `i` is the vector field ξᵢ(q) of a one-parameter group acting on configurations
/// that leaves L invariant. By Noether's theorem the momentum Jᵢ = p·ξᵢ(q) is conserved, and
/// variational integrators conserve it exactly (to round-off).
pub trait Symmetries<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Number of generators (default: none, so a model without symmetries writes
    /// `impl Symmetries<N> for Model {}`).
    fn generator_count(&self) -> usize {
        0
    }
    /// Names of the momenta, one per generator (for reports).
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn momentum_name(&self, index: usize) -> &'static str {
        panic!("no symmetry generator with index {index}")
    }
    /// The generator ξᵢ(q); `index < generator_count()`.
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn generator(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N> {
        let _ = q;
        panic!("no symmetry generator with index {index}")
    }
    /// The Noether momentum Jᵢ = p·ξᵢ(q) of generator `index` at (q, p), as the momentum
    /// observer takes it at every step. The default forms ξᵢ(q), which allocates at run-time
    /// size: a model of run-time size computes it without the vector.
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    fn generator_momentum(&self, index: usize, q: &OVector<f64, N>, p: &OVector<f64, N>) -> f64 {
        p.dot(&self.generator(index, q))
    }
}

/// Other known conserved quantities of a model (besides energy and Noether momenta).
pub trait Invariants<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Number of invariants (default: none, so a model without known invariants writes
    /// `impl Invariants<N> for Model {}`).
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
    /// Value of invariant `index` at (t, q, q̇).
    ///
    /// # Panics
    /// If `index >= invariant_count()` (the default panics for every index).
    fn invariant(&self, index: usize, t: f64, q: &OVector<f64, N>, v: &OVector<f64, N>) -> f64 {
        let _ = (t, q, v);
        panic!("no invariant with index {index}")
    }
}

/// A closed-form solution of the Euler–Lagrange equations.
pub trait ExactSolution<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The state (q(t), q̇(t)) of the solution through (q0, q̇0) at time t0, or `None` when
    /// no closed form is available for that initial state (for example an unbound orbit).
    fn exact_solution(
        &self,
        t0: f64,
        q0: &OVector<f64, N>,
        v0: &OVector<f64, N>,
        t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)>;
}

/// Named parameters and literature defaults of a model.
pub trait Defaults<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Short name (as used by the CLI, e.g. `"kepler"`).
    fn name(&self) -> &'static str;
    /// Names of the configuration coordinates, one per coordinate.
    fn coordinate_names(&self) -> Vec<String>;
    /// Current parameter values, by name.
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter; an unknown name or an out-of-range value is an
    /// [`crate::Error::InvalidParameter`].
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), crate::error::Error>;
    /// Default initial state (t0, q0, q̇0) for the current parameters.
    fn initial_state(&self) -> (f64, OVector<f64, N>, OVector<f64, N>);
    /// Default step size.
    fn default_step(&self) -> f64;
    /// Default final time.
    fn default_horizon(&self) -> f64;
}
