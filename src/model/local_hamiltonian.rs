//! Hamiltonians on T*ℝⁿ with n chosen at run time, written as sums of small local terms:
//!
//! H(t, q, p) = Σₑ hₑ(t, q_{I(e)}, p_{I(e)}),
//!
//! the Hamiltonian counterpart of [`crate::model::local`] (a chain's springs and its particles'
//! kinetic energies, however relativistic). A [`LocalHamiltonian`] writes one term, generic
//! over [`Scalar`] and K coordinates wide; [`LocalCanonical`] makes it a model that the
//! methods on Hamilton's equations ([`crate::method::hamiltonian`]) run, with every derivative
//! assembled term by term from the terms' fixed-size automatic differentiation — the machinery
//! of [`crate::model::local`] with p in the velocity's slot — so ∂H/∂q, ∂H/∂p and H cost O(n).
//!
//! For a separable H = T(p) + V(t, q) ([`HamiltonianStructure::Separable`], checked term by
//! term at the initial state) `verlet-h` and its compositions step explicitly — kick, drift
//! q ← q + h ∂T/∂p, kick — with any kinetic energy, the relativistic √(m²c⁴ + p²c²)
//! included, in O(n) a step and no n × n matrix. The implicit methods on Hamilton's equations
//! run it too, with dense n × n Hessian blocks (moderate n).
//!
//! There is no Lagrangian: the Legendre map of a general local H is not local, so the methods
//! on the Euler–Lagrange equations refuse the model (as they refuse
//! [`crate::model::rhs::HamiltonianRhs`]). A Lagrangian written as a [`LocalLagrangian`] is
//! the way to run them.
//!
//! ```
//! use nalgebra::{Const, DVector, SVector};
//! use svi::model::local_hamiltonian::{LocalCanonical, LocalHamiltonian};
//! use svi::{HamiltonianStructure, Initial, Integrator, MethodSpec, Scalar};
//!
//! /// n relativistic particles, each in its own harmonic well: H = Σ √(1 + pᵢ²) + qᵢ²/2.
//! struct Wells(usize);
//!
//! impl LocalHamiltonian for Wells {
//!     type Width = Const<1>;
//!     const TIME_DEPENDENT: bool = false;
//!     const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;
//!     fn dimension(&self) -> usize { self.0 }
//!     fn term_count(&self) -> usize { self.0 }
//!     fn indices(&self, e: usize) -> [usize; 1] { [e] }
//!     fn term<D: Scalar>(&self, _e: usize, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
//!         (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
//!     }
//! }
//!
//! let method = "verlet-h".parse::<MethodSpec>()?.vector_method()?;
//! let integrator = Integrator::new(LocalCanonical::new(Wells(1000)), method);
//! let initial = Initial::Momentum { q: DVector::from_element(1000, 1.0), p: DVector::zeros(1000) };
//! let run = integrator.run(0.0, initial, 0.01, 1.0, &mut ())?;
//! assert!(run.last.q[0] < 1.0);
//! # Ok::<(), svi::Error>(())
//! ```

use nalgebra::{DMatrix, DVector, Dyn};

use crate::dimension::Wrt;
use crate::error::Error;
use crate::model::hamiltonian::{CanonicalSecond, HamiltonianForm, HamiltonianStructure};
use crate::model::local::{LocalLagrangian, TermWidth};
use crate::model::{ExactSolution, Invariants, Lagrangian, Symmetries, TermDerivatives, TermSum};
use crate::scalar::{Scalar, constant};

/// H = Σₑ hₑ(t, q_{I(e)}, p_{I(e)}) (see the module docs).
///
/// A term may use fewer than K coordinates: it repeats an index and ignores that slot, as a
/// [`LocalLagrangian`]'s term does.
pub trait LocalHamiltonian {
    /// K, the number of coordinates of one term, as `nalgebra::Const<K>`.
    type Width: TermWidth;

    /// Whether H depends explicitly on t (the default, `true`, is always correct).
    const TIME_DEPENDENT: bool = true;

    /// `General` (the default, always correct) or `Separable`, every term
    /// Tₑ(p) + Vₑ(t, q): `verlet-h` and its compositions then step explicitly. Checked term
    /// by term at the initial state of an integrator's first run.
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::General;

    /// n, the number of coordinates.
    fn dimension(&self) -> usize;

    /// The number of terms.
    fn term_count(&self) -> usize;

    /// The index set I(e) of term `term` (each below [`LocalHamiltonian::dimension`]).
    fn indices(&self, term: usize) -> <Self::Width as TermWidth>::Indices;

    /// The term hₑ(t, q_{I(e)}, p_{I(e)}), written once, generic over the scalar.
    fn term<D: Scalar>(
        &self,
        term: usize,
        t: D,
        q: &<Self::Width as TermWidth>::Vector<D>,
        p: &<Self::Width as TermWidth>::Vector<D>,
    ) -> D;
}

/// H's terms read as a [`LocalLagrangian`]'s, p in the velocity's slot: the term machinery
/// of [`crate::model::local`] then differentiates them.
#[derive(Debug, Clone, PartialEq)]
struct AsTerms<H>(H);

impl<H: LocalHamiltonian> LocalLagrangian for AsTerms<H> {
    type Width = H::Width;
    const TIME_DEPENDENT: bool = H::TIME_DEPENDENT;

    fn dimension(&self) -> usize {
        self.0.dimension()
    }

    fn term_count(&self) -> usize {
        self.0.term_count()
    }

    #[inline]
    fn indices(&self, term: usize) -> <Self::Width as TermWidth>::Indices {
        self.0.indices(term)
    }

    #[inline]
    fn term<D: Scalar>(
        &self,
        term: usize,
        t: D,
        q: &<Self::Width as TermWidth>::Vector<D>,
        p: &<Self::Width as TermWidth>::Vector<D>,
    ) -> D {
        self.0.term(term, t, q, p)
    }
}

/// A [`LocalHamiltonian`] as a model of the methods on Hamilton's equations (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LocalCanonical<H>(AsTerms<H>);

impl<H: LocalHamiltonian> LocalCanonical<H> {
    /// The model of `hamiltonian`.
    pub fn new(hamiltonian: H) -> Self {
        LocalCanonical(AsTerms(hamiltonian))
    }

    /// The Hamiltonian.
    pub fn hamiltonian(&self) -> &H {
        &self.0.0
    }

    /// Every term's first (and with `second`, second) derivatives at (t, q, p), handed to
    /// `visit(indices, derivatives, layout)`.
    fn for_each_term(
        &self,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        second: bool,
        mut visit: impl FnMut(&[usize], &[f64], &TermDerivatives),
    ) {
        let terms: &dyn TermSum<Dyn> = &self.0;
        let layout = TermDerivatives {
            width: terms.width(),
        };
        let k = layout.width;
        let mut indices = vec![0; k];
        let (mut local_q, mut local_p) = (vec![0.0; k], vec![0.0; k]);
        let mut derivatives = vec![0.0; layout.len()];
        for e in 0..terms.term_count() {
            terms.term_indices(e, &mut indices);
            for (a, &i) in indices.iter().enumerate() {
                (local_q[a], local_p[a]) = (q[i], p[i]);
            }
            terms.term_derivatives(e, t, &local_q, &local_p, second, &mut derivatives);
            visit(&indices, &derivatives, &layout);
        }
    }
}

impl<H: LocalHamiltonian> HamiltonianForm<Dyn> for LocalCanonical<H> {
    fn structure(&self) -> HamiltonianStructure {
        H::STRUCTURE
    }

    fn forced(&self) -> bool {
        false
    }

    fn without_lagrangian(&self) -> bool {
        true
    }

    fn value(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> f64 {
        LocalLagrangian::value(&self.0, t, q, p)
    }

    /// Term by term, O(n).
    fn gradient(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> (DVector<f64>, DVector<f64>) {
        let terms: &dyn TermSum<Dyn> = &self.0;
        let (mut hq, mut hp) = (DVector::zeros(q.len()), DVector::zeros(q.len()));
        terms.gradient_into(t, q, p, Wrt::Position, &mut hq);
        terms.gradient_into(t, q, p, Wrt::Velocity, &mut hp);
        (hq, hp)
    }

    /// ∂H/∂p term by term, O(n).
    fn velocity(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> DVector<f64> {
        let mut hp = DVector::zeros(q.len());
        (&self.0 as &dyn TermSum<Dyn>).gradient_into(t, q, p, Wrt::Velocity, &mut hp);
        hp
    }

    /// ∂H/∂q term by term, O(n).
    fn position_gradient(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> DVector<f64> {
        let mut hq = DVector::zeros(q.len());
        (&self.0 as &dyn TermSum<Dyn>).gradient_into(t, q, p, Wrt::Position, &mut hq);
        hq
    }

    /// The Hessian blocks assembled from the terms' into dense n × n matrices (the implicit
    /// methods; the explicit splitting of a separable H never asks for them).
    fn second(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> CanonicalSecond<Dyn> {
        let n = q.len();
        let (hq, hp) = self.gradient(t, q, p);
        let (mut qq, mut qp, mut pp) = (
            DMatrix::zeros(n, n),
            DMatrix::zeros(n, n),
            DMatrix::zeros(n, n),
        );
        self.for_each_term(t, q, p, true, |indices, d, layout| {
            for (a, &i) in indices.iter().enumerate() {
                for (b, &j) in indices.iter().enumerate() {
                    // A repeated index is a slot the term ignores: its derivatives are zero.
                    qq[(i, j)] += layout.qq(d, a, b);
                    qp[(i, j)] += layout.qv(d, a, b);
                    pp[(i, j)] += layout.vv(d, a, b);
                }
            }
        });
        CanonicalSecond {
            value: self.value(t, q, p),
            hq,
            hp,
            qq,
            qp,
            pp,
        }
    }

    fn force(&self, _t: f64, q: &DVector<f64>, _p: &DVector<f64>) -> DVector<f64> {
        DVector::zeros(q.len())
    }

    fn force_jacobian(
        &self,
        _t: f64,
        q: &DVector<f64>,
        _p: &DVector<f64>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = q.len();
        (DMatrix::zeros(n, n), DMatrix::zeros(n, n))
    }

    /// H and its gradient finite; for a declared separable H every term's ∂²hₑ/∂q∂p zero at
    /// (q, p) and at a shifted p. O(n): no n × n matrix.
    fn check(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> Result<(), Error> {
        let (hq, hp) = self.gradient(t, q, p);
        let value = self.value(t, q, p);
        let finite = std::iter::once(value)
            .chain(hq.iter().copied())
            .chain(hp.iter().copied())
            .all(f64::is_finite);
        if !finite {
            return Err(Error::NonFinite {
                what: "Hamiltonian H or its gradient at the initial state".into(),
                step: 0,
                t,
            });
        }
        if H::STRUCTURE == HamiltonianStructure::General {
            return Ok(());
        }
        let shifted = p.map(|x| 2.0 * x + 1.0);
        let mut coupling = 0.0_f64;
        for momenta in [p, &shifted] {
            self.for_each_term(t, q, momenta, true, |indices, d, layout| {
                for a in 0..indices.len() {
                    for b in 0..indices.len() {
                        coupling = coupling.max(layout.qv(d, a, b).abs());
                    }
                }
            });
        }
        if coupling > 1e-12 * (1.0 + value.abs()) {
            return Err(Error::invalid(
                "model",
                format!(
                    "the Hamiltonian is declared separable (T(p) + V(t, q)), but a term's \
                     ∂²h/∂q∂p is {coupling:e} at the initial state"
                ),
            ));
        }
        Ok(())
    }
}

impl<H: LocalHamiltonian> Lagrangian<Dyn> for LocalCanonical<H> {
    const TIME_DEPENDENT: bool = H::TIME_DEPENDENT;

    fn dimension(&self) -> usize {
        self.0.dimension()
    }

    fn hamiltonian_form(&self) -> Option<&dyn HamiltonianForm<Dyn>> {
        Some(self)
    }

    /// NaN: the model has no Lagrangian (module docs); the methods that would read it refuse
    /// the model before the first step.
    fn lagrangian<D: Scalar>(&self, _t: D, _q: &DVector<D>, _v: &DVector<D>) -> D {
        constant(f64::NAN)
    }
}

impl<H: LocalHamiltonian> Symmetries<Dyn> for LocalCanonical<H> {}
impl<H: LocalHamiltonian> Invariants<Dyn> for LocalCanonical<H> {}

impl<H: LocalHamiltonian> ExactSolution<Dyn> for LocalCanonical<H> {
    /// None.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &DVector<f64>,
        _v0: &DVector<f64>,
        _t: f64,
    ) -> Option<(DVector<f64>, DVector<f64>)> {
        None
    }
}
