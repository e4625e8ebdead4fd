//! Failure behaviour and long-time energy behaviour under stress.
//!
//! Each failure (a nonlinear solve that does not converge, a non-finite state, a step beyond
//! the stability limit) is detected in the step where it happens and returned as a typed
//! error with step index and time, together with the run up to the last good state; the
//! observers keep everything seen before. The recovery policy retries a failed step with
//! half steps and keeps the time grid.

use nalgebra::{Const, SVector, U1, U2};
use svi::drift::EnergyWindows;
use svi::observer::{EnergyError, Every, Trajectory};
use svi::{
    Error, Initial, Integrator, Lagrangian, Recovery, RunFailure, RunOptions, Scalar,
    SpectralCollocation, StormerVerlet, Svi,
};
use svi_models::{HarmonicOscillator, Kepler};

/// L = q̇²/2 − √(1.05 − t) q²/2: an oscillator whose stiffness becomes NaN after t = 1.05.
#[derive(Debug, Clone, Copy)]
struct ExpiringSpring;

impl Lagrangian<U1> for ExpiringSpring {
    const TIME_DEPENDENT: bool = true;
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        let stiffness = (D::from(1.05) - t).sqrt();
        (v[0] * v[0] - stiffness * q[0] * q[0]) * 0.5
    }
}

fn kepler_start(e: f64) -> Initial<U2> {
    Initial::Velocity {
        q: SVector::from([1.0 - e, 0.0]),
        v: SVector::from([0.0, ((1.0 + e) / (1.0 - e)).sqrt()]),
    }
}

/// The failure's step index and start time.
fn step_and_time(error: &Error) -> (usize, f64) {
    match *error {
        Error::NonConvergence { step, t, .. }
        | Error::SingularMatrix { step, t }
        | Error::NonFinite { step, t, .. }
        | Error::Diverged { step, t, .. } => (step, t),
        ref other => panic!("no step context in {other:?}"),
    }
}

/// Checks shared by every failure: the partial run ends at the start of the failing step,
/// and the trajectory observer holds every step point up to it.
fn check_partial<const N: usize>(
    failure: &RunFailure<Const<N>>,
    trajectory: &Trajectory<Const<N>>,
    h: f64,
) {
    let (step, t) = step_and_time(&failure.error);
    let partial = failure.partial.as_ref().expect("a partial run");
    assert_eq!(partial.statistics.steps, step);
    assert_eq!(t, step as f64 * h);
    assert_eq!(partial.last.t, t);
    assert_eq!(trajectory.points.len(), step + 1);
    let last = trajectory.points.last().unwrap();
    assert_eq!(last.t, t);
    assert_eq!(last.q, partial.last.q);
    assert_eq!(last.p, partial.last.p);
    assert!(partial.state.is_finite());
}

#[test]
fn a_non_converging_solve_returns_the_run_so_far() {
    // Kepler e = 0.95 with h = 0.11: Newton (which takes over from the fixed point where it
    // stalls) does not converge at step 26.
    let integrator = Integrator::new(Kepler::new(0.95).unwrap(), Svi::new(6));
    let mut trajectory = Trajectory::new();
    let failure = integrator
        .try_run(
            0.0,
            kepler_start(0.95),
            0.11,
            200.0,
            &RunOptions::default(),
            &mut trajectory,
        )
        .unwrap_err();
    assert!(
        matches!(failure.error, Error::NonConvergence { iterations, .. } if iterations > 0),
        "{failure}"
    );
    check_partial(&failure, &trajectory, 0.11);
    let (step, _) = step_and_time(&failure.error);
    assert!(
        step > 10,
        "the first pericentre passage succeeds: {failure}"
    );
    // Everything computed before the failure is a valid orbit point: the angular momentum is
    // conserved to round-off up to the failure.
    let momentum = |p: &svi::PhasePoint<U2>| Kepler::angular_momentum(&p.q, &p.v);
    let first = momentum(&trajectory.points[0]);
    for point in &trajectory.points {
        assert!((momentum(point) - first).abs() < 1e-12);
    }
    // `run` reports the same error.
    let error = integrator
        .run(0.0, kepler_start(0.95), 0.11, 200.0, &mut ())
        .unwrap_err();
    assert_eq!(error, failure.error);
    let message = failure.to_string();
    assert!(message.contains("did not converge at step"), "{message}");
    assert!(message.contains("last good state"), "{message}");
}

#[test]
fn a_non_finite_state_is_caught_in_its_step() {
    // √(1.05 − t) is NaN after t = 1.05: the step [1.0, 1.1] (index 10) is the first to meet it.
    let start = Initial::Velocity {
        q: SVector::from([1.0]),
        v: SVector::from([0.0]),
    };
    let h = 0.1;
    for (name, failure) in [
        ("svi", {
            let mut trajectory = Trajectory::new();
            let failure = Integrator::new(ExpiringSpring, Svi::new(4))
                .try_run(0.0, start, h, 2.0, &RunOptions::default(), &mut trajectory)
                .unwrap_err();
            check_partial(&failure, &trajectory, h);
            failure
        }),
        ("verlet", {
            let mut trajectory = Trajectory::new();
            let failure = Integrator::new(ExpiringSpring, StormerVerlet::default())
                .try_run(0.0, start, h, 2.0, &RunOptions::default(), &mut trajectory)
                .unwrap_err();
            check_partial(&failure, &trajectory, h);
            failure
        }),
        ("sc", {
            let mut trajectory = Trajectory::new();
            let failure = Integrator::new(ExpiringSpring, SpectralCollocation::new(4))
                .try_run(0.0, start, h, 2.0, &RunOptions::default(), &mut trajectory)
                .unwrap_err();
            check_partial(&failure, &trajectory, h);
            failure
        }),
    ] {
        // SC meets the NaN when it inverts the mass matrix for the starting acceleration and
        // reports it as a singular matrix; the others as a non-finite value.
        match name {
            "sc" => assert!(
                matches!(failure.error, Error::SingularMatrix { step: 10, t } if t == 1.0),
                "{failure}"
            ),
            _ => assert!(
                matches!(failure.error, Error::NonFinite { step: 10, t, .. } if t == 1.0),
                "{name}: {failure}"
            ),
        }
        // Up to t = 1 the solution is close to cos-like motion: the last good state is finite
        // and bounded.
        let partial = failure.partial.unwrap();
        assert!(partial.last.q[0].abs() <= 1.0 + 1e-9);
    }
}

/// One Störmer–Verlet step of q̈ = −q in (q, p): the independent reference of the growth.
fn verlet_step(q: f64, p: f64, h: f64) -> (f64, f64) {
    let half = p - 0.5 * h * q;
    let q = q + h * half;
    (q, half - 0.5 * h * q)
}

#[test]
fn a_step_beyond_the_stability_limit_is_caught_where_the_state_diverges() {
    // Störmer–Verlet on q̈ = −q is stable for h < 2; at h = 2.1 the amplification factor is
    // |λ| = (2.41 + √1.8081)/2 ≈ 1.877 per step.
    let integrator = Integrator::new(HarmonicOscillator::default(), StormerVerlet::default());
    let start = Initial::Momentum {
        q: SVector::from([1.0]),
        p: SVector::from([0.0]),
    };
    let (h, limit) = (2.1, 1e6);
    let (mut q, mut p) = (1.0, 0.0);
    let mut expected = 0;
    loop {
        (q, p) = verlet_step(q, p, h);
        if f64::max(q.abs(), p.abs()) > limit {
            break;
        }
        expected += 1;
    }
    assert!((20..=25).contains(&expected), "{expected}");
    let mut trajectory = Trajectory::new();
    let options = RunOptions::default().with_divergence_limit(limit);
    let failure = integrator
        .try_run(0.0, start, h, 1e5, &options, &mut trajectory)
        .unwrap_err();
    match failure.error {
        Error::Diverged {
            step,
            norm,
            limit: bound,
            ..
        } => {
            assert_eq!(step, expected);
            assert_eq!(bound, limit);
            assert!(norm > limit && norm < 2.0 * limit);
        }
        ref other => panic!("expected Diverged, got {other:?}"),
    }
    check_partial(&failure, &trajectory, h);
    // Without a limit the state overflows after ln(1.8e308)/ln(1.877) ≈ 1128 steps: caught
    // as a non-finite state in that step, the last good state still finite.
    let failure = integrator
        .try_run(0.0, start, h, 1e5, &RunOptions::default(), &mut ())
        .unwrap_err();
    let (step, _) = step_and_time(&failure.error);
    assert!(matches!(failure.error, Error::NonFinite { .. }));
    assert!((1100..1160).contains(&step), "{step}");
    // Below the limit (h = 1.9) the same run stays bounded: Verlet conserves the modified
    // energy p²/2 + (1 − h²/4) q²/2 at the step points, so |q| ≤ 1 and |p| ≤ √(1 − h²/4).
    let mut trajectory = Trajectory::new();
    integrator
        .run(0.0, start, 1.9, 1.9e4, &mut trajectory)
        .unwrap();
    assert_eq!(trajectory.points.len(), 10_001);
    let bound = (1.0f64 - 1.9 * 1.9 / 4.0).sqrt();
    for point in &trajectory.points {
        assert!(point.q[0].abs() <= 1.0 + 1e-9, "{point:?}");
        assert!(point.p[0].abs() <= bound + 1e-9, "{point:?}");
    }
}

#[test]
fn recovery_halves_failed_steps_and_keeps_the_time_grid() {
    // The failing run of `a_non_converging_solve_returns_the_run_so_far`, with recovery.
    let integrator = Integrator::new(Kepler::new(0.95).unwrap(), Svi::new(6));
    let options = RunOptions::default().with_recovery(Recovery::HalveStep { max_halvings: 4 });
    let mut trajectory = Trajectory::new();
    let mut energy = EnergyError::default();
    let run = integrator
        .try_run(
            0.0,
            kepler_start(0.95),
            0.11,
            200.0,
            &options,
            &mut (&mut trajectory, &mut energy),
        )
        .unwrap();
    assert!(run.statistics.retries >= 1, "{:?}", run.statistics);
    assert_eq!(run.statistics.steps, 1819);
    assert_eq!(run.last.t, 200.0);
    assert_eq!(trajectory.points.len(), 1820);
    for (k, point) in trajectory.points.iter().enumerate() {
        assert_eq!(point.t, if k == 1819 { 200.0 } else { k as f64 * 0.11 });
    }
    // h = 0.11 does not resolve the pericentre of e = 0.95 (0.05 from the centre at speed 6):
    // recovery gets the run through, but the energy error is O(1). The angular momentum is
    // conserved through the recovered steps (each half step is itself a symplectic,
    // momentum-preserving step).
    assert!(energy.max.is_finite() && energy.max > 0.5, "{}", energy.max);
    let momentum = |p: &svi::PhasePoint<U2>| Kepler::angular_momentum(&p.q, &p.v);
    let first = momentum(&trajectory.points[0]);
    for point in &trajectory.points {
        assert!((momentum(point) - first).abs() < 1e-11);
    }
    // Zero halvings is no recovery.
    let options = RunOptions::default().with_recovery(Recovery::HalveStep { max_halvings: 0 });
    let failure = integrator
        .try_run(0.0, kepler_start(0.95), 0.11, 200.0, &options, &mut ())
        .unwrap_err();
    assert!(matches!(failure.error, Error::NonConvergence { .. }));
    assert_eq!(failure.partial.unwrap().statistics.retries, 0);
}

#[test]
fn recovery_does_not_hide_a_persistent_failure() {
    let integrator = Integrator::new(ExpiringSpring, StormerVerlet::default());
    let start = Initial::Velocity {
        q: SVector::from([1.0]),
        v: SVector::from([0.0]),
    };
    let options = RunOptions::default().with_recovery(Recovery::HalveStep { max_halvings: 3 });
    let mut trajectory = Trajectory::new();
    let failure = integrator
        .try_run(0.0, start, 0.1, 2.0, &options, &mut trajectory)
        .unwrap_err();
    // The full step fails, then its halves: 1 + 2 + 4 + ... retries, at most 2³ − 1 = 7,
    // and the state is that at the start of the failing step.
    assert!(matches!(failure.error, Error::NonFinite { step: 10, .. }));
    let partial = failure.partial.as_ref().unwrap();
    assert!((1..=7).contains(&partial.statistics.retries));
    check_partial(&failure, &trajectory, 0.1);
}

#[test]
fn invalid_run_options_are_rejected_before_the_first_step() {
    let integrator = Integrator::new(HarmonicOscillator::default(), Svi::default());
    let start = Initial::Velocity {
        q: SVector::from([1.0]),
        v: SVector::from([0.0]),
    };
    for options in [
        RunOptions::default().with_recovery(Recovery::HalveStep { max_halvings: 21 }),
        RunOptions::default().with_divergence_limit(f64::NAN),
        RunOptions::default().with_divergence_limit(-1.0),
        RunOptions::default().with_divergence_limit(0.0),
    ] {
        let failure = integrator
            .try_run(0.0, start, 0.1, 1.0, &options, &mut ())
            .unwrap_err();
        assert!(failure.partial.is_none());
        assert!(
            matches!(&failure.error, Error::InvalidParameter { name, .. }
                if name == "max_halvings" || name == "divergence_limit"),
            "{failure}"
        );
    }
}

/// Energy windows of `steps` steps of Kepler e = 0.5 with h = 0.2.
fn kepler_windows<M: svi::Method<U2>>(method: M, steps: usize) -> svi::drift::DriftFit {
    let integrator = Integrator::new(Kepler::new(0.5).unwrap(), method);
    let mut windows = Every::new(1, EnergyWindows::new(steps / 50));
    integrator
        .run(
            0.0,
            kepler_start(0.5),
            0.2,
            0.2 * steps as f64,
            &mut windows,
        )
        .unwrap();
    windows.inner.fit().unwrap()
}

#[test]
fn svi_energy_is_bounded_and_collocation_drifts_on_kepler() {
    // 2·10⁴ steps (T = 4000, about 640 orbits): the 10⁶-step version is `svi stress`.
    let svi = kepler_windows(Svi::new(6), 20_000);
    assert_eq!(svi.windows, 51);
    assert!(svi.drift.abs() < svi.amplitude, "{svi:?}");
    assert!(svi.max_error < 1e-9, "{svi:?}");
    let sc = kepler_windows(SpectralCollocation::new(6), 20_000);
    assert!(sc.drift.abs() > 10.0 * sc.amplitude, "{sc:?}");
    assert!(sc.slope < 0.0, "collocation loses energy on Kepler: {sc:?}");
    assert!(sc.max_error > 1e3 * svi.max_error);
}
