//! Running the stress cases: each case's model and scene step, and for every method its
//! probes of the step limits and its long run (DOP853's as the non-geometric peer).

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::time::Instant;
use svi::drift::EnergyWindows;
use svi::method::registry::VectorMethodVisitor;
use svi::observer::{EnergyError, Every};
use svi::{Dimension, Error, Initial, Integrator, LagrangianExt, Method, RunOptions};
use svi_models::{ModelVisitor, ZooModel, visit_model};

use crate::bench::method::{BenchMethod, Mode, run_mode};
use crate::bench::peers::{FirstOrder, PeerSystem, dop853, split, wired_for};
use crate::scene::{Scene, SceneError};
use crate::stress::drift::{Drift, SAMPLES, WINDOWS, drift};
use crate::stress::options::{CASES, StressCase, StressOptions, peer_not_applicable};
use crate::stress::record::{StressRecord, summary_line};
use crate::stress::search::search;

/// Energy error, relative to max(|E₀|, 1), above which a step is not accurate.
const ACCURATE: f64 = 0.1;
/// Divergence limit relative to max(1, ‖x₀‖∞).
const DIVERGENCE: f64 = 1e3;

/// Run every case of `options` (see the module documentation).
pub fn stress(options: &StressOptions) -> Result<Vec<StressRecord>, SceneError> {
    options.check()?;
    let mut records = Vec::new();
    for case in CASES
        .iter()
        .filter(|case| options.cases.is_empty() || options.cases.iter().any(|c| c == case.scene))
    {
        let scene = Scene::builtin(case.scene).ok_or_else(|| SceneError::UnknownScene {
            name: case.scene.into(),
        })??;
        let rows = visit_model(
            &scene.model,
            CaseRunner {
                scene: &scene,
                case,
                options,
            },
        )??;
        records.extend(rows);
    }
    Ok(records)
}

/// Runs one case with the scene's model.
struct CaseRunner<'a> {
    scene: &'a Scene,
    case: &'a StressCase,
    options: &'a StressOptions,
}

/// A resolved case.
struct Setup<'a, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    scene: &'a str,
    probe_time: f64,
    t0: f64,
    initial: Initial<N>,
    h: f64,
    options: &'a StressOptions,
}

impl ModelVisitor for CaseRunner<'_> {
    type Output = Result<Vec<StressRecord>, SceneError>;

    fn visit<M: ZooModel<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (t0, initial, h, _) = self.scene.resolve(&mut model)?;
        let setup = Setup {
            scene: self.case.scene,
            probe_time: self.case.probe_time,
            t0,
            initial,
            h,
            options: self.options,
        };
        let mut rows = Vec::new();
        for spec in &self.options.methods {
            let label = spec.to_string();
            let start = Instant::now();
            let record = match (Mode::of(spec), spec) {
                (Some((method, mode)), _) => MethodRunner {
                    model: &model,
                    setup: &setup,
                    label: &label,
                    mode,
                }
                .visit(method.vector_method()?)?,
                (None, BenchMethod::Dop853) => StressRecord {
                    scene: setup.scene.into(),
                    method: label.clone(),
                    h,
                    bounded: None,
                    accurate: None,
                    drift: dop853_drift(&model, &setup),
                },
                (None, peer) => return Err(peer_not_applicable(*peer)),
            };
            if self.options.verbose {
                eprintln!(
                    "{:<30} {:<10} {:.1} s: {}",
                    setup.scene,
                    label,
                    start.elapsed().as_secs_f64(),
                    summary_line(&record)
                );
            }
            rows.push(record);
        }
        Ok(rows)
    }
}

/// Runs one case with the visited method in its mode.
struct MethodRunner<'a, M, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: &'a M,
    setup: &'a Setup<'a, N>,
    label: &'a str,
    mode: Mode,
}

impl<M: ZooModel<N>, N: Dimension> VectorMethodVisitor<N> for MethodRunner<'_, M, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Output = Result<StressRecord, SceneError>;

    fn visit<Me: Method<N> + Clone>(self, method: Me) -> Self::Output {
        let setup = self.setup;
        let integrator = Integrator::new(self.model.clone(), method);
        let first = integrator.initial_state(setup.t0, &setup.initial)?;
        let start = integrator.phase_point(setup.t0, &first, &first.y)?;
        let energy0 = integrator.model().energy(setup.t0, &start.q, &start.v);
        let scale = energy0.abs().max(1.0);
        let size = first.q.amax().max(first.y.amax()).max(1.0);
        let options = RunOptions::default().with_divergence_limit(DIVERGENCE * size);
        let mode = self.mode;
        let mut probes: Vec<(f64, Probe)> = Vec::new();
        let mut probe = |h: f64| -> Probe {
            if let Some((_, p)) = probes.iter().find(|(x, _)| *x == h) {
                return p.clone();
            }
            let mut energy = EnergyError::default();
            let from = (
                (setup.t0, setup.initial.clone()),
                setup.t0 + setup.probe_time,
            );
            let result = run_mode(&integrator, mode, &from, h, &options, &mut energy);
            let p = Probe {
                failure: result.err().map(|error| describe(&error)),
                energy_error: energy.max / scale,
            };
            probes.push((h, p.clone()));
            p
        };
        // Step doubling chooses its own steps: it has no step limit to search.
        let searched = !matches!(mode, Mode::StepDoubling);
        let range = (setup.probe_time / 2e6, setup.probe_time / 8.0);
        let bisections = setup.options.bisections();
        let bounded = searched.then(|| {
            search(setup.h, range, bisections, |h| {
                let p = probe(h);
                (p.failure.is_none(), p.failure.unwrap_or_default())
            })
        });
        let accurate = searched.then(|| {
            search(setup.h, range, bisections, |h| {
                let p = probe(h);
                match p.failure {
                    Some(failure) => (false, failure),
                    None => (
                        p.energy_error <= ACCURATE,
                        format!("relative energy error {:.2}", p.energy_error),
                    ),
                }
            })
        });
        Ok(StressRecord {
            scene: setup.scene.into(),
            method: self.label.into(),
            h: setup.h,
            bounded,
            accurate,
            drift: svi_drift(&integrator, mode, setup, &options),
        })
    }
}

/// Outcome of one stability probe.
#[derive(Debug, Clone, PartialEq)]
struct Probe {
    /// Why the run failed, if it did.
    failure: Option<String>,
    /// max |E − E₀| / max(|E₀|, 1).
    energy_error: f64,
}

/// A short description of a run's failure.
fn describe(error: &Error) -> String {
    match error {
        Error::NonConvergence { step, t, .. } => {
            format!("solve does not converge (step {step} at t = {t:.4})")
        }
        Error::SingularMatrix { step, t } => {
            format!("singular Newton matrix (step {step} at t = {t:.4})")
        }
        Error::NonFinite { step, t, .. } => format!("non-finite state (step {step} at t = {t:.4})"),
        Error::Diverged { step, t, .. } => format!("state diverges (step {step} at t = {t:.4})"),
        Error::LegendreMap { t, .. } => format!("inverse Legendre map fails (t = {t:.4})"),
        other => other.to_string(),
    }
}

/// The long run of an svi method in `mode` over `drift_steps` scene steps: at the scene's
/// step (Δτ = h for a reparametrised method, the first step for SEM), or at the peers'
/// tolerance for step doubling.
fn svi_drift<L: ZooModel<N>, Me: Method<N> + Clone, N: Dimension>(
    integrator: &Integrator<L, Me, svi::Euclidean<N>>,
    mode: Mode,
    setup: &Setup<'_, N>,
    options: &RunOptions,
) -> Result<Drift, String>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let steps = setup.options.drift_steps;
    let stride = steps.div_ceil(SAMPLES).max(1);
    let samples = steps / stride + 1;
    let mut windows = Every::new(stride, EnergyWindows::new(samples.div_ceil(WINDOWS)));
    let t_end = setup.t0 + steps as f64 * setup.h;
    let (h, step) = match mode {
        Mode::StepDoubling => (setup.options.tolerance(), None),
        _ => (setup.h, Some(setup.h)),
    };
    let start = Instant::now();
    let (_, statistics) = run_mode(
        integrator,
        mode,
        &((setup.t0, setup.initial.clone()), t_end),
        h,
        options,
        &mut windows,
    )
    .map_err(|error| format!("fails: {}", describe(&error)))?;
    let seconds = start.elapsed().as_secs_f64();
    drift(&windows.inner, statistics.steps, step, seconds)
}

/// DOP853 over the horizon of the long run.
fn dop853_drift<M: ZooModel<N>, N: Dimension>(
    model: &M,
    setup: &Setup<'_, N>,
) -> Result<Drift, String>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    match N::try_to_usize() {
        Some(1) => dop853_drift_sized::<M, N, 2>(model, setup),
        Some(2) => dop853_drift_sized::<M, N, 4>(model, setup),
        Some(3) => dop853_drift_sized::<M, N, 6>(model, setup),
        _ => Err(not_wired::<N>()),
    }
}

/// The failure of DOP853 on a model of a dimension it is not wired for.
fn not_wired<N: Dimension>() -> String {
    format!("dop853 is wired for {}", wired_for::<N>())
}

/// [`dop853_drift`] with the state size S = 2N as a type parameter.
fn dop853_drift_sized<M: ZooModel<N>, N: Dimension, const S: usize>(
    model: &M,
    setup: &Setup<'_, N>,
) -> Result<Drift, String>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (q0, v0) = match &setup.initial {
        Initial::Velocity { q, v } => (q, v.clone()),
        Initial::Momentum { q, p } => (
            q,
            model
                .velocity(setup.t0, q, p, p)
                .map_err(|e| e.to_string())?,
        ),
    };
    let system = FirstOrder::<M, N, S>::new(model, setup.t0, q0, &v0).ok_or_else(not_wired::<N>)?;
    let n = q0.shape_generic().0;
    let y0 = ode_solvers::SVector::<f64, S>::from_iterator(q0.iter().chain(v0.iter()).copied());
    let t_end = setup.t0 + setup.options.drift_steps as f64 * setup.h;
    let tol = setup.options.tolerance();
    // The energy at the accepted step points, as for svi's methods (the dense output's
    // interpolation error would swamp the energy error); ode_solvers stores them all, about
    // 40 bytes per step for N = 2.
    let mut stepper = dop853(PeerSystem::from(&system), setup.t0, t_end, y0, tol);
    let start = Instant::now();
    let stats = stepper.integrate().map_err(|e| format!("fails: {e:?}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let (times, states) = (stepper.x_out(), stepper.y_out());
    let reached = times.last().copied().unwrap_or(setup.t0);
    if (reached - t_end).abs() > 1e-9 * t_end.abs().max(1.0) {
        return Err(format!("fails: stops at t = {reached}"));
    }
    let stride = times.len().saturating_sub(1).div_ceil(SAMPLES).max(1);
    let samples = times.len().div_ceil(stride);
    let mut windows = EnergyWindows::new(samples.div_ceil(WINDOWS));
    for (t, y) in times.iter().zip(states).step_by(stride) {
        let (q, v) = split(n, y.as_slice());
        windows.push(*t, model.energy(*t, &q, &v));
    }
    let steps = (stats.accepted_steps + stats.rejected_steps) as usize;
    drift(&windows, steps, None, seconds)
}
