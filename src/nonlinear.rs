//! Nonlinear iterations shared by the implicit spectral methods.
//!
//! Like Hairer's GNI codes, every iteration starts from extrapolated stage values and runs to
//! round-off.
//! - [`Newton`] (exact Jacobian) stops once an increment is below `1e-10` of the unknowns'
//!   size (the next increment would be at round-off), or when the increments stop decreasing
//!   at a level where only round-off remains.
//! - [`FixedPoint`] (for non-stiff problems with constant mass matrix, where no Jacobian is
//!   needed) converges linearly, so it stops only when an increment is below two ulps of the
//!   positions it updates, or stops decreasing near round-off. (Iterating further, until the
//!   increment vanishes, bought no accuracy on Kepler at T = 2000 once the stage tables are
//!   exact, and cost 15% more force evaluations. Stopping one iteration earlier, once the
//!   contraction estimate predicts a next change below two ulps, saves 20% of the
//!   evaluations but the iteration approaches its fixed point from one side: the leftover
//!   bias accumulates into a drift of the energy, and the same Kepler run ends 10⁻⁸ off
//!   instead of 10⁻¹¹.)

use crate::error::StepFailure;
use crate::linalg::DenseLu;
use nalgebra::{DMatrix, DVector};
use std::ops::ControlFlow;

/// Relative increment below which the iteration is converged.
const CONVERGED: f64 = 1e-10;
/// Relative increment below which a non-decreasing Newton increment means round-off.
const STALLED: f64 = 1e-6;
/// Relative increment below which a non-decreasing fixed-point increment means round-off.
const FIXED_POINT_NOISE: f64 = 1e-13;

/// Buffers of a Newton iteration on `size` unknowns.
#[derive(Debug, Clone)]
pub(crate) struct Newton {
    pub(crate) lu: DenseLu,
    pub(crate) residual: DVector<f64>,
    pub(crate) max_iterations: usize,
}

impl Newton {
    pub(crate) fn new(size: usize, max_iterations: usize) -> Self {
        Newton {
            lu: DenseLu::new(size),
            residual: DVector::zeros(size),
            max_iterations,
        }
    }

    /// Solve F(z) = 0 starting from `z`. `assemble(z, jacobian, residual)` writes F(z) and
    /// F'(z). Returns the number of iterations.
    pub(crate) fn solve<F>(
        &mut self,
        z: &mut DVector<f64>,
        mut assemble: F,
    ) -> Result<usize, StepFailure>
    where
        F: FnMut(&DVector<f64>, &mut DMatrix<f64>, &mut DVector<f64>),
    {
        let mut previous = f64::INFINITY;
        for iteration in 1..=self.max_iterations {
            assemble(z, self.lu.matrix_mut(), &mut self.residual);
            if !self.residual.iter().all(|r| r.is_finite()) {
                return Err(StepFailure::NonFinite);
            }
            self.lu.factor().map_err(|_| StepFailure::SingularMatrix)?;
            self.lu.solve_in_place(&mut self.residual);
            *z -= &self.residual;
            let size = self.residual.amax();
            if !size.is_finite() {
                return Err(StepFailure::NonFinite);
            }
            let scale = z.amax();
            if size <= CONVERGED * scale
                || size == 0.0
                || (size >= previous && size <= STALLED * scale)
            {
                return Ok(iteration);
            }
            previous = size;
        }
        Err(StepFailure::NonConvergence {
            iterations: self.max_iterations,
            residual: previous,
        })
    }
}

/// Convergence control of a fixed-point iteration run to round-off.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FixedPoint {
    previous: f64,
    iterations: usize,
    max_iterations: usize,
}

impl FixedPoint {
    pub(crate) fn new(max_iterations: usize) -> Self {
        FixedPoint {
            previous: f64::INFINITY,
            iterations: 0,
            max_iterations,
        }
    }

    /// Iterations performed so far.
    pub(crate) fn iterations(&self) -> usize {
        self.iterations
    }

    /// Record an increment of infinity norm `size`, for unknowns whose round-off level is
    /// `scale` times the machine epsilon (the size of the positions they build); `Ok(true)`
    /// once converged.
    pub(crate) fn converged(&mut self, size: f64, scale: f64) -> Result<bool, StepFailure> {
        self.iterations += 1;
        if !size.is_finite() {
            return Err(StepFailure::NonFinite);
        }
        if size <= 2.0 * f64::EPSILON * scale
            || (size >= self.previous && size <= FIXED_POINT_NOISE * scale)
        {
            return Ok(true);
        }
        if self.iterations >= self.max_iterations {
            return Err(StepFailure::NonConvergence {
                iterations: self.iterations,
                residual: size,
            });
        }
        self.previous = size;
        Ok(false)
    }
}

/// What a step does after trying the fixed-point iteration: `Break` with the step's result,
/// or `Continue` with the iterations spent, to go on with Newton's method.
///
/// A velocity-dependent force makes the fixed point contract only by a factor
/// O(h ‖M⁻¹ ∂f_L/∂q̇‖), so for a forced model a non-converging or diverging fixed point
/// switches the run to Newton's method (`newton_only`), starting from the same starting
/// values; for an unforced model its failure is the step's failure.
pub(crate) fn after_fixed_point<T>(
    result: Result<T, StepFailure>,
    forced: bool,
    newton_only: &mut bool,
) -> ControlFlow<Result<T, StepFailure>, usize> {
    match result {
        Err(StepFailure::NonConvergence { iterations, .. }) if forced => {
            *newton_only = true;
            ControlFlow::Continue(iterations)
        }
        Err(StepFailure::NonFinite) if forced => {
            *newton_only = true;
            ControlFlow::Continue(0)
        }
        result => ControlFlow::Break(result),
    }
}
