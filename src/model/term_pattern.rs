//! The sparsity pattern P of a sum of local terms' Hessian blocks, L = Σₑ ℓₑ(q_{I(e)}, q̇_{I(e)}):
//! P is the union of the terms' index sets I(e) × I(e), the same for ∂²L/∂q², ∂²L/∂q∂q̇ and
//! ∂²L/∂q̇², fixed once per run. Each term knows the slots of its K² pairs in P's
//! compressed-column storage, so a Newton matrix built from the blocks is assembled term by
//! term in O(K² · terms), without a search ([`crate::model::legendre`], and the stage
//! equations of the spectral and classic variational integrators).

use crate::dimension::Dyn;
use crate::error::{Error, StepFailure};
use crate::linalg::sparse::Pattern;
use crate::model::TermSum;

/// The widest term a sparse Newton iteration takes (its local buffers are this long).
pub(crate) const MAX_WIDTH: usize = 16;

/// The failure of a step whose model's terms read coordinates beyond its dimension (which
/// [`TermSum::check_indices`] refuses before a run).
pub(crate) const PATTERN_MISMATCH: StepFailure = StepFailure::Unsupported {
    option: "model",
    reason: "the pattern of its terms' indices does not fit its dimension",
};

/// Refuse terms wider than [`MAX_WIDTH`].
///
/// # Errors
/// [`Error::InvalidParameter`] `width`.
pub(crate) fn check_width(width: usize) -> Result<(), Error> {
    if width > MAX_WIDTH {
        return Err(Error::invalid(
            "width",
            format!("terms {width} coordinates wide: sparse Newton takes at most {MAX_WIDTH}"),
        ));
    }
    Ok(())
}

/// The pattern P of L's Hessian blocks and, per term, its index set and the slots of its K²
/// pairs.
#[derive(Debug, Clone)]
pub(crate) struct TermPattern {
    /// P, n × n.
    pub(crate) pattern: Pattern,
    /// The slot in P of term e's pair (row slot a, column slot b), at e·K² + a + K·b.
    slots: Vec<usize>,
    /// Term e's index set, at e·K .. (e + 1)·K.
    indices: Vec<usize>,
    width: usize,
}

impl TermPattern {
    /// The pattern of `terms` on `n` coordinates.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `width` for terms wider than [`MAX_WIDTH`], `pattern` for
    /// an index out of range.
    pub(crate) fn new(terms: &dyn TermSum<Dyn>, n: usize) -> Result<Self, Error> {
        let width = terms.width();
        check_width(width)?;
        let count = terms.term_count();
        let mut indices = vec![0; count * width];
        let mut entries = Vec::with_capacity(count * width * width);
        for (e, set) in indices.chunks_exact_mut(width.max(1)).enumerate() {
            terms.term_indices(e, set);
            for &col in set.iter() {
                for &row in set.iter() {
                    entries.push((row, col));
                }
            }
        }
        let pattern = Pattern::new(n, &entries)?;
        let slots = entries
            .iter()
            .map(|&(row, col)| pattern.slot(row, col).unwrap_or(usize::MAX))
            .collect();
        Ok(TermPattern {
            pattern,
            slots,
            indices,
            width,
        })
    }

    /// K, the width of a term.
    pub(crate) fn width(&self) -> usize {
        self.width
    }

    /// The number of terms.
    pub(crate) fn term_count(&self) -> usize {
        self.indices.len().checked_div(self.width).unwrap_or(0)
    }

    /// Term e's index set I(e).
    #[inline]
    pub(crate) fn indices(&self, e: usize) -> &[usize] {
        &self.indices[e * self.width..(e + 1) * self.width]
    }

    /// The slot in P of term e's pair (row slot a, column slot b).
    #[inline]
    pub(crate) fn slot(&self, e: usize, a: usize, b: usize) -> usize {
        let k = self.width;
        self.slots[e * k * k + a + k * b]
    }

    /// Term e's coordinates and velocities, gathered into the first K entries of `ql`, `vl`.
    #[inline]
    pub(crate) fn gather(
        &self,
        e: usize,
        q: &[f64],
        v: &[f64],
        ql: &mut [f64; MAX_WIDTH],
        vl: &mut [f64; MAX_WIDTH],
    ) {
        for (a, &i) in self.indices(e).iter().enumerate() {
            ql[a] = q[i];
            vl[a] = v[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_wider_than_sparse_newton_takes_are_an_error_naming_the_width() {
        assert!(check_width(MAX_WIDTH).is_ok());
        let error = check_width(MAX_WIDTH + 1).unwrap_err().to_string();
        assert!(
            error.contains("width") && error.contains("17") && error.contains("16"),
            "{error}"
        );
    }
}
