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
//! align. Each is a [`TangentObserver`] with an options struct (`Default`); observers compose
//! as tuples, so one run can compute several. Buffers are sized once in
//! [`TangentObserver::begin`] (N may be [`Dyn`](crate::Dyn)): observing a step allocates
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

use crate::dimension::Dimension;
use crate::error::{Error, require_positive};
use crate::linalg::compensated_add;
use crate::method::space::{State, TangentMap};
use crate::stepping::tangent::{TangentObserver, TangentStep};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator};
use std::ops::ControlFlow;

/// Deviation vectors w₁, …, w_k ∈ ℝ²ᴺ (the columns of a 2N × k matrix) and the buffers that
/// propagate them: the step's Jacobian as one 2N × 2N matrix and the product Φ W.
#[derive(Debug, Clone, Default)]
struct Deviations {
    vectors: DMatrix<f64>,
    product: DMatrix<f64>,
    jacobian: DMatrix<f64>,
}

impl Deviations {
    /// The buffers for `vectors` (2N × k).
    fn new(vectors: DMatrix<f64>) -> Self {
        let (rows, columns) = vectors.shape();
        Deviations {
            product: DMatrix::zeros(rows, columns),
            jacobian: DMatrix::zeros(rows, rows),
            vectors,
        }
    }

    /// W ← Φ W (no allocation).
    fn propagate<N: Dimension>(&mut self, tangent: &TangentMap<N>)
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
    fn column(&self, j: usize) -> &[f64] {
        let rows = self.vectors.nrows();
        &self.vectors.as_slice()[j * rows..(j + 1) * rows]
    }

    /// Scale every column to unit length, writing each column's norm into `norms`; `false`
    /// if a norm is zero or not finite.
    fn normalize(&mut self, norms: &mut [f64]) -> bool {
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
fn euclidean_norm(x: &[f64]) -> f64 {
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
fn orthonormalize(columns: &mut [f64], rows: usize, diagonal: &mut [f64]) -> bool {
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
fn default_deviations(rows: usize, count: usize) -> DMatrix<f64> {
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
fn initial_deviations(
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
fn require_interval(every: usize) -> Result<(), Error> {
    if every == 0 {
        return Err(Error::invalid(
            "every",
            "the renormalisation interval must be at least one step",
        ));
    }
    Ok(())
}

/// A threshold below which an indicator stops the run: positive and finite, or none.
fn require_threshold(name: &str, threshold: Option<f64>) -> Result<(), Error> {
    match threshold {
        Some(value) => require_positive(name, value),
        None => Ok(()),
    }
}

/// [`Error::NonFinite`] for deviation vectors that overflowed or vanished at a step.
fn lost<N: Dimension>(what: &str, step: &TangentStep<'_, N>) -> Error
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

/// The phase-space dimension 2N of a run from its initial state.
fn phase_dimension<N: Dimension>(state: &State<N>) -> usize
where
    DefaultAllocator: Allocator<N>,
{
    2 * state.q.len()
}

/// Options of [`LyapunovSpectrum`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SpectrumOptions {
    /// How many exponents, the largest first: 1 ..= 2N (`None`, the default: all 2N).
    pub count: Option<usize>,
    /// Re-orthonormalise the deviation vectors every `every` steps (and after the last
    /// step); at least 1 (the default). Between re-orthonormalisations the vectors grow like
    /// e^{λ₁ t} and align with the most expanding direction: keep e^{(λ₁ − λ_k) every·h}
    /// well below 1/ε ≈ 10¹⁶.
    pub every: usize,
}

impl Default for SpectrumOptions {
    fn default() -> Self {
        SpectrumOptions {
            count: None,
            every: 1,
        }
    }
}

impl SpectrumOptions {
    /// Compute the `count` largest exponents.
    pub fn with_count(mut self, count: usize) -> Self {
        self.count = Some(count);
        self
    }

    /// Re-orthonormalise every `every` steps.
    pub fn with_every(mut self, every: usize) -> Self {
        self.every = every;
        self
    }
}

/// The Lyapunov spectrum λ₁ ≥ λ₂ ≥ … ≥ λ_{2N} of the numerical flow, by the standard method
/// of Benettin et al. (1980): QR re-orthonormalisation of a propagated basis.
///
/// # Mathematics
///
/// Start from the orthonormal basis W₀ = I (its first `count` columns). Propagate by the
/// tangent maps, W ← Φ_k W, and every `every` steps (and after the last) factor
/// W = Q R (modified Gram–Schmidt, applied twice), keep Q as the new basis and accumulate
/// ln r_jj. At a re-orthonormalisation at time t,
///
/// ```text
/// λ_j(t) = (1 / (t − t₀)) Σ ln r_jj        (j = 1, …, count)
/// ```
///
/// which converges to the j-th Lyapunov exponent (Oseledec). The logs are summed with
/// compensation, so that Σ_j λ_j(t) = ln |det(Φ_{k−1} ⋯ Φ_0)| / (t − t₀) holds to round-off:
/// zero for a symplectic method. The exponents come in the basis' order, which is the order
/// of decreasing exponents once the flow has sorted the directions; for t → ∞ a Hamiltonian
/// flow's exponents pair as λ_j + λ_{2N+1−j} = 0, finite-time values up to O(1/t).
///
/// # References
///
/// Benettin, Galgani, Giorgilli, Strelcyn, Meccanica 15 (1980) 9–30; Skokos, Lect. Notes
/// Phys. 790 (2010) 63–135, §4.3 (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct LyapunovSpectrum {
    options: SpectrumOptions,
    deviations: Deviations,
    /// Σ ln r_jj and its compensation.
    logs: Vec<f64>,
    compensation: Vec<f64>,
    /// The last step's ln r_jj (and R's diagonal before the log).
    step_logs: Vec<f64>,
    exponents: Vec<f64>,
    t0: f64,
    time: f64,
    since: usize,
    orthonormalizations: usize,
}

impl LyapunovSpectrum {
    /// The observer, after checking the options that do not depend on the model (the
    /// count is checked against 2N when the run begins).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `every` for a zero interval, `count` for zero.
    pub fn new(options: SpectrumOptions) -> Result<Self, Error> {
        require_interval(options.every)?;
        if options.count == Some(0) {
            return Err(Error::invalid("count", "at least one exponent"));
        }
        Ok(LyapunovSpectrum {
            options,
            deviations: Deviations::default(),
            logs: Vec::new(),
            compensation: Vec::new(),
            step_logs: Vec::new(),
            exponents: Vec::new(),
            t0: 0.0,
            time: 0.0,
            since: 0,
            orthonormalizations: 0,
        })
    }

    /// The options.
    pub fn options(&self) -> &SpectrumOptions {
        &self.options
    }

    /// The running exponents λ_j(t) at the last re-orthonormalisation (empty before the
    /// run; zeros before the first re-orthonormalisation).
    pub fn exponents(&self) -> &[f64] {
        &self.exponents
    }

    /// Σ_j λ_j(t): ln |det| of the propagated flow over t − t₀ when all 2N exponents are
    /// computed.
    pub fn sum(&self) -> f64 {
        let total: f64 = self
            .logs
            .iter()
            .zip(&self.compensation)
            .map(|(s, c)| s - c)
            .sum();
        if self.time > 0.0 {
            total / self.time
        } else {
            0.0
        }
    }

    /// The time t − t₀ of the last re-orthonormalisation.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The number of re-orthonormalisations so far.
    pub fn orthonormalizations(&self) -> usize {
        self.orthonormalizations
    }
}

impl<N: Dimension> TangentObserver<N> for LyapunovSpectrum
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `count` beyond 2N.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let rows = phase_dimension(state);
        let count = self.options.count.unwrap_or(rows);
        if !(1..=rows).contains(&count) {
            return Err(Error::invalid(
                "count",
                format!("{count} exponents of a phase space of {rows} dimensions (1 ..= 2N)"),
            ));
        }
        self.deviations = Deviations::new(DMatrix::identity(rows, count));
        for buffer in [
            &mut self.logs,
            &mut self.compensation,
            &mut self.step_logs,
            &mut self.exponents,
        ] {
            buffer.clear();
            buffer.resize(count, 0.0);
        }
        (self.t0, self.time, self.since, self.orthonormalizations) = (t0, 0.0, 0, 0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        self.since += 1;
        if self.since < self.options.every && !step.last {
            return Ok(ControlFlow::Continue(()));
        }
        self.since = 0;
        let rows = self.deviations.vectors.nrows();
        if !orthonormalize(
            self.deviations.vectors.as_mut_slice(),
            rows,
            &mut self.step_logs,
        ) {
            return Err(lost("Lyapunov spectrum", step));
        }
        self.step_logs.iter_mut().for_each(|r| *r = r.ln());
        compensated_add(&mut self.logs, &mut self.compensation, &self.step_logs);
        self.time = step.t - self.t0;
        self.orthonormalizations += 1;
        for ((exponent, sum), compensation) in self
            .exponents
            .iter_mut()
            .zip(&self.logs)
            .zip(&self.compensation)
        {
            *exponent = (sum - compensation) / self.time;
        }
        Ok(ControlFlow::Continue(()))
    }
}

/// Options of [`MaximalLyapunov`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MaximalOptions {
    /// Renormalise the deviation vector every `every` steps (and after the last); at least 1
    /// (the default). Keep e^{λ₁ every·h} far from overflow.
    pub every: usize,
    /// The initial deviation vector (2N entries, q then y, scaled to unit length); `None`
    /// (the default): a fixed pseudo-random unit vector.
    pub deviation: Option<Vec<f64>>,
}

impl Default for MaximalOptions {
    fn default() -> Self {
        MaximalOptions {
            every: 1,
            deviation: None,
        }
    }
}

impl MaximalOptions {
    /// Renormalise every `every` steps.
    pub fn with_every(mut self, every: usize) -> Self {
        self.every = every;
        self
    }

    /// Start from the deviation vector `deviation`.
    pub fn with_deviation(mut self, deviation: Vec<f64>) -> Self {
        self.deviation = Some(deviation);
        self
    }
}

/// The maximal Lyapunov exponent alone: one deviation vector, renormalised every `every`
/// steps (Benettin et al. 1980; Skokos 2010, §4.2).
///
/// # Mathematics
///
/// w ← Φ_k w; at a renormalisation, accumulate ln ‖w‖ and set w ← w/‖w‖. At a
/// renormalisation at time t,
///
/// ```text
/// λ(t) = (1 / (t − t₀)) Σ ln ‖w‖  →  λ₁
/// ```
///
/// for almost every initial w. For a regular orbit λ(t) → 0 like ln t / t (the deviation
/// grows linearly); for a chaotic one it levels off at λ₁ > 0. One matrix–vector product per
/// step instead of [`LyapunovSpectrum`]'s 2N.
#[derive(Debug, Clone)]
pub struct MaximalLyapunov {
    options: MaximalOptions,
    deviations: Deviations,
    log: [f64; 1],
    compensation: [f64; 1],
    norm: [f64; 1],
    t0: f64,
    time: f64,
    since: usize,
}

impl MaximalLyapunov {
    /// The observer, after checking the options that do not depend on the model.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `every` for a zero interval.
    pub fn new(options: MaximalOptions) -> Result<Self, Error> {
        require_interval(options.every)?;
        Ok(MaximalLyapunov {
            options,
            deviations: Deviations::default(),
            log: [0.0],
            compensation: [0.0],
            norm: [0.0],
            t0: 0.0,
            time: 0.0,
            since: 0,
        })
    }

    /// The options.
    pub fn options(&self) -> &MaximalOptions {
        &self.options
    }

    /// The running exponent λ(t) at the last renormalisation (0 before the first).
    pub fn exponent(&self) -> f64 {
        if self.time > 0.0 {
            (self.log[0] - self.compensation[0]) / self.time
        } else {
            0.0
        }
    }

    /// The time t − t₀ of the last renormalisation.
    pub fn time(&self) -> f64 {
        self.time
    }
}

impl<N: Dimension> TangentObserver<N> for MaximalLyapunov
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviation` for a vector of the wrong length, zero or
    /// not finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let given = self.options.deviation.as_ref().map(std::slice::from_ref);
        let vectors = initial_deviations("deviation", given, phase_dimension(state), 1)?;
        self.deviations = Deviations::new(vectors);
        (self.log, self.compensation) = ([0.0], [0.0]);
        (self.t0, self.time, self.since) = (t0, 0.0, 0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        self.since += 1;
        if self.since < self.options.every && !step.last {
            return Ok(ControlFlow::Continue(()));
        }
        self.since = 0;
        if !self.deviations.normalize(&mut self.norm) {
            return Err(lost("maximal Lyapunov exponent", step));
        }
        compensated_add(&mut self.log, &mut self.compensation, &[self.norm[0].ln()]);
        self.time = step.t - self.t0;
        Ok(ControlFlow::Continue(()))
    }
}

/// Options of [`Megno`].
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct MegnoOptions {
    /// The initial deviation vector (2N entries, q then y); `None` (the default): a fixed
    /// pseudo-random unit vector.
    pub deviation: Option<Vec<f64>>,
}

impl MegnoOptions {
    /// Start from the deviation vector `deviation`.
    pub fn with_deviation(mut self, deviation: Vec<f64>) -> Self {
        self.deviation = Some(deviation);
        self
    }
}

/// MEGNO, the Mean Exponential Growth factor of Nearby Orbits Y(t), and its time average
/// ⟨Y⟩(t) (Cincotta & Simó 2000), in the discrete form of Cincotta, Giordano & Simó (2003)
/// for maps — here the method's one-step map.
///
/// # Mathematics
///
/// Continuous time: Y(t) = (2/t) ∫₀ᵗ (δ̇/δ) s ds, ⟨Y⟩(t) = (1/t) ∫₀ᵗ Y(s) ds, δ = ‖w‖. For the
/// steps t_k (measured from t₀) with δ_k = ‖w_k‖, w renormalised every step:
///
/// ```text
/// Y_n = (2 / t_n) Σ_{k=1}^{n} t_k ln(δ_k / δ_{k−1}),     ⟨Y⟩_n = (1 / t_n) Σ_{k=1}^{n} h_k Y_k
/// ```
///
/// (with t_k = k h the map form (2/n) Σ k ln(δ_k/δ_{k−1}) and (1/n) Σ Y_k). If δ grows like
/// e^{λt}, Y_n ≈ λ t_n and ⟨Y⟩_n ≈ λ t_n / 2: ⟨Y⟩ grows linearly with slope λ₁/2 on a
/// chaotic orbit. If δ grows linearly (a quasi-periodic orbit on a torus with shear),
/// Y_n, ⟨Y⟩_n → 2; on a stable periodic orbit (no shear) → 0. ⟨Y⟩ separates the two faster
/// than the Lyapunov exponent, whose regular-orbit limit is approached only like ln t / t.
/// The running log growth gives λ₁ as a by-product ([`Megno::lyapunov`]).
///
/// # References
///
/// Cincotta & Simó, A&AS 147 (2000) 205–228; Cincotta, Giordano & Simó, Physica D 182 (2003)
/// 151–178, §2 (see the [module](self) documentation).
#[derive(Debug, Clone)]
pub struct Megno {
    options: MegnoOptions,
    deviations: Deviations,
    norm: [f64; 1],
    /// Σ t_k ln(δ_k/δ_{k−1}), Σ h_k Y_k and Σ ln(δ_k/δ_{k−1}).
    sums: [f64; 3],
    compensation: [f64; 3],
    value: f64,
    mean: f64,
    t0: f64,
    time: f64,
}

impl Megno {
    /// The observer, after checking the options that do not depend on the model (none).
    ///
    /// # Errors
    /// None today; the deviation vector is checked when the run begins.
    pub fn new(options: MegnoOptions) -> Result<Self, Error> {
        Ok(Megno {
            options,
            deviations: Deviations::default(),
            norm: [0.0],
            sums: [0.0; 3],
            compensation: [0.0; 3],
            value: 0.0,
            mean: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &MegnoOptions {
        &self.options
    }

    /// Y(t) after the last step.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time average ⟨Y⟩(t) after the last step.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The maximal Lyapunov exponent estimate ln(δ(t)/δ(0)) / t of the same deviation vector.
    pub fn lyapunov(&self) -> f64 {
        if self.time > 0.0 {
            (self.sums[2] - self.compensation[2]) / self.time
        } else {
            0.0
        }
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }
}

impl<N: Dimension> TangentObserver<N> for Megno
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviation` for a vector of the wrong length, zero or
    /// not finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let given = self.options.deviation.as_ref().map(std::slice::from_ref);
        let vectors = initial_deviations("deviation", given, phase_dimension(state), 1)?;
        self.deviations = Deviations::new(vectors);
        (self.sums, self.compensation) = ([0.0; 3], [0.0; 3]);
        (self.value, self.mean, self.t0, self.time) = (0.0, 0.0, t0, 0.0);
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.norm) {
            return Err(lost("MEGNO", step));
        }
        let growth = self.norm[0].ln();
        let time = step.t - self.t0;
        compensated_add(
            &mut self.sums[..1],
            &mut self.compensation[..1],
            &[time * growth],
        );
        self.value = 2.0 * (self.sums[0] - self.compensation[0]) / time;
        compensated_add(
            &mut self.sums[1..],
            &mut self.compensation[1..],
            &[step.h * self.value, growth],
        );
        self.mean = (self.sums[1] - self.compensation[1]) / time;
        self.time = time;
        Ok(ControlFlow::Continue(()))
    }
}

/// Options of [`Sali`].
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct SaliOptions {
    /// The two initial deviation vectors (2N entries each, q then y); `None` (the
    /// default): two fixed pseudo-random orthonormal vectors (the first two of [`Gali`]'s).
    pub deviations: Option<[Vec<f64>; 2]>,
    /// Stop the run once SALI falls below this (positive, finite; the usual criterion of
    /// chaos is 10⁻⁸); `None` (the default): run to the horizon.
    pub stop_below: Option<f64>,
}

impl SaliOptions {
    /// Stop the run once SALI falls below `threshold`.
    pub fn with_stop_below(mut self, threshold: f64) -> Self {
        self.stop_below = Some(threshold);
        self
    }

    /// Start from the deviation vectors `deviations`.
    pub fn with_deviations(mut self, deviations: [Vec<f64>; 2]) -> Self {
        self.deviations = Some(deviations);
        self
    }
}

/// The Smaller Alignment Index of two deviation vectors (Skokos 2001).
///
/// # Mathematics
///
/// Propagate w₁, w₂ by the tangent maps and normalise them every step, ŵ = w/‖w‖:
///
/// ```text
/// SALI(t) = min(‖ŵ₁ + ŵ₂‖, ‖ŵ₁ − ŵ₂‖)  ∈ [0, √2]
/// ```
///
/// On a chaotic orbit both vectors align with the most unstable direction and
/// SALI ∝ e^{−(λ₁−λ₂) t} → 0 (to round-off, ~10⁻¹⁶); on a regular orbit of a system of 2
/// degrees of freedom they fall into the tangent space of the torus without aligning and SALI
/// fluctuates around a positive value.
///
/// # References
///
/// Skokos, J. Phys. A 34 (2001) 10029–10043; Skokos, Lect. Notes Phys. 790 (2010) §6.
#[derive(Debug, Clone)]
pub struct Sali {
    options: SaliOptions,
    deviations: Deviations,
    norms: [f64; 2],
    value: f64,
    t0: f64,
    time: f64,
}

impl Sali {
    /// The observer, after checking the threshold.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `stop_below` unless positive and finite.
    pub fn new(options: SaliOptions) -> Result<Self, Error> {
        require_threshold("stop_below", options.stop_below)?;
        Ok(Sali {
            options,
            deviations: Deviations::default(),
            norms: [0.0; 2],
            value: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &SaliOptions {
        &self.options
    }

    /// SALI after the last step (at the start of a run: of the initial vectors).
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// min(‖ŵ₁ + ŵ₂‖, ‖ŵ₁ − ŵ₂‖) of the current unit vectors.
    fn index(&self) -> f64 {
        let (a, b) = (self.deviations.column(0), self.deviations.column(1));
        let (mut plus, mut minus) = (0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            plus += (x + y) * (x + y);
            minus += (x - y) * (x - y);
        }
        plus.min(minus).sqrt()
    }
}

impl<N: Dimension> TangentObserver<N> for Sali
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `deviations` for vectors of the wrong length, zero or not
    /// finite.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let given = self.options.deviations.as_ref().map(|pair| pair.as_slice());
        let vectors = initial_deviations("deviations", given, phase_dimension(state), 2)?;
        self.deviations = Deviations::new(vectors);
        (self.t0, self.time) = (t0, 0.0);
        self.value = self.index();
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.norms) {
            return Err(lost("SALI", step));
        }
        self.value = self.index();
        self.time = step.t - self.t0;
        Ok(match self.options.stop_below {
            Some(threshold) if self.value < threshold => ControlFlow::Break(()),
            _ => ControlFlow::Continue(()),
        })
    }
}

/// Options of [`Gali`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct GaliOptions {
    /// The number k of deviation vectors, 1 ..= 2N (default 2; GALI₁ is always 1).
    pub k: usize,
    /// The k initial deviation vectors (2N entries each, q then y; linearly independent);
    /// `None` (the default): k fixed pseudo-random orthonormal vectors.
    pub deviations: Option<Vec<Vec<f64>>>,
    /// Stop the run once GALI_k falls below this (positive, finite); `None` (the default):
    /// run to the horizon.
    pub stop_below: Option<f64>,
}

impl Default for GaliOptions {
    fn default() -> Self {
        GaliOptions {
            k: 2,
            deviations: None,
            stop_below: None,
        }
    }
}

impl GaliOptions {
    /// GALI of order `k`.
    pub fn with_k(mut self, k: usize) -> Self {
        self.k = k;
        self
    }

    /// Stop the run once GALI_k falls below `threshold`.
    pub fn with_stop_below(mut self, threshold: f64) -> Self {
        self.stop_below = Some(threshold);
        self
    }

    /// Start from the deviation vectors `deviations`.
    pub fn with_deviations(mut self, deviations: Vec<Vec<f64>>) -> Self {
        self.deviations = Some(deviations);
        self
    }
}

/// The Generalized Alignment Index of order k (Skokos, Bountis & Antonopoulos 2007).
///
/// # Mathematics
///
/// Propagate k deviation vectors, normalise them every step, and take the volume of the
/// parallelepiped of the unit vectors:
///
/// ```text
/// GALI_k(t) = ‖ŵ₁ ∧ ŵ₂ ∧ … ∧ ŵ_k‖ = √det(ŴᵀŴ) = Π σ_i(Ŵ) = Π |r_ii|,   Ŵ = Q R
/// ```
///
/// computed from R's diagonal (modified Gram–Schmidt applied twice on a copy), which keeps
/// its relative accuracy where the Gram determinant 1 − cos²θ would cancel. On a chaotic
/// orbit GALI_k ∝ e^{−[(λ₁−λ₂) + (λ₁−λ₃) + … + (λ₁−λ_k)] t}; on a regular orbit on an
/// N-torus it stays O(1) for k ≤ N and decays like t^{−2(k−N)} for N < k ≤ 2N. With ŵ₁, ŵ₂ at
/// angle θ, GALI₂ = |sin θ| and SALI = 2 min(|sin θ/2|, |cos θ/2|), hence
/// SALI/√2 ≤ GALI₂ ≤ SALI (Skokos et al. 2007, eq. 9).
///
/// # References
///
/// Skokos, Bountis, Antonopoulos, Physica D 231 (2007) 30–54; Skokos, Lect. Notes Phys. 790
/// (2010) §6.
#[derive(Debug, Clone)]
pub struct Gali {
    options: GaliOptions,
    deviations: Deviations,
    /// A copy of the unit vectors for the QR, and its diagonal (the vectors' norms first).
    work: Vec<f64>,
    diagonal: Vec<f64>,
    value: f64,
    t0: f64,
    time: f64,
}

impl Gali {
    /// The observer, after checking the options that do not depend on the model (k is
    /// checked against 2N when the run begins).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `k` for zero, `stop_below` unless positive and finite.
    pub fn new(options: GaliOptions) -> Result<Self, Error> {
        if options.k == 0 {
            return Err(Error::invalid("k", "GALI_k takes k ≥ 1 deviation vectors"));
        }
        require_threshold("stop_below", options.stop_below)?;
        Ok(Gali {
            options,
            deviations: Deviations::default(),
            work: Vec::new(),
            diagonal: Vec::new(),
            value: 0.0,
            t0: 0.0,
            time: 0.0,
        })
    }

    /// The options.
    pub fn options(&self) -> &GaliOptions {
        &self.options
    }

    /// GALI_k after the last step (at the start of a run: of the initial vectors).
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The time t − t₀ after the last step.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Π r_ii of the QR factorisation of the current unit vectors (0 if they are dependent
    /// to round-off).
    fn volume(&mut self) -> f64 {
        self.work
            .copy_from_slice(self.deviations.vectors.as_slice());
        let rows = self.deviations.vectors.nrows();
        if orthonormalize(&mut self.work, rows, &mut self.diagonal) {
            self.diagonal.iter().product()
        } else {
            0.0
        }
    }
}

impl<N: Dimension> TangentObserver<N> for Gali
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// # Errors
    /// [`Error::InvalidParameter`] `k` beyond 2N; `deviations` for vectors of the wrong
    /// number or length, zero, not finite or linearly dependent.
    fn begin(&mut self, t0: f64, state: &State<N>) -> Result<(), Error> {
        let rows = phase_dimension(state);
        let k = self.options.k;
        if !(1..=rows).contains(&k) {
            return Err(Error::invalid(
                "k",
                format!("GALI_{k} in a phase space of {rows} dimensions (1 ..= 2N)"),
            ));
        }
        let vectors =
            initial_deviations("deviations", self.options.deviations.as_deref(), rows, k)?;
        self.work = vec![0.0; rows * k];
        self.diagonal = vec![0.0; k];
        self.deviations = Deviations::new(vectors);
        (self.t0, self.time) = (t0, 0.0);
        self.value = self.volume();
        if self.value == 0.0 {
            return Err(Error::invalid(
                "deviations",
                "the initial deviation vectors are linearly dependent",
            ));
        }
        Ok(())
    }

    fn observe(&mut self, step: &TangentStep<'_, N>) -> Result<ControlFlow<()>, Error> {
        self.deviations.propagate(step.tangent);
        if !self.deviations.normalize(&mut self.diagonal) {
            return Err(lost("GALI", step));
        }
        self.value = self.volume();
        self.time = step.t - self.t0;
        Ok(match self.options.stop_below {
            Some(threshold) if self.value < threshold => ControlFlow::Break(()),
            _ => ControlFlow::Continue(()),
        })
    }
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
