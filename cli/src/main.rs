//! `svi`: run scenes of the svi model zoo from the command line.

use std::process::ExitCode;

mod outcome;

use std::io::IsTerminal;

use clap::{Args, Parser, Subcommand};
use svi_experiments::bench::BenchArgs;
use svi_experiments::compare::CompareArgs;
use svi_experiments::ensemble::EnsembleArgs;
use svi_experiments::scale::ScaleArgs;
use svi_experiments::scene::error::is_bad_input;
use svi_experiments::scene::spectral::SpectralScene;
use svi_experiments::stability::StabilityArgs;
use svi_experiments::stress::StressArgs;
use svi_experiments::{AnyScene, Control, DEFAULT_SCENE, Overrides, SceneError};

/// Spectral variational integrators and spectral collocation, from one Lagrangian.
///
/// Exit status: 0 when the command succeeded; 1 when a run failed after it started (a solve
/// that does not converge, a state that diverges: the error reports the last good state, and
/// the trajectory so far is written), an output could not be written, or a health check
/// failed under `svi run --strict`; 2 for bad input (an unknown scene, model or method, a
/// malformed scene, an invalid value, an option that the scene's model, method or other
/// options cannot use), as for malformed arguments.
#[derive(Debug, Parser)]
#[command(name = "svi", version, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scene: a built-in name or a TOML scene file (a field scene, see `svi list`, runs
    /// the multisymplectic integrator, on a moving mesh the r-adaptive one).
    Run(RunArgs),
    /// List the built-in scenes, the models with their parameters and the Lie groups.
    List,
    /// Work–precision sweep: run time and evaluations against error, per method.
    Bench(BenchArgs),
    /// Run a scene once per method (the same step, horizon and initial state): steps, wall
    /// time, energy and momentum errors per method, and a picture of the trajectories and
    /// energy errors (exit status 1 if a method failed; every method is still reported).
    Compare(CompareArgs),
    /// Linear stability on the harmonic oscillator: S(z), regions, plots.
    Stability(StabilityArgs),
    /// Stress tests: largest stable step, failure mode and long-time energy drift per method.
    Stress(StressArgs),
    /// Time per step against the number of degrees of freedom of chains (runtime-dimension
    /// models): fitted exponent, peak memory, CSV and SVG.
    Scale(ScaleArgs),
    /// Run a scene over grids or random draws of parameters and initial states, in parallel:
    /// one row per member (exit status 1 if any member failed; the table lists every one).
    Ensemble(EnsembleArgs),
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

/// Let a closed pipe end the process as it ends other Unix tools (`svi list | head`), by
/// SIGPIPE, instead of a panic in `println!`: Rust ignores SIGPIPE by default.
fn quit_quietly_when_the_reader_goes() {
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE at the start of `main`, before any
    // thread is spawned; no handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Remove the temporaries of outputs not yet written when Ctrl-C or SIGTERM ends the run, so
/// an interrupted run leaves every output file as it was and no stray file beside it; exit
/// with status 130, as a shell reports an interrupted command.
fn clean_up_when_interrupted() {
    // A handler that cannot be installed (one is already) leaves the default: the process
    // ends, the outputs are still untouched and only a hidden `.svi-*.tmp` file may remain.
    let _ = ctrlc::set_handler(|| {
        svi_experiments::report::output::remove_pending();
        std::process::exit(130);
    });
}

/// The arguments, or the exit status of a command line the parser rejects or answers itself
/// (`--help`, `--version`). A rejected command line with `--json` also prints the one JSON
/// failure object of bad input on stdout, as every failure of a command with `--json` does.
fn parse_arguments() -> Result<Cli, ExitCode> {
    let error = match Cli::try_parse() {
        Ok(cli) => return Ok(cli),
        Err(error) => error,
    };
    let code = error.exit_code();
    let answered = matches!(
        error.kind(),
        clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
    );
    if !answered && std::env::args_os().any(|arg| arg == "--json") {
        let text = error.render().to_string();
        let message = text
            .lines()
            .next()
            .unwrap_or("invalid arguments")
            .trim_start_matches("error: ")
            .to_string();
        let report = svi_experiments::report::summary::ErrorReport {
            kind: "invalid_input",
            message,
            step: None,
            t: None,
        };
        let object = svi_experiments::run::failure_object(&report);
        // Nothing is left to report a failed write with: the exit status still says it.
        let _ = svi_experiments::report::output::print(format_args!("{object}\n"));
    }
    // Help, version and the parser's message, written as clap writes them; a failed write
    // (a full device) is an error, not a panic.
    if error.print().is_err() {
        svi_experiments::report::output::warn("error: cannot write to standard output");
        return Err(ExitCode::from(1));
    }
    Err(ExitCode::from(u8::try_from(code).unwrap_or(2)))
}

fn main() -> ExitCode {
    quit_quietly_when_the_reader_goes();
    clean_up_when_interrupted();
    let cli = match parse_arguments() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    let result = match cli.command {
        Command::Run(args) => run(&args),
        Command::List => svi_experiments::report::output::print(svi_experiments::list::listing())
            .map_err(|error| SceneError::from(error).into()),
        Command::Bench(args) => match args
            .scene
            .as_deref()
            .map(|name| (name, SpectralScene::load(name)))
        {
            Some((name, Some(scene))) => {
                svi_experiments::bench::spectral::execute(name, scene, &args)
            }
            _ => svi_experiments::bench::execute_args(&args),
        },
        Command::Compare(args) => svi_experiments::compare::execute_args(&args),
        Command::Stability(args) => svi_experiments::stability::execute_args(&args),
        Command::Stress(args) => svi_experiments::stress::execute_args(&args),
        Command::Ensemble(args) => svi_experiments::ensemble::execute_args(&args),
        Command::Scale(args) => svi_experiments::scale::execute_args(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            svi_experiments::report::output::warn(format_args!("error: {error:#}"));
            ExitCode::from(exit_status(&error))
        }
    }
}

/// `svi run`: open the scene (built-in or file), put the command-line overrides on top, run
/// it (checked once) and print its outcome.
fn run(args: &RunArgs) -> anyhow::Result<()> {
    let name = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let result = AnyScene::open(name).and_then(|mut scene| {
        scene.overlay(&args.overrides)?;
        scene.run(Control {
            progress: std::io::stderr().is_terminal(),
            stop: None,
        })
    });
    outcome::print_outcome(name, result, args.json, args.strict)
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
