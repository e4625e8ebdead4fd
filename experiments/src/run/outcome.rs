//! The outcome of a run of any kind of scene ([`AnyScene::run`]): its summary ([`AnySummary`])
//! or its error, with the summary up to its last good state where the run started; the JSON
//! `error` object of a scene error and the failure object of bad input.

use serde::Serialize;

use crate::report::field::FieldSummary;
use crate::report::health::Warning;
use crate::report::schema::{Kind, SCHEMA_VERSION, Versioned};
use crate::report::spectral::SpectralSummary;
use crate::report::summary::{ErrorReport, Status, Summary};
use crate::run::Control;
use crate::scene::SceneError;
use crate::scene::any::AnyScene;

/// The summary of a run of some kind of scene: what a front door prints.
pub trait RunSummary: Versioned + std::fmt::Display + Sized {
    /// The health checks the run failed.
    fn warnings(&self) -> &[Warning];
    /// Mark the run failed with `report` (a failed health check under `--strict`).
    fn fail(&mut self, report: ErrorReport);
    /// The summary of the run up to its last good state that `error` carries, if any.
    fn partial(error: &SceneError) -> Option<Self>;
}

impl RunSummary for Summary {
    fn warnings(&self) -> &[Warning] {
        &self.warnings
    }
    fn fail(&mut self, report: ErrorReport) {
        self.status = Status::Failed;
        self.error = Some(report);
    }
    fn partial(error: &SceneError) -> Option<Self> {
        match error {
            SceneError::RunFailed { partial, .. } => Some((**partial).clone()),
            _ => None,
        }
    }
}

/// The one JSON object of a command that failed before it ran anything (bad input, also
/// arguments the parser rejects): `{"schema_version": 1, "kind": "failure", "status": "failed",
/// "error": {kind, message, step, t}}`.
pub fn failure_object(report: &ErrorReport) -> serde_json::Value {
    serde_json::json!({
        "schema_version": SCHEMA_VERSION,
        "kind": Kind::Failure,
        "status": Status::Failed,
        "error": report,
    })
}

/// The JSON `error` object of a scene error: the library's kind for its errors, `health`,
/// `output`, or `invalid_input` for other bad input.
pub fn error_report(error: &SceneError) -> ErrorReport {
    let kind = match error {
        SceneError::Svi(error) | SceneError::RunFailed { source: error, .. } => {
            return ErrorReport::of(error);
        }
        SceneError::Unhealthy { .. } => "health",
        SceneError::Write { .. } | SceneError::Stdout(_) | SceneError::Plot(_) => "output",
        _ => "invalid_input",
    };
    ErrorReport {
        kind,
        message: error.to_string(),
        step: None,
        t: None,
    }
}

/// The summary of a run of a scene of any kind.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum AnySummary {
    /// A run on ℝⁿ or SO(3).
    Ode(Box<Summary>),
    /// A multisymplectic field run.
    Field(Box<FieldSummary>),
    /// A pseudospectral run.
    Pseudospectral(Box<SpectralSummary>),
}

impl AnyScene {
    /// Check the scene once and run it, watched by `control` (a field or pseudospectral run
    /// draws its progress bar but has no stop flag: a `control.stop` is refused for it).
    pub fn run(&self, control: Control<'_>) -> Result<AnySummary, SceneError> {
        if control.stop.is_some() && !matches!(self, AnyScene::Ode(_)) {
            return Err(SceneError::NotApplicable {
                option: "stop",
                reason: "a field or pseudospectral run cannot be stopped between steps".into(),
            });
        }
        Ok(match self {
            AnyScene::Ode(scene) => AnySummary::Ode(Box::new(scene.run(control)?)),
            AnyScene::Field(scene) => AnySummary::Field(Box::new(scene.run(control.progress)?)),
            AnyScene::Pseudospectral(scene) => {
                AnySummary::Pseudospectral(Box::new(scene.run(control.progress)?))
            }
        })
    }
}

impl Versioned for AnySummary {
    fn kind(&self) -> Kind {
        match self {
            AnySummary::Ode(summary) => summary.kind(),
            AnySummary::Field(summary) => summary.kind(),
            AnySummary::Pseudospectral(summary) => summary.kind(),
        }
    }
    fn deprecated(&self) -> Vec<(&'static str, serde_json::Value)> {
        match self {
            AnySummary::Ode(summary) => summary.deprecated(),
            AnySummary::Field(summary) => summary.deprecated(),
            AnySummary::Pseudospectral(summary) => summary.deprecated(),
        }
    }
}

impl std::fmt::Display for AnySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AnySummary::Ode(summary) => summary.fmt(f),
            AnySummary::Field(summary) => summary.fmt(f),
            AnySummary::Pseudospectral(summary) => summary.fmt(f),
        }
    }
}

impl RunSummary for AnySummary {
    fn warnings(&self) -> &[Warning] {
        match self {
            AnySummary::Ode(summary) => summary.warnings(),
            AnySummary::Field(summary) => summary.warnings(),
            AnySummary::Pseudospectral(summary) => summary.warnings(),
        }
    }
    fn fail(&mut self, report: ErrorReport) {
        match self {
            AnySummary::Ode(summary) => summary.fail(report),
            AnySummary::Field(summary) => summary.fail(report),
            AnySummary::Pseudospectral(summary) => summary.fail(report),
        }
    }
    fn partial(error: &SceneError) -> Option<Self> {
        Summary::partial(error).map(|summary| AnySummary::Ode(Box::new(summary)))
    }
}
