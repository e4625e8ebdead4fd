//! `svi run` on a pseudospectral scene ([`SpectralScene`]): the complex field model chosen by
//! name ([`svi_models::visit_spectral_model`]), its Fourier grid, the pseudospectral
//! integrator ([`svi::field::pseudospectral::Pseudospectral`]), the field written as CSV while
//! it runs, and the [`SpectralSummary`].
//!
//! The field CSV has the header `t,x,abs,re,im` and one row per node and written time level
//! (the initial level, every `every`-th level and the last), levels in time order, nodes from
//! left to right (the periodic grid does not repeat its first node). `--plot` draws |ψ| over
//! space and time. The run takes the whole number of steps h that reaches t_end.

use std::time::Instant;

use svi::field::fourier::Complex64;
use svi::field::pseudospectral::{Pseudospectral, PseudospectralOptions, TimeScheme};
use svi_models::{SpectralModelVisitor, SpectralZooModel, UnknownModel, visit_spectral_model};

use crate::report::health::{self, FieldMeasured, Warning};
use crate::report::plot::plot_space_time;
use crate::report::progress::Progress;
use crate::report::spectral::SpectralSummary;
use crate::report::summary::{ErrorReport, Parameters, Status};
use crate::run::field::{field_stream, finish_field_stream, time_levels};
use crate::run::outcome::RunSummary;
use crate::scene::error::SceneError;
use crate::scene::limits;
use crate::scene::spectral::{SpectralScene, scheme_name};

impl RunSummary for SpectralSummary {
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

impl SpectralScene {
    /// Run the scene and summarise it.
    ///
    /// `progress` allows a progress bar on stderr over the time levels of a long run.
    pub fn run(&self, progress: bool) -> Result<SpectralSummary, SceneError> {
        visit_spectral_model(
            &self.model,
            SpectralRun {
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

/// Runs a pseudospectral scene on the model it is handed.
struct SpectralRun<'a> {
    progress: bool,
    scene: &'a SpectralScene,
}

impl SpectralModelVisitor for SpectralRun<'_> {
    type Output = Result<SpectralSummary, SceneError>;

    fn visit<M: SpectralZooModel>(self, mut model: M) -> Self::Output {
        let scene = self.scene;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let scheme = scene.scheme()?;
        let points = scene.mesh.points.unwrap_or_else(|| model.default_points());
        let (h, steps) = time_levels(&scene.run, model.default_step(), model.default_horizon())?;
        let Prepared {
            mut integrator,
            nodes: xs,
            initial,
        } = prepare(&model, scheme, points, h)?;
        let dx = integrator.fourier().dx();

        let every = scene.output.every.unwrap_or(1);
        let mut csv = field_stream(scene.output.trajectory.as_ref(), "t,x,abs,re,im\n")?;
        let mut write_error = None;
        let (mut error_max, mut error_final) = (0.0f64, 0.0f64);
        let bar = self
            .progress
            .then(|| Progress::for_levels(steps, points))
            .flatten();
        let start = Instant::now();
        let run = integrator.run(0.0, &initial, steps, |level, t, psi| {
            if let Some(bar) = &bar {
                bar.advance(level);
            }
            error_final = error_against_exact(&model, &xs, t, psi);
            error_max = error_max.max(error_final);
            let Some((_, stream)) = csv.as_mut() else {
                return;
            };
            if write_error.is_some() || !(level % every == 0 || level == steps) {
                return;
            }
            for (x, value) in xs.iter().zip(psi) {
                let row = [t, *x, value.norm(), value.re, value.im];
                if let Err(error) = stream.write_row(t, |out| out.extend(row)) {
                    write_error = Some(error);
                    return;
                }
            }
        })?;
        let seconds = start.elapsed().as_secs_f64();
        if let Some(bar) = &bar {
            bar.finish();
        }
        let trajectory = finish_field_stream(csv, write_error, every)?;
        if let (Some(svg), Some(csv)) = (&scene.output.plot, &scene.output.trajectory) {
            plot_space_time(csv, svg, model.name())?;
        }
        let energy_error = (run.energy_final - run.energy_initial).abs();
        let size = initial.iter().map(|psi| psi.norm()).fold(0.0, f64::max);
        let mut warnings = health::check_field(&FieldMeasured {
            norm_error_relative: run.norm_error_max,
            energy: (energy_error, run.energy_initial.abs()),
            solution: (error_max, size),
        });
        warnings.extend(health::non_finite(&[
            ("norm_initial", Some(run.norm_initial)),
            ("energy_initial", Some(run.energy_initial)),
        ]));
        Ok(SpectralSummary {
            model: model.name().into(),
            parameters: Parameters(model.parameters()),
            method: scheme_name(scheme),
            order: scheme.order(),
            mesh_points: points,
            dx,
            h,
            steps,
            t_end: steps as f64 * h,
            norm_initial: run.norm_initial,
            norm_error_max: run.norm_error_max,
            energy_initial: run.energy_initial,
            energy_error_final: energy_error,
            solution_error_max: error_max,
            solution_error_final: error_final,
            ffts: run.ffts,
            iterations: run.iterations,
            seconds,
            trajectory,
            status: Status::Ok,
            warnings,
            error: None,
        })
    }
}

/// A run ready to start: the integrator, its nodes and the initial field there.
pub struct Prepared<M> {
    /// The integrator.
    pub integrator: Pseudospectral<M>,
    /// The nodes x_j.
    pub nodes: Vec<f64>,
    /// ψ(x_j, 0).
    pub initial: Vec<Complex64>,
}

/// The integrator of `model` with `scheme` on `points` Fourier modes and step `h`, the nodes,
/// and the initial field at the nodes.
pub fn prepare<M: SpectralZooModel>(
    model: &M,
    scheme: TimeScheme,
    points: usize,
    h: f64,
) -> Result<Prepared<M>, SceneError> {
    let stages = match scheme {
        TimeScheme::Galerkin { degree } => degree,
        TimeScheme::Strang => 1,
    };
    limits::check_memory(
        "points (--param points, or --method)",
        limits::spectral_memory(points, stages),
        &format!(
            "{} with {points} Fourier modes and {stages} stages",
            model.name()
        ),
    )?;
    let mut options = PseudospectralOptions::default();
    options.scheme = scheme;
    let integrator = Pseudospectral::new(
        model.clone(),
        model.domain(),
        model.boundary(),
        points,
        h,
        options,
    )?;
    let xs: Vec<f64> = (0..points).map(|j| integrator.fourier().x(j)).collect();
    let initial = xs
        .iter()
        .map(|&x| {
            let u = model.initial_field(x).0;
            Complex64::new(u[0], u[1])
        })
        .collect();
    Ok(Prepared {
        integrator,
        nodes: xs,
        initial,
    })
}

/// max_j |ψ_j − ψ_exact(x_j, t)|.
pub fn error_against_exact<M: SpectralZooModel>(
    model: &M,
    xs: &[f64],
    t: f64,
    psi: &[Complex64],
) -> f64 {
    xs.iter()
        .zip(psi)
        .map(|(&x, value)| {
            let exact = model.exact_field(x, t);
            (value - Complex64::new(exact[0], exact[1])).norm()
        })
        .fold(0.0, f64::max)
}
