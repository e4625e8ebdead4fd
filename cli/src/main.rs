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
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
    /// Form of the Lie-group integrator for rigid-body scenes: full or reduced.
    #[arg(long, value_name = "FORM")]
    form: Option<String>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::List => {
            list();
            Ok(())
        }
        Command::Bench(args) => bench(args),
        Command::Stability(args) => stability(args),
        Command::Stress(args) => stress(args),
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
    if let Some(scene) = svi_cli::rigid::RigidScene::load_if_rigid(name) {
        return run_rigid(scene?, name, &args);
    }
    anyhow::ensure!(
        args.form.is_none(),
        "--form applies to rigid-body scenes only (see svi list)"
    );
    let mut scene = Scene::load(name)?;
    scene.apply(&args.overrides)?;
    let summary = scene
        .run(std::io::stderr().is_terminal())
        .with_context(|| format!("scene '{name}' failed"))?;
    print_summary(&summary, args.json)
}

fn run_rigid(
    mut scene: svi_cli::rigid::RigidScene,
    name: &str,
    args: &RunArgs,
) -> anyhow::Result<()> {
    scene.apply(&args.overrides, args.form.as_deref())?;
    let summary = scene
        .run(std::io::stderr().is_terminal())
        .with_context(|| format!("scene '{name}' failed"))?;
    print_summary(&summary, args.json)
}

/// Print a run's summary as one JSON object or as text.
fn print_summary<S: serde::Serialize + std::fmt::Display>(
    summary: &S,
    json: bool,
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(summary)?);
    } else {
        print!("{summary}");
    }
    Ok(())
}

fn bench(args: BenchArgs) -> anyhow::Result<()> {
    use svi_cli::bench::{BenchOptions, parse_methods, plot, to_csv, work_precision};
    let name = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let mut scene = Scene::load(name)?;
    let overrides = Overrides {
        parameters: args.parameters.clone(),
        t_end: args.t_end,
        ..Overrides::default()
    };
    scene.apply(&overrides)?;
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
    let records = work_precision(&scene, &options)
        .with_context(|| format!("benchmark of scene '{name}' failed"))?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("cannot create {}", args.out_dir.display()))?;
    let stem = std::path::Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("bench");
    let csv = args.out_dir.join(format!("{stem}.csv"));
    std::fs::write(&csv, to_csv(&records))
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let svg = args.out_dir.join(format!("{stem}.svg"));
    plot(&records, stem, &svg)?;
    print!("{}", to_csv(&records));
    eprintln!("wrote {} and {}", csv.display(), svg.display());
    Ok(())
}

fn stress(args: StressArgs) -> anyhow::Result<()> {
    use svi_cli::stress::{StressOptions, stress, to_markdown, write_outputs};
    let options = StressOptions {
        cases: args.cases,
        methods: svi_cli::bench::parse_methods(&args.methods)?,
        drift_steps: args.steps,
        bisections: args.bisections,
        tolerance: args.tolerance,
        verbose: true,
    };
    let records = stress(&options)?;
    write_outputs(&records, &args.out_dir)?;
    print!("{}", to_markdown(&records));
    eprintln!(
        "wrote stress.md, stress.csv, windows.csv and drift.svg to {}",
        args.out_dir.display()
    );
    Ok(())
}

fn stability(args: StabilityArgs) -> anyhow::Result<()> {
    use svi::MethodSpec;
    use svi_cli::stability::{Answer, Request, describe, figure_configurations, plot, run, to_csv};
    if let Some(values) = args.z {
        let spec: MethodSpec = args.method.parse()?;
        if let Answer::Points(points) = run(spec, &Request::Values(values))? {
            print!("{}", to_csv(&points));
        }
        return Ok(());
    }
    let request = Request::Range {
        z_min: args.z_min,
        z_max: args.z_max,
        samples: args.samples,
    };
    let configurations: Vec<(String, MethodSpec)> = if args.figures {
        figure_configurations()
            .into_iter()
            .map(|(label, spec)| (label.to_string(), spec))
            .collect()
    } else {
        vec![(args.method.clone(), args.method.parse()?)]
    };
    let mut reports = Vec::new();
    for (label, spec) in configurations {
        if let Answer::Report(report) = run(spec, &request)? {
            print!("{}", describe(&label, &report));
            reports.push((label, report));
        }
    }
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("cannot create {}", args.out_dir.display()))?;
    if let [(_, report)] = reports.as_slice() {
        let csv = args.out_dir.join("stability.csv");
        std::fs::write(&csv, to_csv(&report.points))
            .with_context(|| format!("cannot write {}", csv.display()))?;
        eprintln!("wrote {}", csv.display());
    }
    let svg = args.out_dir.join("stability.svg");
    plot(&reports, &svg)?;
    eprintln!("wrote {}", svg.display());
    Ok(())
}

fn list() {
    println!("Built-in scenes (svi run NAME):");
    let width = BUILTIN_SCENES
        .iter()
        .map(|(name, _)| name.len() + 2)
        .max()
        .unwrap_or(0)
        .max(18);
    for (name, text) in BUILTIN_SCENES {
        let description = text
            .lines()
            .next()
            .and_then(|line| line.strip_prefix('#'))
            .unwrap_or("")
            .trim();
        println!("  {name:<width$}{description}");
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
    println!();
    for line in svi_cli::rigid::list_lines() {
        println!("{line}");
    }
}
