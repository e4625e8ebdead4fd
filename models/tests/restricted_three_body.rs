//! The restricted three-body problem integrated by SVI: at μ = 0 against the Kepler orbit
//! seen in the rotating frame (an independent closed form, [`svi_models::KeplerOrbit`]
//! rotated by −t), and the Jacobi constant over a long run at the Sun–Jupiter mass ratio.

use std::f64::consts::TAU;

use nalgebra::{SVector, U2};
use svi::observer::{EnergyError, InvariantError, Trajectory};
use svi::{Defaults, Initial, Integrator, Lagrangian, Scalar, Structure, Svi};
use svi_models::{KeplerOrbit, RestrictedThreeBody};

/// The inertial Kepler orbit (G M = 1) through the model's initial state, rotated by −t into
/// the frame of the primaries: written here from the orbit's inertial state, not through
/// the model's `ExactSolution`.
fn kepler_in_rotating_frame(
    q0: &SVector<f64, 2>,
    v0: &SVector<f64, 2>,
    t: f64,
) -> (SVector<f64, 2>, SVector<f64, 2>) {
    // At t = 0 the frames coincide; the inertial velocity is q̇ + ω × q.
    let inertial_v0 = SVector::from([v0[0] - q0[1], v0[1] + q0[0]]);
    let orbit = KeplerOrbit::from_state(q0, &inertial_v0).expect("a bound orbit");
    let (q, v) = orbit.state_after(t);
    let (sin, cos) = t.sin_cos();
    let back =
        |w: SVector<f64, 2>| SVector::from([cos * w[0] + sin * w[1], -sin * w[0] + cos * w[1]]);
    (back(q), back(SVector::from([v[0] + q[1], v[1] - q[0]])))
}

#[test]
fn mu_zero_is_kepler_motion_in_the_rotating_frame() {
    let model = RestrictedThreeBody {
        mu: 0.0,
        a: 0.8,
        e: 0.3,
    };
    let (t0, q0, v0) = model.initial_state();
    let (h, t_end) = (0.05, 10.0 * TAU);
    let integrator = Integrator::new(model, Svi::new(6));
    let mut trajectory = Trajectory::new();
    integrator
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            h,
            t_end,
            &mut trajectory,
        )
        .unwrap();
    let mut worst: f64 = 0.0;
    for point in &trajectory.points {
        let (q, v) = kepler_in_rotating_frame(&q0, &v0, point.t);
        worst = worst.max((point.q - q).amax()).max((point.v - v).amax());
        // The model's own closed form agrees with this one.
        let (q_model, v_model) = svi::ExactSolution::exact_solution(&model, t0, &q0, &v0, point.t)
            .expect("μ = 0 has a closed form");
        assert!((q_model - q).amax() < 1e-12 && (v_model - v).amax() < 1e-12);
    }
    println!("μ = 0, SVI 6, h = {h}, T = {t_end:.2}: max state error {worst:.2e}");
    let last = trajectory.points.last().unwrap();
    assert!((last.t - t_end).abs() < 1e-12, "{}", last.t);
    assert!(worst < 1e-9, "{worst:e}");
}

#[test]
fn svi_conserves_the_jacobi_constant() {
    let model = RestrictedThreeBody::default();
    let (t0, q0, v0) = model.initial_state();
    let jacobi = model.jacobi(&q0, &v0);
    let integrator = Integrator::new(model, Svi::new(6));
    let mut observers = (EnergyError::default(), InvariantError::default());
    let run = integrator
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            model.default_step(),
            100.0,
            &mut observers,
        )
        .unwrap();
    let (energy, invariant) = observers;
    println!(
        "SVI 6, h = {}, T = 100: Jacobi constant {jacobi:.15}, max |ΔC| {:.2e}, max |ΔE| {:.2e}",
        model.default_step(),
        invariant.max,
        energy.max
    );
    assert_eq!(invariant.initial, [jacobi]);
    // E = −C/2 along the run.
    assert!((energy.initial.unwrap() + 0.5 * jacobi).abs() < 1e-15);
    assert!(invariant.max < 1e-12, "{:e}", invariant.max);
    assert!(energy.max < 1e-12, "{:e}", energy.max);
    assert!((run.last.t - 100.0).abs() < 1e-12);
}

/// The model with a false [`Structure::ConstantMass`] declaration.
#[derive(Clone, Copy, Debug)]
struct DeclaredConstantMass(RestrictedThreeBody);

impl Lagrangian<U2> for DeclaredConstantMass {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        self.0.lagrangian(t, q, v)
    }
}

#[test]
fn a_constant_mass_declaration_is_refused() {
    let model = RestrictedThreeBody::default();
    let (t0, q0, v0) = model.initial_state();
    let integrator = Integrator::new(DeclaredConstantMass(model), Svi::new(6));
    let error = integrator
        .run(t0, Initial::Velocity { q: q0, v: v0 }, 0.02, 1.0, &mut ())
        .unwrap_err();
    println!("{error}");
    assert!(
        error.to_string().to_lowercase().contains("constant"),
        "{error}"
    );
}
