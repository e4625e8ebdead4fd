//! What a run's events and Poincaré section found, in its summary: the located events with
//! their states, the terminal event that ended the run, and the section's point count and
//! drawn axes (the points themselves go to the trajectory file).

use std::fmt;

use serde::Serialize;

use crate::report::csv::Float;

/// One located event of the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventRecord {
    /// The event's name.
    pub name: String,
    /// Its time.
    pub t: f64,
    /// The configuration there.
    pub q: Vec<f64>,
    /// The velocity.
    pub v: Vec<f64>,
    /// The momentum.
    pub p: Vec<f64>,
}

/// What a run's events and section found, for the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventsSummary {
    /// The events located, in time order (not the section's crossings).
    pub events: Vec<EventRecord>,
    /// The terminal event that ended the run, by name.
    pub terminal_event: Option<String>,
    /// The section and how many of its crossings met its condition.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub section: Option<SectionSummary>,
}

/// A Poincaré section's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SectionSummary {
    /// The section as written (`"y=0,vy>0"`).
    pub surface: String,
    /// Its points (crossings meeting the condition): the rows of the trajectory file.
    pub points: usize,
    /// The two columns of the trajectory file the plot draws, e.g. `["q_x", "v_x"]`.
    pub axes: [String; 2],
}

impl EventsSummary {
    /// The events as CSV (the file of `--events-out`): a header `event,t,q_<name>…,v_<name>…,
    /// p_<name>…` for the model's coordinate `names`, then one row per event in time order,
    /// every number by [`Float`] (it reads back exactly); a name with a comma or a quote is
    /// quoted.
    pub fn to_csv(&self, names: &[String]) -> String {
        let header = crate::report::csv::csv_header(names);
        let columns = header.trim_end().trim_end_matches(",energy");
        let mut text = format!("event,{columns}\n");
        for record in &self.events {
            let name = if record.name.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", record.name.replace('"', "\"\""))
            } else {
                record.name.clone()
            };
            text.push_str(&name);
            let numbers = std::iter::once(&record.t)
                .chain(&record.q)
                .chain(&record.v)
                .chain(&record.p);
            for x in numbers {
                text.push_str(&format!(",{}", Float(*x)));
            }
            text.push('\n');
        }
        text
    }

    /// The summary's lines: per event name its count and first and last times, the event
    /// that ended the run, the section.
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        let mut rows = Vec::new();
        let mut names: Vec<&str> = Vec::new();
        for record in &self.events {
            if !names.contains(&record.name.as_str()) {
                names.push(&record.name);
            }
        }
        for name in names {
            let times: Vec<f64> = self
                .events
                .iter()
                .filter(|record| record.name == name)
                .map(|record| record.t)
                .collect();
            let (first, last) = (times[0], times[times.len() - 1]);
            let line = if times.len() == 1 {
                format!("{name} at t = {}", Float(first))
            } else {
                format!(
                    "{name} ×{} from t = {} to {}",
                    times.len(),
                    Float(first),
                    Float(last)
                )
            };
            rows.push(("events", line));
        }
        if self.events.is_empty() {
            rows.push(("events", "none located".to_string()));
        }
        if let Some(name) = &self.terminal_event {
            rows.push(("ended by", format!("terminal event {name}")));
        }
        if let Some(section) = &self.section {
            rows.push(("section", section.to_string()));
        }
        rows
    }
}

impl fmt::Display for SectionSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} points ({}, {})",
            self.surface, self.points, self.axes[0], self.axes[1]
        )
    }
}
