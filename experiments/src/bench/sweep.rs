//! The course of a sweep, whatever the method: its horizon checked, the per-run time (median
//! of batches), the step counts from the fewest that resolve the solution up to the target,
//! the points asked for instead, when a sweep ends, the report of its points, and the
//! methods' outcomes.

use indicatif::ProgressBar;
use std::fmt;
use std::time::Instant;

use crate::bench::files::Float;
use crate::bench::options::BenchOptions;
use crate::bench::record::{MethodFailure, Record, Sweeps};
use crate::report::csv;
use crate::scene::SceneError;
use crate::scene::limits::MAX_STEPS;

/// The methods' outcomes of a bench as they come: the records, the failures, and the first
/// failure's error.
#[derive(Default)]
pub(super) struct Outcomes {
    sweeps: Sweeps,
    first_error: Option<SceneError>,
}

impl Outcomes {
    /// Add the outcome of the method `label`: its records, or its failure (a warning naming
    /// it, and a [`MethodFailure`]); bad input ends the bench.
    pub(super) fn add(
        &mut self,
        label: &str,
        swept: Result<Vec<Record>, SceneError>,
        report: Report<'_>,
    ) -> Result<(), SceneError> {
        match swept {
            Ok(records) => self.sweeps.records.extend(records),
            Err(error) if error.is_bad_input() => return Err(error),
            Err(error) => {
                report.warn(&format!("{label} measured no point: {error}"));
                self.sweeps.failures.push(MethodFailure {
                    method: label.to_string(),
                    kind: crate::run::outcome::error_report(&error).kind,
                    message: error.to_string(),
                });
                self.first_error.get_or_insert(error);
            }
        }
        Ok(())
    }

    /// The sweeps, or the first failure when no method measured any point.
    pub(super) fn finish(self) -> Result<Sweeps, SceneError> {
        match self.first_error {
            Some(error) if self.sweeps.records.is_empty() => Err(error),
            _ => Ok(self.sweeps),
        }
    }
}

/// Check the horizon of a sweep before anything is run: a span svi can step through
/// ([`svi::stepping::grid::check_span`]) that needs at most [`MAX_STEPS`] steps of the
/// model's default step `h` (the most a sweep takes). An error names `--t-end`.
pub(super) fn check_horizon(t0: f64, t_end: f64, h: f64) -> Result<(), SceneError> {
    const OPTION: &str = "--t-end (run.t_end)";
    svi::stepping::grid::check_span(t0, t_end).map_err(|error| match error {
        svi::Error::InvalidParameter { name, reason } if name == "t_end" => {
            SceneError::InvalidOption {
                option: OPTION,
                reason,
            }
        }
        other => other.into(),
    })?;
    let longest = h * MAX_STEPS as f64;
    if t_end - t0 > longest {
        return Err(SceneError::InvalidOption {
            option: OPTION,
            reason: format!(
                "the span from {} to {} needs more than {MAX_STEPS} steps of the model's step {} \
                 (the most a sweep takes): at most {}",
                csv::Float(t0),
                csv::Float(t_end),
                csv::Float(h),
                csv::Float(t0 + longest)
            ),
        });
    }
    Ok(())
}

/// Median per-run time of `run` (see the module docs).
pub(super) fn median_seconds(mut run: impl FnMut(), options: &BenchOptions) -> f64 {
    let start = Instant::now();
    run();
    let single = start.elapsed().as_secs_f64();
    let batches = if single > 1.0 {
        3
    } else {
        options.batches.max(1)
    };
    let mut times: Vec<f64> = (0..batches)
        .map(|_| {
            let start = Instant::now();
            let mut count = 0u32;
            loop {
                run();
                count += 1;
                if start.elapsed().as_secs_f64() >= options.min_batch {
                    break;
                }
            }
            start.elapsed().as_secs_f64() / f64::from(count)
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Tracks when a sweep has stalled at round-off.
#[derive(Default)]
pub(super) struct Stall {
    best: f64,
    count: usize,
}

impl Stall {
    /// Whether a sweep ends after `record`: its error is below the target, its run took
    /// longer than `max_run`, or the error has stalled.
    pub(super) fn ends_after(&mut self, record: &Record, options: &BenchOptions) -> bool {
        record.final_error < options.target()
            || self.stalled(record.final_error)
            || record.seconds > options.max_run()
    }

    /// Record an error; `true` once three points in a row failed to halve the best error
    /// below 1e-7.
    fn stalled(&mut self, error: f64) -> bool {
        if self.count == 0 && self.best == 0.0 {
            self.best = f64::INFINITY;
        }
        if error < 1e-7 && error > 0.5 * self.best {
            self.count += 1;
        } else {
            self.count = 0;
        }
        self.best = self.best.min(error);
        self.count >= 3
    }
}

/// Where a sweep reports its points.
#[derive(Clone, Copy)]
pub(super) struct Report<'a> {
    pub(super) verbose: bool,
    pub(super) progress: &'a ProgressBar,
}

impl Report<'_> {
    /// Print a remark (verbose only), above the progress bar.
    pub(super) fn note(&self, text: &str) {
        if self.verbose {
            self.progress.suspend(|| eprintln!("{text}"));
        }
    }

    /// Print a warning (always), above the progress bar.
    pub(super) fn warn(&self, text: &str) {
        self.progress.suspend(|| eprintln!("warning: {text}"));
    }

    /// Print a measured point (verbose only), above the progress bar.
    pub(super) fn record(&self, record: &Record) {
        if self.verbose {
            self.progress.suspend(|| {
                eprintln!(
                    "{:>10} {:>12} error {:.3e} energy {:.3e} evaluations {:>10} time {:.4e} s",
                    record.method,
                    Float(record.parameter),
                    record.final_error,
                    record.energy_error_max,
                    record.evaluations,
                    record.seconds
                )
            });
        }
    }
}

/// Sweep the fixed-step method `label` of order `order` over step counts (see the module
/// docs): the given `--steps` ([`measure_requested`]), or from 8 steps doubled until
/// `final_error` is below 3·10⁻², bisected back to the fewest such steps, then grown by
/// 10^(1/(2·order)) per point until the sweep ends ([`Stall::ends_after`]); `measure` makes
/// the record of a step count (passed as `f64`).
pub(super) fn sweep_steps<E: Into<SceneError> + fmt::Display>(
    label: &str,
    order: f64,
    options: &BenchOptions,
    report: Report<'_>,
    records: &mut Vec<Record>,
    final_error: impl Fn(usize) -> Result<f64, E>,
    measure: impl Fn(f64) -> Result<Record, E>,
) -> Result<(), SceneError> {
    if !options.steps.is_empty() {
        let steps: Vec<f64> = options.steps.iter().map(|&steps| steps as f64).collect();
        return measure_requested(label, &steps, "steps", measure, report, records);
    }
    let mut steps = fewest_resolved_steps(|steps| matches!(final_error(steps), Ok(e) if e <= 3e-2));
    // Two points per halving of the error exponent: 10^(1/(2r)) between step counts.
    let factor = 10f64.powf(0.5 / order);
    let mut stall = Stall::default();
    let mut failures = 0;
    while steps < MAX_STEPS {
        let record = match measure(steps as f64) {
            Ok(record) => record,
            Err(_) if failures < 3 => {
                failures += 1;
                steps = (steps as f64 * factor).ceil() as usize;
                continue;
            }
            Err(error) => return Err(error.into()),
        };
        report.record(&record);
        let done = stall.ends_after(&record, options);
        records.push(record);
        if done {
            break;
        }
        steps = ((steps as f64 * factor).ceil() as usize).max(steps + 1);
    }
    Ok(())
}

/// The fewest step counts (to within 1/16, or one step) from which a method's final error
/// reaches 3·10⁻² (`resolved`): 8 steps doubled until resolved, then bisected back between
/// the last count that was not and the first that was; at least [`MAX_STEPS`] if none is.
fn fewest_resolved_steps(resolved: impl Fn(usize) -> bool) -> usize {
    let mut steps = 8usize;
    while steps < MAX_STEPS && !resolved(steps) {
        steps *= 2;
    }
    let mut short = steps / 2;
    // A bracket of one step cannot be split (below 16 steps 1/16 of a count rounds to 0).
    while steps < MAX_STEPS && short >= 8 && steps - short > (steps / 16).max(1) {
        let middle = short + (steps - short) / 2;
        if resolved(middle) {
            steps = middle;
        } else {
            short = middle;
        }
    }
    steps
}

/// Measure the points of the method `label` that the user asked for (`--steps` or
/// `--tolerances`, named `what`): a point that fails is a warning naming it and the others are
/// kept; if every point fails, the first failure is the error.
pub(super) fn measure_requested<E: Into<SceneError> + fmt::Display>(
    label: &str,
    points: &[f64],
    what: &str,
    measure: impl Fn(f64) -> Result<Record, E>,
    report: Report<'_>,
    records: &mut Vec<Record>,
) -> Result<(), SceneError> {
    let mut first_failure = None;
    let mut measured = 0;
    for &point in points {
        match measure(point) {
            Ok(record) => {
                report.record(&record);
                records.push(record);
                measured += 1;
            }
            Err(error) => {
                report.warn(&format!("{label} at {what} {point} failed: {error}"));
                first_failure.get_or_insert(error);
            }
        }
    }
    match first_failure {
        Some(error) if measured == 0 => Err(error.into()),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bisection ends on every bracket, also one of a single step below 16 steps (it
    /// looped forever on [8, 16] when 9 steps did not resolve: `multiscale` on the stiff
    /// spring pendulum, 8 steps 9.5e-2, 16 steps 1.7e-3), and lands within 1/16 above the
    /// least resolving count.
    #[test]
    fn the_fewest_resolved_steps_are_found_by_a_bisection_that_ends() {
        for least in [9, 10, 15, 16, 17, 100, 1000, 12345] {
            let steps = fewest_resolved_steps(|steps| steps >= least);
            assert!(
                steps >= least && steps - least <= (steps / 16).max(1),
                "least {least}: {steps}"
            );
        }
        assert_eq!(fewest_resolved_steps(|_| true), 8);
        assert!(fewest_resolved_steps(|_| false) >= MAX_STEPS);
    }
}
