//! The Lie-group variational integrator on SO(3) (issue #6): geometry over long runs,
//! convergence order against an independent reference, symplecticity of the one-step map,
//! and agreement of the reduced Euler–Poincaré form with the full form.
//!
//! The reference solutions are classical RK4 on the quaternion / body-momentum ODE
//! q̇ = ½ q ⊗ (0, Ω), Π̇ = Π × Ω + m g Γ × χ (Γ = Rᵀe₃, Ω = I⁻¹Π), written out here by
//! hand, with a step 100 times smaller than the smallest step tested (its error, O(h⁴), is
//! far below the errors measured).

use crate::allocations;

use nalgebra::{SMatrix, SVector};
use std::ops::ControlFlow;
use svi::lie_group::so3::{dexp, dexp_inverse, exp, log, orthogonality_error};
use svi::lie_group::{
    AngularMomentumError, Form, LieSvi, OrthogonalityError, RigidBodyDefaults, RigidBodyExt,
    RigidBodyIntegrator, RigidBodyLagrangian, RigidInitial, RigidPoint, RigidState,
    RigidTrajectory,
};
use svi::observer::{EnergyError, Every, InvariantError, Observer};
use svi::solve::{SolveOptions, Span};
use svi::verify::observed_order;
use svi::{Error, Recovery, RunOptions, Scalar};
use svi_models::{FreeRigidBody, HeavyTop, Pendulum3d};

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
    svi::lie_group::rotation(&q.map(|c| c / n))
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
fn reference(
    body: &Body,
    r0: &Matrix3,
    p0: &Vector3,
    duration: f64,
    steps: usize,
) -> (Matrix3, Vector3) {
    let mut q = svi::lie_group::quaternion(r0);
    let mut p = *p0;
    let h = duration / steps as f64;
    let add = |q: &Quaternion, dq: &Quaternion, s: f64| -> Quaternion {
        [
            q[0] + s * dq[0],
            q[1] + s * dq[1],
            q[2] + s * dq[2],
            q[3] + s * dq[3],
        ]
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

/// Convergence order against the RK4 reference at T = 1, for a step ladder.
fn order<L: RigidBodyLagrangian + Clone>(
    model: &L,
    body: &Body,
    r0: &Matrix3,
    omega0: &Vector3,
    method: LieSvi,
    steps: &[f64],
) -> (f64, Vec<f64>) {
    let duration = 1.0;
    let p0 = Vector3::from_fn(|i, _| body.inertia[i] * omega0[i]);
    let exact = reference(body, r0, &p0, duration, 100_000);
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| error_at(model, method.clone(), r0, omega0, h, duration, &exact))
        .collect();
    (observed_order(steps, &errors, 1e-12).unwrap(), errors)
}

#[test]
fn observed_order_matches_the_declared_order() {
    let steps = [0.2, 0.1, 0.05, 0.025];
    let pendulum = Pendulum3d::default();
    let (r0, omega0) = pendulum.initial_state();
    let top = HeavyTop::default();
    let (top_r0, _) = top.initial_state();
    // A slower top than the default keeps the coarsest step in the asymptotic range.
    let top_omega0 = Vector3::new(0.5, -0.3, 3.0);
    let free = FreeRigidBody::default();
    let (free_r0, free_omega0) = free.initial_state();
    for (points, quadrature) in [(2, 1), (2, 2), (3, 2), (3, 3), (4, 3), (4, 4)] {
        let method = LieSvi::new(points).with_quadrature(quadrature);
        let declared = method.info().order as f64;
        let (observed, errors) = order(
            &pendulum,
            &pendulum_body(&pendulum),
            &r0,
            &omega0,
            method.clone(),
            &steps,
        );
        eprintln!(
            "3D pendulum ({points}, {quadrature}): order {observed:.3} (declared {declared}), errors {errors:?}"
        );
        assert!(
            (observed - declared).abs() < 0.3,
            "3D pendulum, {points} points, {quadrature} Gauss points: observed {observed}, \
             declared {declared}, errors {errors:?}"
        );
        let (observed, errors) = order(
            &top,
            &top_body(&top),
            &top_r0,
            &top_omega0,
            method.clone(),
            &steps,
        );
        eprintln!(
            "heavy top ({points}, {quadrature}): order {observed:.3} (declared {declared}), errors {errors:?}"
        );
        assert!(
            (observed - declared).abs() < 0.3,
            "heavy top, {points} points, {quadrature} Gauss points: observed {observed}, \
             declared {declared}, errors {errors:?}"
        );
        let reduced = method.with_form(Form::Reduced);
        let (observed, errors) = order(
            &free,
            &free_body(&free),
            &free_r0,
            &free_omega0,
            reduced,
            &steps,
        );
        eprintln!(
            "free body reduced ({points}, {quadrature}): order {observed:.3} (declared {declared}), errors {errors:?}"
        );
        assert!(
            (observed - declared).abs() < 0.3,
            "free body (reduced), {points} points, {quadrature} Gauss points: observed \
             {observed}, declared {declared}, errors {errors:?}"
        );
    }
}

/// Energy errors over the first and the second half of a run, to detect drift.
#[derive(Default)]
struct EnergyHalves {
    steps: usize,
    initial: Option<f64>,
    first: f64,
    second: f64,
}

impl<L: RigidBodyLagrangian> Observer<L, RigidPoint> for EnergyHalves {
    fn observe(&mut self, model: &L, step: usize, point: &RigidPoint) -> ControlFlow<()> {
        let energy = model.energy(&point.r, &point.omega);
        let initial = *self.initial.get_or_insert(energy);
        let error = (energy - initial).abs();
        if 2 * step <= self.steps {
            self.first = self.first.max(error);
        } else {
            self.second = self.second.max(error);
        }
        ControlFlow::Continue(())
    }
}

/// 10⁵ steps: orthogonality, angular momentum, Casimir and energy of one run.
fn long_run<L: svi_models::RigidZooModel>(model: L, method: LieSvi, h: f64) -> LongRun {
    let (r0, omega0) = model.initial_state();
    let steps = 100_000;
    let mut observers = (
        OrthogonalityError::default(),
        AngularMomentumError::default(),
        InvariantError::default(),
        EnergyHalves {
            steps,
            ..EnergyHalves::default()
        },
        EnergyError::default(),
    );
    let run = RigidBodyIntegrator::new(model, method)
        .run(
            0.0,
            RigidInitial::Velocity {
                r: r0,
                omega: omega0,
            },
            h,
            h * steps as f64,
            &mut observers,
        )
        .unwrap();
    assert_eq!(run.statistics.steps, steps);
    let (orthogonality, momentum, invariants, halves, energy) = observers;
    assert_eq!(energy.max, halves.first.max(halves.second));
    LongRun {
        orthogonality: orthogonality_error(&run.state.r),
        orthogonality_max: orthogonality.max,
        momentum: momentum.relative(),
        invariants: invariants.max,
        energy_first: halves.first,
        energy_second: halves.second,
    }
}

#[derive(Debug)]
struct LongRun {
    orthogonality: f64,
    orthogonality_max: f64,
    momentum: f64,
    invariants: f64,
    energy_first: f64,
    energy_second: f64,
}

impl LongRun {
    fn check(&self, name: &str) {
        eprintln!("{name}: {self:?}");
        assert!(self.orthogonality <= 1e-13, "{name}: {self:?}");
        assert!(self.orthogonality_max <= 1e-13, "{name}: {self:?}");
        assert!(self.momentum <= 1e-12, "{name}: {self:?}");
        assert!(
            self.energy_second <= 2.0 * self.energy_first,
            "{name}: energy drifts: {self:?}"
        );
    }
}

#[test]
fn free_rigid_body_over_a_hundred_thousand_steps() {
    // Reduced (Euler–Poincaré) form, 2 CGL points and 1 Gauss point: the cheap
    // configuration; T = 5000.
    let result = long_run(
        FreeRigidBody::default(),
        LieSvi::new(2).with_quadrature(1).with_form(Form::Reduced),
        0.05,
    );
    result.check("free rigid body");
    // The Casimir ‖Π‖² = ‖π‖² is conserved to round-off as well.
    assert!(result.invariants <= 1e-12 * 5.0, "{result:?}");
    // Energy error of a second-order method with h = 0.05: small and bounded.
    assert!(result.energy_first < 1e-3, "{result:?}");
}

#[test]
fn heavy_top_over_a_hundred_thousand_steps() {
    // Full form (the top is not G-invariant), 2 CGL points and 1 Gauss point, h = 0.01,
    // T = 1000.
    let result = long_run(HeavyTop::default(), LieSvi::new(2).with_quadrature(1), 0.01);
    result.check("heavy top");
    // Lagrange's integral Π₃ (symmetric top) too.
    assert!(result.invariants <= 1e-12 * 5.0, "{result:?}");
    assert!(result.energy_first < 1e-2, "{result:?}");
}

#[test]
fn pendulum_3d_conserves_vertical_momentum_and_stays_orthogonal() {
    let model = Pendulum3d::default();
    let result = {
        let (r0, omega0) = model.initial_state();
        let mut observers = (
            OrthogonalityError::default(),
            AngularMomentumError::default(),
            EnergyError::default(),
        );
        RigidBodyIntegrator::new(model, LieSvi::new(3))
            .run(
                0.0,
                RigidInitial::Velocity {
                    r: r0,
                    omega: omega0,
                },
                0.01,
                100.0,
                &mut observers,
            )
            .unwrap();
        observers
    };
    assert!(result.0.max <= 1e-13, "{result:?}");
    assert!(result.1.relative() <= 1e-12, "{result:?}");
    assert!(result.2.max <= 1e-4, "{result:?}");
}

/// The one-step map in canonical coordinates (η, p) about a base state: R = R_k exp(η),
/// μ = dexp_η⁻¹ p (p = dexp_{−η}ᵀ μ = dexp_η μ is the momentum conjugate to η); the output
/// is charted about the image of the base state the same way.
fn step_in_chart<L: RigidBodyLagrangian + Clone>(
    integrator: &RigidBodyIntegrator<L>,
    base: &RigidState,
    image: &RigidState,
    h: f64,
    x: &SVector<f64, 6>,
) -> SVector<f64, 6> {
    let eta = x.fixed_rows::<3>(0).into_owned();
    let p = x.fixed_rows::<3>(3).into_owned();
    let state = RigidState {
        r: base.r * exp(&eta),
        momentum: dexp_inverse(&eta) * p,
    };
    let (next, _) = integrator.step(0.0, &state, h).unwrap();
    let eta_next = log(&(image.r.transpose() * next.r));
    let p_next = dexp(&eta_next) * next.momentum;
    let mut out = SVector::<f64, 6>::zeros();
    out.fixed_rows_mut::<3>(0).copy_from(&eta_next);
    out.fixed_rows_mut::<3>(3).copy_from(&p_next);
    out
}

fn symplectic_form() -> SMatrix<f64, 6, 6> {
    let mut j = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..3 {
        j[(i, 3 + i)] = 1.0;
        j[(3 + i, i)] = -1.0;
    }
    j
}

/// ‖ΦᵀJΦ − J‖_max of the one-step map, Φ by fourth-order central differences in (η, p), and
/// of the exact tangent map (implicit function theorem, num-dual), and the largest
/// difference between the two Φ.
fn symplecticity_error<L: RigidBodyLagrangian + Clone>(
    model: L,
    method: LieSvi,
    state: &RigidState,
    h: f64,
) -> (f64, f64, f64) {
    let integrator = RigidBodyIntegrator::new(model, method);
    let (image, _) = integrator.step(0.0, state, h).unwrap();
    let mut phi = SMatrix::<f64, 6, 6>::zeros();
    for j in 0..6 {
        // Steps of 10⁻³ relative to the size of each coordinate.
        let e = 1e-3
            * if j < 3 {
                1.0
            } else {
                state.momentum.amax().max(1.0)
            };
        let f = |t: f64| {
            let mut x = SVector::<f64, 6>::zeros();
            x.fixed_rows_mut::<3>(3).copy_from(&state.momentum);
            x[j] += t;
            step_in_chart(&integrator, state, &image, h, &x)
        };
        let column = (f(-2.0 * e) - f(-e) * 8.0 + f(e) * 8.0 - f(2.0 * e)) / (12.0 * e);
        phi.set_column(j, &column);
    }
    let j = symplectic_form();
    let (next, exact) = integrator.tangent_map(0.0, state, h).unwrap();
    assert_eq!(next, image);
    (
        (phi.transpose() * j * phi - j).amax(),
        (exact.transpose() * j * exact - j).amax(),
        (exact - phi).amax() / exact.amax(),
    )
}

#[test]
fn the_one_step_map_is_symplectic_on_the_cotangent_bundle() {
    let top = HeavyTop::default();
    let (r0, omega0) = top.initial_state();
    let top_state = RigidState {
        r: r0,
        momentum: top.momentum(&r0, &Vector3::new(0.7, -0.4, omega0[2] * 0.3)),
    };
    let pendulum = Pendulum3d::default();
    let (r0, omega0) = pendulum.initial_state();
    let pendulum_state = RigidState {
        r: r0,
        momentum: pendulum.momentum(&r0, &omega0),
    };
    let free = FreeRigidBody::default();
    let (r0, omega0) = free.initial_state();
    let free_state = RigidState {
        r: exp(&Vector3::new(0.4, 0.1, -0.9)) * r0,
        momentum: free.momentum(&r0, &omega0),
    };
    for (points, quadrature) in [(2, 1), (3, 2), (4, 4)] {
        let method = LieSvi::new(points).with_quadrature(quadrature);
        for h in [0.05, 0.2] {
            let errors = [
                symplecticity_error(top, method.clone(), &top_state, h),
                symplecticity_error(pendulum, method.clone(), &pendulum_state, h),
                symplecticity_error(free, method.clone(), &free_state, h),
                symplecticity_error(
                    free,
                    method.clone().with_form(Form::Reduced),
                    &free_state,
                    h,
                ),
            ];
            eprintln!(
                "symplecticity ({points}, {quadrature}), h = {h}: \
                 (differences, exact, mismatch) {errors:?}"
            );
            for (differences, exact, mismatch) in errors {
                assert!(
                    differences <= 1e-11 && exact <= 1e-13 && mismatch <= 1e-10,
                    "{points} points, {quadrature} Gauss, h = {h}: {errors:?}"
                );
            }
        }
    }
}

#[test]
fn a_non_canonical_chart_is_not_symplectic() {
    // Control for the test above: in (η, μ) coordinates (μ not transformed by dexp) the
    // same map is not symplectic for the constant J, so the test does detect the wrong
    // form.
    let pendulum = Pendulum3d::default();
    let (r0, omega0) = pendulum.initial_state();
    let state = RigidState {
        r: r0,
        momentum: pendulum.momentum(&r0, &omega0),
    };
    let integrator = RigidBodyIntegrator::new(pendulum, LieSvi::new(3));
    let h = 0.2;
    let (image, _) = integrator.step(0.0, &state, h).unwrap();
    let map = |x: &SVector<f64, 6>| {
        let eta = x.fixed_rows::<3>(0).into_owned();
        let s = RigidState {
            r: state.r * exp(&eta),
            momentum: x.fixed_rows::<3>(3).into_owned(),
        };
        let (next, _) = integrator.step(0.0, &s, h).unwrap();
        let mut out = SVector::<f64, 6>::zeros();
        out.fixed_rows_mut::<3>(0)
            .copy_from(&log(&(image.r.transpose() * next.r)));
        out.fixed_rows_mut::<3>(3).copy_from(&next.momentum);
        out
    };
    let mut phi = SMatrix::<f64, 6, 6>::zeros();
    for j in 0..6 {
        let e = 1e-4;
        let mut x = SVector::<f64, 6>::zeros();
        x.fixed_rows_mut::<3>(3).copy_from(&state.momentum);
        let mut plus = x;
        plus[j] += e;
        let mut minus = x;
        minus[j] -= e;
        phi.set_column(j, &((map(&plus) - map(&minus)) / (2.0 * e)));
    }
    let mut j = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..3 {
        j[(i, 3 + i)] = 1.0;
        j[(3 + i, i)] = -1.0;
    }
    assert!((phi.transpose() * j * phi - j).amax() > 1e-3);
}

#[test]
fn reduced_form_agrees_with_the_full_form_on_the_free_rigid_body() {
    let model = FreeRigidBody::default();
    let (r0, omega0) = model.initial_state();
    let initial = RigidInitial::Velocity {
        r: exp(&Vector3::new(0.2, -0.5, 0.3)) * r0,
        omega: omega0,
    };
    for (points, quadrature) in [(2, 1), (3, 3), (5, 4)] {
        let method = LieSvi::new(points).with_quadrature(quadrature);
        let mut full_trajectory = Every::new(100, RigidTrajectory::new());
        let mut reduced_trajectory = Every::new(100, RigidTrajectory::new());
        RigidBodyIntegrator::new(model, method.clone())
            .run(0.0, initial, 0.1, 100.0, &mut full_trajectory)
            .unwrap();
        RigidBodyIntegrator::new(model, method.with_form(Form::Reduced))
            .run(0.0, initial, 0.1, 100.0, &mut reduced_trajectory)
            .unwrap();
        let (full, reduced) = (
            full_trajectory.inner.points,
            reduced_trajectory.inner.points,
        );
        assert_eq!(full.len(), 11);
        for (a, b) in full.iter().zip(&reduced) {
            assert!(
                (a.r - b.r).amax() <= 1e-12,
                "{points} points: {a:?} vs {b:?}"
            );
            assert!((a.momentum - b.momentum).amax() <= 1e-12 * a.momentum.amax());
            assert!((a.omega - b.omega).amax() <= 1e-12 * a.omega.amax());
        }
    }
}

#[test]
fn the_step_loop_allocates_nothing() {
    let allocations = |steps: usize| {
        let model = HeavyTop::default();
        let (r, omega) = model.initial_state();
        let integrator = RigidBodyIntegrator::new(model, LieSvi::new(3));
        let before = allocations::count();
        integrator
            .run(
                0.0,
                RigidInitial::Velocity { r, omega },
                0.01,
                0.01 * steps as f64,
                &mut (OrthogonalityError::default(), EnergyError::default()),
            )
            .unwrap();
        allocations::count() - before
    };
    assert_eq!(allocations(20), allocations(500));
}

/// Declares G-invariance but depends on R.
struct Liar;
impl RigidBodyLagrangian for Liar {
    const G_INVARIANT: bool = true;
    fn lagrangian<D: Scalar>(&self, r: &SMatrix<D, 3, 3>, w: &SVector<D, 3>) -> D {
        w.dot(w) * 0.5 - r[(2, 2)]
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let model = HeavyTop::default();
    let (r, omega) = model.initial_state();
    let initial = RigidInitial::Velocity { r, omega };
    let run = |method: LieSvi, initial: RigidInitial, h: f64, t_end: f64| {
        RigidBodyIntegrator::new(model, method).run(0.0, initial, h, t_end, &mut ())
    };
    let name = |result: Result<svi::lie_group::RigidRun, Error>| match result {
        Err(Error::InvalidParameter { name, .. }) => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    };
    assert_eq!(name(run(LieSvi::new(1), initial, 0.01, 1.0)), "points");
    assert_eq!(
        name(run(
            LieSvi::new(svi::spectral::MAX_POINTS + 1),
            initial,
            0.01,
            1.0
        )),
        "points"
    );
    assert_eq!(
        name(run(LieSvi::new(3).with_quadrature(0), initial, 0.01, 1.0)),
        "quadrature"
    );
    assert_eq!(
        name(run(
            LieSvi::new(3).with_max_iterations(0),
            initial,
            0.01,
            1.0
        )),
        "max_iterations"
    );
    assert_eq!(
        name(run(
            LieSvi::new(3).with_form(Form::Reduced),
            initial,
            0.01,
            1.0
        )),
        "form"
    );
    assert_eq!(name(run(LieSvi::new(3), initial, 0.0, 1.0)), "h");
    assert_eq!(name(run(LieSvi::new(3), initial, -0.1, 1.0)), "h");
    assert_eq!(name(run(LieSvi::new(3), initial, f64::NAN, 1.0)), "h");
    assert_eq!(name(run(LieSvi::new(3), initial, 0.01, 0.0)), "t_end");
    assert_eq!(
        name(run(LieSvi::new(3), initial, 0.01, f64::INFINITY)),
        "t_end"
    );
    let skewed = RigidInitial::Velocity {
        r: r * 1.001,
        omega,
    };
    assert_eq!(
        name(run(LieSvi::new(3), skewed, 0.01, 1.0)),
        "initial attitude"
    );
    let reflected = RigidInitial::Velocity { r: -r, omega };
    assert_eq!(
        name(run(LieSvi::new(3), reflected, 0.01, 1.0)),
        "initial attitude"
    );
    let not_finite = RigidInitial::Velocity {
        r,
        omega: Vector3::new(0.0, f64::NAN, 1.0),
    };
    assert_eq!(
        name(run(LieSvi::new(3), not_finite, 0.01, 1.0)),
        "initial angular velocity[1]"
    );
    let mut r_nan = r;
    r_nan[(1, 1)] = f64::NAN;
    let not_finite = RigidInitial::Momentum {
        r: r_nan,
        momentum: omega,
    };
    assert_eq!(
        name(run(LieSvi::new(3), not_finite, 0.01, 1.0)),
        "initial attitude[4]"
    );
    // A false G-invariance declaration is caught at the initial state.
    let liar = RigidBodyIntegrator::new(Liar, LieSvi::new(3).with_form(Form::Reduced));
    let result = liar.run(0.0, RigidInitial::Velocity { r, omega }, 0.01, 1.0, &mut ());
    assert_eq!(name(result), "G_INVARIANT");
    // One Newton iteration is not enough: a typed non-convergence with step context.
    match run(LieSvi::new(3).with_max_iterations(1), initial, 0.1, 1.0) {
        Err(Error::NonConvergence {
            step, iterations, ..
        }) => {
            assert_eq!(step, 0);
            assert_eq!(iterations, 1);
        }
        other => panic!("expected non-convergence, got {other:?}"),
    }
}

/// ‖Φ_h(R', −μ') − (R, −μ)‖ with (R', μ') = Φ_h(R, μ): zero for a symmetric method on a
/// reversible Lagrangian (L(R, −Ω) = L(R, Ω)), since then Φ_h ∘ ρ ∘ Φ_h = ρ with ρ(R, μ) =
/// (R, −μ).
fn reversibility_defect<L: RigidBodyLagrangian + RigidBodyDefaults + Clone>(
    model: L,
    method: LieSvi,
    h: f64,
) -> f64 {
    let (r0, omega0) = model.initial_state();
    let state = RigidState {
        r: r0,
        momentum: model.momentum(&r0, &omega0),
    };
    let integrator = RigidBodyIntegrator::new(model, method);
    let (next, _) = integrator.step(0.0, &state, h).unwrap();
    let flipped = RigidState {
        r: next.r,
        momentum: -next.momentum,
    };
    let (back, _) = integrator.step(0.0, &flipped, h).unwrap();
    (back.r - state.r)
        .amax()
        .max((back.momentum + state.momentum).amax() / state.momentum.amax())
}

#[test]
fn symmetry_as_declared() {
    for (points, quadrature) in [(2, 1), (2, 2), (3, 2), (3, 3), (4, 4)] {
        let method = LieSvi::new(points).with_quadrature(quadrature);
        let defect = reversibility_defect(Pendulum3d::default(), method.clone(), 0.1).max(
            reversibility_defect(HeavyTop::default(), method.clone(), 0.05),
        );
        eprintln!("reversibility ({points}, {quadrature}): {defect:e}");
        if method.info().symmetric {
            assert!(defect < 1e-13, "({points}, {quadrature}): {defect:e}");
        } else {
            // O(h^(2d+1)) for d ≥ 2, far above round-off.
            assert!(defect > 1e-12, "({points}, {quadrature}): {defect:e}");
        }
    }
}

/// Error of a rigid-body point against the RK4 reference at its time.
fn point_error(point: &RigidPoint, exact: &(Matrix3, Vector3)) -> f64 {
    let attitude = log(&(exact.0.transpose() * point.r)).norm();
    attitude.max((point.momentum - exact.1).norm() / exact.1.norm())
}

#[test]
fn step_and_degree_adaptivity_on_so3_meet_their_tolerance() {
    // The one stepping core serves SO(3) too: step doubling and degree adaptivity of the
    // Lie-group SVI on the heavy top over T = 1, against RK4 with 10⁵ steps.
    let model = HeavyTop::default();
    let (r0, omega0) = model.initial_state();
    let body = top_body(&model);
    let p0 = Vector3::from_fn(|i, _| body.inertia[i] * omega0[i]);
    let exact = reference(&body, &r0, &p0, 1.0, 100_000);
    let integrator = RigidBodyIntegrator::new(model, LieSvi::new(3));
    let initial = RigidInitial::Velocity {
        r: r0,
        omega: omega0,
    };
    let span = Span::new(0.0, 1.0);
    for tol in [1e-6, 1e-8, 1e-10] {
        let step = integrator
            .solve(&span, initial, &SolveOptions::step_adaptive(tol))
            .unwrap();
        assert!(step.adaptivity.accepted > 10);
        assert!(point_error(&step.last, &exact) < tol, "step, tol {tol:e}");
        let degree = integrator
            .solve(
                &span,
                initial,
                &SolveOptions::degree_adaptive(0.1, tol, 2, 12),
            )
            .unwrap();
        assert!(!degree.adaptivity.points.is_empty());
        assert!(
            point_error(&degree.last, &exact) < tol,
            "degree, tol {tol:e}"
        );
    }
}

#[test]
fn recovery_carries_a_rigid_run_past_a_failing_step() {
    let model = HeavyTop::default();
    let (r, omega) = model.initial_state();
    let initial = RigidInitial::Velocity { r, omega };
    let integrator = RigidBodyIntegrator::new(model, LieSvi::new(3));
    // h = 0.5 turns the top by 5 radians in a step, beyond the natural chart (|ξ| < π).
    let mut trajectory = RigidTrajectory::new();
    let failure = integrator
        .try_run(
            0.0,
            initial,
            0.5,
            10.0,
            &RunOptions::default(),
            &mut trajectory,
        )
        .unwrap_err();
    let Error::OutsideChart { step, reach, .. } = failure.error else {
        panic!("{failure}")
    };
    assert!(reach > 1.0, "{reach}");
    let partial = failure.partial.unwrap();
    assert_eq!(partial.statistics.steps, step);
    assert_eq!(trajectory.points.len(), step + 1);
    assert_eq!(trajectory.points[step].r, partial.last.r);
    // Halving failed steps gets through, on the same grid, through the same points up to
    // the failure.
    let options = RunOptions::default().with_recovery(Recovery::HalveStep { max_halvings: 4 });
    let mut recovered = RigidTrajectory::new();
    let run = integrator
        .try_run(0.0, initial, 0.5, 10.0, &options, &mut recovered)
        .unwrap();
    assert_eq!(run.statistics.steps, 20);
    assert!(run.statistics.retries > 0);
    assert_eq!(recovered.points.len(), 21);
    assert_eq!(recovered.points[..=step], trajectory.points[..]);
    assert_eq!(recovered.points[20].t, 10.0);
}

#[test]
fn dense_output_on_so3_converges_with_the_degree_of_the_step_curve() {
    // Output times inside the steps are read off the step curve R_k exp(ξ(τ)) of the
    // Lie-group SVI: on the heavy top with 4 CGL points ξ has degree d = 3. Inside a step the
    // attitude converges like h^(d+1) and Ω = dexp₋ξ ξ̇ (hence Π) like h^(d−1), the orders of
    // the vector SVI's dense output (measured on Kepler with 4 points: q 4.2, q̇ 1.75), while
    // the step points are of order 6. Reference: RK4 with 10⁵ steps per unit time.
    let model = HeavyTop::default();
    let (r0, omega0) = model.initial_state();
    let body = top_body(&model);
    let p0 = Vector3::from_fn(|i, _| body.inertia[i] * omega0[i]);
    let integrator = RigidBodyIntegrator::new(model, LieSvi::new(4));
    let initial = RigidInitial::Velocity {
        r: r0,
        omega: omega0,
    };
    // Interior times sampling one coarse step densely (the maximum over them stands for
    // the sup over the step for both step sizes).
    let mut times = vec![0.0];
    times.extend((1..10).map(|j| 0.7 + 0.005 * j as f64));
    times.push(1.0);
    let exact: Vec<_> = times
        .iter()
        .map(|&t| reference(&body, &r0, &p0, t, ((t * 100_000.0) as usize).max(1)))
        .collect();
    let interior_errors = |h: f64| {
        let solution = integrator
            .solve(&Span::times(&times), initial, &SolveOptions::fixed_step(h))
            .unwrap();
        assert_eq!(solution.points.len(), times.len());
        let (mut attitude, mut momentum): (f64, f64) = (0.0, 0.0);
        for ((point, &t), exact) in solution.points.iter().zip(&times).zip(&exact) {
            assert_eq!(point.t, t);
            assert!(orthogonality_error(&point.r) < 1e-14);
            let legendre = integrator.model().momentum(&point.r, &point.omega);
            assert!((legendre - point.momentum).amax() < 1e-14);
            if [0.0, 1.0].contains(&t) {
                assert!(point_error(point, exact) < 1e-8, "step point t = {t}");
            } else {
                attitude = attitude.max(log(&(exact.0.transpose() * point.r)).norm());
                momentum = momentum.max((point.momentum - exact.1).norm() / exact.1.norm());
            }
        }
        (attitude, momentum)
    };
    let (coarse, fine) = (interior_errors(0.05), interior_errors(0.025));
    assert!(coarse.0 < 1e-6 && coarse.1 < 1e-4, "{coarse:?}");
    let attitude_order = (coarse.0 / fine.0).log2();
    let momentum_order = (coarse.1 / fine.1).log2();
    assert!(
        (3.6..4.6).contains(&attitude_order),
        "attitude order {attitude_order}"
    );
    assert!(
        (1.5..2.6).contains(&momentum_order),
        "momentum order {momentum_order}"
    );
}
