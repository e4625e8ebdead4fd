//! What `svi run` prints of a run of any kind of scene: its summary or its error (with the
//! summary up to its last good state) as text or as one JSON object, and the failed health
//! checks on stderr.

use anyhow::Context;
use svi_experiments::SceneError;
use svi_experiments::report::output;
use svi_experiments::report::schema;
use svi_experiments::run::{RunSummary, error_report, failure_object};

/// Print the outcome of a run of the scene `name` as text or as one JSON object, the
/// warnings on stderr, and return the error, if any, for the exit status (an error of a run
/// that started names the scene; bad input names what is wrong).
///
/// With `json` every outcome prints one JSON object: the summary with `"status": "ok"`; a
/// run that failed after it started, the summary up to its last good state with
/// `"status": "failed"` and the `error` (kind, message, step, t); bad input, only `status`
/// and `error` ([`failure_object`]). With `strict` a failed health check is an error.
pub fn print_outcome<S: RunSummary>(
    name: &str,
    result: Result<S, SceneError>,
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
        Some(error) if error.is_bad_input() => Err(error.into()),
        Some(error) => Err(error).with_context(|| format!("scene '{name}' failed")),
    }
}
