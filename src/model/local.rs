//! Lagrangians on ℝⁿ with n chosen at run time, written as sums of small local terms.
//!
//! Chains, lattices and semi-discretised strings and fields have Lagrangians
//!
//! L(t, q, q̇) = Σₑ ℓₑ(t, q_{I(e)}, q̇_{I(e)}),
//!
//! each term ℓₑ a function of a few coordinates, those of its index set I(e) (a spring and
//! the two particles it joins, a particle's kinetic energy). A [`LocalLagrangian`] writes one
//! term, generic over [`Scalar`] and K = [`LocalLagrangian::Width`] coordinates wide, and
//! says which coordinates each term reads; everything else follows term by term from the
//! fixed-size automatic differentiation of [`crate::model::derived`] (each term is a
//! [`Lagrangian<K>`] through [`Term`]) and is scattered into vectors of length n — so one
//! evaluation of ∂L/∂q, of p = ∂L/∂q̇ or of the energy costs O(n), and the sparsity of the
//! Hessian blocks is the union of the terms' index sets.
//!
//! Companions, as for [`crate::Lagrangian`]: [`LocalDefaults`] (name, parameters, default
//! state, step and horizon) and [`LocalInvariants`] (known conserved quantities).
//!
//! # Example
//! ```
//! use nalgebra::{Const, SVector};
//! use svi::model::local::LocalLagrangian;
//! use svi::Scalar;
//!
//! /// n unit masses joined by unit springs, with both ends fixed: n + 1 springs.
//! struct Chain {
//!     n: usize,
//! }
//!
//! impl LocalLagrangian for Chain {
//!     type Width = Const<2>;
//!     const TIME_DEPENDENT: bool = false;
//!     fn dimension(&self) -> usize {
//!         self.n
//!     }
//!     fn term_count(&self) -> usize {
//!         self.n + 1
//!     }
//!     /// Spring e joins particles e − 1 and e (the walls at −1 and n are slot 0 or 1 with
//!     /// the neighbouring particle's index repeated, and the term ignores that slot).
//!     fn indices(&self, e: usize) -> [usize; 2] {
//!         [e.saturating_sub(1), e.min(self.n - 1)]
//!     }
//!     fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
//!         let (left, right) = match e {
//!             0 => (D::from(0.0), q[1]),
//!             e if e == self.n => (q[0], D::from(0.0)),
//!             _ => (q[0], q[1]),
//!         };
//!         // The kinetic energy of particle e rides on spring e (the last spring has none).
//!         let kinetic = if e < self.n { v[1] * v[1] * 0.5 } else { D::from(0.0) };
//!         let stretch = right - left;
//!         kinetic - stretch * stretch * 0.5
//!     }
//! }
//! ```

use crate::dimension::{Dyn, Wrt};
use crate::error::Error;
pub use crate::model::TermDerivatives;
use crate::model::derived::{LagrangianExt, second_derivatives_along};
use crate::model::{Invariants, Lagrangian, Structure, TermSum};
use crate::scalar::Scalar;
use nalgebra::{Const, DVector, SVector, U1};
use num_dual::{Derivative, Dual64, DualSVec64, HyperDual64};

/// The width K of a [`LocalLagrangian`]'s terms (and of the local constraints of
/// [`crate::model::constraint::local`]): `nalgebra::Const<K>`.
///
/// It carries K to the fixed-size code a term is differentiated by (stable Rust cannot use
/// an associated constant as an array length). Implemented for every `Const<K>`; not meant
/// to be implemented elsewhere.
pub trait TermWidth {
    /// K.
    const WIDTH: usize;
    /// The coordinates (or velocities) of one term: `SVector<D, K>`.
    type Vector<D: Scalar>;
    /// The index set of one term: `[usize; K]`.
    type Indices: AsRef<[usize]> + Copy;

    /// The vector of the K slots `entry(0)`, …, `entry(K − 1)`.
    fn vector<D: Scalar>(entry: impl FnMut(usize) -> D) -> Self::Vector<D>;

    /// Add the term's ∂ℓₑ/∂q (`velocity == false`) or ∂ℓₑ/∂q̇ (`velocity == true`) at
    /// (t, q, q̇) into `out` at the term's indices.
    fn scatter_gradient<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        velocity: bool,
        out: &mut DVector<f64>,
    );

    /// The term's value ℓₑ(t, q_{I(e)}, q̇_{I(e)}), over any scalar.
    fn value<L: LocalLagrangian<Width = Self> + ?Sized, D: Scalar>(
        model: &L,
        term: usize,
        t: D,
        q: &DVector<D>,
        v: &DVector<D>,
    ) -> D;

    /// The term's first derivatives ∂ℓ/∂q, ∂ℓ/∂q̇ at (t, q, q̇) (local coordinates), written
    /// to the first 2K entries of `out` in the layout of [`TermDerivatives`].
    fn first_derivatives<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    );

    /// The term's first and second derivatives at (t, q, q̇), flattened into `out` (length
    /// 2K + 3K², see [`TermDerivatives`]).
    fn second_derivatives<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    );

    /// The term's first and second derivatives at the dual point (t + ε, q + ε dq, q̇ + ε dv):
    /// values, then ε-parts, each 2K + 3K² long ([`TermSum::term_derivatives_along`]).
    fn second_derivatives_along<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        point: (&[f64], &[f64]),
        direction: (&[f64], &[f64]),
        out: &mut [f64],
    );

    /// Add the term's block of ∂²L/∂q̇∂q̇ into `out` as (row, column, value) triplets.
    fn mass_triplets<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        out: &mut Vec<(usize, usize, f64)>,
    );
}

/// One term of a [`LocalLagrangian`] as a fixed-size [`Lagrangian<K>`] in its own K
/// coordinates, so that every derived quantity of [`LagrangianExt`] applies to it.
#[derive(Debug)]
pub struct Term<'a, L: ?Sized> {
    /// The whole model.
    pub model: &'a L,
    /// Which term.
    pub index: usize,
}

impl<L, const K: usize> Lagrangian<Const<K>> for Term<'_, L>
where
    L: LocalLagrangian<Width = Const<K>> + ?Sized,
{
    const TIME_DEPENDENT: bool = L::TIME_DEPENDENT;
    const STRUCTURE: Structure = L::STRUCTURE;

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, K>, v: &SVector<D, K>) -> D {
        self.model.term(self.index, t, q, v)
    }
}

/// The term's coordinates and velocities, gathered from the global vectors.
#[inline]
fn gather<D: Scalar, const K: usize>(
    indices: &[usize; K],
    q: &DVector<D>,
    v: &DVector<D>,
) -> (SVector<D, K>, SVector<D, K>) {
    let (q, v) = (q.as_slice(), v.as_slice());
    (
        SVector::from_fn(|i, _| q[indices[i]]),
        SVector::from_fn(|i, _| v[indices[i]]),
    )
}

impl<const K: usize> TermWidth for Const<K> {
    const WIDTH: usize = K;
    type Vector<D: Scalar> = SVector<D, K>;
    type Indices = [usize; K];

    #[inline]
    fn vector<D: Scalar>(mut entry: impl FnMut(usize) -> D) -> SVector<D, K> {
        SVector::from_fn(|i, _| entry(i))
    }

    /// K sweeps of the scalar dual number (one of the vector dual where the model asks,
    /// [`LocalLagrangian::VECTOR_SWEEP`]), written out here so that the term is inlined into
    /// the caller's loop over the terms: through [`LagrangianExt`] the compiler may keep the
    /// sweeps a call per term, at twice the cost (`cargo bench --bench chain`).
    #[inline(always)]
    fn scatter_gradient<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        velocity: bool,
        out: &mut DVector<f64>,
    ) {
        let indices = model.indices(term);
        let (ql, vl) = gather(&indices, q, v);
        let out = out.as_mut_slice();
        if L::VECTOR_SWEEP {
            // One sweep of the vector dual carrying all K directions.
            let lift = |x: SVector<f64, K>, seeded: bool| -> SVector<DualSVec64<K>, K> {
                SVector::from_fn(|a, _| {
                    let mut lifted = DualSVec64::<K>::from_re(x[a]);
                    if seeded {
                        lifted.eps = Derivative::derivative_generic(Const::<K>, U1, a);
                    }
                    lifted
                })
            };
            let (x, y) = (lift(ql, !velocity), lift(vl, velocity));
            let gradient = model
                .term(term, DualSVec64::<K>::from_re(t), &x, &y)
                .eps
                .unwrap_generic(Const::<K>, U1);
            for (a, &i) in indices.iter().enumerate() {
                out[i] += gradient[a];
            }
            return;
        }
        let (mut x, mut y) = (ql.map(Dual64::from_re), vl.map(Dual64::from_re));
        let t = Dual64::from_re(t);
        for (a, &i) in indices.iter().enumerate() {
            let seeded = if velocity { &mut y[a] } else { &mut x[a] };
            seeded.eps = 1.0;
            let gradient = model.term(term, t, &x, &y).eps;
            let seeded = if velocity { &mut y[a] } else { &mut x[a] };
            seeded.eps = 0.0;
            out[i] += gradient;
        }
    }

    #[inline]
    fn value<L: LocalLagrangian<Width = Self> + ?Sized, D: Scalar>(
        model: &L,
        term: usize,
        t: D,
        q: &DVector<D>,
        v: &DVector<D>,
    ) -> D {
        let (ql, vl) = gather(&model.indices(term), q, v);
        model.term(term, t, &ql, &vl)
    }

    #[inline]
    fn first_derivatives<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) {
        let d = Term { model, index: term }.first_derivatives(
            t,
            &SVector::from_column_slice(q),
            &SVector::from_column_slice(v),
        );
        out[..K].copy_from_slice(d.q.as_slice());
        out[K..2 * K].copy_from_slice(d.v.as_slice());
    }

    #[inline]
    fn second_derivatives<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) {
        let d = Term { model, index: term }.second_derivatives(
            t,
            &SVector::from_column_slice(q),
            &SVector::from_column_slice(v),
        );
        let (gradients, hessians) = out.split_at_mut(2 * K);
        gradients[..K].copy_from_slice(d.q.as_slice());
        gradients[K..].copy_from_slice(d.v.as_slice());
        let square = K * K;
        hessians[..square].copy_from_slice(d.qq.as_slice());
        hessians[square..2 * square].copy_from_slice(d.qv.as_slice());
        hessians[2 * square..].copy_from_slice(d.vv.as_slice());
    }

    fn second_derivatives_along<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        (q, v): (&[f64], &[f64]),
        (dq, dv): (&[f64], &[f64]),
        out: &mut [f64],
    ) {
        let lift =
            |x: &[f64], dx: &[f64]| SVector::<Dual64, K>::from_fn(|i, _| Dual64::new(x[i], dx[i]));
        second_derivatives_along(
            &Term { model, index: term },
            Dual64::new(t, 1.0),
            (&lift(q, dq), &lift(v, dv)),
            out.split_at_mut(out.len() / 2),
        );
    }

    fn mass_triplets<L: LocalLagrangian<Width = Self> + ?Sized>(
        model: &L,
        term: usize,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        out: &mut Vec<(usize, usize, f64)>,
    ) {
        let indices = model.indices(term);
        let (ql, vl) = gather(&indices, q, v);
        // One sweep of the scalar hyper-dual number per entry on and above the diagonal:
        // no vector dual (whose optional derivatives cost ten times as much per term).
        let (t, ql) = (HyperDual64::from_re(t), ql.map(HyperDual64::from_re));
        for a in 0..K {
            for b in a..K {
                let mut lifted = vl.map(HyperDual64::from_re);
                lifted[a].eps1 = 1.0;
                lifted[b].eps2 = 1.0;
                let entry = model.term(term, t, &ql, &lifted).eps1eps2;
                if entry != 0.0 {
                    out.push((indices[a], indices[b], entry));
                    if a != b {
                        out.push((indices[b], indices[a], entry));
                    }
                }
            }
        }
    }
}

/// A Lagrangian on ℝⁿ (n at run time) written as a sum of local terms,
/// L = Σₑ ℓₑ(t, q_{I(e)}, q̇_{I(e)}) (see the module docs).
///
/// A term may use fewer than K coordinates (a spring to a fixed wall): it then repeats an
/// index in [`LocalLagrangian::indices`] and ignores that slot; the derivatives it scatters
/// there are zero.
pub trait LocalLagrangian {
    /// K, the number of coordinates of one term, as `nalgebra::Const<K>`.
    type Width: TermWidth;

    /// Whether L depends explicitly on t (the default, `true`, is always correct).
    const TIME_DEPENDENT: bool = true;

    /// Structure the integrators may exploit, as [`crate::Lagrangian::STRUCTURE`]: with
    /// [`Structure::ConstantMass`] (every term ½ q̇ᵀMₑq̇ − Vₑ(t, q) with constant Mₑ) SVI
    /// iterates without a Hessian and Störmer–Verlet runs explicitly. Checked at the initial
    /// state of an integrator's first run.
    const STRUCTURE: Structure = Structure::General;

    /// Whether a term's gradient is taken in one sweep of the vector dual carrying all K
    /// directions (`true`) instead of K sweeps of the scalar dual (the default). One sweep
    /// pays where the K directions share a costly part of the term: the N-body problem's
    /// pair term, whose square root and reciprocal one sweep takes once (its force 1.06 µs
    /// against 2.19 µs by six sweeps per pair, `cargo bench --bench derivatives --
    /// run-time-size`). The polymer's bending term, cheap arithmetic around one square root,
    /// took 8–11 % longer per RATTLE step that way (`cargo bench --bench polymer`).
    const VECTOR_SWEEP: bool = false;

    /// n, the number of coordinates.
    fn dimension(&self) -> usize;

    /// The number of terms.
    fn term_count(&self) -> usize;

    /// The index set I(e) of term `term`: which coordinates its K slots read (each below
    /// [`LocalLagrangian::dimension`]).
    fn indices(&self, term: usize) -> <Self::Width as TermWidth>::Indices;

    /// The term ℓₑ(t, q_{I(e)}, q̇_{I(e)}), written once, generic over the scalar.
    fn term<D: Scalar>(
        &self,
        term: usize,
        t: D,
        q: &<Self::Width as TermWidth>::Vector<D>,
        v: &<Self::Width as TermWidth>::Vector<D>,
    ) -> D;

    /// L(t, q, q̇): by default [`value_by_terms`], term by term; a model that can sum its
    /// terms faster may override it (the two must agree to round-off).
    #[inline]
    fn value(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        value_by_terms(self, t, q, v)
    }

    /// ∂L/∂q at (t, q, q̇), written into `out`: the one derivative the explicit methods and
    /// SVI's fixed point take at every stage. By default [`force_by_terms`], term by term; a
    /// model that can assemble the same sum faster may override it (a chain written as text
    /// runs a compiled gradient on batches of sites). The two must agree to round-off.
    #[inline]
    fn force_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        force_by_terms(self, t, q, v, out);
    }
}

/// L of `model` at (t, q, q̇), term by term ([`LocalLagrangian::value`]'s default).
#[inline]
pub fn value_by_terms<L: LocalLagrangian + ?Sized>(
    model: &L,
    t: f64,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> f64 {
    (0..model.term_count())
        .map(|e| L::Width::value(model, e, t, q, v))
        .sum()
}

/// ∂L/∂q of `model` at (t, q, q̇), written into `out`: each term's gradient by the
/// fixed-size automatic differentiation of [`crate::model::derived`], added at its indices
/// ([`LocalLagrangian::force_into`]'s default).
#[inline]
pub fn force_by_terms<L: LocalLagrangian + ?Sized>(
    model: &L,
    t: f64,
    q: &DVector<f64>,
    v: &DVector<f64>,
    out: &mut DVector<f64>,
) {
    out.as_mut_slice().fill(0.0);
    for e in 0..model.term_count() {
        L::Width::scatter_gradient(model, e, t, q, v, false, out);
    }
}

/// ∂²L/∂q̇² of `model` at (t, q, q̇) as triplets appended to `out`, term by term.
fn mass_triplets_by_terms<L: LocalLagrangian + ?Sized>(
    model: &L,
    t: f64,
    q: &DVector<f64>,
    v: &DVector<f64>,
    out: &mut Vec<(usize, usize, f64)>,
) {
    for e in 0..model.term_count() {
        L::Width::mass_triplets(model, e, t, q, v, out);
    }
}

/// Quantities of a whole [`LocalLagrangian`], assembled term by term (each in O(n)).
pub trait LocalLagrangianExt: LocalLagrangian {
    /// p = ∂L/∂q̇, written into `out`.
    fn momentum_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        out.as_mut_slice().fill(0.0);
        for e in 0..self.term_count() {
            Self::Width::scatter_gradient(self, e, t, q, v, true, out);
        }
    }

    /// The energy E = p·q̇ − L.
    fn energy(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        let mut p = DVector::zeros(q.len());
        self.momentum_into(t, q, v, &mut p);
        p.dot(v) - self.value(t, q, v)
    }

    /// The mass matrix ∂²L/∂q̇∂q̇ at (t, q, q̇) as (row, column, value) triplets, one per
    /// nonzero entry of each term's block (entries of different terms at the same place add
    /// up).
    fn mass_triplets(
        &self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
    ) -> Vec<(usize, usize, f64)> {
        let mut triplets = Vec::new();
        mass_triplets_by_terms(self, t, q, v, &mut triplets);
        triplets
    }
}

impl<L: LocalLagrangian + ?Sized> LocalLagrangianExt for L {}

/// A sum of local terms as a Lagrangian of run-time size, for the methods of ℝᴺ: L = Σₑ ℓₑ
/// over any scalar, with its derivatives assembled term by term ([`Lagrangian::terms`]), so
/// that every method of ℝᴺ runs on it (those that keep the sparsity,
/// [`crate::Method::keeps_sparsity`], at 10⁵ coordinates and more).
///
/// ```
/// use svi::model::local::Terms;
/// # use nalgebra::{Const, DVector, SVector};
/// # use svi::model::local::LocalLagrangian;
/// # use svi::{Integrator, Midpoint, Scalar, VariationalIntegrator};
/// # struct Springs;
/// # impl LocalLagrangian for Springs {
/// #     type Width = Const<1>;
/// #     fn dimension(&self) -> usize { 3 }
/// #     fn term_count(&self) -> usize { 3 }
/// #     fn indices(&self, e: usize) -> [usize; 1] { [e] }
/// #     fn term<D: Scalar>(&self, _e: usize, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
/// #         (v[0] * v[0] - q[0] * q[0]) * 0.5
/// #     }
/// # }
/// // Three independent unit oscillators, by the implicit midpoint rule.
/// let integrator = Integrator::new(Terms(Springs), VariationalIntegrator::new(Midpoint));
/// let (q, v) = (DVector::from_element(3, 1.0), DVector::zeros(3));
/// let run = integrator.run_from_velocity(0.0, q, v, 0.01, 1.0, &mut ()).unwrap();
/// assert!((run.last.q[2] - 1f64.cos()).abs() < 1e-4);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Terms<L>(pub L);

impl<L: LocalLagrangian> Lagrangian<Dyn> for Terms<L> {
    const TIME_DEPENDENT: bool = L::TIME_DEPENDENT;
    const STRUCTURE: Structure = L::STRUCTURE;

    #[inline]
    fn dimension(&self) -> usize {
        self.0.dimension()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        (0..self.0.term_count()).fold(D::from(0.0), |sum, e| {
            sum + L::Width::value(&self.0, e, t, q, v)
        })
    }

    #[inline]
    fn terms(&self) -> Option<&dyn TermSum<Dyn>> {
        Some(&self.0)
    }
}

/// The invariants of a sum of local terms, for the observers of ℝᴺ.
impl<L: LocalInvariants> Invariants<Dyn> for Terms<L> {
    fn invariant_count(&self) -> usize {
        self.0.invariant_count()
    }

    fn invariant_name(&self, index: usize) -> &'static str {
        self.0.invariant_name(index)
    }

    fn invariant(&self, index: usize, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        self.0.invariant(index, t, q, v)
    }
}

/// Every sum of local terms hands its terms to the methods of ℝᴺ ([`Lagrangian::terms`] of
/// [`Terms`]).
impl<L: LocalLagrangian> TermSum<Dyn> for L {
    fn value(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        LocalLagrangian::value(self, t, q, v)
    }

    fn gradient_into(
        &self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        wrt: Wrt,
        out: &mut DVector<f64>,
    ) {
        match wrt {
            Wrt::Position => self.force_into(t, q, v, out),
            Wrt::Velocity => self.momentum_into(t, q, v, out),
        }
    }

    fn as_run_time(&self) -> Option<&dyn TermSum<Dyn>> {
        Some(self)
    }

    /// Each term's ∂²ℓ/∂q̇² alone, one hyper-dual sweep per entry (no other block).
    fn mass_triplets(
        &self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        out: &mut Vec<(usize, usize, f64)>,
    ) {
        mass_triplets_by_terms(self, t, q, v, out);
    }

    fn width(&self) -> usize {
        L::Width::WIDTH
    }

    fn term_count(&self) -> usize {
        LocalLagrangian::term_count(self)
    }

    fn term_indices(&self, e: usize, out: &mut [usize]) {
        out.copy_from_slice(self.indices(e).as_ref());
    }

    fn term_derivatives(
        &self,
        e: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        second: bool,
        out: &mut [f64],
    ) {
        if second {
            L::Width::second_derivatives(self, e, t, q, v, out);
        } else {
            L::Width::first_derivatives(self, e, t, q, v, out);
        }
    }

    fn term_derivatives_along(
        &self,
        e: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        direction: (&[f64], &[f64]),
        out: &mut [f64],
    ) {
        L::Width::second_derivatives_along(self, e, t, (q, v), direction, out);
    }
}

/// Named parameters and defaults of a [`LocalLagrangian`] (as [`crate::Defaults`] for
/// fixed-size models).
pub trait LocalDefaults: LocalLagrangian {
    /// Short name (as used by the CLI, e.g. `"fput"`).
    fn name(&self) -> &'static str;
    /// Current parameter values, by name (the size parameter, e.g. `n`, among them).
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter; an unknown name or an out-of-range value (a size that is not a
    /// positive integer) is an [`Error::InvalidParameter`].
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error>;
    /// Default initial state (t0, q0, q̇0) for the current parameters.
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>);
    /// Default step size.
    fn default_step(&self) -> f64;
    /// Default final time.
    fn default_horizon(&self) -> f64;
}

/// Known conserved quantities of a [`LocalLagrangian`].
pub trait LocalInvariants: LocalLagrangian {
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
    /// Value of invariant `index` at (t, q, q̇).
    ///
    /// # Panics
    /// If `index >= invariant_count()` (the default panics for every index).
    fn invariant(&self, index: usize, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        let _ = (t, q, v);
        panic!("no invariant with index {index}")
    }
}
