//! Large systems: a run of the FPUT chain by svi's Störmer–Verlet, derived from the chain's
//! Lagrangian term by term, against a hand-written Verlet loop over the same force.
//!
//! # `chain/verlet/<implementation>/<n>`, n ∈ {10³, 10⁴}
//!
//! - `svi`: [`Integrator::run`] of [`StormerVerlet`] on `Terms(`[`svi_models::Fput`]`)`
//!   (α = 0.25, β = 0.5; the chain as a run-time-size [`svi::Lagrangian`] whose derivatives
//!   are assembled term by term), no observer: ∂L/∂q assembled from the spring terms by
//!   automatic differentiation, the stepping loop's compensated summation included;
//! - `hand_written`: kick–drift–kick with the force F_i = V'(q_{i+1} − q_i) − V'(q_i − q_{i−1})
//!   written by hand, one force evaluation per step, plain summation (what a user writes
//!   without a library).
//!
//! # `chain_svi/svi/10⁴`
//!
//! Ten steps (h = 0.2) of SVI's fixed point with 6 CGL points on `Terms(Fput)`.
//!
//! # `chain_svi_newton/svi/10³`
//!
//! Ten steps (h = 0.1) of SVI by sparse Newton with 6 CGL points on the relativistic
//! chain (a mass matrix that depends on q̇).
//!
//! # `chain_force/<implementation>/10⁴`
//!
//! The force ∂L/∂q alone at the default state: svi's term-by-term assembly
//! (`LocalLagrangian::force_into`, by default term by term) against the hand-written loop.
//!
//! Each measured unit of `chain_verlet` is 100 steps of h = 0.1 from the default (mode 1) state; both end at
//! the same state to 1e-12 (checked before timing). Run with `cargo bench --bench chain`;
//! medians in `target/criterion/chain_verlet/<implementation>/<n>/new/estimates.json`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::DVector;
use std::hint::black_box;
use std::time::Duration;
use svi::model::local::{LocalDefaults, LocalLagrangian, Terms};
use svi::{Integrator, StormerVerlet, Svi};
use svi_models::{Fput, RelativisticChain};

const STEPS: usize = 100;
const H: f64 = 0.1;

fn model(n: usize) -> Fput {
    let mut model = Fput::default();
    model.set_parameter("n", n as f64).unwrap();
    model.set_parameter("beta", 0.5).unwrap();
    model
}

/// V'(r) = r + α r² + β r³.
#[inline]
fn spring_force(model: &Fput, r: f64) -> f64 {
    r + model.alpha * r * r + model.beta * r * r * r
}

/// ∂L/∂q of the chain with fixed ends.
fn force(model: &Fput, q: &[f64], out: &mut [f64]) {
    let n = q.len();
    let mut left = spring_force(model, q[0]);
    for i in 0..n {
        let right = if i + 1 < n {
            spring_force(model, q[i + 1] - q[i])
        } else {
            spring_force(model, -q[i])
        };
        out[i] = right - left;
        left = right;
    }
}

/// The hand-written kick–drift–kick loop.
fn hand_written(model: &Fput, q: &mut [f64], p: &mut [f64], f: &mut [f64]) {
    force(model, q, f);
    for _ in 0..STEPS {
        for i in 0..q.len() {
            p[i] += 0.5 * H * f[i];
            q[i] += H * p[i];
        }
        force(model, q, f);
        for i in 0..q.len() {
            p[i] += 0.5 * H * f[i];
        }
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("chain_verlet");
    group
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20);
    for n in [1_000, 10_000] {
        let model = model(n);
        let (t0, q0, v0) = model.initial_state();
        let integrator = Integrator::new(Terms(model.clone()), StormerVerlet::default());
        let t_end = t0 + STEPS as f64 * H;
        let run = integrator
            .run_from_velocity(t0, q0.clone(), v0.clone(), H, t_end, &mut ())
            .unwrap();
        let (mut q, mut p, mut f) = (q0.as_slice().to_vec(), v0.as_slice().to_vec(), vec![0.0; n]);
        hand_written(&model, &mut q, &mut p, &mut f);
        let difference = (run.last.q - DVector::from_vec(q)).amax();
        assert!(
            difference < 1e-12,
            "svi and the hand-written loop differ by {difference:e}"
        );
        group.bench_function(BenchmarkId::new("svi", n), |b| {
            b.iter(|| {
                black_box(
                    integrator
                        .run_from_velocity(t0, q0.clone(), v0.clone(), H, t_end, &mut ())
                        .unwrap(),
                )
            })
        });
        group.bench_function(BenchmarkId::new("hand_written", n), |b| {
            b.iter(|| {
                let (mut q, mut p) = (q0.as_slice().to_vec(), v0.as_slice().to_vec());
                hand_written(&model, &mut q, &mut p, &mut f);
                black_box((q, p))
            })
        });
    }
    group.finish();

    // SVI's fixed point (6 CGL points, 12 Gauss points), 10 steps of h = 0.2 on FPUT at
    // n = 10⁴, and SVI by sparse Newton (6 CGL points), 10 steps of h = 0.1 on the
    // relativistic chain at n = 10³.
    svi_on_terms(c, "chain_svi", model(10_000), 0.2);
    let mut chain = RelativisticChain::default();
    chain.set_parameter("n", 1000.0).unwrap();
    svi_on_terms(c, "chain_svi_newton", chain, 0.1);

    // The force alone: ∂L/∂q assembled term by term by AD against the hand-written force.
    let mut group = c.benchmark_group("chain_force");
    group
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(300))
        .sample_size(20);
    let n = 10_000;
    let model = model(n);
    let (t0, q0, v0) = model.initial_state();
    let mut out = DVector::zeros(n);
    group.bench_function(BenchmarkId::new("svi", n), |b| {
        b.iter(|| model.force_into(t0, black_box(&q0), &v0, &mut out))
    });
    let mut f = vec![0.0; n];
    group.bench_function(BenchmarkId::new("hand_written", n), |b| {
        b.iter(|| force(&model, black_box(q0.as_slice()), &mut f))
    });
    group.finish();
}

/// `<name>/svi/<n>`: 10 steps of size `h` of SVI with 6 CGL points on `Terms(chain)`.
fn svi_on_terms<L: LocalLagrangian + LocalDefaults + Clone>(
    c: &mut Criterion,
    name: &str,
    chain: L,
    h: f64,
) {
    let mut group = c.benchmark_group(name);
    group
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20);
    let n = chain.dimension();
    let (t0, q0, v0) = chain.initial_state();
    let t_end = t0 + 10.0 * h;
    let integrator = Integrator::new(Terms(chain), Svi::new(6));
    group.bench_function(BenchmarkId::new("svi", n), |b| {
        b.iter(|| {
            black_box(
                integrator
                    .run_from_velocity(t0, q0.clone(), v0.clone(), h, t_end, &mut ())
                    .unwrap(),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
