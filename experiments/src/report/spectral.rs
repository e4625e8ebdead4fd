//! The summary of a pseudospectral run (`svi run` on a pseudospectral scene), as text or one
//! JSON object.
//!
//! The JSON fields are an interface (`docs/schema/result.schema.json`, kind `pseudospectral`):
//! `model`, `parameters`, `method`, `order`, `mesh_points`, `dx`, `h`, `steps`, `t_end`,
//! `norm_initial`, `norm_error_max` (largest |N_l − N_0|/N_0 of the mass N = Δx Σ|ψ_j|² over
//! all levels), `energy_initial`, `energy_error_final` (|H_end − H_0|), `solution_error_max`
//! (largest |ψ − ψ_exact| over all nodes and levels), `solution_error_final` (the same at the
//! last level), `ffts`, `iterations`, `seconds`, `trajectory`, `status`, `warnings` and, for a
//! failed run, `error`. The names before schema version 1 (`points`, `energy_error`,
//! `error_max`, `error_final`) are printed too, for one release.

use std::fmt;

use serde::Serialize;

use crate::report::csv::Float;
use crate::report::health::Warning;
use crate::report::schema::{Kind, Versioned};
use crate::report::summary::{ErrorReport, Parameters, Status, TrajectoryOutput};

/// The result of a pseudospectral run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectralSummary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// `midpoint`, `svi:P/M` or `strang`.
    pub method: String,
    /// The order in time.
    pub order: usize,
    /// Fourier modes (= nodes in space).
    pub mesh_points: usize,
    /// Δx.
    pub dx: f64,
    /// The time step.
    pub h: f64,
    /// Steps taken.
    pub steps: usize,
    /// Final time reached, steps · h.
    pub t_end: f64,
    /// The initial mass N_0 = Δx Σ|ψ_j|².
    pub norm_initial: f64,
    /// Largest |N_l − N_0| / N_0.
    pub norm_error_max: f64,
    /// The initial semi-discrete energy H.
    pub energy_initial: f64,
    /// |H_end − H_0|.
    pub energy_error_final: f64,
    /// Largest |ψ − ψ_exact| over all nodes and levels.
    pub solution_error_max: f64,
    /// Largest |ψ − ψ_exact| at the last level.
    pub solution_error_final: f64,
    /// FFTs over the run.
    pub ffts: usize,
    /// Iterations of the stage equations (0 for Strang).
    pub iterations: usize,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The field CSV, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
    /// `ok`, or `failed`.
    pub status: Status,
    /// The health checks the run failed.
    pub warnings: Vec<Warning>,
    /// Why the run failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorReport>,
}

impl fmt::Display for SpectralSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut rows = vec![
            ("model", format!("{} ({})", self.model, self.parameters)),
            (
                "method",
                format!(
                    "pseudospectral, {} in time (order {})",
                    self.method, self.order
                ),
            ),
            (
                "grid",
                format!(
                    "{} Fourier modes, dx = {}, h = {}",
                    self.mesh_points,
                    Float(self.dx),
                    Float(self.h)
                ),
            ),
            (
                "time",
                format!("0 to {} in {} steps", Float(self.t_end), self.steps),
            ),
            ("wall time", format!("{:.3} s", self.seconds)),
            (
                "norm",
                format!(
                    "{} (max relative error {:.3e})",
                    Float(self.norm_initial),
                    self.norm_error_max
                ),
            ),
            (
                "energy",
                format!(
                    "{} (error at the end {:.3e})",
                    Float(self.energy_initial),
                    self.energy_error_final
                ),
            ),
            (
                "error vs exact",
                format!(
                    "{:.3e} (at the end {:.3e})",
                    self.solution_error_max, self.solution_error_final
                ),
            ),
            ("FFTs", self.ffts.to_string()),
            ("iterations", self.iterations.to_string()),
        ];
        if let Some(trajectory) = &self.trajectory {
            rows.push((
                "field",
                format!(
                    "{} ({} rows, every {} levels)",
                    trajectory.path, trajectory.rows, trajectory.every
                ),
            ));
        }
        let width = rows.iter().map(|(label, _)| label.len()).max().unwrap_or(0) + 2;
        for (label, value) in rows {
            writeln!(f, "{:width$}{value}", format!("{label}:"))?;
        }
        Ok(())
    }
}

impl Versioned for SpectralSummary {
    fn kind(&self) -> Kind {
        Kind::Pseudospectral
    }

    fn deprecated(&self) -> Vec<(&'static str, serde_json::Value)> {
        vec![
            ("points", self.mesh_points.into()),
            ("energy_error", self.energy_error_final.into()),
            ("error_max", self.solution_error_max.into()),
            ("error_final", self.solution_error_final.into()),
        ]
    }
}
