//! What a sweep measures: one point of a work–precision curve, a method that measured none,
//! and the outcome of a whole sweep.

use serde::Serialize;

/// One point of a work–precision curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// The method configuration, e.g. `svi:7/6`.
    pub method: String,
    /// Steps (fixed-step methods) or tolerance (adaptive ones).
    pub parameter: f64,
    /// Step size, for fixed-step methods.
    pub h: Option<f64>,
    /// Steps taken (accepted and rejected, for adaptive methods).
    pub steps: usize,
    /// Position error at the horizon against the exact solution (or, for a model without
    /// one, a resolved reference run): Euclidean, or in the one coordinate of
    /// [`BenchOptions::coordinate`](crate::bench::options::BenchOptions::coordinate).
    pub final_error: f64,
    /// Largest |E − E₀| over the steps.
    pub energy_error_max: f64,
    /// Largest Noether-momentum error over the steps (`None` without symmetries).
    pub momentum_error_max: Option<f64>,
    /// Derivative (force / right-hand side) evaluations.
    pub evaluations: usize,
    /// Nonlinear iterations.
    pub iterations: usize,
    /// Median wall time of one run without observers, in seconds.
    pub seconds: f64,
}

/// A method whose sweep failed (no point of it measured): the other methods' records are
/// kept, and this is reported beside them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodFailure {
    /// The method configuration, e.g. `svi:6`.
    pub method: String,
    /// The error kind, as in `svi run --json`.
    pub kind: &'static str,
    /// The error message.
    pub message: String,
}

/// The outcome of a sweep: the measured points of every method, and the methods that failed.
#[derive(Debug, Default)]
pub struct Sweeps {
    /// The measured points, method by method.
    pub records: Vec<Record>,
    /// The methods none of whose points could be measured.
    pub failures: Vec<MethodFailure>,
}
