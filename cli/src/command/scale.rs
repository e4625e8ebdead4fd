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
use crate::report::plot::{Panel, Series, write_svg};
use crate::scene::SceneError;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;
use svi::method::DynInitial;
use svi::method::local::LocalMethod;
use svi::model::local::{LocalDefaults, LocalLagrangian};
use svi::{Error, Integrator, StormerVerlet, Svi};
use svi_models::{Fput, RelativisticChain};

/// The largest n `svi scale` takes (a relativistic chain of 10⁶ needs about 5 GB in Newton's
/// factors).
pub const MAX_SIZE: usize = 1_000_000;

/// The largest K.
const MAX_STEPS: usize = 1 << 20;

/// The arguments of `svi scale`.
#[derive(Debug, Clone, clap::Args)]
pub struct ScaleArgs {
    /// Numbers of particles n, comma-separated, each 10 to 10⁶.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,3162,10000,31623,100000"
    )]
    pub sizes: Vec<usize>,
    /// K: the timed runs take K and 2K steps (1 to 2²⁰), K doubled until the longer run
    /// lasts 0.2 s.
    #[arg(long, default_value_t = 10)]
    pub steps: usize,
    /// Timed runs of each length; the median is used (1 to 100).
    #[arg(long, default_value_t = 3)]
    pub batches: usize,
    /// K doubles until the run of 2K steps lasts this many seconds (0 to 60).
    #[arg(long, default_value_t = 0.2)]
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
    /// Check every option before anything runs.
    pub fn check(&self) -> Result<(), SceneError> {
        let bad = |name: &str, reason: String| SceneError::Svi(Error::invalid(name, reason));
        if self.sizes.is_empty() {
            return Err(bad("sizes", "give at least one size".into()));
        }
        if let Some(n) = self.sizes.iter().find(|n| !(10..=MAX_SIZE).contains(*n)) {
            return Err(bad("sizes", format!("{n} is not from 10 to {MAX_SIZE}")));
        }
        if !(1..=10_000).contains(&self.steps) {
            return Err(bad(
                "steps",
                format!("{} is not from 1 to 10000", self.steps),
            ));
        }
        if !(1..=100).contains(&self.batches) {
            return Err(bad(
                "batches",
                format!("{} is not from 1 to 100", self.batches),
            ));
        }
        Ok(())
    }
}

/// The median of `batches` timings of a run of `steps` steps: (seconds, iterations).
fn time_run<L: LocalLagrangian + LocalDefaults + Clone, M: LocalMethod + Clone>(
    model: &L,
    method: &M,
    steps: usize,
    batches: usize,
) -> Result<(f64, usize), Error> {
    let (t0, q, v) = model.initial_state();
    let h = 0.1;
    let integrator = Integrator::new(model.clone(), method.clone());
    let mut times = Vec::with_capacity(batches);
    let mut iterations = 0;
    for _ in 0..batches {
        let initial = DynInitial::Velocity {
            q: q.clone(),
            v: v.clone(),
        };
        let start = Instant::now();
        let run = integrator.run(t0, initial, h, t0 + steps as f64 * h, &mut ())?;
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
fn measure<L: LocalLagrangian + LocalDefaults + Clone, M: LocalMethod + Clone>(
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

/// `svi scale`: measure, print a table with the fitted exponents, write CSV and SVG.
pub fn execute_args(args: &ScaleArgs) -> anyhow::Result<()> {
    let measurements = scale(args)?;
    let directory = Path::new(&args.out_dir);
    std::fs::create_dir_all(directory).map_err(|source| SceneError::Write {
        path: directory.to_path_buf(),
        source,
    })?;
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
    let csv_path = directory.join("scale.csv");
    std::fs::write(&csv_path, csv).map_err(|source| SceneError::Write {
        path: csv_path.clone(),
        source,
    })?;
    let mut series = Vec::new();
    println!("method    model               n  seconds/step  iterations/step  peak MB");
    for method in ["svi:6/5", "verlet", "svi:4/3"] {
        let rows: Vec<&Measurement> = measurements.iter().filter(|m| m.method == method).collect();
        for m in &rows {
            println!(
                "{:<9} {:<18} {:>7}  {:>12.3e}  {:>15.2}  {:>7.0}",
                m.method, m.model, m.n, m.seconds_per_step, m.iterations_per_step, m.peak_memory_mb
            );
        }
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|m| (m.n as f64, m.seconds_per_step))
            .collect();
        if points.len() > 1 {
            println!(
                "{method}: time per step ∝ n^{:.3}",
                fitted_exponent(&points)
            );
        }
        series.push(Series {
            label: format!("{method} ({})", rows.first().map_or("", |m| m.model)),
            points,
        });
    }
    let svg_path = directory.join("scale.svg");
    let panel = Panel {
        title: "Time per step against degrees of freedom".into(),
        x_label: "n".into(),
        y_label: "seconds per step".into(),
        x_log: true,
        y_log: true,
        series,
    };
    write_svg(&svg_path, &[panel], 640, 480)?;
    println!("wrote {} and {}", csv_path.display(), svg_path.display());
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

    #[test]
    fn a_small_measurement_runs_every_configuration() {
        let args = ScaleArgs {
            sizes: vec![50, 20],
            steps: 2,
            batches: 1,
            min_run: 0.0,
            out_dir: "unused".into(),
        };
        let measurements = scale(&args).unwrap();
        assert_eq!(measurements.len(), 6);
        assert_eq!((measurements[0].n, measurements[5].n), (20, 50));
        assert!(measurements.iter().all(|m| m.seconds_per_step.is_finite()));
        // The fixed point and Verlet need no Newton iteration of Verlet, SVI a few.
        assert_eq!(measurements[1].iterations_per_step, 0.0);
        assert!(measurements[2].iterations_per_step >= 1.0);
    }
}
