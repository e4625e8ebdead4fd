//! The Octave package's call, `[T, Y] = spectralvarint(odefun, tspan, y0)`: a model given as
//! the right-hand side of Hamilton's equations alone ([`HamiltonianRhs`]) run by `svi::solve`.
//!
//! References: the Lagrange–d'Alembert run of the same damped pendulum
//! (`svi_models::DampedPendulum`, SVI with the same points and steps, whose map `svi-h`
//! reproduces through the Legendre map), and for every method on Hamilton's equations the
//! same method on the pendulum written as H (`svi_models::PendulumH`, exact derivatives by
//! automatic differentiation).

use nalgebra::DVector;
use svi::method::hamiltonian::galerkin::HamiltonianGalerkin;
use svi::method::registry::hamiltonian_names;
use svi::model::rhs::HamiltonianRhs;
use svi::solve::{Adapt, SolveOptions, Span, solve};
use svi::{Error, Initial, Integrator, MethodSpec, RunOptions, Svi};
use svi_models::{DampedPendulum, PendulumH};

/// Friction of the damped pendulum (m = l = g = 1).
const C: f64 = 0.1;

/// odefun of the damped pendulum: θ' = p, p' = −sin θ − c p.
fn damped(_t: f64, y: &[f64], dy: &mut [f64]) {
    dy[0] = y[1];
    dy[1] = -y[0].sin() - C * y[1];
}

/// ∂F/∂y of [`damped`], column by column.
fn damped_jacobian(_t: f64, y: &[f64], jacobian: &mut [f64]) {
    jacobian.copy_from_slice(&[0.0, -y[0].cos(), 1.0, -C]);
}

fn fixed(h: f64) -> SolveOptions {
    let mut options = SolveOptions::default();
    options.adapt = Adapt::None;
    options.h = Some(h);
    options
}

#[test]
fn the_octave_call_on_the_damped_pendulum_reproduces_the_lagrange_dalembert_run() {
    // Output at listed times on the step grid, fixed steps h = 0.1 to T = 20; the Jacobian by
    // central differences (the default) and given.
    let times = [0.0, 1.0, 2.5, 5.0, 10.0, 20.0];
    let span = Span::times(&times);
    let (q0, p0) = (1.0, 0.0);
    let lagrangian = solve(
        DampedPendulum::default(),
        Svi::default(),
        &span,
        Initial::Velocity {
            q: [q0].into(),
            v: [p0].into(),
        },
        &fixed(0.1),
    )
    .unwrap();
    let initial = Initial::Momentum {
        q: DVector::from_vec(vec![q0]),
        p: DVector::from_vec(vec![p0]),
    };
    for (name, model) in [
        (
            "central differences",
            HamiltonianRhs::new(1, damped).unwrap(),
        ),
        (
            "given Jacobian",
            HamiltonianRhs::new(1, damped)
                .unwrap()
                .with_jacobian(damped_jacobian),
        ),
    ] {
        let octave = solve(
            model,
            HamiltonianGalerkin::default(),
            &span,
            initial.clone(),
            &fixed(0.1),
        )
        .unwrap();
        assert_eq!(octave.points.len(), times.len());
        let mut largest = 0.0_f64;
        for (a, b) in octave.points.iter().zip(&lagrangian.points) {
            assert_eq!(a.t, b.t);
            largest = largest
                .max((a.q[0] - b.q[0]).abs())
                .max((a.p[0] - b.p[0]).abs());
        }
        eprintln!("damped pendulum, {name}: largest difference {largest:.2e}");
        assert!(largest < 1e-10, "{name}: {largest:e}");
        // The pendulum is damped: it has lost energy by T = 20.
        let last = octave.points.last().unwrap();
        let energy = |q: f64, p: f64| 0.5 * p * p - q.cos();
        assert!(energy(last.q[0], last.p[0]) < energy(q0, p0) - 0.1);
    }
}

#[test]
fn the_octave_call_with_its_defaults_takes_the_lagrange_dalembert_steps() {
    // Step doubling to tol = 1e-8 (spectralvarint's step-size control): the same accepted
    // steps and states as the adaptive Lagrange–d'Alembert run, the output times read off
    // the step's curve; both within 1e-5 of svi-h with fixed steps 100 times finer than
    // the default trial step.
    let times = [0.0, 3.0, 7.0, 10.0];
    let span = Span::times(&times);
    let initial = Initial::Momentum {
        q: DVector::from_vec(vec![2.0]),
        p: DVector::from_vec(vec![0.5]),
    };
    let model = HamiltonianRhs::new(1, damped).unwrap();
    let octave = solve(
        model.clone(),
        HamiltonianGalerkin::default(),
        &span,
        initial.clone(),
        &SolveOptions::default(),
    )
    .unwrap();
    let lagrangian = solve(
        DampedPendulum::default(),
        Svi::default(),
        &span,
        Initial::Velocity {
            q: [2.0].into(),
            v: [0.5].into(),
        },
        &SolveOptions::default(),
    )
    .unwrap();
    assert_eq!(octave.statistics.steps, lagrangian.statistics.steps);
    assert_eq!(octave.adaptivity.rejected, lagrangian.adaptivity.rejected);
    let reference = solve(
        model,
        HamiltonianGalerkin::default(),
        &span,
        initial,
        &fixed(0.01),
    )
    .unwrap();
    let (mut same, mut error) = (0.0_f64, 0.0_f64);
    for ((a, b), c) in octave
        .points
        .iter()
        .zip(&lagrangian.points)
        .zip(&reference.points)
    {
        same = same
            .max((a.q[0] - b.q[0]).abs())
            .max((a.p[0] - b.p[0]).abs());
        error = error
            .max((a.q[0] - c.q[0]).abs())
            .max((a.p[0] - c.p[0]).abs());
    }
    // The end of the span is a step's end (superconvergent, order 2(P − 1)); the interior
    // output times are read off the step's curve, of order P between its nodes.
    let (end, fine) = (
        octave.points.last().unwrap(),
        reference.points.last().unwrap(),
    );
    let end_error = (end.q[0] - fine.q[0])
        .abs()
        .max((end.p[0] - fine.p[0]).abs());
    eprintln!(
        "default call: {} steps, {} rejected; against the Lagrangian run {same:.2e}, against \
         the fine run {error:.2e} (at t = 10, a step's end: {end_error:.2e})",
        octave.statistics.steps, octave.adaptivity.rejected
    );
    assert!(same < 1e-10, "{same:e}");
    assert!(error < 1e-5, "{error:e}");
    assert!(end_error < 1e-7, "{end_error:e}");
}

#[test]
fn every_method_on_hamiltons_equations_runs_a_right_hand_side_as_it_runs_h() {
    // The pendulum's field (H = p²/2 − cos q) against the pendulum written as H: the same
    // equations; the derivatives by central differences drive Newton's method only.
    let field = HamiltonianRhs::new(1, |_t, y, dy| {
        dy[0] = y[1];
        dy[1] = -y[0].sin();
    })
    .unwrap();
    let (h, t_end) = (0.05, 5.0);
    for name in hamiltonian_names().split(", ") {
        let method = name.parse::<MethodSpec>().unwrap().vector_method().unwrap();
        let run = |initial| -> (f64, f64) {
            let a = Integrator::new(field.clone(), method.clone())
                .run(0.0, initial, h, t_end, &mut ())
                .unwrap();
            (a.last.q[0], a.last.p[0])
        };
        let (q, p) = run(Initial::Momentum {
            q: DVector::from_vec(vec![1.0]),
            p: DVector::from_vec(vec![0.3]),
        });
        let exact = Integrator::new(svi::Canonical::new(PendulumH::default()), method.clone())
            .run(
                0.0,
                Initial::Momentum {
                    q: [1.0].into(),
                    p: [0.3].into(),
                },
                h,
                t_end,
                &mut (),
            )
            .unwrap();
        let difference = (q - exact.last.q[0]).abs().max((p - exact.last.p[0]).abs());
        assert!(difference < 1e-10, "{name}: {difference:e}");
    }
    assert!(hamiltonian_names().contains("svi-h"));
}

#[test]
fn the_methods_on_the_euler_lagrange_equations_refuse_a_right_hand_side() {
    let field = HamiltonianRhs::new(1, damped).unwrap();
    let initial = Initial::Momentum {
        q: DVector::from_vec(vec![1.0]),
        p: DVector::from_vec(vec![0.0]),
    };
    let error = Integrator::new(field, Svi::default())
        .run(0.0, initial, 0.1, 1.0, &mut ())
        .unwrap_err();
    match &error {
        Error::InvalidParameter { name, reason } => {
            assert_eq!(name, "method");
            assert!(reason.contains("no Lagrangian"), "{reason}");
            assert!(reason.contains("end in -h"), "{reason}");
        }
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

#[test]
fn bad_right_hand_sides_are_typed_errors() {
    assert!(matches!(
        HamiltonianRhs::new(0, damped),
        Err(Error::InvalidParameter { name, .. }) if name == "model"
    ));
    let initial = || Initial::Momentum {
        q: DVector::from_vec(vec![1.0]),
        p: DVector::from_vec(vec![0.0]),
    };
    // Not finite at the initial state.
    let nan = HamiltonianRhs::new(1, |_t, _y, dy| dy.fill(f64::NAN)).unwrap();
    let error = Integrator::new(nan, HamiltonianGalerkin::default())
        .run(0.0, initial(), 0.1, 1.0, &mut ())
        .unwrap_err();
    assert!(
        matches!(&error, Error::NonFinite { what, .. } if what.contains("right-hand side")),
        "{error:?}"
    );
    // Not finite from t = 0.5 on: the run stops there with the good part kept.
    let late = HamiltonianRhs::new(1, |t, y, dy| {
        dy[0] = y[1];
        dy[1] = if t > 0.5 { f64::NAN } else { -y[0] };
    })
    .unwrap();
    let failure = Integrator::new(late, HamiltonianGalerkin::default())
        .try_run(0.0, initial(), 0.1, 1.0, &RunOptions::default(), &mut ())
        .unwrap_err();
    assert!(
        matches!(failure.error, Error::NonFinite { .. }),
        "{:?}",
        failure.error
    );
    let partial = failure.partial.expect("the steps before t = 0.5 are kept");
    assert!(partial.last.t <= 0.5 + 1e-12, "{}", partial.last.t);
    assert!(partial.last.q[0].is_finite());
}
