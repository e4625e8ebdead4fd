//! Time-reparametrised variational integrators (Leok §5.6, the Poincaré transformation):
//! fixed steps in τ, dt = g(q) dτ. References: the exact Kepler orbit (`KeplerOrbit`,
//! Kepler's equation), the symplectic form ΦᵀJΦ = J of the step's AD Jacobian.

use nalgebra::{SVector, U1, U2};
use std::ops::ControlFlow;
use svi::model::reparametrized::{Force, Monitor, MonitorSpec, Potential, Reparametrized, Sundman};
use svi::observer::Observer;
use svi::solve::{SolveOptions, Span};
use svi::stepping::reparam::solve_reparametrized;
use svi::{
    Defaults, Error, ExactSolution, Initial, Integrator, Lagrangian, LagrangianExt, Method,
    PhasePoint, Scalar, State, StormerVerlet, Svi,
};
use svi_models::{HarmonicOscillator, Kepler};

/// Kepler e = 0.9 from its pericentre: (model, q0, v0).
fn eccentric() -> (Kepler, SVector<f64, 2>, SVector<f64, 2>) {
    let model = Kepler::new(0.9).unwrap();
    let (_, q0, v0) = model.initial_state();
    (model, q0, v0)
}

/// Position error at the end of a reparametrised run of `method` over [0, t_end] with Δτ.
fn final_error<M: Method<U2> + Clone>(
    method: M,
    alpha: f64,
    dtau: f64,
    t_end: f64,
) -> (f64, usize) {
    let (model, q0, v0) = eccentric();
    let solution = solve_reparametrized(
        model,
        method,
        Sundman { alpha },
        &Span::new(0.0, t_end),
        Initial::Velocity { q: q0, v: v0 },
        &SolveOptions::fixed_step(dtau),
    )
    .unwrap();
    assert_eq!(solution.last.t, t_end);
    let (q, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
    ((solution.last.q - q).norm(), solution.statistics.steps)
}

#[test]
fn svi_on_an_eccentric_kepler_orbit_meets_the_exact_solution() {
    // Ten periods of e = 0.9 (T = 20π): the fixed-step SVI at h = 0.05 has error 1e-3 here.
    for (alpha, dtau) in [(1.5, 0.05), (1.0, 0.1)] {
        let (error, steps) = final_error(
            Svi::new(7).with_quadrature(6),
            alpha,
            dtau,
            20.0 * std::f64::consts::PI,
        );
        // Measured: 3.0e-12 in 1674 steps (α = 1.5), 2.9e-12 in 629 (α = 1).
        assert!(error < 1e-10, "α = {alpha}: {error:e} in {steps} steps");
    }
}

#[test]
fn the_order_of_the_method_is_retained() {
    // Halving Δτ divides the final error by 2^r: Störmer–Verlet r = 2, SVI with 3 points
    // r = 4, over two periods.
    let t_end = 4.0 * std::f64::consts::PI;
    for (name, coarse, fine) in [
        (
            "verlet",
            final_error(StormerVerlet::default(), 1.5, 0.004, t_end).0,
            final_error(StormerVerlet::default(), 1.5, 0.002, t_end).0,
        ),
        (
            "svi:3",
            final_error(Svi::new(3), 1.5, 0.04, t_end).0,
            final_error(Svi::new(3), 1.5, 0.02, t_end).0,
        ),
    ] {
        let order = (coarse / fine).log2();
        let expected = if name == "verlet" { 2.0 } else { 4.0 };
        assert!(
            (order - expected).abs() < 0.1,
            "{name}: {coarse:e} -> {fine:e}, order {order}"
        );
    }
}

#[test]
fn the_tau_step_is_symplectic() {
    let (model, q0, v0) = eccentric();
    let monitor = Sundman { alpha: 1.5 };
    let energy = model.energy(0.0, &q0, &v0);
    let tilde = Reparametrized::new(&model, &monitor, energy).unwrap();
    let state = State {
        q: SVector::from([0.3, 0.2]),
        y: SVector::from([-1.0, 2.0]),
    };
    for (name, error) in [
        (
            "svi:5",
            Integrator::new(tilde, Svi::new(5))
                .tangent_map(0.0, &state, 0.1)
                .unwrap()
                .1
                .symplecticity_error(),
        ),
        (
            "verlet",
            Integrator::new(tilde, StormerVerlet::default())
                .tangent_map(0.0, &state, 0.1)
                .unwrap()
                .1
                .symplecticity_error(),
        ),
    ] {
        println!("{name}: symplecticity error {error:e}");
        assert!(error < 1e-12, "{name}: {error:e}");
    }
}

/// The largest |H − E₀| over the first and the second half (in time) of the run.
struct EnergyHalves {
    energy: f64,
    half: f64,
    worst: [f64; 2],
}

impl Observer<Kepler, PhasePoint<U2>> for EnergyHalves {
    fn observe(&mut self, _: &Kepler, _: usize, point: &PhasePoint<U2>) -> ControlFlow<()> {
        let error = (Kepler::energy(&point.q, &point.v) - self.energy).abs();
        let half = usize::from(point.t >= self.half);
        self.worst[half] = self.worst[half].max(error);
        ControlFlow::Continue(())
    }
}

#[test]
fn the_energy_error_stays_bounded() {
    // Störmer–Verlet in τ over 100 periods of e = 0.9: no drift between the halves.
    let (model, q0, v0) = eccentric();
    let t_end = 200.0 * std::f64::consts::PI;
    let mut observer = EnergyHalves {
        energy: Kepler::energy(&q0, &v0),
        half: 0.5 * t_end,
        worst: [0.0; 2],
    };
    let solution = Integrator::new(model, StormerVerlet::default())
        .try_solve_reparametrized(
            &Sundman { alpha: 1.5 },
            &Span::new(0.0, t_end),
            Initial::Velocity { q: q0, v: v0 },
            &SolveOptions::fixed_step(0.01),
            &mut observer,
        )
        .unwrap();
    let [first, second] = observer.worst;
    assert!(
        first < 2e-4 && second < 1.1 * first,
        "{first:e} then {second:e}"
    );
    // The physical steps span two orders of magnitude (2e-4 at pericentre, 2.6e-2 at
    // apocentre).
    let adaptivity = solution.adaptivity;
    assert!(
        adaptivity.max_step > 100.0 * adaptivity.min_step,
        "{adaptivity:?}"
    );
}

/// g = −1: not a monitor.
struct Negative;
impl Monitor<U2> for Negative {
    fn monitor<D: Scalar, L: Lagrangian<U2> + ?Sized>(&self, _model: &L, q: &SVector<D, 2>) -> D {
        q[0] * 0.0 - 1.0
    }
}

#[test]
fn a_monitor_that_is_not_positive_is_a_typed_error() {
    let (model, q0, v0) = eccentric();
    let error = solve_reparametrized(
        model,
        StormerVerlet::default(),
        Negative,
        &Span::new(0.0, 1.0),
        Initial::Velocity { q: q0, v: v0 },
        &SolveOptions::fixed_step(0.01),
    )
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "monitor"),
        "{error}"
    );
}

#[test]
fn output_times_inside_steps_come_from_the_step_polynomial() {
    // Two periods of e = 0.9, states at times that fall inside τ-steps, near the
    // pericentre and the apocentre.
    let (model, q0, v0) = eccentric();
    let times = [0.0, 0.013, 3.0, 6.2, 6.3, 4.0 * std::f64::consts::PI];
    let solution = solve_reparametrized(
        model,
        Svi::new(7).with_quadrature(6),
        Sundman { alpha: 1.5 },
        &Span::times(&times),
        Initial::Velocity { q: q0, v: v0 },
        &SolveOptions::fixed_step(0.05),
    )
    .unwrap();
    assert_eq!(solution.points.len(), times.len());
    for (point, &t) in solution.points.iter().zip(&times) {
        assert_eq!(point.t, t);
        let (q, v) = model.exact_solution(0.0, &q0, &v0, t).unwrap();
        let error = (point.q - q).norm() + (point.v - v).norm() / v.norm();
        // The polynomial of a step (degree 6) is less accurate inside than at its ends.
        assert!(error < 1e-8, "t = {t}: {error:e}");
        assert!((point.p - point.v).norm() < 1e-12, "p = q̇ for Kepler");
    }
}

#[test]
fn the_last_step_lands_on_the_horizon_near_a_close_approach() {
    // Horizons just before and after the pericentre at t = 2π, where g is small at the end of
    // an overshooting step (a plain Newton step on Δτ left the bracket there and took a step
    // of size 0).
    let (model, q0, v0) = eccentric();
    for k in 0..40 {
        let t_end = std::f64::consts::TAU - 0.2 + 0.01 * f64::from(k);
        let solution = solve_reparametrized(
            model,
            Svi::new(5),
            Sundman { alpha: 1.5 },
            &Span::new(0.0, t_end),
            Initial::Velocity { q: q0, v: v0 },
            &SolveOptions::fixed_step(0.2),
        )
        .unwrap_or_else(|error| panic!("t_end = {t_end}: {error}"));
        assert_eq!(solution.last.t, t_end);
        let (q, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
        assert!((solution.last.q - q).norm() < 1e-4, "t_end = {t_end}");
    }
}

#[test]
fn the_force_monitor_of_kepler_is_sundman_three_halves() {
    // Kepler's force at rest is |∂L/∂q| = 1/r² (μ = 1), so |F|^(−3/4) = r^(3/2): the force
    // monitor, derived from L by nested dual numbers, must take the steps of sundman:1.5 —
    // the same final state to round-off over two periods of e = 0.9.
    let (model, q0, v0) = eccentric();
    let t_end = 4.0 * std::f64::consts::PI;
    let run = |monitor: MonitorSpec| {
        solve_reparametrized(
            model,
            Svi::new(7).with_quadrature(6),
            monitor,
            &Span::new(0.0, t_end),
            Initial::Velocity { q: q0, v: v0 },
            &SolveOptions::fixed_step(0.05),
        )
        .unwrap()
    };
    let sundman = run(MonitorSpec::Sundman(Sundman { alpha: 1.5 }));
    let force = run(MonitorSpec::Force(Force { beta: 0.75 }));
    assert_eq!(force.statistics.steps, sundman.statistics.steps);
    let difference =
        (force.last.q - sundman.last.q).norm() + (force.last.v - sundman.last.v).norm();
    assert!(difference < 1e-11, "{difference:e}");
    // And both meet the exact orbit.
    let (q, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
    let error = (force.last.q - q).norm();
    assert!(error < 1e-9, "{error:e}");
}

#[test]
fn the_force_monitor_at_an_equilibrium_is_a_typed_error() {
    // The oscillator starts at q = 0, where the force vanishes: g = |F|^(−β) = ∞.
    let model = HarmonicOscillator::default();
    let error = solve_reparametrized(
        model,
        StormerVerlet::default(),
        Force { beta: 0.5 },
        &Span::new(0.0, 1.0),
        Initial::Velocity {
            q: SVector::from([0.0]),
            v: SVector::from([1.0]),
        },
        &SolveOptions::fixed_step(0.01),
    )
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "monitor"),
        "{error}"
    );
}

/// An oscillator whose stiffness grows with t: L = ½q̇² − ½(1 + t)q² (time-dependent).
#[derive(Clone, Copy)]
struct Stiffening;

impl Lagrangian<U1> for Stiffening {
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - (t + 1.0) * q[0] * q[0]) * 0.5
    }
}

/// Reparametrisation needs an autonomous, unforced model: a time-dependent and a forced
/// (damped) oscillator are refused with the reason, by every method (for Störmer–Verlet also
/// with the potential monitor, whose splitting is taken before anything else).
#[test]
fn time_dependent_and_forced_models_are_refused_with_the_reason() {
    fn refusal<L: Lagrangian<U1> + Copy, M: Method<U1> + Clone>(model: L, method: M) -> String {
        let initial = Initial::Velocity {
            q: SVector::from([1.0]),
            v: SVector::from([0.0]),
        };
        let (span, options) = (Span::new(0.0, 1.0), SolveOptions::fixed_step(0.1));
        let sundman = Sundman { alpha: 1.0 };
        let error = solve_reparametrized(model, method.clone(), sundman, &span, initial, &options)
            .unwrap_err();
        let potential = Potential;
        let other =
            solve_reparametrized(model, method, potential, &span, initial, &options).unwrap_err();
        assert_eq!(error.to_string(), other.to_string());
        assert!(
            matches!(&error, Error::InvalidParameter { name, .. } if name == "adapt"),
            "{error}"
        );
        error.to_string()
    }
    let damped = svi_models::DampedOscillator::default();
    for (message, reason) in [
        (
            refusal(Stiffening, StormerVerlet::default()),
            "an autonomous Lagrangian",
        ),
        (refusal(Stiffening, Svi::new(4)), "an autonomous Lagrangian"),
        (
            refusal(damped, StormerVerlet::default()),
            "an unforced model",
        ),
        (refusal(damped, Svi::new(4)), "an unforced model"),
    ] {
        assert!(
            message.contains(&format!("reparam needs {reason}")),
            "{message}"
        );
    }
}
