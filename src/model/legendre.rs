//! The inverse Legendre map of a sum of local terms, q̇ = (∂L/∂q̇)⁻¹(p) at (t, q), by Newton's
//! method with the sparse mass matrix ∂²L/∂q̇² assembled term by term on its pattern
//! ([`crate::model::term_pattern`]) and solved through the linear-solver seam
//! ([`crate::linalg::sparse`]): O(n) work and memory per iteration for a chain or lattice,
//! where the dense map of [`crate::model::derived::LagrangianExt::velocity`] would hold an
//! n × n matrix.
//!
//! Each Newton step is halved until ∂L/∂q̇ is finite again: a relativistic kinetic energy is
//! defined only for |q̇| < c, and a full step from rest can leave that domain.

use crate::dimension::Dyn;
use crate::error::Error;
use crate::linalg::sparse::{AnySolver, LinearSolverKind};
use crate::model::term_pattern::{MAX_WIDTH, TermPattern};
use crate::model::{TermDerivatives, TermSum};
use crate::nonlinear::stalled;
use nalgebra::DVector;
use std::cell::RefCell;

/// The pattern, solver and buffers of the inverse Legendre map of one sum of terms.
#[derive(Debug)]
pub(crate) struct Legendre {
    terms: TermPattern,
    solver: AnySolver,
    /// ∂²L/∂q̇² in the pattern's slot order.
    values: Vec<f64>,
    derivatives: Vec<f64>,
    /// ∂L/∂q̇ − p, then the Newton correction.
    residual: DVector<f64>,
    correction: DVector<f64>,
    max_iterations: usize,
}

impl Legendre {
    /// The map of `terms` on `n` coordinates, its pattern analysed by a solver of `kind`.
    ///
    /// # Errors
    /// As [`TermPattern::new`], or when the symbolic analysis fails.
    pub(crate) fn new(
        terms: &dyn TermSum<Dyn>,
        n: usize,
        kind: LinearSolverKind,
    ) -> Result<Self, Error> {
        let pattern = TermPattern::new(terms, n)?;
        let solver = AnySolver::analysed(kind, &pattern.pattern)?;
        Ok(Legendre {
            values: vec![0.0; pattern.pattern.len()],
            derivatives: vec![
                0.0;
                TermDerivatives {
                    width: pattern.width()
                }
                .len()
            ],
            residual: DVector::zeros(n),
            correction: DVector::zeros(n),
            terms: pattern,
            solver,
            max_iterations: 50,
        })
    }

    /// ∂L/∂q̇(t, q, v) − p into `self.residual` (and with `matrix` the values of ∂²L/∂q̇²);
    /// its largest absolute entry, NaN when one is not finite.
    fn residual(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        q: &[f64],
        p: &[f64],
        v: &[f64],
        matrix: bool,
    ) -> f64 {
        let k = self.terms.width();
        let layout = TermDerivatives { width: k };
        let (mut ql, mut vl) = ([0.0; MAX_WIDTH], [0.0; MAX_WIDTH]);
        if matrix {
            self.values.fill(0.0);
        }
        for (r, p) in self.residual.iter_mut().zip(p) {
            *r = -p;
        }
        for e in 0..self.terms.term_count() {
            self.terms.gather(e, q, v, &mut ql, &mut vl);
            terms.term_derivatives(e, t, &ql[..k], &vl[..k], matrix, &mut self.derivatives);
            for (a, &i) in self.terms.indices(e).iter().enumerate() {
                self.residual[i] += layout.v(&self.derivatives, a);
                if matrix {
                    for b in 0..k {
                        let slot = self.terms.slot(e, a, b);
                        self.values[slot] += layout.vv(&self.derivatives, a, b);
                    }
                }
            }
        }
        self.residual
            .iter()
            .try_fold(0.0f64, |m, x| x.is_finite().then(|| m.max(x.abs())))
            .unwrap_or(f64::NAN)
    }

    /// Solve ∂L/∂q̇(t, q, v) = p for v by Newton's method, starting from `v` (from rest where
    /// ∂L/∂q̇ is not finite at `v`).
    ///
    /// # Errors
    /// [`Error::LegendreMap`] when the iteration does not converge or meets a singular mass
    /// matrix.
    pub(crate) fn solve(
        &mut self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        q: &[f64],
        p: &[f64],
        v: &mut [f64],
    ) -> Result<(), Error> {
        let scale = p
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        let failure = |iterations: usize, residual: f64| Error::LegendreMap {
            t,
            iterations,
            residual,
        };
        let mut size = self.residual(terms, t, q, p, v, true);
        if !size.is_finite() {
            v.fill(0.0);
            size = self.residual(terms, t, q, p, v, true);
        }
        let mut previous = f64::INFINITY;
        for iteration in 0..self.max_iterations {
            if !size.is_finite() {
                return Err(failure(iteration, size));
            }
            if size <= 4.0 * f64::EPSILON * scale || stalled(size, previous, 1e-12, scale) {
                return Ok(());
            }
            previous = size;
            let solver = self.solver.get();
            solver
                .factor(&self.terms.pattern, &self.values)
                .map_err(|_| failure(iteration, f64::INFINITY))?;
            solver
                .solve_in_place(&mut self.residual)
                .map_err(|_| failure(iteration, f64::INFINITY))?;
            std::mem::swap(&mut self.residual, &mut self.correction);
            // The full step, halved (half of it given back) until ∂L/∂q̇ is finite again.
            let mut fraction = 1.0;
            shift(v, -fraction, &self.correction);
            while !self.residual(terms, t, q, p, v, false).is_finite() && fraction >= 1e-6 {
                fraction *= 0.5;
                shift(v, fraction, &self.correction);
            }
            size = self.residual(terms, t, q, p, v, true);
        }
        Err(failure(self.max_iterations, previous))
    }
}

/// `v += a c`.
fn shift(v: &mut [f64], a: f64, c: &DVector<f64>) {
    for (v, c) in v.iter_mut().zip(c.iter()) {
        *v += a * c;
    }
}

/// A run's inverse Legendre map (pattern, symbolic analysis and buffers), made at its first
/// use and kept for the run's later points; a clone starts without one (faer's factors are
/// not cloned) and makes its own.
#[derive(Debug, Default)]
pub(crate) struct LazyLegendre(RefCell<Option<Legendre>>);

impl Clone for LazyLegendre {
    fn clone(&self) -> Self {
        LazyLegendre::default()
    }
}

impl LazyLegendre {
    /// q̇ for the momentum `p` at (t, q), into `v` (the guess on entry), as [`velocity`]
    /// but without making the map anew.
    ///
    /// # Errors
    /// As [`velocity`].
    pub(crate) fn solve(
        &self,
        terms: &dyn TermSum<Dyn>,
        t: f64,
        q: &[f64],
        p: &[f64],
        v: &mut [f64],
    ) -> Result<(), Error> {
        let mut slot = self.0.borrow_mut();
        let legendre = match &mut *slot {
            Some(legendre) => legendre,
            empty => empty.insert(Legendre::new(terms, q.len(), LinearSolverKind::Auto)?),
        };
        legendre.solve(terms, t, q, p, v)
    }
}

/// The velocity of the momentum `p` at (t, q) by a [`Legendre`] map made for this call (its LU
/// chosen by [`LinearSolverKind::resolve`]), started from `v`'s value on entry and written into
/// `v`.
///
/// # Errors
/// As [`Legendre::new`] and [`Legendre::solve`].
pub(crate) fn velocity(
    terms: &dyn TermSum<Dyn>,
    t: f64,
    q: &[f64],
    p: &[f64],
    v: &mut [f64],
) -> Result<(), Error> {
    Legendre::new(terms, q.len(), LinearSolverKind::Auto)?.solve(terms, t, q, p, v)
}
