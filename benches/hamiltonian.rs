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
//! # `hamiltonian/relativistic_chain_n10000/<method>`: one step of a chain of 10⁴ particles
//!
//! [`RelativisticChain`] with n = 10⁴ (peak speed 0.8 c) from its default state, step 0.1:
//! `svi` is SVI with its default points on the Lagrangian (a kinetic energy that is not
//! quadratic: Newton's method with the sparse Hessian assembled term by term), `verlet_h` and
//! `kahan_li8_h` the explicit splitting of the same chain written as the separable
//! H = Σ c√(m²c² + pᵢ²) + V(q) ([`RelativisticChainH`] through [`LocalCanonical`]). Each is
//! timed per step (mean over runs of 10 steps); the gap between each final state and SVI's is
//! printed first.
//!
//! Run with `cargo bench --bench hamiltonian`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;
use svi::method::hamiltonian::{HamiltonianGalerkin, ImplicitMidpoint};
use svi::model::local::{LocalDefaults, Terms};
use svi::model::local_hamiltonian::LocalCanonical;
use svi::{Canonical, Defaults, ExactSolution, Initial, Integrator, Method, MethodSpec, Svi};
use svi_models::{Kepler, KeplerH, MagneticBottle, RelativisticChain, RelativisticChainH};

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

/// Steps per timed run of the chain.
const CHAIN_STEPS: usize = 10;

fn relativistic_chain(c: &mut Criterion) {
    let mut group = c.benchmark_group("hamiltonian/relativistic_chain_n10000");
    group.sample_size(10);
    let chain = RelativisticChain {
        n: 10_000,
        ..RelativisticChain::default()
    };
    let h = chain.default_step();
    let t_end = CHAIN_STEPS as f64 * h;
    let (t0, q0, v0) = chain.initial_state();
    let lagrangian = Integrator::new(Terms(chain.clone()), Svi::default());
    let reference = lagrangian
        .run_from_velocity(t0, q0.clone(), v0.clone(), h, t_end, &mut ())
        .expect("svi on the chain");
    eprintln!(
        "svi: {} steps, {} iterations, {} factorisations",
        reference.statistics.steps,
        reference.statistics.iterations,
        reference.statistics.factorizations
    );
    group.bench_function("svi", |b| {
        b.iter(|| {
            lagrangian.run_from_velocity(t0, black_box(q0.clone()), v0.clone(), h, t_end, &mut ())
        })
    });
    let hamiltonian = RelativisticChainH(chain);
    let (_, q0, p0) = hamiltonian.initial_state();
    for (id, name) in [("verlet_h", "verlet-h"), ("kahan_li8_h", "kahan-li8-h")] {
        let method = name
            .parse::<MethodSpec>()
            .and_then(|spec| spec.vector_method())
            .expect("a registry method");
        let integrator = Integrator::new(LocalCanonical::new(hamiltonian.clone()), method);
        let initial = Initial::Momentum {
            q: q0.clone(),
            p: p0.clone(),
        };
        let run = integrator
            .run(t0, initial.clone(), h, t_end, &mut ())
            .unwrap_or_else(|error| panic!("{id}: {error}"));
        eprintln!(
            "{id}: {} steps, {} iterations; gap to svi {:.2e} in q, {:.2e} in p",
            run.statistics.steps,
            run.statistics.iterations,
            (&run.last.q - &reference.last.q).amax(),
            (&run.last.p - &reference.last.p).amax()
        );
        group.bench_function(id, |b| {
            b.iter(|| integrator.run(t0, black_box(initial.clone()), h, t_end, &mut ()))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    targets = kepler, magnetic_bottle, relativistic_chain
}
criterion_main!(benches);
