//! One warm-started step of the Lie-group variational integrator on SO(3), per model, node
//! count and form.
//!
//! `lie_step/<model>/<p>cgl_<m>gl[_reduced]`: [`LieSvi::new`]`(p)` with m Gauss points on
//! the free rigid body (h = 0.05), the heavy top (h = 0.01) and the 3D pendulum (h = 0.01),
//! each from its default initial state; the free body also in the reduced Euler–Poincaré
//! form. The workspace is built once and 50 steps are taken untimed (so the warm start is in
//! place); each timed step starts from the previous step's output; every 1000 timed steps
//! the trajectory is re-seeded with the clock stopped. A failing step panics.
//!
//! `lie_step/falling-body-se3/<p>cgl_<p>gl` is the same measurement through the group
//! interface ([`svi::lie_group::LieGroup`]) on SE(3): the falling rigid body (h = 0.01),
//! from the state of the tests. (SO(3) rigid bodies run the same group step on
//! [`svi::lie_group::Rotations`], so the rows above measure it too.)
//!
//! `lie_step/spherical-chain-8/<p>cgl_<p>gl`: eight spherical pendulums on SO(3)⁸
//! (`svi_models::SphericalChain`, derivatives term by term over pairs of links), h = 0.002.
//!
//! Run with `cargo bench --bench lie_step`.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{SVector, Vector3};
use std::hint::black_box;
use std::time::{Duration, Instant};
use svi::Step;
use svi::lie_group::{
    Form, GroupLagrangian, GroupLagrangianExt, GroupSpace, GroupState, LieSvi, LieWorkspace,
    RigidBodyDefaults, RigidBodyExt, RigidBodyLagrangian, RigidMotions, RigidState, so3,
};
use svi::method::lie_svi::GroupWorkspace;
use svi_models::{FallingBody, FreeRigidBody, HeavyTop, Pendulum3d, SphericalChain};

/// Untimed steps after each (re-)seed.
const PRE_STEPS: usize = 50;
/// Timed steps per segment.
const SEGMENT: u64 = 1000;

fn seed<L: RigidBodyLagrangian + RigidBodyDefaults>(
    model: &L,
    method: &LieSvi,
    h: f64,
) -> (LieWorkspace, RigidState) {
    let (r, omega) = model.initial_state();
    let mut state = RigidState {
        r,
        momentum: model.momentum(&r, &omega),
    };
    let mut workspace = method.workspace(model, h).expect("valid options");
    let mut increment = RigidState::zeros();
    for _ in 0..PRE_STEPS {
        method
            .step(model, &mut workspace, 0.0, h, &state, &mut increment)
            .expect("step converges");
        state.r += increment.r;
        state.momentum += increment.momentum;
    }
    (workspace, state)
}

/// `iterations` timed steps in segments of at most [`SEGMENT`], each from a fresh `seed`
/// (not timed); `step` advances the state once.
fn timed_steps<W, S>(
    iterations: u64,
    mut seed: impl FnMut() -> (W, S),
    mut step: impl FnMut(&mut W, &mut S),
) -> Duration {
    let mut total = Duration::ZERO;
    let mut done = 0;
    while done < iterations {
        let (mut workspace, mut state) = seed();
        let count = SEGMENT.min(iterations - done);
        let clock = Instant::now();
        for _ in 0..count {
            step(&mut workspace, &mut state);
        }
        total += clock.elapsed();
        black_box(&state);
        done += count;
    }
    total
}

fn bench_model<L: RigidBodyLagrangian + RigidBodyDefaults>(
    c: &mut Criterion,
    model: L,
    configurations: &[(usize, usize, Form)],
) {
    let h = model.default_step();
    let mut group = c.benchmark_group(format!("lie_step/{}", model.name()));
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    for &(points, quadrature, form) in configurations {
        let method = LieSvi::new(points)
            .with_quadrature(quadrature)
            .with_form(form);
        let suffix = if form == Form::Reduced {
            "_reduced"
        } else {
            ""
        };
        let id = format!("{points}cgl_{quadrature}gl{suffix}");
        group.bench_function(&id, |b| {
            let mut increment = RigidState::zeros();
            b.iter_custom(|iterations| {
                timed_steps(
                    iterations,
                    || seed(&model, &method, h),
                    |workspace, state| {
                        method
                            .step(&model, workspace, 0.0, h, state, &mut increment)
                            .expect("step converges");
                        state.r += increment.r;
                        state.momentum += increment.momentum;
                    },
                )
            })
        });
    }
    group.finish();
}

/// A model's workspace and state after [`PRE_STEPS`] steps from (g, ξ).
fn seed_group<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    method: &LieSvi,
    h: f64,
    (g, xi): (SVector<f64, E>, SVector<f64, N>),
) -> (GroupWorkspace<N>, GroupState<N, E>) {
    let mut state = GroupState {
        g,
        momentum: model.momentum(&g, &xi),
    };
    let mut workspace =
        Step::<L, GroupSpace<L::Group, N, E>>::workspace(method, model, h).expect("valid options");
    let mut increment = GroupState::zeros();
    for _ in 0..PRE_STEPS {
        Step::<L, GroupSpace<L::Group, N, E>>::step(
            method,
            model,
            &mut workspace,
            0.0,
            h,
            &state,
            &mut increment,
        )
        .expect("step converges");
        state.g += increment.g;
        state.momentum += increment.momentum;
    }
    (workspace, state)
}

/// `lie_step/<name>/<p>cgl_<p>gl` through the group interface from (g, ξ) with steps `h`.
fn bench_group<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    c: &mut Criterion,
    name: &str,
    model: &L,
    start: (SVector<f64, E>, SVector<f64, N>),
    h: f64,
) {
    let mut group = c.benchmark_group(format!("lie_step/{name}"));
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    for points in [2, 3, 4] {
        let method = LieSvi::new(points);
        group.bench_function(format!("{points}cgl_{points}gl"), |b| {
            let mut increment = GroupState::zeros();
            b.iter_custom(|iterations| {
                timed_steps(
                    iterations,
                    || seed_group(model, &method, h, start),
                    |workspace, state| {
                        Step::<L, GroupSpace<L::Group, N, E>>::step(
                            &method,
                            model,
                            workspace,
                            0.0,
                            h,
                            state,
                            &mut increment,
                        )
                        .expect("step converges");
                        state.g += increment.g;
                        state.momentum += increment.momentum;
                    },
                )
            })
        });
    }
    group.finish();
}

fn group_steps(c: &mut Criterion) {
    let r = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
    let g = RigidMotions::element(&r, &Vector3::new(1.0, -2.0, 3.0));
    let xi = SVector::<f64, 6>::from([1.0, 0.2, 0.8, 0.5, 0.0, 2.0]);
    bench_group(
        c,
        "falling-body-se3",
        &FallingBody::default(),
        (g, xi),
        0.01,
    );
    // Eight spherical pendulums on SO(3)⁸ (dimension 24, derivatives term by term), leaning
    // and moving, h = 0.002.
    let chain = SphericalChain::<8, 24, 72>::default();
    let directions: [Vector3<f64>; 8] = std::array::from_fn(|i| {
        let (tilt, turn) = (0.3 + 0.05 * i as f64, 0.5 * i as f64);
        Vector3::new(
            tilt.sin() * turn.cos(),
            tilt.sin() * turn.sin(),
            -tilt.cos(),
        )
    });
    let rates: [Vector3<f64>; 8] = std::array::from_fn(|i| {
        let v = Vector3::new(0.2, -0.1 * i as f64, 0.05);
        v - directions[i] * directions[i].dot(&v)
    });
    bench_group(
        c,
        "spherical-chain-8",
        &chain,
        chain.state(&directions, &rates),
        0.002,
    );
}

fn lie_steps(c: &mut Criterion) {
    let full = [(2, 1, Form::Full), (3, 3, Form::Full), (5, 5, Form::Full)];
    bench_model(
        c,
        FreeRigidBody::default(),
        &[
            (2, 1, Form::Full),
            (2, 1, Form::Reduced),
            (3, 3, Form::Full),
            (3, 3, Form::Reduced),
            (5, 5, Form::Reduced),
        ],
    );
    bench_model(c, HeavyTop::default(), &full);
    bench_model(c, Pendulum3d::default(), &full);
}

criterion_group!(benches, lie_steps, group_steps);
criterion_main!(benches);
