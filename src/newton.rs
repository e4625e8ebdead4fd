//! The Newton iteration shared by the implicit spectral methods.
//!
//! Like Hairer's GNI codes, the iteration starts from extrapolated stage values and runs to
//! round-off: it stops once an increment is below `1e-10` of the unknowns' size (with the
//! exact Jacobian the next increment would be at round-off), or when the increments stop
//! decreasing at a level where only round-off remains.

use crate::error::StepFailure;
use crate::linalg::DenseLu;
use nalgebra::{DMatrix, DVector};

/// Relative increment below which the iteration is converged.
const CONVERGED: f64 = 1e-10;
/// Relative increment below which a non-decreasing increment means round-off.
const STALLED: f64 = 1e-6;

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
    pub(crate) fn solve<F>(&mut self, z: &mut DVector<f64>, mut assemble: F) -> Result<usize, StepFailure>
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
            if size <= CONVERGED * scale || size == 0.0 || (size >= previous && size <= STALLED * scale) {
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
