//! One step of each method × model × node count, and one whole run of the paper's Kepler scene.
//!
//! # `step/<model>/<method>`: one steady-state step
//!
//! Models and step sizes: `kepler` (e = 0.5, h = 0.1), `pendulum` (h = 0.1) and
//! `double-pendulum` (h = 0.01), each from its default initial state. Kepler and the pendulum
//! declare a constant mass matrix, so SVI takes its Hessian-free fixed-point path on them; the
//! double pendulum goes through Newton with the exact Jacobian. Methods:
//!
//! - `svi_<p>cgl_<2p>gl`: [`Svi::new`]`(p)` with its default 2p Gauss points, p ∈ {3, 6, 9};
//! - `svi_<p>cgl_<p-1>gl`: the Gauss-equivalent configuration (degree s = p − 1 with s Gauss
//!   points is the s-stage Gauss–Legendre method), p ∈ {3, 6, 7, 9};
//! - `sc_<p>cgl`: [`SpectralCollocation::new`]`(p)`, p ∈ {3, 6, 9};
//! - `verlet`, `symplectic_euler`, `symplectic_euler_adjoint`: [`StormerVerlet`] and the
//!   [`VariationalIntegrator`] of [`SymplecticEuler`] and [`AdjointSymplecticEuler`], all
//!   three explicit kick–drift–kick steps on the constant-mass models (one gradient per step),
//!   Newton's method on the double pendulum.
//!
//! How a step is measured (`Bencher::iter_custom`): the workspace is built once and 200
//! steps are taken untimed, so the warm start (the previous step's polynomial extrapolated
//! to the new nodes) is in place; then each timed step starts from the previous step's
//! output, exactly as in a run. Every 1000 timed steps the trajectory is re-seeded with the
//! clock stopped: a fresh workspace, the default initial state, 200 untimed steps again.
//! Re-seeding is needed because the non-symplectic collocation drifts (SC with 3 points on
//! Kepler at h = 0.1 drifts off the orbit and fails to converge after about 2000 steps), and
//! it is done untimed so that neither a cold start nor a mismatched warm start enters the
//! figure. So the number is the mean cost of a warm-started step over steps 200..1200 of
//! the scene (16 Kepler orbits, 15 pendulum periods, 10 time units of the double pendulum).
//! The mean nonlinear iterations and evaluation points per step over that same window are
//! printed to stderr. The increment is added without compensated summation, which changes
//! nothing about the cost. A failing step panics, so a number is never for a broken run.
//!
//! # `run/kepler_T200/<method>`: a whole run
//!
//! The Kepler scene of Li, Wu, Leok (2018), Figs. 13–17 (e = 0.5, h = 0.2) shortened to
//! T = 200 (1000 steps), through [`Integrator::run_from_velocity`] with no observer (`()`),
//! workspace construction and the initial Legendre map included: SVI with 6 CGL / 12 GL
//! points, SVI with 7 CGL / 6 GL (the 6-stage Gauss method) and, for comparison, SC with
//! 6 CGL points and Störmer–Verlet (the explicit kick–drift–kick path of a constant mass).
//!
//! Run with `cargo bench --bench step` (add a filter such as `-- step/kepler` to run a subset).
//! Timings are short on purpose (2 s measurement, 0.5 s warm-up, 20 samples); the medians
//! are in `target/criterion/<group>/<method>/new/estimates.json`.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use nalgebra::{Const, U2};
use std::hint::black_box;
use std::time::{Duration, Instant};
use svi::method::StepReport;
use svi::{
    AdjointSymplecticEuler, Defaults, Initial, Integrator, Lagrangian, Method, SpectralCollocation,
    State, StormerVerlet, Svi, SymplecticEuler, VariationalIntegrator,
};
use svi_models::{DoublePendulum, Kepler, Pendulum};

/// Untimed steps after each (re-)seed, to reach the warm-started steady state.
const PRE_STEPS: usize = 200;
/// Timed steps per segment; then the trajectory is re-seeded (untimed).
const SEGMENT: u64 = 1000;

/// One trajectory of `method` on `model`: the workspace, the current state and the step
/// counter, re-seeded from the model's default initial state every [`SEGMENT`] timed steps.
struct Trajectory<'a, L, M: Method<Const<N>>, const N: usize> {
    id: &'a str,
    model: L,
    method: M,
    h: f64,
    t0: f64,
    initial: State<Const<N>>,
    workspace: M::Workspace,
    state: State<Const<N>>,
    increment: State<Const<N>>,
    /// Steps since the last seed.
    k: usize,
    /// Timed steps since the last seed.
    timed: u64,
}

impl<'a, L, M, const N: usize> Trajectory<'a, L, M, N>
where
    L: Lagrangian<Const<N>> + Defaults<Const<N>> + Clone,
    M: Method<Const<N>> + Clone,
{
    fn new(id: &'a str, model: L, method: M, h: f64) -> Self {
        let (t0, q0, v0) = model.initial_state();
        let initial = Integrator::new(model.clone(), method.clone())
            .initial_state(t0, &Initial::Velocity { q: q0, v: v0 })
            .expect("valid initial state");
        let workspace = method.workspace(&model, h).expect("valid method options");
        let mut trajectory = Trajectory {
            id,
            model,
            method,
            h,
            t0,
            initial,
            workspace,
            state: initial,
            increment: State::zeros(Const::<N>),
            k: 0,
            timed: 0,
        };
        trajectory.reseed();
        trajectory
    }

    /// Start again from the initial state with a fresh workspace, and take [`PRE_STEPS`]
    /// untimed steps so that the warm start is in place.
    fn reseed(&mut self) {
        self.workspace = self
            .method
            .workspace(&self.model, self.h)
            .expect("valid method options");
        self.state = self.initial;
        self.k = 0;
        self.timed = 0;
        for _ in 0..PRE_STEPS {
            self.step();
        }
    }

    /// One step; its output becomes the next input. Panics if the step fails.
    #[inline]
    fn step(&mut self) -> StepReport {
        let t = self.t0 + self.k as f64 * self.h;
        let report = self
            .method
            .step(
                &self.model,
                &mut self.workspace,
                t,
                self.h,
                &self.state,
                &mut self.increment,
            )
            .unwrap_or_else(|failure| panic!("{}: step {} failed: {failure:?}", self.id, self.k));
        self.state.q += self.increment.q;
        self.state.y += self.increment.y;
        self.k += 1;
        report
    }

    /// Time `steps` steps, re-seeding (with the clock stopped) at the end of every segment.
    fn timed_steps(&mut self, steps: u64) -> Duration {
        let mut elapsed = Duration::ZERO;
        let mut remaining = steps;
        while remaining > 0 {
            if self.timed == SEGMENT {
                self.reseed();
            }
            let chunk = remaining.min(SEGMENT - self.timed);
            let start = Instant::now();
            for _ in 0..chunk {
                black_box(self.step());
            }
            black_box(&self.state);
            elapsed += start.elapsed();
            remaining -= chunk;
            self.timed += chunk;
        }
        elapsed
    }
}

/// Time one steady-state step of `method` on `model` with step `h` (see the module docs).
fn bench_step<L, M, const N: usize>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: &str,
    model: L,
    method: M,
    h: f64,
) where
    L: Lagrangian<Const<N>> + Defaults<Const<N>> + Clone,
    M: Method<Const<N>> + Clone,
{
    let mut trajectory = Trajectory::new(id, model, method, h);
    // Work per step over exactly one timed segment (untimed here), then start afresh.
    let (mut iterations, mut evaluations) = (0, 0);
    for _ in 0..SEGMENT {
        let report = trajectory.step();
        iterations += report.iterations;
        evaluations += report.evaluations;
    }
    eprintln!(
        "{id}: {:.2} iterations and {:.1} evaluation points per step (steps {PRE_STEPS}..{})",
        iterations as f64 / SEGMENT as f64,
        evaluations as f64 / SEGMENT as f64,
        PRE_STEPS as u64 + SEGMENT,
    );
    trajectory.reseed();
    group.bench_function(id, |b| b.iter_custom(|steps| trajectory.timed_steps(steps)));
}

/// Every method configuration of the per-step benches, on one model.
fn bench_model<L, const N: usize>(c: &mut Criterion, name: &str, model: L, h: f64)
where
    L: Lagrangian<Const<N>> + Defaults<Const<N>> + Clone,
{
    let mut group = c.benchmark_group(format!("step/{name}"));
    for points in [3, 6, 9] {
        let id = format!("svi_{points}cgl_{}gl", 2 * points);
        bench_step(&mut group, &id, model.clone(), Svi::new(points), h);
    }
    for points in [3, 6, 7, 9] {
        let id = format!("svi_{points}cgl_{}gl", points - 1);
        let method = Svi::new(points).with_quadrature(points - 1);
        bench_step(&mut group, &id, model.clone(), method, h);
    }
    for points in [3, 6, 9] {
        let id = format!("sc_{points}cgl");
        bench_step(
            &mut group,
            &id,
            model.clone(),
            SpectralCollocation::new(points),
            h,
        );
    }
    bench_step(
        &mut group,
        "verlet",
        model.clone(),
        StormerVerlet::default(),
        h,
    );
    let euler = VariationalIntegrator::new(SymplecticEuler);
    bench_step(&mut group, "symplectic_euler", model.clone(), euler, h);
    let adjoint = VariationalIntegrator::new(AdjointSymplecticEuler);
    bench_step(
        &mut group,
        "symplectic_euler_adjoint",
        model.clone(),
        adjoint,
        h,
    );
    group.finish();
}

fn steps(c: &mut Criterion) {
    bench_model(c, "kepler", Kepler::default(), 0.1);
    bench_model(c, "pendulum", Pendulum::default(), 0.1);
    bench_model(c, "double-pendulum", DoublePendulum::default(), 0.01);
}

/// Time a whole run of the Kepler scene (e = 0.5, h = 0.2, T = 200) with `method`.
fn bench_run<M: Method<U2> + Clone>(group: &mut BenchmarkGroup<'_, WallTime>, id: &str, method: M) {
    const H: f64 = 0.2;
    const T_END: f64 = 200.0;
    let model = Kepler::new(0.5).expect("valid eccentricity");
    let (t0, q0, v0) = model.initial_state();
    let integrator = Integrator::new(model, method);
    let run = integrator
        .run_from_velocity(t0, q0, v0, H, T_END, &mut ())
        .unwrap_or_else(|error| panic!("{id}: {error}"));
    eprintln!(
        "{id}: {} steps, {} iterations, energy error {:.1e}",
        run.statistics.steps,
        run.statistics.iterations,
        Kepler::energy(&run.last.q, &run.last.v) + 0.5,
    );
    group.bench_function(id, |b| {
        b.iter(|| {
            integrator.run_from_velocity(
                black_box(t0),
                black_box(q0),
                black_box(v0),
                black_box(H),
                black_box(T_END),
                &mut (),
            )
        })
    });
}

fn runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("run/kepler_T200");
    bench_run(&mut group, "svi_6cgl_12gl", Svi::new(6));
    bench_run(&mut group, "svi_7cgl_6gl", Svi::new(7).with_quadrature(6));
    bench_run(&mut group, "sc_6cgl", SpectralCollocation::new(6));
    bench_run(&mut group, "verlet", StormerVerlet::default());
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20);
    targets = steps, runs
}
criterion_main!(benches);
