//! `svi run`: the one run path, for scenes on every space.
//!
//! 1. The front door (the command line's `svi run`, the Python package) opens the scene
//!    ([`crate::scene::any::AnyScene::open`]), puts its overrides on top and checks it once
//!    ([`Scene::checked`]).
//! 2. [`Scene::run`] hands the scene's model, chosen by name at run time, to a visitor as its
//!    concrete type: [`svi_models::visit_model`] on ℝᴺ, [`svi_models::visit_local_model`] on
//!    runtime-sized ℝⁿ (chains, lattices; [`svi_models::visit_text_chain`] for a chain
//!    written as text), [`svi_models::visit_rigid_model`] on SO(3),
//!    [`svi_models::visit_group_model`] on the other Lie groups. The visitor resolves the
//!    initial state, the step and the horizon, builds the
//!    method (on ℝᴺ one [`svi::method::any::AnyMethod`] through
//!    [`svi::MethodSpec::vector_method`], so the run is compiled once per model; on a group
//!    the Lie-group integrator) and pairs both in an [`Integrator`].
//! 3. `run_scene`, generic over the space ([`RunSpace`]), builds the observers the scene
//!    asks for, runs [`Integrator::try_solve`] (fixed steps, step or degree adaptivity,
//!    output times, recovery, divergence limit: one call for all), writes the trajectory and
//!    assembles the one [`Summary`]. A run that fails after it started still writes its
//!    trajectory and reports its last good state ([`SceneError::RunFailed`]).
//!
//! A scene with holonomic constraints takes its own path (`constrained.rs`): the library's
//! constrained integrator with the scene's constrained method, observed for the same summary.

mod constrained;
mod control;
mod events;
pub mod field;
pub(crate) mod outcome;
mod sensitivity;
mod solver;
pub mod space;
pub mod spectral;
mod tangent;
mod trajectory;

pub use control::{Control, STOP_STRIDE};
pub use outcome::{AnySummary, RunSummary, error_report, failure_object};
pub use sensitivity::{LossAt, NativeLoss};

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::cell::RefCell;
use std::path::Path;
use std::time::Instant;
use svi::Dimension;

use svi::lie_group::{GroupIntegrator, RigidBodyIntegrator};
use svi::method::any::AnyMethod;
use svi::method::registry::{METHODS, SpaceKind, VectorMethodVisitor};
use svi::observer::Every;
use svi::solve::{SolveOptions, Span};
use svi::stepping::event::EventPoint;
use svi::stepping::run::RunFailure;
use svi::{Dyn, Integrator, LagrangianExt, Method, Statistics, Structure};
use svi_models::{
    AnyChain, GroupModelVisitor, GroupZooModel, LocalModelVisitor, LocalZooModel, ModelVisitor,
    RigidModelVisitor, RigidZooModel, ZooModel, visit_group_model, visit_local_model, visit_model,
    visit_rigid_model, visit_text_chain, visit_text_model,
};

use crate::report::csv::Float;
use crate::report::health::Warning;
use crate::report::health::{self, Measured};
use crate::report::output::{EVENTS, write_file};
use crate::report::plot::{plot_csv, plot_section};
use crate::report::progress::Progress;
use crate::report::summary::{
    AdaptivitySummary, ErrorReport, OutputPoint, Parameters, SolveSummary, Status, Summary,
};
use crate::run::control::Stop;
use crate::run::events::SceneEvents;
use crate::run::solver::{InTau, Solver};
use crate::run::space::{Chain, RunSpace};
use crate::run::tangent::TangentRun;
use crate::run::trajectory::TrajectoryStream;
use crate::scene::rigid::{METHOD_NAME, form_name};
use crate::scene::schema::{AdaptMode, RecoveryKind};
use crate::scene::{CheckedScene, Scene, SceneError, Text};

impl Scene {
    /// Check the scene ([`Scene::checked`]), integrate it, write its trajectory if asked, and
    /// summarise.
    pub fn run(&self, control: Control<'_>) -> Result<Summary, SceneError> {
        self.checked()?.run(control)
    }
}

impl CheckedScene<'_> {
    /// Integrate the scene, write its trajectory if asked, and summarise, watched by
    /// `control` (a progress bar, a stop flag).
    pub fn run(self, control: Control<'_>) -> Result<Summary, SceneError> {
        let run = SceneRun {
            scene: &self,
            control,
        };
        match self.space() {
            SpaceKind::Vector => match self.text() {
                Some(text) => match text? {
                    Text::Model(model) if self.is_constrained() => {
                        constrained::run(&self, control, model)
                    }
                    Text::Model(model) => visit_text_model(model, run)?,
                    Text::Chain(chain) => visit_text_chain(chain, run)?,
                },
                None if self.is_local() => visit_local_model(&self.model, run)
                    .unwrap_or_else(|| unreachable!("is_local: a runtime-dimension model")),
                None => sensitivity::with_sensitivity(&self, visit_model(&self.model, run)?),
            },
            SpaceKind::Group if self.is_rigid() => visit_rigid_model(&self.model, run)
                .unwrap_or_else(|| unreachable!("the space of a scene is its model's")),
            SpaceKind::Group => visit_group_model(&self.model, run)
                .unwrap_or_else(|| unreachable!("the space of a scene is its model's")),
        }
    }
}

/// A scene resolved for a model on the space `S`: what [`run_scene`] needs besides the
/// integrator.
struct Plan<'a, S: svi::method::space::Space> {
    scene: &'a Scene,
    control: Control<'a>,
    t0: f64,
    initial: S::Initial,
    h: f64,
    t_end: f64,
    /// The method as the summary names it.
    method: MethodFields,
    /// Warnings known before the run (a symmetry generator that is none).
    warnings: Vec<Warning>,
}

/// The method's fields of the summary that the built method does not tell.
struct MethodFields {
    name: String,
    form: Option<String>,
    points: Option<usize>,
    quadrature: Option<usize>,
}

impl MethodFields {
    /// The fields of the Lie-group integrator `lie_svi`, on every group.
    fn lie_svi(lie_svi: &svi::lie_group::LieSvi) -> MethodFields {
        MethodFields {
            name: METHOD_NAME.into(),
            form: Some(form_name(lie_svi.form).into()),
            points: Some(lie_svi.points),
            quadrature: Some(lie_svi.quadrature_points()),
        }
    }
}

/// Receives the model of a scene, on ℝᴺ or a Lie group, and runs it with the scene's method.
#[derive(Clone, Copy)]
struct SceneRun<'a> {
    scene: &'a Scene,
    control: Control<'a>,
}

impl<'a> SceneRun<'a> {
    /// The plan of a run from `t0` with `initial`, step `h` to `t_end`, by `method`.
    fn plan<S: svi::method::space::Space>(
        self,
        (t0, initial, h, t_end): (f64, S::Initial, f64, f64),
        method: MethodFields,
    ) -> Plan<'a, S> {
        Plan {
            scene: self.scene,
            control: self.control,
            t0,
            initial,
            h,
            t_end,
            method,
            warnings: Vec::new(),
        }
    }
}

impl ModelVisitor for SceneRun<'_> {
    type Output = Result<Summary, SceneError>;

    fn visit<M: ZooModel<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let resolved = self.scene.resolve(&mut model)?;
        let spec = self.scene.method_spec()?;
        let method = MethodFields {
            name: spec.name().into(),
            form: None,
            points: spec.points_in_use(),
            quadrature: spec.quadrature_in_use(),
        };
        let mut plan = self.plan(resolved, method);
        plan.warnings = symmetry_warnings(&model, plan.t0, &plan.initial);
        VectorMethod::<_, _, true> { model, plan }.visit(spec.vector_method()?)
    }
}

/// Largest relative variation of L along a symmetry generator accepted as a symmetry
/// ([`svi::LagrangianExt::symmetry_defect`]: round-off and the central difference give
/// about 1e-10).
const SYMMETRY_DEFECT: f64 = 1e-6;

/// A warning for each symmetry generator of `model` that is not a symmetry of L near the
/// initial state (at it and at two points around it): its "momentum error" would measure
/// nothing (a text model's `symmetries` are the user's claim).
fn symmetry_warnings<M: ZooModel<N>, N: Dimension>(
    model: &M,
    t0: f64,
    initial: &svi::Initial<N>,
) -> Vec<Warning>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (q, v) = match initial {
        svi::Initial::Velocity { q, v } => (q, v.clone()),
        svi::Initial::Momentum { q, p } => match model.velocity(t0, q, p, p) {
            Ok(v) => (q, v),
            Err(_) => return Vec::new(),
        },
    };
    // Two fixed points around the initial state, so that a state where δL vanishes by
    // accident (at rest, at the origin) does not pass a generator that is none.
    let n = q.shape_generic().0;
    let offset = |k: usize| {
        nalgebra::OVector::<f64, N>::from_fn_generic(n, nalgebra::U1, |i, _| {
            ((i + 1) as f64 * (0.7 + k as f64)).sin()
        })
    };
    let near = (q + offset(1) * 0.1, &v + offset(2));
    let far = (q + offset(3) * 0.2, &v - offset(4));
    let points = [(q.clone(), v), near, far];
    (0..model.generator_count())
        .filter_map(|index| {
            let defect = points
                .iter()
                .map(|(q, v)| model.symmetry_defect(index, t0, q, v))
                .fold(
                    0.0,
                    |worst: f64, d| if d.is_nan() { f64::NAN } else { worst.max(d) },
                );
            (defect.is_nan() || defect > SYMMETRY_DEFECT).then(|| Warning {
                kind: "symmetry",
                message: format!(
                    "the generator of {} is not a symmetry of L: near the initial state L \
                     changes along it by {defect:.1e} of its terms, so {} is not conserved and \
                     its momentum error measures nothing",
                    model.momentum_name(index),
                    model.momentum_name(index)
                ),
            })
        })
        .collect()
}

/// Runs a scene's model on ℝᴺ with the visited method. `IN_TAU`: whether the model may run in
/// computational time τ (`adapt = "reparam"`, models of fixed dimension): chains, which the
/// scene's checks refuse it, are compiled without that path (a copy of every method on the
/// reparametrised model, a twelfth of the command line's code).
struct VectorMethod<'a, M, N: Dimension, const IN_TAU: bool>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: M,
    plan: Plan<'a, svi::Euclidean<N>>,
}

impl<M: svi::Lagrangian<N>, N: Dimension, const IN_TAU: bool> VectorMethodVisitor<N>
    for VectorMethod<'_, M, N, IN_TAU>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
    svi::Euclidean<N>: RunSpace<M>,
{
    type Output = Result<Summary, SceneError>;
    fn visit<Me: Method<N> + Clone>(self, method: Me) -> Self::Output {
        let integrator = Integrator::new(self.model, method);
        let indicators = self.plan.scene.run.indicators.clone().unwrap_or_default();
        if !indicators.is_empty() {
            let solver = TangentRun {
                integrator: &integrator,
                asked: indicators,
                h: self.plan.h,
                found: RefCell::new(None),
            };
            run_scene(&self.plan, &solver)
        } else if IN_TAU && self.plan.scene.run.adapt == Some(AdaptMode::Reparam) {
            let monitor = self.plan.scene.monitor()?;
            let solver = InTau {
                integrator: &integrator,
                monitor,
            };
            run_scene(&self.plan, &solver)
        } else {
            run_scene(&self.plan, &integrator)
        }
    }
}

impl LocalModelVisitor for SceneRun<'_> {
    type Output = Result<Summary, SceneError>;

    /// A chain runs as a run-time-size Lagrangian of ℝⁿ ([`Chain`]) with the scene's method,
    /// as every other model does; a method that would hold a dense n × n matrix refuses a
    /// chain too large for it, naming itself and the size.
    fn visit<M: LocalZooModel>(self, mut model: M) -> Self::Output {
        let resolved = self.scene.resolve_local(&mut model)?;
        let spec = self.scene.method_spec()?;
        let method = MethodFields {
            name: spec.name().into(),
            form: None,
            points: spec.points_in_use(),
            quadrature: spec.quadrature_in_use(),
        };
        let plan = self.plan(resolved, method);
        run_chain(plan, model.into(), spec.vector_method()?)
    }
}

/// Runs a chain with `method` under the tightest declarations it allows, of three: the
/// methods are compiled once per declaration, not once per chain ([`Chain`]). A
/// time-dependent chain runs as general (correct for every chain; no chain of the zoo or
/// written as text is both time-dependent and constant-mass).
fn run_chain(
    plan: Plan<'_, svi::Euclidean<Dyn>>,
    chain: AnyChain,
    method: AnyMethod,
) -> Result<Summary, SceneError> {
    let view = chain.view();
    match (view.time_dependent(), view.structure()) {
        (false, Structure::ConstantMass) => run_declared::<false, true>(plan, chain, method),
        (false, Structure::General) => run_declared::<false, false>(plan, chain, method),
        (true, _) => run_declared::<true, false>(plan, chain, method),
    }
}

/// The library's methods on ℝⁿ that run `chain` at any size: those that keep its sparsity
/// ([`Method::keeps_sparsity`]) under the declarations [`run_chain`] runs it with. The others
/// hold dense matrices of the chain's size and refuse a chain too large for them
/// ([`svi::method::step::dense_size`]). In the registry's order.
pub fn methods_of_any_size(chain: AnyChain) -> Vec<&'static str> {
    let view = chain.view();
    let declarations = (view.time_dependent(), view.structure());
    match declarations {
        (false, Structure::ConstantMass) => sparse_methods(&Chain::<false, true>(chain)),
        (false, Structure::General) => sparse_methods(&Chain::<false, false>(chain)),
        (true, _) => sparse_methods(&Chain::<true, false>(chain)),
    }
}

/// The registry's methods on ℝⁿ, with their default options, that keep `model`'s sparsity.
fn sparse_methods<L: svi::Lagrangian<Dyn>>(model: &L) -> Vec<&'static str> {
    METHODS
        .iter()
        .filter(|entry| entry.space == SpaceKind::Vector)
        .filter(|entry| {
            entry
                .spec()
                .vector_method()
                .is_ok_and(|method| Method::<Dyn>::keeps_sparsity(&method, model))
        })
        .map(|entry| entry.name)
        .collect()
}

/// Runs a chain with `method` as a [`Chain`] of the declarations given.
fn run_declared<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool>(
    plan: Plan<'_, svi::Euclidean<Dyn>>,
    chain: AnyChain,
    method: AnyMethod,
) -> Result<Summary, SceneError> {
    VectorMethod::<_, _, false> {
        model: Chain::<TIME_DEPENDENT, CONSTANT_MASS>(chain),
        plan,
    }
    .visit(method)
}

impl RigidModelVisitor for SceneRun<'_> {
    type Output = Result<Summary, SceneError>;

    fn visit<M: RigidZooModel>(self, mut model: M) -> Self::Output {
        let resolved = self.scene.resolve_rigid(&mut model)?;
        let lie_svi = self.scene.lie_svi()?;
        let plan = self.plan(resolved, MethodFields::lie_svi(&lie_svi));
        let integrator = RigidBodyIntegrator::new(model, lie_svi);
        run_scene(&plan, &integrator)
    }
}

impl GroupModelVisitor for SceneRun<'_> {
    type Output = Result<Summary, SceneError>;

    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(
        self,
        mut model: M,
    ) -> Self::Output {
        let resolved = self.scene.resolve_group(&mut model)?;
        let lie_svi = self.scene.lie_svi()?;
        let plan = self.plan(resolved, MethodFields::lie_svi(&lie_svi));
        let integrator: GroupIntegrator<M, M::Group, N, E> = Integrator::new(model, lie_svi);
        run_scene(&plan, &integrator)
    }
}

/// The solve options of a scene: its adaptivity (step control chooses its own first step),
/// tolerance, degree bounds, recovery and divergence limit.
fn solve_options(scene: &Scene, h: f64) -> Result<SolveOptions, SceneError> {
    let run = &scene.run;
    let adapt = run.adapt.unwrap_or_default();
    let mut options = SolveOptions::default();
    options.adapt = adapt.into();
    // Step control chooses its own first step from the initial state: a default step that is
    // far too large at a close approach can pass the step-doubling test pre-asymptotically.
    options.h = (adapt != AdaptMode::Step).then_some(h);
    options.tol = tolerance(scene);
    if let Some(points) = run.min_points {
        options.min_points = points;
    }
    if let Some(points) = run.max_points {
        options.max_points = points;
    }
    if let Some(steps) = run.max_steps {
        options.max_steps = steps;
    }
    options.run = run.options()?;
    options.dense = scene.output.dense;
    Ok(options)
}

/// What a run produced, whether it reached the end or failed after it started.
struct Outcome<P> {
    last: P,
    statistics: Statistics,
    /// The adaptivity and the states at the output times (a run that reached the end).
    solved: Option<(svi::solve::Adaptivity, Vec<P>)>,
    /// The steps' polynomials, when the scene keeps them (a run that reached the end).
    dense: Option<svi::stepping::dense::DenseOutput>,
    /// The located events and the index of the terminal one (a run that reached the end).
    located: (Vec<EventPoint<P>>, Option<usize>),
}

/// The one run path: run `integrator` on the scene of `plan` through
/// [`Integrator::try_solve`], observing only what the scene asks for; write the trajectory
/// and summarise.
///
/// With fixed steps and no output times inside the span this is [`Integrator::try_run`]'s
/// loop: the same steps, points and statistics.
fn run_scene<L, S: RunSpace<L>>(
    plan: &Plan<'_, S>,
    solver: &dyn Solver<L, S>,
) -> Result<Summary, SceneError> {
    let scene = plan.scene;
    let model = solver.model();
    let (t0, t_end) = (plan.t0, plan.t_end);
    let adapt = scene.run.adapt.unwrap_or_default();
    let output_times = scene.output.output_times.as_ref();
    let every = scene.output.every.unwrap_or(1);
    let options = solve_options(scene, plan.h)?;
    // The trajectory file is opened before the first step and written as the run goes; with
    // output times it holds the states at those times (written after the run).
    let mut stream = match (&scene.output.trajectory, scene.output.record) {
        (Some(path), record) => Some(TrajectoryStream::<S>::create(model, path, record)?),
        (None, true) => Some(TrajectoryStream::<S>::create(model, Path::new(""), true)?),
        (None, false) => None,
    };
    let scene_events = SceneEvents::of::<L, S>(scene, model)?;
    let section = scene.output.section.is_some();
    // With output times or a section the file holds those points, written after the run.
    let trajectory = stream
        .as_mut()
        .filter(|_| output_times.is_none() && !section)
        .map(|stream| Every::new(every, stream));
    // The step count of step doubling and of steps in τ is not known ahead.
    let progress = (plan.control.progress
        && !matches!(adapt, AdaptMode::Step | AdaptMode::Reparam | AdaptMode::Sem))
    .then(|| Progress::for_run(t0, plan.h, t_end, S::coordinate_count(&plan.initial)))
    .flatten();
    let stop = plan.control.stop.map(Stop);
    let mut observers = (S::diagnostics(model, scene), trajectory, progress, stop);
    let span = match output_times {
        Some(times) => Span::with_outputs(t0, t_end, times.clone()),
        None => Span::new(t0, t_end),
    };
    let start = Instant::now();
    let events = scene_events.as_ref().map_or(&[][..], |e| &e.events[..]);
    let result = solver.solve(
        &span,
        plan.initial.clone(),
        &options,
        events,
        &mut observers,
    );
    let seconds = start.elapsed().as_secs_f64();
    let (diagnostics, _, progress, _) = observers;
    if let Some(progress) = &progress {
        progress.finish();
    }
    // A stopped run is no result (an observer of the run may have stopped it too: the flag
    // says which); its outputs are not written.
    if plan.control.stopped() {
        let (steps, t) = match &result {
            Ok(solution) => (solution.statistics.steps, S::time(&solution.last)),
            Err(failure) => failure
                .partial
                .as_ref()
                .map_or((0, t0), |run| (run.statistics.steps, S::time(&run.last))),
        };
        return Err(SceneError::Interrupted {
            at: format!("the run at t = {} after {steps} steps", Float(t)),
        });
    }
    // A failed run still reports (and writes) everything up to its last good state.
    let (outcome, failure) = match result {
        Ok(solution) => (
            Outcome {
                last: solution.last,
                statistics: solution.statistics,
                solved: Some((solution.adaptivity, solution.points)),
                dense: solution.dense,
                located: (solution.events, solution.terminal),
            },
            None,
        ),
        Err(RunFailure {
            error,
            partial: Some(run),
            events,
        }) => (
            Outcome {
                last: run.last,
                statistics: run.statistics,
                solved: None,
                dense: None,
                located: (events.into_vec(), None),
            },
            Some(error),
        ),
        Err(RunFailure {
            error,
            partial: None,
            ..
        }) => return Err(error.into()),
    };
    let last = outcome.last.clone();
    let first = solver.first_point(t0, &plan.initial, &S::initial_guess_at_rest(&plan.initial))?;

    let (events_summary, section_points) = match &scene_events {
        Some(scene_events) => {
            let (summary, points) =
                scene_events.sort::<L, S>(&outcome.located.0, outcome.located.1);
            (Some(summary), points)
        }
        None => (None, Vec::new()),
    };
    if let (Some(path), Some(events)) = (&scene.output.events, &events_summary) {
        let names = S::coordinates(model).unwrap_or_default();
        write_file(EVENTS, path, events.to_csv(&names).as_bytes())?;
    }
    let trajectory = match stream {
        Some(mut stream) => {
            if section {
                for point in &section_points {
                    stream.write(model, point)?;
                }
            } else if output_times.is_some() {
                // The initial point and the states at the output times.
                let outputs = outcome.solved.iter().flat_map(|(_, points)| points);
                let later = outputs.filter(|point| S::time(point) > t0);
                for point in std::iter::once(&first).chain(later) {
                    stream.write(model, point)?;
                }
            } else if stream.last_time() != Some(S::time(&last)) {
                // The last point, when the thinning skipped it.
                stream.write(model, &last)?;
            }
            Some(stream.finish(every)?)
        }
        None => None,
    };
    let (trajectory, recorded) = match trajectory {
        Some((output, recorded)) => (Some(output).filter(|_| recorded.is_none()), recorded),
        None => (None, None),
    };
    if let (Some(svg), Some(csv)) = (&scene.output.plot, &scene.output.trajectory) {
        let title = format!("{} ({})", scene.model, plan.method.name);
        match events_summary.as_ref().and_then(|e| e.section.as_ref()) {
            Some(section) => {
                let title = format!("{title}: section {}", section.surface);
                plot_section(&[csv.as_path()], svg, &title, &section.axes)?;
            }
            None => plot_csv(csv, svg, &title)?,
        }
    }

    let solves = adapt != AdaptMode::None || output_times.is_some();
    let solve = (S::LISTS_RUN_FIELDS || solves).then(|| solve_summary::<L, S>(scene, &outcome));
    let recovers = scene.run.recovery == Some(RecoveryKind::HalveStep);
    let (energy_error_max, conservation) = S::measured(model, diagnostics, &first, &last);
    let (energy_initial, energy_final) = (S::energy(model, &first), S::energy(model, &last));
    let energy_scale = S::energy_scale(model, &first).max(S::energy_scale(model, &last));
    // A state whose energy overflows (finite q and q̇ of 1e155 and more) is no result: the
    // run fails at its end rather than printing a null energy with status 0.
    let failure = failure.or_else(|| {
        (!(energy_initial.is_finite() && energy_final.is_finite() && energy_scale.is_finite()))
            .then(|| svi::Error::NonFinite {
                what: "energy (the initial or the final state overflows it)".into(),
                step: outcome.statistics.steps,
                t: S::time(&last),
            })
    });
    let mut warnings = plan.warnings.clone();
    warnings.extend(health::check(&Measured {
        conserves_energy: S::conserves_energy(model),
        energy_initial,
        energy_final,
        energy_error_max,
        energy_scale,
        extent: S::extent(&first).zip(S::extent(&last)),
        retries: outcome.statistics.retries,
    }));
    let mut numbers = conservation.numbers();
    numbers.push(("energy_error_max", energy_error_max));
    warnings.extend(health::non_finite(&numbers));
    let info = solver.info();
    let summary = Summary {
        model: S::model_name(model).into(),
        parameters: Parameters(S::parameters(model)),
        coordinates: S::coordinates(model),
        method: plan.method.name.clone(),
        form: plan.method.form.clone(),
        points: plan.method.points,
        quadrature: plan.method.quadrature,
        order: info.order,
        symmetric: info.symmetric,
        symplectic: info.symplectic,
        h: plan.h,
        t0,
        t_end: S::time(&last),
        steps: outcome.statistics.steps,
        state: S::state(&last),
        energy_initial,
        energy_final,
        energy_error_max,
        energy_error_final: (energy_final - energy_initial).abs(),
        energy_scale,
        conservation,
        iterations: outcome.statistics.iterations,
        evaluations: outcome.statistics.evaluations,
        factorizations: outcome.statistics.factorizations,
        retries: (S::LISTS_RUN_FIELDS || recovers).then_some(outcome.statistics.retries),
        seconds,
        trajectory,
        solve,
        status: Status::Ok,
        warnings,
        error: None,
        recorded,
        dense: outcome.dense,
        events: events_summary,
        indicators: solver.indicators(),
        sensitivity: None,
    };
    ended(summary, failure)
}

/// The tolerance of an adaptive run: the scene's, or without one the library's default;
/// `None` for fixed steps (in t or in τ).
fn tolerance(scene: &Scene) -> Option<f64> {
    let adaptive = matches!(
        scene.run.adapt.unwrap_or_default(),
        AdaptMode::Step | AdaptMode::Degree
    );
    adaptive
        .then(|| scene.run.tol.or(SolveOptions::default().tol))
        .flatten()
}

/// The adaptivity and output-time fields of a summary: what the adaptivity did (adaptive
/// runs and runs with output times that reached the end) and the states at the output times.
fn solve_summary<L, S: RunSpace<L>>(scene: &Scene, outcome: &Outcome<S::Point>) -> SolveSummary {
    let adapt = scene.run.adapt.unwrap_or_default();
    let output_times = scene.output.output_times.as_ref();
    let solves = adapt != AdaptMode::None || output_times.is_some();
    let solved = outcome.solved.as_ref().filter(|_| solves);
    SolveSummary {
        adapt: adapt.name(),
        monitor: (adapt == AdaptMode::Reparam)
            .then(|| scene.monitor().ok())
            .flatten()
            .map(|monitor| monitor.to_string()),
        tol: tolerance(scene),
        adaptivity: solved.map(|(adaptivity, points)| AdaptivitySummary {
            accepted: adaptivity.accepted,
            rejected: adaptivity.rejected,
            min_step: adaptivity.min_step,
            max_step: adaptivity.max_step,
            points_used: adaptivity.points.clone(),
            unmet: adaptivity.unmet,
            outputs: points.len(),
        }),
        outputs: output_times.map(|_| {
            let points = solved.iter().flat_map(|(_, points)| points);
            points
                .map(|point| OutputPoint {
                    t: S::time(point),
                    state: S::state(point),
                })
                .collect()
        }),
    }
}

/// The summary of a run that ended, or, with a `failure`, the error carrying it as the partial
/// summary up to the last good state.
fn ended(summary: Summary, failure: Option<svi::Error>) -> Result<Summary, SceneError> {
    match failure {
        None => Ok(summary),
        Some(source) => Err(SceneError::RunFailed {
            partial: Box::new(Summary {
                status: Status::Failed,
                error: Some(ErrorReport::of(&source)),
                ..summary
            }),
            source,
        }),
    }
}
