//! The inverse of a constant mass matrix M = ∂²L/∂q̇² on runtime-sized ℝⁿ, assembled from
//! the terms' blocks once per run and applied as q̇ = M⁻¹p in O(n).
//!
//! A diagonal M (particles with their own masses: chains, lattices) is inverted entry by
//! entry. A coupled M (a consistent finite-element mass matrix, bodies sharing
//! coordinates) is factored once by faer's sparse LU on the pattern of the terms' blocks
//! (`linalg::sparse`), so any n whose factors fit in memory runs.

use crate::error::Error;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use nalgebra::DVector;
use std::cell::RefCell;

/// M⁻¹ of a constant mass matrix, ready to apply.
#[derive(Debug)]
pub enum MassInverse {
    /// The reciprocal diagonal entries.
    Diagonal(DVector<f64>),
    /// The sparse LU factors of a coupled M (faer), in a cell because the solve writes
    /// to the factorisation's scratch memory.
    Coupled(Box<RefCell<SparseLu>>),
}

impl MassInverse {
    /// M⁻¹ for M of size n given as (row, column, value) triplets (repeated places add up).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular or not positive on its
    /// diagonal.
    pub fn new(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Self, Error> {
        let singular = |what: String| {
            Error::invalid(
                "structure",
                format!("the mass matrix ∂²L/∂q̇² is {what}: the Legendre map is not invertible"),
            )
        };
        let mut diagonal = DVector::<f64>::zeros(n);
        for (i, j, value) in triplets {
            if i == j {
                diagonal[*i] += value;
            }
        }
        if let Some(i) = diagonal.iter().position(|m| !(*m > 0.0 && m.is_finite())) {
            return Err(singular(format!(
                "not positive on its diagonal: entry {:e} at coordinate {i}",
                diagonal[i]
            )));
        }
        if triplets.iter().all(|(i, j, _)| i == j) {
            return Ok(MassInverse::Diagonal(diagonal.map(|m| 1.0 / m)));
        }
        let places: Vec<(usize, usize)> = triplets.iter().map(|&(i, j, _)| (i, j)).collect();
        let pattern = Pattern::new(n, &places)?;
        let mut values = vec![0.0; pattern.len()];
        for &(i, j, value) in triplets {
            if let Some(slot) = pattern.slot(i, j) {
                values[slot] += value;
            }
        }
        let mut lu = SparseLu::default();
        lu.analyse(&pattern)?;
        lu.factor(&pattern, &values)
            .map_err(|_| singular("singular".to_string()))?;
        // faer does not stop at a zero pivot: a singular M shows in a solve.
        let mut probe = DVector::from_element(n, 1.0);
        lu.solve_in_place(&mut probe)
            .map_err(|_| singular("singular".to_string()))?;
        Ok(MassInverse::Coupled(Box::new(RefCell::new(lu))))
    }

    /// out = M⁻¹ p (out and p of length n).
    pub fn apply_into(&self, p: &DVector<f64>, out: &mut DVector<f64>) {
        match self {
            MassInverse::Diagonal(inverse) => {
                for ((o, p), m) in out
                    .as_mut_slice()
                    .iter_mut()
                    .zip(p.as_slice())
                    .zip(inverse.as_slice())
                {
                    *o = p * m;
                }
            }
            MassInverse::Coupled(lu) => {
                out.copy_from(p);
                // Factored and probed in `new`: a non-finite result can only come from a
                // non-finite p, and shows in the caller's finiteness checks.
                let _ = lu.borrow_mut().solve_in_place(out);
            }
        }
    }

    /// M⁻¹ p.
    pub fn apply(&self, p: &DVector<f64>) -> DVector<f64> {
        let mut out = DVector::zeros(p.len());
        self.apply_into(p, &mut out);
        out
    }
}
