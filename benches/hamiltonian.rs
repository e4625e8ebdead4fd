//! Hamiltonian methods against their Lagrangian twins (issue #39).
//!
//! # `hamiltonian/kepler_T2000/<method>`: one whole run
//!
//! Kepler, e = 0.5, T = 2000 with 13953 steps (h = 2000/13953, the configuration at which
//! SVI 7/6 ends near 6e-10): `svi_7cgl_6gl` is [`Svi`] on [`Kepler`] written as L,
//! `svi_h_7cgl_6gl` is [`HamiltonianGalerkin`] on [`KeplerH`] (the same system written as
//! H = |p|²/2 − 1/|q|, a quadratic kinetic energy: SVI's fixed point with the force −∂H/∂q by
//! automatic differentiation of H). The final position error against Kepler's equation is
//! printed to stderr before timing.
//!
//! # `hamiltonian/magnetic_bottle/<method>`: one step of a non-separable H
//!
//! The magnetic bottle's default scene (a general H = |p − eA(x)|²/(2m)): `svi_h_4cgl_3gl` is
//! the Galerkin Hamiltonian integrator's Newton path on H's Hessian blocks, `svi_4cgl_3gl`
//! SVI on the same model's Lagrangian (the adapter's Legendre transform by chord steps in dual
//! numbers), and `midpoint_h` the implicit midpoint rule on Hamilton's equations. Each is timed
//! per step (mean over whole runs of 2000 steps from the default state).
//!
//! Run with `cargo bench --bench hamiltonian`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;
use svi::method::hamiltonian::{HamiltonianGalerkin, ImplicitMidpoint};
use svi::{Canonical, Defaults, ExactSolution, Initial, Integrator, Method, Svi};
use svi_models::{Kepler, KeplerH, MagneticBottle};

const T_END: f64 = 2000.0;
const STEPS: usize = 13953;

/// Time whole Kepler runs of `method` on `model`, after printing their final error.
fn kepler_run<L, M>(
    c: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    model: L,
    method: M,
) where
    L: svi::Lagrangian<nalgebra::U2> + Defaults<nalgebra::U2> + ExactSolution<nalgebra::U2>,
    M: Method<nalgebra::U2> + Clone,
{
    let (t0, q0, v0) = model.initial_state();
    let h = (T_END - t0) / STEPS as f64;
    let (exact, _) = model
        .exact_solution(t0, &q0, &v0, T_END)
        .expect("bound orbit");
    let integrator = Integrator::new(model, method);
    let run = integrator
        .run_from_velocity(t0, q0, v0, h, T_END, &mut ())
        .unwrap_or_else(|error| panic!("{id}: {error}"));
    eprintln!(
        "{id}: {} steps, final position error {:.2e}",
        run.statistics.steps,
        (run.last.q - exact).norm()
    );
    c.bench_function(id, |b| {
        b.iter(|| {
            integrator.run_from_velocity(
                black_box(t0),
                black_box(q0),
                black_box(v0),
                h,
                T_END,
                &mut (),
            )
        })
    });
}

fn kepler(c: &mut Criterion) {
    let mut group = c.benchmark_group("hamiltonian/kepler_T2000");
    group.sample_size(10);
    kepler_run(
        &mut group,
        "svi_7cgl_6gl",
        Kepler::default(),
        Svi::new(7).with_quadrature(6),
    );
    kepler_run(
        &mut group,
        "svi_h_7cgl_6gl",
        Canonical::new(KeplerH::default()),
        HamiltonianGalerkin::new(7).with_quadrature(6),
    );
    group.finish();
}

/// Time 2000-step runs of `method` on the magnetic bottle from its default state.
fn bottle_run<M: Method<nalgebra::U3> + Clone>(
    c: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    method: M,
) {
    let model = Canonical::new(MagneticBottle::default());
    let (t0, q0, v0) = model.initial_state();
    let h = model.default_step();
    let t_end = t0 + 2000.0 * h;
    let integrator = Integrator::new(model, method);
    let initial = Initial::Velocity { q: q0, v: v0 };
    let run = integrator
        .run(t0, initial, h, t_end, &mut ())
        .unwrap_or_else(|error| panic!("{id}: {error}"));
    eprintln!(
        "{id}: {} steps, {} iterations, {} factorisations",
        run.statistics.steps, run.statistics.iterations, run.statistics.factorizations
    );
    c.bench_function(id, |b| {
        b.iter(|| integrator.run(t0, black_box(initial), h, t_end, &mut ()))
    });
}

fn magnetic_bottle(c: &mut Criterion) {
    let mut group = c.benchmark_group("hamiltonian/magnetic_bottle");
    group.sample_size(10);
    bottle_run(
        &mut group,
        "svi_h_4cgl_3gl",
        HamiltonianGalerkin::new(4).with_quadrature(3),
    );
    bottle_run(&mut group, "svi_4cgl_3gl", Svi::new(4).with_quadrature(3));
    bottle_run(&mut group, "midpoint_h", ImplicitMidpoint::default());
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    targets = kepler, magnetic_bottle
}
criterion_main!(benches);
