//! `svi`: run scenes of the svi model zoo from the command line.

use std::io::IsTerminal;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use svi_cli::{BUILTIN_SCENES, DEFAULT_SCENE, Float, Overrides, Scene, describe_models};

/// Spectral variational integrators and spectral collocation, from one Lagrangian.
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
        Command::Run(args) => run(args),
        Command::List => {
            list();
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: RunArgs) -> anyhow::Result<()> {
    let name = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let mut scene = Scene::load(name)?;
    scene.apply(&args.overrides)?;
    let summary = scene
        .run(std::io::stderr().is_terminal())
        .with_context(|| format!("scene '{name}' failed"))?;
    if args.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        print!("{summary}");
    }
    Ok(())
}

fn list() {
    println!("Built-in scenes (svi run NAME):");
    for (name, text) in BUILTIN_SCENES {
        let description = text
            .lines()
            .next()
            .and_then(|line| line.strip_prefix('#'))
            .unwrap_or("")
            .trim();
        println!("  {name:<18}{description}");
    }
    println!();
    println!("Models (model = \"NAME\" in a scene; parameters, default step and horizon):");
    for model in describe_models() {
        let parameters: Vec<String> = model
            .parameters
            .0
            .iter()
            .map(|(name, value)| format!("{name} = {}", Float(*value)))
            .collect();
        let mut facts = vec![format!("q = ({})", model.coordinates.join(", "))];
        if model.momenta > 0 {
            let noun = if model.momenta == 1 {
                "momentum"
            } else {
                "momenta"
            };
            facts.push(format!("{} Noether {noun}", model.momenta));
        }
        if model.exact_solution {
            facts.push("exact solution".into());
        }
        println!(
            "  {:<18}{}; h = {}, t_end = {}; {}",
            model.name,
            parameters.join(", "),
            Float(model.h),
            Float(model.t_end),
            facts.join(", ")
        );
    }
}
