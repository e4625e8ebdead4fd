//! # svi-experiments — the experiments of svi as a library
//!
//! What the `svi` command line and the Python package run, with a typed Rust API; the two
//! front doors parse their arguments, call this crate and print or convert what it returns.
//!
//! - [`scene`]: what to simulate — the scene format (TOML), the built-in scenes, the
//!   overrides of a scene's options, and every check of a scene's input;
//! - [`run`]: one run of a scene on any space (ℝᴺ, ℝⁿ chains, SO(3)), and of the field and
//!   pseudospectral scenes;
//! - [`ensemble`], [`bench`](mod@bench), [`compare`], [`stability`], [`stress`], [`scale`],
//!   [`list`]: the experiments built on runs;
//! - [`report`]: what comes out — the one run summary, trajectory CSV and number format,
//!   plots, the progress bar.

pub mod bench;
pub mod compare;
pub mod ensemble;
pub mod list;
pub mod report;
pub mod run;
pub mod scale;
pub mod scene;
pub mod stability;
pub mod stress;

pub use list::{ModelDescription, describe_models};
pub use report::csv::{Float, csv_header};
pub use report::progress::{PROGRESS_MIN_STEPS, PROGRESS_MIN_WORK, Progress};
pub use report::summary::{
    AdaptivitySummary, Conservation, OutputPoint, Parameters, SolveSummary, StateSummary, Summary,
    TrajectoryOutput,
};
pub use run::Control;
pub use scene::any::AnyScene;
pub use scene::builtin::{BUILTIN_SCENES, DEFAULT_SCENE, builtin_scene, builtin_scene_names};
pub use scene::overrides::{Overrides, method_help, parse_parameter};
pub use scene::schema::{
    AdaptMode, BoundaryName, Components, DEFAULT_MAX_HALVINGS, Diagnostic, FormName,
    InitialSection, MethodSection, OutputSection, RecoveryKind, RunSection,
};
pub use scene::{Scene, SceneError};
