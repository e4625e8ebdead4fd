//! `svi run`: integrate a scene and summarise it.

use std::fs::File;
use std::io::IsTerminal;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;

use svi::method::registry::VectorMethodVisitor;
use svi::observer::{EnergyError, Every, MomentumError, Observer, SolutionError, Trajectory};
use svi::solve::{SolveOptions, Span};
use svi::{
    Initial, Integrator, LagrangianExt, Method, MethodSpec, PhasePoint, RunFailure, RunOptions,
    Statistics,
};
use svi_models::{ModelVisitor, ZooModel, visit_model};

use crate::report::csv::{Float, csv_header};
use crate::report::progress::Progress;
use crate::report::summary::{
    AdaptivitySummary, OutputPoint, Parameters, Summary, TrajectoryOutput,
};
use crate::scene::overrides::Overrides;
use crate::scene::schema::{AdaptMode, Diagnostic};
use crate::scene::{Scene, SceneError};

impl Scene {
    /// Integrate the scene, write its trajectory if asked, and summarise. `progress` allows a
    /// progress bar on stderr for runs of at least [`PROGRESS_MIN_STEPS`] steps.
    pub fn run(&self, progress: bool) -> Result<Summary, SceneError> {
        self.check()?;
        visit_model(
            &self.model,
            RunScene {
                scene: self,
                progress,
            },
        )?
    }
}

/// Receives the model of a scene and runs it.
struct RunScene<'a> {
    scene: &'a Scene,
    progress: bool,
}

/// A scene resolved for a model of dimension `N`.
struct Setup<const N: usize> {
    t0: f64,
    initial: Initial<N>,
    h: f64,
    t_end: f64,
    energy: bool,
    momentum: bool,
    solution: bool,
    trajectory: Option<(PathBuf, usize)>,
    progress: bool,
    spec: MethodSpec,
    points: Option<usize>,
    quadrature: Option<usize>,
    options: RunOptions,
    adapt: AdaptMode,
    tol: Option<f64>,
    points_range: (Option<usize>, Option<usize>),
    output_times: Option<Vec<f64>>,
}

impl<const N: usize> Setup<N> {
    /// Whether the run goes through [`svi::solve()`] (adaptivity or output times) rather than
    /// the plain stepping loop.
    fn solves(&self) -> bool {
        self.adapt != AdaptMode::None || self.output_times.is_some()
    }
}

impl ModelVisitor for RunScene<'_> {
    type Output = Result<Summary, SceneError>;

    fn visit<M: ZooModel<N>, const N: usize>(self, mut model: M) -> Self::Output {
        let scene = self.scene;
        let (t0, initial, h, t_end) = scene.resolve(&mut model)?;
        let spec = scene.method_spec()?;
        let setup = Setup {
            t0,
            initial,
            h,
            t_end,
            energy: scene.wants(Diagnostic::Energy),
            momentum: scene.wants(Diagnostic::Momentum),
            solution: scene.wants(Diagnostic::Solution),
            trajectory: scene
                .output
                .trajectory
                .clone()
                .map(|path| (path, scene.output.every.unwrap_or(1))),
            progress: self.progress,
            spec,
            points: spec.points_in_use(),
            quadrature: spec.quadrature_in_use(),
            adapt: scene.run.adapt.unwrap_or_default(),
            tol: scene.run.tol,
            points_range: (scene.run.min_points, scene.run.max_points),
            output_times: scene.output.output_times.clone(),
            options: scene.run.options()?,
        };
        spec.visit_vector(RunWith {
            model,
            setup: &setup,
        })?
    }
}

/// Runs a scene's model with the visited method.
struct RunWith<'a, M, const N: usize> {
    model: M,
    setup: &'a Setup<N>,
}

impl<M: ZooModel<N>, const N: usize> VectorMethodVisitor<N> for RunWith<'_, M, N> {
    type Output = Result<Summary, SceneError>;
    fn visit<Me: Method<N> + Clone>(self, method: Me) -> Self::Output {
        run_with(self.model, method, self.setup)
    }
}

/// The diagnostics and outputs a run asked for.
type Observers<const N: usize> = (
    Option<EnergyError>,
    Option<MomentumError>,
    Option<SolutionError<N>>,
    Option<Every<Trajectory<N>>>,
);

/// What a run produced, whichever loop ran it.
struct Outcome<const N: usize> {
    statistics: Statistics,
    last: svi::PhasePoint<N>,
    adaptivity: Option<AdaptivitySummary>,
    outputs: Option<Vec<OutputPoint>>,
    seconds: f64,
}

/// Run `model` with `method`, observing only what `setup` asks for.
fn run_with<M: ZooModel<N>, Me: Method<N> + Clone, const N: usize>(
    model: M,
    method: Me,
    setup: &Setup<N>,
) -> Result<Summary, SceneError> {
    let integrator = Integrator::new(model, method);
    let model = integrator.model();
    let mut observers: Observers<N> = (
        setup.energy.then(EnergyError::default),
        (setup.momentum && model.generator_count() > 0).then(MomentumError::default),
        setup.solution.then(SolutionError::<N>::default),
        setup
            .trajectory
            .as_ref()
            .map(|(_, every)| Every::new(*every, Trajectory::<N>::new())),
    );
    let mut failure = None;
    let outcome = if setup.solves() {
        solve_scene(&integrator, setup, &mut observers)?
    } else {
        let mut progress = setup
            .progress
            .then(|| Progress::for_run(setup.t0, setup.h, setup.t_end))
            .flatten();
        let start = Instant::now();
        let run = integrator.try_run(
            setup.t0,
            setup.initial,
            setup.h,
            setup.t_end,
            &setup.options,
            &mut (&mut observers, &mut progress),
        );
        let seconds = start.elapsed().as_secs_f64();
        if let Some(progress) = &progress {
            progress.finish();
        }
        // A failed run still reports (and writes) everything up to its last good state.
        let run = match run {
            Ok(run) => run,
            Err(RunFailure {
                error,
                partial: Some(run),
            }) => {
                failure = Some(error);
                run
            }
            Err(RunFailure {
                error,
                partial: None,
            }) => return Err(error.into()),
        };
        Outcome {
            statistics: run.statistics,
            last: run.last,
            adaptivity: None,
            outputs: None,
            seconds,
        }
    };
    let (energy, momentum, solution, trajectory) = observers;

    let guess = match setup.initial {
        Initial::Velocity { v, .. } => v,
        Initial::Momentum { p, .. } => p,
    };
    let first = integrator.initial_state(setup.t0, &setup.initial)?;
    let first = integrator.phase_point(setup.t0, &first, &guess)?;
    let last = outcome.last;

    let trajectory = match (trajectory, &setup.trajectory) {
        (Some(Every { every, inner }), Some((path, _))) => {
            let mut rows = inner.points;
            if rows.last().is_none_or(|row| row.t != last.t) && setup.output_times.is_none() {
                rows.push(last);
            }
            write_trajectory(path, model, &rows)?;
            Some(TrajectoryOutput {
                path: path.display().to_string(),
                every,
                rows: rows.len(),
            })
        }
        _ => None,
    };

    let info = integrator.method().info();
    let summary = Summary {
        model: model.name().into(),
        parameters: Parameters(model.parameters()),
        coordinates: model.coordinate_names().iter().map(|&n| n.into()).collect(),
        method: setup.spec.name().into(),
        points: setup.points,
        quadrature: setup.quadrature,
        order: info.order,
        symmetric: info.symmetric,
        symplectic: info.symplectic,
        h: setup.h,
        t0: setup.t0,
        t_end: last.t,
        steps: outcome.statistics.steps,
        q: last.q.iter().copied().collect(),
        v: last.v.iter().copied().collect(),
        p: last.p.iter().copied().collect(),
        energy_initial: model.energy(first.t, &first.q, &first.v),
        energy_final: model.energy(last.t, &last.q, &last.v),
        energy_error_max: energy.map(|e| e.max),
        momentum_error_max: momentum.map(|m| m.max),
        solution_error_max: solution.and_then(|s| s.max),
        iterations: outcome.statistics.iterations,
        evaluations: outcome.statistics.evaluations,
        retries: outcome.statistics.retries,
        seconds: outcome.seconds,
        trajectory,
        adapt: setup.adapt.into(),
        tol: setup.tol,
        adaptivity: outcome.adaptivity,
        outputs: outcome.outputs,
    };
    match failure {
        None => Ok(summary),
        Some(source) => Err(SceneError::RunFailed {
            partial: Box::new(summary),
            source,
        }),
    }
}

/// Run a scene through [`svi::solve()`]: the observers see the initial point and the states
/// at the output times (every step's end when no output times are given).
fn solve_scene<M: ZooModel<N>, Me: Method<N> + Clone, const N: usize>(
    integrator: &Integrator<M, Me, svi::Euclidean<N>>,
    setup: &Setup<N>,
    observers: &mut Observers<N>,
) -> Result<Outcome<N>, SceneError> {
    let mut options = SolveOptions::default();
    options.adapt = setup.adapt.into();
    // Step control chooses its own first step from the initial state: a default step that is
    // far too large at a close approach can pass the step-doubling test pre-asymptotically.
    options.h = (setup.adapt != AdaptMode::Step).then_some(setup.h);
    options.tol = setup.tol;
    if let Some(points) = setup.points_range.0 {
        options.min_points = points;
    }
    if let Some(points) = setup.points_range.1 {
        options.max_points = points;
    }
    let span = match &setup.output_times {
        Some(times) => Span::with_outputs(setup.t0, setup.t_end, times.clone()),
        None => Span::new(setup.t0, setup.t_end),
    };
    let start = Instant::now();
    let solution = integrator.solve(&span, setup.initial, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    let model = integrator.model();
    let guess = match setup.initial {
        Initial::Velocity { v, .. } => v,
        Initial::Momentum { p, .. } => p,
    };
    let first = integrator.initial_state(setup.t0, &setup.initial)?;
    let first = integrator.phase_point(setup.t0, &first, &guess)?;
    let points = solution.points.iter().filter(|point| point.t > setup.t0);
    for (index, point) in std::iter::once(&first).chain(points).enumerate() {
        if Observer::<M, PhasePoint<N>>::wants(observers, index) {
            // Observers of a scene never stop a run.
            let _ = observers.observe(model, index, point);
        }
    }
    let adaptivity = &solution.adaptivity;
    let outputs = setup.output_times.as_ref().map(|_| {
        solution
            .points
            .iter()
            .map(|point| OutputPoint {
                t: point.t,
                q: point.q.iter().copied().collect(),
                v: point.v.iter().copied().collect(),
                p: point.p.iter().copied().collect(),
            })
            .collect()
    });
    Ok(Outcome {
        statistics: solution.statistics,
        last: solution.last,
        adaptivity: Some(AdaptivitySummary {
            accepted: adaptivity.accepted,
            rejected: adaptivity.rejected,
            min_step: adaptivity.min_step,
            max_step: adaptivity.max_step,
            points_used: adaptivity.points.clone(),
            unmet: adaptivity.unmet,
            outputs: solution.points.len(),
        }),
        outputs,
        seconds,
    })
}

/// Write `rows` as CSV: `t,q_<name>…,v_<name>…,p_<name>…,energy`, full precision.
fn write_trajectory<M: ZooModel<N>, const N: usize>(
    path: &Path,
    model: &M,
    rows: &[PhasePoint<N>],
) -> Result<(), SceneError> {
    let write = || -> std::io::Result<()> {
        let mut out = BufWriter::new(File::create(path)?);
        out.write_all(csv_header(&model.coordinate_names()).as_bytes())?;
        for point in rows {
            let energy = point.p.dot(&point.v) - model.value(point.t, &point.q, &point.v);
            write!(out, "{}", Float(point.t))?;
            for x in point.q.iter().chain(&point.v).chain(&point.p) {
                write!(out, ",{}", Float(*x))?;
            }
            writeln!(out, ",{}", Float(energy))?;
        }
        out.flush()
    };
    write().map_err(|source| SceneError::Write {
        path: path.into(),
        source,
    })
}

/// `svi run`: load the scene `name` (built-in or file), apply the command-line overrides (and
/// `--form`, rigid-body scenes only), run it and print its summary as text or JSON.
pub fn execute(
    name: &str,
    overrides: &Overrides,
    form: Option<&str>,
    json: bool,
) -> anyhow::Result<()> {
    if let Some(scene) = crate::rigid::RigidScene::load_if_rigid(name) {
        let mut scene = scene?;
        scene.apply(overrides, form)?;
        let summary = scene
            .run(std::io::stderr().is_terminal())
            .with_context(|| format!("scene '{name}' failed"))?;
        return print_summary(&summary, json);
    }
    anyhow::ensure!(
        form.is_none(),
        "--form applies to rigid-body scenes only (see svi list)"
    );
    let mut scene = Scene::load(name)?;
    scene.apply(overrides)?;
    let summary = scene
        .run(std::io::stderr().is_terminal())
        .with_context(|| format!("scene '{name}' failed"))?;
    print_summary(&summary, json)
}

/// Print a run's summary as one JSON object or as text.
fn print_summary<S: serde::Serialize + std::fmt::Display>(
    summary: &S,
    json: bool,
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(summary)?);
    } else {
        print!("{summary}");
    }
    Ok(())
}
