//! The logarithmic-Hamiltonian splitting (potential monitor g = 1/U with Störmer–Verlet or its
//! compositions) and the compositions as fixed-step methods. References: the exact Kepler
//! orbit (Kepler's equation), exact conservation of energy and angular momentum on Kepler
//! (Mikkola & Tanikawa 1999: the leapfrog of the logarithmic Hamiltonian follows the exact
//! ellipse), observed orders.

use nalgebra::{SVector, U2};
use std::ops::ControlFlow;
use svi::model::reparametrized::{MonitorSpec, Potential};
use svi::observer::Observer;
use svi::solve::{SolveOptions, Span};
use svi::stepping::reparam::solve_reparametrized;
use svi::{
    Composition, Defaults, Error, ExactSolution, Initial, Integrator, Method, PhasePoint, Scheme,
    StormerVerlet,
};
use svi_models::{HarmonicOscillator, Kepler};

const PERIOD: f64 = std::f64::consts::TAU;

/// Kepler e = 0.9 from its pericentre: (model, q0, v0).
fn eccentric() -> (Kepler, SVector<f64, 2>, SVector<f64, 2>) {
    let model = Kepler::new(0.9).unwrap();
    let (_, q0, v0) = model.initial_state();
    (model, q0, v0)
}

/// Position error at `t_end` of the potential-monitor run of `method` with Δτ, and its steps.
fn final_error<M: Method<U2> + Clone>(method: M, dtau: f64, t_end: f64) -> (f64, usize) {
    let (model, q0, v0) = eccentric();
    let solution = solve_reparametrized(
        model,
        method,
        Potential,
        &Span::new(0.0, t_end),
        Initial::Velocity { q: q0, v: v0 },
        &SolveOptions::fixed_step(dtau),
    )
    .unwrap();
    assert_eq!(solution.last.t, t_end);
    let (q, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
    ((solution.last.q - q).norm(), solution.statistics.steps)
}

/// The largest errors of energy and angular momentum over every τ-step.
struct Invariants {
    energy: f64,
    momentum: f64,
    worst: [f64; 2],
}

fn angular_momentum(point: &PhasePoint<U2>) -> f64 {
    point.q[0] * point.p[1] - point.q[1] * point.p[0]
}

impl Observer<Kepler, PhasePoint<U2>> for Invariants {
    fn observe(&mut self, _: &Kepler, _: usize, point: &PhasePoint<U2>) -> ControlFlow<()> {
        let energy = (Kepler::energy(&point.q, &point.v) - self.energy).abs();
        let momentum = (angular_momentum(point) - self.momentum).abs();
        self.worst[0] = self.worst[0].max(energy);
        self.worst[1] = self.worst[1].max(momentum);
        ControlFlow::Continue(())
    }
}

#[test]
fn the_leapfrog_follows_the_exact_ellipse() {
    // 100 periods of e = 0.9 with a coarse τ-step: the time along the orbit is off by a
    // percent, the orbit itself is exact (energy and angular momentum to round-off).
    let (model, q0, v0) = eccentric();
    let mut observer = Invariants {
        energy: Kepler::energy(&q0, &v0),
        momentum: q0[0] * v0[1] - q0[1] * v0[0],
        worst: [0.0; 2],
    };
    let solution = Integrator::new(model, StormerVerlet::default())
        .try_solve_reparametrized(
            &Potential,
            &Span::new(0.0, 100.0 * PERIOD),
            Initial::Velocity { q: q0, v: v0 },
            &SolveOptions::fixed_step(0.1),
            &mut observer,
        )
        .unwrap();
    let [energy, momentum] = observer.worst;
    // Measured: 5e-15 and 3e-15 over 6300 steps.
    assert!(
        energy < 1e-13 && momentum < 1e-13,
        "energy {energy:e}, angular momentum {momentum:e}"
    );
    // One gradient per step, none to start: explicit.
    let statistics = solution.statistics;
    assert_eq!(statistics.iterations, 0);
    assert!(
        statistics.evaluations <= statistics.steps + 40,
        "{statistics:?}"
    );
    // The physical steps follow g = 1/U = r: r ranges over [0.1, 1.9].
    let adaptivity = solution.adaptivity;
    assert!(
        adaptivity.max_step > 15.0 * adaptivity.min_step,
        "{adaptivity:?}"
    );
}

#[test]
fn the_compositions_reach_their_orders() {
    // Halving Δτ divides the final error by 2^p over ten periods of e = 0.9.
    let t_end = 10.0 * PERIOD;
    let verlet = [
        final_error(StormerVerlet::default(), 0.02, t_end).0,
        final_error(StormerVerlet::default(), 0.01, t_end).0,
    ];
    let cases = [
        (2.0, verlet),
        (
            4.0,
            [0.1, 0.05].map(|dtau| final_error(Composition::new(Scheme::Yoshida4), dtau, t_end).0),
        ),
        (
            6.0,
            [0.4, 0.2].map(|dtau| final_error(Composition::new(Scheme::KahanLi6), dtau, t_end).0),
        ),
        (
            8.0,
            [0.8, 0.4].map(|dtau| final_error(Composition::new(Scheme::KahanLi8), dtau, t_end).0),
        ),
    ];
    for (expected, [coarse, fine]) in cases {
        let order = (coarse / fine).log2();
        assert!(
            (order - expected).abs() < 0.3,
            "order {expected}: {coarse:e} -> {fine:e}, observed {order}"
        );
    }
}

#[test]
fn kahan_li8_meets_1e9_over_318_orbits() {
    // The #17 setting: T = 2000 on e = 0.9. Measured 6e-10 at Δτ = 0.2 (10003 steps).
    let (error, steps) = final_error(Composition::new(Scheme::KahanLi8), 0.2, 2000.0);
    assert!(error < 1e-9, "{error:e} in {steps} steps");
}

#[test]
fn compositions_as_fixed_step_methods_reach_their_orders() {
    // Kepler e = 0.5 over two periods with fixed physical steps.
    let model = Kepler::new(0.5).unwrap();
    let (_, q0, v0) = model.initial_state();
    let t_end = 2.0 * PERIOD;
    let (exact, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
    let error = |scheme: Scheme, steps: usize| {
        let run = Integrator::new(model, Composition::new(scheme))
            .run_from_velocity(0.0, q0, v0, t_end / steps as f64, t_end, &mut ())
            .unwrap();
        (run.last.q - exact).norm()
    };
    for (scheme, steps) in [
        (Scheme::Yoshida4, 400),
        (Scheme::KahanLi6, 200),
        (Scheme::KahanLi8, 100),
    ] {
        let (coarse, fine) = (error(scheme, steps), error(scheme, 2 * steps));
        let order = (coarse / fine).log2();
        let expected = scheme.order() as f64;
        assert!(
            (order - expected).abs() < 0.4,
            "{scheme:?}: {coarse:e} -> {fine:e}, observed {order}"
        );
        let fractions = scheme.fractions();
        assert!((fractions.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}

#[test]
fn a_composition_step_is_symplectic() {
    let (model, q0, v0) = eccentric();
    let integrator = Integrator::new(model, Composition::new(Scheme::KahanLi6));
    let state = svi::State { q: q0, y: v0 };
    let method = integrator.method();
    let mut workspace = Method::<U2>::workspace(method, &model, 0.01).unwrap();
    let (_, tangent, _) = method
        .tangent_map(&model, &mut workspace, 0.0, 0.01, &state)
        .unwrap();
    let error = tangent.symplecticity_error();
    assert!(error < 1e-10, "{error:e}");
}

#[test]
fn a_potential_that_is_not_below_zero_is_a_typed_error() {
    // The oscillator's U = −V = −q²/2 ≤ 0.
    let error = solve_reparametrized(
        HarmonicOscillator::default(),
        StormerVerlet::default(),
        Potential,
        &Span::new(0.0, 1.0),
        Initial::Velocity {
            q: SVector::from([1.0]),
            v: SVector::from([0.0]),
        },
        &SolveOptions::fixed_step(0.01),
    )
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, reason } if name == "monitor" && reason.contains("U(q)")),
        "{error}"
    );
}

#[test]
fn output_inside_the_span_is_a_typed_error() {
    let (model, q0, v0) = eccentric();
    let error = solve_reparametrized(
        model,
        StormerVerlet::default(),
        Potential,
        &Span::times(&[0.0, 1.0, 2.0]),
        Initial::Velocity { q: q0, v: v0 },
        &SolveOptions::fixed_step(0.01),
    )
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "output_times"),
        "{error}"
    );
}

#[test]
fn the_potential_monitor_is_named_potential() {
    let spec: MonitorSpec = "potential".parse().unwrap();
    assert_eq!(spec, MonitorSpec::Potential(Potential));
    assert_eq!(spec.to_string(), "potential");
    assert!("potential:2".parse::<MonitorSpec>().is_err());
}

#[test]
fn a_step_that_runs_away_is_a_non_finite_state_not_a_monitor_error() {
    // Δτ = 1e300: the first drift throws q to ~1e300, where U underflows to zero or the
    // kinetic energy overflows.
    let (model, q0, v0) = eccentric();
    let failure = Integrator::new(model, StormerVerlet::default())
        .try_solve_reparametrized(
            &Potential,
            &Span::new(0.0, 1.0),
            Initial::Velocity { q: q0, v: v0 },
            &SolveOptions::fixed_step(1e300),
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(failure.error, Error::NonFinite { step: 0, .. }),
        "{}",
        failure.error
    );
    // The run up to the last good state: the initial one.
    let partial = failure.partial.unwrap();
    assert_eq!(partial.last.q, q0);
}
