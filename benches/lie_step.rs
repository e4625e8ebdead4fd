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
//! from the state of the tests (the generic Lie-SVI with chain-rule derivatives).
//!
//! Run with `cargo bench --bench lie_step`.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{SVector, Vector3};
use std::hint::black_box;
use std::time::{Duration, Instant};
use svi::Step;
use svi::lie_group::{
    Form, GroupLagrangianExt, GroupSpace, GroupState, LieSvi, LieWorkspace, RigidBodyDefaults,
    RigidBodyExt, RigidBodyLagrangian, RigidMotions, RigidState, so3,
};
use svi::method::lie_svi::GroupWorkspace;
use svi_models::{FallingBody, FreeRigidBody, HeavyTop, Pendulum3d};

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
            b.iter_custom(|iterations| {
                let mut total = Duration::ZERO;
                let mut done = 0;
                while done < iterations {
                    let (mut workspace, mut state) = seed(&model, &method, h);
                    let mut increment = RigidState::zeros();
                    let count = SEGMENT.min(iterations - done);
                    let start = Instant::now();
                    for _ in 0..count {
                        method
                            .step(&model, &mut workspace, 0.0, h, &state, &mut increment)
                            .expect("step converges");
                        state.r += increment.r;
                        state.momentum += increment.momentum;
                    }
                    total += start.elapsed();
                    black_box(&state);
                    done += count;
                }
                total
            })
        });
    }
    group.finish();
}

/// The falling body's workspace and state after [`PRE_STEPS`] steps.
fn seed_falling(
    body: &FallingBody,
    method: &LieSvi,
    h: f64,
) -> (GroupWorkspace<6>, GroupState<6, 12>) {
    let r = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
    let g = RigidMotions::element(&r, &Vector3::new(1.0, -2.0, 3.0));
    let xi = SVector::<f64, 6>::from([1.0, 0.2, 0.8, 0.5, 0.0, 2.0]);
    let mut state = GroupState {
        g,
        momentum: body.momentum(&g, &xi),
    };
    let mut workspace =
        Step::<FallingBody, GroupSpace<RigidMotions, 6, 12>>::workspace(method, body, h)
            .expect("valid options");
    let mut increment = GroupState::zeros();
    for _ in 0..PRE_STEPS {
        Step::<FallingBody, GroupSpace<RigidMotions, 6, 12>>::step(
            method,
            body,
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

fn falling_steps(c: &mut Criterion) {
    let body = FallingBody::default();
    let h = 0.01;
    let mut group = c.benchmark_group("lie_step/falling-body-se3");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    for points in [2, 3, 4] {
        let method = LieSvi::new(points);
        group.bench_function(format!("{points}cgl_{points}gl"), |b| {
            b.iter_custom(|iterations| {
                let mut total = Duration::ZERO;
                let mut done = 0;
                while done < iterations {
                    let (mut workspace, mut state) = seed_falling(&body, &method, h);
                    let mut increment = GroupState::zeros();
                    let count = SEGMENT.min(iterations - done);
                    let start = Instant::now();
                    for _ in 0..count {
                        Step::<FallingBody, GroupSpace<RigidMotions, 6, 12>>::step(
                            &method,
                            &body,
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
                    total += start.elapsed();
                    black_box(&state);
                    done += count;
                }
                total
            })
        });
    }
    group.finish();
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

criterion_group!(benches, lie_steps, falling_steps);
criterion_main!(benches);
