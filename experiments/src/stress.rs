//! `svi stress`: where each method breaks, how it fails, and how its energy behaves over a
//! long run.
//!
//! For every stress case (a built-in scene, [`CASES`]) and method, [`stress`] measures:
//!
//! 1. **The largest bounded step**: runs over the case's probe horizon on a geometric ladder
//!    of steps h_ref·2^(j/4) from the scene's step upwards (downwards if the scene's step
//!    already fails), refined by bisection between the last good and the first failing step.
//!    A step is *bounded* if the run completes with no error: every step's nonlinear solve
//!    converges, the state stays finite and within the divergence limit
//!    10³·max(1, ‖x₀‖∞). The failure mode beyond it is the error of the smallest failing step
//!    found (typed, with step index and time). Steps are probed from h_ref/2¹² to 2¹²·h_ref,
//!    within [T/(2·10⁶), T/8] for a probe horizon T.
//! 2. **The largest accurate step**: the same search for runs that also keep the energy error
//!    max |E − E₀| within 10 % of max(|E₀|, 1).
//! 3. **Long-time energy behaviour**: a run of `drift_steps` steps (default 10⁶) at the
//!    scene's step, the energy error sampled at up to 10⁵ points in 100 windows
//!    ([`svi::drift::EnergyWindows`]) and a line fitted through the window means
//!    ([`svi::drift::DriftFit`]): slope, slope × horizon (the drift), the mean half-range of
//!    the windows (the oscillation amplitude) and the largest |E − E₀|. DOP853 (ode_solvers,
//!    rtol = atol = [`StressOptions::tolerance`]) runs the same horizon as a non-geometric
//!    peer, sampled at up to 10⁵ of its accepted step points.
//!
//! The library's adaptive modes run as in `svi bench`: `METHOD@MONITOR` (time-reparametrised,
//! its τ-step Δτ in place of h: the searches run over Δτ, the long run takes Δτ = the scene's
//! step over the same physical horizon, so its step count is the number of τ-steps that
//! horizon needs), `METHOD@sem` (the searches and the long run over the first step) and
//! `METHOD@step` (step doubling at tol = [`StressOptions::tolerance`] over the same horizon,
//! no step limits: it chooses its steps).
//!
//! Every option is checked before anything runs ([`StressOptions::check`]).
//!
//! The ladder assumes the set of bounded steps is an interval starting at 0; a method with
//! stability gaps (resonances) is reported at the first failure on the ladder.

use crate::bench::peers::{FirstOrder, dop853, split, wired_for};
use crate::bench::{BenchMethod, Mode, parse_methods, run_mode};
use crate::report::csv::Float;
use crate::report::output::{self, OutputDirectory};
use crate::report::plot::{Panel, PlotError, Series, render_svg};
use crate::scene::limits::{self, MAX_BISECTIONS, MAX_DRIFT_STEPS, MIN_PEER_TOLERANCE};
use crate::scene::overrides::method_help;
use crate::scene::{Scene, SceneError};
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;
use svi::drift::{DriftFit, EnergyWindows, Window};
use svi::method::registry::VectorMethodVisitor;
use svi::observer::{EnergyError, Every};
use svi::{Dimension, Error, Initial, Integrator, LagrangianExt, Method, RunOptions};
use svi_models::{ModelVisitor, ZooModel, visit_model};

/// A stress case: a built-in scene and the horizon of its stability probes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressCase {
    /// Built-in scene name.
    pub scene: &'static str,
    /// Length of the time interval each stability probe integrates.
    pub probe_time: f64,
}

/// The stress cases of `svi stress`, in table order.
pub const CASES: &[StressCase] = &[
    StressCase {
        scene: "oscillator",
        probe_time: 100.0,
    },
    StressCase {
        scene: "kepler-long",
        probe_time: 200.0,
    },
    StressCase {
        scene: "kepler-e0.9",
        probe_time: 63.0,
    },
    StressCase {
        scene: "kepler-e0.99",
        probe_time: 63.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum",
        probe_time: 10.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum-coarse",
        probe_time: 10.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum-multiscale",
        probe_time: 10.0,
    },
    StressCase {
        scene: "double-pendulum-chaotic",
        probe_time: 20.0,
    },
];

/// The default method list of `svi stress`.
pub const DEFAULT_METHODS: &str = "svi:6,sc:6,midpoint,verlet,dop853";

/// Ladder factor per probe: 2^(1/4).
const LADDER: f64 = 1.189_207_115_002_721;
/// Largest number of ladder rungs in either direction (a factor 2^12).
const RUNGS: i32 = 48;
/// Energy error, relative to max(|E₀|, 1), above which a step is not accurate.
const ACCURATE: f64 = 0.1;
/// Divergence limit relative to max(1, ‖x₀‖∞).
const DIVERGENCE: f64 = 1e3;
/// Windows of the drift fit.
const WINDOWS: usize = 100;
/// Largest number of energy samples of a drift run.
const SAMPLES: usize = 100_000;

/// Fewest steps of the long run (two per window of the drift fit).
pub const MIN_DRIFT_STEPS: usize = 2 * WINDOWS;

/// Bisections refining each stability boundary by default (`--bisections`).
pub const DEFAULT_BISECTIONS: usize = 5;

/// DOP853's rtol = atol by default (`--tolerance`).
pub const DEFAULT_TOLERANCE: f64 = 1e-10;

/// `svi stress`'s arguments (parsed by the binary, and by tests as the binary does).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct StressArgs {
    /// Stress scenes, comma-separated [default: all of them].
    #[arg(long, value_delimiter = ',')]
    pub cases: Vec<String>,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help), their adaptive
    /// modes METHOD@MONITOR, METHOD@sem and METHOD@step, and dop853.
    #[arg(
        long,
        value_name = "LIST",
        default_value = DEFAULT_METHODS,
        long_help = method_help(
            "Methods, comma-separated: the library's; their adaptive modes METHOD@MONITOR \
             (time-reparametrised, Δτ in place of h), METHOD@sem (symplectic-energy-momentum, \
             the first step in place of h) and METHOD@step (step doubling at --tolerance, drift \
             only); and dop853 (ode_solvers' DOP853, drift only)."
        )
    )]
    pub methods: String,
    /// Steps of the long run of each method.
    #[arg(
        long,
        default_value_t = 1_000_000,
        allow_hyphen_values = true,
        help = format!(
            "Steps of the long run of each method, {} to {MAX_DRIFT_STEPS}",
            MIN_DRIFT_STEPS
        )
    )]
    pub steps: usize,
    /// Bisections refining each stability boundary.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "Bisections refining each stability boundary, 0 to {MAX_BISECTIONS} [default: {}]; \
             not with dop853 alone (it has no boundary)",
            DEFAULT_BISECTIONS
        )
    )]
    pub bisections: Option<usize>,
    /// DOP853's rtol = atol, and step doubling's tolerance.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "DOP853's rtol = atol and METHOD@step's tolerance, at least {} [default: {}]; \
             only with dop853 or METHOD@step in --methods",
            Float(MIN_PEER_TOLERANCE),
            Float(DEFAULT_TOLERANCE)
        )
    )]
    pub tolerance: Option<f64>,
    /// Directory for stress.md, stress.csv, windows.csv and drift.svg.
    #[arg(long, default_value = "stress-out")]
    pub out_dir: std::path::PathBuf,
}

impl StressArgs {
    /// The options these arguments ask for; an error names a method that is not known.
    pub fn options(&self) -> Result<StressOptions, SceneError> {
        Ok(StressOptions {
            cases: self.cases.clone(),
            methods: parse_methods(&self.methods)?,
            drift_steps: self.steps,
            bisections: self.bisections,
            tolerance: self.tolerance,
            verbose: true,
        })
    }
}

/// Options of [`stress`].
#[derive(Debug, Clone, PartialEq)]
pub struct StressOptions {
    /// Scenes (names from [`CASES`]); empty: all.
    pub cases: Vec<String>,
    /// Methods: the library's (`svi:P/M`, `sc:P`, `verlet`, ...), their adaptive modes
    /// (`METHOD@MONITOR`, `METHOD@sem`, `METHOD@step`) and `dop853` (drift only).
    pub methods: Vec<BenchMethod>,
    /// Steps of the long run, [`MIN_DRIFT_STEPS`] to [`MAX_DRIFT_STEPS`].
    pub drift_steps: usize,
    /// Bisections refining each stability boundary, up to [`MAX_BISECTIONS`] (`None`:
    /// [`DEFAULT_BISECTIONS`]); set only with a library method.
    pub bisections: Option<usize>,
    /// DOP853's rtol = atol and step doubling's tolerance (`None`: [`DEFAULT_TOLERANCE`]);
    /// set only with `dop853` or `METHOD@step`.
    pub tolerance: Option<f64>,
    /// Print progress to stderr.
    pub verbose: bool,
}

impl Default for StressOptions {
    fn default() -> Self {
        StressOptions {
            cases: Vec::new(),
            methods: parse_methods(DEFAULT_METHODS).unwrap_or_default(),
            drift_steps: 1_000_000,
            bisections: None,
            tolerance: None,
            verbose: false,
        }
    }
}

impl StressOptions {
    /// The bisections refining each stability boundary.
    pub fn bisections(&self) -> usize {
        self.bisections.unwrap_or(DEFAULT_BISECTIONS)
    }

    /// DOP853's rtol = atol, and step doubling's tolerance.
    pub fn tolerance(&self) -> f64 {
        self.tolerance.unwrap_or(DEFAULT_TOLERANCE)
    }

    /// Check every option before anything runs: known stress cases, methods `svi stress`
    /// can use, counts within their caps ([`crate::scene::limits`]), and `--bisections` and
    /// `--tolerance` only with the methods they apply to. An error names the option.
    pub fn check(&self) -> Result<(), SceneError> {
        for name in &self.cases {
            if !CASES.iter().any(|case| case.scene == name) {
                return Err(SceneError::UnknownStressCase {
                    name: name.clone(),
                    known: CASES.iter().map(|case| case.scene).collect(),
                });
            }
        }
        if self.methods.is_empty() {
            return Err(SceneError::InvalidOption {
                option: "--methods",
                reason: "no method given".into(),
            });
        }
        if let Some(&peer) = self.methods.iter().find(|method| {
            matches!(
                method,
                BenchMethod::Dopri5 | BenchMethod::Radau5 | BenchMethod::Molly
            )
        }) {
            return Err(peer_not_applicable(peer));
        }
        limits::count(
            "--steps",
            self.drift_steps,
            MIN_DRIFT_STEPS,
            MAX_DRIFT_STEPS,
            "steps",
        )?;
        // Dopri5, Radau5 and molly are refused above: the methods left without steps are
        // dop853 and METHOD@step, which take --tolerance.
        let searched = self.methods.iter().any(BenchMethod::takes_steps);
        let tolerance_driven = self.methods.iter().any(|method| !method.takes_steps());
        if let Some(bisections) = self.bisections {
            limits::count("--bisections", bisections, 0, MAX_BISECTIONS, "bisections")?;
            if !searched {
                return Err(SceneError::NotApplicable {
                    option: "--bisections",
                    reason: "refines the step limits of the library's stepped methods, and \
                             --methods lists only dop853 and METHOD@step (which have none)"
                        .into(),
                });
            }
        }
        if let Some(tolerance) = self.tolerance {
            limits::peer_tolerance("--tolerance", tolerance)?;
            if !tolerance_driven {
                return Err(SceneError::NotApplicable {
                    option: "--tolerance",
                    reason: "sets the tolerance of dop853 and METHOD@step, and --methods has \
                             neither"
                        .into(),
                });
            }
        }
        Ok(())
    }
}

/// A peer other than `dop853` (`dopri5`, `radau5`, `molly`) in `svi stress --methods`.
fn peer_not_applicable(peer: BenchMethod) -> SceneError {
    SceneError::MethodNotApplicable {
        method: peer.to_string(),
        reason: "svi stress compares with dop853 only".into(),
    }
}

/// The largest step meeting a criterion, and what happens just beyond it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Limit {
    /// Largest step found that meets the criterion (`None`: not even the smallest probed).
    pub h: Option<f64>,
    /// Smallest step found that fails it (`None`: none up to the largest probed).
    pub beyond: Option<f64>,
    /// What happens at `beyond`.
    pub failure: String,
}

/// Energy behaviour of one long run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drift {
    /// Steps taken (accepted plus rejected for DOP853).
    pub steps: usize,
    /// Step (the scene's; `None` for DOP853 and step doubling).
    pub h: Option<f64>,
    /// Horizon of the run.
    pub horizon: f64,
    /// Fitted slope of the energy error (per unit time).
    pub slope: f64,
    /// Slope × horizon.
    pub drift: f64,
    /// Mean half-range of the energy error in the windows.
    pub amplitude: f64,
    /// Largest |E − E₀|.
    pub max_error: f64,
    /// max(|E₀|, 1), the scale of the round-off floor.
    pub energy_scale: f64,
    /// Wall time, in seconds.
    pub seconds: f64,
    /// The windows.
    #[serde(skip)]
    pub windows: Vec<Window>,
}

/// Energy errors below this many ulps of max(|E₀|, 1) are round-off.
const ROUND_OFF: f64 = 1e3 * f64::EPSILON;

impl Drift {
    /// Whether the drift over the run exceeds both the oscillation amplitude and the
    /// round-off floor 10³·ε·max(|E₀|, 1).
    pub fn drifts(&self) -> bool {
        self.drift.abs() > self.amplitude && self.drift.abs() > ROUND_OFF * self.energy_scale
    }

    /// `drifts`, `bounded`, or `round-off` (every error below the round-off floor).
    pub fn verdict(&self) -> &'static str {
        if self.max_error <= ROUND_OFF * self.energy_scale {
            "round-off"
        } else if self.drifts() {
            "drifts"
        } else {
            "bounded"
        }
    }
}

/// One row of the stress table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StressRecord {
    /// Scene name.
    pub scene: String,
    /// Method specification.
    pub method: String,
    /// The scene's step.
    pub h: f64,
    /// Largest bounded step (`None` for DOP853 and step doubling).
    pub bounded: Option<Limit>,
    /// Largest step with an energy error below 10 % (`None` for DOP853 and step
    /// doubling).
    pub accurate: Option<Limit>,
    /// The long run, or why it failed.
    pub drift: Result<Drift, String>,
}

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

/// The largest step in `range` for which `good` holds, searched from `h_ref` (see the module
/// documentation); `good(h)` returns whether the step is good and, if not, why.
fn search(
    h_ref: f64,
    range: (f64, f64),
    bisections: usize,
    mut good: impl FnMut(f64) -> (bool, String),
) -> Limit {
    let h_ref = h_ref.clamp(range.0, range.1);
    let mut best: Option<f64> = None;
    let mut beyond: Option<(f64, String)> = None;
    let (ok, why) = good(h_ref);
    if ok {
        best = Some(h_ref);
        for j in 1..=RUNGS {
            let h = h_ref * LADDER.powi(j);
            if h > range.1 {
                break;
            }
            match good(h) {
                (true, _) => best = Some(h),
                (false, why) => {
                    beyond = Some((h, why));
                    break;
                }
            }
        }
    } else {
        beyond = Some((h_ref, why));
        for j in 1..=RUNGS {
            let h = h_ref / LADDER.powi(j);
            if h < range.0 {
                break;
            }
            match good(h) {
                (true, _) => {
                    best = Some(h);
                    break;
                }
                (false, why) => beyond = Some((h, why)),
            }
        }
    }
    if let (Some(low), Some((high, _))) = (best, &beyond) {
        let mut high = *high;
        let mut low = low;
        for _ in 0..bisections {
            let middle = (low * high).sqrt();
            match good(middle) {
                (true, _) => low = middle,
                (false, why) => {
                    high = middle;
                    beyond = Some((middle, why));
                }
            }
        }
        best = Some(low);
    }
    Limit {
        h: best,
        beyond: beyond.as_ref().map(|(h, _)| *h),
        failure: beyond.map_or_else(
            || {
                format!(
                    "none up to h = {}",
                    best.map_or_else(String::new, |h| format!("{h:.3e}"))
                )
            },
            |(_, why)| why,
        ),
    }
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

/// Fit the drift of collected windows.
fn drift(
    windows: &EnergyWindows,
    steps: usize,
    h: Option<f64>,
    seconds: f64,
) -> Result<Drift, String> {
    let all = windows.all();
    let fit: DriftFit = DriftFit::from_windows(&all)
        .ok_or_else(|| "no fit (too few or non-finite samples)".to_string())?;
    Ok(Drift {
        steps,
        h,
        horizon: fit.horizon,
        slope: fit.slope,
        drift: fit.drift,
        amplitude: fit.amplitude,
        max_error: fit.max_error,
        energy_scale: windows.initial.map_or(1.0, |e| e.abs().max(1.0)),
        seconds,
        windows: all,
    })
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
    let mut stepper = dop853(system, setup.t0, t_end, y0, tol);
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

/// `1.23e-4`, or `—`.
fn short(value: Option<f64>) -> String {
    value.map_or_else(|| "—".into(), |x| format!("{x:.3e}"))
}

/// One line for the progress log.
fn summary_line(record: &StressRecord) -> String {
    let mut line = String::new();
    if let Some(limit) = &record.bounded {
        let _ = write!(line, "bounded h ≤ {} ({}); ", short(limit.h), limit.failure);
    }
    match &record.drift {
        Ok(d) => {
            let _ = write!(
                line,
                "drift {:.2e} amplitude {:.2e} max {:.2e}",
                d.drift, d.amplitude, d.max_error
            );
        }
        Err(why) => line.push_str(why),
    }
    line
}

/// The stress table in Markdown.
pub fn to_markdown(records: &[StressRecord]) -> String {
    let mut out = String::from(
        "| scene | method | h | largest bounded h | beyond it | largest h with \\|ΔE\\| < 10 % | steps | drift slope | drift × T | amplitude | max \\|ΔE\\| | energy |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in records {
        let (bounded, beyond) = match &r.bounded {
            Some(limit) => (short(limit.h), limit.failure.clone()),
            None => ("—".into(), "—".into()),
        };
        let accurate = r
            .accurate
            .as_ref()
            .map_or_else(|| "—".into(), |limit| short(limit.h));
        let drift = match &r.drift {
            Ok(d) => format!(
                "{} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {}",
                d.steps,
                d.slope,
                d.drift,
                d.amplitude,
                d.max_error,
                d.verdict()
            ),
            Err(why) => format!("— | — | — | — | — | {why}"),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.scene,
            r.method,
            Float(r.h),
            bounded,
            beyond,
            accurate,
            drift
        );
    }
    out
}

/// The stress table as CSV (empty fields where a value does not apply; the failure texts
/// are quoted and hold no commas).
pub fn to_csv(records: &[StressRecord]) -> String {
    let mut out = String::from(
        "scene,method,h,bounded_h,bounded_beyond,bounded_failure,accurate_h,accurate_beyond,accurate_failure,steps,horizon,slope,drift,amplitude,max_error,verdict,seconds,drift_failure\n",
    );
    let number = |x: Option<f64>| x.map_or_else(String::new, |x| Float(x).to_string());
    let quote = |s: &str| format!("\"{}\"", s.replace('"', "'").replace(',', ";"));
    for r in records {
        let limit = |limit: &Option<Limit>| match limit {
            Some(l) => format!("{},{},{}", number(l.h), number(l.beyond), quote(&l.failure)),
            None => ",,".into(),
        };
        let drift = match &r.drift {
            Ok(d) => format!(
                "{},{},{},{},{},{},{},{},",
                d.steps,
                Float(d.horizon),
                Float(d.slope),
                Float(d.drift),
                Float(d.amplitude),
                Float(d.max_error),
                d.verdict(),
                Float(d.seconds)
            ),
            Err(why) => format!(",,,,,,,,{}", quote(why)),
        };
        let _ = writeln!(
            out,
            "{},{},{},{},{},{}",
            r.scene,
            r.method,
            Float(r.h),
            limit(&r.bounded),
            limit(&r.accurate),
            drift
        );
    }
    out
}

/// The windows of every long run as CSV.
pub fn windows_csv(records: &[StressRecord]) -> String {
    let mut out = String::from("scene,method,t_start,t_end,mean,min,max,samples\n");
    for r in records {
        if let Ok(d) = &r.drift {
            for w in &d.windows {
                let _ = writeln!(
                    out,
                    "{},{},{},{},{},{},{},{}",
                    r.scene,
                    r.method,
                    Float(w.t_start),
                    Float(w.t_end),
                    Float(w.mean),
                    Float(w.min),
                    Float(w.max),
                    w.samples
                );
            }
        }
    }
    out
}

/// One panel per scene, as SVG text: the largest |E − E₀| in each window against time, per
/// method. Every
/// panel lists every method in the same order (so a method keeps its colour); a long run that
/// failed is an empty series labelled "(failed)".
pub fn plot(records: &[StressRecord]) -> Result<String, PlotError> {
    let mut panels: Vec<Panel> = Vec::new();
    for r in records {
        let series = match &r.drift {
            Ok(d) => Series {
                label: r.method.clone(),
                points: d
                    .windows
                    .iter()
                    .map(|w| (w.t_end, w.max.abs().max(w.min.abs())))
                    .collect(),
            },
            Err(_) => Series {
                label: format!("{} (failed)", r.method),
                points: Vec::new(),
            },
        };
        match panels.iter_mut().find(|p| p.title == r.scene) {
            Some(panel) => panel.series.push(series),
            None => panels.push(Panel {
                title: r.scene.clone(),
                x_label: "t".into(),
                y_label: "max |E − E₀| per window".into(),
                x_log: false,
                y_log: true,
                equal_scale: false,
                series: vec![series],
            }),
        }
    }
    render_svg(&panels, 480, 400)
}

/// The files `svi stress` writes into its output directory.
pub const OUTPUT_FILES: [&str; 4] = ["stress.md", "stress.csv", "windows.csv", "drift.svg"];

/// Write `stress.md`, `stress.csv`, `windows.csv` and `drift.svg` into `dir` (created before
/// the cases run).
pub fn write_outputs(records: &[StressRecord], mut dir: OutputDirectory) -> Result<(), SceneError> {
    dir.write("stress.md", to_markdown(records).as_bytes())?;
    dir.write("stress.csv", to_csv(records).as_bytes())?;
    dir.write("windows.csv", windows_csv(records).as_bytes())?;
    dir.write("drift.svg", plot(records)?.as_bytes())?;
    Ok(dir.commit()?)
}

/// `svi stress` with the arguments `args`: [`execute`] on their options and output directory.
pub fn execute_args(args: &StressArgs) -> anyhow::Result<()> {
    execute(&args.options()?, &args.out_dir)
}

/// `svi stress`: run the cases of `options`, write `stress.md`, `stress.csv`, `windows.csv`
/// and `drift.svg` into `out_dir` (its files are created before the cases run) and print the
/// table.
pub fn execute(options: &StressOptions, out_dir: &Path) -> anyhow::Result<()> {
    options.check()?;
    let names = OUTPUT_FILES.map(String::from);
    let dir = OutputDirectory::create("--out-dir", out_dir, &names, &[])?;
    let records = stress(options)?;
    write_outputs(&records, dir)?;
    output::print(to_markdown(&records)).map_err(SceneError::from)?;
    output::warn(format_args!(
        "wrote stress.md, stress.csv, windows.csv and drift.svg to {}",
        out_dir.display()
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_finds_a_threshold_from_either_side() {
        let good = |h: f64| (h < 2.0, format!("fails at {h}"));
        let up = search(0.5, (1e-6, 100.0), 8, good);
        let h = up.h.unwrap();
        let beyond = up.beyond.unwrap();
        assert!(h < 2.0 && beyond >= 2.0 && beyond / h < 1.002, "{up:?}");
        assert!(up.failure.starts_with("fails at"));
        let down = search(10.0, (1e-6, 100.0), 8, good);
        assert!(down.h.unwrap() < 2.0 && down.h.unwrap() > 1.99, "{down:?}");
        let never = search(1.0, (1e-6, 100.0), 3, |_| (true, String::new()));
        assert_eq!(never.beyond, None);
        assert!(never.failure.starts_with("none up to"));
        assert!(never.h.unwrap() <= 100.0 && never.h.unwrap() > 100.0 / LADDER);
    }

    #[test]
    fn the_peers_other_than_dop853_are_refused_by_name() {
        // dopri5, radau5 and molly alike: the same error, naming the peer, before anything
        // runs.
        for (methods, named) in [
            ("verlet,dopri5", "dopri5"),
            ("radau5", "radau5"),
            ("dop853,radau5,dopri5", "radau5"),
            ("verlet,molly", "molly"),
        ] {
            let options = StressOptions {
                methods: parse_methods(methods).unwrap(),
                ..StressOptions::default()
            };
            let error = options.check().unwrap_err();
            assert!(
                matches!(&error, SceneError::MethodNotApplicable { method, reason }
                    if method == named && reason == "svi stress compares with dop853 only"),
                "{methods}: {error}"
            );
        }
    }
}
