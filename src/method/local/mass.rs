//! The inverse of a constant mass matrix M = ∂²L/∂q̇² on runtime-sized ℝⁿ, assembled from
//! the terms' blocks once per run and applied as q̇ = M⁻¹p in O(n).
//!
//! A diagonal M (particles with their own masses: chains, lattices) is inverted entry by
//! entry. A coupled M is factored densely up to [`MassInverse::MAX_DENSE`] coordinates;
//! beyond, it needs the sparse factorisation of the linear-solver seam, not built yet, and is
//! an error that says so.

use crate::error::Error;
use crate::linalg::DenseLu;
use nalgebra::DVector;

/// M⁻¹ of a constant mass matrix, ready to apply.
#[derive(Debug, Clone)]
pub enum MassInverse {
    /// The reciprocal diagonal entries.
    Diagonal(DVector<f64>),
    /// The LU factors of a coupled M (moderate n).
    Dense(Box<DenseLu>),
}

impl MassInverse {
    /// The largest n whose coupled mass matrix is factored densely.
    pub const MAX_DENSE: usize = 2000;

    /// M⁻¹ for M of size n given as (row, column, value) triplets (repeated places add up).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular
    /// or not positive on its diagonal, or coupled with n above [`MassInverse::MAX_DENSE`].
    pub fn new(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Self, Error> {
        let singular = |what: String| {
            Error::invalid(
                "structure",
                format!("the mass matrix ∂²L/∂q̇² is {what}: the Legendre map is not invertible"),
            )
        };
        if triplets.iter().all(|(i, j, _)| i == j) {
            let mut diagonal = DVector::<f64>::zeros(n);
            for (i, _, value) in triplets {
                diagonal[*i] += value;
            }
            if let Some(i) = diagonal.iter().position(|m| !(*m > 0.0 && m.is_finite())) {
                return Err(singular(format!(
                    "diagonal with entry {:e} at coordinate {i}",
                    diagonal[i]
                )));
            }
            return Ok(MassInverse::Diagonal(diagonal.map(|m| 1.0 / m)));
        }
        if n > Self::MAX_DENSE {
            return Err(Error::invalid(
                "structure",
                format!(
                    "a coupled (non-diagonal) constant mass matrix of {n} coordinates needs a \
                     sparse factorisation (at most {} are factored densely)",
                    Self::MAX_DENSE
                ),
            ));
        }
        let mut lu = DenseLu::new(n);
        for (i, j, value) in triplets {
            lu.matrix_mut()[(*i, *j)] += value;
        }
        lu.factor().map_err(|_| singular("singular".to_string()))?;
        Ok(MassInverse::Dense(Box::new(lu)))
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
            MassInverse::Dense(lu) => {
                out.copy_from(p);
                lu.solve_in_place(out);
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
