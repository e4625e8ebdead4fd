//! The inverse of a constant mass matrix M = ∂²L/∂q̇² on runtime-sized ℝⁿ, assembled from
//! the terms' blocks once per run and applied as q̇ = M⁻¹p in O(n).
//!
//! A diagonal M (particles with their own masses: chains, lattices) is inverted entry by
//! entry. A coupled M (a consistent finite-element mass matrix, bodies sharing
//! coordinates) is factored once by faer's sparse LU on the pattern of the terms' blocks
//! (`linalg::sparse`), so any n whose factors fit in memory runs.

use crate::error::Error;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::local::{LocalLagrangian, TermWidth};
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
    /// M⁻¹ of the model's mass matrix ∂²L/∂q̇² at (t, q), q̇ = 0, assembled term by term
    /// without a list of all entries: the diagonal is summed in place and only the entries
    /// off it are kept (none for particles with their own masses).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular or not positive on its
    /// diagonal.
    pub fn of_model<L: LocalLagrangian>(
        model: &L,
        t: f64,
        q: &DVector<f64>,
    ) -> Result<Self, Error> {
        let n = q.len();
        let zero = DVector::zeros(n);
        let mut diagonal = DVector::<f64>::zeros(n);
        let mut coupled = Vec::new();
        let mut block = Vec::new();
        for e in 0..model.term_count() {
            block.clear();
            L::Width::mass_triplets(model, e, t, q, &zero, &mut block);
            for &(i, j, value) in &block {
                if i == j {
                    diagonal[i] += value;
                } else {
                    coupled.push((i, j, value));
                }
            }
        }
        Self::from_parts(diagonal, coupled)
    }

    /// M⁻¹ from M's diagonal and its entries off the diagonal (repeated places add up).
    fn from_parts(
        diagonal: DVector<f64>,
        coupled: Vec<(usize, usize, f64)>,
    ) -> Result<Self, Error> {
        let singular = |what: String| {
            Error::invalid(
                "structure",
                format!("the mass matrix ∂²L/∂q̇² is {what}: the Legendre map is not invertible"),
            )
        };
        if let Some(i) = diagonal.iter().position(|m| !(*m > 0.0 && m.is_finite())) {
            return Err(singular(format!(
                "not positive on its diagonal: entry {:e} at coordinate {i}",
                diagonal[i]
            )));
        }
        if coupled.is_empty() {
            return Ok(MassInverse::Diagonal(diagonal.map(|m| 1.0 / m)));
        }
        let n = diagonal.len();
        let places: Vec<(usize, usize)> = (0..n)
            .map(|i| (i, i))
            .chain(coupled.iter().map(|&(i, j, _)| (i, j)))
            .collect();
        let pattern = Pattern::new(n, &places)?;
        let mut values = vec![0.0; pattern.len()];
        let entries = diagonal
            .iter()
            .enumerate()
            .map(|(i, &m)| (i, i, m))
            .chain(coupled.iter().copied());
        for (i, j, value) in entries {
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
