//! A model given as the right-hand side of Hamilton's equations alone — the calling convention
//! of Porcù & Penati's Octave package, `[T, Y] = spectralvarint(odefun, tspan, y0, options)`
//! (002, "Code organization"): y = (q, p) ∈ ℝ²ᴺ and
//!
//! y' = F(t, y) = (∂H/∂p, −∂H/∂q + f_H),
//!
//! with neither H nor f_H known apart. [`HamiltonianRhs`] runs on the methods on Hamilton's
//! equations ([`crate::method::hamiltonian`]: `svi-h`, `sc-h`, `midpoint-h`, the partitioned
//! methods and their compositions), which read only the field and its derivatives: with
//! g = −ṗ and the blocks of F's Jacobian J = ∂F/∂y,
//!
//! | what a method reads | from F |
//! | --- | --- |
//! | q̇ = ∂H/∂p | F_q(t, y) |
//! | g = ∂H/∂q − f_H | −F_p(t, y) |
//! | ∂g/∂q, ∂g/∂p | −J_pq, −J_pp |
//! | ∂q̇/∂q, ∂q̇/∂p | J_qq, J_qp |
//!
//! These are handed over as a forced Hamiltonian form ([`HamiltonianForm`]): ∂H/∂q := −F_p,
//! ∂H/∂p := F_q, ∂²H/∂q² := −J_pq, ∂²H/∂q∂p := J_qqᵀ, ∂²H/∂p² := J_qp, f_H := 0 and
//! ∂f_H/∂p := J_qqᵀ + J_pp, so that ∂g/∂p = ∂²H/∂q∂p − ∂f_H/∂p = −J_pp. For a field that is
//! Hamiltonian (J_pp = −J_qqᵀ) the force's Jacobian vanishes and the blocks are H's.
//!
//! J comes from the caller when given ([`HamiltonianRhs::with_jacobian`]), else by central
//! differences with steps ε^{1/3}·max(1, |yⱼ|) (2·2N evaluations of F). The Jacobian drives
//! Newton's method only: the solution of a step's equations, solved to the methods' tolerance,
//! does not depend on it. A model written as H ([`crate::Hamiltonian`]) or L has its exact
//! derivatives by automatic differentiation instead, and an energy.
//!
//! With no H there is no energy ([`HamiltonianForm::value`] is NaN) and no Lagrangian: the
//! methods on the Euler–Lagrange equations refuse the model ([`Equations`]) with a typed error.
//!
//! [`Equations`]: crate::method::Equations

use std::fmt;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Dyn, OMatrix, OVector};

use crate::error::Error;
use crate::model::hamiltonian::{CanonicalSecond, HamiltonianForm, HamiltonianStructure};
use crate::model::{Defaults, ExactSolution, Invariants, Lagrangian, Symmetries};
use crate::scalar::{Scalar, constant};

/// F(t, y, dy): writes y' = F(t, y) into `dy` (both of length 2N, y = (q, p)). A failure is
/// written as a non-finite entry (the step then fails as
/// [`crate::StepFailure::NonFinite`]).
pub type RhsFunction = Arc<dyn Fn(f64, &[f64], &mut [f64]) + Send + Sync>;

/// J(t, y, jacobian): writes ∂F/∂y at (t, y) into `jacobian`, the 2N × 2N matrix column by
/// column (entry (i, j) = ∂Fᵢ/∂yⱼ at index i + 2N·j).
pub type RhsJacobian = Arc<dyn Fn(f64, &[f64], &mut [f64]) + Send + Sync>;

/// A model on T*ℝᴺ given by the right-hand side of Hamilton's equations (module docs).
///
/// ```
/// use nalgebra::DVector;
/// use svi::method::hamiltonian::galerkin::HamiltonianGalerkin;
/// use svi::model::rhs::HamiltonianRhs;
/// use svi::solve::{SolveOptions, Span, solve};
/// use svi::Initial;
///
/// // The damped pendulum: q' = p, p' = −sin q − c p (c = 0.1).
/// let odefun = |_t: f64, y: &[f64], dy: &mut [f64]| {
///     dy[0] = y[1];
///     dy[1] = -y[0].sin() - 0.1 * y[1];
/// };
/// let model = HamiltonianRhs::new(1, odefun)?;
/// let span = Span::times(&[0.0, 1.0, 2.0, 5.0]);
/// let initial = Initial::Momentum {
///     q: DVector::from_vec(vec![1.0]),
///     p: DVector::from_vec(vec![0.0]),
/// };
/// // Step doubling to tol = 1e-8, as spectralvarint's default.
/// let solution = solve(model, HamiltonianGalerkin::default(), &span, initial, &SolveOptions::default())?;
/// assert_eq!(solution.points.len(), 4);
/// assert!(solution.points[3].q[0].abs() < 1.0);
/// # Ok::<(), svi::Error>(())
/// ```
#[derive(Clone)]
pub struct HamiltonianRhs {
    /// N: y has 2N entries.
    dimension: usize,
    rhs: RhsFunction,
    jacobian: Option<RhsJacobian>,
}

impl fmt::Debug for HamiltonianRhs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HamiltonianRhs")
            .field("dimension", &self.dimension)
            .field("jacobian", &self.jacobian.is_some())
            .finish()
    }
}

impl HamiltonianRhs {
    /// The model y' = `rhs`(t, y) on T*ℝᴺ with N = `dimension` (y has 2N entries), its
    /// Jacobian by central differences.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`model`) for `dimension = 0`.
    pub fn new(
        dimension: usize,
        rhs: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Result<Self, Error> {
        if dimension == 0 {
            return Err(Error::invalid(
                "model",
                "a right-hand side of Hamilton's equations needs at least one coordinate \
                 (y = (q, p) has 2N ≥ 2 entries)",
            ));
        }
        Ok(HamiltonianRhs {
            dimension,
            rhs: Arc::new(rhs),
            jacobian: None,
        })
    }

    /// The same model with its Jacobian ∂F/∂y given by `jacobian` ([`RhsJacobian`]) instead of
    /// central differences.
    pub fn with_jacobian(
        mut self,
        jacobian: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        self.jacobian = Some(Arc::new(jacobian));
        self
    }

    /// y' = F(t, (q, p)).
    fn field(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> DVector<f64> {
        let y = DVector::from_iterator(2 * self.dimension, q.iter().chain(p.iter()).copied());
        let mut dy = DVector::zeros(2 * self.dimension);
        (self.rhs)(t, y.as_slice(), dy.as_mut_slice());
        dy
    }

    /// ∂F/∂y at (t, (q, p)): the caller's, or by central differences.
    fn jacobian(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> DMatrix<f64> {
        let size = 2 * self.dimension;
        let mut y = DVector::from_iterator(size, q.iter().chain(p.iter()).copied());
        let mut jacobian = DMatrix::zeros(size, size);
        if let Some(given) = &self.jacobian {
            given(t, y.as_slice(), jacobian.as_mut_slice());
            return jacobian;
        }
        let (mut plus, mut minus) = (DVector::zeros(size), DVector::zeros(size));
        for j in 0..size {
            let yj = y[j];
            let step = f64::EPSILON.cbrt() * yj.abs().max(1.0);
            y[j] = yj + step;
            (self.rhs)(t, y.as_slice(), plus.as_mut_slice());
            y[j] = yj - step;
            (self.rhs)(t, y.as_slice(), minus.as_mut_slice());
            y[j] = yj;
            jacobian.set_column(j, &((&plus - &minus) / (2.0 * step)));
        }
        jacobian
    }

    /// The N × N block (rows of `rows`, columns of `columns`: 0 for q, 1 for p) of `jacobian`.
    fn block(&self, jacobian: &DMatrix<f64>, rows: usize, columns: usize) -> DMatrix<f64> {
        let n = self.dimension;
        jacobian.view((rows * n, columns * n), (n, n)).into_owned()
    }
}

impl HamiltonianForm<Dyn> for HamiltonianRhs {
    fn structure(&self) -> HamiltonianStructure {
        HamiltonianStructure::General
    }

    /// Always: the part of F that is not a Hamiltonian field is handed over as f_H's
    /// Jacobian (module docs).
    fn forced(&self) -> bool {
        true
    }

    fn without_lagrangian(&self) -> bool {
        true
    }

    /// NaN: no H is known.
    fn value(&self, _t: f64, _q: &DVector<f64>, _p: &DVector<f64>) -> f64 {
        f64::NAN
    }

    /// (−F_p, F_q).
    fn gradient(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> (DVector<f64>, DVector<f64>) {
        let n = self.dimension;
        let dy = self.field(t, q, p);
        (-dy.rows(n, n), dy.rows(0, n).into_owned())
    }

    fn velocity(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> DVector<f64> {
        self.field(t, q, p).rows(0, self.dimension).into_owned()
    }

    /// The blocks of the module docs' table, H's value NaN.
    fn second(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> CanonicalSecond<Dyn> {
        let (hq, hp) = self.gradient(t, q, p);
        let jacobian = self.jacobian(t, q, p);
        CanonicalSecond {
            value: f64::NAN,
            hq,
            hp,
            qq: -self.block(&jacobian, 1, 0),
            qp: self.block(&jacobian, 0, 0).transpose(),
            pp: self.block(&jacobian, 0, 1),
        }
    }

    /// Zero: −∂H/∂q above is the whole of ṗ.
    fn force(&self, _t: f64, q: &DVector<f64>, _p: &DVector<f64>) -> DVector<f64> {
        DVector::zeros(q.len())
    }

    /// (0, J_qqᵀ + J_pp): what makes ∂g/∂p = −J_pp (module docs).
    fn force_jacobian(
        &self,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
    ) -> (OMatrix<f64, Dyn, Dyn>, OMatrix<f64, Dyn, Dyn>) {
        let n = self.dimension;
        let jacobian = self.jacobian(t, q, p);
        let fp = self.block(&jacobian, 0, 0).transpose() + self.block(&jacobian, 1, 1);
        (DMatrix::zeros(n, n), fp)
    }

    /// F finite at the initial state.
    fn check(&self, t: f64, q: &DVector<f64>, p: &DVector<f64>) -> Result<(), Error> {
        if self.field(t, q, p).iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(Error::NonFinite {
                what: "right-hand side of Hamilton's equations at the initial state".into(),
                step: 0,
                t,
            })
        }
    }
}

impl Lagrangian<Dyn> for HamiltonianRhs {
    const TIME_DEPENDENT: bool = true;

    fn dimension(&self) -> usize {
        self.dimension
    }

    fn hamiltonian_form(&self) -> Option<&dyn HamiltonianForm<Dyn>> {
        Some(self)
    }

    /// NaN: the model has no Lagrangian; the methods that would read it refuse the model
    /// before the first step.
    fn lagrangian<D: Scalar>(&self, _t: D, _q: &OVector<D, Dyn>, _v: &OVector<D, Dyn>) -> D {
        constant(f64::NAN)
    }
}

impl Symmetries<Dyn> for HamiltonianRhs {}
impl Invariants<Dyn> for HamiltonianRhs {}
impl ExactSolution<Dyn> for HamiltonianRhs {
    /// None: a right-hand side given as code has no known solution.
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

impl Defaults<Dyn> for HamiltonianRhs {
    fn name(&self) -> &'static str {
        "rhs"
    }

    /// `q1`, `q2`, ...
    fn coordinate_names(&self) -> Vec<String> {
        (1..=self.dimension).map(|i| format!("q{i}")).collect()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    fn set_parameter(&mut self, name: &str, _value: f64) -> Result<(), Error> {
        Err(Error::invalid(
            "parameter",
            format!("a right-hand side given as code has no parameters, not even '{name}'"),
        ))
    }

    /// The origin at rest: a right-hand side has no initial state of its own (the caller
    /// gives y0).
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let zero = DVector::zeros(self.dimension);
        (0.0, zero.clone(), zero)
    }

    fn default_step(&self) -> f64 {
        0.1
    }

    fn default_horizon(&self) -> f64 {
        10.0
    }
}
