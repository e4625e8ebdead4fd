//! A Lagrangian written as text against the same model written in Rust: one whole run of the
//! paper's Kepler scene (e = 0.5, h = 0.2, T = 2000, 10 000 steps; Li, Wu, Leok 2018,
//! Figs. 13–17) through [`Integrator::run_from_velocity`] with no observer, workspace and
//! initial Legendre map included, `kepler_T2000/<method>/<implementation>`:
//!
//! - methods `svi_7_6` (7 CGL points, 6 Gauss points: `svi:7/6` of the work–precision
//!   section, the case issue #35 names) and `svi_6_12` (6 CGL / 12 GL points, the paper's);
//! - `zoo`: `svi_models::Kepler`;
//! - `text`: `0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)` with μ = 1, the scene
//!   `experiments/scenes/kepler-text.toml`, as a `TextLagrangian<U2>` (autonomous, unforced,
//!   constant mass);
//! - `text_run_time`: the same as the `TextLagrangian<Dyn>` that `svi run` dispatches to.
//!
//! Issue #20 asked for the text run within 3× the zoo's, issue #35 within 1.5× (SVI 7/6).
//! Run with `cargo bench --bench text -- kepler_T2000`; the medians are in
//! `target/criterion/kepler_T2000/<method>/<implementation>/new/estimates.json`.
//!
//! # `fput_chain/<method>/<implementation>`, n = 10⁵
//!
//! The FPUT chain (α = 0.25, β = 0.5, fixed ends) from its mode-1 state, `STEPS` = 20 steps
//! of h = 0.1 per measured unit, without the set-up (a run of 21 steps less a run of one):
//! `zoo` is `svi_models::Fput`, `text` the one-line sum of `experiments/scenes/fput-text.toml` as the
//! `TextChain<2, false, true>` that `svi run` dispatches to; methods `verlet` (explicit) and
//! `svi` (6/12, the Hessian-free fixed point). Issue #35 asks for the text chain within 1.3×
//! the zoo's time per step. `fput_chain_setup/<implementation>` times the set-up (a run of
//! one Verlet step: workspace, initial momenta, mass matrix), `fput_chain_force/…` ∂L/∂q
//! and L alone.

use nalgebra::{DVector, SVector, U2};
use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use svi::model::local::{LocalDefaults, LocalLagrangian, Terms};
use svi::model::text::{TextChain, TextChainModel, TextLagrangian, TextModel, TextSpec};
use svi::{Dyn, Initial, Integrator, Lagrangian, Method, StormerVerlet, Svi};
use svi_models::{Fput, Kepler};

/// One run of the scene with `model` and `method`; its final q.
fn run<L: Lagrangian<U2>>(model: L, method: Svi) -> SVector<f64, 2> {
    let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
    Integrator::new(model, method)
        .run_from_velocity(0.0, q, v, 0.2, 2000.0, &mut ())
        .expect("the Kepler scene runs")
        .last
        .q
}

/// The same run at run-time size, as `svi run` takes a text model.
fn run_run_time<L: Lagrangian<Dyn>>(model: L, method: Svi) -> DVector<f64> {
    let q = DVector::from_column_slice(&[0.5, 0.0]);
    let v = DVector::from_column_slice(&[0.0, 3f64.sqrt()]);
    Integrator::new(model, method)
        .run_from_velocity(0.0, q, v, 0.2, 2000.0, &mut ())
        .expect("the Kepler scene runs")
        .last
        .q
}

fn kepler(c: &mut Criterion) {
    let spec = TextSpec {
        lagrangian: "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)".into(),
        coordinates: vec!["x".into(), "y".into()],
        parameters: vec![("mu".into(), 1.0)],
        ..TextSpec::default()
    };
    let text = TextLagrangian::<U2, false, false, true>::new(TextModel::new(&spec).unwrap())
        .expect("Kepler is autonomous, unforced and constant-mass");
    let mut group = c.benchmark_group("kepler_T2000");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let run_time = TextLagrangian::<Dyn, false, false, true>::new(text.model().clone())
        .expect("the same declarations at run-time size");
    let methods = [
        ("svi_7_6", Svi::new(7).with_quadrature(6)),
        ("svi_6_12", Svi::new(6)),
    ];
    for (name, method) in methods {
        group.bench_function(format!("{name}/zoo"), |b| {
            b.iter(|| black_box(run(Kepler::default(), method.clone())))
        });
        group.bench_function(format!("{name}/text"), |b| {
            b.iter(|| black_box(run(text.clone(), method.clone())))
        });
        group.bench_function(format!("{name}/text_run_time"), |b| {
            b.iter(|| black_box(run_run_time(run_time.clone(), method.clone())))
        });
    }
    group.finish();
}

/// Steps per measured unit of `fput_chain`.
const STEPS: usize = 20;

/// The FPUT chain of n particles written as one line of text (α = 0.25, β = 0.5).
fn fput_text(n: usize) -> TextChain<2, false, true> {
    let spec = TextSpec {
        lagrangian: "sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1]-q[i])^2 \
                     + alpha/3*(q[i+1]-q[i])^3 + beta/4*(q[i+1]-q[i])^4)"
            .into(),
        coordinates: vec!["q[1..n]".into()],
        parameters: vec![
            ("n".into(), n as f64),
            ("alpha".into(), 0.25),
            ("beta".into(), 0.5),
        ],
        ..TextSpec::default()
    };
    TextChain::new(TextChainModel::new(&spec).unwrap()).expect("FPUT is a constant-mass chain")
}

/// The time of a run of `steps` steps of h = 0.1 of `method` on `model` from `initial`.
fn run_chain<L: LocalLagrangian + Clone, M: Method<Dyn> + Clone>(
    model: &L,
    method: &M,
    initial: &Initial<Dyn>,
    steps: usize,
) -> Duration {
    let start = Instant::now();
    let run = Integrator::new(Terms(model.clone()), method.clone())
        .run(0.0, initial.clone(), 0.1, 0.1 * steps as f64, &mut ())
        .expect("the FPUT chain runs");
    black_box(run.last.q);
    start.elapsed()
}

/// `iterations` times `STEPS` steps without the set-up: a run of 1 + `STEPS` steps less a
/// run of one step (workspace, mass matrix, initial Legendre map and one step).
fn steps_only<L: LocalLagrangian + Clone, M: Method<Dyn> + Clone>(
    model: &L,
    method: &M,
    initial: &Initial<Dyn>,
    iterations: u64,
) -> Duration {
    let mut seconds = 0.0;
    for _ in 0..iterations {
        let one = run_chain(model, method, initial, 1);
        let many = run_chain(model, method, initial, 1 + STEPS);
        seconds += many.as_secs_f64() - one.as_secs_f64();
    }
    Duration::from_secs_f64(seconds.max(0.0))
}

fn chain(c: &mut Criterion) {
    let n = 100_000;
    let text = fput_text(n);
    let mut zoo = Fput::default();
    zoo.set_parameter("n", n as f64).unwrap();
    zoo.set_parameter("beta", 0.5).unwrap();
    let (_, q, v) = zoo.initial_state();
    let initial = Initial::Velocity { q, v };
    let mut group = c.benchmark_group("fput_chain");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10));
    let verlet = StormerVerlet::default();
    let svi = Svi::new(6);
    group.bench_function("verlet/zoo", |b| {
        b.iter_custom(|iterations| steps_only(&zoo, &verlet, &initial, iterations))
    });
    group.bench_function("verlet/text", |b| {
        b.iter_custom(|iterations| steps_only(&text, &verlet, &initial, iterations))
    });
    group.bench_function("svi/zoo", |b| {
        b.iter_custom(|iterations| steps_only(&zoo, &svi, &initial, iterations))
    });
    group.bench_function("svi/text", |b| {
        b.iter_custom(|iterations| steps_only(&text, &svi, &initial, iterations))
    });
    group.finish();
    let mut group = c.benchmark_group("fput_chain_setup");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("zoo", |b| {
        b.iter_custom(|iterations| {
            (0..iterations)
                .map(|_| run_chain(&zoo, &verlet, &initial, 1))
                .sum()
        })
    });
    group.bench_function("text", |b| {
        b.iter_custom(|iterations| {
            (0..iterations)
                .map(|_| run_chain(&text, &verlet, &initial, 1))
                .sum()
        })
    });
    group.finish();
    let mut group = c.benchmark_group("fput_chain_force");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let Initial::Velocity { q, v } = &initial else {
        unreachable!("a state with velocities")
    };
    let mut out = DVector::zeros(n);
    group.bench_function("zoo", |b| {
        b.iter(|| zoo.force_into(0.0, black_box(q), v, &mut out))
    });
    group.bench_function("text", |b| {
        b.iter(|| text.force_into(0.0, black_box(q), v, &mut out))
    });
    group.bench_function("zoo_value", |b| b.iter(|| zoo.value(0.0, black_box(q), v)));
    group.bench_function("text_value", |b| {
        b.iter(|| text.value(0.0, black_box(q), v))
    });
    group.finish();
}

criterion_group!(benches, kepler, chain);
criterion_main!(benches);
