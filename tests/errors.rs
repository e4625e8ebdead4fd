//! Bad input gives typed errors naming the problem, never a panic.

use nalgebra::{DVector, SVector, U1, U3};
use svi::model::local::{LocalLagrangian, Terms};
use svi::{Error, Integrator, SpectralCollocation, Svi};
use svi_models::{HarmonicOscillator, Kepler};

fn kepler_start() -> (SVector<f64, 2>, SVector<f64, 2>) {
    (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]))
}

fn invalid_name(error: Error) -> String {
    match error {
        Error::InvalidParameter { name, .. } => name,
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

#[test]
fn bad_steps_and_spans_are_rejected() {
    let integrator = Integrator::new(HarmonicOscillator::default(), Svi::default());
    let q = SVector::from([0.0]);
    let v = SVector::from([1.0]);
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let error = integrator
            .run_from_velocity(0.0, q, v, h, 1.0, &mut ())
            .unwrap_err();
        assert_eq!(invalid_name(error), "h");
    }
    let error = integrator
        .run_from_velocity(0.0, q, v, 0.1, 0.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "t_end");
    let error = integrator
        .run_from_velocity(1.0, q, v, 0.1, -1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "t_end");
    let error = integrator
        .run_from_velocity(f64::NAN, q, v, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "t0");
    let error = integrator
        .run_from_velocity(0.0, q, v, 1e-20, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "h");
}

#[test]
fn non_finite_initial_states_are_rejected() {
    let integrator = Integrator::new(Kepler::default(), Svi::default());
    let (q, v) = kepler_start();
    let bad = SVector::from([f64::NAN, 0.0]);
    let error = integrator
        .run_from_velocity(0.0, bad, v, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "initial position[0]");
    let bad = SVector::from([0.0, f64::INFINITY]);
    let error = integrator
        .run_from_momentum(0.0, q, bad, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "initial momentum[1]");
}

#[test]
fn out_of_range_options_are_rejected() {
    let (q, v) = kepler_start();
    for points in [0usize, 1, 100_000] {
        let integrator = Integrator::new(Kepler::default(), Svi::new(points));
        let error = integrator
            .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
            .unwrap_err();
        assert_eq!(invalid_name(error), "points");
        let integrator = Integrator::new(Kepler::default(), SpectralCollocation::new(points));
        let error = integrator
            .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
            .unwrap_err();
        assert_eq!(invalid_name(error), "points");
    }
    let integrator = Integrator::new(Kepler::default(), Svi::new(4).with_quadrature(0));
    let error = integrator
        .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(invalid_name(error), "quadrature");
}

#[test]
fn newton_failure_is_reported_with_step_time_and_residual() {
    // One Newton iteration cannot converge on Kepler's nonlinear step.
    let (q, v) = kepler_start();
    let integrator = Integrator::new(Kepler::default(), Svi::new(5).with_max_iterations(1));
    match integrator
        .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
        .unwrap_err()
    {
        Error::NonConvergence {
            step,
            t,
            iterations,
            residual,
        } => {
            assert_eq!((step, t, iterations), (0, 0.0, 1));
            assert!(residual > 0.0 && residual.is_finite());
        }
        other => panic!("unexpected {other:?}"),
    }
}

/// A degenerate Lagrangian with no kinetic term: its mass matrix is singular.
struct Degenerate;

impl svi::Lagrangian<U1> for Degenerate {
    fn lagrangian<D: svi::Scalar>(&self, _t: D, q: &SVector<D, 1>, _v: &SVector<D, 1>) -> D {
        q[0] * q[0]
    }
}

#[test]
fn singular_systems_are_reported_not_panicked_on() {
    let q = SVector::from([1.0]);
    let v = SVector::from([0.0]);
    let integrator = Integrator::new(Degenerate, SpectralCollocation::new(4));
    let error = integrator
        .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert_eq!(error, Error::SingularMatrix { step: 0, t: 0.0 });
    // The SVI step itself is solvable here (the action is a quadratic form in the nodes),
    // but the final (q, p) cannot be completed with a velocity: the inverse Legendre map
    // reports the singular mass matrix at the final time.
    let integrator = Integrator::new(Degenerate, Svi::new(4));
    let error = integrator
        .run_from_momentum(0.0, q, v, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert!(
        matches!(error, Error::LegendreMap { t, .. } if t == 1.0),
        "{error:?}"
    );
}

/// A particle declared to have a constant mass matrix, with a term linear in q̇ (`drift`)
/// and a q-dependent mass (`stiffening`) that break the declaration.
struct Declared {
    drift: f64,
    stiffening: f64,
}

impl svi::Lagrangian<U1> for Declared {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: svi::Structure = svi::Structure::ConstantMass;
    fn lagrangian<D: svi::Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        let mass = q[0] * q[0] * self.stiffening + 1.0;
        mass * v[0] * v[0] * 0.5 + v[0] * self.drift - q[0] * q[0] * 0.5
    }
}

#[test]
fn a_wrong_constant_mass_declaration_is_an_error_not_a_wrong_result() {
    // L = ½q̇² + c q̇ − ½q² has L_qv = 0 and a constant L_vv, but p = q̇ + c: the fixed-point
    // iteration and q̇ = M⁻¹p assume p = Mq̇, so the declaration is refused by name.
    let (q, v) = (SVector::from([0.5]), SVector::from([0.2]));
    for (drift, stiffening, named) in [(0.3, 0.0, "∂L/∂q̇ = 3e-1"), (0.0, 1.0, "∂²L/∂q∂q̇")]
    {
        let integrator = Integrator::new(Declared { drift, stiffening }, Svi::new(4));
        let error = integrator
            .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
            .unwrap_err();
        let message = error.to_string();
        assert_eq!(invalid_name(error), "structure");
        assert!(message.contains(named), "{message}");
    }
    // The true declaration runs.
    let integrator = Integrator::new(
        Declared {
            drift: 0.0,
            stiffening: 0.0,
        },
        Svi::new(4),
    );
    assert!(
        integrator
            .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
            .is_ok()
    );
}

/// Three particles declared constant-mass, breaking the declaration with a first mass that
/// grows with q₀² (`stiffening`) or a term q₀q̇₁ linear in q̇ (`drift`). At N = 3 the Hessian
/// blocks take vector sweeps that trust the declaration for the mixed block, so the check has
/// to see M move with q, and ∂L/∂q̇ at q̇ = 0 away from q₀ = 0.
#[derive(Clone, Copy)]
struct Declared3 {
    stiffening: f64,
    drift: f64,
}

impl svi::Lagrangian<U3> for Declared3 {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: svi::Structure = svi::Structure::ConstantMass;
    fn lagrangian<D: svi::Scalar>(&self, _t: D, q: &SVector<D, 3>, v: &SVector<D, 3>) -> D {
        let mass = q[0] * q[0] * self.stiffening + 1.0;
        (mass * v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - q[0] * q[0] - q[1] * q[1]) * 0.5
            + q[0] * v[1] * self.drift
    }
}

/// The same particles as one term of width 3 (a sum of local terms of run-time size).
struct Declared3Terms(Declared3);

impl LocalLagrangian for Declared3Terms {
    type Width = nalgebra::Const<3>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: svi::Structure = svi::Structure::ConstantMass;
    fn dimension(&self) -> usize {
        3
    }
    fn term_count(&self) -> usize {
        1
    }
    fn indices(&self, _: usize) -> [usize; 3] {
        [0, 1, 2]
    }
    fn term<D: svi::Scalar>(&self, _: usize, t: D, q: &SVector<D, 3>, v: &SVector<D, 3>) -> D {
        svi::Lagrangian::lagrangian(&self.0, t, q, v)
    }
}

#[test]
fn a_mass_declared_constant_that_moves_with_q_is_refused_at_any_size() {
    // Started at q₀ = 0, where the drift term's ∂L/∂q̇₁ = q₀ vanishes.
    let (q, v) = (
        SVector::from([0.0, -0.3, 0.2]),
        SVector::from([0.2, 0.1, -0.4]),
    );
    let (qd, vd) = (
        DVector::from_column_slice(q.as_slice()),
        DVector::from_column_slice(v.as_slice()),
    );
    for (model, named) in [
        (
            Declared3 {
                stiffening: 1.0,
                drift: 0.0,
            },
            "by 1e0 with q,",
        ),
        (
            Declared3 {
                stiffening: 0.0,
                drift: 1.0,
            },
            "∂L/∂q̇ = 1e0",
        ),
    ] {
        let errors = [
            Integrator::new(model, Svi::new(4))
                .run_from_velocity(0.0, q, v, 0.1, 1.0, &mut ())
                .unwrap_err(),
            Integrator::new(Terms(Declared3Terms(model)), Svi::new(4))
                .run_from_velocity(0.0, qd.clone(), vd.clone(), 0.1, 1.0, &mut ())
                .unwrap_err(),
        ];
        for error in errors {
            let message = error.to_string();
            assert_eq!(invalid_name(error), "structure");
            assert!(message.contains(named), "{message}");
        }
    }
}
