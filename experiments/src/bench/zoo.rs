//! The sweep of a zoo model of fixed size, received as its concrete type: its problem, then
//! each method's sweep — the library's in its mode, the mollified impulse method, the
//! adaptive peers.

use indicatif::ProgressBar;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, SVector, U1};
use svi::method::registry::VectorMethodVisitor;
use svi::observer::{EnergyError, MomentumError};
use svi::{Dimension, Initial, Integrator, LagrangianExt, Method};
use svi_models::{ModelVisitor, ZooModel};

use crate::bench::adaptive::sweep_adaptive;
use crate::bench::method::{BenchMethod, Mode, run_mode};
use crate::bench::molly;
use crate::bench::options::BenchOptions;
use crate::bench::problem::{Problem, resolved_reference};
use crate::bench::record::{Record, Sweeps};
use crate::bench::sweep::{
    Outcomes, Report, Stall, check_horizon, measure_requested, median_seconds, sweep_steps,
};
use crate::scene::{Scene, SceneError};

/// Receives the scene's model and sweeps the methods on it.
pub(super) struct Bench<'a> {
    pub(super) scene: &'a Scene,
    pub(super) options: &'a BenchOptions,
    pub(super) progress: &'a ProgressBar,
}

impl ModelVisitor for Bench<'_> {
    type Output = Result<Sweeps, SceneError>;

    fn visit<M: ZooModel<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (t0, initial, _, t_end) = self.scene.resolve(&mut model)?;
        check_horizon(t0, t_end, model.default_step())?;
        let run = self.scene.run.options()?;
        let (q0, v0) = match initial {
            Initial::Velocity { q, v } => (q, v),
            Initial::Momentum { q, p } => {
                let v = model.velocity(t0, &q, &p, &p)?;
                (q, v)
            }
        };
        let coordinate = match &self.options.coordinate {
            None => None,
            Some(name) => {
                let names = model.coordinate_names();
                let index = names
                    .iter()
                    .position(|known| known == name)
                    .ok_or_else(|| SceneError::InvalidOption {
                        option: "--coordinate",
                        reason: format!(
                            "'{name}' is not a coordinate of {} (its coordinates: {})",
                            model.name(),
                            names.join(", ")
                        ),
                    })?;
                Some(index)
            }
        };
        let exact = match model.exact_solution(t0, &q0, &v0, t_end) {
            Some((q, _)) => q,
            None => {
                let (q, discrepancy) = resolved_reference(&model, t0, &q0, &v0, t_end)?;
                if self.options.verbose {
                    self.progress.suspend(|| {
                        eprintln!(
                            "reference: svi:7/6 at h = {:e}, {discrepancy:.1e} from the run at \
                             twice the step",
                            0.5 * model.default_step()
                        )
                    });
                }
                q
            }
        };
        let problem = Problem {
            t0,
            q0,
            v0,
            t_end,
            exact,
            coordinate,
            run,
        };
        let mut outcomes = Outcomes::default();
        for spec in &self.options.methods {
            let label = spec.to_string();
            self.progress.set_message(label.clone());
            let report = Report {
                verbose: self.options.verbose,
                progress: self.progress,
            };
            let sweep = |mode| Sweep {
                model: &model,
                label: &label,
                mode,
                problem: &problem,
                options: self.options,
                report,
            };
            let mut records = Vec::new();
            let swept = match (Mode::of(spec), spec) {
                (Some((method, mode)), _) => method
                    .vector_method()
                    .map(|any| sweep(mode).visit(any))
                    .map_err(SceneError::from)
                    .and_then(|swept| swept.map(|points| records.extend(points))),
                (None, BenchMethod::Molly) => {
                    sweep_molly(&model, &problem, self.options, report, &mut records)
                }
                (None, _) => {
                    sweep_adaptive(&model, *spec, &problem, self.options, report, &mut records)
                }
            };
            outcomes.add(&label, swept.map(|()| records), report)?;
            self.progress.inc(1);
        }
        outcomes.finish()
    }
}

/// Sweeps the visited library method in its mode.
struct Sweep<'a, M, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: &'a M,
    label: &'a str,
    mode: Mode,
    problem: &'a Problem<N>,
    options: &'a BenchOptions,
    report: Report<'a>,
}

impl<M: ZooModel<N>, N: Dimension> VectorMethodVisitor<N> for Sweep<'_, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Output = Result<Vec<Record>, SceneError>;
    fn visit<Me: Method<N> + Clone>(self, method: Me) -> Self::Output {
        let mut records = Vec::new();
        sweep_library(self, method, &mut records)?;
        Ok(records)
    }
}

/// Sweep a library method in its mode: over step counts (fixed steps, steps in τ) or
/// tolerances (step doubling).
fn sweep_library<M: ZooModel<N>, Me: Method<N> + Clone, N: Dimension>(
    sweep: Sweep<'_, M, N>,
    method: Me,
    records: &mut Vec<Record>,
) -> Result<(), SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let Sweep {
        model,
        label,
        mode,
        problem,
        options,
        report,
    } = sweep;
    let order = method.info().order.max(1) as f64;
    let integrator = Integrator::new(model.clone(), method);
    let span = problem.t_end - problem.t0;
    let from = (problem.start(), problem.t_end);
    // The scene's recovery and divergence limit, as `svi run` of the scene runs under them
    // (a chain's sweep runs the scene itself): the same scene, the same steps and numbers.
    let run = &problem.run;
    let final_error = |steps: usize| {
        run_mode(&integrator, mode, &from, span / steps as f64, run, &mut ())
            .map(|(q, _)| problem.error(&q))
    };
    // `parameter`: a step count, or a tolerance of step doubling.
    let measure = |parameter: f64| -> Result<Record, svi::Error> {
        let h = match mode {
            Mode::StepDoubling => parameter,
            _ => span / parameter,
        };
        let mut energy = EnergyError::default();
        let mut momentum = MomentumError::default();
        let (q, statistics) = if model.generator_count() > 0 {
            run_mode(
                &integrator,
                mode,
                &from,
                h,
                run,
                &mut (&mut energy, &mut momentum),
            )
        } else {
            run_mode(&integrator, mode, &from, h, run, &mut energy)
        }?;
        let seconds = median_seconds(
            || {
                let _ = run_mode(&integrator, mode, &from, h, run, &mut ());
            },
            options,
        );
        Ok(Record {
            method: label.to_string(),
            parameter,
            h: (!matches!(mode, Mode::StepDoubling)).then_some(h),
            steps: statistics.steps,
            final_error: problem.error(&q),
            energy_error_max: energy.max,
            momentum_error_max: (model.generator_count() > 0).then_some(momentum.max),
            evaluations: statistics.evaluations,
            iterations: statistics.iterations,
            seconds,
        })
    };
    if let Mode::StepDoubling = mode {
        if !options.tolerances.is_empty() {
            return measure_requested(
                label,
                &options.tolerances,
                "tolerance",
                measure,
                report,
                records,
            );
        }
        // 10^-3, 10^-3.5, …, 10^-15 (the smallest tolerance step doubling takes).
        let mut stall = Stall::default();
        for k in 0..=24 {
            let tol = 10f64.powf(-3.0 - 0.5 * f64::from(k));
            let record = match measure(tol) {
                Ok(record) => record,
                Err(error) => {
                    report.note(&format!("{label} at tolerance {tol:e}: {error}"));
                    continue;
                }
            };
            report.record(&record);
            let done = stall.ends_after(&record, options);
            records.push(record);
            if done {
                break;
            }
        }
        return Ok(());
    }
    sweep_steps(label, order, options, report, records, final_error, measure)
}

/// Sweep the mollified impulse method ([`molly`]) over step counts, as a fixed-step method
/// of order 2; a model other than the spring pendulum is an error naming `molly`. Its energy
/// error is measured at every step of a separate run, its evaluations are the slow-force
/// evaluations ([`molly::EVALUATIONS_PER_STEP`] per step).
fn sweep_molly<M: ZooModel<N>, N: Dimension>(
    model: &M,
    problem: &Problem<N>,
    options: &BenchOptions,
    report: Report<'_>,
    records: &mut Vec<Record>,
) -> Result<(), SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let pendulum = molly::spring_pendulum(model)?;
    // A model of dimension 2 ([`molly::spring_pendulum`]).
    let n = problem.q0.shape_generic().0;
    let position = |q: &SVector<f64, 2>| OVector::<f64, N>::from_fn_generic(n, U1, |i, _| q[i]);
    let start = molly::State::from_velocity(
        &pendulum,
        &SVector::from_fn(|i, _| problem.q0[i]),
        &SVector::from_fn(|i, _| problem.v0[i]),
    );
    let from = (problem.t0, start);
    let energy0 = start.energy(&pendulum);
    let final_error = |steps: usize| {
        molly::run(pendulum, from, problem.t_end, steps, |_| ())
            .map(|end| problem.error(&position(&end.position())))
    };
    let measure = |parameter: f64| -> Result<Record, svi::Error> {
        let steps = parameter as usize;
        let mut energy_error_max: f64 = 0.0;
        let end = molly::run(pendulum, from, problem.t_end, steps, |state| {
            energy_error_max = energy_error_max.max((state.energy(&pendulum) - energy0).abs());
        })?;
        let seconds = median_seconds(
            || {
                let _ = molly::run(pendulum, from, problem.t_end, steps, |_| ());
            },
            options,
        );
        Ok(Record {
            method: molly::NAME.into(),
            parameter,
            h: Some((problem.t_end - problem.t0) / parameter),
            steps,
            final_error: problem.error(&position(&end.position())),
            energy_error_max,
            momentum_error_max: None,
            evaluations: molly::EVALUATIONS_PER_STEP * steps,
            iterations: 0,
            seconds,
        })
    };
    sweep_steps(
        molly::NAME,
        2.0,
        options,
        report,
        records,
        final_error,
        measure,
    )
}
