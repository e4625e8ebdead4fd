//! The forced zoo models: their closed-form solutions against their equations of motion
//! (central differences), their forces against the derived Euler–Lagrange acceleration, and
//! their defaults.

use nalgebra::{SVector, U1};
use svi::{Defaults, ExactSolution, Lagrangian, LagrangianExt};
use svi_models::{
    DampedOscillator, DampedPendulum, DrivenOscillator, HarmonicOscillator, Pendulum,
};

/// Relative residual of q̈ + 2ζσ q̇ + σ² q − drive(t) along the exact solution, by central
/// differences of the exact position (step 1e-4: truncation ~1e-9 · q''''), and of q̇ against
/// dq/dt.
fn ode_residual<M: ExactSolution<U1>>(
    model: &M,
    sigma: f64,
    zeta: f64,
    drive: impl Fn(f64) -> f64,
    q0: f64,
    v0: f64,
) -> f64 {
    let (q0, v0) = (SVector::from([q0]), SVector::from([v0]));
    let at = |t: f64| model.exact_solution(0.5, &q0, &v0, t).unwrap();
    let step = 1e-4;
    let mut worst: f64 = 0.0;
    for k in 0..40 {
        let t = 0.5 + 0.37 * k as f64;
        let (minus, (q, v), plus) = (at(t - step).0[0], at(t), at(t + step).0[0]);
        let acceleration = (plus - 2.0 * q[0] + minus) / (step * step);
        let rate = (plus - minus) / (2.0 * step);
        let terms = [
            acceleration,
            2.0 * zeta * sigma * v[0],
            sigma * sigma * q[0],
            -drive(t),
        ];
        // Relative to the size of the terms (the truncation error grows with the stiffness).
        let scale = terms.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let residual = terms.iter().sum::<f64>() / scale;
        let rate_error = (rate - v[0]).abs() / v[0].abs().max(1.0);
        worst = worst.max(residual.abs()).max(rate_error);
    }
    worst
}

#[test]
fn damped_oscillator_solves_its_equation_in_every_damping_regime() {
    for zeta in [0.0, 0.1, 0.7, 1.0 - 1e-9, 1.0, 1.0 + 1e-9, 1.5, 2.5, 10.0] {
        for sigma in [1.0, 2.3] {
            let model = DampedOscillator::new(sigma, zeta).unwrap();
            let residual = ode_residual(&model, sigma, zeta, |_| 0.0, 0.8, -0.4);
            assert!(residual < 1e-5, "ζ = {zeta}, σ = {sigma}: {residual:e}");
            // The initial state is reproduced.
            let (q, v) = model
                .exact_solution(0.5, &SVector::from([0.8]), &SVector::from([-0.4]), 0.5)
                .unwrap();
            assert!(
                (q[0] - 0.8).abs() < 1e-15 && (v[0] + 0.4).abs() < 1e-14,
                "{q} {v}"
            );
        }
    }
    // Continuous across critical damping, and equal to the undamped oscillator at ζ = 0.
    let state = (SVector::from([0.8]), SVector::from([-0.4]));
    let solution = |zeta: f64| {
        DampedOscillator::new(1.0, zeta)
            .unwrap()
            .exact_solution(0.0, &state.0, &state.1, 3.0)
            .unwrap()
    };
    for side in [1.0 - 1e-8, 1.0 + 1e-8] {
        let (a, b) = (solution(side), solution(1.0));
        assert!((a.0 - b.0).amax() < 1e-7 && (a.1 - b.1).amax() < 1e-7);
    }
    let undamped = HarmonicOscillator::new(1.0)
        .unwrap()
        .exact_solution(0.0, &state.0, &state.1, 3.0)
        .unwrap();
    assert_eq!(solution(0.0), undamped);
    // Long over-damped runs neither overflow nor lose the slow mode.
    let (q, _) = DampedOscillator::new(1.0, 50.0)
        .unwrap()
        .exact_solution(0.0, &state.0, &state.1, 1000.0)
        .unwrap();
    assert!(q[0].is_finite() && q[0] > 0.0, "{q}");
}

#[test]
fn driven_oscillator_solves_its_equation_and_settles_to_the_steady_state() {
    let model = DrivenOscillator::default();
    let drive = |t: f64| model.amplitude * (model.drive * t).cos();
    let residual = ode_residual(&model, model.sigma, model.zeta, drive, 0.3, 0.1);
    assert!(residual < 1e-5, "{residual:e}");
    // Undamped resonance: q_p = F t sin(σt)/(2σ).
    let resonant = DrivenOscillator {
        zeta: 0.0,
        drive: 1.0,
        ..model
    };
    let drive = |t: f64| resonant.amplitude * t.cos();
    let residual = ode_residual(&resonant, 1.0, 0.0, drive, 0.3, 0.1);
    assert!(residual < 1e-5, "{residual:e}");
    // After 300 time units (transient e^{−30}) the solution is the steady state.
    let (q, v) = model
        .exact_solution(0.0, &SVector::from([1.0]), &SVector::from([0.0]), 300.0)
        .unwrap();
    let (qp, vp) = model.steady_state(300.0);
    assert!((q[0] - qp).abs() < 1e-12 && (v[0] - vp).abs() < 1e-12);
    // Its amplitude is F/√((σ² − Ω²)² + (2ζσΩ)²).
    let amplitude = (0..1000)
        .map(|k| model.steady_state(k as f64 * 0.01).0.abs())
        .fold(0.0, f64::max);
    let expected = 0.5 / ((1.0f64 - 0.81).powi(2) + 0.18f64.powi(2)).sqrt();
    assert!(
        (amplitude - expected).abs() < 1e-3 * expected,
        "{amplitude}"
    );
}

#[test]
fn forces_enter_the_derived_euler_lagrange_acceleration() {
    const { assert!(DampedOscillator::FORCED && DampedPendulum::FORCED) };
    const { assert!(DrivenOscillator::FORCED && !Pendulum::FORCED) };
    let (q, v) = (SVector::from([0.7]), SVector::from([-0.3]));
    let pendulum = DampedPendulum {
        m: 2.0,
        l: 0.5,
        g: 9.81,
        c: 0.4,
    };
    let acceleration = pendulum.acceleration(0.0, &q, &v).unwrap()[0];
    let expected = -(9.81 / 0.5) * 0.7f64.sin() - 0.4 * -0.3 / (2.0 * 0.25);
    assert!(
        (acceleration - expected).abs() < 1e-13,
        "{acceleration} vs {expected}"
    );
    // ∂q̈/∂q̇ = −c/(m l²) and ∂q̈/∂q = −(g/l) cos θ, through nested duals.
    let jacobian = pendulum.acceleration_jacobian(0.0, &q, &v).unwrap();
    assert!((jacobian.v[(0, 0)] + 0.4 / 0.5).abs() < 1e-13);
    assert!((jacobian.q[(0, 0)] + (9.81 / 0.5) * 0.7f64.cos()).abs() < 1e-12);
    // The force Jacobian by itself.
    let force = pendulum.external_force_jacobian(0.0, &q, &v);
    assert_eq!(
        (force.value[0], force.q[(0, 0)], force.v[(0, 0)]),
        (0.4 * 0.3, 0.0, -0.4)
    );
    // A time-dependent drive on a time-independent Lagrangian.
    let driven = DrivenOscillator::default();
    let t = 1.3;
    let acceleration = driven.acceleration(t, &q, &v).unwrap()[0];
    let expected = -0.7 - 2.0 * 0.1 * -0.3 + 0.5 * (0.9 * t).cos();
    assert!((acceleration - expected).abs() < 1e-14);
    // An unforced model's force is never evaluated: all zero.
    let none = Pendulum::default().external_force_jacobian(0.0, &q, &v);
    assert_eq!(none, svi::derived::ForceJacobian::zeros(U1));
}

#[test]
fn damped_pendulum_is_the_pendulum_plus_friction() {
    let model = DampedPendulum::default();
    assert_eq!((model.m, model.l, model.g, model.c), (1.0, 1.0, 1.0, 0.1));
    assert_eq!(model.initial_state(), Pendulum::default().initial_state());
    let (q0, v0) = (SVector::from([1.0]), SVector::from([0.0]));
    assert!(model.exact_solution(0.0, &q0, &v0, 1.0).is_none());
    let undamped = DampedPendulum { c: 0.0, ..model };
    assert_eq!(
        undamped.exact_solution(0.0, &q0, &v0, 1.0),
        Pendulum::default().exact_solution(0.0, &q0, &v0, 1.0)
    );
    let state = (SVector::from([0.4]), SVector::from([1.1]));
    assert_eq!(
        model.value(0.0, &state.0, &state.1),
        Pendulum::default().value(0.0, &state.0, &state.1)
    );
}

#[test]
fn forced_model_defaults() {
    let damped = DampedOscillator::default();
    assert_eq!((damped.sigma, damped.zeta), (1.0, 0.1));
    assert_eq!(damped.friction(), 0.2);
    assert_eq!(
        (damped.default_step(), damped.default_horizon()),
        (0.1, 50.0)
    );
    let driven = DrivenOscillator::default();
    assert_eq!(
        (driven.sigma, driven.zeta, driven.amplitude, driven.drive),
        (1.0, 0.1, 0.5, 0.9)
    );
    assert_eq!(driven.initial_state().1[0], 0.0);
    assert!(DampedOscillator::new(1.0, -0.1).is_err());
    assert!(DampedOscillator::new(0.0, 0.1).is_err());
}
