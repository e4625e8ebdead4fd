//! `svi`: run scenes of the svi model zoo from the command line.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use svi_cli::command;
use svi_cli::command::bench::BenchArgs;
use svi_cli::command::stability::StabilityArgs;
use svi_cli::command::stress::StressArgs;
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
struct RunArgs {
    /// Built-in scene (see `svi list`) or path to a scene TOML file [default: kepler].
    scene: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => command::run::execute(
            args.scene.as_deref().unwrap_or(DEFAULT_SCENE),
            &args.overrides,
            args.json,
        ),
        Command::List => {
            command::list::print();
            Ok(())
        }
        Command::Bench(args) => command::bench::execute_args(&args),
        Command::Stability(args) => command::stability::execute_args(&args),
        Command::Stress(args) => command::stress::execute_args(&args),
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
