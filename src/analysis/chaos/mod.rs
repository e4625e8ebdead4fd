//! Chaos indicators from the exact tangent maps of a method: observers of
//! [`Integrator::try_run_tangent`](crate::Integrator::try_run_tangent).
//!
//! A run by the tangent map hands over, step by step, the Jacobian Φ_k of the method's
//! one-step map (y = p or q̇ by the method's coordinates):
//!
//! ```text
//! Φ_k = ∂(q_{k+1}, y_{k+1}) / ∂(q_k, y_k),   w_{k+1} = Φ_k w_k
//! ```
//!
//! so a deviation vector w ∈ ℝ²ᴺ follows the linearised *numerical* flow exactly (no
//! variational equations integrated beside the orbit, no finite differences of two orbits).
//! The indicators below propagate a few deviation vectors and read off how they grow and
//! align. Each is a [`TangentObserver`](crate::stepping::tangent::TangentObserver) with an options struct (`Default`); observers compose
//! as tuples, so one run can compute several. Buffers are sized once in
//! [`TangentObserver::begin`](crate::stepping::tangent::TangentObserver::begin) (N may be [`Dyn`](crate::Dyn)): observing a step allocates
//! nothing. Times are measured from the start t₀ of the run.
//!
//! | indicator | vectors | regular orbit | chaotic orbit |
//! | --- | --- | --- | --- |
//! | [`LyapunovSpectrum`] | 2N (or `count`) | all λᵢ → 0 like ln t / t | λ₁ > 0, pairs ±λ |
//! | [`MaximalLyapunov`] | 1 | λ → 0 like ln t / t | λ → λ₁ |
//! | [`Megno`] | 1 | ⟨Y⟩ → 2 | ⟨Y⟩ ≈ λ₁ t / 2 |
//! | [`Sali`] | 2 | O(1) (2 degrees of freedom) | ∝ e^{−(λ₁−λ₂) t} → 0 |
//! | [`Gali`] | k | O(1) or ∝ t^{−p} | ∝ e^{−[(λ₁−λ₂) + … + (λ₁−λ_k)] t} |
//!
//! For a symplectic method in (q, p) every Φ_k is symplectic: det Φ_k = 1, so the exponents
//! sum to zero to round-off at every time, and they pair as ±λ in the limit t → ∞ (with
//! energy conservation two of them vanish in 2 degrees of freedom). A method that is not
//! symplectic (explicit Euler, RK4, collocation) has exponents of the numerical flow that sum
//! to its average log-volume change, not to zero.
//!
//! # References
//!
//! - G. Benettin, L. Galgani, A. Giorgilli, J.-M. Strelcyn, *Lyapunov characteristic
//!   exponents for smooth dynamical systems and for Hamiltonian systems; a method for
//!   computing all of them*, Meccanica 15 (1980) 9–20 (theory) and 21–30 (numerical
//!   application).
//! - Ch. Skokos, *The Lyapunov characteristic exponents and their computation*, Lect. Notes
//!   Phys. 790 (2010) 63–135 (§4: the standard method; §6: SALI and GALI).
//! - P. M. Cincotta, C. Simó, *Simple tools to study global dynamics in non-axisymmetric
//!   galactic potentials – I*, Astron. Astrophys. Suppl. Ser. 147 (2000) 205–228 (MEGNO).
//! - P. M. Cincotta, C. M. Giordano, C. Simó, *Phase space structure of multi-dimensional
//!   systems by means of the mean exponential growth factor of nearby orbits*, Physica D 182
//!   (2003) 151–178 (MEGNO of maps, §2).
//! - Ch. Skokos, *Alignment indices: a new, simple method for determining the ordered or
//!   chaotic nature of orbits*, J. Phys. A 34 (2001) 10029–10043 (SALI).
//! - Ch. Skokos, T. C. Bountis, Ch. Antonopoulos, *Geometrical properties of local dynamics in
//!   Hamiltonian systems: the Generalized Alignment Index (GALI) method*, Physica D 231
//!   (2007) 30–54 (GALI; eq. 9: SALI/√2 ≤ GALI₂ ≤ SALI).

mod alignment;
mod lyapunov;
mod megno;

pub use alignment::{Gali, GaliOptions, Sali, SaliOptions};
pub use lyapunov::{LyapunovSpectrum, MaximalLyapunov, MaximalOptions, SpectrumOptions};
pub use megno::{Megno, MegnoOptions};

use crate::dimension::Dimension;
use crate::error::{Error, require_positive};
use crate::method::space::{State, TangentMap};
use crate::stepping::tangent::TangentStep;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator};

/// Deviation vectors w₁, …, w_k ∈ ℝ²ᴺ (the columns of a 2N × k matrix) and the buffers that
/// propagate them: the step's Jacobian as one 2N × 2N matrix and the product Φ W.
#[derive(Debug, Clone, Default)]
pub(super) struct Deviations {
    pub(super) vectors: DMatrix<f64>,
    pub(super) product: DMatrix<f64>,
    pub(super) jacobian: DMatrix<f64>,
}

impl Deviations {
    /// The buffers for `vectors` (2N × k).
    pub(super) fn new(vectors: DMatrix<f64>) -> Self {
        let (rows, columns) = vectors.shape();
        Deviations {
            product: DMatrix::zeros(rows, columns),
            jacobian: DMatrix::zeros(rows, rows),
            vectors,
        }
    }

    /// W ← Φ W (no allocation).
    pub(super) fn propagate<N: Dimension>(&mut self, tangent: &TangentMap<N>)
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let n = tangent.dimension();
        debug_assert_eq!(2 * n, self.jacobian.nrows());
        for j in 0..n {
            for i in 0..n {
                self.jacobian[(i, j)] = tangent.qq[(i, j)];
                self.jacobian[(i, n + j)] = tangent.qy[(i, j)];
                self.jacobian[(n + i, j)] = tangent.yq[(i, j)];
                self.jacobian[(n + i, n + j)] = tangent.yy[(i, j)];
            }
        }
        self.product.gemm(1.0, &self.jacobian, &self.vectors, 0.0);
        std::mem::swap(&mut self.vectors, &mut self.product);
    }

    /// Column `j`.
    pub(super) fn column(&self, j: usize) -> &[f64] {
        let rows = self.vectors.nrows();
        &self.vectors.as_slice()[j * rows..(j + 1) * rows]
    }

    /// Scale every column to unit length, writing each column's norm into `norms`; `false`
    /// if a norm is zero or not finite.
    pub(super) fn normalize(&mut self, norms: &mut [f64]) -> bool {
        let rows = self.vectors.nrows();
        let mut good = true;
        for (column, norm) in self
            .vectors
            .as_mut_slice()
            .chunks_exact_mut(rows)
            .zip(norms.iter_mut())
        {
            *norm = euclidean_norm(column);
            if !(norm.is_finite() && *norm > 0.0) {
                good = false;
                continue;
            }
            column.iter_mut().for_each(|x| *x /= *norm);
        }
        good
    }
}

/// ‖x‖₂ without overflow or underflow of the squares; NaN if an entry is not finite.
pub(super) fn euclidean_norm(x: &[f64]) -> f64 {
    if x.iter().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return 0.0;
    }
    scale
        * x.iter()
            .map(|v| (v / scale) * (v / scale))
            .sum::<f64>()
            .sqrt()
}

/// The QR factorisation of the 2N × k matrix in `columns` (column-major, `rows` per column)
/// by modified Gram–Schmidt applied twice ("twice is enough": orthogonal to round-off even
/// for ill-conditioned columns): the columns are replaced by Q's, and `diagonal` receives
/// R's diagonal r_jj > 0. `false` if a column is zero or not finite after projection.
pub(super) fn orthonormalize(columns: &mut [f64], rows: usize, diagonal: &mut [f64]) -> bool {
    for (j, r) in diagonal.iter_mut().enumerate() {
        let (before, rest) = columns.split_at_mut(j * rows);
        let column = &mut rest[..rows];
        for _ in 0..2 {
            for q in before.chunks_exact(rows) {
                let projection: f64 = q.iter().zip(column.iter()).map(|(a, b)| a * b).sum();
                column
                    .iter_mut()
                    .zip(q)
                    .for_each(|(x, a)| *x -= projection * a);
            }
        }
        *r = euclidean_norm(column);
        if !(r.is_finite() && *r > 0.0) {
            return false;
        }
        column.iter_mut().for_each(|x| *x /= *r);
    }
    true
}

/// `count` orthonormal vectors of ℝ^`rows`, the same for every run: pseudo-random entries
/// (SplitMix64 from a fixed seed) orthonormalised, so that no deviation vector starts along
/// a special direction of a model (an axis, the flow).
pub(super) fn default_deviations(rows: usize, count: usize) -> DMatrix<f64> {
    let mut seed: u64 = 0x5eed_c4a0_5eed_c4a0;
    let mut next = || {
        seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut vectors = DMatrix::from_fn(rows, count, |_, _| next());
    let mut diagonal = vec![0.0; count];
    let independent = orthonormalize(vectors.as_mut_slice(), rows, &mut diagonal);
    debug_assert!(independent, "pseudo-random vectors are independent");
    vectors
}

/// The deviation vectors of a run of phase-space dimension `rows` = 2N: the user's (each
/// checked: `rows` finite entries, not zero; scaled to unit length) or `count` default ones
/// ([`default_deviations`]).
pub(super) fn initial_deviations(
    name: &str,
    given: Option<&[Vec<f64>]>,
    rows: usize,
    count: usize,
) -> Result<DMatrix<f64>, Error> {
    let Some(given) = given else {
        return Ok(default_deviations(rows, count));
    };
    if given.len() != count {
        return Err(Error::invalid(
            name,
            format!("{} deviation vectors given, {count} needed", given.len()),
        ));
    }
    let mut vectors = DMatrix::zeros(rows, count);
    for (j, vector) in given.iter().enumerate() {
        if vector.len() != rows {
            return Err(Error::invalid(
                name,
                format!(
                    "deviation vector {j} has {} entries, the phase space {rows} dimensions \
                     (q then y, the method's coordinates)",
                    vector.len()
                ),
            ));
        }
        let norm = euclidean_norm(vector);
        if !(norm.is_finite() && norm > 0.0) {
            return Err(Error::invalid(
                name,
                format!("deviation vector {j} is zero or not finite: {vector:?}"),
            ));
        }
        vectors
            .column_mut(j)
            .iter_mut()
            .zip(vector)
            .for_each(|(x, v)| *x = v / norm);
    }
    Ok(vectors)
}

/// [`Error::InvalidParameter`] `every` unless it is at least 1.
pub(super) fn require_interval(every: usize) -> Result<(), Error> {
    if every == 0 {
        return Err(Error::invalid(
            "every",
            "the renormalisation interval must be at least one step",
        ));
    }
    Ok(())
}

/// A threshold below which an indicator stops the run: positive and finite, or none.
pub(super) fn require_threshold(name: &str, threshold: Option<f64>) -> Result<(), Error> {
    match threshold {
        Some(value) => require_positive(name, value),
        None => Ok(()),
    }
}

/// [`Error::NonFinite`] for deviation vectors that overflowed or vanished at a step.
pub(super) fn lost<N: Dimension>(what: &str, step: &TangentStep<'_, N>) -> Error
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    Error::NonFinite {
        what: format!(
            "{what}: a deviation vector overflowed, vanished or the tangent map is not finite \
             (renormalise more often)"
        ),
        step: step.step - 1,
        t: step.t - step.h,
    }
}

/// A compensated sum of logarithms (`sum` − `compensation`) per unit time `time`: an
/// exponent's running estimate, 0 before any time has passed.
pub(super) fn rate(sum: f64, compensation: f64, time: f64) -> f64 {
    if time > 0.0 {
        (sum - compensation) / time
    } else {
        0.0
    }
}

/// The one deviation vector of an indicator on the run of `state`: the user's `deviation`
/// (checked and normalised) or the default one.
pub(super) fn one_deviation<N: Dimension>(
    deviation: Option<&Vec<f64>>,
    state: &State<N>,
) -> Result<Deviations, Error>
where
    DefaultAllocator: Allocator<N>,
{
    let given = deviation.map(std::slice::from_ref);
    let vectors = initial_deviations("deviation", given, phase_dimension(state), 1)?;
    Ok(Deviations::new(vectors))
}

/// The phase-space dimension 2N of a run from its initial state.
pub(super) fn phase_dimension<N: Dimension>(state: &State<N>) -> usize
where
    DefaultAllocator: Allocator<N>,
{
    2 * state.q.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_deviations_are_orthonormal_for_every_size() {
        for rows in 1..=40 {
            for count in 1..=rows {
                let w = default_deviations(rows, count);
                let gram = w.transpose() * &w;
                let defect = (gram - DMatrix::<f64>::identity(count, count)).amax();
                assert!(defect < 1e-13, "{rows} × {count}: {defect:e}");
            }
        }
    }

    #[test]
    fn twice_modified_gram_schmidt_keeps_orthogonality_for_nearly_parallel_columns() {
        // Columns 1 and 1 + 1e-12 e₂: R's second diagonal entry is 1e-12/√… to full relative
        // accuracy.
        let mut columns = vec![1.0, 0.0, 0.0, 1.0, 1e-12, 0.0];
        let mut diagonal = [0.0; 2];
        assert!(orthonormalize(&mut columns, 3, &mut diagonal));
        assert!((diagonal[0] - 1.0).abs() < 1e-15);
        assert!((diagonal[1] / 1e-12 - 1.0).abs() < 1e-3, "{}", diagonal[1]);
        let dot: f64 = columns[..3]
            .iter()
            .zip(&columns[3..])
            .map(|(a, b)| a * b)
            .sum();
        assert!(dot.abs() < 1e-15, "{dot:e}");
    }

    #[test]
    fn the_norm_neither_overflows_nor_underflows() {
        assert_eq!(euclidean_norm(&[3e300, 4e300]), 5e300);
        assert!((euclidean_norm(&[3e-300, 4e-300]) / 5e-300 - 1.0).abs() < 1e-15);
        assert!(euclidean_norm(&[1.0, f64::NAN]).is_nan());
        assert_eq!(euclidean_norm(&[0.0, 0.0]), 0.0);
    }
}
