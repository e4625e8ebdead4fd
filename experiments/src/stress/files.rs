//! What `svi stress` writes: the stress table in Markdown and CSV, the windows of every long
//! run as CSV, and the drift plot, into its output directory.

use std::fmt::Write as _;

use crate::report::csv::Float;
use crate::report::output::OutputDirectory;
use crate::report::plot::{Panel, PlotError, Series, render_svg};
use crate::scene::SceneError;
use crate::stress::record::{StressRecord, short};
use crate::stress::search::Limit;

/// The stress table in Markdown.
pub fn to_markdown(records: &[StressRecord]) -> String {
    let mut out = String::from(
        "| scene | method | h | largest bounded h | beyond it | largest h with \\|ΔE\\| < 10 % | steps | drift slope | drift × T | amplitude | max \\|ΔE\\| | energy |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in records {
        let (bounded, beyond) = match &r.bounded {
            Some(limit) => (short(limit.h), limit.failure.clone()),
            None => ("—".into(), "—".into()),
        };
        let accurate = r
            .accurate
            .as_ref()
            .map_or_else(|| "—".into(), |limit| short(limit.h));
        let drift = match &r.drift {
            Ok(d) => format!(
                "{} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {}",
                d.steps,
                d.slope,
                d.drift,
                d.amplitude,
                d.max_error,
                d.verdict()
            ),
            Err(why) => format!("— | — | — | — | — | {why}"),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.scene,
            r.method,
            Float(r.h),
            bounded,
            beyond,
            accurate,
            drift
        );
    }
    out
}

/// The stress table as CSV (empty fields where a value does not apply; the failure texts
/// are quoted and hold no commas).
pub fn to_csv(records: &[StressRecord]) -> String {
    let mut out = String::from(
        "scene,method,h,bounded_h,bounded_beyond,bounded_failure,accurate_h,accurate_beyond,accurate_failure,steps,horizon,slope,drift,amplitude,max_error,verdict,seconds,drift_failure\n",
    );
    let number = |x: Option<f64>| x.map_or_else(String::new, |x| Float(x).to_string());
    let quote = |s: &str| format!("\"{}\"", s.replace('"', "'").replace(',', ";"));
    for r in records {
        let limit = |limit: &Option<Limit>| match limit {
            Some(l) => format!("{},{},{}", number(l.h), number(l.beyond), quote(&l.failure)),
            None => ",,".into(),
        };
        let drift = match &r.drift {
            Ok(d) => format!(
                "{},{},{},{},{},{},{},{},",
                d.steps,
                Float(d.horizon),
                Float(d.slope),
                Float(d.drift),
                Float(d.amplitude),
                Float(d.max_error),
                d.verdict(),
                Float(d.seconds)
            ),
            Err(why) => format!(",,,,,,,,{}", quote(why)),
        };
        let _ = writeln!(
            out,
            "{},{},{},{},{},{}",
            r.scene,
            r.method,
            Float(r.h),
            limit(&r.bounded),
            limit(&r.accurate),
            drift
        );
    }
    out
}

/// The windows of every long run as CSV.
pub fn windows_csv(records: &[StressRecord]) -> String {
    let mut out = String::from("scene,method,t_start,t_end,mean,min,max,samples\n");
    for r in records {
        if let Ok(d) = &r.drift {
            for w in &d.windows {
                let _ = writeln!(
                    out,
                    "{},{},{},{},{},{},{},{}",
                    r.scene,
                    r.method,
                    Float(w.t_start),
                    Float(w.t_end),
                    Float(w.mean),
                    Float(w.min),
                    Float(w.max),
                    w.samples
                );
            }
        }
    }
    out
}

/// One panel per scene, as SVG text: the largest |E − E₀| in each window against time, per
/// method. Every
/// panel lists every method in the same order (so a method keeps its colour); a long run that
/// failed is an empty series labelled "(failed)".
pub fn plot(records: &[StressRecord]) -> Result<String, PlotError> {
    let mut panels: Vec<Panel> = Vec::new();
    for r in records {
        let series = match &r.drift {
            Ok(d) => Series {
                label: r.method.clone(),
                points: d
                    .windows
                    .iter()
                    .map(|w| (w.t_end, w.max.abs().max(w.min.abs())))
                    .collect(),
            },
            Err(_) => Series {
                label: format!("{} (failed)", r.method),
                points: Vec::new(),
            },
        };
        match panels.iter_mut().find(|p| p.title == r.scene) {
            Some(panel) => panel.series.push(series),
            None => panels.push(Panel {
                title: r.scene.clone(),
                x_label: "t".into(),
                y_label: "max |E − E₀| per window".into(),
                x_log: false,
                y_log: true,
                equal_scale: false,
                scatter: false,
                series: vec![series],
            }),
        }
    }
    render_svg(&panels, 480, 400)
}

/// The files `svi stress` writes into its output directory.
pub const OUTPUT_FILES: [&str; 4] = ["stress.md", "stress.csv", "windows.csv", "drift.svg"];

/// Write `stress.md`, `stress.csv`, `windows.csv` and `drift.svg` into `dir` (created before
/// the cases run).
pub fn write_outputs(records: &[StressRecord], mut dir: OutputDirectory) -> Result<(), SceneError> {
    dir.write("stress.md", to_markdown(records).as_bytes())?;
    dir.write("stress.csv", to_csv(records).as_bytes())?;
    dir.write("windows.csv", windows_csv(records).as_bytes())?;
    dir.write("drift.svg", plot(records)?.as_bytes())?;
    Ok(dir.commit()?)
}
