//! The rigid-body models on SO(3): registry, parameter validation, and that their
//! declarations hold — G-invariance of the free body, the symmetry axes (L unchanged under
//! R ↦ exp(θâ)R), and the invariants (conserved along the exact flow, checked by the
//! Euler–Poincaré right-hand side: d/dt of each declared quantity vanishes).

use nalgebra::{SMatrix, SVector};
use svi::Error;
use svi::lie_group::so3::{exp, hat};
use svi::lie_group::{RigidBodyExt, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries};
use svi_models::{RIGID_MODEL_NAMES, RigidModelVisitor, RigidZooModel, visit_rigid_model};

type Matrix3 = SMatrix<f64, 3, 3>;
type Vector3 = SVector<f64, 3>;

struct Name;

impl RigidModelVisitor for Name {
    type Output = &'static str;
    fn visit<M: RigidZooModel>(self, model: M) -> &'static str {
        model.name()
    }
}

#[test]
fn every_rigid_name_visits_the_model_of_that_name() {
    assert_eq!(
        RIGID_MODEL_NAMES,
        ["rigid-body", "heavy-top", "pendulum-3d"]
    );
    for &name in RIGID_MODEL_NAMES {
        assert_eq!(visit_rigid_model(name, Name), Some(name));
    }
    assert_eq!(visit_rigid_model("rigid-bdy", Name), None);
}

/// Checks the declarations of one model.
struct Declarations;

impl RigidModelVisitor for Declarations {
    type Output = ();
    fn visit<M: RigidZooModel>(self, mut model: M) {
        let name = model.name();
        // Parameters: every one can be set to its value; unknown names and bad values fail.
        for (parameter, value) in model.parameters() {
            model.set_parameter(parameter, value).unwrap();
            let error = model.set_parameter(parameter, f64::NAN).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { .. }), "{name}");
        }
        assert!(model.set_parameter("nonsense", 1.0).is_err());
        assert!(model.set_parameter("i1", -1.0).is_err(), "{name}");
        assert!(model.default_step() > 0.0 && model.default_horizon() > model.default_step());

        let (r0, omega0) = model.initial_state();
        assert!((r0.transpose() * r0 - Matrix3::identity()).amax() < 1e-15);
        let states = [
            (r0, omega0),
            (
                exp(&Vector3::new(0.7, -1.1, 0.4)),
                Vector3::new(-0.3, 0.9, 1.7),
            ),
        ];
        for (r, omega) in states {
            let value = model.value(&r, &omega);
            // G-invariance declaration.
            if M::G_INVARIANT {
                let moved = model.value(&(exp(&Vector3::new(1.0, 2.0, -0.5)) * r), &omega);
                assert!((moved - value).abs() < 1e-14, "{name}");
                assert!(model.torque(&r, &omega).amax() < 1e-14, "{name}");
            }
            // Symmetry axes: L(exp(θâ)R, Ω) = L(R, Ω).
            for i in 0..model.axis_count() {
                let axis = model.axis(i);
                assert!((axis.norm() - 1.0).abs() < 1e-15, "{name}");
                for theta in [0.3, -1.2, 2.5] {
                    let moved = model.value(&(exp(&(axis * theta)) * r), &omega);
                    assert!((moved - value).abs() < 1e-13, "{name}: axis {i}");
                }
                // d/dt a·(RΠ) = a·R(Π × Ω + Π̇) along the Euler–Poincaré flow vanishes.
                let momentum = model.momentum(&r, &omega);
                let (_, rate) = model.euler_poincare(&r, &momentum, &omega).unwrap();
                let derivative = axis.dot(&(r * (hat(&omega) * momentum + rate)));
                assert!(derivative.abs() < 1e-12, "{name}: axis {i}: {derivative}");
            }
            // Invariants: conserved along the flow, i.e. their values at
            // (R exp(±εΩ), Π ± εΠ̇) agree to O(ε²) (central difference of the time derivative).
            let momentum = model.momentum(&r, &omega);
            let (_, rate) = model.euler_poincare(&r, &momentum, &omega).unwrap();
            for i in 0..model.invariant_count() {
                let eps = 1e-6;
                let at = |s: f64| {
                    let r = r * exp(&(omega * s));
                    let p = momentum + rate * s;
                    let w = model.velocity(&r, &p, &omega).unwrap();
                    model.invariant(i, &r, &w, &p)
                };
                let derivative = (at(eps) - at(-eps)) / (2.0 * eps);
                assert!(
                    derivative.abs() < 1e-8,
                    "{name}: invariant {i}: {derivative}"
                );
            }
            // Energy is conserved by the flow as well.
            let energy = |s: f64| {
                let r = r * exp(&(omega * s));
                let p = momentum + rate * s;
                let w = model.velocity(&r, &p, &omega).unwrap();
                model.energy(&r, &w)
            };
            let eps = 1e-6;
            let derivative = (energy(eps) - energy(-eps)) / (2.0 * eps);
            assert!(derivative.abs() < 1e-7, "{name}: energy: {derivative}");
        }
    }
}

#[test]
fn declarations_of_every_rigid_model_hold() {
    for &name in RIGID_MODEL_NAMES {
        visit_rigid_model(name, Declarations).unwrap();
    }
}

#[test]
fn free_body_casimir_and_heavy_top_spin() {
    use svi_models::{FreeRigidBody, HeavyTop};
    let body = FreeRigidBody::default();
    const { assert!(FreeRigidBody::G_INVARIANT) };
    assert_eq!(body.invariant_name(0), "casimir |Pi|^2");
    let p = Vector3::new(1.0, 2.0, 2.0);
    assert_eq!(
        body.invariant(0, &Matrix3::identity(), &Vector3::zeros(), &p),
        9.0
    );
    let top = HeavyTop::default();
    const { assert!(!HeavyTop::G_INVARIANT) };
    assert_eq!(top.axis(0), Vector3::z());
}
