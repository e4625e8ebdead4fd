//! `svi compare`: one scene run once per method — the same step, horizon and initial state —
//! with a row per method (steps, wall time, energy and momentum errors) and a picture of the
//! trajectories and energy errors. Hairer, Lubich & Wanner's Fig. I.2.4 is one command:
//! `svi compare outer-solar-system --methods
//! explicit-euler,implicit-euler,symplectic-euler,verlet --plot solar-system.svg`.
//!
//! Each method's run is [`Scene::run`], the one run path of `svi run`: the scene with the
//! shared flags applied ([`Scene::apply`]), then the method as `--method` sets it, with the
//! trajectory kept in memory for the picture (`output.record`). The command compiles no
//! method or model of its own. Every method is checked against the scene before the first
//! runs (bad input: exit status 2, nothing run); a method that fails as it runs has its row
//! say so, the others still run, and the exit status is 1 (2 if a method refused the scene's
//! model before its first step, as a dense method refuses a model too large for its
//! matrices; 2 and no table if every method did, as for a parameter the model rejects).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use serde::Serialize;
use svi::MethodSpec;

use crate::report::csv::{Float, Recorded};
use crate::report::health::Warning;
use crate::report::output::{self, OutputFile};
use crate::report::plot::{Panel, Series, render_svg_grid};
use crate::report::schema::{self, Kind, Versioned};
use crate::report::summary::{ErrorReport, Parameters, Status, Summary};
use crate::run::Control;
use crate::run::outcome::{error_report, failure_object};
use crate::scene::overrides::{Overrides, RunFlags, method_help, parse_parameter};
use crate::scene::{Scene, SceneError};

/// `svi compare`'s arguments.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct CompareArgs {
    /// Built-in scene (see `svi list`) or path to a scene TOML file.
    pub scene: String,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help).
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        required = true,
        long_help = method_help(
            "Methods, comma-separated, each run once on the scene with the same step, horizon \
             and initial state."
        )
    )]
    pub methods: Vec<MethodSpec>,
    /// Step size (overrides the scene's).
    #[arg(long = "h", value_name = "H", allow_hyphen_values = true)]
    pub h: Option<f64>,
    /// Final time (overrides the scene's).
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Model parameter (repeatable), e.g. `--param G=3e-4`.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_parameter)]
    pub parameters: Vec<(String, f64)>,
    /// Draw FILE.svg: a panel per method with its trajectory (the bodies' orbits in the x–y
    /// plane for a model whose coordinates are BODY_x, BODY_y (, BODY_z) for each body;
    /// otherwise each coordinate against t) and a panel of every method's energy error
    /// |E − E0| against t.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print the comparison as one JSON object: the scene, and per method the fields of
    /// `svi run --json` for the same quantities (`steps`, `seconds`, `energy_error_max`,
    /// `momentum_error_max`, `status`, `error`, …) and `energy_error_final`.
    #[arg(long)]
    pub json: bool,
}

impl CompareArgs {
    /// The flags every method's run shares.
    fn overrides(&self) -> Overrides {
        Overrides {
            run: RunFlags {
                h: self.h,
                t_end: self.t_end,
                ..RunFlags::default()
            },
            parameters: self.parameters.clone(),
            ..Overrides::default()
        }
    }
}

/// Most points of a curve in the picture: longer runs are drawn at every k-th step point
/// (the energy error as the largest over each k steps).
pub const PLOT_POINTS: usize = 3000;

/// One method's row of the comparison (`--json`: an element of `methods`). The numbers are
/// those of the method's `svi run --json`, under the same names; `null` where the run never
/// started.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodRow {
    /// The method as given (`svi:7/6`).
    pub method: String,
    /// `ok`, or `failed` (with `error`).
    pub status: Status,
    /// The method's classical order.
    pub order: Option<usize>,
    /// Whether the method is symplectic.
    pub symplectic: Option<bool>,
    /// Steps taken.
    pub steps: Option<usize>,
    /// The time reached (the horizon, or the last good state of a failed run).
    pub t_end: Option<f64>,
    /// Wall time of the integration, in seconds.
    pub seconds: Option<f64>,
    /// Energy of the initial state.
    pub energy_initial: Option<f64>,
    /// Energy of the final state.
    pub energy_final: Option<f64>,
    /// Largest |E − E₀| over the step points.
    pub energy_error_max: Option<f64>,
    /// |E − E₀| at the final state.
    pub energy_error_final: Option<f64>,
    /// Largest deviation of the Noether momenta (`null` for a model without symmetries).
    pub momentum_error_max: Option<f64>,
    /// Nonlinear iterations, summed over all steps.
    pub iterations: Option<usize>,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: Option<usize>,
    /// The health checks the run failed.
    pub warnings: Vec<Warning>,
    /// Why the method failed (`status` = `failed`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorReport>,
}

impl MethodRow {
    /// The row of `method` from its summary (also of a failed run up to its last good state)
    /// and its error.
    fn new(method: &MethodSpec, summary: Option<&Summary>, error: Option<ErrorReport>) -> Self {
        let field = |get: fn(&Summary) -> f64| summary.map(get);
        MethodRow {
            method: method.to_string(),
            status: if error.is_some() {
                Status::Failed
            } else {
                Status::Ok
            },
            order: summary.map(|s| s.order),
            symplectic: summary.map(|s| s.symplectic),
            steps: summary.map(|s| s.steps),
            t_end: field(|s| s.t_end),
            seconds: field(|s| s.seconds),
            energy_initial: field(|s| s.energy_initial),
            energy_final: field(|s| s.energy_final),
            energy_error_max: summary.and_then(|s| s.energy_error_max),
            energy_error_final: field(|s| (s.energy_final - s.energy_initial).abs()),
            momentum_error_max: summary.and_then(|s| s.conservation.momentum_error_max()),
            iterations: summary.map(|s| s.iterations),
            evaluations: summary.map(|s| s.evaluations),
            warnings: summary.map(|s| s.warnings.clone()).unwrap_or_default(),
            error,
        }
    }
}

impl Versioned for Comparison {
    fn kind(&self) -> Kind {
        Kind::Comparison
    }
}

/// The comparison (`svi compare --json`): the scene, what its runs share, and a row per
/// method in the order given.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// The scene as named.
    pub scene: String,
    /// The model's name (`text` for a Lagrangian written as text).
    pub model: String,
    /// The model's parameters in effect (`null` if no method started).
    pub parameters: Option<Parameters>,
    /// The step every method takes (`null` if no method started).
    pub h: Option<f64>,
    /// The initial time (`null` if no method started).
    pub t0: Option<f64>,
    /// `ok` if every method reached the horizon, else `failed`.
    pub status: Status,
    /// The methods' rows.
    pub methods: Vec<MethodRow>,
    /// The picture, if drawn.
    pub plot: Option<String>,
}

/// Methods that failed after the scene was accepted: exit status 1, after every row is
/// printed.
#[derive(Debug, thiserror::Error)]
#[error("{} of {count} methods failed: {}; their rows say why", failed.len(), failed.join(", "))]
pub struct MethodsFailed {
    /// The methods that failed, each with its error kind.
    pub failed: Vec<String>,
    /// Methods run.
    pub count: usize,
}

/// One method's run: its summary (of a failed run, up to its last good state) and why it
/// failed, if it did.
struct Outcome {
    method: MethodSpec,
    summary: Option<Summary>,
    failure: Option<Failure>,
    /// The curves of its panel and its energy error, thinned to [`PLOT_POINTS`].
    drawn: Option<Drawn>,
}

/// Why a method has no complete run.
enum Failure {
    /// It failed as it ran: its summary holds the error (exit status 1).
    Run,
    /// It did not run: a method that refuses the scene's model as it starts (bad input, exit
    /// status 2), or an output that cannot be written.
    Refused(SceneError),
}

/// `svi compare`: check the scene and every method, run each, draw the picture (`--plot`)
/// and print the table (or, with `--json`, one JSON object, also when the command fails).
pub fn execute_args(args: &CompareArgs) -> anyhow::Result<()> {
    let bad_input = |error: SceneError| {
        if args.json {
            // Stdout that cannot be written leaves the exit status to tell.
            let object = failure_object(&error_report(&error));
            let _ = output::print(format_args!("{object}\n"));
        }
        Err(error.into())
    };
    let (scenes, plot) = match prepare(args) {
        Ok(prepared) => prepared,
        Err(error) => return bad_input(error),
    };
    let model = scenes
        .first()
        .map_or_else(String::new, |(_, scene)| scene.model_name().to_owned());
    let progress = std::io::stderr().is_terminal();
    let mut outcomes: Vec<Outcome> = scenes
        .into_iter()
        .map(|(method, scene)| run_method(method, &scene, plot.is_some(), progress))
        .collect();
    // No method could start (a shared value the model rejects, as --param G=-1): bad input of
    // the comparison itself, as the same `svi run` would be; nothing is drawn.
    let refused = |outcome: &Outcome| matches!(&outcome.failure, Some(Failure::Refused(error)) if error.is_bad_input());
    if !outcomes.is_empty()
        && outcomes.iter().all(refused)
        && let Some(Failure::Refused(error)) = outcomes.swap_remove(0).failure
    {
        return bad_input(error);
    }
    let picture = plot.map(|file| draw(file, &outcomes));
    let drawn = picture.as_ref().and_then(|picture| picture.as_ref().ok());
    let comparison = comparison(args, model, &outcomes, drawn);
    for row in &comparison.methods {
        for warning in &row.warnings {
            output::warn(format_args!("warning: {}: {}", row.method, warning.message));
        }
    }
    if args.json {
        output::print(format_args!("{}\n", schema::to_json(&comparison)?))
    } else {
        output::print(text_table(&comparison))
    }
    .map_err(SceneError::from)?;
    if let Some(Err(error)) = picture {
        return Err(error.into());
    }
    outcome(outcomes, &comparison.methods)
}

/// Each method with its scene, ready to run.
type Prepared = Vec<(MethodSpec, Scene)>;

/// The scene of every method, checked (the shared flags, then the method's), and the picture's
/// file created (a temporary until it is drawn). Every error is bad input.
fn prepare(args: &CompareArgs) -> Result<(Prepared, Option<OutputFile>), SceneError> {
    let mut scene = Scene::load(&args.scene)?;
    let output = &scene.output;
    if output.trajectory.is_some() || output.output_times.is_some() {
        return Err(SceneError::NotApplicable {
            option: "output.trajectory, output.output_times",
            reason: "svi compare keeps every method's trajectory in memory for its picture \
                     (--plot) and writes no trajectory file; run one method with svi run for \
                     those"
                .into(),
        });
    }
    // The comparison measures what its table shows, whatever the scene asks `svi run` for.
    scene.output.diagnostics = None;
    scene.output.record = args.plot.is_some();
    scene.apply(&args.overrides())?;
    let scenes = args
        .methods
        .iter()
        .map(|method| {
            let mut scene = scene.clone();
            scene.apply(&Overrides {
                run: RunFlags {
                    method: Some((*method).into()),
                    ..RunFlags::default()
                },
                ..Overrides::default()
            })?;
            Ok((*method, scene))
        })
        .collect::<Result<_, SceneError>>()?;
    let plot = match &args.plot {
        Some(path) => {
            output::check_file("--plot", path)?;
            output::check_extension("--plot", path, &["svg"], "SVG")?;
            let inputs: Vec<&Path> = scene.source.iter().map(PathBuf::as_path).collect();
            output::check_distinct(&[("--plot", path)], &inputs)?;
            Some(OutputFile::create("--plot", path)?)
        }
        None => None,
    };
    Ok((scenes, plot))
}

/// Run `scene` (the scene with `method`) through the one run path; with `draw`, keep the
/// curves of its picture.
fn run_method(method: MethodSpec, scene: &Scene, draw: bool, progress: bool) -> Outcome {
    let (mut summary, failure) = match scene.run(Control {
        progress,
        stop: None,
    }) {
        Ok(summary) => (Some(summary), None),
        Err(SceneError::RunFailed { partial, .. }) => (Some(*partial), Some(Failure::Run)),
        Err(error) => (None, Some(Failure::Refused(error))),
    };
    let label = method.to_string();
    let recorded = summary.as_mut().and_then(|summary| summary.recorded.take());
    let drawn = summary
        .as_ref()
        .zip(recorded.filter(|_| draw))
        .map(|(summary, recorded)| Drawn::new(label, summary, recorded));
    Outcome {
        method,
        summary,
        failure,
        drawn,
    }
}

/// The comparison of `outcomes` of the scene's `model`, with the picture's path if it was
/// drawn.
fn comparison(
    args: &CompareArgs,
    model: String,
    outcomes: &[Outcome],
    plot: Option<&PathBuf>,
) -> Comparison {
    let first = outcomes.iter().find_map(|outcome| outcome.summary.as_ref());
    let methods: Vec<MethodRow> = outcomes
        .iter()
        .map(|outcome| {
            let error = match &outcome.failure {
                None => None,
                Some(Failure::Run) => outcome.summary.as_ref().and_then(|s| s.error.clone()),
                Some(Failure::Refused(error)) => Some(error_report(error)),
            };
            MethodRow::new(&outcome.method, outcome.summary.as_ref(), error)
        })
        .collect();
    let ok = methods.iter().all(|row| row.status == Status::Ok);
    Comparison {
        scene: args.scene.clone(),
        model,
        parameters: first.map(|summary| summary.parameters.clone()),
        h: first.map(|summary| summary.h),
        t0: first.map(|summary| summary.t0),
        status: if ok { Status::Ok } else { Status::Failed },
        methods,
        plot: plot.map(|path| path.display().to_string()),
    }
}

/// The error of the command after every row is printed: the first method's that refused the
/// scene as bad input (exit status 2), else [`MethodsFailed`] (exit status 1) if any failed.
fn outcome(outcomes: Vec<Outcome>, rows: &[MethodRow]) -> anyhow::Result<()> {
    let failed: Vec<String> = rows
        .iter()
        .filter_map(|row| {
            let kind = row.error.as_ref()?.kind;
            Some(format!("{} ({kind})", row.method))
        })
        .collect();
    let refused = outcomes
        .into_iter()
        .find_map(|outcome| match outcome.failure {
            Some(Failure::Refused(error)) if error.is_bad_input() => Some((outcome.method, error)),
            _ => None,
        });
    match refused {
        Some((method, error)) => {
            Err(anyhow::Error::new(error).context(format!("method {method} cannot run the scene")))
        }
        None if failed.is_empty() => Ok(()),
        None => Err(MethodsFailed {
            failed,
            count: rows.len(),
        }
        .into()),
    }
}

/// The text table: a line on the scene, then a row per method, and the errors of the
/// methods that failed.
fn text_table(comparison: &Comparison) -> String {
    let number = |value: Option<f64>| value.map_or_else(|| "n/a".into(), |x| format!("{x:.3e}"));
    let momenta = comparison
        .methods
        .iter()
        .any(|row| row.momentum_error_max.is_some());
    let mut header = vec![
        "method",
        "status",
        "steps",
        "t_end",
        "wall time",
        "max |E-E0|",
        "final |E-E0|",
    ];
    if momenta {
        header.push("max momentum error");
    }
    let rows: Vec<Vec<String>> = comparison
        .methods
        .iter()
        .map(|row| {
            let mut cells = vec![
                row.method.clone(),
                match row.status {
                    Status::Ok => "ok".into(),
                    Status::Failed => "failed".into(),
                },
                row.steps
                    .map_or_else(|| "n/a".into(), |steps| steps.to_string()),
                row.t_end
                    .map_or_else(|| "n/a".into(), |t| Float(t).to_string()),
                row.seconds
                    .map_or_else(|| "n/a".into(), |s| format!("{s:.3} s")),
                number(row.energy_error_max),
                number(row.energy_error_final),
            ];
            if momenta {
                cells.push(number(row.momentum_error_max));
            }
            cells
        })
        .collect();
    let widths: Vec<usize> = (0..header.len())
        .map(|column| {
            rows.iter()
                .map(|cells| cells[column].chars().count())
                .chain([header[column].len()])
                .max()
                .unwrap_or(0)
                + 2
        })
        .collect();
    let line = |cells: Vec<&str>| {
        let mut text: String = cells
            .iter()
            .zip(&widths)
            .map(|(cell, width)| format!("{cell:<width$}"))
            .collect();
        text.truncate(text.trim_end().len());
        text + "\n"
    };
    let mut text = format!("scene {}: {}", comparison.scene, comparison.model);
    if let Some(parameters) = comparison.parameters.as_ref().filter(|p| !p.0.is_empty()) {
        text.push_str(&format!(" ({parameters})"));
    }
    if let (Some(h), Some(t0)) = (comparison.h, comparison.t0) {
        text.push_str(&format!(", h = {}, t0 = {}", Float(h), Float(t0)));
    }
    if let Some(energy) = comparison.methods.iter().find_map(|row| row.energy_initial) {
        text.push_str(&format!(", E0 = {}", Float(energy)));
    }
    text.push('\n');
    text.push_str(&line(header));
    for cells in &rows {
        text.push_str(&line(cells.iter().map(String::as_str).collect()));
    }
    for row in &comparison.methods {
        if let Some(error) = &row.error {
            text.push_str(&format!("{} failed: {}\n", row.method, error.message));
        }
    }
    if let Some(plot) = &comparison.plot {
        text.push_str(&format!("picture: {plot}\n"));
    }
    text
}

/// A method's part of the picture: its trajectory's curves and its energy error against t.
struct Drawn {
    /// The panel of its trajectory.
    panel: Panel,
    /// |E − E₀| against t: the largest over each run of consecutive step points drawn as one.
    energy_error: Vec<(f64, f64)>,
}

impl Drawn {
    /// The curves of the trajectory `recorded` by the run of `summary` of the method
    /// `label`, thinned to at most [`PLOT_POINTS`] points each.
    fn new(label: String, summary: &Summary, recorded: Recorded) -> Self {
        let column = |name: &str| recorded.columns.iter().position(|column| column == name);
        let count = recorded.rows().len();
        let stride = count.div_ceil(PLOT_POINTS).max(1);
        // Every stride-th row and the last.
        let thinned: Vec<&[f64]> = recorded
            .rows()
            .enumerate()
            .filter(|(index, _)| index % stride == 0 || index + 1 == count)
            .map(|(_, row)| row)
            .collect();
        let curve = |x: usize, y: usize| -> Vec<(f64, f64)> {
            thinned.iter().map(|row| (row[x], row[y])).collect()
        };
        let bodies = summary.coordinates.as_deref().and_then(bodies);
        let title = match summary.status {
            Status::Failed => format!("{label} (failed at t = {})", Float(summary.t_end)),
            Status::Ok => label,
        };
        let panel = match bodies {
            Some(bodies) => Panel {
                title,
                x_label: "x".into(),
                y_label: "y".into(),
                x_log: false,
                y_log: false,
                equal_scale: true,
                scatter: false,
                series: bodies
                    .into_iter()
                    .filter_map(|body| {
                        let x = column(&format!("q_{body}_x"))?;
                        let y = column(&format!("q_{body}_y"))?;
                        Some(Series {
                            points: curve(x, y),
                            label: body,
                        })
                    })
                    .collect(),
            },
            None => {
                // The configuration: q on ℝᴺ, every column but t and the energy elsewhere.
                let configuration = |name: &&String| match &summary.coordinates {
                    Some(_) => name.starts_with("q_"),
                    None => !matches!(name.as_str(), "t" | "energy"),
                };
                Panel {
                    title,
                    x_label: "t".into(),
                    y_label: "configuration".into(),
                    x_log: false,
                    y_log: false,
                    equal_scale: false,
                    scatter: false,
                    series: recorded
                        .columns
                        .iter()
                        .filter(configuration)
                        .filter_map(|name| {
                            Some(Series {
                                label: name.strip_prefix("q_").unwrap_or(name).into(),
                                points: curve(0, column(name)?),
                            })
                        })
                        .collect(),
                }
            }
        };
        let energy_error = match column("energy") {
            Some(energy) => {
                let rows: Vec<&[f64]> = recorded.rows().collect();
                rows.chunks(stride)
                    .filter_map(|chunk| {
                        chunk
                            .iter()
                            .map(|row| (row[0], (row[energy] - summary.energy_initial).abs()))
                            .max_by(|a, b| a.1.total_cmp(&b.1))
                    })
                    .collect()
            }
            None => Vec::new(),
        };
        Drawn {
            panel,
            energy_error,
        }
    }
}

/// The bodies of a model whose coordinates come in groups `<body>_x`, `<body>_y` (and
/// `<body>_z`), in order; `None` if any coordinate is not of such a group.
fn bodies(coordinates: &[String]) -> Option<Vec<String>> {
    let mut bodies: Vec<String> = Vec::new();
    for name in coordinates {
        let (body, axis) = name.rsplit_once('_')?;
        let grouped = |axis: &str| coordinates.contains(&format!("{body}_{axis}"));
        if !matches!(axis, "x" | "y" | "z") || !grouped("x") || !grouped("y") || body.is_empty() {
            return None;
        }
        if !bodies.iter().any(|known| known == body) {
            bodies.push(body.into());
        }
    }
    (!bodies.is_empty()).then_some(bodies)
}

/// Width and height of a panel of the picture, in pixels.
const PANEL_SIZE: (u32, u32) = (560, 520);

/// Draw the picture into `file` and put it in place: a panel per method (in order, those
/// that ran) and one of the energy errors; the path drawn.
fn draw(mut file: OutputFile, outcomes: &[Outcome]) -> Result<PathBuf, SceneError> {
    let drawn: Vec<(&Outcome, &Drawn)> = outcomes
        .iter()
        .filter_map(|outcome| Some((outcome, outcome.drawn.as_ref()?)))
        .collect();
    let mut panels: Vec<Panel> = drawn.iter().map(|(_, d)| d.panel.clone()).collect();
    panels.push(Panel {
        title: "energy error".into(),
        x_label: "t".into(),
        y_label: "|E - E0|".into(),
        x_log: false,
        y_log: true,
        equal_scale: false,
        scatter: false,
        series: drawn
            .iter()
            .map(|(outcome, d)| Series {
                label: outcome.method.to_string(),
                points: d.energy_error.clone(),
            })
            .collect(),
    });
    let columns = (panels.len() as f64).sqrt().ceil() as usize;
    let svg = render_svg_grid(&panels, columns, PANEL_SIZE.0, PANEL_SIZE.1)?;
    let path = file.path().to_path_buf();
    std::io::Write::write_all(&mut file, svg.as_bytes()).map_err(|source| SceneError::Write {
        path: path.clone(),
        source,
    })?;
    file.commit()?;
    Ok(path)
}
