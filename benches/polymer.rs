//! The polymer chain with rigid bonds: time per RATTLE step against the number of beads, and
//! the fitted exponent of time ∝ nᵖ (issue #37: p ≤ 1.15 from 10² to 10⁴ beads).
//!
//! # `polymer_rattle/step/<n>`, n ∈ {10², 10³, 10⁴}
//!
//! One step of RATTLE (h = 0.01) on [`svi_models::Polymer`] with n beads (3n coordinates,
//! n − 1 bonds as [`SparseConstraints`], bending springs, no gravity) from its default state
//! (a moving helix): the sparse path — G stored row by row, Newton on the multipliers and the
//! velocity projection by faer's sparse LU. Each sample times a run of [`STEPS`] steps and a
//! run of none from the same state and reports the difference over [`STEPS`]: the time of a
//! step, without the set-up of a run (mass matrix, projection of the initial data, rank check,
//! pattern and symbolic analysis, all O(n) too). Times are the thread's CPU time, not the
//! wall clock: on a shared machine (CI's two cores, builds beside the bench) the wall clock
//! also counts the time other processes hold the core, up to twice the step's own.
//!
//! After the three sizes the bench prints the median time per step of each, its Newton
//! iterations a step (they fall with n: the stopping rule is relative to |q|∞, which grows
//! with the helix's length), and the least-squares slope of log time against log n, per step
//! and per factorisation (a step factors one matrix per Newton iteration and one for the
//! velocity projection). Run with
//! `cargo bench --bench polymer`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::DVector;
use std::cell::RefCell;
use std::hint::black_box;
use std::time::Duration;
use svi::method::constrained::{ConstrainedIntegrator, Rattle};
use svi::model::constraint::local::SparseConstraints;
use svi::model::local::{LocalDefaults, Terms};
use svi_models::Polymer;
use svi_models::polymer::Bonds;

/// Steps of the timed run.
const STEPS: usize = 50;
const H: f64 = 0.01;

/// RATTLE on the polymer chain.
type Chain = ConstrainedIntegrator<Terms<Polymer>, SparseConstraints<Bonds>>;

/// The integrator and default state (q₀, p₀) of a chain of `n` beads.
fn setup(n: usize) -> (Chain, DVector<f64>, DVector<f64>) {
    let mut polymer = Polymer::default();
    polymer.set_parameter("n", n as f64).unwrap();
    let (_, q, v) = polymer.initial_state();
    let p = v * polymer.mass;
    let (terms, bonds) = polymer.constrained();
    let integrator = ConstrainedIntegrator::new(terms, bonds, Rattle::default()).unwrap();
    (integrator, q, p)
}

/// The CPU time this thread has used (`CLOCK_THREAD_CPUTIME_ID`).
fn thread_time() -> Duration {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid timespec for clock_gettime to write; the clock exists on Linux
    // (and a failure leaves zero, which the assertion below reports).
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    assert_eq!(status, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    Duration::new(now.tv_sec as u64, now.tv_nsec as u32)
}

/// The thread CPU time of a run of `steps` steps.
fn time_run(integrator: &Chain, q: &DVector<f64>, p: &DVector<f64>, steps: usize) -> Duration {
    let start = thread_time();
    let run = integrator.run(0.0, q, p, H, steps, |_| {}).unwrap();
    let elapsed = thread_time().saturating_sub(start);
    black_box(run);
    elapsed
}

/// The median of `values` (`None` when empty: a size the bench's filter left out).
fn median(values: &mut [f64]) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied()
}

/// The least-squares slope of log y against log x.
fn fitted_exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|(x, y)| (x.ln(), y.ln())).collect();
    let count = logs.len() as f64;
    let (mean_x, mean_y) = (
        logs.iter().map(|p| p.0).sum::<f64>() / count,
        logs.iter().map(|p| p.1).sum::<f64>() / count,
    );
    let covariance: f64 = logs.iter().map(|(x, y)| (x - mean_x) * (y - mean_y)).sum();
    let variance: f64 = logs.iter().map(|(x, _)| (x - mean_x).powi(2)).sum();
    covariance / variance
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("polymer_rattle");
    group
        .measurement_time(Duration::from_secs(6))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(10);
    let mut medians = Vec::new();
    for n in [100, 1_000, 10_000] {
        let (integrator, q, p) = setup(n);
        let run = integrator.run(0.0, &q, &p, H, STEPS, |_| {}).unwrap();
        assert!(run.constraint_error_max < 1e-10 && run.velocity_constraint_error_max < 1e-10);
        let iterations = run.iterations as f64 / STEPS as f64;
        let per_step = RefCell::new(Vec::new());
        group.bench_function(BenchmarkId::new("step", n), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let empty = time_run(&integrator, &q, &p, 0);
                    let full = time_run(&integrator, &q, &p, STEPS);
                    let step = full.saturating_sub(empty) / STEPS as u32;
                    per_step.borrow_mut().push(step.as_secs_f64());
                    total += step;
                }
                total
            })
        });
        if let Some(seconds) = median(&mut per_step.borrow_mut()) {
            medians.push((n as f64, seconds, iterations));
        }
    }
    group.finish();
    if medians.len() < 2 {
        return;
    }
    println!("\npolymer, RATTLE, time per step (median of every timed run):");
    for (n, seconds, iterations) in &medians {
        println!(
            "  n = {n:>6}: {:>9.1} µs  ({:.2} µs per bead, {iterations:.2} Newton iterations a step)",
            seconds * 1e6,
            seconds * 1e6 / n
        );
    }
    let per_step: Vec<(f64, f64)> = medians.iter().map(|&(n, s, _)| (n, s)).collect();
    // Each Newton iteration and the velocity projection factor one matrix.
    let per_factorisation: Vec<(f64, f64)> = medians
        .iter()
        .map(|&(n, s, iterations)| (n, s / (iterations + 1.0)))
        .collect();
    println!(
        "  fitted exponent (log-log least squares, time ∝ nᵖ): p = {:.3} per step, {:.3} per \
         factorisation",
        fitted_exponent(&per_step),
        fitted_exponent(&per_factorisation)
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
