//! `svi bench` on a pseudospectral scene (e.g. `svi bench nls-soliton`): the work–precision
//! comparison of Leok §5.8 — the Galerkin SVI in time with Fourier in space against the
//! Strang split-step Fourier method, the traditional pseudospectral scheme.
//!
//! Each method (`--methods`, default [`DEFAULT_SPECTRAL_METHODS`]; names as
//! [`time_scheme`] reads them) runs the scene's model, grid and horizon at step counts
//! n = n₀·2ᵏ (or `--steps`), until its final error |ψ − ψ_exact|∞ is below the target
//! (`--target`, default [`DEFAULT_SPECTRAL_TARGET`]) or a run takes longer than `--max-run`
//! seconds. A point's time is the median of `--batches` runs (one run when a run takes
//! longer than [`SINGLE_RUN_SECONDS`]), without any observer: the error is measured at the
//! end only. `<scene>.csv` has the columns `method,steps,h,error,seconds,ffts,norm_error_max`;
//! `<scene>.svg` draws the error against wall time and against FFTs. The closing lines name
//! the method that reaches [`CROSSING_ERROR`] first in wall time (log–log interpolation
//! between the two points that bracket it) and by how much.

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use svi::field::pseudospectral::TimeScheme;
use svi_models::{SpectralModelVisitor, SpectralZooModel, UnknownModel, visit_spectral_model};

use crate::bench::options::{BenchArgs, DEFAULT_MAX_RUN, DEFAULT_METHODS};
use crate::report::output::{self, OutputDirectory};
use crate::report::plot::{Panel, Series, render_svg};
use crate::run::spectral::{Prepared, error_against_exact, prepare};
use crate::scene::error::SceneError;
use crate::scene::overrides::{Overrides, RunFlags};
use crate::scene::spectral::{SpectralScene, scheme_name, time_scheme};

/// The methods of a pseudospectral bench unless `--methods` names others.
pub const DEFAULT_SPECTRAL_METHODS: &str = "svi:3,svi:4,svi:5,strang";

/// The default target error of a pseudospectral sweep.
pub const DEFAULT_SPECTRAL_TARGET: f64 = 1e-10;

/// The error at which the closing note compares the methods' wall times.
pub const CROSSING_ERROR: f64 = 1e-8;

/// A run longer than this is timed once.
pub const SINGLE_RUN_SECONDS: f64 = 0.5;

/// The most steps of one run.
const MAX_SPECTRAL_STEPS: usize = 10_000_000;

/// One point of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralRecord {
    /// The method, as [`scheme_name`] writes it.
    pub method: String,
    /// Steps over the horizon.
    pub steps: usize,
    /// The step.
    pub h: f64,
    /// |ψ − ψ_exact|∞ at the end.
    pub error: f64,
    /// Wall time of one run (median of the batches).
    pub seconds: f64,
    /// FFTs of one run.
    pub ffts: usize,
    /// The largest relative norm error over the run.
    pub norm_error_max: f64,
}

/// `svi bench` on the pseudospectral scene `scene` (loaded as `name`): sweep, write
/// `<scene>.csv` and `<scene>.svg` into `--out-dir`, print the CSV and the closing note.
pub fn execute(
    name: &str,
    scene: Result<SpectralScene, SceneError>,
    args: &BenchArgs,
) -> anyhow::Result<()> {
    let mut scene = scene?;
    scene.apply(&Overrides {
        run: RunFlags {
            t_end: args.t_end,
            ..RunFlags::default()
        },
        parameters: args.parameters.clone(),
        ..Overrides::default()
    })?;
    let methods = if args.methods == DEFAULT_METHODS {
        DEFAULT_SPECTRAL_METHODS
    } else {
        args.methods.as_str()
    };
    let schemes = methods
        .split(',')
        .map(time_scheme)
        .collect::<Result<Vec<_>, _>>()?;
    let target = positive_option("target", args.target, DEFAULT_SPECTRAL_TARGET)?;
    let max_run = positive_option("max_run", args.max_run, DEFAULT_MAX_RUN)?;
    if args.batches == 0 {
        return Err(SceneError::InvalidOption {
            option: "batches",
            reason: "0; need at least one timing batch".into(),
        }
        .into());
    }
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("bench");
    let (csv, svg) = (format!("{stem}.csv"), format!("{stem}.svg"));
    let mut dir = OutputDirectory::create(
        "--out-dir",
        &args.out_dir,
        &[csv.clone(), svg.clone()],
        &[Path::new(name)],
    )
    .map_err(SceneError::from)?;
    let sweep = Sweep {
        scene: &scene,
        schemes,
        target,
        max_run,
        batches: args.batches,
        steps: args.steps.clone(),
    };
    let records = visit_spectral_model(&scene.model, sweep)
        .unwrap_or_else(|| {
            Err(SceneError::UnknownModel(UnknownModel {
                name: scene.model.clone(),
            }))
        })
        .with_context(|| format!("benchmark of scene '{name}' failed"))?;
    let table = to_csv(&records);
    dir.write(&csv, table.as_bytes())
        .map_err(SceneError::from)?;
    dir.write(&svg, plot(&records, stem)?.as_bytes())
        .map_err(SceneError::from)?;
    dir.commit().map_err(SceneError::from)?;
    output::print(format_args!("{table}{}\n", crossing_note(&records)))
        .map_err(SceneError::from)?;
    output::warn(format_args!(
        "wrote {} and {}",
        args.out_dir.join(&csv).display(),
        args.out_dir.join(&svg).display()
    ));
    Ok(())
}

/// `value`, or `default` when absent; a non-positive or non-finite value is an error.
fn positive_option(
    option: &'static str,
    value: Option<f64>,
    default: f64,
) -> Result<f64, SceneError> {
    match value {
        None => Ok(default),
        Some(v) if v.is_finite() && v > 0.0 => Ok(v),
        Some(v) => Err(SceneError::InvalidOption {
            option,
            reason: format!("{v}; need a positive number"),
        }),
    }
}

/// The sweep over the methods, run on the model it is handed.
struct Sweep<'a> {
    scene: &'a SpectralScene,
    schemes: Vec<TimeScheme>,
    target: f64,
    max_run: f64,
    batches: usize,
    steps: Vec<usize>,
}

impl SpectralModelVisitor for Sweep<'_> {
    type Output = Result<Vec<SpectralRecord>, SceneError>;

    fn visit<M: SpectralZooModel>(self, mut model: M) -> Self::Output {
        let scene = self.scene;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let points = scene.mesh.points.unwrap_or_else(|| model.default_points());
        let t_end = scene.run.t_end.unwrap_or_else(|| model.default_horizon());
        if !(t_end.is_finite() && t_end > 0.0) {
            return Err(SceneError::InvalidOption {
                option: "t_end",
                reason: format!("{t_end}; need a positive horizon"),
            });
        }
        let mut records = Vec::new();
        for &scheme in &self.schemes {
            // The Galerkin iteration needs h·3ν < 2 (ν ≈ η² for the soliton): start at h = ½.
            let first = match scheme {
                TimeScheme::Strang => (t_end * 8.0).ceil() as usize,
                TimeScheme::Galerkin { .. } => (t_end * 2.0).ceil() as usize,
            };
            let ladder: Vec<usize> = if self.steps.is_empty() {
                (0..)
                    .map(|k| first << k)
                    .take_while(|&n| n <= MAX_SPECTRAL_STEPS)
                    .collect()
            } else {
                self.steps.clone()
            };
            for steps in ladder {
                let h = t_end / steps as f64;
                let record = self.point(&model, scheme, points, h, steps, t_end)?;
                eprintln!(
                    "{:>10} {:>8} steps: error {:.3e}, {:.4} s, {} FFTs",
                    record.method, steps, record.error, record.seconds, record.ffts
                );
                let done = self.steps.is_empty()
                    && (record.error < self.target || record.seconds > self.max_run);
                records.push(record);
                if done {
                    break;
                }
            }
        }
        Ok(records)
    }
}

impl Sweep<'_> {
    /// One point: the median wall time of the batches and the final error.
    fn point<M: SpectralZooModel>(
        &self,
        model: &M,
        scheme: TimeScheme,
        points: usize,
        h: f64,
        steps: usize,
        t_end: f64,
    ) -> Result<SpectralRecord, SceneError> {
        let mut times = Vec::with_capacity(self.batches);
        let mut outcome = None;
        for _ in 0..self.batches {
            let Prepared {
                mut integrator,
                nodes,
                initial,
            } = prepare(model, scheme, points, h)?;
            let start = Instant::now();
            let run = integrator.run(0.0, &initial, steps, |_, _, _| {})?;
            let seconds = start.elapsed().as_secs_f64();
            times.push(seconds);
            let error = error_against_exact(model, &nodes, t_end, &run.last);
            outcome = Some((error, run.ffts, run.norm_error_max));
            if seconds > SINGLE_RUN_SECONDS {
                break;
            }
        }
        times.sort_by(f64::total_cmp);
        let (error, ffts, norm_error_max) = outcome.unwrap_or((f64::NAN, 0, f64::NAN));
        Ok(SpectralRecord {
            method: scheme_name(scheme),
            steps,
            h,
            error,
            seconds: times[times.len() / 2],
            ffts,
            norm_error_max,
        })
    }
}

/// The CSV of the records.
pub fn to_csv(records: &[SpectralRecord]) -> String {
    let mut out = String::from("method,steps,h,error,seconds,ffts,norm_error_max\n");
    for r in records {
        out.push_str(&format!(
            "{},{},{:e},{:e},{:e},{},{:e}\n",
            r.method, r.steps, r.h, r.error, r.seconds, r.ffts, r.norm_error_max
        ));
    }
    out
}

/// The methods in order of first appearance.
fn labels(records: &[SpectralRecord]) -> Vec<&str> {
    let mut labels: Vec<&str> = Vec::new();
    for r in records {
        if !labels.contains(&r.method.as_str()) {
            labels.push(&r.method);
        }
    }
    labels
}

/// The wall time at which `method`'s sweep reaches `error`, by log–log interpolation between
/// the first two consecutive points that bracket it; `None` if none do.
pub fn time_to_error(records: &[SpectralRecord], method: &str, error: f64) -> Option<f64> {
    let points: Vec<&SpectralRecord> = records.iter().filter(|r| r.method == method).collect();
    points.windows(2).find_map(|pair| {
        let (a, b) = (pair[0], pair[1]);
        (a.error > error && b.error <= error && b.error > 0.0).then(|| {
            let fraction = (error.ln() - a.error.ln()) / (b.error.ln() - a.error.ln());
            (a.seconds.ln() + fraction * (b.seconds.ln() - a.seconds.ln())).exp()
        })
    })
}

/// The methods whose sweeps bracket [`CROSSING_ERROR`], with the wall time at which each
/// reaches it, fastest first.
fn crossing_times(records: &[SpectralRecord]) -> Vec<(&str, f64)> {
    let mut times: Vec<(&str, f64)> = labels(records)
        .into_iter()
        .filter_map(|m| time_to_error(records, m, CROSSING_ERROR).map(|t| (m, t)))
        .collect();
    times.sort_by(|a, b| a.1.total_cmp(&b.1));
    times
}

/// "M reaches it first" for the fastest of `times`, with how many times faster it is than
/// the runner-up and (when neither of the two is Strang) than Strang; `None` for fewer than
/// two methods.
fn winner(times: &[(&str, f64)]) -> Option<String> {
    let [(first, t_first), (second, t_second), ..] = times else {
        return None;
    };
    let mut line = format!(
        "{first} reaches it first, {:.1}× faster than {second}",
        t_second / t_first
    );
    if let Some((_, t_strang)) = times.iter().find(|(m, _)| *m == "strang")
        && *first != "strang"
        && *second != "strang"
    {
        line.push_str(&format!(" ({:.1}× faster than strang)", t_strang / t_first));
    }
    Some(line)
}

/// Which method reaches [`CROSSING_ERROR`] first in wall time, and the ratio to the next.
pub fn crossing_note(records: &[SpectralRecord]) -> String {
    let times = crossing_times(records);
    let listed: Vec<String> = times
        .iter()
        .map(|(m, t)| format!("{m} {t:.3e} s"))
        .collect();
    let mut note = format!(
        "time to error {CROSSING_ERROR:e}: {}",
        if listed.is_empty() {
            "no method brackets it".into()
        } else {
            listed.join(", ")
        }
    );
    if let Some(line) = winner(&times) {
        note.push('\n');
        note.push_str(&line);
    }
    note
}

/// The SVG: error against wall time and against FFTs, log–log.
fn plot(records: &[SpectralRecord], title: &str) -> Result<String, crate::report::plot::PlotError> {
    let labels = labels(records);
    let series = |x: fn(&SpectralRecord) -> f64| -> Vec<Series> {
        labels
            .iter()
            .map(|label| Series {
                label: label.to_string(),
                points: records
                    .iter()
                    .filter(|r| r.method == *label)
                    .map(|r| (x(r), r.error))
                    .collect(),
            })
            .collect()
    };
    let panel = |what: &str, x_label: &str, x: fn(&SpectralRecord) -> f64| {
        // The crossing error as a horizontal line across the panel's range.
        let xs = records.iter().map(x).filter(|v| v.is_finite() && *v > 0.0);
        let (low, high) = xs.fold((f64::INFINITY, 0.0_f64), |(l, h), v| (l.min(v), h.max(v)));
        let mut series = series(x);
        if low <= high {
            series.push(Series {
                label: format!("error {CROSSING_ERROR:e}"),
                points: vec![(low, CROSSING_ERROR), (high, CROSSING_ERROR)],
            });
        }
        Panel {
            title: format!("{title}: error against {what}"),
            x_label: x_label.into(),
            y_label: "final error max|ψ − ψ_exact|".into(),
            x_log: true,
            y_log: true,
            equal_scale: false,
            scatter: false,
            series,
        }
    };
    let mut time_panel = panel("wall time", "seconds per run", |r| r.seconds);
    // The panel's title names the winner against Strang (or the runner-up), short enough
    // to fit over the panel.
    let times = crossing_times(records);
    if let [(first, t_first), runner_up, ..] = times.as_slice() {
        let (rival, t_rival) = times
            .iter()
            .find(|(m, _)| *m == "strang" && m != first)
            .unwrap_or(runner_up);
        time_panel.title = format!(
            "{title}: {first} reaches {CROSSING_ERROR:e} first, {:.1}× faster than {rival}",
            t_rival / t_first
        );
    }
    render_svg(
        &[time_panel, panel("FFTs", "FFTs per run", |r| r.ffts as f64)],
        640,
        480,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(method: &str, error: f64, seconds: f64) -> SpectralRecord {
        SpectralRecord {
            method: method.into(),
            steps: 1,
            h: 1.0,
            error,
            seconds,
            ffts: 1,
            norm_error_max: 0.0,
        }
    }

    #[test]
    fn the_crossing_time_is_interpolated_log_log_and_the_note_names_the_winner() {
        let records = [
            record("svi:4/3", 1e-6, 0.01),
            record("svi:4/3", 1e-10, 0.1),
            record("strang", 1e-7, 1.0),
            record("strang", 1e-9, 100.0),
        ];
        let t = time_to_error(&records, "svi:4/3", 1e-8).unwrap();
        assert!((t - 0.01f64.sqrt() * 0.1f64.sqrt()).abs() < 1e-12);
        assert!((time_to_error(&records, "strang", 1e-8).unwrap() - 10.0).abs() < 1e-9);
        let note = crossing_note(&records);
        assert!(
            note.contains("svi:4/3 reaches it first, 316.2× faster than strang"),
            "{note}"
        );
        assert_eq!(time_to_error(&records[..1], "svi:4/3", 1e-8), None);
        // The picture names the winner over the wall-time panel and draws the crossing error.
        let picture = plot(&records, "soliton").unwrap();
        assert!(
            picture.contains("soliton: svi:4/3 reaches 1e-8 first, 316.2× faster than strang"),
            "{picture}"
        );
        assert!(picture.contains("error 1e-8"));
    }
}
