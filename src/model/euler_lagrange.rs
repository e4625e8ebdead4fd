//! The Euler–Lagrange equations of a sum of local terms ([`crate::model::TermSum`]) in
//! implicit form, term by term, and the acceleration they define, with the sparse mass matrix:
//! O(n) work and memory where differentiating the whole L would cost O(n³) for the
//! acceleration and O(n⁴) for its Jacobian.
//!
//! # The equations
//! At (t, q, y) with acceleration a the Euler–Lagrange residual is
//!
//! R = L_q̇q̇ a + L_q̇q y + L_q̇t − L_q = d/dε ∂L/∂q̇(t + ε, q + ε y, y + ε a)|₀ − ∂L/∂q,
//!
//! zero for the acceleration of the motion through (q, y). Its Jacobian blocks are
//!
//! J_q = ε[L_q̇q] − L_qq,   J_y = L_q̇q + ε[L_q̇q̇] − L_qq̇,   J_a = L_q̇q̇ = M,
//!
//! where ε[·] is the ε-part of a Hessian block at the dual point (t + ε, q + ε y, y + ε a):
//! third derivatives of L contracted with (1, y, a), from one evaluation of each term's
//! Hessian blocks over dual numbers ([`TermSum::term_derivatives_along`]). Each block has the
//! pattern of L's Hessian ([`TermPattern`]).
//!
//! The acceleration is a(t, q, q̇) = −M⁻¹ R(a = 0), and differentiating R(a(q, q̇); q, q̇) = 0
//! gives ∂a/∂q = −M⁻¹ J_q and ∂a/∂q̇ = −M⁻¹ J_y at (q, q̇, a) — the Jacobian the reference
//! methods' tangent maps and implicit Euler need ([`crate::method::reference`]). SC's
//! collocation equations on a sum of terms are the same residual at its nodes
//! ([`crate::method::collocation`]).

use crate::dimension::Dyn;
use crate::error::{Error, StepFailure};
use crate::linalg::sparse::{AnySolver, LinearSolverKind};
use crate::model::term_pattern::{MAX_WIDTH, PATTERN_MISMATCH, TermPattern};
use crate::model::{TermDerivatives, TermSum};
use nalgebra::{DMatrix, DVector};

/// One term's share of R and of its Jacobian blocks, from its derivatives along (1, y, a).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TermShare<'a> {
    layout: TermDerivatives,
    /// The term's gradients and Hessian blocks.
    value: &'a [f64],
    /// Their ε-parts.
    rate: &'a [f64],
}

impl<'a> TermShare<'a> {
    /// Term `e`'s share at (`t`, `q`, `y`) with acceleration `a` (its own K coordinates each),
    /// evaluated into `derivatives` (2 (2K + 3K²) entries).
    #[inline]
    pub(crate) fn along(
        terms: &dyn TermSum<Dyn>,
        e: usize,
        t: f64,
        (q, y, a): (&[f64], &[f64], &[f64]),
        derivatives: &'a mut [f64],
    ) -> Self {
        terms.term_derivatives_along(e, t, q, y, (y, a), derivatives);
        let layout = TermDerivatives { width: q.len() };
        let (value, rate) = derivatives.split_at(layout.len());
        TermShare {
            layout,
            value,
            rate,
        }
    }

    /// The entry of R at the term's coordinate `a`.
    #[inline]
    pub(crate) fn residual(&self, a: usize) -> f64 {
        self.layout.v(self.rate, a) - self.layout.q(self.value, a)
    }

    /// The entries (J_q, J_y, J_a) at the term's row `a` (the equation of its coordinate a) and
    /// column `b`.
    #[inline]
    pub(crate) fn jacobian(&self, a: usize, b: usize) -> [f64; 3] {
        let (layout, value, rate) = (self.layout, self.value, self.rate);
        [
            layout.qv(rate, b, a) - layout.qq(value, a, b),
            layout.qv(value, b, a) + layout.vv(rate, a, b) - layout.qv(value, a, b),
            layout.vv(value, a, b),
        ]
    }
}

/// The acceleration of one sum of terms and its Jacobian: the pattern, the LU of M (sparse or
/// dense by [`LinearSolverKind::resolve`]) and the buffers, made once per run.
#[derive(Debug)]
pub(crate) struct Acceleration {
    terms: TermPattern,
    solver: AnySolver,
    /// M, J_q and J_y in the pattern's slot order.
    blocks: [Vec<f64>; 3],
    derivatives: Vec<f64>,
    /// R, then the solution of M x = R.
    residual: DVector<f64>,
    zeros: DVector<f64>,
}

impl Acceleration {
    /// The acceleration of `terms` on `n` coordinates.
    ///
    /// # Errors
    /// As [`TermPattern::new`], or when the symbolic analysis fails.
    pub(crate) fn new(terms: &dyn TermSum<Dyn>, n: usize) -> Result<Self, Error> {
        let pattern = TermPattern::new(terms, n)?;
        let solver = AnySolver::analysed(LinearSolverKind::Auto, &pattern.pattern)?;
        let slots = pattern.pattern.len();
        let width = pattern.width();
        Ok(Acceleration {
            blocks: [vec![0.0; slots], vec![0.0; slots], vec![0.0; slots]],
            derivatives: vec![0.0; 2 * TermDerivatives { width }.len()],
            residual: DVector::zeros(n),
            zeros: DVector::zeros(n),
            terms: pattern,
            solver,
        })
    }

    /// R at (t, q, y) with acceleration `a` into `self.residual`, M into `blocks[0]` and, with
    /// `jacobian`, J_q and J_y into the others; M factored.
    fn assemble(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        (q, y, a): (&[f64], &[f64], &[f64]),
        jacobian: bool,
    ) -> Result<(), StepFailure> {
        let k = self.terms.width();
        let mut local = [[0.0; MAX_WIDTH]; 3];
        self.residual.fill(0.0);
        let [mass, jq, jy] = &mut self.blocks;
        mass.fill(0.0);
        if jacobian {
            jq.fill(0.0);
            jy.fill(0.0);
        }
        for e in 0..self.terms.term_count() {
            let [ql, yl, al] = &mut local;
            self.terms.gather(e, q, y, ql, yl);
            for (slot, &i) in self.terms.indices(e).iter().enumerate() {
                al[slot] = a[i];
            }
            let share = TermShare::along(
                terms,
                e,
                t,
                (&ql[..k], &yl[..k], &al[..k]),
                &mut self.derivatives,
            );
            for (row, &i) in self.terms.indices(e).iter().enumerate() {
                self.residual[i] += share.residual(row);
                for column in 0..k {
                    let slot = self.terms.slot(e, row, column);
                    let [from_q, from_y, from_a] = share.jacobian(row, column);
                    mass[slot] += from_a;
                    if jacobian {
                        jq[slot] += from_q;
                        jy[slot] += from_y;
                    }
                }
            }
        }
        if !self.residual.iter().all(|x| x.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        self.solver
            .get()
            .factor(&self.terms.pattern, mass)
            .map_err(|_| StepFailure::SingularMatrix)
    }

    /// The acceleration a = −M⁻¹ R(0) at (t, q, q̇) into `out`.
    ///
    /// # Errors
    /// [`StepFailure::SingularMatrix`] for a singular M, [`StepFailure::NonFinite`] where the
    /// derivatives are not finite.
    pub(crate) fn acceleration(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        (q, v): (&[f64], &[f64]),
        out: &mut [f64],
    ) -> Result<(), StepFailure> {
        let zeros = std::mem::take(&mut self.zeros);
        let assembled = self.assemble(terms, t, (q, v, zeros.as_slice()), false);
        self.zeros = zeros;
        assembled?;
        self.solve_residual(out)
    }

    /// −M⁻¹ R into `out`, M factored.
    fn solve_residual(&mut self, out: &mut [f64]) -> Result<(), StepFailure> {
        self.solver
            .get()
            .solve_in_place(&mut self.residual)
            .map_err(|_| StepFailure::SingularMatrix)?;
        for (x, r) in out.iter_mut().zip(self.residual.iter()) {
            *x = -r;
        }
        Ok(())
    }

    /// The acceleration a at (t, q, q̇) and its Jacobian ∂a/∂q = −M⁻¹ J_q, ∂a/∂q̇ = −M⁻¹ J_y,
    /// dense (n columns, each one sparse solve).
    ///
    /// # Errors
    /// As [`Acceleration::acceleration`].
    pub(crate) fn jacobian(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        (q, v): (&[f64], &[f64]),
    ) -> Result<RunTimeJacobian, StepFailure> {
        let n = q.len();
        let mut a = DVector::zeros(n);
        self.acceleration(terms, t, (q, v), a.as_mut_slice())?;
        self.assemble(terms, t, (q, v, a.as_slice()), true)?;
        let mut columns = [DMatrix::zeros(n, n), DMatrix::zeros(n, n)];
        let pattern = &self.terms.pattern;
        for (block, out) in self.blocks[1..].iter().zip(&mut columns) {
            for c in 0..n {
                self.residual.fill(0.0);
                for (slot, row) in
                    (pattern.column_start(c)..pattern.column_start(c + 1)).zip(pattern.column(c))
                {
                    self.residual[row] = block[slot];
                }
                self.solver
                    .get()
                    .solve_in_place(&mut self.residual)
                    .map_err(|_| StepFailure::SingularMatrix)?;
                for (x, r) in out.column_mut(c).iter_mut().zip(self.residual.iter()) {
                    *x = -r;
                }
            }
        }
        let [q, v] = columns;
        Ok(RunTimeJacobian { value: a, q, v })
    }
}

/// The acceleration and its Jacobian at one point, of run-time size
/// ([`crate::model::derived::AccelerationJacobian`] converts it to a model's dimension).
#[derive(Debug, Clone)]
pub(crate) struct RunTimeJacobian {
    /// q̈.
    pub(crate) value: DVector<f64>,
    /// ∂q̈/∂q.
    pub(crate) q: DMatrix<f64>,
    /// ∂q̈/∂q̇.
    pub(crate) v: DMatrix<f64>,
}

/// A run's [`Acceleration`], made at its first use; a clone starts without one (faer's factors
/// are not cloned) and makes its own.
#[derive(Debug, Default)]
pub(crate) struct LazyAcceleration(Option<Box<Acceleration>>);

impl Clone for LazyAcceleration {
    fn clone(&self) -> Self {
        LazyAcceleration(None)
    }
}

impl LazyAcceleration {
    /// The acceleration of `terms` on `n` coordinates, made at the first call, and the
    /// symbolic analyses this call made (1 at the first, else 0).
    ///
    /// # Errors
    /// [`StepFailure::Unsupported`] when the terms' pattern does not fit `n` coordinates.
    pub(crate) fn get(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        n: usize,
    ) -> Result<(&mut Acceleration, usize), StepFailure> {
        match &mut self.0 {
            Some(acceleration) => Ok((acceleration, 0)),
            empty => {
                let made = Acceleration::new(terms, n).map_err(|_| PATTERN_MISMATCH)?;
                Ok((empty.insert(Box::new(made)), 1))
            }
        }
    }
}
