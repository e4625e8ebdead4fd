//! The summary of a run: what `svi run` prints, as text or as one JSON object.

use std::fmt;

use serde::Serialize;

use crate::report::csv::{Float, vector};
use svi::solve::Adapt;

/// A state at a requested output time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputPoint {
    /// Time.
    pub t: f64,
    /// Configuration.
    pub q: Vec<f64>,
    /// Velocity.
    pub v: Vec<f64>,
    /// Momentum.
    pub p: Vec<f64>,
}

/// What [`svi::solve()`] did, for the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdaptivitySummary {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected trial steps.
    pub rejected: usize,
    /// Smallest accepted step.
    pub min_step: f64,
    /// Largest accepted step.
    pub max_step: f64,
    /// (CGL points, steps that used them).
    pub points_used: Vec<(usize, usize)>,
    /// Steps of `adapt = "degree"` that missed the tolerance at `max_points`.
    pub unmet: usize,
    /// States reported at output times.
    pub outputs: usize,
}

/// Model parameters in the model's order (serialised as a JSON object).
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters(pub Vec<(&'static str, f64)>);

impl Serialize for Parameters {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// Serialise a value as its `Display` text.
fn serialize_display<T: fmt::Display, S: serde::Serializer>(
    value: &T,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    serializer.collect_str(value)
}

/// Where the trajectory went.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryOutput {
    /// The CSV file.
    pub path: String,
    /// Thinning factor.
    pub every: usize,
    /// Data rows written (the initial point, every `every`-th step, and the last point).
    pub rows: usize,
}

/// The result of running a scene (`svi run --json` prints it as one JSON object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// Names of the configuration coordinates (the order of `q`, `v`, `p`).
    pub coordinates: Vec<String>,
    /// The method's name (see [`registry::METHODS`]; its options are `points` and
    /// `quadrature`).
    pub method: String,
    /// Chebyshev–Gauss–Lobatto points (`None` for the classic methods).
    pub points: Option<usize>,
    /// Gauss–Legendre points (`None` for all methods but svi).
    pub quadrature: Option<usize>,
    /// Classical order of the method.
    pub order: usize,
    /// Whether the method is symmetric.
    pub symmetric: bool,
    /// Whether the method is symplectic.
    pub symplectic: bool,
    /// Step size.
    pub h: f64,
    /// Initial time.
    pub t0: f64,
    /// Final time reached.
    pub t_end: f64,
    /// Steps taken.
    pub steps: usize,
    /// Final configuration.
    pub q: Vec<f64>,
    /// Final velocity.
    pub v: Vec<f64>,
    /// Final momentum.
    pub p: Vec<f64>,
    /// Energy of the initial state.
    pub energy_initial: f64,
    /// Energy of the final state.
    pub energy_final: f64,
    /// Largest |E − E₀| over the step points (`None` if not asked for).
    pub energy_error_max: Option<f64>,
    /// Largest deviation of the Noether momenta (`None` if the model has no symmetry or it
    /// was not asked for).
    pub momentum_error_max: Option<f64>,
    /// Largest position error against the exact solution (`None` if there is none or it was
    /// not asked for).
    pub solution_error_max: Option<f64>,
    /// Nonlinear iterations, summed over all steps.
    pub iterations: usize,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: usize,
    /// Failed steps retried with half the step (`recovery = "halve-step"`).
    pub retries: usize,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The trajectory file, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
    /// Adaptivity mode.
    #[serde(serialize_with = "serialize_display")]
    pub adapt: Adapt,
    /// Target final error of the adaptive modes.
    pub tol: Option<f64>,
    /// What the adaptivity did (runs through `svi::solve` only: adaptive or with output
    /// times).
    pub adaptivity: Option<AdaptivitySummary>,
    /// The states at the requested output times (`None` without output times).
    pub outputs: Option<Vec<OutputPoint>>,
}

/// `{:.3e}`, or `n/a` when absent.
fn error(value: Option<f64>) -> String {
    value.map_or_else(|| "n/a".into(), |x| format!("{x:.3e}"))
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parameters: Vec<String> = self
            .parameters
            .0
            .iter()
            .map(|(name, value)| format!("{name} = {value}"))
            .collect();
        let mut method = self.method.clone();
        if let Some(points) = self.points {
            method.push_str(&format!(", {points} CGL points"));
        }
        if let Some(quadrature) = self.quadrature {
            method.push_str(&format!(", {quadrature} Gauss points"));
        }
        method.push_str(&format!("; order {}", self.order));
        if self.symmetric {
            method.push_str(", symmetric");
        }
        if self.symplectic {
            method.push_str(", symplectic");
        }
        let coordinates = self.coordinates.join(", ");
        let rows = [
            (
                "model",
                format!("{} ({})", self.model, parameters.join(", ")),
            ),
            ("method", method),
            ("step h", Float(self.h).to_string()),
            (
                "time",
                format!(
                    "{} to {} in {} steps",
                    Float(self.t0),
                    Float(self.t_end),
                    self.steps
                ),
            ),
            ("wall time", format!("{:.3} s", self.seconds)),
            (
                "work",
                format!(
                    "{} nonlinear iterations, {} evaluations{}",
                    self.iterations,
                    self.evaluations,
                    if self.retries > 0 {
                        format!(", {} steps retried with h/2", self.retries)
                    } else {
                        String::new()
                    }
                ),
            ),
            ("coordinates", coordinates),
            ("final q", vector(&self.q)),
            ("final v", vector(&self.v)),
            ("final p", vector(&self.p)),
            (
                "energy",
                format!(
                    "{} to {}",
                    Float(self.energy_initial),
                    Float(self.energy_final)
                ),
            ),
            ("energy error", error(self.energy_error_max)),
            ("momentum error", error(self.momentum_error_max)),
            ("solution error", error(self.solution_error_max)),
        ];
        for (label, value) in rows {
            writeln!(f, "{label:<16}{value}")?;
        }
        if let Some(a) = &self.adaptivity {
            let mut line = format!(
                "{} accepted, {} rejected steps, h from {:.3e} to {:.3e}",
                a.accepted, a.rejected, a.min_step, a.max_step
            );
            if let Some(tol) = self.tol {
                line = format!("{}, tol {tol:e}: {line}", self.adapt);
            }
            if self.adapt == Adapt::Degree {
                let used: Vec<String> = a
                    .points_used
                    .iter()
                    .map(|(points, steps)| format!("{points}:{steps}"))
                    .collect();
                line.push_str(&format!("; points:steps {}", used.join(" ")));
                if a.unmet > 0 {
                    line.push_str(&format!("; {} steps missed tol at max_points", a.unmet));
                }
            }
            writeln!(f, "{:<16}{line}", "adaptivity")?;
        }
        for point in self.outputs.iter().flatten() {
            writeln!(
                f,
                "{:<16}q {} v {} p {}",
                format!("t = {}", Float(point.t)),
                vector(&point.q),
                vector(&point.v),
                vector(&point.p)
            )?;
        }
        if let Some(trajectory) = &self.trajectory {
            writeln!(
                f,
                "{:<16}{} ({} rows, every {} steps)",
                "trajectory", trajectory.path, trajectory.rows, trajectory.every
            )?;
        }
        Ok(())
    }
}
