//! The Lie-group variational integrator on SO(3) (issue #6): geometry over long runs,
//! convergence order against an independent reference, symplecticity of the one-step map,
//! and agreement of the reduced Euler–Poincaré form with the full form.
//!
//! The reference solutions are classical RK4 on the quaternion / body-momentum ODE
//! q̇ = ½ q ⊗ (0, Ω), Π̇ = Π × Ω + m g Γ × χ (Γ = Rᵀe₃, Ω = I⁻¹Π), written out here by
//! hand, with a step 100 times smaller than the smallest step tested (its error, O(h⁴), is
//! far below the errors measured).

use nalgebra::{SMatrix, SVector};
use svi::lie_group::so3::{exp, log, orthogonality_error};
use svi::lie_group::{
    AngularMomentumError, Form, LieSvi, OrthogonalityError, RigidBodyDefaults,
    RigidBodyIntegrator, RigidBodyLagrangian, RigidEnergyError, RigidInitial, RigidInvariantError,
    RigidObserver, RigidPoint, RigidState,
};
use svi::observer::Every;
use svi::verify::observed_order;
use svi_models::{FreeRigidBody, HeavyTop, Pendulum3d};
use std::ops::ControlFlow;

type Matrix3 = SMatrix<f64, 3, 3>;
type Vector3 = SVector<f64, 3>;

/// Inertia, m g and χ of a body L = ½ΩᵀIΩ − m g e₃·(Rχ), for the reference ODE.
#[derive(Clone, Copy)]
struct Body {
    inertia: [f64; 3],
    weight: f64,
    centre: Vector3,
}

fn free_body(model: &FreeRigidBody) -> Body {
    Body {
        inertia: model.inertia,
        weight: 0.0,
        centre: Vector3::zeros(),
    }
}

fn top_body(model: &HeavyTop) -> Body {
    Body {
        inertia: [model.i1, model.i1, model.i3],
        weight: model.m * model.g,
        centre: Vector3::new(0.0, 0.0, model.l),
    }
}

fn pendulum_body(model: &Pendulum3d) -> Body {
    Body {
        inertia: model.inertia,
        weight: model.m * model.g,
        centre: Vector3::from(model.centre),
    }
}

type Quaternion = [f64; 4];

fn quaternion_product(p: &Quaternion, q: &Quaternion) -> Quaternion {
    [
        p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3],
        p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
        p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1],
        p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0],
    ]
}

fn rotation(q: &Quaternion) -> Matrix3 {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|c| c / n);
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// Right-hand side of the reference ODE in (q, Π).
fn rate(body: &Body, q: &Quaternion, momentum: &Vector3) -> (Quaternion, Vector3) {
    let omega = Vector3::from_fn(|i, _| momentum[i] / body.inertia[i]);
    let half = quaternion_product(q, &[0.0, omega[0], omega[1], omega[2]]).map(|c| 0.5 * c);
    let gamma = rotation(q).transpose() * Vector3::z();
    let torque = gamma.cross(&body.centre) * body.weight;
    (half, momentum.cross(&omega) + torque)
}

/// Classical RK4 from (R₀, Π₀) over `duration` with `steps` steps.
fn reference(body: &Body, r0: &Matrix3, p0: &Vector3, duration: f64, steps: usize) -> (Matrix3, Vector3) {
    let mut q = svi::lie_group::quaternion(r0);
    let mut p = *p0;
    let h = duration / steps as f64;
    let add = |q: &Quaternion, dq: &Quaternion, s: f64| -> Quaternion {
        [q[0] + s * dq[0], q[1] + s * dq[1], q[2] + s * dq[2], q[3] + s * dq[3]]
    };
    for _ in 0..steps {
        let (k1q, k1p) = rate(body, &q, &p);
        let (k2q, k2p) = rate(body, &add(&q, &k1q, 0.5 * h), &(p + k1p * (0.5 * h)));
        let (k3q, k3p) = rate(body, &add(&q, &k2q, 0.5 * h), &(p + k2p * (0.5 * h)));
        let (k4q, k4p) = rate(body, &add(&q, &k3q, h), &(p + k3p * h));
        for i in 0..4 {
            q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
        }
        p += (k1p + k2p * 2.0 + k3p * 2.0 + k4p) * (h / 6.0);
    }
    (rotation(&q), p)
}

/// Error max(‖log(R_refᵀR)‖, ‖Π − Π_ref‖/‖Π_ref‖) at T.
fn error_at<L: RigidBodyLagrangian + Clone>(
    model: &L,
    method: LieSvi,
    r0: &Matrix3,
    omega0: &Vector3,
    h: f64,
    duration: f64,
    exact: &(Matrix3, Vector3),
) -> f64 {
    let run = RigidBodyIntegrator::new(model.clone(), method)
        .run(
            0.0,
            RigidInitial::Velocity {
                r: *r0,
                omega: *omega0,
            },
            h,
            duration,
            &mut (),
        )
        .unwrap();
    let attitude = log(&(exact.0.transpose() * run.state.r)).norm();
    let momentum = (run.state.momentum - exact.1).norm() / exact.1.norm();
    attitude.max(momentum)
}

#[test]
fn explore() {
    let model = Pendulum3d::default();
    let (r0, omega0) = model.initial_state();
    let body = pendulum_body(&model);
    let p0 = Vector3::from_fn(|i, _| body.inertia[i] * omega0[i]);
    let duration = 1.0;
    let exact = reference(&body, &r0, &p0, duration, 200_000);
    for (points, quadrature) in [(2, 1), (2, 2), (3, 2), (3, 3), (4, 3), (4, 4), (5, 5)] {
        let steps = [0.2, 0.1, 0.05, 0.025];
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| {
                error_at(
                    &model,
                    LieSvi::new(points).with_quadrature(quadrature),
                    &r0,
                    &omega0,
                    h,
                    duration,
                    &exact,
                )
            })
            .collect();
        let order = observed_order(&steps, &errors, 1e-12).unwrap_or(f64::NAN);
        println!("{points} {quadrature}: {errors:?} order {order}");
    }
}
