//! Constrained variational integrators: a Lagrangian L(t, q, q̇) on ℝⁿ with holonomic
//! constraints g(q) = 0 ([`Constraints`]).
//!
//! The discrete variational principle with multipliers (Marsden & West 2001, §3.5) makes
//! stationary the discrete action Σ L_d(q_k, q_{k+1}) − Σ λ_kᵀ g(q_k): each step solves the
//! discrete Euler–Lagrange equations with the constraint forces −G(q)ᵀλ (G = ∂g/∂q) together
//! with g(q_{k+1}) = 0, and the momentum is projected onto the cotangent space
//! G(q) M⁻¹ p = 0 of the hidden velocity constraint. The methods keep the constraint manifold
//! to round-off, are symplectic on its cotangent bundle and keep the momenta of the symmetries
//! that respect the constraints.
//!
//! [`ConstrainedMethod`] names them: RATTLE and its symmetric compositions ([`rattle`]), the
//! segment rules symplectic Euler, midpoint and trapezoid ([`discrete`]), and the
//! constrained SVI ([`galerkin`]). A run projects the initial data onto the constraints first
//! ([`crate::model::constraint::project`]) and reports how far it moved them, and the largest
//! constraint violations over the run at position and velocity level.

pub mod discrete;
pub mod galerkin;
pub mod rattle;

use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::linalg::DenseLu;
use crate::method::variational::composition::Scheme;
use crate::model::constraint::{Constraints, ConstraintsExt, Projected, project};
use crate::model::derived::LagrangianExt;
use crate::model::{Lagrangian, Structure};
pub use discrete::{ConstrainedDel, SegmentRule};
pub use galerkin::{ConstrainedSvi, ConstraintPoints};
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector, U1};
pub use rattle::Rattle;
use std::ops::ControlFlow;

/// A constrained method, by name.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ConstrainedMethod {
    /// RATTLE, alone or composed ([`rattle`]).
    Rattle(Rattle),
    /// The constrained SVI ([`galerkin`]).
    Galerkin(ConstrainedSvi),
    /// The constrained discrete Euler–Lagrange equations of a segment rule ([`discrete`]).
    Discrete(ConstrainedDel),
}

impl ConstrainedMethod {
    /// The names [`ConstrainedMethod::named`] accepts: `rattle`, `rattle-yoshida4`,
    /// `rattle-kahan-li6`, `rattle-kahan-li8`, the segment rules `symplectic-euler`,
    /// `symplectic-euler-adjoint`, `midpoint`, `trapezoid`, and the constrained SVI `svi:P/Q`
    /// (P nodes, Q Gauss points, constrained at Gauss points; listed as `svi:5/4`) and
    /// `svi:P/Q@nodes` (constrained at the interior nodes; listed as `svi:5/4@nodes`).
    pub fn names() -> Vec<String> {
        let galerkin = [
            ConstrainedSvi::new(5, 4),
            ConstrainedSvi::new(5, 4).constrained_at(ConstraintPoints::Nodes),
        ];
        std::iter::once(Rattle::default())
            .chain(Scheme::ALL.into_iter().map(Rattle::composed))
            .map(ConstrainedMethod::from)
            .chain(
                SegmentRule::ALL
                    .into_iter()
                    .map(|rule| ConstrainedDel::new(rule).into()),
            )
            .chain(galerkin.into_iter().map(ConstrainedMethod::from))
            .map(|method| method.name())
            .collect()
    }

    /// The method called `name` (one of [`ConstrainedMethod::names`]), with default options.
    pub fn named(name: &str) -> Option<Self> {
        if name == "rattle" {
            return Some(Rattle::default().into());
        }
        if let Some(rule) = SegmentRule::named(name) {
            return Some(ConstrainedDel::new(rule).into());
        }
        if let Some(method) = ConstrainedSvi::named(name) {
            return Some(method.into());
        }
        let scheme = Scheme::named(name.strip_prefix("rattle-")?)?;
        Some(Rattle::composed(scheme).into())
    }

    /// The method's name.
    pub fn name(&self) -> String {
        match self {
            ConstrainedMethod::Rattle(rattle) => rattle.name(),
            ConstrainedMethod::Galerkin(method) => method.name(),
            ConstrainedMethod::Discrete(method) => method.rule.name().into(),
        }
    }

    /// Whether the method is symmetric (all are symplectic on the constraint manifold):
    /// every one but symplectic Euler and its adjoint.
    pub fn symmetric(&self) -> bool {
        match self {
            ConstrainedMethod::Rattle(_) | ConstrainedMethod::Galerkin(_) => true,
            ConstrainedMethod::Discrete(method) => method.rule.symmetric(),
        }
    }

    /// Whether the method's numbers can run ([`ConstrainedSvi::check`]; the other methods
    /// have none).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the number out of range.
    pub fn check(&self) -> Result<(), Error> {
        match self {
            ConstrainedMethod::Galerkin(method) => method.check(),
            ConstrainedMethod::Rattle(_) | ConstrainedMethod::Discrete(_) => Ok(()),
        }
    }

    /// The order of the method.
    pub fn order(&self) -> usize {
        match self {
            ConstrainedMethod::Rattle(rattle) => rattle.order(),
            ConstrainedMethod::Galerkin(method) => method.order(),
            ConstrainedMethod::Discrete(method) => method.rule.order(),
        }
    }
}

impl From<ConstrainedDel> for ConstrainedMethod {
    fn from(method: ConstrainedDel) -> Self {
        ConstrainedMethod::Discrete(method)
    }
}

impl From<ConstrainedSvi> for ConstrainedMethod {
    fn from(method: ConstrainedSvi) -> Self {
        ConstrainedMethod::Galerkin(method)
    }
}

impl From<Rattle> for ConstrainedMethod {
    fn from(rattle: Rattle) -> Self {
        ConstrainedMethod::Rattle(rattle)
    }
}

/// A point of a constrained run.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstrainedPoint<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Time.
    pub t: f64,
    /// Configuration, on g = 0.
    pub q: OVector<f64, N>,
    /// Momentum, in the cotangent space G M⁻¹ p = 0.
    pub p: OVector<f64, N>,
    /// The position multipliers λ of the step's last (sub-)step: the constraint force at its
    /// start is −Gᵀλ.
    pub multipliers: DVector<f64>,
}

/// The end of a constrained run, with its constraint diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstrainedRun<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The last point.
    pub last: ConstrainedPoint<N>,
    /// The initial data as projected onto the constraints (and how far it moved).
    pub initial: Projected<N>,
    /// Steps taken.
    pub steps: usize,
    /// Newton iterations for the multipliers, summed over the run.
    pub iterations: usize,
    /// Evaluations of L's derivatives at a point (of L_d's for the segment rules), summed
    /// over the run.
    pub evaluations: usize,
    /// Matrices factorised (Newton's and the cotangent projection's), summed over the run.
    pub factorizations: usize,
    /// Whether the observer stopped the run (at `last`, before its `steps` were all taken).
    pub stopped: bool,
    /// max over the run of |g(q)|∞ (position level).
    pub constraint_error_max: f64,
    /// max over the run of |G(q) q̇|∞ (velocity level, q̇ = M⁻¹p).
    pub velocity_constraint_error_max: f64,
}

/// A Lagrangian with holonomic constraints and a constrained method.
#[derive(Debug, Clone)]
pub struct ConstrainedIntegrator<L, C> {
    /// The Lagrangian, of constant mass.
    pub model: L,
    /// The constraints g(q) = 0.
    pub constraints: C,
    /// The method.
    pub method: ConstrainedMethod,
}

impl<L, C> ConstrainedIntegrator<L, C> {
    /// Pair `model` and `constraints` with `method`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a Lagrangian without a constant mass matrix or with a
    /// non-conservative force (RATTLE needs L = ½ q̇ᵀMq̇ − V(q)), or with no constraint.
    pub fn new<N: Dimension>(
        model: L,
        constraints: C,
        method: impl Into<ConstrainedMethod>,
    ) -> Result<Self, Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let method = method.into();
        if L::FORCED {
            return Err(Error::invalid(
                "model",
                "the constrained methods take no external force yet (write it as a potential)",
            ));
        }
        let explicit = L::STRUCTURE == Structure::ConstantMass && !L::TIME_DEPENDENT;
        if matches!(method, ConstrainedMethod::Rattle(_)) && !explicit {
            return Err(Error::invalid(
                "model",
                "RATTLE needs L = ½ q̇ᵀMq̇ − V(q): a constant mass matrix and no explicit time \
                 dependence (run midpoint or the constrained SVI)",
            ));
        }
        if constraints.count() == 0 {
            return Err(Error::invalid(
                "constraints",
                "none given: run the unconstrained model with verlet",
            ));
        }
        Ok(ConstrainedIntegrator {
            model,
            constraints,
            method,
        })
    }

    /// Run `steps` steps of size `h` from (t0, q0, p0), projected first onto the constraints
    /// ([`project`]); `observe` sees the initial point and the end of every step, and stops
    /// the run there by returning `ControlFlow::Break(())` ([`Flow`]; a closure returning
    /// `()` never stops it).
    ///
    /// # Errors
    /// Invalid input (h, the initial data, constraints of deficient rank), a mass matrix that
    /// is singular, or a Newton iteration for the multipliers that does not converge
    /// ([`Error::NonConvergence`]).
    pub fn run<N: Dimension, R: Flow>(
        &self,
        t0: f64,
        q0: &OVector<f64, N>,
        p0: &OVector<f64, N>,
        h: f64,
        steps: usize,
        observe: impl FnMut(&ConstrainedPoint<N>) -> R,
    ) -> Result<ConstrainedRun<N>, Error>
    where
        L: Lagrangian<N>,
        C: Constraints<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::invalid(
                "h",
                format!("must be finite and > 0, got {h}"),
            ));
        }
        if !t0.is_finite() || q0.iter().chain(p0.iter()).any(|x| !x.is_finite()) {
            return Err(Error::invalid("initial", "t0, q0 and p0 must be finite"));
        }
        let n = dimension_of::<N>(self.model.dimension())
            .map_err(|reason| Error::invalid("model", reason))?;
        if q0.len() != n.value() || p0.len() != n.value() {
            return Err(Error::invalid(
                "initial",
                format!("q0 and p0 need {} components", n.value()),
            ));
        }
        let zero = OVector::<f64, N>::zeros_generic(n, U1);
        let mass_inverse = self.model.mass_inverse(t0, q0, &zero)?;
        let initial = project(&self.constraints, &mass_inverse, q0, p0)?;
        match &self.method {
            ConstrainedMethod::Rattle(rattle) => {
                rattle::run(self, rattle, t0, h, steps, mass_inverse, initial, observe)
            }
            ConstrainedMethod::Galerkin(method) => {
                galerkin::run(self, method, t0, h, steps, initial, observe)
            }
            ConstrainedMethod::Discrete(method) => {
                discrete::run(self, method, t0, h, steps, initial, observe)
            }
        }
    }
}

/// The constraint violations at `point` (with velocity `velocity` and G(q) `jacobian`) into
/// `run`'s maxima, and one more step counted (`g` and `rate` are scratch of length m).
fn record<N: Dimension, C: Constraints<N>>(
    run: &mut ConstrainedRun<N>,
    constraints: &C,
    point: &ConstrainedPoint<N>,
    jacobian: &nalgebra::DMatrix<f64>,
    velocity: &OVector<f64, N>,
    (g, rate): (&mut DVector<f64>, &mut DVector<f64>),
) where
    DefaultAllocator: Allocator<N>,
{
    constraints.values_into(&point.q, g);
    rate.gemv(
        1.0,
        jacobian,
        &nalgebra::DVectorView::from_slice(velocity.as_slice(), velocity.len()),
        0.0,
    );
    run.constraint_error_max = run.constraint_error_max.max(g.amax());
    run.velocity_constraint_error_max = run.velocity_constraint_error_max.max(rate.amax());
    run.steps += 1;
}

/// Buffers of the projection of a momentum onto the cotangent space, sized once.
struct Projection<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    rate: DVector<f64>,
    directions: nalgebra::DMatrix<f64>,
    schur: DenseLu,
    /// The matrices S factorised so far.
    factorizations: usize,
    row: OVector<f64, N>,
    buffer: OVector<f64, N>,
}

impl<N: Dimension> Projection<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Buffers for `m` constraints on vectors shaped like `zero`.
    fn new(zero: &OVector<f64, N>, m: usize) -> Self {
        Projection {
            rate: DVector::zeros(m),
            directions: nalgebra::DMatrix::zeros(zero.len(), m),
            schur: DenseLu::new(m),
            factorizations: 0,
            row: zero.clone(),
            buffer: zero.clone(),
        }
    }

    /// `momentum` projected in place onto the cotangent space at `q` (with G(q) =
    /// `jacobian`): p − Gᵀμ with G q̇(q, p − Gᵀμ) = 0, q̇ the inverse Legendre map, by Newton's
    /// method on μ with S = G M⁻¹ Gᵀ (one iteration for a constant mass). Returns the velocity
    /// there; `guess` starts the Legendre map. `(step, cap)`: the step for errors and the cap
    /// on iterations.
    #[allow(clippy::too_many_arguments)]
    fn project<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        jacobian: &nalgebra::DMatrix<f64>,
        momentum: &mut OVector<f64, N>,
        guess: &OVector<f64, N>,
        (step, cap): (usize, usize),
    ) -> Result<OVector<f64, N>, Error> {
        let mut velocity = model.velocity(t, q, momentum, guess)?;
        for iteration in 0..cap {
            self.rate.gemv(1.0, jacobian, &rattle::view(&velocity), 0.0);
            if iteration > 0 && self.rate.amax() <= 4.0 * f64::EPSILON * velocity.amax().max(1.0) {
                return Ok(velocity);
            }
            let inverse = model.mass_inverse(t, q, &velocity)?;
            rattle::directions_into(
                &inverse,
                jacobian,
                &mut self.row,
                &mut self.buffer,
                &mut self.directions,
            );
            jacobian.mul_to(&self.directions, self.schur.matrix_mut());
            self.factorizations += 1;
            self.schur
                .factor()
                .map_err(|_| Error::SingularMatrix { step, t })?;
            self.schur.solve_in_place(&mut self.rate);
            rattle::view_mut(momentum).gemv_tr(-1.0, jacobian, &self.rate, 1.0);
            velocity = model.velocity(t, q, momentum, &velocity)?;
            if L::STRUCTURE == Structure::ConstantMass {
                return Ok(velocity);
            }
        }
        Err(Error::NonConvergence {
            step,
            t,
            iterations: cap,
            residual: self.rate.amax(),
        })
    }
}

impl<N: Dimension> ConstrainedRun<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The first point of a run from the projected `initial` data at `t0` with `m`
    /// multipliers, and the run with nothing done yet.
    fn start(t0: f64, initial: Projected<N>, m: usize) -> (ConstrainedPoint<N>, Self) {
        let point = ConstrainedPoint {
            t: t0,
            q: initial.q.clone(),
            p: initial.p.clone(),
            multipliers: DVector::zeros(m),
        };
        let run = ConstrainedRun {
            last: point.clone(),
            initial,
            steps: 0,
            iterations: 0,
            evaluations: 0,
            factorizations: 0,
            stopped: false,
            constraint_error_max: 0.0,
            velocity_constraint_error_max: 0.0,
        };
        (point, run)
    }
}

/// The stopping rule of the constrained methods' Newton iterations: the correction `moved`
/// to the positions is at round-off of their size `scale`, or has stopped shrinking (by half
/// from `before`) near it.
fn at_round_off(moved: f64, before: f64, scale: f64) -> bool {
    moved <= 4.0 * f64::EPSILON * scale
        || (moved <= 1e3 * f64::EPSILON * scale && moved > 0.5 * before)
}

/// What an observer of a constrained run returns: `()` to go on, or a [`ControlFlow`] whose
/// `Break` stops the run at the point just observed ([`ConstrainedRun::stopped`]).
pub trait Flow {
    /// Whether the run stops here.
    fn stops(&self) -> bool;
}

impl Flow for () {
    fn stops(&self) -> bool {
        false
    }
}

impl Flow for ControlFlow<()> {
    fn stops(&self) -> bool {
        self.is_break()
    }
}

/// One Newton correction of the implicit constrained methods: `residual` (finite, else
/// [`Error::NonConvergence`]) becomes −J⁻¹ residual with J the matrix written into `newton`.
fn newton_correction(
    newton: &mut DenseLu,
    residual: &mut DVector<f64>,
    (step, t, iterations): (usize, f64, usize),
) -> Result<(), Error> {
    if !residual.iter().all(|x| x.is_finite()) {
        return Err(Error::NonConvergence {
            step,
            t,
            iterations,
            residual: f64::INFINITY,
        });
    }
    newton
        .factor()
        .map_err(|_| Error::SingularMatrix { step, t })?;
    residual.neg_mut();
    newton.solve_in_place(residual);
    Ok(())
}
