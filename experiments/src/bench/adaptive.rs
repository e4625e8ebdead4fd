//! The sweep of an adaptive peer (DOP853, Dopri5, Radau5) over tolerances, on the
//! first-order form of a model with N ≤ 3.

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::{Dimension, LagrangianExt};
use svi_models::ZooModel;

use crate::bench::method::BenchMethod;
use crate::bench::options::BenchOptions;
use crate::bench::peers::{
    FirstOrder, PeerRun, PeerSystem, RADAU5_TOLERANCE_FLOOR, dop853, dopri5, radau5, split,
    wired_for,
};
use crate::bench::problem::Problem;
use crate::bench::record::Record;
use crate::bench::sweep::{Report, Stall, median_seconds};
use crate::scene::SceneError;

/// One DOP853 / Dopri5 / Radau5 run to the horizon (`None` if it fails or stops short).
fn adaptive_run<M: ZooModel<N>, N: Dimension, const S: usize>(
    system: FirstOrder<'_, M, N, S>,
    spec: BenchMethod,
    problem: &Problem<N>,
    tol: f64,
) -> Option<PeerRun<S>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let y0 = ode_solvers::SVector::<f64, S>::from_iterator(
        problem.q0.iter().chain(problem.v0.iter()).copied(),
    );
    let (t0, t_end) = (problem.t0, problem.t_end);
    macro_rules! go {
        ($stepper:expr) => {{
            let mut stepper = $stepper;
            let stats = stepper.integrate().ok()?;
            let reached = *stepper.x_out().last()?;
            if (reached - t_end).abs() > 1e-9 * t_end.abs().max(1.0) {
                return None;
            }
            Some(PeerRun {
                steps: (stats.accepted_steps + stats.rejected_steps) as usize,
                evaluations: stats.num_eval as usize,
                iterations: 0,
                states: stepper.y_out().clone(),
            })
        }};
    }
    let system = PeerSystem::from(&system);
    match spec {
        BenchMethod::Dop853 => go!(dop853(system, t0, t_end, y0, tol)),
        BenchMethod::Radau5 => radau5(system, t0, t_end, y0.into(), tol),
        _ => go!(dopri5(system, t0, t_end, y0, tol)),
    }
}

/// Sweep an adaptive peer over tolerances (models with N ≤ 3).
pub(super) fn sweep_adaptive<M: ZooModel<N>, N: Dimension>(
    model: &M,
    spec: BenchMethod,
    problem: &Problem<N>,
    options: &BenchOptions,
    report: Report<'_>,
    records: &mut Vec<Record>,
) -> Result<(), SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    // `2 * N` is not a const expression on stable Rust: dispatch on the size at run time.
    match N::try_to_usize() {
        Some(1) => sweep_adaptive_sized::<M, N, 2>(model, spec, problem, options, report, records),
        Some(2) => sweep_adaptive_sized::<M, N, 4>(model, spec, problem, options, report, records),
        Some(3) => sweep_adaptive_sized::<M, N, 6>(model, spec, problem, options, report, records),
        _ => Err(not_wired::<N>(spec)),
    }
}

/// The error of a peer asked to run a model of a dimension it is not wired for.
fn not_wired<N: Dimension>(spec: BenchMethod) -> SceneError {
    SceneError::MethodNotApplicable {
        method: spec.to_string(),
        reason: format!("the peers are wired for {}", wired_for::<N>()),
    }
}

/// [`sweep_adaptive`] with the state size S = 2N as a type parameter.
fn sweep_adaptive_sized<M: ZooModel<N>, N: Dimension, const S: usize>(
    model: &M,
    spec: BenchMethod,
    problem: &Problem<N>,
    options: &BenchOptions,
    report: Report<'_>,
    records: &mut Vec<Record>,
) -> Result<(), SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let system = || FirstOrder::<M, N, S>::new(model, problem.t0, &problem.q0, &problem.v0);
    if system().is_none() {
        return Err(not_wired::<N>(spec));
    }
    let n = problem.q0.shape_generic().0;
    let energy0 = model.energy(problem.t0, &problem.q0, &problem.v0);
    let measure = |tol: f64| -> Option<Record> {
        let PeerRun {
            steps,
            evaluations,
            iterations,
            states,
        } = adaptive_run(system()?, spec, problem, tol)?;
        let (q, _) = split(n, states.last()?.as_slice());
        let energy_error_max = states
            .iter()
            .map(|y| {
                let (q, v) = split(n, y.as_slice());
                (model.energy(problem.t_end, &q, &v) - energy0).abs()
            })
            .fold(0.0, f64::max);
        let momentum_error_max = (model.generator_count() > 0).then(|| {
            let initial: Vec<f64> = (0..model.generator_count())
                .map(|i| model.noether_momentum(i, problem.t0, &problem.q0, &problem.v0))
                .collect();
            let mut largest: f64 = 0.0;
            for y in &states {
                let (q, v) = split(n, y.as_slice());
                for (i, start) in initial.iter().enumerate() {
                    largest = largest.max((model.noether_momentum(i, 0.0, &q, &v) - start).abs());
                }
            }
            largest
        });
        let seconds = median_seconds(
            || {
                let _ = system().and_then(|system| adaptive_run(system, spec, problem, tol));
            },
            options,
        );
        Some(Record {
            method: spec.to_string(),
            parameter: tol,
            h: None,
            steps,
            final_error: problem.error(&q),
            energy_error_max,
            momentum_error_max,
            evaluations,
            iterations,
            seconds,
        })
    };
    if !options.tolerances.is_empty() {
        for &tol in &options.tolerances {
            let record = measure(tol).ok_or_else(|| {
                SceneError::BenchParameter(format!(
                    "{spec} at tolerance {tol:e} did not reach the horizon"
                ))
            })?;
            report.record(&record);
            records.push(record);
        }
        return Ok(());
    }
    // Radau5 runs at the internal tolerance 0.1·tol^(2/3), and its error falls as about
    // tol^0.55: whole decades keep the √10-fold error reduction per point of the other
    // sweeps (per half decade its error would fall by 1.9, not the halving that tells a
    // sweep from one stalled at round-off).
    let decades_per_point = if spec == BenchMethod::Radau5 {
        1.0
    } else {
        0.5
    };
    let mut stall = Stall::default();
    for k in 0..=26 {
        let tol = 10f64.powf(-3.0 - decades_per_point * f64::from(k));
        if spec == BenchMethod::Radau5 && tol <= RADAU5_TOLERANCE_FLOOR {
            break;
        }
        // Loose tolerances can lose the orbit (Dopri5 on Kepler at T = 2000 stops short up to
        // tol ≈ 1e-4): reported and skipped, the sweep goes on.
        let Some(record) = measure(tol) else {
            report.note(&format!(
                "{spec} at tolerance {tol:e}: did not reach the horizon"
            ));
            continue;
        };
        report.record(&record);
        let done = stall.ends_after(&record, options);
        records.push(record);
        if done {
            break;
        }
    }
    Ok(())
}
