//! One row of the stress table, and its line in the progress log.

use serde::Serialize;
use std::fmt::Write as _;

use crate::stress::drift::Drift;
use crate::stress::search::Limit;

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

/// `1.23e-4`, or `—`.
pub(super) fn short(value: Option<f64>) -> String {
    value.map_or_else(|| "—".into(), |x| format!("{x:.3e}"))
}

/// One line for the progress log.
pub(super) fn summary_line(record: &StressRecord) -> String {
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
