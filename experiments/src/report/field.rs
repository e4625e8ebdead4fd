//! The summary of a field run (`svi run` on a field scene), as text or one JSON object.
//!
//! The JSON fields are an interface (`docs/schema/result.schema.json`, kind `field`): `model`,
//! `parameters`, `method` (`multisymplectic`, or `r-adaptive` on a moving mesh),
//! `mesh_points`, `dx` (null on a moving mesh), `h`, `steps` (time levels), `t_end`,
//! `cell_rule`, on a moving mesh only `monitor` (`arc-length` or `curvature`), `smoothing`
//! and `smallest_width` (the smallest cell width over the run), `explicit`,
//! `energy_initial`, `energy_error_max` (largest |E^{j+½} − E^{½}| of the discrete energy),
//! `momentum_initial`, `momentum_error_max`, `multisymplectic_residual_max` (null when not
//! measured, always on a moving mesh), `solution_error_max` (largest |u − u_exact| over all
//! nodes and levels), `iterations` (Newton's), `seconds`, `trajectory`, `status`, `warnings`
//! and, for a failed run, `error`. The names before schema
//! version 1 (`points`, `levels`, `quadrature`, `error_max`, `newton_iterations`) are printed
//! too, for one release.

use std::fmt;

use serde::Serialize;

use crate::report::csv::Float;
use crate::report::health::Warning;
use crate::report::schema::{Kind, Versioned};
use crate::report::summary::{ErrorReport, Parameters, Status, TrajectoryOutput};

/// The result of a field run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldSummary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// `multisymplectic` (a uniform mesh) or `r-adaptive` (a moving mesh).
    pub method: &'static str,
    /// Nodes in space.
    pub mesh_points: usize,
    /// Δx of a uniform mesh (`None` for a moving mesh).
    pub dx: Option<f64>,
    /// The time step Δt.
    pub h: f64,
    /// Time levels computed (steps).
    pub steps: usize,
    /// Final time reached, levels · h (the first level at or after the scene's t_end).
    pub t_end: f64,
    /// The rule of the action on a cell: `trapezoid` or `midpoint`.
    pub cell_rule: &'static str,
    /// The moving mesh's monitor, smoothing and smallest width (absent for a uniform mesh).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub moving: Option<MovingMeshSummary>,
    /// Whether the levels were solved explicitly.
    pub explicit: bool,
    /// The discrete energy of the first slab.
    pub energy_initial: f64,
    /// Largest |E^{j+½} − E^{½}|.
    pub energy_error_max: f64,
    /// The discrete momentum of the first slab.
    pub momentum_initial: f64,
    /// Largest |P^{j+½} − P^{½}|.
    pub momentum_error_max: f64,
    /// Largest |residual| of the discrete multisymplectic conservation law.
    pub multisymplectic_residual_max: Option<f64>,
    /// Largest |u − u_exact| over all nodes and levels.
    pub solution_error_max: f64,
    /// Newton iterations over the run (0 when explicit).
    pub iterations: usize,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The field CSV, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
    /// `ok`, or `failed` (a failed health check under `--strict`).
    pub status: Status,
    /// The health checks the run failed.
    pub warnings: Vec<Warning>,
    /// Why the run failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorReport>,
}

/// The part of a [`FieldSummary`] particular to a moving mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MovingMeshSummary {
    /// The monitor: `arc-length` or `curvature`.
    pub monitor: &'static str,
    /// The smoothing κ of the mesh concentration.
    pub smoothing: f64,
    /// The smallest cell width over the run.
    pub smallest_width: f64,
}

impl fmt::Display for FieldSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let optional = |value: Option<f64>| value.map_or("n/a".into(), |v| format!("{v:.3e}"));
        let solver = if self.explicit { "explicit" } else { "Newton" };
        let (method, mesh) = match (&self.moving, self.dx) {
            (Some(moving), _) => (
                format!(
                    "r-adaptive, {} monitor, smoothing {}, {} cells ({solver})",
                    moving.monitor,
                    Float(moving.smoothing),
                    self.cell_rule
                ),
                format!(
                    "{} moving nodes, smallest width {:.3e}, h = {}",
                    self.mesh_points,
                    moving.smallest_width,
                    Float(self.h)
                ),
            ),
            (None, dx) => (
                format!("{}, {} cells ({solver})", self.method, self.cell_rule),
                format!(
                    "{} points, dx = {}, h = {}",
                    self.mesh_points,
                    dx.map_or("n/a".into(), |dx| Float(dx).to_string()),
                    Float(self.h)
                ),
            ),
        };
        let mut rows = vec![
            ("model", format!("{} ({})", self.model, self.parameters)),
            ("method", method),
            ("mesh", mesh),
            (
                "time",
                format!("0 to {} in {} levels", Float(self.t_end), self.steps),
            ),
            ("wall time", format!("{:.3} s", self.seconds)),
            (
                "energy",
                format!(
                    "{} (max error {:.3e})",
                    Float(self.energy_initial),
                    self.energy_error_max
                ),
            ),
            (
                "momentum",
                format!(
                    "{} (max error {:.3e})",
                    Float(self.momentum_initial),
                    self.momentum_error_max
                ),
            ),
            (
                "multisymplectic residual",
                optional(self.multisymplectic_residual_max),
            ),
            ("error vs exact", format!("{:.3e}", self.solution_error_max)),
            ("Newton iterations", self.iterations.to_string()),
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

impl Versioned for FieldSummary {
    fn kind(&self) -> Kind {
        Kind::Field
    }

    fn deprecated(&self) -> Vec<(&'static str, serde_json::Value)> {
        vec![
            ("points", self.mesh_points.into()),
            ("levels", self.steps.into()),
            ("quadrature", self.cell_rule.into()),
            ("error_max", self.solution_error_max.into()),
            ("newton_iterations", self.iterations.into()),
        ]
    }
}
