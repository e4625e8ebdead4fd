//! `svi stress`: where each method breaks, how it fails, and how its energy behaves over a
//! long run.
//!
//! For every stress case (a built-in scene, [`CASES`]) and method, [`stress`] measures:
//!
//! 1. **The largest bounded step**: runs over the case's probe horizon on a geometric ladder
//!    of steps h_ref·2^(j/4) from the scene's step upwards (downwards if the scene's step
//!    already fails), refined by bisection between the last good and the first failing step.
//!    A step is *bounded* if the run completes with no error: every step's nonlinear solve
//!    converges, the state stays finite and within the divergence limit
//!    10³·max(1, ‖x₀‖∞). The failure mode beyond it is the error of the smallest failing step
//!    found (typed, with step index and time). Steps are probed from h_ref/2¹² to 2¹²·h_ref,
//!    within [T/(2·10⁶), T/8] for a probe horizon T.
//! 2. **The largest accurate step**: the same search for runs that also keep the energy error
//!    max |E − E₀| within 10 % of max(|E₀|, 1).
//! 3. **Long-time energy behaviour**: a run of `drift_steps` steps (default 10⁶) at the
//!    scene's step, the energy error sampled at up to 10⁵ points in 100 windows
//!    ([`svi::drift::EnergyWindows`]) and a line fitted through the window means
//!    ([`svi::drift::DriftFit`]): slope, slope × horizon (the drift), the mean half-range of
//!    the windows (the oscillation amplitude) and the largest |E − E₀|. DOP853 (ode_solvers,
//!    rtol = atol = [`StressOptions::tolerance`]) runs the same horizon as a non-geometric
//!    peer, sampled at up to 10⁵ of its accepted step points.
//!
//! The library's adaptive modes run as in `svi bench`: `METHOD@MONITOR` (time-reparametrised,
//! its τ-step Δτ in place of h: the searches run over Δτ, the long run takes Δτ = the scene's
//! step over the same physical horizon, so its step count is the number of τ-steps that
//! horizon needs), `METHOD@sem` (the searches and the long run over the first step) and
//! `METHOD@step` (step doubling at tol = [`StressOptions::tolerance`] over the same horizon,
//! no step limits: it chooses its steps).
//!
//! Every option is checked before anything runs ([`StressOptions::check`]).
//!
//! The ladder assumes the set of bounded steps is an interval starting at 0; a method with
//! stability gaps (resonances) is reported at the first failure on the ladder.

mod case;
mod drift;
mod files;
mod options;
mod record;
mod search;

pub use case::stress;
pub use drift::{Drift, MIN_DRIFT_STEPS};
pub use files::{OUTPUT_FILES, plot, to_csv, to_markdown, windows_csv, write_outputs};
pub use options::{
    CASES, DEFAULT_BISECTIONS, DEFAULT_METHODS, DEFAULT_TOLERANCE, StressArgs, StressCase,
    StressOptions,
};
pub use record::StressRecord;
pub use search::Limit;

use crate::report::output::{self, OutputDirectory};
use crate::scene::SceneError;
use std::path::Path;

/// `svi stress` with the arguments `args`: [`execute`] on their options and output directory.
pub fn execute_args(args: &StressArgs) -> anyhow::Result<()> {
    execute(&args.options()?, &args.out_dir)
}

/// `svi stress`: run the cases of `options`, write `stress.md`, `stress.csv`, `windows.csv`
/// and `drift.svg` into `out_dir` (its files are created before the cases run) and print the
/// table.
pub fn execute(options: &StressOptions, out_dir: &Path) -> anyhow::Result<()> {
    options.check()?;
    let names = OUTPUT_FILES.map(String::from);
    let dir = OutputDirectory::create("--out-dir", out_dir, &names, &[])?;
    let records = stress(options)?;
    write_outputs(&records, dir)?;
    output::print(to_markdown(&records)).map_err(SceneError::from)?;
    output::warn(format_args!(
        "wrote stress.md, stress.csv, windows.csv and drift.svg to {}",
        out_dir.display()
    ));
    Ok(())
}
