//! `svi`: run scenes of the svi model zoo from the command line.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use svi_cli::command;
use svi_cli::command::bench::{BenchOptions, parse_methods};
use svi_cli::command::stability::Request;
use svi_cli::command::stress::StressOptions;
use svi_cli::scene::error::is_bad_input;
use svi_cli::{DEFAULT_SCENE, Overrides, SceneError};

/// Spectral variational integrators and spectral collocation, from one Lagrangian.
///
/// Exit status: 0 when the command succeeded; 1 when a run failed after it started (a solve
/// that does not converge, a state that diverges: the error reports the last good state, and
/// the trajectory so far is written) or an output could not be written; 2 for bad input (an
/// unknown scene, model or method, a malformed scene, an invalid value, an option that the
/// scene's model, method or other options cannot use), as for malformed arguments.
#[derive(Debug, Parser)]
#[command(name = "svi", version, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scene: a built-in name or a TOML scene file.
    Run(RunArgs),
    /// List the built-in scenes and the models with their parameters.
    List,
    /// Work–precision sweep: run time and evaluations against error, per method.
    Bench(BenchArgs),
    /// Linear stability on the harmonic oscillator: S(z), regions, plots.
    Stability(StabilityArgs),
    /// Stress tests: largest stable step, failure mode and long-time energy drift per method.
    Stress(StressArgs),
}

#[derive(Debug, Args)]
struct StressArgs {
    /// Stress scenes, comma-separated [default: all of them].
    #[arg(long, value_delimiter = ',')]
    cases: Vec<String>,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help), and dop853.
    #[arg(
        long,
        value_name = "LIST",
        default_value = svi_cli::stress::DEFAULT_METHODS,
        long_help = svi_cli::method_help(
            "Methods, comma-separated: the library's, and dop853 (ode_solvers' DOP853, drift \
             only)."
        )
    )]
    methods: String,
    /// Steps of the long run of each method.
    #[arg(long, default_value_t = 1_000_000)]
    steps: usize,
    /// Bisections refining each stability boundary.
    #[arg(long, default_value_t = 5)]
    bisections: usize,
    /// DOP853's rtol = atol.
    #[arg(long, default_value_t = 1e-10)]
    tolerance: f64,
    /// Directory for stress.md, stress.csv, windows.csv and drift.svg.
    #[arg(long, default_value = "stress-out")]
    out_dir: std::path::PathBuf,
}

#[derive(Debug, Args)]
struct StabilityArgs {
    /// Method: NAME, NAME:P or NAME:P/M, e.g. svi:5/4, sc:9, verlet (see --help).
    #[arg(
        long,
        value_name = "METHOD",
        default_value = "svi:5/4",
        long_help = svi_cli::method_help("Method (for models on ℝᴺ).")
    )]
    method: String,
    /// Evaluate exactly these z values (comma-separated) and print CSV to stdout.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    z: Option<Vec<f64>>,
    /// Lower end of the z range.
    #[arg(long, default_value_t = 1e-6)]
    z_min: f64,
    /// Upper end of the z range.
    #[arg(long, default_value_t = 900.0)]
    z_max: f64,
    /// Grid points on the z range.
    #[arg(long, default_value_t = 900)]
    samples: usize,
    /// The six configurations of the paper's Figs. 3–6 instead of --method.
    #[arg(long)]
    figures: bool,
    /// Directory for `stability.csv` (one method) and `stability.svg`.
    #[arg(long, default_value = "stability-out")]
    out_dir: std::path::PathBuf,
}

#[derive(Debug, Args)]
struct BenchArgs {
    /// Built-in scene or scene file; its model needs an exact solution [default: kepler].
    scene: Option<String>,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help), dop853, dopri5.
    #[arg(
        long,
        value_name = "LIST",
        default_value = svi_cli::bench::DEFAULT_METHODS,
        long_help = svi_cli::method_help(
            "Methods, comma-separated: the library's (for models on ℝᴺ), and the adaptive \
             peers dop853 and dopri5 (ode_solvers' DOP853 and Dopri5)."
        )
    )]
    methods: String,
    /// Model parameter NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = svi_cli::parse_parameter)]
    parameters: Vec<(String, f64)>,
    /// Horizon (overrides the scene's).
    #[arg(long)]
    t_end: Option<f64>,
    /// Stop a method's sweep once its final error is below this.
    #[arg(long, default_value_t = 1e-13)]
    target: f64,
    /// Stop a method's sweep after a point whose single run takes longer (seconds).
    #[arg(long, default_value_t = 2.0)]
    max_run: f64,
    /// Timing batches per point (median reported).
    #[arg(long, default_value_t = 5)]
    batches: usize,
    /// Minimum duration of a timing batch (seconds).
    #[arg(long, default_value_t = 0.2)]
    min_batch: f64,
    /// Run the fixed-step methods at these step counts instead of sweeping them.
    #[arg(long, value_delimiter = ',')]
    steps: Vec<usize>,
    /// Run the adaptive peers (dop853, dopri5) at these tolerances instead of sweeping them.
    #[arg(long, value_delimiter = ',')]
    tolerances: Vec<f64>,
    /// Directory for `<scene>.csv` and `<scene>.svg`.
    #[arg(long, default_value = "bench-out")]
    out_dir: std::path::PathBuf,
}

#[derive(Debug, Args)]
struct RunArgs {
    /// Built-in scene (see `svi list`) or path to a scene TOML file [default: kepler].
    scene: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
    /// Print the summary as one JSON object, also when the run fails ("status": "failed",
    /// with the error and the run up to its last good state).
    #[arg(long)]
    json: bool,
    /// Make a failed health check (an energy error above 1 % of the energy's scale, an
    /// escaped configuration) an error: exit status 1 instead of a warning.
    #[arg(long)]
    strict: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => command::run::execute(
            args.scene.as_deref().unwrap_or(DEFAULT_SCENE),
            &args.overrides,
            args.json,
            args.strict,
        ),
        Command::List => {
            command::list::print();
            Ok(())
        }
        Command::Bench(args) => bench(args),
        Command::Stability(args) => command::stability::execute(
            &args.method,
            match args.z {
                Some(values) => Request::Values(values),
                None => Request::Range {
                    z_min: args.z_min,
                    z_max: args.z_max,
                    samples: args.samples,
                },
            },
            args.figures,
            &args.out_dir,
        ),
        Command::Stress(args) => stress(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(exit_status(&error))
        }
    }
}

/// The exit status of a failed command (see the long help): 2 when the outermost typed error
/// is bad input, as for clap's own argument errors; 1 when a run failed or an output could
/// not be written.
fn exit_status(error: &anyhow::Error) -> u8 {
    let bad_input = error.chain().find_map(|cause| {
        cause
            .downcast_ref::<SceneError>()
            .map(SceneError::is_bad_input)
            .or_else(|| cause.downcast_ref::<svi::Error>().map(is_bad_input))
    });
    if bad_input == Some(true) { 2 } else { 1 }
}

/// `svi bench`: the options from the arguments.
fn bench(args: BenchArgs) -> anyhow::Result<()> {
    let overrides = Overrides {
        parameters: args.parameters,
        t_end: args.t_end,
        ..Overrides::default()
    };
    let options = BenchOptions {
        methods: parse_methods(&args.methods)?,
        target: args.target,
        max_run: args.max_run,
        batches: args.batches,
        min_batch: args.min_batch,
        steps: args.steps,
        tolerances: args.tolerances,
        verbose: true,
    };
    command::bench::execute(
        args.scene.as_deref().unwrap_or(DEFAULT_SCENE),
        &overrides,
        &options,
        &args.out_dir,
    )
}

/// `svi stress`: the options from the arguments.
fn stress(args: StressArgs) -> anyhow::Result<()> {
    let options = StressOptions {
        cases: args.cases,
        methods: parse_methods(&args.methods)?,
        drift_steps: args.steps,
        bisections: args.bisections,
        tolerance: args.tolerance,
        verbose: true,
    };
    command::stress::execute(&options, &args.out_dir)
}
