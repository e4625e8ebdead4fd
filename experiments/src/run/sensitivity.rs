//! Runs with sensitivities (`--sensitivity`): after the scene's run, the forward
//! sensitivities of the same fixed-step run ([`svi::Integrator::sensitivities`]) for the
//! summary, with respect to the initial state (`q0`, `v0` or `p0`) and the parameters named;
//! and the gradient of a loss given natively (the Python package's `svi.gradient`) by the
//! discrete adjoint ([`Scene::gradient`], [`svi::Integrator::gradient`]).

use std::cell::RefCell;

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::sensitivity::{Checkpoints, Loss, SensitivityRun, Start};
use svi::{Dimension, Initial, Integrator, Parametric, Scalar};
use svi_models::{ParametricModelVisitor, ZooModel, visit_parametric_model};

use crate::report::sensitivity::{GradientSummary, SensitivityOutput, SensitivitySummary};
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
    let differentiate = Differentiate {
        scene,
        names,
        loss: None,
    };
    match visit_parametric_model(&scene.model, differentiate)
        .unwrap_or_else(|| unreachable!("the scene's check admits parametric models only"))?
    {
        Differentiated::Sensitivities(sensitivities) => summary.sensitivity = Some(sensitivities),
        Differentiated::Gradient(_) => unreachable!("no loss was given"),
    }
    Ok(summary)
}

/// A loss of a run given natively, J = Σ_j ℓ_j(t, q, q̇) over the outputs of the scene's
/// `sensitivity_every`: `loss(j, t, q, v)` returns ℓ_j and its gradient (∂ℓ_j/∂q, ∂ℓ_j/∂q̇),
/// n entries each. A value or gradient that is not finite fails the gradient naming the output.
pub type NativeLoss = dyn Fn(usize, f64, &[f64], &[f64]) -> LossAt + Send + Sync;

/// What a [`NativeLoss`] returns at an output: ℓ_j, ∂ℓ_j/∂q and ∂ℓ_j/∂q̇.
pub type LossAt = (f64, Vec<f64>, Vec<f64>);

impl Scene {
    /// The gradient of `loss` over the scene's fixed-step run with respect to the initial-state
    /// blocks and parameters of its `sensitivity` names, in their order, by the discrete
    /// adjoint with `checkpoints` forward states kept (default ⌈√K⌉ for K steps). The scene is
    /// checked as for `--sensitivity`; only the differentiated run is taken.
    ///
    /// # Errors
    /// [`SceneError::NotApplicable`] without `sensitivity` names; those of the scene's check;
    /// those of [`svi::Integrator::gradient`] (a loss that is not finite, a budget of 0
    /// checkpoints).
    pub fn gradient(
        &self,
        loss: &NativeLoss,
        checkpoints: Option<usize>,
    ) -> Result<GradientSummary, SceneError> {
        let scene = self.checked()?;
        let Some(names) = &scene.run.sensitivity else {
            return Err(SceneError::NotApplicable {
                option: "gradient",
                reason: "names nothing to differentiate with respect to: give the parameters \
                         and initial-state blocks (run.sensitivity)"
                    .into(),
            });
        };
        let checkpoints = checkpoints.map_or(Checkpoints::Sqrt, Checkpoints::Budget);
        let differentiate = Differentiate {
            scene: &scene,
            names,
            loss: Some((loss, checkpoints)),
        };
        match visit_parametric_model(&scene.model, differentiate)
            .unwrap_or_else(|| unreachable!("the scene's check admits parametric models only"))?
        {
            Differentiated::Gradient(gradient) => Ok(gradient),
            Differentiated::Sensitivities(_) => unreachable!("a loss was given"),
        }
    }
}

/// A [`NativeLoss`] as a [`Loss`] of any scalar: ℓ at the real parts of (q, q̇) plus its
/// gradient times their dual parts, ℓ(x) + ∇ℓ(x)·δx, which is all the adjoint's first
/// derivatives take. The native loss is called once per output: the real parts' evaluation
/// and the gradient's sweeps at the same point share it.
struct Linearised<'a> {
    loss: &'a NativeLoss,
    /// The last call.
    last: RefCell<Option<Call>>,
}

/// A call of a [`NativeLoss`]: its arguments and what it returned.
struct Call {
    output: usize,
    t: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    returned: LossAt,
}

impl Loss for Linearised<'_> {
    fn loss<D: Scalar>(&self, output: usize, t: f64, q: &[D], v: &[D]) -> D {
        let real = |x: &[D]| x.iter().map(|x| x.re()).collect::<Vec<f64>>();
        let (q_re, v_re) = (real(q), real(v));
        let mut last = self.last.borrow_mut();
        let same = matches!(&*last, Some(call)
            if call.output == output && call.t == t && call.q == q_re && call.v == v_re);
        if !same {
            let returned = (self.loss)(output, t, &q_re, &v_re);
            *last = Some(Call {
                output,
                t,
                q: q_re.clone(),
                v: v_re.clone(),
                returned,
            });
        }
        let Some(Call {
            returned: (value, dq, dv),
            ..
        }) = &*last
        else {
            unreachable!("set above")
        };
        // A gradient of the wrong length is not finite: the adjoint names the output.
        if dq.len() != q.len() || dv.len() != v.len() {
            return D::from(f64::NAN);
        }
        let mut result = D::from(*value);
        for ((x, x_re), g) in q
            .iter()
            .zip(&q_re)
            .zip(dq)
            .chain(v.iter().zip(&v_re).zip(dv))
        {
            result += (*x - D::from(*x_re)) * *g;
        }
        result
    }
}

/// What [`Differentiate`] computed.
enum Differentiated {
    /// The forward sensitivities (`--sensitivity`).
    Sensitivities(SensitivitySummary),
    /// The gradient of a native loss.
    Gradient(GradientSummary),
}

/// The blocks of the initial state a scene may name in `--sensitivity`.
const INITIAL_BLOCKS: [&str; 3] = ["q0", "v0", "p0"];

/// Differentiates a scene's run of its (parametric) model: its forward sensitivities, or with
/// a loss the loss's gradient.
struct Differentiate<'a> {
    scene: &'a Scene,
    names: &'a [String],
    loss: Option<(&'a NativeLoss, Checkpoints)>,
}

impl ParametricModelVisitor for Differentiate<'_> {
    type Output = Result<Differentiated, SceneError>;

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
        let integrator = Integrator::new(model, method);
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
        if let Some((loss, checkpoints)) = self.loss {
            let linearised = Linearised {
                loss,
                last: RefCell::new(None),
            };
            let gradient = integrator.gradient(&run, &linearised, checkpoints)?;
            // The initial state's entries (2n), then the parameters': the Jacobian's columns.
            let entry = |c: usize| {
                if c < 2 * n {
                    gradient.initial[c]
                } else {
                    gradient.parameters[c - 2 * n]
                }
            };
            return Ok(Differentiated::Gradient(GradientSummary {
                value: gradient.value,
                columns,
                gradient: indices.iter().map(|&c| entry(c)).collect(),
                peak_stored: gradient.peak_stored,
                peak_bytes: gradient.peak_bytes,
            }));
        }
        let sensitivities = integrator.sensitivities(&run)?;
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
        Ok(Differentiated::Sensitivities(SensitivitySummary {
            columns,
            rows,
            outputs,
        }))
    }
}
