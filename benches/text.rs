//! A Lagrangian written as text against the same model written in Rust: one whole run of the
//! paper's Kepler scene (e = 0.5, SVI with 6 CGL / 12 GL points, h = 0.2, T = 2000, 10 000
//! steps; Li, Wu, Leok 2018, Figs. 13–17) through [`Integrator::run_from_velocity`] with no
//! observer, workspace and initial Legendre map included.
//!
//! - `kepler_T2000/zoo`: `svi_models::Kepler`;
//! - `kepler_T2000/text`: `0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)` with μ = 1, the scene
//!   `cli/scenes/kepler-text.toml`, as the `TextLagrangian` that `svi run` dispatches to
//!   (autonomous, unforced, constant mass).
//!
//! Issue #20 asks for the text run within 3× the zoo's. Run with `cargo bench --bench text`;
//! the medians are in `target/criterion/kepler_T2000/{zoo,text}/new/estimates.json`.

use nalgebra::{SVector, U2};
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use svi::model::text::{TextLagrangian, TextModel, TextSpec};
use svi::{Integrator, Lagrangian, Svi};
use svi_models::Kepler;

/// One run of the scene with `model`; its final q.
fn run<L: Lagrangian<U2>>(model: L) -> SVector<f64, 2> {
    let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
    Integrator::new(model, Svi::new(6))
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
    group.bench_function("zoo", |b| b.iter(|| black_box(run(Kepler::default()))));
    group.bench_function("text", |b| b.iter(|| black_box(run(text.clone()))));
    group.finish();
}

criterion_group!(benches, kepler);
criterion_main!(benches);
