//! `svi ensemble`: one scene run many times over parameter and initial-state grids or random
//! draws, the members in parallel (rayon), one row per member in a table.
//!
//! Every member goes through the one run path: the ensemble's scene (loaded and overridden
//! as `svi run` does), the member's values applied ([`Member::apply`]: `--param` overrides
//! and `[initial]` fields), then [`Scene::run`]. A member's row therefore holds exactly the
//! numbers `svi run` prints for that member's scene. A member that fails — rejected values,
//! a solve that does not converge, a state that diverges, even a panic — is recorded with its
//! error kind and never stops or loses the others. Members are independent and their results
//! are collected in member order, so the table is the same for every thread count.

use std::io::{IsTerminal, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;

use crate::report::map::{self, Heatmap};
use crate::report::output::{self, OutputFile};
use crate::report::plot::{Panel, Series, render_svg};
use crate::report::schema::{self, Kind, Versioned};
use crate::report::summary::{ErrorReport, Status};
use crate::report::table::{MemberOutcome, Schema, Table};
use crate::run::Control;
use crate::run::outcome::error_report;
use crate::scene::ensemble::{
    Axis, Member, Random, Values, check_axes, members, parse_initial_axis, parse_parameter_axis,
};
use crate::scene::events::SectionSpec;
use crate::scene::overrides::{Overrides, RunFlags, diagnostics_help, diagnostics_long_help};
use crate::scene::schema::{Diagnostic, Indicator};
use crate::scene::{Scene, SceneError};

/// The most threads `--threads` accepts.
pub const MAX_THREADS: usize = 1024;

/// The diagnostics of a member when the ensemble names none: the energy error only (one
/// energy evaluation per step; the momentum and exact-solution errors cost more per step and
/// are asked for with `--diagnostics`).
pub const DEFAULT_DIAGNOSTICS: [Diagnostic; 1] = [Diagnostic::Energy];

/// `svi ensemble`'s arguments: its own, and the flags of `svi run` every member shares
/// ([`RunFlags`], with the ensemble's default diagnostics).
#[derive(Debug, Clone, Default, clap::Args)]
#[command(mut_arg("diagnostics", |arg| arg
    .help(diagnostics_help(&DEFAULT_DIAGNOSTICS))
    .long_help(diagnostics_long_help(&DEFAULT_DIAGNOSTICS))))]
pub struct EnsembleArgs {
    /// Built-in scene (see `svi list`) or path to a scene TOML file [default: kepler].
    pub scene: Option<String>,
    /// A varied model parameter (repeatable; several make a grid of every combination, the
    /// first slowest): NAME=LO:HI:COUNT (COUNT values from LO to HI, both included),
    /// NAME=V1,V2,... (these values; an item may be a grid: e=0:0.9:999,1.2) or, with --random, NAME=LO:HI (a range to draw from).
    #[arg(long = "param", value_name = "NAME=SPEC", value_parser = parse_parameter_axis, allow_hyphen_values = true)]
    pub parameters: Vec<Axis>,
    /// A varied initial component (repeatable, ℝᴺ scenes): FIELD.COORDINATE=SPEC with FIELD
    /// q, v or p and COORDINATE the model's name for it (see `svi list`) or its index from 0,
    /// e.g. q.alpha1=-3.1:3.1:200; SPEC as for --param. The other components are the
    /// scene's (or the model's defaults).
    #[arg(long = "initial", value_name = "FIELD.COORDINATE=SPEC", value_parser = parse_initial_axis, allow_hyphen_values = true)]
    pub initial: Vec<Axis>,
    /// Draw N members at random instead of a grid: each varied field uniformly from its
    /// range (LO:HI or LO:HI:COUNT) or its list.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub random: Option<usize>,
    /// Seed of the random draws (Xoshiro256++; the same seed gives the same members
    /// everywhere) [default: 0].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Threads running members [default: 0 = every core].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub threads: Option<usize>,
    /// Write the member table as CSV to FILE (one row per member); without it the table is
    /// printed on stdout (unless --json).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print the ensemble's summary (members, ok, failed by kind, threads, wall time) as one
    /// JSON object.
    #[arg(long)]
    pub json: bool,
    /// Draw the members: FILE.svg, a line of --plot-value against the one varied field;
    /// FILE.png, a heat map of --plot-value over a grid of two varied fields (the first
    /// across, the second up); with --section, FILE.svg of every member's section points.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// The table column to draw with --plot, e.g. energy_error_max or q_alpha2.
    #[arg(long, value_name = "COLUMN", requires = "plot")]
    pub plot_value: Option<String>,
    /// Colour the heat map cyclically with period 2π (for angles: a full turn is the same
    /// colour).
    #[arg(long, requires = "plot")]
    pub plot_cyclic: bool,
    /// Poincaré section of every member, COORDINATE=VALUE[,VARIABLE>VALUE] as for `svi run`
    /// (e.g. "x=0,vx>0"): --plot FILE.svg draws all members' points in one picture, the
    /// table counts them (column section_points).
    #[arg(long, value_name = "SECTION")]
    pub section: Option<SectionSpec>,
    /// The flags of `svi run` every member shares.
    #[command(flatten)]
    pub run: RunFlags,
}

impl EnsembleArgs {
    /// The overrides every member shares (those of `svi run` that an ensemble takes).
    pub fn overrides(&self) -> Overrides {
        Overrides {
            run: self.run.clone(),
            section: self.section.clone(),
            ..Overrides::default()
        }
    }

    /// The varied fields: the parameters, then the initial components.
    pub fn axes(&self) -> Vec<Axis> {
        self.parameters
            .iter()
            .chain(&self.initial)
            .cloned()
            .collect()
    }
}

/// An ensemble ready to run: the scene every member starts from, the varied fields and the
/// members.
#[derive(Debug, Clone)]
pub struct Ensemble {
    /// The scene with the shared overrides applied (and the default diagnostics of an
    /// ensemble, [`DEFAULT_DIAGNOSTICS`], where neither the scene nor the overrides name
    /// any).
    pub scene: Scene,
    /// The varied fields.
    pub axes: Vec<Axis>,
    /// The members, in table order.
    pub members: Vec<Member>,
    /// The summary columns of the table.
    pub schema: Schema,
}

impl Ensemble {
    /// Apply `overrides` to `scene`, check the axes against its model and expand the members.
    /// Every error here is bad input (exit status 2).
    pub fn new(
        mut scene: Scene,
        overrides: &Overrides,
        axes: Vec<Axis>,
        random: Option<Random>,
    ) -> Result<Ensemble, SceneError> {
        if overrides.run.diagnostics.is_none() && scene.output.diagnostics.is_none() {
            scene.output.diagnostics = Some(DEFAULT_DIAGNOSTICS.to_vec());
        }
        scene.apply(overrides)?;
        if scene.output.trajectory.is_some() {
            return Err(SceneError::NotApplicable {
                option: "output.trajectory",
                reason: "every member would write the same file; an ensemble writes one row \
                         per member (--out)"
                    .into(),
            });
        }
        // Each member keeps its section's points in memory, for the one picture of them all.
        scene.output.record = scene.output.section.is_some();
        let names = check_axes(&scene, &axes)?;
        let mut schema = match (&names.coordinates, names.group) {
            (Some(coordinates), _) => Schema::vector(coordinates),
            (None, Some((dimension, stored))) => Schema::group(dimension, stored),
            (None, None) if names.chain => Schema::chain(),
            (None, None) => Schema::rigid(),
        };
        if scene.output.section.is_some() {
            schema.add("section_points".into(), "section.points", None);
        }
        if let (Some(asked), Some(coordinates)) = (&scene.run.indicators, &names.coordinates) {
            for indicator in Indicator::ALL.into_iter().filter(|i| asked.contains(i)) {
                for (column, field, component) in indicator.columns(2 * coordinates.len()) {
                    schema.add(column, field, component);
                }
            }
        }
        let members = members(&axes, random)?;
        Ok(Ensemble {
            scene,
            axes,
            members,
            schema,
        })
    }

    /// The names of the varied fields, the table's columns after `member`.
    pub fn axis_names(&self) -> Vec<String> {
        self.axes.iter().map(Axis::name).collect()
    }

    /// Run the members `range` of the ensemble on `threads` threads (0: every core), calling
    /// `done` after each member. The outcomes are in member order whatever the thread count.
    /// When `stop` is set, the members running stop between steps, the others do not start,
    /// and the ensemble ends with [`SceneError::Interrupted`].
    pub fn run(
        &self,
        range: std::ops::Range<usize>,
        threads: usize,
        done: &(dyn Fn() + Sync),
        stop: Option<&AtomicBool>,
    ) -> Result<Vec<MemberOutcome>, SceneError> {
        let pool = thread_pool(threads)?;
        let members = self.members.get(range.clone()).unwrap_or(&[]);
        let control = Control {
            progress: false,
            stop,
        };
        let outcomes: Vec<MemberOutcome> = pool
            .install(|| {
                members
                    .par_iter()
                    .with_max_len(1)
                    .map(|member| {
                        let outcome =
                            (!control.stopped()).then(|| self.run_member(member, control));
                        done();
                        outcome
                    })
                    .collect::<Option<_>>()
            })
            .filter(|_| !control.stopped())
            .ok_or_else(|| SceneError::Interrupted {
                at: format!("the ensemble of members {range:?}"),
            })?;
        Ok(outcomes)
    }

    /// Run one member through the one run path, watched by `control`; a panic is recorded,
    /// not propagated.
    pub fn run_member(&self, member: &Member, control: Control<'_>) -> MemberOutcome {
        let run = || {
            member
                .apply(&self.axes, &self.scene)
                .and_then(|scene| scene.run(control))
        };
        match catch_unwind(AssertUnwindSafe(run)) {
            Ok(Ok(summary)) => MemberOutcome {
                summary: Some(summary),
                error: None,
            },
            Ok(Err(SceneError::RunFailed { partial, source })) => MemberOutcome {
                error: Some(ErrorReport::of(&source)),
                summary: Some(*partial),
            },
            Ok(Err(error)) => MemberOutcome {
                summary: None,
                error: Some(error_report(&error)),
            },
            Err(panic) => MemberOutcome {
                summary: None,
                error: Some(ErrorReport {
                    kind: "panic",
                    message: panic
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| panic.downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "the member's run panicked".into()),
                    step: None,
                    t: None,
                }),
            },
        }
    }

    /// The table of `outcomes`, the outcomes of the members from `first` on, in order.
    pub fn table(&self, first: usize, outcomes: &[MemberOutcome]) -> Table {
        let members = self.members.iter().skip(first).take(outcomes.len());
        let values: Vec<Vec<f64>> = members.map(|m| m.values.clone()).collect();
        Table::new(&self.schema, &self.axis_names(), first, &values, outcomes)
    }
}

/// A rayon pool of `threads` threads (0: every core).
fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, SceneError> {
    if threads > MAX_THREADS {
        return Err(SceneError::InvalidOption {
            option: "--threads",
            reason: format!("{threads} threads; need 0 (every core) to {MAX_THREADS}"),
        });
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|error| SceneError::InvalidOption {
            option: "--threads",
            reason: format!("cannot start {threads} threads: {error}"),
        })
}

impl Versioned for EnsembleSummary {
    fn kind(&self) -> Kind {
        Kind::Ensemble
    }
}

/// The summary of an ensemble (`svi ensemble --json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EnsembleSummary {
    /// The scene.
    pub scene: String,
    /// The varied fields.
    pub varied: Vec<String>,
    /// Members run.
    pub members: usize,
    /// Members with status `ok`.
    pub ok: usize,
    /// Members that failed.
    pub failed: usize,
    /// Failed members by error kind.
    pub failures: std::collections::BTreeMap<&'static str, usize>,
    /// Threads used.
    pub threads: usize,
    /// Wall time of all members, in seconds.
    pub seconds: f64,
    /// The table file, if written.
    pub out: Option<String>,
    /// The plot file, if drawn.
    pub plot: Option<String>,
    /// `ok` if every member reached its horizon, else `failed` (exit status 1).
    pub status: Status,
}

/// The error of an ensemble in which some members failed: exit status 1, after the table and
/// the summary are written.
#[derive(Debug, thiserror::Error)]
#[error("{failed} of {members} members failed ({kinds}); the table lists each with its error")]
pub struct MembersFailed {
    /// Members that failed.
    pub failed: usize,
    /// Members run.
    pub members: usize,
    /// The failures by kind, `kind: count, ...`.
    pub kinds: String,
}

/// `svi ensemble`: run the members, write the table (`--out` or stdout), the plot and the
/// summary. Exit status 0 when every member is `ok`; 1 when some failed (everything is still
/// written); 2 for bad input of the ensemble itself, including options that every member
/// rejects before it starts (then nothing is written).
///
/// With `--json` every outcome prints one JSON object: the summary, also when members failed;
/// for an ensemble that could not start, the failure object of `svi run --json`.
pub fn execute_args(args: &EnsembleArgs) -> anyhow::Result<()> {
    let result = run_and_write(args);
    if let Err(error) = &result
        && args.json
        && !error.is::<MembersFailed>()
    {
        let object = crate::run::outcome::failure_object(&report_of(error));
        // Stdout that cannot be written leaves the exit status to tell.
        let _ = output::print(format_args!("{object}\n"));
    }
    result
}

/// The JSON `error` object of any error of a command: that of the scene error in its chain
/// ([`error_report`]), else an `output` error.
pub fn report_of(error: &anyhow::Error) -> ErrorReport {
    error
        .chain()
        .find_map(|cause| cause.downcast_ref::<SceneError>())
        .map(error_report)
        .unwrap_or_else(|| ErrorReport {
            kind: "output",
            message: format!("{error:#}"),
            step: None,
            t: None,
        })
}

/// [`execute_args`] without the JSON failure object.
fn run_and_write(args: &EnsembleArgs) -> anyhow::Result<()> {
    let name = args
        .scene
        .as_deref()
        .unwrap_or(crate::scene::builtin::DEFAULT_SCENE);
    if args.seed.is_some() && args.random.is_none() {
        return Err(SceneError::NotApplicable {
            option: "--seed",
            reason: "seeds the draws of --random; a grid draws nothing".into(),
        }
        .into());
    }
    let random = args.random.map(|count| Random {
        count,
        seed: args.seed.unwrap_or(0),
    });
    let ensemble = Ensemble::new(Scene::load(name)?, &args.overrides(), args.axes(), random)?;
    let section = ensemble.scene.output.section.is_some();
    match (&args.plot, &args.plot_value) {
        (Some(plot), None) if section => check_section_plot(plot)?,
        (Some(_), Some(_)) if section => {
            return Err(SceneError::NotApplicable {
                option: "--plot-value",
                reason: "with --section, --plot draws the members' section points".into(),
            }
            .into());
        }
        (Some(plot), Some(column)) => check_plot(&ensemble, plot, column, random.is_some())?,
        (Some(_), None) => {
            return Err(SceneError::NotApplicable {
                option: "--plot",
                reason: "draws a column of the table: give --plot-value COLUMN (or --section \
                         for the members' section points)"
                    .into(),
            }
            .into());
        }
        (None, _) => {}
    }
    // The output files exist (as temporaries) before any member runs: an unwritable path is
    // reported first, and an existing file is replaced only once the table is complete.
    let outputs: Vec<(&'static str, &Path)> = [("--out", &args.out), ("--plot", &args.plot)]
        .into_iter()
        .filter_map(|(option, path)| Some((option, path.as_deref()?)))
        .collect();
    let inputs: Vec<&Path> = ensemble.scene.source.iter().map(PathBuf::as_path).collect();
    output::check_distinct(&outputs, &inputs).map_err(SceneError::from)?;
    if let Some(out) = &args.out {
        output::check_not_a_picture("--out", out).map_err(SceneError::from)?;
    }
    let mut out_file = args
        .out
        .as_deref()
        .map(|path| OutputFile::create("--out", path))
        .transpose()
        .map_err(SceneError::from)?;
    let plot_file = args
        .plot
        .as_deref()
        .map(|path| OutputFile::create("--plot", path))
        .transpose()
        .map_err(SceneError::from)?;
    let threads = args.threads.unwrap_or(0);
    let pool_threads = thread_pool(threads)?.current_num_threads();
    let count = ensemble.members.len();
    let bar = if std::io::stderr().is_terminal() && count > 1 {
        let bar = ProgressBar::new(count as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} members, {elapsed} (eta {eta})")
        {
            bar.set_style(style);
        }
        Some(bar)
    } else {
        None
    };
    let start = Instant::now();
    let outcomes = ensemble.run(
        0..count,
        threads,
        &|| {
            if let Some(bar) = &bar {
                bar.inc(1);
            }
        },
        None,
    )?;
    let seconds = start.elapsed().as_secs_f64();
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    // An ensemble none of whose members could start (a shared option the runs reject, as
    // --h -1) is bad input, as the same `svi run` would be: nothing is written.
    let bad_input = |outcome: &MemberOutcome| {
        outcome.summary.is_none()
            && outcome
                .error
                .as_ref()
                .is_some_and(|error| matches!(error.kind, "invalid_parameter" | "invalid_input"))
    };
    if !outcomes.is_empty() && outcomes.iter().all(bad_input) {
        let message = outcomes[0]
            .error
            .as_ref()
            .map(|error| error.message.clone());
        return Err(SceneError::NotApplicable {
            option: "the ensemble",
            reason: format!(
                "no member could start; the first: {}",
                message.unwrap_or_default()
            ),
        }
        .into());
    }
    let table = ensemble.table(0, &outcomes);
    match (out_file.as_mut(), args.json) {
        (Some(file), _) => {
            let path = file.path().to_path_buf();
            table
                .write_csv(file)
                .map_err(|source| SceneError::Write { path, source })?;
        }
        (None, false) => {
            let mut stdout = std::io::stdout().lock();
            table
                .write_csv(&mut stdout)
                .and_then(|()| stdout.flush())
                .map_err(SceneError::Stdout)?;
        }
        (None, true) => {}
    }
    if let Some(file) = out_file {
        file.commit().map_err(SceneError::from)?;
    }
    if let Some(mut file) = plot_file {
        match &args.plot_value {
            Some(column) => draw(&ensemble, &table, &mut file, column, args.plot_cyclic)?,
            None => draw_section(&ensemble, &outcomes, &mut file)?,
        }
        file.commit().map_err(SceneError::from)?;
    }
    let mut failures = std::collections::BTreeMap::new();
    for outcome in &outcomes {
        if let Some(error) = &outcome.error {
            *failures.entry(error.kind).or_insert(0) += 1;
        }
    }
    let failed: usize = failures.values().sum();
    let summary = EnsembleSummary {
        scene: name.into(),
        varied: ensemble.axis_names(),
        members: count,
        ok: count - failed,
        failed,
        failures,
        threads: pool_threads,
        seconds,
        out: args.out.as_ref().map(|path| path.display().to_string()),
        plot: args.plot.as_ref().map(|path| path.display().to_string()),
        status: if failed == 0 {
            Status::Ok
        } else {
            Status::Failed
        },
    };
    if args.json {
        output::print(format_args!("{}\n", schema::to_json(&summary)?))
            .map_err(SceneError::from)?;
    } else if args.out.is_some() {
        output::print(format_args!(
            "{} members ({} ok, {} failed) on {} threads in {:.3} s\n",
            count, summary.ok, failed, pool_threads, seconds
        ))
        .map_err(SceneError::from)?;
    }
    if failed > 0 {
        let kinds: Vec<String> = summary
            .failures
            .iter()
            .map(|(kind, n)| format!("{kind}: {n}"))
            .collect();
        return Err(MembersFailed {
            failed,
            members: count,
            kinds: kinds.join(", "),
        }
        .into());
    }
    Ok(())
}

/// Check before running that the plot can be drawn: a column of the table, over a grid (not
/// random draws) of one varied field for an `.svg` line, of two for a `.png` heat map.
fn check_plot(
    ensemble: &Ensemble,
    path: &Path,
    column: &str,
    random: bool,
) -> Result<(), SceneError> {
    let columns = ensemble.table(0, &[]).columns;
    if !columns.iter().any(|name| name == column) {
        return Err(SceneError::InvalidOption {
            option: "--plot-value",
            reason: format!(
                "no column '{column}' in the table (columns: {})",
                columns.join(", ")
            ),
        });
    }
    let not_applicable = |reason: String| SceneError::NotApplicable {
        option: "--plot",
        reason,
    };
    if random {
        return Err(not_applicable(
            "draws a grid; random members have no grid to draw on".into(),
        ));
    }
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match (extension, ensemble.axes.len()) {
        ("svg", 1) | ("png", 2) => Ok(()),
        ("svg", n) => Err(not_applicable(format!(
            "FILE.svg draws a line against one varied field; this ensemble varies {n}"
        ))),
        ("png", n) => Err(not_applicable(format!(
            "FILE.png draws a heat map over two varied fields; this ensemble varies {n}"
        ))),
        _ => Err(not_applicable(
            "FILE must end in .svg (a line over one varied field) or .png (a heat map over two)"
                .into(),
        )),
    }
}

/// Draw the column `column` of `table` into `file`: a line over one axis (SVG) or a heat map
/// over two (PNG).
fn draw(
    ensemble: &Ensemble,
    table: &Table,
    file: &mut OutputFile,
    column: &str,
    cyclic: bool,
) -> Result<(), SceneError> {
    let path = file.path().to_path_buf();
    let write_error = |source| SceneError::Write {
        path: path.clone(),
        source,
    };
    let index = table
        .column(column)
        .ok_or_else(|| SceneError::InvalidOption {
            option: "--plot-value",
            reason: format!(
                "no column '{column}' in the table (columns: {})",
                table.columns.join(", ")
            ),
        })?;
    let values = table.numbers(index);
    let names = ensemble.axis_names();
    if ensemble.axes.len() == 1 {
        let points: Vec<(f64, f64)> = ensemble
            .members
            .iter()
            .zip(&values)
            .filter_map(|(member, value)| value.map(|y| (member.values[0], y)))
            .collect();
        let positive = points.iter().all(|(_, y)| *y > 0.0);
        let (low, high) = points
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), (_, y)| {
                (l.min(*y), h.max(*y))
            });
        let panel = Panel {
            title: format!("{column} against {} ({})", names[0], ensemble.scene.model),
            x_label: names[0].clone(),
            y_label: column.into(),
            x_log: false,
            y_log: positive && high > 100.0 * low,
            equal_scale: false,
            scatter: false,
            series: vec![Series {
                label: column.into(),
                points,
            }],
        };
        let svg = render_svg(&[panel], 800, 500)?;
        file.write_all(svg.as_bytes()).map_err(write_error)
    } else {
        let size = |axis: &Axis| match axis.values {
            Values::Grid { count, .. } => count,
            Values::List(ref values) => values.len(),
            Values::Range { .. } => 1,
        };
        let (across, up) = (size(&ensemble.axes[0]), size(&ensemble.axes[1]));
        let heatmap = Heatmap {
            columns: across,
            rows: up,
            // Member i·up + j has the i-th value of the first axis and the j-th of the second.
            values: &values,
            cyclic,
        };
        map::write_png(&heatmap, file).map_err(write_error)
    }
}

/// A section picture is an SVG file.
fn check_section_plot(path: &Path) -> Result<(), SceneError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("svg") => Ok(()),
        _ => Err(SceneError::NotApplicable {
            option: "--plot",
            reason: "with --section draws FILE.svg, the members' section points".into(),
        }),
    }
}

/// The section points of every member (kept in memory by the members' runs), one series
/// each, as one scatter picture.
fn draw_section(
    ensemble: &Ensemble,
    outcomes: &[MemberOutcome],
    file: &mut OutputFile,
) -> Result<(), SceneError> {
    let path = file.path().to_path_buf();
    let mut axes = None;
    let mut series = Vec::new();
    for (member, outcome) in ensemble.members.iter().zip(outcomes) {
        let Some(summary) = &outcome.summary else {
            continue;
        };
        let (Some(recorded), Some(section)) = (
            &summary.recorded,
            summary.events.as_ref().and_then(|e| e.section.as_ref()),
        ) else {
            continue;
        };
        let column = |name: &String| recorded.columns.iter().position(|c| c == name);
        let (Some(x), Some(y)) = (column(&section.axes[0]), column(&section.axes[1])) else {
            continue;
        };
        axes.get_or_insert_with(|| (section.axes.clone(), section.surface.clone()));
        let label: Vec<String> = ensemble
            .axis_names()
            .iter()
            .zip(&member.values)
            .map(|(name, value)| format!("{name} = {value}"))
            .collect();
        series.push(Series {
            label: label.join(", "),
            points: recorded.rows().map(|row| (row[x], row[y])).collect(),
        });
    }
    let Some(([x_label, y_label], surface)) = axes else {
        return Err(SceneError::NotApplicable {
            option: "--plot",
            reason: "no member crossed the section: nothing to draw".into(),
        });
    };
    let panel = Panel {
        title: format!(
            "{}: section {surface}, {} orbits",
            ensemble.scene.model,
            series.len()
        ),
        x_label,
        y_label,
        x_log: false,
        y_log: false,
        equal_scale: false,
        scatter: true,
        series,
    };
    let svg = render_svg(&[panel], 800, 800)?;
    file.write_all(svg.as_bytes())
        .map_err(|source| SceneError::Write { path, source })
}
