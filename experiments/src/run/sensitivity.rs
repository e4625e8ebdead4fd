//! Runs with sensitivities (`--sensitivity`): after the scene's run, the forward
//! sensitivities of the same fixed-step run ([`svi::Integrator::sensitivities`]) for the
//! summary, with respect to the initial state (`q0`, `v0` or `p0`) and the parameters named.

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::sensitivity::{SensitivityRun, Start};
use svi::{Dimension, Initial, Integrator, Parametric};
use svi_models::{ParametricModelVisitor, ZooModel, visit_parametric_model};

use crate::report::sensitivity::{SensitivityOutput, SensitivitySummary};
use crate::report::summary::{Status, Summary};
use crate::scene::{Scene, SceneError};

/// The summary of a run, with its sensitivities when the scene asks for them (and the run
/// ended well: a failed run reports what it has).
pub(super) fn with_sensitivity(
    scene: &Scene,
    summary: Result<Summary, SceneError>,
) -> Result<Summary, SceneError> {
    let Some(names) = &scene.run.sensitivity else {
        return summary;
    };
    let mut summary = summary?;
    if summary.status != Status::Ok {
        return Ok(summary);
    }
    let differentiate = Differentiate { scene, names };
    summary.sensitivity = Some(
        visit_parametric_model(&scene.model, differentiate)
            .unwrap_or_else(|| unreachable!("the scene's check admits parametric models only"))?,
    );
    Ok(summary)
}

/// The blocks of the initial state a scene may name in `--sensitivity`.
const INITIAL_BLOCKS: [&str; 3] = ["q0", "v0", "p0"];

/// Differentiates a scene's run of its (parametric) model.
struct Differentiate<'a> {
    scene: &'a Scene,
    names: &'a [String],
}

impl ParametricModelVisitor for Differentiate<'_> {
    type Output = Result<SensitivitySummary, SceneError>;

    fn visit<M: ZooModel<N> + Parametric<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let scene = self.scene;
        let (t0, initial, h, t_end) = scene.resolve(&mut model)?;
        let given_momentum = matches!(initial, Initial::Momentum { .. });
        let second = if given_momentum { "p0" } else { "v0" };
        for name in self.names {
            let other = if given_momentum { "v0" } else { "p0" };
            if *name == other {
                return Err(SceneError::NotApplicable {
                    option: "--sensitivity (run.sensitivity)",
                    reason: format!(
                        "the initial state is given in {}: name {second}, not {other}",
                        if given_momentum {
                            "momenta"
                        } else {
                            "velocities"
                        }
                    ),
                });
            }
        }
        let parameters: Vec<&str> = self
            .names
            .iter()
            .map(String::as_str)
            .filter(|name| !INITIAL_BLOCKS.contains(name))
            .collect();
        // The model's own start moves with its parameters (Kepler's e) unless the scene
        // gives the initial state.
        let section = &scene.initial;
        let default_start = section.q.is_none() && section.v.is_none() && section.p.is_none();
        let start = if default_start
            && model
                .initial_state_with(&model.parameter_values())
                .is_some()
        {
            Start::Model
        } else {
            Start::Given(initial)
        };
        let coordinates = model.coordinate_names();
        let run = SensitivityRun::new(t0, start, h, t_end)
            .with_parameters(&parameters)
            .with_outputs_every(scene.run.sensitivity_every.unwrap_or(usize::MAX));
        let method = scene.method_spec()?.vector_method()?;
        let sensitivities = Integrator::new(model, method).sensitivities(&run)?;
        // The columns asked for, in order: blocks of n, then each parameter.
        let n = coordinates.len();
        let mut columns = Vec::new();
        let mut indices = Vec::new();
        for name in self.names {
            match name.as_str() {
                "q0" | "v0" | "p0" => {
                    let offset = if name == "q0" { 0 } else { n };
                    for (i, coordinate) in coordinates.iter().enumerate() {
                        columns.push(format!("{name}_{coordinate}"));
                        indices.push(offset + i);
                    }
                }
                parameter => {
                    let k = parameters
                        .iter()
                        .position(|p| *p == parameter)
                        .expect("named");
                    columns.push(parameter.to_owned());
                    indices.push(2 * n + k);
                }
            }
        }
        let rows = (coordinates.iter().map(|c| format!("q_{c}")))
            .chain(coordinates.iter().map(|c| format!("v_{c}")))
            .collect();
        let outputs = sensitivities
            .outputs
            .iter()
            .map(|output| SensitivityOutput {
                t: output.t,
                q: output.q.iter().copied().collect(),
                v: output.v.iter().copied().collect(),
                jacobian: (0..2 * n)
                    .map(|r| indices.iter().map(|&c| output.jacobian[(r, c)]).collect())
                    .collect(),
            })
            .collect();
        Ok(SensitivitySummary {
            columns,
            rows,
            outputs,
        })
    }
}
