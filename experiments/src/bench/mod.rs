//! Work–precision harness: run time and cost against error, method by method.
//!
//! [`work_precision`] sweeps each method's step (or tolerance) on a scene, and records for
//! every point the final position error at the horizon (against the model's exact solution,
//! or for a model without one against a resolved reference run: SVI of order 12 at the
//! model's default step h, checked against h/2; `--coordinate` measures one coordinate, e.g.
//! the slow angle of the stiff spring pendulum), the
//! largest energy and Noether-momentum errors (measured in a separate, untimed run with
//! observers), the derivative evaluations, the nonlinear iterations and the wall time of a run
//! that observes nothing (median over batches, each batch repeating the run for at least
//! `min_batch` seconds, after a warm-up run). Chains (zoo or text) and Lagrangians written as
//! text, which have no exact solution, are swept through the scene's own run against the
//! resolved reference run, each point a whole run (`sweep_runs`; fixed-step methods).
//!
//! Fixed-step methods start from 8 steps, double until the error is below 3·10⁻², go back by
//! bisection to the fewest steps (to within 1/16, or one step) with an error below 3·10⁻² — a method that
//! fails at too few steps, as a reparametrised one whose stage solve does not converge, jumps
//! from failing to far below it, and its sweep would otherwise start there — then
//! multiply the step count by 10^(1/(2·order)) per point (about a √10-fold error reduction,
//! so that the crossing of an error target is located to within a factor 1.2 in time). The
//! trigonometric peer `molly`, the mollified impulse method of García-Archilla, Sanz-Serna &
//! Skeel (1999) written for the spring pendulum's splitting ([`crate::bench::molly`]), takes
//! fixed steps over the fast spring and is swept in the same way (order 2).
//! Adaptive peers (`ode_solvers`' DOP853 and Dopri5, and the stiff solver
//! `differential-equations`' Radau5 with the exact Jacobian by automatic differentiation, on
//! the first-order form q̇ = v, v̇ = q̈(t, q, v) derived from the Lagrangian) sweep
//! tol = 10⁻³, 10⁻³·⁵, …, 10⁻¹⁶ (Radau5, whose error falls as about tol^0.55: 10⁻³, 10⁻⁴,
//! …, 10⁻¹⁴, as RADAU5 rejects rtol ≤ 10⁻¹⁵) with rtol = atol = tol and sparse output. A
//! sweep stops at the target error, when a single run takes longer than `max_run`, or when
//! the error has stalled for three points (round-off).
//! Given step counts ([`BenchOptions::steps`]) or tolerances ([`BenchOptions::tolerances`])
//! replace the sweep: every one of them is measured; a run that fails is a warning naming it,
//! and an error only when every one of a method's runs fails.
//!
//! The library's adaptive modes have rows of their own beside the fixed-step methods and the
//! peers, so one plot shows all: `METHOD@MONITOR` (e.g. `svi:9/8@sundman:1`) is the method
//! reparametrised in time ([`svi::Integrator::try_solve_reparametrized`]), swept like a
//! fixed-step method over n steps in τ of Δτ = (t_end − t0)/n (its `h` column is Δτ, its
//! `steps` the τ-steps taken); `METHOD@step` is step doubling ([`svi::solve()`]), swept over
//! tolerances like the peers down to 1e-15; `METHOD@sem` takes symplectic-energy-momentum
//! steps ([`svi::stepping::sem`]), swept over its first step (t_end − t0)/n like a fixed-step
//! method (its `steps` count every trial step of the energy equation).

mod adaptive;
mod files;
pub(crate) mod method;
pub mod molly;
mod options;
pub mod peers;
mod problem;
mod record;
mod scene_runs;
pub mod spectral;
mod sweep;
mod zoo;

pub use files::{plot, to_csv};
pub use method::{BenchMethod, parse_methods};
pub use options::{BenchArgs, BenchOptions, DEFAULT_MAX_RUN, DEFAULT_METHODS, DEFAULT_TARGET};
pub use record::{MethodFailure, Record, Sweeps};

use crate::bench::scene_runs::sweep_runs;
use crate::bench::zoo::Bench;
use crate::report::output::{self, OutputDirectory};
use crate::scene::builtin::DEFAULT_SCENE;
use crate::scene::overrides::Overrides;
use crate::scene::{Scene, SceneError};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use svi::method::registry::SpaceKind;
use svi_models::visit_model;

/// Sweep every method of `options` on `scene`. A method that fails is reported in
/// [`Sweeps::failures`] (and as a warning on stderr) while the others go on; the sweep is an
/// error when the input is bad or when no method measured any point (the first method's
/// error). With `verbose`, every point is printed to stderr under a progress bar over the
/// methods (drawn only on a terminal). On a chain or a text model the default method list
/// ([`DEFAULT_METHODS`]) is narrowed to its fixed-step methods of the library, the ones such a
/// model runs.
pub fn work_precision(scene: &Scene, options: &BenchOptions) -> Result<Sweeps, SceneError> {
    let runs_whole_scenes = scene.is_local() || scene.is_text();
    let narrowed;
    let options = if runs_whole_scenes && options.methods == BenchOptions::default().methods {
        narrowed = BenchOptions {
            methods: (options.methods.iter())
                .filter(|method| matches!(method, BenchMethod::Library(_)))
                .cloned()
                .collect(),
            ..options.clone()
        };
        &narrowed
    } else {
        options
    };
    options.check()?;
    scene.check()?;
    if scene.space() == SpaceKind::Group {
        return Err(SceneError::NotApplicable {
            option: "svi bench SCENE",
            reason: format!(
                "'{}' is a rigid body on SO(3); svi bench measures models on ℝᴺ against their \
                 exact solution (see svi list)",
                scene.model
            ),
        });
    }
    if options.methods.contains(&BenchMethod::Molly) {
        molly::check_model(&scene.model)?;
    }
    let progress = if options.verbose {
        let bar = ProgressBar::new(options.methods.len() as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} methods {msg}") {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let records = if runs_whole_scenes {
        sweep_runs(scene, options, &progress)
    } else {
        let bench = Bench {
            scene,
            options,
            progress: &progress,
        };
        visit_model(&scene.model, bench).unwrap_or_else(|error| Err(error.into()))
    };
    progress.finish_and_clear();
    records
}

/// `svi bench` with the arguments `args`: [`execute`] on their scene, overrides, options and
/// output directory.
pub fn execute_args(args: &BenchArgs) -> anyhow::Result<()> {
    let (overrides, options) = args.options()?;
    execute(
        args.scene.as_deref().unwrap_or(DEFAULT_SCENE),
        &overrides,
        &options,
        &args.out_dir,
    )
}

/// `svi bench`: sweep `options.methods` on the scene `name` (with the parameter and horizon
/// overrides), write `<scene>.csv` and `<scene>.svg` into `out_dir` (created, with its files,
/// before the sweep) and print the CSV. A method that measured no point is a warning; the
/// others' rows are kept.
pub fn execute(
    name: &str,
    overrides: &Overrides,
    options: &BenchOptions,
    out_dir: &Path,
) -> anyhow::Result<()> {
    options.check()?;
    let mut scene = Scene::load(name)?;
    scene.apply(overrides)?;
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("bench");
    let (csv, svg) = (format!("{stem}.csv"), format!("{stem}.svg"));
    let inputs: Vec<&Path> = scene.source.iter().map(PathBuf::as_path).collect();
    let mut dir =
        OutputDirectory::create("--out-dir", out_dir, &[csv.clone(), svg.clone()], &inputs)
            .map_err(SceneError::from)?;
    let records = work_precision(&scene, options)
        .with_context(|| format!("benchmark of scene '{name}' failed"))?
        .records;
    let table = to_csv(&records);
    dir.write(&csv, table.as_bytes())
        .map_err(SceneError::from)?;
    let picture = plot(&records, stem, options.coordinate.as_deref())?;
    dir.write(&svg, picture.as_bytes())
        .map_err(SceneError::from)?;
    dir.commit().map_err(SceneError::from)?;
    output::print(&table).map_err(SceneError::from)?;
    output::warn(format_args!(
        "wrote {} and {}",
        out_dir.join(&csv).display(),
        out_dir.join(&svg).display()
    ));
    Ok(())
}
