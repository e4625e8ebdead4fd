//! The derivatives of a run in its summary (`--sensitivity`): the Jacobian of the state at
//! each output with respect to the initial state and the model's parameters, the exact
//! derivative of the method's discrete map ([`svi::analysis::sensitivity`]).

use serde::Serialize;

use crate::report::csv::{Float, vector};

/// The Jacobians of a run, by output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensitivitySummary {
    /// What the columns differentiate with respect to, in the order asked: `q0_NAME` and
    /// `v0_NAME` (`p0_NAME` for a start given in momenta) per coordinate, and parameter names.
    pub columns: Vec<String>,
    /// The rows: `q_NAME`, then `v_NAME`, per coordinate.
    pub rows: Vec<String>,
    /// The outputs: the start, every `sensitivity_every`-th step, and the last step.
    pub outputs: Vec<SensitivityOutput>,
}

/// The Jacobian at one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensitivityOutput {
    /// The time.
    pub t: f64,
    /// The configuration there.
    pub q: Vec<f64>,
    /// The velocity there.
    pub v: Vec<f64>,
    /// ∂(row)/∂(column), row by row.
    pub jacobian: Vec<Vec<f64>>,
}

impl SensitivitySummary {
    /// The summary's lines: what the Jacobian at the last output differentiates, then its
    /// rows.
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        let mut lines = Vec::new();
        if let Some(last) = self.outputs.last() {
            lines.push((
                "sensitivity",
                format!(
                    "∂({})/∂({}) at t = {}",
                    self.rows.join(", "),
                    self.columns.join(", "),
                    Float(last.t)
                ),
            ));
            for (name, row) in self.rows.iter().zip(&last.jacobian) {
                lines.push(("", format!("{name}: {}", vector(row))));
            }
        }
        lines
    }
}

/// The gradient of a loss of a run ([`crate::Scene::gradient`]): ∂J/∂(column) for the columns
/// of the scene's `sensitivity` names, by the discrete adjoint ([`svi::Integrator::gradient`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GradientSummary {
    /// J, the loss summed over the outputs.
    pub value: f64,
    /// What the entries differentiate with respect to, as [`SensitivitySummary::columns`].
    pub columns: Vec<String>,
    /// ∂J/∂(column), in the order of `columns`.
    pub gradient: Vec<f64>,
    /// The most forward states (checkpoints) and tangent maps held at once.
    pub peak_stored: usize,
    /// The memory they took at the peak, in bytes.
    pub peak_bytes: usize,
}
