//! `svi run` on a field scene ([`FieldScene`]): the model chosen by name
//! ([`svi_models::visit_field_model`]), its mesh, the multisymplectic integrator
//! ([`svi::field::multisymplectic::Multisymplectic`]) on a uniform mesh or the r-adaptive one
//! ([`svi::field::r_adaptive::RAdaptive`]) on a moving mesh, the field written as CSV while it
//! runs, and the [`FieldSummary`].
//!
//! The field CSV has the header `t,x,u` and one row per node and written time level (the
//! initial level, every `every`-th level and the last), levels in time order, nodes from
//! left to right (a periodic mesh does not repeat its first node at the right end). On a
//! moving mesh the header is `t,x,u,node`, with the node's index i = 0 … N in the last
//! column: the rows of one node are its path x_i(t). The run takes the whole number of steps
//! h that reaches t_end (the last level at or after it).

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::SVector;
use svi::field::mesh::Mesh;
use svi::field::multisymplectic::{CellQuadrature, Multisymplectic, MultisymplecticOptions};
use svi::field::r_adaptive::{RAdaptive, RAdaptiveOptions};
use svi_models::{FieldModelVisitor, FieldZooModel, UnknownModel, visit_field_model};

use crate::report::csv::{CsvStream, Float};
use crate::report::field::{FieldSummary, MovingMeshSummary};
use crate::report::health::{self, Measured, Warning};
use crate::report::plot::plot_space_time;
use crate::report::progress::Progress;
use crate::report::summary::{ErrorReport, Parameters, Status, TrajectoryOutput};
use crate::run::outcome::RunSummary;
use crate::scene::error::SceneError;
use crate::scene::field::{FieldRunSection, FieldScene, MovingMesh, QuadratureName};
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
        let run = Setup {
            scene,
            progress: self.progress,
            points,
            h,
            levels,
        };
        match scene.moving()? {
            None => run.uniform(model),
            Some(moving) => run.moving(model, moving),
        }
    }
}

/// A field run ready to start: the scene, the nodes, the step and the levels.
struct Setup<'a> {
    scene: &'a FieldScene,
    progress: bool,
    points: usize,
    h: f64,
    levels: usize,
}

impl Setup<'_> {
    /// The multisymplectic integrator on the uniform mesh.
    fn uniform<M: FieldZooModel>(&self, model: M) -> Result<FieldSummary, SceneError> {
        let scene = self.scene;
        let quadrature = scene.mesh.quadrature.unwrap_or(QuadratureName::Trapezoid);
        let mut options = MultisymplecticOptions::default();
        options.quadrature = quadrature.quadrature();
        options.multisymplectic_check = scene.output.multisymplectic_check.unwrap_or(true);
        let mesh = Mesh::new(model.domain(), self.points, self.h, model.boundary())?;
        let xs: Vec<f64> = (0..self.points).map(|n| mesh.x(n)).collect();
        let dx = mesh.dx();
        let integrator = Multisymplectic::new(model.clone(), mesh, options)?;
        let mut levels = self.writer("t,x,u\n")?;
        let start = Instant::now();
        let run = integrator.run(
            0.0,
            |x| model.initial_field(x),
            self.levels,
            |level, t, u| levels.level(&model, level, t, &xs, u, false),
        )?;
        let seconds = start.elapsed().as_secs_f64();
        let (error_max, trajectory) = levels.finish()?;
        self.plot(&model)?;
        Ok(self.summary(
            &model,
            Integrated {
                method: "multisymplectic",
                dx: Some(dx),
                cell_rule: options.quadrature,
                explicit: run.explicit,
                energy: &run.energy,
                momentum: &run.momentum,
                multisymplectic_residual_max: run.multisymplectic_residual_max,
                solution_error_max: error_max,
                iterations: run.newton_iterations,
                seconds,
                moving: None,
            },
            trajectory,
        ))
    }

    /// The r-adaptive integrator on the mesh that moves by `moving`'s monitor. Only the
    /// first and the last level are kept in memory: the others stream through the CSV.
    fn moving<M: FieldZooModel>(
        &self,
        model: M,
        moving: MovingMesh,
    ) -> Result<FieldSummary, SceneError> {
        let scene = self.scene;
        let quadrature = scene.mesh.quadrature.unwrap_or(QuadratureName::Midpoint);
        let mut options = RAdaptiveOptions::default();
        options.nodes = self.points;
        options.dt = self.h;
        options.monitor = moving.monitor;
        options.smoothing = moving.smoothing;
        options.quadrature = quadrature.quadrature();
        options.record_every = usize::MAX;
        let integrator = RAdaptive::new(model.clone(), model.domain(), model.boundary(), options)?;
        let mut levels = self.writer("t,x,u,node\n")?;
        let start = Instant::now();
        let run = integrator.run(
            0.0,
            |x| model.initial_field(x),
            self.levels,
            |level, t, x, u| levels.level(&model, level, t, x, u, true),
        )?;
        let seconds = start.elapsed().as_secs_f64();
        let (error_max, trajectory) = levels.finish()?;
        self.plot(&model)?;
        Ok(self.summary(
            &model,
            Integrated {
                method: "r-adaptive",
                dx: None,
                cell_rule: quadrature.quadrature(),
                explicit: false,
                energy: &run.energy,
                momentum: &run.momentum,
                multisymplectic_residual_max: None,
                solution_error_max: error_max,
                iterations: run.newton_iterations,
                seconds,
                moving: Some(MovingMeshSummary {
                    monitor: moving.name.name(),
                    smoothing: moving.smoothing,
                    smallest_width: run.smallest_width,
                }),
            },
            trajectory,
        ))
    }

    /// The writer of the levels, with the CSV's `header`.
    fn writer(&self, header: &str) -> Result<LevelWriter<'_>, SceneError> {
        let levels = self.levels;
        Ok(LevelWriter {
            csv: field_stream(self.scene.output.trajectory.as_ref(), header)?,
            write_error: None,
            every: self.scene.output.every.unwrap_or(1),
            levels,
            bar: self
                .progress
                .then(|| Progress::for_levels(levels, self.points))
                .flatten(),
            error_max: 0.0,
        })
    }

    /// The space-time picture of the written field, if the scene asks for one.
    fn plot<M: FieldZooModel>(&self, model: &M) -> Result<(), SceneError> {
        let output = &self.scene.output;
        if let (Some(svg), Some(csv)) = (&output.plot, &output.trajectory) {
            plot_space_time(csv, svg, model.name())?;
        }
        Ok(())
    }

    /// The summary of a run that ended well, with its health checks.
    fn summary<M: FieldZooModel>(
        &self,
        model: &M,
        run: Integrated<'_>,
        trajectory: Option<TrajectoryOutput>,
    ) -> FieldSummary {
        let spread = |values: &[f64]| {
            values
                .iter()
                .map(|v| (v - values[0]).abs())
                .fold(0.0, f64::max)
        };
        let energy_initial = run.energy[0];
        let energy_error_max = spread(run.energy);
        let mut warnings = health::check(&Measured {
            conserves_energy: true,
            energy_initial,
            energy_final: run.energy[run.energy.len() - 1],
            energy_error_max: Some(energy_error_max),
            energy_scale: energy_initial.abs(),
            extent: None,
            retries: 0,
        });
        let momentum_error_max = spread(run.momentum);
        let smallest_width = run.moving.as_ref().map(|moving| moving.smallest_width);
        warnings.extend(health::non_finite(&[
            ("momentum_error_max", Some(momentum_error_max)),
            (
                "multisymplectic_residual_max",
                run.multisymplectic_residual_max,
            ),
            ("solution_error_max", Some(run.solution_error_max)),
            ("smallest_width", smallest_width),
        ]));
        FieldSummary {
            model: model.name().into(),
            parameters: Parameters(model.parameters()),
            method: run.method,
            mesh_points: self.points,
            dx: run.dx,
            h: self.h,
            steps: self.levels,
            t_end: self.levels as f64 * self.h,
            cell_rule: match run.cell_rule {
                CellQuadrature::Trapezoid => "trapezoid",
                CellQuadrature::Midpoint => "midpoint",
            },
            explicit: run.explicit,
            energy_initial,
            energy_error_max,
            momentum_initial: run.momentum[0],
            momentum_error_max,
            multisymplectic_residual_max: run.multisymplectic_residual_max,
            solution_error_max: run.solution_error_max,
            iterations: run.iterations,
            seconds: run.seconds,
            trajectory,
            moving: run.moving,
            status: Status::Ok,
            warnings,
            error: None,
        }
    }
}

/// What an integrator measured over a run, for [`Setup::summary`].
struct Integrated<'a> {
    /// The method's name in the summary.
    method: &'static str,
    /// Δx of a uniform mesh.
    dx: Option<f64>,
    /// The cell quadrature.
    cell_rule: CellQuadrature,
    /// Whether the levels were solved explicitly.
    explicit: bool,
    /// The discrete energy of each slab.
    energy: &'a [f64],
    /// The discrete momentum of each slab.
    momentum: &'a [f64],
    /// The residual of the discrete multisymplectic law, where measured.
    multisymplectic_residual_max: Option<f64>,
    /// Largest |u − u_exact| over all nodes and levels.
    solution_error_max: f64,
    /// Newton iterations.
    iterations: usize,
    /// Wall time of the integration.
    seconds: f64,
    /// The moving mesh's part of the summary.
    moving: Option<MovingMeshSummary>,
}

/// What a run does at every time level: advance the progress bar, measure the error against
/// the exact field at the level's nodes, and write the level's rows to the field CSV.
struct LevelWriter<'a> {
    csv: Option<(&'a PathBuf, CsvStream)>,
    write_error: Option<std::io::Error>,
    every: usize,
    levels: usize,
    bar: Option<Progress>,
    error_max: f64,
}

impl LevelWriter<'_> {
    /// Level `level` at time t: the field `u` at the nodes `xs`; with `node_column` each row
    /// ends with the node's index (a moving mesh).
    fn level<M: FieldZooModel>(
        &mut self,
        model: &M,
        level: usize,
        t: f64,
        xs: &[f64],
        u: &[SVector<f64, 1>],
        node_column: bool,
    ) {
        if let Some(bar) = &self.bar {
            bar.advance(level);
        }
        for (x, value) in xs.iter().zip(u) {
            self.error_max = self
                .error_max
                .max((value[0] - model.exact_field(*x, t)[0]).abs());
        }
        let Some((_, stream)) = self.csv.as_mut() else {
            return;
        };
        if self.write_error.is_some() || !(level.is_multiple_of(self.every) || level == self.levels)
        {
            return;
        }
        for (node, (x, value)) in xs.iter().zip(u).enumerate() {
            let written = stream.write_row(t, |row| {
                row.extend([t, *x, value[0]]);
                if node_column {
                    row.push(node as f64);
                }
            });
            if let Err(error) = written {
                self.write_error = Some(error);
                return;
            }
        }
    }

    /// Close the progress bar and put the CSV in place: the largest error against the exact
    /// field and the trajectory output of the summary.
    fn finish(self) -> Result<(f64, Option<TrajectoryOutput>), SceneError> {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
        let trajectory = finish_field_stream(self.csv, self.write_error, self.every)?;
        Ok((self.error_max, trajectory))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::schema::to_value;
    use crate::run::error_report;
    use crate::scene::overrides::{Overrides, RunFlags};

    /// The built-in scene `name` with `parameters` (`--param`), `h`, `t_end` and the outputs
    /// `out` and `plot` from the command line.
    fn scene(
        name: &str,
        parameters: &[(&str, f64)],
        (h, t_end): (Option<f64>, f64),
        (out, plot): (Option<PathBuf>, Option<PathBuf>),
    ) -> FieldScene {
        let mut scene = FieldScene::load(name).unwrap().unwrap();
        scene
            .apply(&Overrides {
                run: RunFlags {
                    h,
                    t_end: Some(t_end),
                    ..RunFlags::default()
                },
                parameters: parameters
                    .iter()
                    .map(|(name, value)| (name.to_string(), *value))
                    .collect(),
                out,
                plot,
                ..Overrides::default()
            })
            .unwrap();
        scene
    }

    #[test]
    fn a_moving_mesh_follows_the_fast_kink_and_writes_the_node_paths() {
        let dir = tempfile::tempdir().unwrap();
        let (csv, svg) = (dir.path().join("kink.csv"), dir.path().join("kink.svg"));
        // The kink at v = 0.99 to t = 2 (40 levels) on 61 moving nodes (on 41 the level's
        // Newton iteration stops converging at t = 0.1 with α = 4).
        let summary = scene(
            "sine-gordon-kink-fast",
            &[("points", 61.0)],
            (None, 2.0),
            (Some(csv.clone()), Some(svg.clone())),
        )
        .run(false)
        .unwrap();
        // Measured: 0.0708 (a uniform mesh of 61 nodes: Δx = 0.67, wider than the kink,
        // γ⁻¹ = 0.14).
        assert!(
            summary.solution_error_max > 0.01 && summary.solution_error_max < 0.09,
            "{summary}"
        );
        assert_eq!(summary.steps, 40);
        assert!(summary.iterations > 40, "{summary}");
        let json = to_value(&summary).unwrap();
        assert_eq!(json["method"], "r-adaptive");
        assert_eq!(json["cell_rule"], "midpoint");
        assert_eq!(json["monitor"], "arc-length");
        assert_eq!(json["smoothing"], 2.0);
        assert!(json["dx"].is_null(), "{json}");
        assert!(json["multisymplectic_residual_max"].is_null(), "{json}");
        let width = json["smallest_width"].as_f64().unwrap();
        // The nodes crowd into the kink: its smallest cell is far below the uniform Δx = 1.
        assert!(width > 0.0 && width < 0.2, "{json}");
        assert_eq!(json["trajectory"]["rows"], 61 * 41);

        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,x,u,node"));
        let rows: Vec<Vec<f64>> = lines
            .map(|line| line.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 61 * 41);
        let mut moved = 0.0f64;
        for (level, nodes) in rows.chunks(61).enumerate() {
            let t = level as f64 * 0.05;
            for (i, row) in nodes.iter().enumerate() {
                assert!((row[0] - t).abs() < 1e-12, "level {level}: {row:?}");
                assert_eq!(row[3], i as f64, "level {level}: {row:?}");
            }
            assert_eq!((nodes[0][1], nodes[60][1]), (-20.0, 20.0), "level {level}");
            assert!(
                nodes.windows(2).all(|pair| pair[1][1] > pair[0][1]),
                "level {level}: the nodes are not in order"
            );
            moved = moved.max((nodes[30][1] - rows[30][1]).abs());
        }
        // The middle node moves with the kink (by vt = 1.98 at most).
        assert!(moved > 0.5 && moved < 4.0, "{moved}");

        let picture = std::fs::read_to_string(&svg).unwrap();
        assert!(picture.contains("lines: node paths"));
        assert!(picture.matches("<polygon").count() >= 40 * 40);
        assert!(
            picture.matches("<polyline").count() >= 41,
            "every node's path"
        );
    }

    /// A step far too long for the fast kink on 41 nodes (it moves 2 in one step, 14 times
    /// its width): the first level does not converge (measured).
    const FAILING_H: f64 = 2.0;

    #[test]
    fn a_uniform_mesh_keeps_its_summary_fields() {
        let summary = scene("phi4-kink", &[("points", 81.0)], (None, 0.5), (None, None))
            .run(false)
            .unwrap();
        let json = to_value(&summary).unwrap();
        assert_eq!(json["method"], "multisymplectic");
        assert_eq!(json["dx"], 0.5);
        for absent in ["monitor", "smoothing", "smallest_width"] {
            assert!(json.get(absent).is_none(), "{absent}: {json}");
        }
        assert!(summary.to_string().contains("81 points, dx = 0.5"));
    }

    #[test]
    fn a_moving_mesh_that_cannot_follow_ends_the_run_as_a_failure() {
        // Steps far too long for the fast kink: the level's Newton iteration or the mesh fails.
        let failed = scene(
            "sine-gordon-kink-fast",
            &[("points", 41.0)],
            (Some(FAILING_H), 20.0),
            (None, None),
        )
        .run(false)
        .unwrap_err();
        assert!(!failed.is_bad_input(), "{failed}");
        let report = error_report(&failed);
        assert!(
            ["mesh_fold", "non_convergence"].contains(&report.kind),
            "{report:?}"
        );
        assert!(report.step.is_some() && report.t.is_some(), "{report:?}");
    }
}
