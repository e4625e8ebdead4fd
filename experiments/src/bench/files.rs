//! What `svi bench` writes: the records as CSV, and the error against run time and against
//! evaluations as SVG.

use std::fmt;

use crate::bench::record::Record;
use crate::report::plot::{Panel, Series, render_svg};

/// Round-trip float formatting for CSV.
pub(super) struct Float(pub(super) f64);

impl fmt::Display for Float {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:e}", self.0)
    }
}

/// The records as CSV with a header row.
pub fn to_csv(records: &[Record]) -> String {
    let mut text = String::from(
        "method,parameter,h,steps,final_error,energy_error_max,momentum_error_max,evaluations,iterations,seconds\n",
    );
    for r in records {
        let optional = |x: Option<f64>| x.map(|v| Float(v).to_string()).unwrap_or_default();
        text.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{}\n",
            r.method,
            Float(r.parameter),
            optional(r.h),
            r.steps,
            Float(r.final_error),
            Float(r.energy_error_max),
            optional(r.momentum_error_max),
            r.evaluations,
            r.iterations,
            Float(r.seconds)
        ));
    }
    text
}

/// Error against time and error against evaluations, one curve per method, as SVG text (runs
/// with an error above 1 are left to the CSV); `coordinate` names the one coordinate the
/// error was measured in (`--coordinate`), if any.
pub fn plot(
    records: &[Record],
    title: &str,
    coordinate: Option<&str>,
) -> Result<String, crate::report::plot::PlotError> {
    let y_label = coordinate.map_or_else(
        || "final position error".to_string(),
        |name| format!("final error in {name}"),
    );
    let mut labels: Vec<&str> = Vec::new();
    for r in records {
        if !labels.contains(&r.method.as_str()) {
            labels.push(&r.method);
        }
    }
    let series = |x: fn(&Record) -> f64| -> Vec<Series> {
        labels
            .iter()
            .map(|label| Series {
                label: label.to_string(),
                // A run that lost the solution (error above 1, up to 1e40 for a diverged
                // one) would stretch the axis over the whole page: it stays in the CSV.
                points: records
                    .iter()
                    .filter(|r| r.method == *label && r.final_error <= 1.0)
                    .map(|r| (x(r), r.final_error))
                    .collect(),
            })
            .collect()
    };
    let panel = |what: &str, x_label: &str, x: fn(&Record) -> f64| Panel {
        title: format!("{title}: error against {what}"),
        x_label: x_label.into(),
        y_label: y_label.clone(),
        x_log: true,
        y_log: true,
        equal_scale: false,
        scatter: false,
        series: series(x),
    };
    render_svg(
        &[
            panel("run time", "seconds per run", |r| r.seconds),
            panel("evaluations", "derivative evaluations", |r| {
                r.evaluations as f64
            }),
        ],
        640,
        480,
    )
}
