//! Starting values for the Newton iteration of the spectral methods.
//!
//! As in Hairer's GNI codes, step k + 1 starts from the polynomial of step k evaluated at the
//! new step's nodes: on the reference interval of step k the new nodes sit at
//! 1 + ρ (x_ν + 1), with ρ = h_{k+1}/h_k (x_ν + 2 for a constant step), so the guess is a
//! matrix l_j(1 + ρ (x_ν + 1)) applied to the previous node values; the matrix is rebuilt
//! only when ρ changes. The first step (or the first after [`StartingValues::invalidate`],
//! when a step does not continue the previous one) starts from the Taylor polynomial
//! q_k + q̇ (t − t_k) + q̈ (t − t_k)²/2.
//!
//! Node values are stored as offsets qᵛ − q_k (ν = 1, …, s; q⁰ − q_k = 0 is implicit).

use crate::dimension::Dimension;
use crate::spectral::Scratch;
use crate::spectral::basis::LagrangeBasis;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector, U1};

/// Extrapolation table and the previous step's node offsets.
#[derive(Debug, Clone)]
pub(crate) struct StartingValues {
    /// The interpolation basis on the CGL nodes x_ν of [−1, 1].
    basis: LagrangeBasis,
    /// X_νj = l_j(1 + ρ (x_ν + 1)) − δ_js, ν, j = 1..s, row-major: by Σ_j l_j = 1 the new
    /// offsets are Σ_j X_νj Z_j from the previous offsets Z_j.
    extrapolation: Vec<f64>,
    /// The step ratio ρ the table was built for.
    ratio: f64,
    /// Node offsets of the previous step (ν = 1..s, stacked).
    previous: DVector<f64>,
    /// The dimension N of the configuration space (numbers per node), as given to
    /// [`StartingValues::new`]; a fixed dimension type overrides it.
    dimension: usize,
    /// Size of the previous step; `None` when there is no previous step to continue.
    previous_step: Option<f64>,
}

impl StartingValues {
    pub(crate) fn new(basis: &LagrangeBasis, dimension: usize) -> Self {
        let s = basis.len() - 1;
        let mut start = StartingValues {
            basis: basis.clone(),
            extrapolation: vec![0.0; s * s],
            ratio: f64::NAN,
            previous: DVector::zeros(s * dimension),
            dimension,
            previous_step: None,
        };
        start.build(1.0);
        start
    }

    /// Rebuild the extrapolation table for the step ratio ρ (no allocation).
    fn build(&mut self, ratio: f64) {
        let s = self.basis.len() - 1;
        let mut values = [0.0; crate::spectral::MAX_POINTS];
        for nu in 1..=s {
            let x = 1.0 + ratio * (self.basis.nodes()[nu] + 1.0);
            self.basis.values_into(x, &mut values[..=s]);
            let row = &mut self.extrapolation[(nu - 1) * s..nu * s];
            for (j, (target, value)) in row.iter_mut().zip(&values[1..=s]).enumerate() {
                *target = value - f64::from(j + 1 == s);
            }
        }
        self.ratio = ratio;
    }

    /// Forget the previous step: the next step does not continue it.
    pub(crate) fn invalidate(&mut self) {
        self.previous_step = None;
    }

    /// Prepare to extrapolate into a step of size `h`; false if there is no previous step.
    pub(crate) fn prepare(&mut self, h: f64) -> bool {
        let Some(previous) = self.previous_step else {
            return false;
        };
        let ratio = h / previous;
        if ratio != self.ratio {
            self.build(ratio);
        }
        true
    }

    /// The numbers per node for the dimension type `N`: its size if fixed, else the
    /// dimension given to [`StartingValues::new`].
    #[inline]
    fn width<N: Dimension>(&self) -> usize {
        N::try_to_usize().unwrap_or(self.dimension)
    }

    /// Remember the converged offsets of a step of size `h`.
    pub(crate) fn remember(&mut self, offsets: &DVector<f64>, h: f64) {
        self.previous.copy_from(offsets);
        self.previous_step = Some(h);
    }

    /// Remember a step of size `h` whose offsets the caller writes later, through
    /// [`StartingValues::previous_mut`], before anything reads them (a method that can
    /// start the next step without them).
    pub(crate) fn remember_size(&mut self, h: f64) {
        self.previous_step = Some(h);
    }

    /// The remembered offsets, to be written (see [`StartingValues::remember_size`]).
    pub(crate) fn previous_mut(&mut self) -> &mut [f64] {
        self.previous.as_mut_slice()
    }

    /// Offsets from the previous step's polynomial, relative to the new start q_{k+1}, for
    /// the step size last given to [`StartingValues::prepare`].
    /// `N` is the dimension type of the configuration space (a fixed size is known to the
    /// compiler).
    pub(crate) fn extrapolate<N: Dimension>(&self, offsets: &mut DVector<f64>) {
        let s = self.basis.len() - 1;
        let width = self.width::<N>();
        let previous = self.previous.as_slice();
        for (nu, target) in offsets.as_mut_slice().chunks_exact_mut(width).enumerate() {
            let row = &self.extrapolation[nu * s..(nu + 1) * s];
            target.fill(0.0);
            for (x, node) in row.iter().zip(previous.chunks_exact(width)) {
                for (t, z) in target.iter_mut().zip(node) {
                    *t += x * z;
                }
            }
        }
    }

    /// The extrapolation table X (s × s, row-major) for the step ratio last given to
    /// [`StartingValues::prepare`], and that ratio.
    pub(crate) fn table(&self) -> (&[f64], f64) {
        (&self.extrapolation, self.ratio)
    }

    /// Node offsets of the remembered step, if any.
    /// The number of points of the basis (the polynomial's degree + 1).
    pub(crate) fn points(&self) -> usize {
        self.basis.len()
    }

    pub(crate) fn last_offsets(&self) -> Option<&[f64]> {
        self.previous_step.map(|_| self.previous.as_slice())
    }

    /// The remembered step's polynomial at τ ∈ [−1, 1] (dense output): the offset
    /// Σ_j l_j(τ) Z_j from the step's start and its τ-derivative Σ_j l̇_j(τ) Z_j, with the
    /// basis values l_j(τ) written to `values` (length s + 1). `None` without a remembered
    /// step.
    pub(crate) fn last_step<N: Dimension>(
        &self,
        tau: f64,
        values: &mut [f64],
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        self.previous_step?;
        let width = self.width::<N>();
        let dimension = N::from_usize(width);
        let previous = self.previous.as_slice();
        Some(self.polynomial(tau, values, |j| {
            OVector::from_column_slice_generic(dimension, U1, &previous[j * width..(j + 1) * width])
        }))
    }

    /// The polynomial with node offsets `node(j)` (j = 0..s − 1 for the nodes 1..s) at
    /// τ ∈ [−1, 1]: Σ_j l_j(τ) Z_j and Σ_j l̇_j(τ) Z_j, with the basis values l_j(τ) written to
    /// `values` (length s + 1). The vectors are of the dimension type `N` (for a run-time
    /// size, the dimension given to [`StartingValues::new`]).
    pub(crate) fn polynomial<N: Dimension>(
        &self,
        tau: f64,
        values: &mut [f64],
        node: impl Fn(usize) -> OVector<f64, N>,
    ) -> (OVector<f64, N>, OVector<f64, N>)
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let points = self.basis.len();
        let mut derivatives = Scratch::zeros(points);
        self.basis.values_into(tau, &mut values[..points]);
        self.basis.derivatives_into(tau, &mut derivatives[..points]);
        let dimension = N::from_usize(self.width::<N>());
        let mut offset = OVector::zeros_generic(dimension, U1);
        let mut rate = OVector::zeros_generic(dimension, U1);
        for j in 0..points - 1 {
            let node = node(j);
            offset += &node * values[j + 1];
            rate += &node * derivatives[j + 1];
        }
        (offset, rate)
    }

    /// Offsets of the Taylor polynomial with velocity `v` and acceleration `a`.
    pub(crate) fn taylor<N: Dimension>(
        &self,
        h: f64,
        v: &OVector<f64, N>,
        a: &OVector<f64, N>,
        offsets: &mut DVector<f64>,
    ) where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let width = v.len();
        for (nu, x) in self.basis.nodes().iter().enumerate().skip(1) {
            let dt = 0.5 * h * (x + 1.0);
            let half_square = 0.5 * dt * dt;
            let target = &mut offsets.as_mut_slice()[(nu - 1) * width..nu * width];
            for ((guess, v), a) in target.iter_mut().zip(v.as_slice()).zip(a.as_slice()) {
                *guess = v * dt + a * half_square;
            }
        }
    }
}
