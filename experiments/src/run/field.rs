//! `svi run` on a field scene ([`FieldScene`]): the model chosen by name
//! ([`svi_models::visit_field_model`]), its mesh, the multisymplectic integrator
//! ([`svi::field::multisymplectic::Multisymplectic`]), the field written as CSV while it runs,
//! and the [`FieldSummary`].
//!
//! The field CSV has the header `t,x,u` and one row per node and written time level (the
//! initial level, every `every`-th level and the last), levels in time order, nodes from
//! left to right (a periodic mesh does not repeat its first node at the right end). The run
//! takes the whole number of steps h that reaches t_end (the last level at or after it).

use std::path::PathBuf;
use std::time::Instant;

use svi::field::mesh::Mesh;
use svi::field::multisymplectic::{CellQuadrature, Multisymplectic, MultisymplecticOptions};
use svi_models::{FieldModelVisitor, FieldZooModel, UnknownModel, visit_field_model};

use crate::report::csv::{CsvStream, Float};
use crate::report::field::FieldSummary;
use crate::report::health::{self, Measured, Warning};
use crate::report::plot::plot_space_time;
use crate::report::progress::Progress;
use crate::report::summary::{ErrorReport, Parameters, Status, TrajectoryOutput};
use crate::run::outcome::RunSummary;
use crate::scene::error::SceneError;
use crate::scene::field::{FieldRunSection, FieldScene, QuadratureName};
use crate::scene::limits;

/// The most time levels a field run may take.
pub const MAX_LEVELS: usize = 100_000_000;

/// The step h of a space–time scene's `[run]` (or `default_step`) and the number of steps
/// that reaches its t_end (or `default_horizon`): the last level at or after t_end (the time
/// step is the mesh's: no shorter last step), at most [`MAX_LEVELS`].
pub fn time_levels(
    run: &FieldRunSection,
    default_step: f64,
    default_horizon: f64,
) -> Result<(f64, usize), SceneError> {
    let h = limits::positive("h", run.h.unwrap_or(default_step))?;
    let t_end = limits::positive("t_end", run.t_end.unwrap_or(default_horizon))?;
    let levels = (t_end / h * (1.0 - 1e-12)).ceil().max(1.0);
    if levels > MAX_LEVELS as f64 {
        return Err(SceneError::InvalidOption {
            option: "t_end",
            reason: format!(
                "{} takes more than {MAX_LEVELS} steps h = {}",
                Float(t_end),
                Float(h)
            ),
        });
    }
    Ok((h, levels as usize))
}

/// The CSV stream of a space–time scene's field, with `header`, if it writes one.
pub fn field_stream<'a>(
    path: Option<&'a PathBuf>,
    header: &str,
) -> Result<Option<(&'a PathBuf, CsvStream)>, SceneError> {
    path.map(|path| {
        CsvStream::create("--out (output.trajectory)", path, header)
            .map(|stream| (path, stream))
            .map_err(SceneError::from)
    })
    .transpose()
}

/// Put the field CSV of a space–time run in place (or report the write error that stopped
/// it): the trajectory output of the summary.
pub fn finish_field_stream(
    csv: Option<(&PathBuf, CsvStream)>,
    write_error: Option<std::io::Error>,
    every: usize,
) -> Result<Option<TrajectoryOutput>, SceneError> {
    let Some((path, stream)) = csv else {
        return Ok(None);
    };
    let rows = match write_error {
        Some(source) => Err(SceneError::Write {
            path: path.clone(),
            source,
        }),
        None => stream
            .finish()
            .map(|(rows, _)| rows)
            .map_err(SceneError::from),
    }?;
    Ok(Some(TrajectoryOutput {
        path: path.display().to_string(),
        every,
        rows,
    }))
}

impl RunSummary for FieldSummary {
    fn warnings(&self) -> &[Warning] {
        &self.warnings
    }
    fn fail(&mut self, report: ErrorReport) {
        self.status = Status::Failed;
        self.error = Some(report);
    }
    fn partial(_: &SceneError) -> Option<Self> {
        None
    }
}

impl FieldScene {
    /// Run the scene and summarise it.
    ///
    /// `progress` allows a progress bar on stderr over the time levels of a long run.
    pub fn run(&self, progress: bool) -> Result<FieldSummary, SceneError> {
        visit_field_model(
            &self.model,
            FieldRun {
                scene: self,
                progress,
            },
        )
        .unwrap_or_else(|| {
            Err(SceneError::UnknownModel(UnknownModel {
                name: self.model.clone(),
            }))
        })
    }
}

/// Runs a field scene on the model it is handed.
struct FieldRun<'a> {
    progress: bool,
    scene: &'a FieldScene,
}

impl FieldModelVisitor for FieldRun<'_> {
    type Output = Result<FieldSummary, SceneError>;

    fn visit<M: FieldZooModel>(self, mut model: M) -> Self::Output {
        let scene = self.scene;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let points = scene.mesh.points.unwrap_or_else(|| model.default_points());
        let (h, levels) = time_levels(&scene.run, model.default_step(), model.default_horizon())?;
        let quadrature = scene.mesh.quadrature.unwrap_or(QuadratureName::Trapezoid);
        let mut options = MultisymplecticOptions::default();
        options.quadrature = quadrature.quadrature();
        options.multisymplectic_check = scene.output.multisymplectic_check.unwrap_or(true);
        let mesh = Mesh::new(model.domain(), points, h, model.boundary())?;
        let xs: Vec<f64> = (0..points).map(|n| mesh.x(n)).collect();
        let dx = mesh.dx();
        let integrator = Multisymplectic::new(model.clone(), mesh, options)?;

        let every = scene.output.every.unwrap_or(1);
        let mut csv = field_stream(scene.output.trajectory.as_ref(), "t,x,u\n")?;
        let mut write_error = None;
        let mut error_max = 0.0f64;
        let bar = self
            .progress
            .then(|| Progress::for_levels(levels, points))
            .flatten();
        let start = Instant::now();
        let run = integrator.run(
            0.0,
            |x| model.initial_field(x),
            levels,
            |level, t, u| {
                if let Some(bar) = &bar {
                    bar.advance(level);
                }
                for (x, value) in xs.iter().zip(u) {
                    error_max = error_max.max((value[0] - model.exact_field(*x, t)[0]).abs());
                }
                let Some((_, stream)) = csv.as_mut() else {
                    return;
                };
                if write_error.is_some() || !(level % every == 0 || level == levels) {
                    return;
                }
                for (x, value) in xs.iter().zip(u) {
                    if let Err(error) = stream.write_row(t, |row| row.extend([t, *x, value[0]])) {
                        write_error = Some(error);
                        return;
                    }
                }
            },
        )?;
        let seconds = start.elapsed().as_secs_f64();
        if let Some(bar) = &bar {
            bar.finish();
        }
        let trajectory = finish_field_stream(csv, write_error, every)?;
        if let (Some(svg), Some(csv)) = (&scene.output.plot, &scene.output.trajectory) {
            plot_space_time(csv, svg, model.name())?;
        }
        let spread = |values: &[f64]| {
            values
                .iter()
                .map(|v| (v - values[0]).abs())
                .fold(0.0, f64::max)
        };
        let energy_initial = run.energy[0];
        let energy_error_max = spread(&run.energy);
        let mut warnings = health::check(&Measured {
            conserves_energy: true,
            energy_initial,
            energy_final: run.energy[run.energy.len() - 1],
            energy_error_max: Some(energy_error_max),
            energy_scale: energy_initial.abs(),
            extent: None,
            retries: 0,
        });
        let momentum_error_max = spread(&run.momentum);
        warnings.extend(health::non_finite(&[
            ("momentum_error_max", Some(momentum_error_max)),
            (
                "multisymplectic_residual_max",
                run.multisymplectic_residual_max,
            ),
            ("solution_error_max", Some(error_max)),
        ]));
        Ok(FieldSummary {
            model: model.name().into(),
            parameters: Parameters(model.parameters()),
            method: "multisymplectic",
            mesh_points: points,
            dx,
            h,
            steps: levels,
            t_end: levels as f64 * h,
            cell_rule: match options.quadrature {
                CellQuadrature::Trapezoid => "trapezoid",
                CellQuadrature::Midpoint => "midpoint",
            },
            explicit: run.explicit,
            energy_initial,
            energy_error_max,
            momentum_initial: run.momentum[0],
            momentum_error_max,
            multisymplectic_residual_max: run.multisymplectic_residual_max,
            solution_error_max: error_max,
            iterations: run.newton_iterations,
            seconds,
            trajectory,
            status: Status::Ok,
            warnings,
            error: None,
        })
    }
}
