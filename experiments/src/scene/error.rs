//! [`SceneError`]: everything that can go wrong between reading a scene and writing its
//! outputs, and which of it is bad input ([`SceneError::is_bad_input`]: exit status 2) rather
//! than a run that failed (exit status 1).

use std::path::PathBuf;

use svi::MethodSpec;
use svi::method::registry::{self, SpaceKind};
use svi_models::{
    GROUP_MODEL_NAMES, LOCAL_MODEL_NAMES, MODEL_NAMES, RIGID_MODEL_NAMES, UnknownModel,
};

use crate::report::csv::Float;
use crate::report::output::OutputError;
use crate::report::plot::PlotError;
use crate::report::summary::Summary;
use crate::scene::builtin::builtin_scene_names;
use crate::scene::schema::UnknownDiagnostic;

/// Everything that can go wrong between reading a scene and writing its outputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene is not valid TOML or does not fit the scene format. The message quotes the
    /// parser's, which names the line and column, with its long numbers written short.
    #[error("cannot parse scene {origin}: {}", shorten_long_numbers(&parser.to_string()))]
    Parse {
        /// Where the text came from (a file path or `built-in scene 'name'`).
        origin: String,
        /// The TOML parser's error. Not the error's `source`: its message writes a value such
        /// as 1e-300 with all its digits, so the message above carries a shortened copy.
        parser: toml::de::Error,
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
    /// A path that names no regular file of at most
    /// [`MAX_SCENE_BYTES`](crate::scene::limits::MAX_SCENE_BYTES): a directory, a FIFO, a
    /// device, a huge file (read only up to the limit, never without bound).
    #[error("'{}' is not a scene file: {reason}", path.display())]
    NotASceneFile {
        /// The path given.
        path: PathBuf,
        /// What it is instead.
        reason: String,
    },
    /// A name given to `svi stress --cases` that is not one of its stress cases (its own
    /// list, not every built-in scene).
    #[error(
        "'{name}' is not a stress case of svi stress (stress cases: {})",
        known.join(", ")
    )]
    UnknownStressCase {
        /// The name asked for.
        name: String,
        /// The stress cases.
        known: Vec<&'static str>,
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
    /// A model name that is not in the zoo (the message lists the models on ℝᴺ, the rigid
    /// bodies, the models on other Lie groups and the chains of runtime dimension).
    #[error(
        "unknown model '{}' (known: {}; rigid bodies: {}; on Lie groups: {}; chains of any          size: {})",
        .0.name,
        MODEL_NAMES.join(", "),
        RIGID_MODEL_NAMES.join(", "),
        GROUP_MODEL_NAMES.join(", "),
        LOCAL_MODEL_NAMES.join(", ")
    )]
    UnknownModel(UnknownModel),
    /// A scene with neither a zoo model nor a Lagrangian written as text.
    #[error(
        "the scene names no model: give model = \"NAME\" (see svi list) or write the \
         Lagrangian, lagrangian = \"...\" with coordinates = [...]"
    )]
    NoModel,
    /// A scene with both a zoo model and a Lagrangian or Hamiltonian written as text.
    #[error(
        "the scene gives both model = \"{model}\" and lagrangian or hamiltonian: give one of \
         them"
    )]
    ModelAndLagrangian {
        /// The zoo model named.
        model: String,
    },
    /// A scene with both a Lagrangian and a Hamiltonian written as text.
    #[error("the scene gives both lagrangian and hamiltonian: give one of them")]
    LagrangianAndHamiltonian,
    /// A Lagrangian written as text that cannot be read (the message names the field, the
    /// column and the symbol).
    #[error(transparent)]
    Text(#[from] svi::model::text::TextError),
    /// A field that a scene with a Lagrangian written as text must give: such a model has
    /// no default initial state, step or horizon.
    #[error("{field} is needed: a Lagrangian written as text has no default for it")]
    TextModelNeeds {
        /// The field, as written in the scene.
        field: &'static str,
    },
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
    /// A diagnostic name that is not one of
    /// [`Diagnostic::NAMES`](crate::scene::schema::Diagnostic::NAMES).
    #[error(transparent)]
    UnknownDiagnostic(#[from] UnknownDiagnostic),
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
    /// An option, or a scene field, that the scene's model, method or other options cannot
    /// use (it would otherwise be silently ignored).
    #[error("{option}: {reason}")]
    NotApplicable {
        /// The option as written on the command line, with the scene field where there is
        /// one: `--tol (run.tol)`.
        option: &'static str,
        /// Why it does not apply, and what would.
        reason: String,
    },
    /// A command-line option (or its scene field) whose value is out of range: a count above
    /// its cap, a time budget that is not a finite positive number of seconds below its cap,
    /// a horizon that cannot be run (see [`crate::scene::limits`]).
    #[error("invalid {option}: {reason}")]
    InvalidOption {
        /// The option as written on the command line, with the scene field where there is
        /// one: `--t-end (run.t_end)`.
        option: &'static str,
        /// What is wrong with the value, and what would do.
        reason: String,
    },
    /// A trajectory thinning factor without a file to write the trajectory to.
    #[error("output.every is set but no trajectory file is (give --out FILE or output.trajectory)")]
    EveryWithoutOutput,
    /// An output file (trajectory, table, picture) or its directory cannot be written.
    #[error("cannot write output file '{}'", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Standard output could not be written (a full device, a closed pipe).
    #[error("cannot write to standard output")]
    Stdout(#[source] std::io::Error),
    /// An output path that cannot be used (a link, a directory, a FIFO, a device, the scene
    /// file, another output's file, a name of another format): bad input, named before any
    /// work.
    #[error("cannot write {option} to '{}': {reason}", path.display())]
    Output {
        /// The option, as written on the command line.
        option: &'static str,
        /// The path given.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
    /// A plot (`--plot`, `svi ensemble --plot`) cannot be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A run that reached its horizon but failed its health check, under `svi run --strict`.
    #[error("the run failed its health check (--strict): {}", .warnings.join("; "))]
    Unhealthy {
        /// The messages of the failed checks.
        warnings: Vec<String>,
    },
    /// Everything the library rejects: parameters, step, horizon, method options, initial
    /// state, nonlinear solves.
    #[error(transparent)]
    Svi(#[from] svi::Error),
    /// A run that failed after it started: the summary of the run up to the last good state
    /// (its trajectory file, if asked for, is written) and the library's error.
    #[error(
        "the run failed after {} steps; last good state at t = {}: {}{}",
        .partial.steps,
        Float(.partial.t_end),
        .partial.state.describe(),
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
    /// A run stopped by its caller's stop flag ([`crate::run::Control::stop`]; Ctrl-C in
    /// Python) before its horizon: nothing of it is reported as a result.
    #[error("interrupted: {at}")]
    Interrupted {
        /// Where: the time and step a run reached, the members of an ensemble.
        at: String,
    },
    /// A method name of `svi bench` or `svi stress` that is neither a library method nor
    /// one of the peers `dop853`, `dopri5`, `radau5` and `molly`.
    #[error(
        "unknown method '{text}' (known: {}, dop853, dopri5, radau5, molly)",
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
    /// A benchmark of a model without an exact solution whose resolved reference run failed
    /// or did not converge.
    #[error("model '{model}' has no exact solution for this initial state, and {reason}")]
    NoReference {
        /// The model's name.
        model: String,
        /// What happened to the reference run.
        reason: String,
    },
}

impl From<OutputError> for SceneError {
    fn from(error: OutputError) -> SceneError {
        match error {
            OutputError::Unusable {
                option,
                path,
                reason,
            } => SceneError::Output {
                option,
                path,
                reason,
            },
            OutputError::Write { path, source } => SceneError::Write { path, source },
            OutputError::Stdout(source) => SceneError::Stdout(source),
        }
    }
}

impl From<UnknownModel> for SceneError {
    fn from(error: UnknownModel) -> SceneError {
        SceneError::UnknownModel(error)
    }
}

/// The methods on the same space as `method` that take `option`, as named in
/// [`SceneError::OptionNotForMethod`]: "svi and sc".
fn option_owners(option: &str, method: &MethodSpec) -> String {
    let has = match option {
        "points" => registry::Entry::takes_points,
        _ => registry::Entry::takes_quadrature,
    };
    methods_with(method.space(), has)
}

/// The methods on `space` that have an option, as named in messages: "svi and sc".
pub fn methods_with(space: SpaceKind, has: fn(&registry::Entry) -> bool) -> String {
    let names: Vec<&str> = registry::METHODS
        .iter()
        .filter(|entry| entry.space == space && has(entry))
        .map(|entry| entry.name)
        .collect();
    match names.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => "no method".into(),
    }
}

impl SceneError {
    /// Whether the error is in the input (a scene, an option, a value the library rejects
    /// as invalid) rather than in a run that started: `svi` exits with status 2 for bad input
    /// and 1 for a failed run (or an output that cannot be written).
    pub fn is_bad_input(&self) -> bool {
        match self {
            SceneError::Svi(error) => is_bad_input(error),
            SceneError::RunFailed { .. }
            | SceneError::Interrupted { .. }
            | SceneError::Write { .. }
            | SceneError::Stdout(_)
            | SceneError::Plot(_)
            | SceneError::Unhealthy { .. } => false,
            _ => true,
        }
    }
}

/// Whether a library error is in the input ([`svi::Error::InvalidParameter`]) rather than in
/// a run (a solve that does not converge, a state that diverges, ...).
pub fn is_bad_input(error: &svi::Error) -> bool {
    matches!(error, svi::Error::InvalidParameter { .. })
}

/// Numbers of 17 or more digits in `text` (the TOML parser writes 1e-300 as 0.000…1 with
/// 300 zeros) rewritten in the shortest exponent form, `1e-300`; the rest unchanged.
fn shorten_long_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let token = &rest[start..];
        let end = token
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(token.len());
        let (number, tail) = token.split_at(end);
        let digits = number.chars().filter(char::is_ascii_digit).count();
        match number.parse::<f64>() {
            Ok(value) if digits >= 17 => out.push_str(&format!("{value:e}")),
            _ => out.push_str(number),
        }
        rest = tail;
    }
    out.push_str(rest);
    out
}

impl From<crate::scene::events::SpecError> for SceneError {
    fn from(error: crate::scene::events::SpecError) -> Self {
        SceneError::InvalidOption {
            option: error.option,
            reason: error.reason,
        }
    }
}
