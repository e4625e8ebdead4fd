//! # svi-cli — scenes for the `svi` command-line tool
//!
//! A [`Scene`] says what to simulate: a model of the zoo and its parameters, an initial
//! state, a method and its options, the step and horizon, and the outputs wanted. Scenes are
//! TOML files; the built-in ones ([`BUILTIN_SCENES`]) reproduce the experiments of Li, Wu,
//! Leok (2018) and run each zoo model with its defaults. Command-line flags ([`Overrides`])
//! are applied on top of a scene, and [`Scene::run`] integrates it and returns a [`Summary`].
//!
//! ```toml
//! model = "kepler"
//!
//! [parameters]          # model parameters, name = value (absent: the model's defaults)
//! e = 0.5
//!
//! [initial]             # optional; absent fields come from the model's default state
//! t0 = 0.0
//! q = [0.5, 0.0]
//! v = [0.0, 1.7320508075688772]   # or p = [...], not both
//!
//! [method]
//! name = "svi"          # NAME, NAME:P or NAME:P/M of svi::method::registry::METHODS:
//!                       # "svi" (default), "svi:7/6", "sc:9", "midpoint", "verlet", ...
//! points = 6            # Chebyshev–Gauss–Lobatto points, svi and sc (default 6): the same
//!                       # as name = "svi:6"
//! quadrature = 12       # Gauss–Legendre points, svi only (default 2 × points)
//!
//! [run]                 # absent: the model's default step and horizon
//! h = 0.2               # the step (unused by adapt = "step")
//! t_end = 2000.0
//! adapt = "none"        # "none" (default), "step" (step doubling) or "degree" (points per
//!                       # step, svi and sc), both to meet `tol`
//! tol = 1e-9            # target final error of the adaptive modes
//! min_points = 3        # bounds of adapt = "degree" (defaults 3 and 24)
//! max_points = 24
//! recovery = "none"     # or "halve-step": retry a failed step as two half steps
//! # max_halvings = 4    # with "halve-step": successive halvings allowed (default 4)
//! # divergence_limit = 1e6   # stop once |q_i| or |p_i| exceeds this (default: no limit)
//!
//! [output]
//! trajectory = "kepler.csv"   # write the trajectory as CSV (absent: none)
//! every = 10                  # every 10th step (default 1)
//! output_times = [1.0, 2.5]   # report (and write) the states at these times, read off each
//!                             # step's polynomial (dense output), instead of every step
//! diagnostics = ["energy", "momentum", "solution"]   # the default: all three
//! ```
//!
//! A built-in name wins over a file of the same name (write `./kepler` for the file). Paths in
//! a scene (the trajectory file) are relative to the working directory.
//!
//! Forces (friction, driving) are part of a model's definition: the forced zoo models
//! (`damped-oscillator`, `damped-pendulum`, `driven-oscillator`) are chosen by name like any
//! other, and their force parameters are ordinary `[parameters]`.
//!
//! The model, chosen by name at run time, reaches the one generic runner as its concrete
//! type through [`svi_models::visit_model`]; the method, a [`MethodSpec`] of the library's
//! registry ([`svi::method::registry`]), reaches it as its concrete type through
//! [`MethodSpec::visit_vector`]. Observers are built only for the diagnostics and outputs
//! asked for.

use std::collections::BTreeMap;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::SVector;
use serde::{Deserialize, Serialize};
pub mod command;
pub mod report;
pub mod rigid;

pub use command::{bench, stability, stress};

use svi::method::registry::{self, SpaceKind, VectorMethodVisitor};
use svi::observer::{EnergyError, Every, MomentumError, Observer, SolutionError, Trajectory};
use svi::solve::{Adapt, SolveOptions, Span};
use svi::{Initial, Recovery, RunFailure, RunOptions, Statistics};
use svi::{Integrator, LagrangianExt, Method, MethodSpec, PhasePoint};
use svi_models::{MODEL_NAMES, ModelVisitor, UnknownModel, ZooModel, visit_model};

/// The built-in scenes, as (name, TOML text).
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    ("oscillator", include_str!("../scenes/oscillator.toml")),
    ("kepler", include_str!("../scenes/kepler.toml")),
    ("pendulum", include_str!("../scenes/pendulum.toml")),
    (
        "spring-pendulum",
        include_str!("../scenes/spring-pendulum.toml"),
    ),
    (
        "double-pendulum",
        include_str!("../scenes/double-pendulum.toml"),
    ),
    (
        "damped-oscillator",
        include_str!("../scenes/damped-oscillator.toml"),
    ),
    (
        "damped-pendulum",
        include_str!("../scenes/damped-pendulum.toml"),
    ),
    (
        "driven-oscillator",
        include_str!("../scenes/driven-oscillator.toml"),
    ),
    (
        "stiff-spring-pendulum",
        include_str!("../scenes/stiff-spring-pendulum.toml"),
    ),
    (
        "stiff-spring-pendulum-coarse",
        include_str!("../scenes/stiff-spring-pendulum-coarse.toml"),
    ),
    ("kepler-long", include_str!("../scenes/kepler-long.toml")),
    ("kepler-e0.9", include_str!("../scenes/kepler-e0.9.toml")),
    ("kepler-e0.99", include_str!("../scenes/kepler-e0.99.toml")),
    (
        "kepler-recovery",
        include_str!("../scenes/kepler-recovery.toml"),
    ),
    (
        "double-pendulum-chaotic",
        include_str!("../scenes/double-pendulum-chaotic.toml"),
    ),
    (
        "oscillator-beyond-stability",
        include_str!("../scenes/oscillator-beyond-stability.toml"),
    ),
];

/// The scene `svi run` runs when none is named.
pub const DEFAULT_SCENE: &str = "kepler";

/// Runs with at least this many steps show a progress bar (on a terminal).
pub const PROGRESS_MIN_STEPS: usize = 10_000;

/// Names of the built-in scenes.
pub fn builtin_scene_names() -> Vec<&'static str> {
    BUILTIN_SCENES.iter().map(|(name, _)| *name).collect()
}

/// The TOML text of a built-in scene.
pub fn builtin_scene(name: &str) -> Option<&'static str> {
    BUILTIN_SCENES
        .iter()
        .find(|(scene, _)| *scene == name)
        .map(|(_, text)| *text)
}

/// Everything that can go wrong between reading a scene and writing its outputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene is not valid TOML or does not fit the scene format (the source names the
    /// line and column).
    #[error("cannot parse scene {origin}")]
    Parse {
        /// Where the text came from (a file path or `built-in scene 'name'`).
        origin: String,
        /// The TOML parser's message.
        #[source]
        source: toml::de::Error,
    },
    /// Neither a built-in scene name nor an existing file.
    #[error(
        "no built-in scene or scene file named '{name}' (built-in scenes: {})",
        builtin_scene_names().join(", ")
    )]
    UnknownScene {
        /// The name asked for.
        name: String,
    },
    /// A scene file that cannot be read.
    #[error("cannot read scene file '{}'", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A model name that is not in the zoo.
    #[error(transparent)]
    UnknownModel(#[from] UnknownModel),
    /// An initial-state vector whose length is not the model dimension.
    #[error("initial.{field} has {found} components, but model '{model}' has dimension {expected}")]
    Dimension {
        /// The model.
        model: String,
        /// `q`, `v` or `p`.
        field: &'static str,
        /// The model dimension.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// An initial state with both a velocity and a momentum.
    #[error("the initial state gives both v and p: give one of them")]
    VelocityAndMomentum,
    /// A diagnostic other than `energy`, `momentum` and `solution`.
    #[error("unknown diagnostic '{name}' (known: {})", Diagnostic::NAMES.join(", "))]
    UnknownDiagnostic {
        /// The name asked for.
        name: String,
    },
    /// A `--param` that is not `NAME=VALUE` with a number as value.
    #[error("malformed parameter '{text}': {reason}")]
    MalformedParameter {
        /// The argument as given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A command-line method option (`--points`, `--quadrature`) given with a method that
    /// does not take it.
    #[error("--{option} is an option of {}, not of {method}", option_owners(.option, .method))]
    OptionNotForMethod {
        /// The option: `points` or `quadrature`.
        option: &'static str,
        /// The method in use.
        method: MethodSpec,
    },
    /// A trajectory thinning factor without a file to write the trajectory to.
    #[error("output.every is set but no trajectory file is (give --out FILE or output.trajectory)")]
    EveryWithoutOutput,
    /// The trajectory file cannot be written.
    #[error("cannot write trajectory '{}'", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Everything the library rejects: parameters, step, horizon, method options, initial
    /// state, nonlinear solves.
    #[error(transparent)]
    Svi(#[from] svi::Error),
    /// A run that failed after it started: the summary of the run up to the last good state
    /// (its trajectory file, if asked for, is written) and the library's error.
    #[error(
        "the run failed after {} steps; last good state at t = {}: q = {}, v = {}{}",
        .partial.steps,
        Float(.partial.t_end),
        vector(&.partial.q),
        vector(&.partial.v),
        .partial.trajectory.as_ref().map_or_else(String::new, |trajectory| format!(
            "; the trajectory so far is in '{}'",
            trajectory.path
        ))
    )]
    RunFailed {
        /// Summary of the run up to the last good state.
        partial: Box<Summary>,
        /// What went wrong, with step index and time.
        #[source]
        source: svi::Error,
    },
    /// A method name of `svi bench` or `svi stress` that is neither a library method nor
    /// one of the peers `dop853` and `dopri5`.
    #[error(
        "unknown method '{text}' (known: {}, dop853, dopri5)",
        registry::known_names()
    )]
    BenchMethod {
        /// The method as written.
        text: String,
    },
    /// A method that a command cannot use (a peer without a stability matrix, a peer wired
    /// for small models only, ...).
    #[error("method '{method}' cannot be used here: {reason}")]
    MethodNotApplicable {
        /// The method as written.
        method: String,
        /// Why not.
        reason: String,
    },
    /// A `svi bench` step count or tolerance that is out of range or whose run failed.
    #[error("svi bench: {0}")]
    BenchParameter(String),
    /// A benchmark needs an exact solution as reference.
    #[error(
        "model '{0}' has no exact solution for this initial state: nothing to measure errors against"
    )]
    NoReference(String),
}

/// The methods on the same space as `method` that take `option`, as named in
/// [`SceneError::OptionNotForMethod`]: "svi and sc".
fn option_owners(option: &str, method: &MethodSpec) -> String {
    let owners: Vec<&str> = registry::METHODS
        .iter()
        .filter(|entry| entry.space == method.space())
        .filter(|entry| match option {
            "points" => entry.takes_points(),
            _ => entry.takes_quadrature(),
        })
        .map(|entry| entry.name)
        .collect();
    match owners.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => "no method".into(),
    }
}

/// Deserialise a method written `name`, `name:P` or `name:P/M`.
fn method_spec<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<MethodSpec, D::Error> {
    let text = String::deserialize(deserializer)?;
    text.parse().map_err(serde::de::Error::custom)
}

/// Deserialise an optional method written `name`, `name:P` or `name:P/M`.
fn optional_method_spec<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<Option<MethodSpec>, D::Error> {
    method_spec(deserializer).map(Some)
}

/// The help of an option taking a method: `intro`, then the grammar and every method.
pub fn method_help(intro: &str) -> String {
    format!("{intro}\n\n{}", registry::grammar_help())
}

/// A diagnostic evaluated at every step point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(try_from = "String")]
pub enum Diagnostic {
    /// Largest energy deviation |E − E₀|.
    Energy,
    /// Largest deviation of the Noether momenta.
    Momentum,
    /// Largest position error against the exact solution.
    Solution,
}

impl Diagnostic {
    /// The names, as written in scenes and on the command line.
    pub const NAMES: [&'static str; 3] = ["energy", "momentum", "solution"];
}

impl FromStr for Diagnostic {
    type Err = SceneError;
    fn from_str(name: &str) -> Result<Self, SceneError> {
        match name {
            "energy" => Ok(Diagnostic::Energy),
            "momentum" => Ok(Diagnostic::Momentum),
            "solution" => Ok(Diagnostic::Solution),
            _ => Err(SceneError::UnknownDiagnostic { name: name.into() }),
        }
    }
}

impl TryFrom<String> for Diagnostic {
    type Error = SceneError;
    fn try_from(name: String) -> Result<Self, SceneError> {
        name.parse()
    }
}

/// A scene: what to simulate and what to report. Absent fields fall back to the model's
/// [`svi::Defaults`] and the method's defaults.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Zoo model name (see [`svi_models::MODEL_NAMES`]).
    pub model: String,
    /// Model parameters, name → value, applied on top of the model's defaults.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// Initial state; absent fields come from the model's default state.
    #[serde(default)]
    pub initial: InitialSection,
    /// Method and options.
    #[serde(default)]
    pub method: MethodSection,
    /// Step and horizon.
    #[serde(default)]
    pub run: RunSection,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSection,
}

/// `[initial]`: t0, q and one of v, p.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSection {
    /// Initial time.
    pub t0: Option<f64>,
    /// Initial configuration.
    pub q: Option<Vec<f64>>,
    /// Initial velocity (excludes `p`).
    pub v: Option<Vec<f64>>,
    /// Initial momentum (excludes `v`).
    pub p: Option<Vec<f64>>,
}

/// `[method]`: name and options.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSection {
    /// The method, `name`, `name:P` or `name:P/M` of [`registry::METHODS`] (default `svi`).
    #[serde(default, deserialize_with = "method_spec")]
    pub name: MethodSpec,
    /// Chebyshev–Gauss–Lobatto points of svi and sc, applied on top of `name` (default: the
    /// method's); ignored by the methods without.
    pub points: Option<usize>,
    /// Gauss–Legendre points of svi, applied on top of `name` (default 2 × points); ignored
    /// by the other methods.
    pub quadrature: Option<usize>,
}

/// `[run]`: step, horizon, adaptivity and failure handling.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Step size (default: the model's default step); unused by `adapt = "step"`, which
    /// chooses its first step from the initial state.
    pub h: Option<f64>,
    /// Final time (default: the model's default horizon).
    pub t_end: Option<f64>,
    /// Adaptivity (default none).
    pub adapt: Option<AdaptMode>,
    /// Target final error of the adaptive modes.
    pub tol: Option<f64>,
    /// Fewest CGL points of `adapt = "degree"` (default 3).
    pub min_points: Option<usize>,
    /// Most CGL points of `adapt = "degree"` (default 24).
    pub max_points: Option<usize>,
    /// What to do when a step fails (default: `none`, stop with the error).
    pub recovery: Option<RecoveryKind>,
    /// Successive halvings allowed by `recovery = "halve-step"` (default
    /// [`DEFAULT_MAX_HALVINGS`]).
    pub max_halvings: Option<usize>,
    /// Stop with an error once a state component exceeds this in absolute value (default:
    /// no limit; NaN and infinity always stop the run).
    pub divergence_limit: Option<f64>,
}

/// The adaptivity modes of [`svi::solve()`], as named in scenes and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum AdaptMode {
    /// Fixed step.
    #[default]
    None,
    /// Step doubling to meet `tol`.
    Step,
    /// Points per step (svi and sc) to meet `tol`, at fixed step.
    Degree,
}

impl AdaptMode {
    /// The name, as written in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AdaptMode::None => "none",
            AdaptMode::Step => "step",
            AdaptMode::Degree => "degree",
        }
    }
}

impl From<AdaptMode> for Adapt {
    fn from(mode: AdaptMode) -> Adapt {
        match mode {
            AdaptMode::None => Adapt::None,
            AdaptMode::Step => Adapt::Step,
            AdaptMode::Degree => Adapt::Degree,
        }
    }
}

/// Successive halvings of a failed step allowed by default under `recovery = "halve-step"`.
pub const DEFAULT_MAX_HALVINGS: usize = 4;

/// A scene's recovery policy for failed steps (`[run] recovery`, `--recovery`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RecoveryKind {
    /// Stop the run with the failed step's error.
    #[default]
    None,
    /// Retry a failed step as two half steps (recursively), then go on with the original
    /// step.
    HalveStep,
}

impl RunSection {
    /// The library's run options for this section.
    pub fn options(&self) -> Result<RunOptions, SceneError> {
        let mut options = RunOptions::default();
        match (self.recovery.unwrap_or_default(), self.max_halvings) {
            (RecoveryKind::None, Some(_)) => {
                return Err(svi::Error::invalid(
                    "max_halvings",
                    "set, but recovery is not \"halve-step\"",
                )
                .into());
            }
            (RecoveryKind::None, None) => {}
            (RecoveryKind::HalveStep, halvings) => {
                options = options.with_recovery(Recovery::HalveStep {
                    max_halvings: halvings.unwrap_or(DEFAULT_MAX_HALVINGS),
                });
            }
        }
        if let Some(limit) = self.divergence_limit {
            options = options.with_divergence_limit(limit);
        }
        options.validate()?;
        Ok(options)
    }
}

/// `[output]`: trajectory file and diagnostics.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Write every `every`-th step of the trajectory (default 1; needs `trajectory`).
    pub every: Option<usize>,
    /// CSV file for the trajectory (absent: no trajectory is kept).
    pub trajectory: Option<PathBuf>,
    /// Diagnostics to compute (default: all of [`Diagnostic::NAMES`]).
    pub diagnostics: Option<Vec<Diagnostic>>,
    /// Report the states at these times (dense output) instead of at every step.
    pub output_times: Option<Vec<f64>>,
}

/// Scene fields set from the command line.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct Overrides {
    /// Integration method: NAME, NAME:P or NAME:P/M, e.g. svi:7/6, sc:9, verlet.
    #[arg(
        long,
        value_name = "METHOD",
        long_help = method_help(
            "Integration method (default: the scene's). Rigid-body scenes take lie-svi or \
             lie-svi-reduced."
        )
    )]
    pub method: Option<MethodSpec>,
    /// Number of Chebyshev–Gauss–Lobatto points (svi and sc), on top of --method.
    #[arg(long, value_name = "N")]
    pub points: Option<usize>,
    /// Number of Gauss–Legendre quadrature points (svi only), on top of --method.
    #[arg(long, value_name = "M")]
    pub quadrature: Option<usize>,
    /// Step size.
    #[arg(long = "h", value_name = "H", allow_negative_numbers = true)]
    pub h: Option<f64>,
    /// Final time.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Model parameter (repeatable), e.g. `--param e=0.9`.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_parameter)]
    pub parameters: Vec<(String, f64)>,
    /// Keep every K-th step of the trajectory (with --out; default 1).
    #[arg(long, value_name = "K")]
    pub every: Option<usize>,
    /// Write the trajectory as CSV to FILE.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Diagnostics to compute, comma-separated (default: energy,momentum,solution).
    #[arg(long, value_enum, value_name = "LIST", value_delimiter = ',')]
    pub diagnostics: Option<Vec<Diagnostic>>,
    /// Adaptivity: none (fixed step), step (step doubling) or degree (points per step).
    #[arg(long, value_enum)]
    pub adapt: Option<AdaptMode>,
    /// Target final error of the adaptive modes.
    #[arg(long, value_name = "TOL", allow_negative_numbers = true)]
    pub tol: Option<f64>,
    /// Report the states at these times, comma-separated (dense output).
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub output_times: Option<Vec<f64>>,
    /// Recovery policy for failed steps.
    #[arg(long, value_enum)]
    pub recovery: Option<RecoveryKind>,
    /// Stop once a state component exceeds this in absolute value.
    #[arg(long, value_name = "LIMIT")]
    pub divergence_limit: Option<f64>,
}

/// Parse `NAME=VALUE` (the argument of `--param`).
pub fn parse_parameter(text: &str) -> Result<(String, f64), SceneError> {
    let malformed = |reason: &str| SceneError::MalformedParameter {
        text: text.into(),
        reason: reason.into(),
    };
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| malformed("expected NAME=VALUE"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(malformed("the name is empty (expected NAME=VALUE)"));
    }
    let value = value
        .trim()
        .parse::<f64>()
        .map_err(|_| malformed(&format!("'{}' is not a number", value.trim())))?;
    Ok((name.into(), value))
}

impl Scene {
    /// Parse a scene from TOML; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|source| SceneError::Parse {
            origin: origin.into(),
            source,
        })?;
        scene.check()?;
        Ok(scene)
    }

    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
        builtin_scene(name).map(|text| Scene::from_toml(text, &format!("built-in scene '{name}'")))
    }

    /// A built-in scene if `name_or_path` names one, else the scene file at that path.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(scene) = Scene::builtin(name_or_path) {
            return scene;
        }
        let path = Path::new(name_or_path);
        match std::fs::read_to_string(path) {
            Ok(text) => Scene::from_toml(&text, &format!("'{}'", path.display())),
            Err(error)
                if error.kind() == std::io::ErrorKind::NotFound
                    && path.extension().is_none()
                    && path.components().count() == 1 =>
            {
                Err(SceneError::UnknownScene {
                    name: name_or_path.into(),
                })
            }
            Err(source) => Err(SceneError::Read {
                path: path.into(),
                source,
            }),
        }
    }

    /// Consistency checks that need no model: a method for models on ℝᴺ with valid options,
    /// one of v and p, `every` only with a file, valid run options (recovery and divergence
    /// limit only for fixed-step runs).
    pub fn check(&self) -> Result<(), SceneError> {
        self.method_spec()?;
        if self.initial.v.is_some() && self.initial.p.is_some() {
            return Err(SceneError::VelocityAndMomentum);
        }
        if self.run.options()? != RunOptions::default()
            && (self.run.adapt.is_some_and(|adapt| adapt != AdaptMode::None)
                || self.output.output_times.is_some())
        {
            return Err(svi::Error::invalid(
                "recovery",
                "recovery and divergence_limit apply to fixed-step runs (adapt = \"none\", no \
                 output_times)",
            )
            .into());
        }
        match (self.output.every, &self.output.trajectory) {
            (Some(_), None) => Err(SceneError::EveryWithoutOutput),
            (Some(0), Some(_)) => {
                Err(svi::Error::invalid("every", "0 steps; need at least 1").into())
            }
            _ => Ok(()),
        }
    }

    /// Apply command-line overrides.
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        let Overrides {
            method,
            points,
            quadrature,
            h,
            t_end,
            parameters,
            every,
            out,
            diagnostics,
            adapt,
            tol,
            output_times,
            recovery,
            divergence_limit,
        } = overrides;
        if let Some(method) = method {
            method.check_space(SpaceKind::Vector)?;
            // The options written in `--method` replace the scene's; the others carry over.
            self.method.name = *method;
            if method.points().is_some() {
                self.method.points = None;
            }
            if method.quadrature().is_some() {
                self.method.quadrature = None;
            }
        }
        let entry = self.method.name.entry();
        if !entry.takes_quadrature() && quadrature.is_some() {
            return Err(SceneError::OptionNotForMethod {
                option: "quadrature",
                method: self.method.name,
            });
        }
        if !entry.takes_points() && points.is_some() {
            return Err(SceneError::OptionNotForMethod {
                option: "points",
                method: self.method.name,
            });
        }
        set(&mut self.method.points, points);
        set(&mut self.method.quadrature, quadrature);
        set(&mut self.run.h, h);
        set(&mut self.run.t_end, t_end);
        for (name, value) in parameters {
            self.parameters.insert(name.clone(), *value);
        }
        set(&mut self.output.every, every);
        set(&mut self.output.trajectory, out);
        set(&mut self.output.diagnostics, diagnostics);
        set(&mut self.run.adapt, adapt);
        set(&mut self.run.tol, tol);
        set(&mut self.output.output_times, output_times);
        if *recovery == Some(RecoveryKind::None) {
            self.run.max_halvings = None;
        }
        set(&mut self.run.recovery, recovery);
        set(&mut self.run.divergence_limit, divergence_limit);
        self.check()
    }

    /// The method in use: `[method] name` with `points` and `quadrature` applied on top
    /// (each only for a method that takes it). An error names the method if it is not for
    /// models on ℝᴺ, or the option out of range.
    pub fn method_spec(&self) -> Result<MethodSpec, SceneError> {
        let mut spec = self.method.name;
        spec.check_space(SpaceKind::Vector)?;
        if let Some(points) = self.method.points
            && spec.entry().takes_points()
        {
            spec = spec.with_points(points)?;
        }
        if let Some(quadrature) = self.method.quadrature
            && spec.entry().takes_quadrature()
        {
            spec = spec.with_quadrature(quadrature)?;
        }
        Ok(spec)
    }

    /// The number of CGL points in use (`None` for the classic methods or an invalid
    /// method).
    pub fn points(&self) -> Option<usize> {
        self.method_spec().ok()?.points_in_use()
    }

    /// The number of Gauss–Legendre points in use (`None` for all methods but svi or an
    /// invalid method).
    pub fn quadrature(&self) -> Option<usize> {
        self.method_spec().ok()?.quadrature_in_use()
    }

    /// Whether `diagnostic` is asked for.
    pub fn wants(&self, diagnostic: Diagnostic) -> bool {
        self.output
            .diagnostics
            .as_ref()
            .is_none_or(|wanted| wanted.contains(&diagnostic))
    }

    /// Apply the scene's parameters to `model` and resolve the initial time and state, the
    /// step and the horizon (scene values, else the model's defaults).
    pub fn resolve<M: ZooModel<N>, const N: usize>(
        &self,
        model: &mut M,
    ) -> Result<(f64, Initial<N>, f64, f64), SceneError> {
        let scene = self;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let (default_t0, default_q, default_v) = model.initial_state();
        let vector = |field: &'static str, values: &Option<Vec<f64>>| {
            values
                .as_ref()
                .map(|values| {
                    if values.len() == N {
                        Ok(SVector::<f64, N>::from_iterator(values.iter().copied()))
                    } else {
                        Err(SceneError::Dimension {
                            model: model.name().into(),
                            field,
                            expected: N,
                            found: values.len(),
                        })
                    }
                })
                .transpose()
        };
        let q = vector("q", &scene.initial.q)?.unwrap_or(default_q);
        let initial = match (
            vector("v", &scene.initial.v)?,
            vector("p", &scene.initial.p)?,
        ) {
            (Some(_), Some(_)) => return Err(SceneError::VelocityAndMomentum),
            (Some(v), None) => Initial::Velocity { q, v },
            (None, Some(p)) => Initial::Momentum { q, p },
            (None, None) => Initial::Velocity { q, v: default_v },
        };
        Ok((
            scene.initial.t0.unwrap_or(default_t0),
            initial,
            scene.run.h.unwrap_or_else(|| model.default_step()),
            scene.run.t_end.unwrap_or_else(|| model.default_horizon()),
        ))
    }

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

/// `target = value` if a value is given.
fn set<T: Clone>(target: &mut Option<T>, value: &Option<T>) {
    if let Some(value) = value {
        *target = Some(value.clone());
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
        adapt: setup.adapt,
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

/// A state at a requested output time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputPoint {
    /// Time.
    pub t: f64,
    /// Configuration.
    pub q: Vec<f64>,
    /// Velocity.
    pub v: Vec<f64>,
    /// Momentum.
    pub p: Vec<f64>,
}

/// What [`svi::solve()`] did, for the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdaptivitySummary {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected trial steps.
    pub rejected: usize,
    /// Smallest accepted step.
    pub min_step: f64,
    /// Largest accepted step.
    pub max_step: f64,
    /// (CGL points, steps that used them).
    pub points_used: Vec<(usize, usize)>,
    /// Steps of `adapt = "degree"` that missed the tolerance at `max_points`.
    pub unmet: usize,
    /// States reported at output times.
    pub outputs: usize,
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

/// The CSV header line (with its newline) for the given coordinate names.
pub fn csv_header(names: &[&str]) -> String {
    let mut header = String::from("t");
    for prefix in ["q", "v", "p"] {
        for name in names {
            header.push_str(&format!(",{prefix}_{name}"));
        }
    }
    header.push_str(",energy\n");
    header
}

/// An `f64` printed so that it reads back exactly: shortest decimal, in exponent form when
/// very large or small.
#[derive(Debug, Clone, Copy)]
pub struct Float(pub f64);

impl fmt::Display for Float {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A progress bar on stderr, updated about every 1 % of the steps.
#[derive(Debug)]
pub struct Progress {
    bar: ProgressBar,
    stride: usize,
}

impl Progress {
    /// A progress bar for `steps` steps.
    pub fn new(steps: usize) -> Self {
        let bar = ProgressBar::new(steps as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} steps, {elapsed} (eta {eta})")
        {
            bar.set_style(style);
        }
        Progress {
            bar,
            stride: (steps / 100).max(1),
        }
    }

    /// A progress bar for a run from `t0` to `t_end` with step `h`, or `None` if the run has
    /// fewer than [`PROGRESS_MIN_STEPS`] steps (or invalid inputs, which the run rejects).
    pub fn for_run(t0: f64, h: f64, t_end: f64) -> Option<Self> {
        let steps = svi::step_count(t_end - t0, h).ok()?;
        (steps >= PROGRESS_MIN_STEPS).then(|| Progress::new(steps))
    }

    /// Remove the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl<L: ?Sized, P> Observer<L, P> for Progress {
    fn wants(&self, step: usize) -> bool {
        step > 0 && step.is_multiple_of(self.stride)
    }

    fn observe(&mut self, _: &L, step: usize, _: &P) -> ControlFlow<()> {
        self.bar.set_position(step as u64);
        ControlFlow::Continue(())
    }
}

/// Model parameters in the model's order (serialised as a JSON object).
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters(pub Vec<(&'static str, f64)>);

impl Serialize for Parameters {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// Where the trajectory went.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryOutput {
    /// The CSV file.
    pub path: String,
    /// Thinning factor.
    pub every: usize,
    /// Data rows written (the initial point, every `every`-th step, and the last point).
    pub rows: usize,
}

/// The result of running a scene (`svi run --json` prints it as one JSON object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// Names of the configuration coordinates (the order of `q`, `v`, `p`).
    pub coordinates: Vec<String>,
    /// The method's name (see [`registry::METHODS`]; its options are `points` and
    /// `quadrature`).
    pub method: String,
    /// Chebyshev–Gauss–Lobatto points (`None` for the classic methods).
    pub points: Option<usize>,
    /// Gauss–Legendre points (`None` for all methods but svi).
    pub quadrature: Option<usize>,
    /// Classical order of the method.
    pub order: usize,
    /// Whether the method is symmetric.
    pub symmetric: bool,
    /// Whether the method is symplectic.
    pub symplectic: bool,
    /// Step size.
    pub h: f64,
    /// Initial time.
    pub t0: f64,
    /// Final time reached.
    pub t_end: f64,
    /// Steps taken.
    pub steps: usize,
    /// Final configuration.
    pub q: Vec<f64>,
    /// Final velocity.
    pub v: Vec<f64>,
    /// Final momentum.
    pub p: Vec<f64>,
    /// Energy of the initial state.
    pub energy_initial: f64,
    /// Energy of the final state.
    pub energy_final: f64,
    /// Largest |E − E₀| over the step points (`None` if not asked for).
    pub energy_error_max: Option<f64>,
    /// Largest deviation of the Noether momenta (`None` if the model has no symmetry or it
    /// was not asked for).
    pub momentum_error_max: Option<f64>,
    /// Largest position error against the exact solution (`None` if there is none or it was
    /// not asked for).
    pub solution_error_max: Option<f64>,
    /// Nonlinear iterations, summed over all steps.
    pub iterations: usize,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: usize,
    /// Failed steps retried with half the step (`recovery = "halve-step"`).
    pub retries: usize,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The trajectory file, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
    /// Adaptivity mode.
    pub adapt: AdaptMode,
    /// Target final error of the adaptive modes.
    pub tol: Option<f64>,
    /// What the adaptivity did (runs through `svi::solve` only: adaptive or with output
    /// times).
    pub adaptivity: Option<AdaptivitySummary>,
    /// The states at the requested output times (`None` without output times).
    pub outputs: Option<Vec<OutputPoint>>,
}

/// Comma-separated shortest round-trip values in brackets.
fn vector(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|x| Float(*x).to_string()).collect();
    format!("[{}]", items.join(", "))
}

/// `{:.3e}`, or `n/a` when absent.
fn error(value: Option<f64>) -> String {
    value.map_or_else(|| "n/a".into(), |x| format!("{x:.3e}"))
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parameters: Vec<String> = self
            .parameters
            .0
            .iter()
            .map(|(name, value)| format!("{name} = {value}"))
            .collect();
        let mut method = self.method.clone();
        if let Some(points) = self.points {
            method.push_str(&format!(", {points} CGL points"));
        }
        if let Some(quadrature) = self.quadrature {
            method.push_str(&format!(", {quadrature} Gauss points"));
        }
        method.push_str(&format!("; order {}", self.order));
        if self.symmetric {
            method.push_str(", symmetric");
        }
        if self.symplectic {
            method.push_str(", symplectic");
        }
        let coordinates = self.coordinates.join(", ");
        let rows = [
            (
                "model",
                format!("{} ({})", self.model, parameters.join(", ")),
            ),
            ("method", method),
            ("step h", Float(self.h).to_string()),
            (
                "time",
                format!(
                    "{} to {} in {} steps",
                    Float(self.t0),
                    Float(self.t_end),
                    self.steps
                ),
            ),
            ("wall time", format!("{:.3} s", self.seconds)),
            (
                "work",
                format!(
                    "{} nonlinear iterations, {} evaluations{}",
                    self.iterations,
                    self.evaluations,
                    if self.retries > 0 {
                        format!(", {} steps retried with h/2", self.retries)
                    } else {
                        String::new()
                    }
                ),
            ),
            ("coordinates", coordinates),
            ("final q", vector(&self.q)),
            ("final v", vector(&self.v)),
            ("final p", vector(&self.p)),
            (
                "energy",
                format!(
                    "{} to {}",
                    Float(self.energy_initial),
                    Float(self.energy_final)
                ),
            ),
            ("energy error", error(self.energy_error_max)),
            ("momentum error", error(self.momentum_error_max)),
            ("solution error", error(self.solution_error_max)),
        ];
        for (label, value) in rows {
            writeln!(f, "{label:<16}{value}")?;
        }
        if let Some(a) = &self.adaptivity {
            let mut line = format!(
                "{} accepted, {} rejected steps, h from {:.3e} to {:.3e}",
                a.accepted, a.rejected, a.min_step, a.max_step
            );
            if let Some(tol) = self.tol {
                line = format!("{}, tol {tol:e}: {line}", self.adapt.name());
            }
            if self.adapt == AdaptMode::Degree {
                let used: Vec<String> = a
                    .points_used
                    .iter()
                    .map(|(points, steps)| format!("{points}:{steps}"))
                    .collect();
                line.push_str(&format!("; points:steps {}", used.join(" ")));
                if a.unmet > 0 {
                    line.push_str(&format!("; {} steps missed tol at max_points", a.unmet));
                }
            }
            writeln!(f, "{:<16}{line}", "adaptivity")?;
        }
        for point in self.outputs.iter().flatten() {
            writeln!(
                f,
                "{:<16}q {} v {} p {}",
                format!("t = {}", Float(point.t)),
                vector(&point.q),
                vector(&point.v),
                vector(&point.p)
            )?;
        }
        if let Some(trajectory) = &self.trajectory {
            writeln!(
                f,
                "{:<16}{} ({} rows, every {} steps)",
                "trajectory", trajectory.path, trajectory.rows, trajectory.every
            )?;
        }
        Ok(())
    }
}

/// A zoo model's name, dimension, coordinates, parameters and defaults (for `svi list`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelDescription {
    /// Name.
    pub name: &'static str,
    /// Configuration coordinate names.
    pub coordinates: Vec<&'static str>,
    /// Default parameters.
    pub parameters: Parameters,
    /// Default step.
    pub h: f64,
    /// Default horizon.
    pub t_end: f64,
    /// Number of Noether momenta.
    pub momenta: usize,
    /// Whether an exact solution is known for the default initial state.
    pub exact_solution: bool,
}

/// Describes a model.
struct Describe;

impl ModelVisitor for Describe {
    type Output = ModelDescription;

    fn visit<M: ZooModel<N>, const N: usize>(self, model: M) -> ModelDescription {
        let (t0, q0, v0) = model.initial_state();
        ModelDescription {
            name: model.name(),
            coordinates: model.coordinate_names().to_vec(),
            parameters: Parameters(model.parameters()),
            h: model.default_step(),
            t_end: model.default_horizon(),
            momenta: model.generator_count(),
            exact_solution: model.exact_solution(t0, &q0, &v0, t0).is_some(),
        }
    }
}

/// Descriptions of all zoo models, in [`MODEL_NAMES`] order.
pub fn describe_models() -> Vec<ModelDescription> {
    MODEL_NAMES
        .iter()
        .filter_map(|name| visit_model(name, Describe).ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(name: &str) -> Scene {
        Scene::builtin(name).expect("built-in").expect("parses")
    }

    fn overrides() -> Overrides {
        Overrides::default()
    }

    fn method(text: &str) -> MethodSpec {
        text.parse().expect("a method")
    }

    #[test]
    fn every_builtin_scene_parses_and_names_a_zoo_model() {
        assert_eq!(
            builtin_scene_names(),
            [
                "oscillator",
                "kepler",
                "pendulum",
                "spring-pendulum",
                "double-pendulum",
                "damped-oscillator",
                "damped-pendulum",
                "driven-oscillator",
                "stiff-spring-pendulum",
                "stiff-spring-pendulum-coarse",
                "kepler-long",
                "kepler-e0.9",
                "kepler-e0.99",
                "kepler-recovery",
                "double-pendulum-chaotic",
                "oscillator-beyond-stability"
            ]
        );
        for name in builtin_scene_names() {
            let scene = scene(name);
            assert!(MODEL_NAMES.contains(&scene.model.as_str()), "{name}");
            if MODEL_NAMES.contains(&name) {
                assert_eq!(scene.model, name);
                assert_eq!(scene.method.name, method("svi"));
            } else {
                // The stress scenes are named after their model.
                assert!(name.contains(&scene.model), "{name}");
            }
        }
        assert!(Scene::builtin("kepler2").is_none());
    }

    #[test]
    fn oscillator_scene_is_the_papers_setting() {
        let scene = scene("oscillator");
        assert_eq!(scene.parameters["sigma"], 1.0);
        assert_eq!(scene.initial.t0, Some(0.0));
        assert_eq!(scene.initial.q, Some(vec![0.0]));
        assert_eq!(scene.initial.p, Some(vec![1.0]));
        assert_eq!(scene.initial.v, None);
        assert_eq!(scene.run.h, Some(1.0));
        assert_eq!(scene.run.t_end, Some(100.0));
        assert_eq!(scene.points(), Some(9));
        assert_eq!(scene.quadrature(), Some(18));
        assert!(scene.output.trajectory.is_none());
        for diagnostic in [
            Diagnostic::Energy,
            Diagnostic::Momentum,
            Diagnostic::Solution,
        ] {
            assert!(scene.wants(diagnostic));
        }
    }

    #[test]
    fn kepler_scene_is_the_papers_setting() {
        let scene = scene("kepler");
        assert_eq!(scene.parameters["e"], 0.5);
        assert_eq!(scene.initial, InitialSection::default());
        assert_eq!(scene.run.h, Some(0.2));
        assert_eq!(scene.run.t_end, Some(2000.0));
        assert_eq!(scene.points(), Some(6));
        assert_eq!(scene.quadrature(), Some(12));
        assert_eq!(DEFAULT_SCENE, "kepler");
    }

    #[test]
    fn the_other_scenes_use_the_model_defaults() {
        for name in ["pendulum", "spring-pendulum", "double-pendulum"] {
            let scene = scene(name);
            assert!(scene.parameters.is_empty(), "{name}");
            assert_eq!(scene.initial, InitialSection::default(), "{name}");
            assert_eq!(scene.run, RunSection::default(), "{name}");
            assert_eq!(scene.points(), Some(6), "{name}");
        }
    }

    #[test]
    fn a_minimal_scene_falls_back_to_defaults() {
        let scene = Scene::from_toml("model = \"pendulum\"\n", "test").unwrap();
        assert_eq!(scene.method.name, method("svi"));
        assert_eq!(scene.points(), Some(svi::Svi::default().points));
        assert_eq!(scene.quadrature(), Some(2 * svi::Svi::default().points));
        assert_eq!(scene.output, OutputSection::default());
    }

    #[test]
    fn overrides_replace_scene_fields() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                method: Some(method("svi")),
                points: Some(5),
                quadrature: Some(7),
                h: Some(0.05),
                t_end: Some(10.0),
                parameters: vec![("e".into(), 0.9)],
                every: Some(10),
                out: Some("x.csv".into()),
                diagnostics: Some(vec![Diagnostic::Energy]),
                adapt: Some(AdaptMode::Degree),
                tol: Some(1e-9),
                output_times: Some(vec![1.0, 2.0]),
                recovery: None,
                divergence_limit: None,
            })
            .unwrap();
        assert_eq!(scene.run.adapt, Some(AdaptMode::Degree));
        assert_eq!(scene.run.tol, Some(1e-9));
        assert_eq!(scene.output.output_times, Some(vec![1.0, 2.0]));
        // Recovery and a divergence limit are for fixed-step runs only.
        let recovery = Overrides {
            recovery: Some(RecoveryKind::HalveStep),
            divergence_limit: Some(1e9),
            ..Overrides::default()
        };
        assert!(scene.clone().apply(&recovery).is_err());
        let mut fixed = self::scene("kepler");
        fixed.apply(&recovery).unwrap();
        assert_eq!(fixed.run.recovery, Some(RecoveryKind::HalveStep));
        assert_eq!(
            fixed.run.options().unwrap(),
            RunOptions::default()
                .with_recovery(Recovery::HalveStep {
                    max_halvings: DEFAULT_MAX_HALVINGS
                })
                .with_divergence_limit(1e9)
        );
        assert_eq!(scene.points(), Some(5));
        assert_eq!(scene.quadrature(), Some(7));
        assert_eq!(scene.run.h, Some(0.05));
        assert_eq!(scene.run.t_end, Some(10.0));
        assert_eq!(scene.parameters["e"], 0.9);
        assert_eq!(scene.output.every, Some(10));
        assert_eq!(scene.output.trajectory, Some("x.csv".into()));
        assert!(scene.wants(Diagnostic::Energy));
        assert!(!scene.wants(Diagnostic::Momentum));
        assert!(!scene.wants(Diagnostic::Solution));
    }

    #[test]
    fn points_without_quadrature_keep_the_papers_rule() {
        let mut scene = scene("oscillator");
        scene
            .apply(&Overrides {
                points: Some(4),
                ..overrides()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), Some(8));
    }

    #[test]
    fn switching_to_sc_drops_the_quadrature_and_rejects_it_as_a_flag() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                method: Some(method("sc")),
                ..overrides()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), None);
        let error = scene
            .apply(&Overrides {
                quadrature: Some(12),
                ..overrides()
            })
            .unwrap_err();
        assert!(matches!(
            error,
            SceneError::OptionNotForMethod {
                option: "quadrature",
                method
            } if method == self::method("sc")
        ));
    }

    #[test]
    fn classic_methods_have_neither_points_nor_quadrature() {
        for name in [
            "symplectic-euler",
            "symplectic-euler-adjoint",
            "midpoint",
            "verlet",
            "trapezoid",
        ] {
            let kind = method(name);
            assert_eq!(kind.name(), name);
            assert!(!kind.entry().takes_points());
            // The scene's `points = 9` is ignored, a `--points` flag is an error.
            let mut scene = scene("oscillator");
            scene
                .apply(&Overrides {
                    method: Some(kind),
                    ..overrides()
                })
                .unwrap();
            assert_eq!((scene.points(), scene.quadrature()), (None, None));
            let error = scene
                .apply(&Overrides {
                    points: Some(4),
                    ..overrides()
                })
                .unwrap_err();
            assert_eq!(
                error.to_string(),
                format!(
                    "--points is an option of svi and sc, not of {}",
                    kind.name()
                )
            );
            let summary = scene.run(false).unwrap();
            assert_eq!(summary.method, kind.name());
            assert_eq!((summary.points, summary.quadrature), (None, None));
            assert!(summary.symplectic && summary.order <= 2);
            // h = 1 on the oscillator: first- and second-order methods are coarse (the phase
            // is lost) but stable, with bounded energy error.
            assert!(summary.energy_error_max.unwrap() <= 0.5, "{kind}");
            assert!(summary.solution_error_max.unwrap() < 2.0, "{kind}");
        }
    }

    #[test]
    fn the_damped_oscillator_scene_reports_its_solution_error() {
        let scene = scene("damped-oscillator");
        assert_eq!(scene.parameters["zeta"], 0.1);
        assert_eq!((scene.run.h, scene.run.t_end), (Some(0.1), Some(50.0)));
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 500);
        assert!(summary.solution_error_max.unwrap() < 1e-12);
        // E(50) = E(0) e^{−5}-ish: the friction removed almost all the energy.
        assert!(summary.energy_final < 0.01 * summary.energy_initial);
        let mut verlet = scene.clone();
        verlet.method.name = method("verlet");
        let summary = verlet.run(false).unwrap();
        // Second order: 1.6e-3 at h = 0.1.
        let error = summary.solution_error_max.unwrap();
        assert!(error > 1e-3 && error < 2e-3, "{error:e}");
        assert_eq!(summary.evaluations, 501);
    }

    #[test]
    fn parameters_parse_as_name_equals_number() {
        assert_eq!(parse_parameter("e=0.9").unwrap(), ("e".into(), 0.9));
        assert_eq!(parse_parameter(" g = 9.81 ").unwrap(), ("g".into(), 9.81));
        assert_eq!(parse_parameter("k=1e4").unwrap(), ("k".into(), 1e4));
        for bad in ["e", "e=", "=1", "e=abc", "e:1"] {
            let error = parse_parameter(bad).unwrap_err();
            assert!(
                matches!(&error, SceneError::MalformedParameter { text, .. } if text == bad),
                "{bad}: {error}"
            );
        }
    }

    #[test]
    fn scene_format_errors_name_the_line() {
        let text = "model = \"kepler\"\n[run]\nh = 0.1\nstep = 3\n";
        let error = Scene::from_toml(text, "'test.toml'").unwrap_err();
        let SceneError::Parse { origin, source } = &error else {
            panic!("{error}")
        };
        assert_eq!(origin, "'test.toml'");
        let message = source.to_string();
        assert!(message.contains("line 4"), "{message}");
        assert!(message.contains("step"), "{message}");
    }

    #[test]
    fn unknown_method_and_diagnostic_names_are_listed() {
        let error =
            Scene::from_toml("model = \"kepler\"\n[method]\nname = \"rk4\"\n", "t").unwrap_err();
        let SceneError::Parse { source, .. } = &error else {
            panic!("{error}")
        };
        assert!(
            source
                .to_string()
                .contains("unknown method 'rk4' (known: svi, sc, symplectic-euler,")
        );
        let text = "model = \"kepler\"\n[output]\ndiagnostics = [\"energy\", \"angular\"]\n";
        let SceneError::Parse { source, .. } = Scene::from_toml(text, "t").unwrap_err() else {
            panic!()
        };
        let message = source.to_string();
        assert!(
            message.contains("unknown diagnostic 'angular'"),
            "{message}"
        );
        assert!(message.contains("line 3"), "{message}");
    }

    #[test]
    fn both_velocity_and_momentum_are_rejected() {
        let text = "model = \"kepler\"\n[initial]\nq = [1, 0]\nv = [0, 1]\np = [0, 1]\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::VelocityAndMomentum)
        ));
    }

    #[test]
    fn every_needs_a_file_and_a_positive_count() {
        let text = "model = \"kepler\"\n[output]\nevery = 10\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::EveryWithoutOutput)
        ));
        let text = "model = \"kepler\"\n[output]\nevery = 0\ntrajectory = \"x.csv\"\n";
        assert!(matches!(
            Scene::from_toml(text, "t"),
            Err(SceneError::Svi(svi::Error::InvalidParameter { name, .. })) if name == "every"
        ));
    }

    #[test]
    fn wrong_dimension_names_field_and_sizes() {
        let text = "model = \"kepler\"\n[initial]\nq = [1, 0, 0]\n";
        let error = Scene::from_toml(text, "t").unwrap().run(false).unwrap_err();
        assert!(matches!(
            &error,
            SceneError::Dimension {
                field: "q",
                expected: 2,
                found: 3,
                ..
            }
        ));
        assert_eq!(
            error.to_string(),
            "initial.q has 3 components, but model 'kepler' has dimension 2"
        );
        let text = "model = \"oscillator\"\n[initial]\np = []\n";
        let error = Scene::from_toml(text, "t").unwrap().run(false).unwrap_err();
        assert!(matches!(
            error,
            SceneError::Dimension {
                field: "p",
                expected: 1,
                found: 0,
                ..
            }
        ));
    }

    #[test]
    fn an_unknown_model_lists_the_known_ones() {
        let error = Scene::from_toml("model = \"kepler3\"\n", "t")
            .unwrap()
            .run(false)
            .unwrap_err();
        assert!(matches!(error, SceneError::UnknownModel(_)));
        assert!(error.to_string().contains("known: oscillator, pendulum"));
    }

    #[test]
    fn a_missing_bare_name_is_an_unknown_scene_and_a_missing_path_a_read_error() {
        let error = Scene::load("keppler").unwrap_err();
        assert!(matches!(error, SceneError::UnknownScene { .. }));
        assert!(error.to_string().contains("oscillator, kepler"), "{error}");
        let path = std::env::temp_dir().join("svi-cli-no-such-dir/scene.toml");
        let error = Scene::load(path.to_str().unwrap()).unwrap_err();
        assert!(matches!(error, SceneError::Read { .. }), "{error}");
    }

    #[test]
    fn a_run_that_asks_for_nothing_reports_no_errors() {
        let mut scene = scene("oscillator");
        scene.output.diagnostics = Some(vec![]);
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 100);
        assert_eq!(summary.energy_error_max, None);
        assert_eq!(summary.momentum_error_max, None);
        assert_eq!(summary.solution_error_max, None);
        // q(100) = sin(100) for q0 = 0, p0 = 1.
        assert!(
            (summary.q[0] - 100f64.sin()).abs() < 1e-10,
            "{:?}",
            summary.q
        );
    }

    #[test]
    fn the_summary_reports_the_initial_and_final_energy() {
        let mut scene = scene("kepler");
        scene.run.t_end = Some(2.0);
        let summary = scene.run(false).unwrap();
        assert_eq!(summary.steps, 10);
        assert!((summary.energy_initial + 0.5).abs() < 1e-15);
        assert!(
            (summary.energy_final + 0.5).abs() < 1e-9,
            "{}",
            summary.energy_final
        );
        assert_eq!(summary.parameters, Parameters(vec![("e", 0.5)]));
        assert_eq!(summary.coordinates, ["q1", "q2"]);
        assert!(summary.to_string().contains("kepler (e = 0.5)"));
    }

    #[test]
    fn csv_header_prefixes_the_coordinate_names() {
        assert_eq!(
            csv_header(&["q1", "q2"]),
            "t,q_q1,q_q2,v_q1,v_q2,p_q1,p_q2,energy\n"
        );
        assert_eq!(csv_header(&["q"]), "t,q_q,v_q,p_q,energy\n");
    }

    #[test]
    fn floats_print_to_round_trip() {
        for x in [
            0.0,
            1.0,
            -0.5,
            0.1,
            1.0 / 3.0,
            2000.0,
            1e-300,
            -2.5e-17,
            1e20,
            123456.789,
        ] {
            let text = Float(x).to_string();
            assert_eq!(text.parse::<f64>().unwrap(), x, "{text}");
            assert!(text.len() < 26, "{text}");
        }
        assert_eq!(Float(0.2).to_string(), "0.2");
        assert_eq!(Float(1e-300).to_string(), "1e-300");
    }

    #[test]
    fn progress_is_only_for_long_runs() {
        assert!(Progress::for_run(0.0, 0.2, 2000.0).is_some());
        assert!(Progress::for_run(0.0, 1.0, 100.0).is_none());
        assert!(Progress::for_run(0.0, 0.0, 100.0).is_none());
        assert!(Progress::for_run(0.0, -1.0, 100.0).is_none());
        let progress = Progress::new(10_000);
        assert_eq!(progress.stride, 100);
        let wants = |step| Observer::<(), ()>::wants(&progress, step);
        assert!(!wants(0));
        assert!(!wants(150));
        assert!(wants(200));
    }
}
