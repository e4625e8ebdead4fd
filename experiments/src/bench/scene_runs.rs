//! The sweep of a chain (zoo or text) or a Lagrangian written as text, which have no model
//! of fixed size: each point a whole run of the scene, measured against a resolved reference
//! run.

use indicatif::ProgressBar;
use nalgebra::DVector;
use svi::{Method, MethodSpec};

use crate::bench::method::BenchMethod;
use crate::bench::options::BenchOptions;
use crate::bench::record::{Record, Sweeps};
use crate::bench::sweep::{Outcomes, Report, check_horizon, median_seconds, sweep_steps};
use crate::report::summary::{StateSummary, Summary};
use crate::run::Control;
use crate::scene::overrides::{Overrides, RunFlags};
use crate::scene::schema::{Diagnostic, OutputSection};
use crate::scene::{Scene, SceneError};

/// Sweep the methods of `options` on a chain (zoo or text) or a Lagrangian written as text
/// through the scene's own run ([`Scene::run`], compiled once for every such model): each
/// point is a whole run of the scene with the method and the step, its final position
/// measured against the resolved reference run (SVI 7/6 at the scene's step h halved, up to
/// h/16, until two runs agree to 10⁻¹¹ relative) in the Euclidean norm, its time the median
/// of runs without diagnostics. The fixed-step methods of the library are swept this way; the
/// peers and the adaptive modes need a model of fixed size.
pub(super) fn sweep_runs(
    scene: &Scene,
    options: &BenchOptions,
    progress: &ProgressBar,
) -> Result<Sweeps, SceneError> {
    if options.coordinate.is_some() {
        return Err(SceneError::NotApplicable {
            option: "--coordinate",
            reason: "measures one coordinate of a zoo model of fixed size; a chain or a text \
                     model is measured in all its coordinates"
                .into(),
        });
    }
    let specs = options
        .methods
        .iter()
        .map(|method| match method {
            BenchMethod::Library(spec) => Ok(*spec),
            other => Err(SceneError::NotApplicable {
                option: "--methods",
                reason: format!(
                    "{other} needs a model of fixed size; on a chain or a text model svi bench \
                     sweeps the fixed-step methods of the library"
                ),
            }),
        })
        .collect::<Result<Vec<_>, _>>()?;
    // The scene with `method` at step `h`, measuring the energy error or nothing.
    let with = |method: MethodSpec, h: Option<f64>, energy: bool| -> Result<Scene, SceneError> {
        let mut variant = scene.clone();
        variant.overlay(&Overrides {
            run: RunFlags {
                method: Some(method.into()),
                h,
                ..RunFlags::default()
            },
            ..Overrides::default()
        })?;
        // Only the final state and the energy error are read: no trajectory, plot or output
        // times of the scene's own.
        variant.output = OutputSection {
            diagnostics: Some(vec![if energy {
                Diagnostic::Energy
            } else {
                Diagnostic::None
            }]),
            ..OutputSection::default()
        };
        Ok(variant)
    };
    let final_q = |summary: &Summary| match &summary.state {
        StateSummary::Vector { q, .. } => DVector::from_column_slice(q),
        StateSummary::Rigid { .. } | StateSummary::Group { .. } => {
            unreachable!("a chain or a text model lives on ℝᴺ")
        }
    };
    // The reference: svi:7/6 at the scene's step halved until two runs agree.
    let reference_spec: MethodSpec = "svi:7/6".parse()?;
    let first = with(reference_spec, None, false)?.run(Control::QUIET)?;
    let span = first.t_end - first.t0;
    check_horizon(first.t0, first.t_end, first.h)?;
    let (mut h, mut coarse) = (first.h, final_q(&first));
    let reference = loop {
        let fine = final_q(&with(reference_spec, Some(0.5 * h), false)?.run(Control::QUIET)?);
        let discrepancy = (&coarse - &fine).amax();
        if discrepancy <= 1e-11 * fine.amax().max(1.0) {
            break fine;
        }
        if h <= first.h / 8.0 {
            return Err(SceneError::NoReference {
                model: scene.model_name().into(),
                reason: format!(
                    "its reference runs (svi:7/6 at h = {h:e} and h/2) differ by \
                     {discrepancy:.1e}: the scene's step divided by 16 does not resolve it"
                ),
            });
        }
        (h, coarse) = (0.5 * h, fine);
    };
    let report = Report {
        verbose: options.verbose,
        progress,
    };
    let mut outcomes = Outcomes::default();
    for spec in specs {
        let label = spec.to_string();
        progress.set_message(label.clone());
        let run = |steps: f64, energy: bool| {
            with(spec, Some(span / steps), energy)?
                .run(Control::QUIET)
                .map_err(|error| match error {
                    SceneError::RunFailed { source, .. } => SceneError::from(source),
                    other => other,
                })
        };
        let final_error = |steps: usize| -> Result<f64, SceneError> {
            Ok((final_q(&run(steps as f64, false)?) - &reference).norm())
        };
        let measure = |steps: f64| -> Result<Record, SceneError> {
            let summary = run(steps, true)?;
            // Checked once: the timed runs do only the run.
            let quiet = with(spec, Some(span / steps), false)?;
            let quiet = quiet.checked()?;
            let seconds = median_seconds(
                || {
                    let _ = quiet.run(Control::QUIET);
                },
                options,
            );
            Ok(Record {
                method: label.clone(),
                parameter: steps,
                h: Some(summary.h),
                steps: summary.steps,
                final_error: (final_q(&summary) - &reference).norm(),
                energy_error_max: summary.energy_error_max.unwrap_or(f64::NAN),
                momentum_error_max: None,
                evaluations: summary.evaluations,
                iterations: summary.iterations,
                seconds,
            })
        };
        let order = Method::<svi::Dyn>::info(&spec.vector_method()?)
            .order
            .max(1) as f64;
        let mut records = Vec::new();
        let swept = sweep_steps(
            &label,
            order,
            options,
            report,
            &mut records,
            final_error,
            measure,
        );
        outcomes.add(&label, swept.map(|()| records), report)?;
        progress.inc(1);
    }
    outcomes.finish()
}
