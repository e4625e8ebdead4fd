//! # svi-cli — the `svi` command-line tool
//!
//! - [`scene`]: what to simulate — the scene format (TOML), the built-in scenes, the
//!   command-line overrides, and every check of a scene's input;
//! - [`command`]: what `svi` does with it — `run` (the one run path for every space), `list`,
//!   `bench`, `compare`, `stability`, `stress`;
//! - [`report`]: what comes out — the one run summary, trajectory CSV and number format,
//!   plots, the progress bar.
//!
//! The binary (`main.rs`) defines the arguments and dispatches to [`command`].

pub mod command;
pub mod report;
pub mod scene;

pub use command::list::{ModelDescription, describe_models};
pub use command::{bench, stability, stress};
pub use report::csv::{Float, csv_header};
pub use report::progress::{PROGRESS_MIN_STEPS, PROGRESS_MIN_WORK, Progress};
pub use report::summary::{
    AdaptivitySummary, Conservation, OutputPoint, Parameters, SolveSummary, StateSummary, Summary,
    TrajectoryOutput,
};
pub use scene::builtin::{BUILTIN_SCENES, DEFAULT_SCENE, builtin_scene, builtin_scene_names};
pub use scene::overrides::{Overrides, method_help, parse_parameter};
pub use scene::schema::{
    AdaptMode, BoundaryName, Components, DEFAULT_MAX_HALVINGS, Diagnostic, FormName,
    InitialSection, MethodSection, OutputSection, RecoveryKind, RunSection,
};
pub use scene::{Scene, SceneError};
