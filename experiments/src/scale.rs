//! `svi scale`: time per step against the number of degrees of freedom n, for the methods of
//! runtime-dimension models (sums of local terms), with a fitted exponent and the peak memory.
//!
//! Configurations (fixed, one per solver path):
//! - `svi:6/5` on the FPUT chain (α = 0.25, β = 0.5; constant mass: the Hessian-free fixed
//!   point), h = 0.1;
//! - `verlet` on the same chain (explicit kick–drift–kick), h = 0.1;
//! - `svi:4/3` on the relativistic chain (velocity-dependent mass: sparse Newton, faer's LU,
//!   simplified across iterations and steps), h = 0.1.
//!
//! For each n the run of 2K steps and the run of K steps are timed (the median of `batches`
//! runs each; K doubled from `--steps` until the longer run lasts 0.2 s) and their difference
//! divided by K is the cost of a step, free of the set-up (workspace, symbolic analysis, the
//! first factorisation). The exponent is the
//! least-squares slope of log(time per step) against log n. The peak resident memory of the
//! process (getrusage) is read after each size; sizes run in ascending order, so the figure
//! after the largest size is that size's peak. Writes `scale.csv` and `scale.svg` to
//! `--out-dir`.

use crate::report::csv::Float;
use crate::report::output::{self, OutputDirectory};
use crate::report::plot::{Panel, Series, render_svg};
use crate::scene::SceneError;
use crate::scene::limits;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;
use svi::model::local::{LocalDefaults, LocalLagrangian, Terms};
use svi::{Dyn, Error, Integrator, Method, StormerVerlet, Svi};
use svi_models::{Fput, RelativisticChain};

/// The largest n `svi scale` takes (a relativistic chain of 10⁶ needs about 5 GB in Newton's
/// factors).
pub const MAX_SIZE: usize = 1_000_000;

/// The smallest n.
pub const MIN_SIZE: usize = 10;

/// The most sizes of one call.
pub const MAX_SIZES: usize = 100;

/// The largest K (`--steps`, and where the doubling stops).
pub const MAX_STEPS: usize = 1 << 20;

/// The most timed runs of each length.
pub const MAX_BATCHES: usize = 100;

/// The longest `--min-run`, in seconds.
pub const MAX_MIN_RUN: f64 = 60.0;

/// The longest a call may be estimated to take, in seconds ([`ScaleArgs::estimated_seconds`]):
/// one hour.
pub const MAX_ESTIMATED_SECONDS: f64 = 3600.0;

/// Seconds per step and degree of freedom of the three configurations (`svi:6/5` and
/// `verlet` on FPUT, `svi:4/3` on the relativistic chain), measured on a 2-core machine at
/// n = 10⁵ (`benches/results/scale.csv`, 2026-11-24): the basis of the estimate.
const SECONDS_PER_DOF_STEP: [f64; 3] = [1.3e-7, 1.6e-8, 5.6e-7];

/// The help of `--sizes`, from the limits above.
fn sizes_help() -> String {
    format!(
        "Numbers of particles n, comma-separated, each {MIN_SIZE} to {MAX_SIZE} (at most \
         {MAX_SIZES} sizes)"
    )
}

/// The help of `--steps`.
fn steps_help() -> String {
    format!(
        "K: the timed runs take K and 2K steps (1 to {MAX_STEPS}), K doubled (up to \
         {MAX_STEPS}) until the longer run lasts --min-run"
    )
}

/// The help of `--batches`.
fn batches_help() -> String {
    format!("Timed runs of each length; the median is used (1 to {MAX_BATCHES})")
}

/// The help of `--min-run`.
fn min_run_help() -> String {
    format!(
        "K doubles until the run of 2K steps lasts this many seconds (0 to {MAX_MIN_RUN}); a \
         call estimated to take more than {} s in all is refused with its estimate",
        MAX_ESTIMATED_SECONDS
    )
}

/// The arguments of `svi scale`.
#[derive(Debug, Clone, clap::Args)]
pub struct ScaleArgs {
    /// Numbers of particles n, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,3162,10000,31623,100000",
        help = sizes_help()
    )]
    pub sizes: Vec<usize>,
    /// K: the timed runs take K and 2K steps.
    #[arg(long, default_value_t = 10, help = steps_help())]
    pub steps: usize,
    /// Timed runs of each length.
    #[arg(long, default_value_t = 3, help = batches_help())]
    pub batches: usize,
    /// K doubles until the run of 2K steps lasts this many seconds.
    #[arg(long, default_value_t = 0.2, allow_hyphen_values = true, help = min_run_help())]
    pub min_run: f64,
    /// Where `scale.csv` and `scale.svg` are written.
    #[arg(long, default_value = "benches/results")]
    pub out_dir: String,
}

/// One measured configuration at one size.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// The method as given (`svi:6/5`).
    pub method: &'static str,
    /// The model's name.
    pub model: &'static str,
    /// Degrees of freedom.
    pub n: usize,
    /// Seconds per step (set-up excluded).
    pub seconds_per_step: f64,
    /// Nonlinear iterations per step.
    pub iterations_per_step: f64,
    /// The process's peak resident memory after this size, in MB.
    pub peak_memory_mb: f64,
}

impl ScaleArgs {
    /// Check every option before anything runs: each in its range, and the whole call
    /// estimated at most [`MAX_ESTIMATED_SECONDS`].
    pub fn check(&self) -> Result<(), SceneError> {
        if self.sizes.is_empty() {
            return Err(SceneError::InvalidOption {
                option: "--sizes",
                reason: "no size; give at least one".into(),
            });
        }
        limits::count("--sizes", self.sizes.len(), 1, MAX_SIZES, "sizes")?;
        for &n in &self.sizes {
            limits::count("--sizes", n, MIN_SIZE, MAX_SIZE, "particles")?;
        }
        limits::count("--steps", self.steps, 1, MAX_STEPS, "steps")?;
        limits::count("--batches", self.batches, 1, MAX_BATCHES, "batches")?;
        limits::seconds("--min-run", self.min_run, true, MAX_MIN_RUN)?;
        let estimate = self.estimated_seconds();
        if estimate > MAX_ESTIMATED_SECONDS {
            return Err(SceneError::InvalidOption {
                option: "the call (--sizes, --steps, --batches, --min-run together)",
                reason: format!(
                    "the measurements would take about {:.0} s on a 2-core machine, more than \
                     the {MAX_ESTIMATED_SECONDS} s svi scale runs; take fewer or smaller sizes, \
                     fewer steps or batches, or a shorter --min-run",
                    estimate
                ),
            });
        }
        Ok(())
    }

    /// The estimated duration of the call, in seconds: for every size and configuration,
    /// `batches` runs of K and 2K steps for each K doubled from `--steps` until the longer
    /// run lasts `--min-run` (about 6·K·c·n or 3·min_run per batch, whichever is larger, with
    /// c the configuration's measured cost per degree of freedom and step).
    pub fn estimated_seconds(&self) -> f64 {
        let batches = self.batches as f64;
        self.sizes
            .iter()
            .flat_map(|&n| {
                SECONDS_PER_DOF_STEP.map(|cost| {
                    let first = 6.0 * self.steps as f64 * cost * n as f64;
                    batches * first.max(3.0 * self.min_run)
                })
            })
            .sum()
    }
}

/// The median of `batches` timings of a run of `steps` steps: (seconds, iterations).
fn time_run<L: LocalLagrangian + LocalDefaults + Clone, M: Method<Dyn> + Clone>(
    model: &L,
    method: &M,
    steps: usize,
    batches: usize,
) -> Result<(f64, usize), Error> {
    let (t0, q, v) = model.initial_state();
    let h = 0.1;
    let integrator = Integrator::new(Terms(model.clone()), method.clone());
    let mut times = Vec::with_capacity(batches);
    let mut iterations = 0;
    for _ in 0..batches {
        let (q, v) = (q.clone(), v.clone());
        let start = Instant::now();
        let run = integrator.run_from_velocity(t0, q, v, h, t0 + steps as f64 * h, &mut ())?;
        times.push(start.elapsed().as_secs_f64());
        iterations = run.statistics.iterations;
    }
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], iterations))
}

/// The process's peak resident memory in MB.
fn peak_memory_mb() -> f64 {
    // SAFETY: getrusage writes the struct it is given; RUSAGE_SELF is always valid.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let status = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    if status == 0 {
        usage.ru_maxrss as f64 / 1024.0
    } else {
        f64::NAN
    }
}

/// Measure one configuration at size n.
fn measure<L: LocalLagrangian + LocalDefaults + Clone, M: Method<Dyn> + Clone>(
    method_name: &'static str,
    mut model: L,
    method: M,
    n: usize,
    args: &ScaleArgs,
) -> Result<Measurement, Error> {
    model.set_parameter("n", n as f64)?;
    // K doubles until the run of 2K steps lasts `min_run`: cheap steps need many to stand out
    // of the set-up and the clock's noise.
    let mut k = args.steps;
    let (short, short_iterations, long, long_iterations) = loop {
        let (short, short_iterations) = time_run(&model, &method, k, args.batches)?;
        let (long, long_iterations) = time_run(&model, &method, 2 * k, args.batches)?;
        if long >= args.min_run || k >= MAX_STEPS {
            break (short, short_iterations, long, long_iterations);
        }
        k *= 2;
    };
    Ok(Measurement {
        method: method_name,
        model: model.name(),
        n,
        seconds_per_step: ((long - short) / k as f64).max(0.0),
        iterations_per_step: (long_iterations - short_iterations) as f64 / k as f64,
        peak_memory_mb: peak_memory_mb(),
    })
}

/// The least-squares slope of log y against log x.
pub fn fitted_exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let count = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / count, b + y / count));
    let (sxy, sxx) = logs.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    sxy / sxx
}

/// Run every configuration at every size.
pub fn scale(args: &ScaleArgs) -> Result<Vec<Measurement>, SceneError> {
    args.check()?;
    let mut sizes = args.sizes.clone();
    sizes.sort_unstable();
    let mut fput = Fput::default();
    fput.set_parameter("beta", 0.5)?;
    let mut measurements = Vec::new();
    for &n in &sizes {
        let svi = Svi::new(6).with_quadrature(5);
        measurements.push(measure("svi:6/5", fput.clone(), svi, n, args)?);
        measurements.push(measure(
            "verlet",
            fput.clone(),
            StormerVerlet::default(),
            n,
            args,
        )?);
        let newton = Svi::new(4).with_quadrature(3);
        measurements.push(measure(
            "svi:4/3",
            RelativisticChain::default(),
            newton,
            n,
            args,
        )?);
    }
    Ok(measurements)
}

/// `svi scale`: measure, print a table with the fitted exponents, write CSV and SVG (the
/// output directory and its files are created before the measurements).
pub fn execute_args(args: &ScaleArgs) -> anyhow::Result<()> {
    args.check()?;
    let directory = Path::new(&args.out_dir);
    let names = ["scale.csv".to_string(), "scale.svg".to_string()];
    let mut dir =
        OutputDirectory::create("--out-dir", directory, &names, &[]).map_err(SceneError::from)?;
    let measurements = scale(args)?;
    let mut csv =
        String::from("method,model,n,seconds_per_step,iterations_per_step,peak_memory_mb\n");
    for m in &measurements {
        writeln!(
            csv,
            "{},{},{},{},{},{}",
            m.method,
            m.model,
            m.n,
            Float(m.seconds_per_step),
            Float(m.iterations_per_step),
            Float(m.peak_memory_mb)
        )?;
    }
    let mut series = Vec::new();
    let mut table =
        String::from("method    model               n  seconds/step  iterations/step  peak MB\n");
    for method in ["svi:6/5", "verlet", "svi:4/3"] {
        let rows: Vec<&Measurement> = measurements.iter().filter(|m| m.method == method).collect();
        for m in &rows {
            writeln!(
                table,
                "{:<9} {:<18} {:>7}  {:>12.3e}  {:>15.2}  {:>7.0}",
                m.method, m.model, m.n, m.seconds_per_step, m.iterations_per_step, m.peak_memory_mb
            )?;
        }
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|m| (m.n as f64, m.seconds_per_step))
            .collect();
        if points.len() > 1 {
            writeln!(
                table,
                "{method}: time per step ∝ n^{:.3}",
                fitted_exponent(&points)
            )?;
        }
        series.push(Series {
            label: format!("{method} ({})", rows.first().map_or("", |m| m.model)),
            points,
        });
    }
    let panel = Panel {
        title: "Time per step against degrees of freedom".into(),
        x_label: "n".into(),
        y_label: "seconds per step".into(),
        x_log: true,
        y_log: true,
        equal_scale: false,
        scatter: false,
        series,
    };
    dir.write("scale.csv", csv.as_bytes())
        .map_err(SceneError::from)?;
    dir.write("scale.svg", render_svg(&[panel], 640, 480)?.as_bytes())
        .map_err(SceneError::from)?;
    dir.commit().map_err(SceneError::from)?;
    writeln!(
        table,
        "wrote {} and {}",
        directory.join("scale.csv").display(),
        directory.join("scale.svg").display()
    )?;
    output::print(table).map_err(SceneError::from)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exponent_of_a_power_law_is_recovered() {
        let points: Vec<(f64, f64)> = [1e3f64, 1e4, 1e5]
            .iter()
            .map(|n| (*n, 3e-9 * n.powf(1.07)))
            .collect();
        assert!((fitted_exponent(&points) - 1.07).abs() < 1e-12);
    }

    #[test]
    fn every_option_is_checked() {
        let good = ScaleArgs {
            sizes: vec![100],
            steps: 2,
            batches: 1,
            min_run: 0.0,
            out_dir: "x".into(),
        };
        assert!(good.check().is_ok());
        for (bad, name) in [
            (
                ScaleArgs {
                    sizes: vec![],
                    ..good.clone()
                },
                "sizes",
            ),
            (
                ScaleArgs {
                    sizes: vec![5],
                    ..good.clone()
                },
                "sizes",
            ),
            (
                ScaleArgs {
                    steps: 0,
                    ..good.clone()
                },
                "steps",
            ),
            (
                ScaleArgs {
                    batches: 0,
                    ..good.clone()
                },
                "batches",
            ),
        ] {
            assert!(bad.check().unwrap_err().to_string().contains(name));
        }
    }
}
