//! The AD tax: what each derived quantity of a Lagrangian costs, per model and per dual type.
//!
//! For every zoo model and a coupled chain of N = 3, 4, 6 pendulums (where the scalar sweeps
//! stop paying), and of N = 12 and 20 (the size of a robot arm: how the dense derivatives of a
//! configuration-dependent mass grow), at one fixed generic state (no symmetric or zero components), this
//! times the methods of [`LagrangianExt`]:
//!
//! | id | work | num-dual type |
//! | --- | --- | --- |
//! | `value` | L itself | `f64` (the baseline) |
//! | `force_ad` | ∂L/∂q: N sweeps for N ≤ 3, else one | `Dual64`, else `DualSVec64<N>` |
//! | `force_jacobian` | L_qq alone (the adjoint's stage matrices): one sweep per entry for N ≤ 2, else one | `HyperDual64`, else `Dual2Vec` |
//! | `first_derivatives` | L, ∂L/∂q, ∂L/∂q̇: 2N sweeps for N ≤ 3, else two | `Dual64`, else `DualSVec64<N>` |
//! | `second_derivatives` | L, gradients, L_qq, L_qv, L_vv: one sweep per Hessian entry in (q, q̇) for N ≤ 2, else three | `HyperDual64`, else `HyperDualVec`, 2 × `Dual2Vec` |
//! | `acceleration` | q̈ = L_vv⁻¹(L_q − L_vq q̇): second derivatives + a small solve | as above |
//! | `acceleration_jacobian` | q̈, ∂q̈/∂q, ∂q̈/∂q̇: the acceleration on nested duals | `DualSVec64` over `HyperDualVec`/`Dual2Vec` |
//!
//! For Kepler (L = |v|²/2 + 1/|q|) the same quantities are also written by hand, so the ratio
//! `force_ad / force_hand` is the price of never writing a derivative:
//! `force_hand` (−q/|q|³), `force_vector_dual` (one `DualSVec64<2>` sweep, the alternative to
//! N scalar sweeps that [`svi::dimension::SCALAR_SWEEPS_UP_TO`] decides against for N ≤ 3),
//! `second_derivatives_hand` (the same [`SecondDerivatives`] struct,
//! with L_qq = −I/|q|³ + 3qqᵀ/|q|⁵) and `acceleration_jacobian_hand` (q̈ = −q/|q|³ with
//! ∂q̈/∂q = L_qq, ∂q̈/∂q̇ = 0). The hand-written results are checked against AD before timing.
//!
//! A model of run-time size (`derivatives/run-time-size`, the outer Solar System as
//! [`svi_models::NBody`], n = 18, a sum of 15 pair terms): `nbody_force_ad` (∂L/∂q as the
//! integrators take it: one vector-dual sweep per pair term) against `nbody_force_hand`
//! (Σ G mᵢmⱼ (qⱼ − qᵢ)/|qⱼ − qᵢ|³, checked against AD before timing).
//!
//! Every input goes through [`std::hint::black_box`], and so does every output.
//! Benchmark ids are `derivatives/<model>/<quantity>`.
//!
//! Run with `cargo bench --bench derivatives` (add a filter such as `-- kepler` to run one
//! model). Timings are short on purpose (2 s measurement, 0.5 s warm-up, 20 samples); the
//! medians are in `target/criterion/derivatives_<model>/<quantity>/new/estimates.json`.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use nalgebra::{Const, DVector, SMatrix, SVector, U2};
use num_dual::{DualSVec64, DualVec};
use std::hint::black_box;
use std::time::Duration;
use svi::derived::{AccelerationJacobian, SecondDerivatives};
use svi::scalar::Scalar;
use svi::{Lagrangian, LagrangianExt};
use svi_models::{DoublePendulum, HarmonicOscillator, Kepler, NBody, Pendulum, SpringPendulum};

/// Time of the fixed evaluation point (no model here depends on it).
const T: f64 = 0.3;

/// Open the group `derivatives/<name>` and time the six AD quantities of `model` at (q, v).
/// The group is returned so that a caller can add hand-written variants before finishing it.
fn model_group<'a, L: Lagrangian<Const<N>>, const N: usize>(
    c: &'a mut Criterion,
    name: &str,
    model: L,
    q: SVector<f64, N>,
    v: SVector<f64, N>,
) -> BenchmarkGroup<'a, WallTime> {
    let mut group = c.benchmark_group(format!("derivatives/{name}"));
    group.bench_function("value", |b| {
        b.iter(|| black_box(&model).value(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("force_ad", |b| {
        b.iter(|| black_box(&model).force(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("force_jacobian", |b| {
        b.iter(|| black_box(&model).force_jacobian(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("first_derivatives", |b| {
        b.iter(|| black_box(&model).first_derivatives(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("second_derivatives", |b| {
        b.iter(|| black_box(&model).second_derivatives(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("acceleration", |b| {
        b.iter(|| black_box(&model).acceleration(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("acceleration_jacobian", |b| {
        b.iter(|| {
            black_box(&model).acceleration_jacobian(black_box(T), black_box(&q), black_box(&v))
        })
    });
    group
}

/// A chain of N pendulums with velocity coupling, a generic N-dimensional Lagrangian with a
/// configuration-dependent mass matrix: L = Σᵢ (q̇ᵢ²/2 + cos qᵢ) plus the coupling
/// Σᵢ q̇ᵢ q̇ᵢ₊₁ cos(qᵢ − qᵢ₊₁)/10.
struct CoupledChain;

impl<const N: usize> Lagrangian<Const<N>> for CoupledChain {
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, N>, v: &SVector<D, N>) -> D {
        let mut l = D::from(0.0);
        for i in 0..N {
            l += v[i] * v[i] * 0.5 + q[i].cos();
            if i + 1 < N {
                l += v[i] * v[i + 1] * (q[i] - q[i + 1]).cos() * 0.1;
            }
        }
        l
    }
}

/// The chain's evaluation point: distinct angles and rates.
fn chain_q(i: usize, _: usize) -> f64 {
    0.1 + 0.2 * i as f64
}

fn chain_v(i: usize, _: usize) -> f64 {
    0.3 - 0.1 * i as f64
}

/// Kepler's ∂L/∂q = −q/|q|³, by hand.
fn kepler_force_hand(q: &SVector<f64, 2>) -> SVector<f64, 2> {
    let inverse_radius = q.dot(q).sqrt().recip();
    q * -(inverse_radius * inverse_radius * inverse_radius)
}

/// Kepler's L_qq = −I/|q|³ + 3 q qᵀ/|q|⁵, by hand.
fn kepler_hessian_hand(q: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
    let inverse_radius = q.dot(q).sqrt().recip();
    let inverse_radius2 = inverse_radius * inverse_radius;
    let inverse_radius3 = inverse_radius2 * inverse_radius;
    (q * q.transpose()) * (3.0 * inverse_radius3 * inverse_radius2)
        - SMatrix::identity() * inverse_radius3
}

/// Everything [`LagrangianExt::second_derivatives`] returns for Kepler, by hand.
fn kepler_second_derivatives_hand(
    q: &SVector<f64, 2>,
    v: &SVector<f64, 2>,
) -> SecondDerivatives<U2> {
    let inverse_radius = q.dot(q).sqrt().recip();
    let inverse_radius2 = inverse_radius * inverse_radius;
    let inverse_radius3 = inverse_radius2 * inverse_radius;
    SecondDerivatives {
        value: 0.5 * v.dot(v) + inverse_radius,
        q: q * -inverse_radius3,
        v: *v,
        qq: (q * q.transpose()) * (3.0 * inverse_radius3 * inverse_radius2)
            - SMatrix::identity() * inverse_radius3,
        qv: SMatrix::zeros(),
        vv: SMatrix::identity(),
    }
}

/// Everything [`LagrangianExt::acceleration_jacobian`] returns for Kepler, by hand.
fn kepler_acceleration_jacobian_hand(q: &SVector<f64, 2>) -> AccelerationJacobian<U2> {
    AccelerationJacobian {
        value: kepler_force_hand(q),
        q: kepler_hessian_hand(q),
        v: SMatrix::zeros(),
    }
}

/// The hand-written Kepler derivatives agree with AD at (q, v).
fn check_kepler_hand(model: &Kepler, q: &SVector<f64, 2>, v: &SVector<f64, 2>) {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * (1.0 + b.abs());
    let ad = model.second_derivatives(T, q, v);
    let hand = kepler_second_derivatives_hand(q, v);
    let pairs = [
        (hand.value, ad.value),
        (hand.q[0], ad.q[0]),
        (hand.q[1], ad.q[1]),
        (hand.v[0], ad.v[0]),
        (hand.v[1], ad.v[1]),
    ];
    assert!(pairs.iter().all(|&(a, b)| close(a, b)), "Kepler gradients");
    for (a, b) in [(hand.qq, ad.qq), (hand.qv, ad.qv), (hand.vv, ad.vv)] {
        assert!(
            a.iter().zip(b.iter()).all(|(&x, &y)| close(x, y)),
            "Kepler Hessian"
        );
    }
    let force = model.force(T, q, v);
    let by_hand = kepler_force_hand(q);
    assert!(
        close(force[0], by_hand[0]) && close(force[1], by_hand[1]),
        "Kepler force"
    );
    let ad = model
        .acceleration_jacobian(T, q, v)
        .expect("regular mass matrix");
    let hand = kepler_acceleration_jacobian_hand(q);
    for (a, b) in [(hand.q, ad.q), (hand.v, ad.v)] {
        assert!(
            a.iter().zip(b.iter()).all(|(&x, &y)| close(x, y)),
            "Kepler ∂q̈"
        );
    }
}

/// ∂L/∂q of an N-body model written by hand: Σⱼ G mᵢmⱼ (qⱼ − qᵢ)/|qⱼ − qᵢ|³.
fn nbody_force_hand(model: &NBody, q: &DVector<f64>) -> DVector<f64> {
    let d = model.space();
    let bodies = model.bodies();
    let mut force = DVector::zeros(q.len());
    for (i, a) in bodies.iter().enumerate() {
        for (j, b) in bodies.iter().enumerate().skip(i + 1) {
            let mut r2 = 0.0;
            for k in 0..d {
                let x = q[d * j + k] - q[d * i + k];
                r2 += x * x;
            }
            let scale = model.g * a.mass * b.mass / (r2 * r2.sqrt());
            for k in 0..d {
                let f = scale * (q[d * j + k] - q[d * i + k]);
                force[d * i + k] += f;
                force[d * j + k] -= f;
            }
        }
    }
    force
}

/// The outer Solar System's force by AD and by hand.
fn run_time_size(c: &mut Criterion) {
    let model = NBody::outer_solar_system();
    let (_, q, v) = svi::Defaults::initial_state(&model);
    let hand = nbody_force_hand(&model, &q);
    let gap = (model.force(T, &q, &v) - &hand).amax();
    assert!(
        gap <= 1e-12 * hand.amax(),
        "AD force off the hand-written by {gap:e}"
    );
    let mut group = c.benchmark_group("derivatives/run-time-size");
    group.bench_function("nbody_force_ad", |b| {
        b.iter(|| black_box(&model).force(black_box(T), black_box(&q), black_box(&v)))
    });
    group.bench_function("nbody_force_hand", |b| {
        b.iter(|| nbody_force_hand(black_box(&model), black_box(&q)))
    });
    group.finish();
}

fn derivatives(c: &mut Criterion) {
    // One-dimensional models: a generic angle and rate.
    let q1 = SVector::from([0.6]);
    let v1 = SVector::from([-0.8]);
    // Two-dimensional models: no zero, equal or symmetric components.
    let q2 = SVector::from([0.7, -0.4]);
    let v2 = SVector::from([0.3, 1.1]);

    model_group(c, "oscillator", HarmonicOscillator::default(), q1, v1).finish();
    model_group(c, "pendulum", Pendulum::default(), q1, v1).finish();
    model_group(c, "spring-pendulum", SpringPendulum::default(), q2, v2).finish();
    model_group(c, "double-pendulum", DoublePendulum::default(), q2, v2).finish();

    // Coupled chains of N = 3, 4, 6 pendulums: where scalar sweeps stop paying
    // (`svi::dimension::SCALAR_SWEEPS_UP_TO`, `svi::dimension::SCALAR_HESSIAN_SWEEPS_UP_TO`,
    // `svi::derived::SCALAR_HESSIAN_UP_TO`); N = 12 and 20: how the dense Hessians grow.
    fn chain<const N: usize>(c: &mut Criterion) {
        let (q, v) = (
            SVector::<f64, N>::from_fn(chain_q),
            SVector::from_fn(chain_v),
        );
        model_group(c, &format!("chain-{N}"), CoupledChain, q, v).finish();
    }
    chain::<3>(c);
    chain::<4>(c);
    chain::<6>(c);
    chain::<12>(c);
    chain::<20>(c);

    let kepler = Kepler::default();
    check_kepler_hand(&kepler, &q2, &v2);
    let mut group = model_group(c, "kepler", kepler, q2, v2);
    group.bench_function("force_hand", |b| {
        b.iter(|| kepler_force_hand(black_box(&q2)))
    });
    group.bench_function("force_vector_dual", |b| {
        b.iter(|| {
            let v = black_box(&v2).map(DualVec::from_re);
            num_dual::gradient(
                |x: SVector<DualSVec64<2>, 2>| kepler.lagrangian(DualVec::from_re(T), &x, &v),
                black_box(&q2),
            )
            .1
        })
    });
    group.bench_function("second_derivatives_hand", |b| {
        b.iter(|| kepler_second_derivatives_hand(black_box(&q2), black_box(&v2)))
    });
    group.bench_function("acceleration_jacobian_hand", |b| {
        b.iter(|| kepler_acceleration_jacobian_hand(black_box(&q2)))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20);
    targets = derivatives, run_time_size
}
criterion_main!(benches);
