//! What `svi run` prints of a run of any kind of scene: its summary or its error (with the
//! summary up to its last good state) as text or as one JSON object, the failed health checks
//! on stderr, and the JSON `error` object of a scene error.

use anyhow::Context;

use crate::report::health::Warning;
use crate::report::output;
use crate::report::schema::{self, Kind, SCHEMA_VERSION, Versioned};
use crate::report::summary::{ErrorReport, Status, Summary};
use crate::scene::SceneError;

/// The summary of a run of any kind of scene, as [`print_outcome`] prints it.
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

/// Print the outcome of a run (`ran`: whether it started, after the scene was loaded and
/// the flags applied) as text or as one JSON object, the warnings on stderr, and return the
/// error, if any, for the exit status.
///
/// With `json` every outcome prints one JSON object: the summary with `"status": "ok"`; a
/// run that failed after it started, the summary up to its last good state with
/// `"status": "failed"` and the `error` (kind, message, step, t); bad input, only `status`
/// and `error` ([`failure_object`]). With `strict` a failed health check is an error.
pub fn print_outcome<S: RunSummary>(
    name: &str,
    result: Result<S, SceneError>,
    ran: bool,
    json: bool,
    strict: bool,
) -> anyhow::Result<()> {
    let (summary, error) = match result {
        Ok(mut summary) => {
            let error = (strict && !summary.warnings().is_empty()).then(|| SceneError::Unhealthy {
                warnings: summary
                    .warnings()
                    .iter()
                    .map(|w| w.message.clone())
                    .collect(),
            });
            if let Some(error) = &error {
                summary.fail(error_report(error));
            }
            (Some(summary), error)
        }
        Err(error) => (S::partial(&error), Some(error)),
    };
    for warning in summary.iter().flat_map(|summary| summary.warnings()) {
        output::warn(format_args!("warning: {}", warning.message));
    }
    let printed = match (&summary, json) {
        (Some(summary), true) => output::print(format_args!("{}\n", schema::to_json(summary)?)),
        (Some(summary), false) if error.is_none() => output::print(summary),
        (None, true) => {
            let report = error.as_ref().map(error_report);
            let object = report.as_ref().map(failure_object);
            output::print(format_args!("{}\n", object.unwrap_or_default()))
        }
        _ => Ok(()),
    };
    let error = match (error, printed) {
        (None, Err(stdout)) => Some(SceneError::from(stdout)),
        (error, _) => error,
    };
    match error {
        None => Ok(()),
        Some(error) if ran => Err(error).with_context(|| format!("scene '{name}' failed")),
        Some(error) => Err(error.into()),
    }
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
