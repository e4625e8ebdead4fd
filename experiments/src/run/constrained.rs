//! The run path of a scene with holonomic constraints ([`crate::scene::constrained`]): a
//! Lagrangian written as text with `constraints = [...]`, run by
//! [`ConstrainedIntegrator`] with the scene's constrained method.
//!
//! The library's constrained integrator has a stepping loop of its own (not yet the one
//! [`svi::Integrator`] drives), so this path does what [`super::run_scene`] does around it: it
//! resolves the initial state (q and v or p, the step and the horizon of the scene), runs the
//! fixed grid t_k = t0 + k·h (a last step that does not fit is taken by a second call of one
//! shorter step, so the run lands on t_end as every fixed-step run does), observes every point
//! for the energy (E = p·q̇ − L, q̇ = M⁻¹p), the Noether momenta of the declared symmetries, the
//! trajectory (with the multipliers on request) and the progress bar, and assembles the one
//! [`Summary`] with the constraint diagnostics and a warning when the initial state was
//! projected. Nothing is allocated per step: the observer writes into buffers sized once.

use std::path::Path;
use std::time::Instant;

use nalgebra::DVector;
use svi::method::constrained::{ConstrainedIntegrator, ConstrainedPoint, ConstrainedRun};
use svi::model::constraint::{ConstraintsExt, Projected};
use svi::model::mass_inverse::MassInverse;
use svi::model::text::{TextConstraints, TextLagrangian, TextModel};
use svi::{Dyn, Initial, LagrangianExt, Symmetries};

use crate::report::csv::{CsvStream, Float, Recorded, csv_header};
use crate::report::health::{self, Measured, Warning};
use crate::report::plot::plot_csv;
use crate::report::progress::Progress;
use crate::report::summary::{
    Conservation, Parameters, SolveSummary, StateSummary, Status, Summary, TrajectoryOutput,
};
use crate::run::Control;
use crate::scene::schema::Diagnostic;
use crate::scene::{Scene, SceneError, vector};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

/// The Lagrangians the constrained methods take: ½q̇ᵀMq̇ − V(q), autonomous and unforced
/// (the scene's check has made sure the text is one).
type Model = TextLagrangian<Dyn, false, false, true>;

/// Initial data moved by less than this, relative to its size (at least 1), is taken as on
/// the constraints already (the round-off of 16 digits written in a scene) and not warned of.
pub const PROJECTION_TOLERANCE: f64 = 1e-12;

/// Run the scene with constraints `scene` (checked) of the text model `text`, watched by
/// `control`: the summary, or the error — with the summary up to the last good state for a
/// run that failed after it started ([`SceneError::RunFailed`]).
pub(super) fn run(
    scene: &Scene,
    control: Control<'_>,
    text: TextModel,
) -> Result<Summary, SceneError> {
    let method = scene.constrained_method()?;
    let constraints = text.constraints();
    let count = constraints.texts().len();
    let coordinates: Vec<String> = text
        .coordinate_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let model = Model::new(text)?;
    let n = coordinates.len();
    let zero = DVector::zeros(n);
    let initial = vector::initial(&scene.initial, TextModel::NAME, zero.clone(), zero.clone())?;
    let t0 = scene.initial.t0.unwrap_or(0.0);
    let needed = |value: Option<f64>, field| value.ok_or(SceneError::TextModelNeeds { field });
    let (h, t_end) = (
        needed(scene.run.h, "run.h")?,
        needed(scene.run.t_end, "run.t_end")?,
    );
    let grid = Grid::of(t0, t_end, h, scene.run.max_steps)?;
    let (q0, p0, velocity_given) = match initial {
        Initial::Velocity { q, v } => {
            let p = model.momentum(t0, &q, &v);
            (q, p, true)
        }
        Initial::Momentum { q, p } => (q, p, false),
    };
    let mass_inverse = model.mass_inverse(t0, &q0, &zero)?;
    let violated = violation(&constraints, &q0);
    let integrator = ConstrainedIntegrator::new(model, constraints, method.clone())?;
    let model = &integrator.model;
    let momenta = if scene.wants(Diagnostic::Momentum) {
        model.generator_count()
    } else {
        0
    };
    let mut watch = Watch {
        model,
        stop: control.stop,
        mass_inverse: &mass_inverse,
        velocity: zero.clone(),
        generator: zero,
        first: None,
        energy: f64::NAN,
        energy_error: scene.wants(Diagnostic::Energy).then_some(0.0),
        momenta: vec![0.0; momenta],
        momentum_error: (momenta > 0).then_some(0.0),
        trajectory: trajectory(scene, &coordinates, count)?,
        multipliers: scene.output.multipliers == Some(true),
        every: scene.output.every.unwrap_or(1),
        write_error: None,
        progress: control
            .progress
            .then(|| Progress::for_run(t0, h, t_end, n))
            .flatten(),
        last: ConstrainedPoint {
            t: t0,
            q: q0.clone(),
            p: p0.clone(),
            multipliers: DVector::zeros(count),
        },
        seen: 0,
        skip: false,
    };
    let start = Instant::now();
    let result = grid.run(&integrator, &q0, &p0, &mut watch);
    let seconds = start.elapsed().as_secs_f64();
    if let Some(progress) = &watch.progress {
        progress.finish();
    }
    let steps = watch.seen.saturating_sub(1);
    if control.stopped() {
        return Err(SceneError::Interrupted {
            at: format!("the run at t = {} after {steps} steps", Float(watch.last.t)),
        });
    }
    let (outcome, failure) = match result {
        Ok(outcome) => (Some(outcome), None),
        // Nothing observed: the input was refused before the first step (rank, projection).
        Err(error) if watch.seen == 0 => return Err(error.into()),
        Err(error) => (None, Some(error)),
    };
    if let Some(source) = watch.write_error.take() {
        return Err(write_failed(scene, source));
    }
    let (trajectory, recorded) = watch.finish(scene)?;
    if let (Some(svg), Some(csv)) = (&scene.output.plot, &scene.output.trajectory) {
        plot_csv(
            csv,
            svg,
            &format!("{} ({})", TextModel::NAME, method.name()),
        )?;
    }
    let Watch {
        last,
        velocity,
        energy: energy_final,
        ..
    } = watch;
    let (energy_initial, kinetic_initial) = watch.first.unwrap_or((f64::NAN, f64::NAN));
    let energy_scale = energy_initial
        .abs()
        .max(kinetic_initial)
        .max(energy_final.abs())
        .max(0.5 * last.p.dot(&velocity).abs());
    let initial = outcome.as_ref().map(|outcome| &outcome.initial);
    let mut warnings: Vec<Warning> = initial
        .and_then(|initial| {
            projection_warning(
                initial,
                (&q0, &p0),
                velocity_given.then_some(&mass_inverse),
                &violated,
            )
        })
        .into_iter()
        .collect();
    let energy_error_max = watch.energy_error;
    let conservation = Conservation::Constrained {
        momentum_error_max: watch.momentum_error,
        solution_error_max: None,
        solution_error_final: None,
        constraints: integrator.constraints.texts().to_vec(),
        constraint_error_max: outcome.as_ref().map(|o| o.constraint_error_max),
        velocity_constraint_error_max: outcome.as_ref().map(|o| o.velocity_constraint_error_max),
        initial_q_moved: initial.map_or(0.0, |i| i.moved_q),
        initial_p_moved: initial.map_or(0.0, |i| i.moved_p),
    };
    warnings.extend(health::check(&Measured {
        conserves_energy: true,
        energy_initial,
        energy_final,
        energy_error_max,
        energy_scale,
        extent: Some((q0.amax(), last.q.amax())),
        retries: 0,
    }));
    let mut numbers = conservation.numbers();
    numbers.push(("energy_error_max", energy_error_max));
    warnings.extend(health::non_finite(&numbers));
    let failure = failure.or_else(|| {
        (!(energy_initial.is_finite() && energy_final.is_finite() && energy_scale.is_finite()))
            .then(|| svi::Error::NonFinite {
                what: "energy (the initial or the final state overflows it)".into(),
                step: steps,
                t: last.t,
            })
    });
    let iterations = outcome.as_ref().map_or(0, |o| o.iterations);
    let evaluations = outcome.as_ref().map_or(0, |o| o.evaluations);
    let factorizations = outcome.as_ref().map_or(0, |o| o.factorizations);
    let summary = Summary {
        model: TextModel::NAME.into(),
        parameters: Parameters(svi::Defaults::parameters(model)),
        coordinates: Some(coordinates),
        method: method.name(),
        form: None,
        points: None,
        quadrature: None,
        order: method.order(),
        symmetric: method.symmetric(),
        // Every constrained method is a variational integrator on the constraint manifold.
        symplectic: true,
        h,
        t0,
        t_end: last.t,
        steps,
        state: StateSummary::Vector {
            q: last.q.iter().copied().collect(),
            v: velocity.iter().copied().collect(),
            p: last.p.iter().copied().collect(),
        },
        energy_initial,
        energy_final,
        energy_error_max,
        energy_error_final: (energy_final - energy_initial).abs(),
        energy_scale,
        conservation,
        iterations,
        evaluations,
        factorizations,
        retries: Some(0),
        seconds,
        trajectory,
        solve: Some(SolveSummary {
            adapt: "none",
            monitor: None,
            tol: None,
            adaptivity: None,
            outputs: None,
        }),
        status: Status::Ok,
        warnings,
        error: None,
        recorded,
        dense: None,
        events: None,
        indicators: None,
        sensitivity: None,
    };
    super::ended(summary, failure)
}

/// The fixed grid of a constrained run: `full` steps of `h` from `t0`, then, when the span is
/// not a whole number of steps, one shorter step `last` landing on t_end.
struct Grid {
    t0: f64,
    h: f64,
    full: usize,
    last: Option<f64>,
}

impl Grid {
    /// The grid over [t0, t_end] of step `h` ([`svi::stepping::grid::grid_steps`]: its checks
    /// and count), of at most `max_steps` steps.
    fn of(t0: f64, t_end: f64, h: f64, max_steps: Option<usize>) -> Result<Grid, SceneError> {
        let steps = svi::stepping::grid::grid_steps(t0, t_end, h)?;
        if let Some(most) = max_steps
            && steps > most
        {
            return Err(SceneError::InvalidOption {
                option: "--max-steps (run.max_steps)",
                reason: format!(
                    "the fixed steps h = {} from t0 = {} to t_end = {} are {steps}, more than \
                     {most}",
                    Float(h),
                    Float(t0),
                    Float(t_end)
                ),
            });
        }
        let whole = svi::step_count(t_end - t0, h)? as f64 * h;
        let exact = ((t_end - t0) - whole).abs() <= 1e-9 * (t_end - t0);
        Ok(if exact {
            Grid {
                t0,
                h,
                full: steps,
                last: None,
            }
        } else {
            Grid {
                t0,
                h,
                full: steps - 1,
                last: Some(t_end - (t0 + (steps - 1) as f64 * h)),
            }
        })
    }

    /// Run `integrator` over the grid from (q0, p0), every point to `watch`.
    fn run(
        &self,
        integrator: &ConstrainedIntegrator<Model, TextConstraints>,
        q0: &DVector<f64>,
        p0: &DVector<f64>,
        watch: &mut Watch<'_>,
    ) -> Result<ConstrainedRun<Dyn>, svi::Error> {
        let mut run = integrator.run(self.t0, q0, p0, self.h, self.full, |point| {
            watch.observe(point)
        })?;
        if run.stopped {
            return Ok(run);
        }
        if let Some(h) = self.last {
            // The shorter last step, from the last point (on the constraints already: its
            // projection moves it by round-off, and its first point is not observed again).
            let (t, q, p) = (watch.last.t, watch.last.q.clone(), watch.last.p.clone());
            watch.skip = true;
            let tail = integrator
                .run(t, &q, &p, h, 1, |point| watch.observe(point))
                .map_err(|error| rebase(error, self.full))?;
            run.steps += tail.steps;
            run.iterations += tail.iterations;
            run.evaluations += tail.evaluations;
            run.factorizations += tail.factorizations;
            run.constraint_error_max = run.constraint_error_max.max(tail.constraint_error_max);
            run.velocity_constraint_error_max = run
                .velocity_constraint_error_max
                .max(tail.velocity_constraint_error_max);
            run.last = tail.last;
        }
        Ok(run)
    }
}

/// A step failure of the last, shorter step, counted from the start of the run (its step
/// index is `offset` further).
fn rebase(error: svi::Error, offset: usize) -> svi::Error {
    match error {
        svi::Error::NonConvergence {
            step,
            t,
            iterations,
            residual,
        } => svi::Error::NonConvergence {
            step: step + offset,
            t,
            iterations,
            residual,
        },
        svi::Error::SingularMatrix { step, t } => svi::Error::SingularMatrix {
            step: step + offset,
            t,
        },
        other => other,
    }
}

/// What the run observes at every point, in buffers sized once.
struct Watch<'a> {
    model: &'a Model,
    /// The caller's stop flag, asked after every point.
    stop: Option<&'a AtomicBool>,
    mass_inverse: &'a MassInverse<Dyn>,
    /// q̇ = M⁻¹p of the last point.
    velocity: DVector<f64>,
    /// A symmetry generator's value (scratch).
    generator: DVector<f64>,
    /// E and ½|p·q̇| at the first point.
    first: Option<(f64, f64)>,
    /// E at the last point.
    energy: f64,
    /// Largest |E − E₀| so far (with the energy diagnostic).
    energy_error: Option<f64>,
    /// The Noether momenta at the first point (with the momentum diagnostic).
    momenta: Vec<f64>,
    /// Largest deviation of the Noether momenta so far.
    momentum_error: Option<f64>,
    trajectory: Option<CsvStream>,
    /// Whether the trajectory has the multipliers' columns.
    multipliers: bool,
    every: usize,
    /// The error of a failed trajectory write (the run goes on; it is reported after).
    write_error: Option<std::io::Error>,
    progress: Option<Progress>,
    /// The last point observed.
    last: ConstrainedPoint<Dyn>,
    /// Points observed (the initial point is the first).
    seen: usize,
    /// Skip the next point: the start of the last, shorter step, observed already.
    skip: bool,
}

/// `max` ← the larger of `max` and `value`, NaN winning (a NaN deviation is no bound).
fn raise(max: &mut f64, value: f64) {
    if value.is_nan() || value > *max {
        *max = value;
    }
}

impl Watch<'_> {
    /// See `point`: its energy and momenta, its trajectory row, the progress bar.
    /// Take `point`, and stop the run there if the stop flag is set.
    fn observe(&mut self, point: &ConstrainedPoint<Dyn>) -> ControlFlow<()> {
        self.take(point);
        if self.stop.is_some_and(|stop| stop.load(Ordering::Relaxed)) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    /// Take `point`: its energy, momenta and constraint numbers, and the trajectory's row.
    fn take(&mut self, point: &ConstrainedPoint<Dyn>) {
        if std::mem::take(&mut self.skip) {
            return;
        }
        let step = self.seen;
        self.seen += 1;
        self.mass_inverse.apply_into(&point.p, &mut self.velocity);
        let twice_kinetic = point.p.dot(&self.velocity);
        let energy = twice_kinetic - self.model.value(point.t, &point.q, &self.velocity);
        self.energy = energy;
        let (energy_initial, _) = *self
            .first
            .get_or_insert((energy, 0.5 * twice_kinetic.abs()));
        if let Some(error) = &mut self.energy_error {
            raise(error, (energy - energy_initial).abs());
        }
        if let Some(error) = &mut self.momentum_error {
            for (index, initial) in self.momenta.iter_mut().enumerate() {
                self.model.model().generator_into(
                    index,
                    point.q.as_slice(),
                    self.generator.as_mut_slice(),
                );
                let momentum = point.p.dot(&self.generator);
                if step == 0 {
                    *initial = momentum;
                } else {
                    raise(error, (momentum - *initial).abs());
                }
            }
        }
        if let Some(progress) = &self.progress {
            progress.advance(step);
        }
        self.last.t = point.t;
        self.last.q.copy_from(&point.q);
        self.last.p.copy_from(&point.p);
        self.last.multipliers.copy_from(&point.multipliers);
        if step.is_multiple_of(self.every)
            && self.write_error.is_none()
            && let Some(stream) = &mut self.trajectory
        {
            let (velocity, multipliers) = (&self.velocity, self.multipliers);
            let written = stream.write_row(point.t, |row| {
                Watch::row(point, velocity, energy, multipliers, row);
            });
            self.write_error = written.err();
        }
    }

    /// One trajectory row: t, q, v, p, the energy, and the multipliers if asked.
    fn row(
        point: &ConstrainedPoint<Dyn>,
        velocity: &DVector<f64>,
        energy: f64,
        multipliers: bool,
        row: &mut Vec<f64>,
    ) {
        row.push(point.t);
        row.extend(point.q.iter().chain(velocity).chain(&point.p));
        row.push(energy);
        if multipliers {
            row.extend(point.multipliers.iter());
        }
    }

    /// The trajectory: the last point written if the thinning skipped it, the file put in
    /// place (or the rows kept in memory).
    fn finish(
        &mut self,
        scene: &Scene,
    ) -> Result<(Option<TrajectoryOutput>, Option<Recorded>), SceneError> {
        let Some(mut stream) = self.trajectory.take() else {
            return Ok((None, None));
        };
        if self.seen > 0 && stream.last_time() != Some(self.last.t) {
            let (last, velocity) = (&self.last, &self.velocity);
            let (energy, multipliers) = (self.energy, self.multipliers);
            stream
                .write_row(last.t, |row| {
                    Watch::row(last, velocity, energy, multipliers, row);
                })
                .map_err(|source| write_failed(scene, source))?;
        }
        let (rows, recorded) = stream.finish()?;
        let path = scene
            .output
            .trajectory
            .as_deref()
            .map_or_else(String::new, |path| path.display().to_string());
        let output = TrajectoryOutput {
            path,
            every: self.every,
            rows,
        };
        Ok((recorded.is_none().then_some(output), recorded))
    }
}

/// The trajectory of `scene`, if it asks for one: its CSV file (created now, so an unwritable
/// path is reported before any step) or rows kept in memory, with the columns of an ODE run
/// and, with `output.multipliers`, `lambda_1` … `lambda_m` for `count` constraints.
fn trajectory(
    scene: &Scene,
    coordinates: &[String],
    count: usize,
) -> Result<Option<CsvStream>, SceneError> {
    let mut header = csv_header(coordinates);
    if scene.output.multipliers == Some(true) {
        header.pop();
        for i in 1..=count {
            header.push_str(&format!(",lambda_{i}"));
        }
        header.push('\n');
    }
    Ok(match (&scene.output.trajectory, scene.output.record) {
        (_, true) => Some(CsvStream::in_memory(&header)),
        (Some(path), false) => Some(CsvStream::create(
            "--out (output.trajectory)",
            path,
            &header,
        )?),
        (None, false) => None,
    })
}

/// A failed write of the trajectory file.
fn write_failed(scene: &Scene, source: std::io::Error) -> SceneError {
    SceneError::Write {
        path: scene
            .output
            .trajectory
            .clone()
            .unwrap_or_else(|| Path::new("").into()),
        source,
    }
}

/// The largest |gᵢ(q)| and the constraint's name.
fn violation(constraints: &TextConstraints, q: &DVector<f64>) -> (f64, String) {
    let values = ConstraintsExt::<Dyn>::values(constraints, q);
    let (index, value) = values
        .iter()
        .enumerate()
        .fold((0, 0.0_f64), |(best, size), (i, g)| {
            if g.abs() > size {
                (i, g.abs())
            } else {
                (best, size)
            }
        });
    (
        value,
        svi::model::constraint::Constraints::<Dyn>::constraint_name(constraints, index),
    )
}

/// The warning of initial data that the projection moved by more than round-off
/// ([`PROJECTION_TOLERANCE`]): how far q₀ and p₀ (or v₀, when the scene gave a velocity, with
/// M⁻¹ `mass_inverse`) moved, and how far q₀ was off the constraints (`violated`: the largest
/// |g(q₀)| and its constraint).
fn projection_warning(
    initial: &Projected<Dyn>,
    (q0, p0): (&DVector<f64>, &DVector<f64>),
    mass_inverse: Option<&MassInverse<Dyn>>,
    (violation, worst): &(f64, String),
) -> Option<Warning> {
    let moved_q = initial.moved_q > PROJECTION_TOLERANCE * q0.amax().max(1.0);
    let moved_p = initial.moved_p > PROJECTION_TOLERANCE * p0.amax().max(1.0);
    if !(moved_q || moved_p) {
        return None;
    }
    let velocity = mass_inverse.map(|inverse| {
        let mut moved = DVector::zeros(p0.len());
        inverse.apply_into(&(&initial.p - p0), &mut moved);
        moved.norm()
    });
    let rate = match velocity {
        Some(moved) => format!("v0 by {moved:.3e}"),
        None => format!("p0 by {:.3e}", initial.moved_p),
    };
    Some(Warning {
        kind: "projection",
        message: format!(
            "the initial state is off the constraints, so it was projected onto them: q0 moved \
             by {:.3e} onto g(q) = 0 (|g(q0)| was {violation:.3e}, largest for '{worst}') and \
             {rate} onto the velocities they allow (G q' = 0); the run starts from the projected \
             state (summary: initial_q_moved, initial_p_moved)",
            initial.moved_q,
        ),
    })
}
