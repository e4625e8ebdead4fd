//! Lie-SVI on any Lie group (issue #38; SO(3) rigid bodies run on it too, checked against
//! the SO(3) equations in `svi::method::lie_svi`): the free fall of a rigid body on SE(3) and on SO(3) × ℝ³ against its exact solution
//! (Jacobi elliptic functions for the rotation, a parabola for the centre of mass), observed
//! orders, the group and its momenta kept to round-off, the sphere through SO(3), forcing, the
//! dual-spin satellite on SO(3) × S¹, and typed errors for bad input.

use nalgebra::SVector;
use svi::lie_group::GroupDefaults;
use svi::lie_group::{
    Circle, DefectError, Form, GroupInitial, GroupIntegrator, GroupLagrangian, GroupLagrangianExt,
    GroupRun, LieSvi, Power, RigidMotions, Rotations, RotationsAndTranslations,
    SpatialMomentumError, so3,
};
use svi::lie_group::{RigidBodyIntegrator, RigidInitial};
use svi::model::group::LocalDerivatives;
use svi::model::group::derivatives::{dense_local_gradient, dense_local_hessian};
use svi::model::group::pair_terms::{self, PairTerms};
use svi::observer::EnergyError;
use svi::{Error, Integrator, Scalar};
use svi_models::{
    DoubleSphericalPendulum, DualSpin, FallingBody, HeavyTop, HeavyTopOnRigidMotions,
    SphericalChain,
};

type Vector3 = SVector<f64, 3>;

/// The observers of a group run: spatial momentum, energy and ‖RᵀR − I‖.
type Watched<const N: usize> = (SpatialMomentumError<N>, EnergyError, DefectError);

/// A run of `model` with `method` from (g₀, ξ₀), steps `h`, to `t_end`, with its observers.
fn observed_run<L, G, const N: usize, const E: usize>(
    model: L,
    method: LieSvi,
    (g, xi): (SVector<f64, E>, SVector<f64, N>),
    h: f64,
    t_end: f64,
) -> (GroupRun<G, N, E>, Watched<N>)
where
    L: GroupLagrangian<N, E, Group = G>,
    G: svi::lie_group::LieGroup<N, E>,
{
    let integrator: GroupIntegrator<L, G, N, E> = Integrator::new(model, method);
    let mut observers = Watched::<N>::default();
    let run = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g, xi },
            h,
            t_end,
            &mut observers,
        )
        .unwrap();
    (run, observers)
}

/// The falling body's initial state: attitude, position, body angular velocity and body
/// velocity of the centre of mass.
fn falling_start() -> (SVector<f64, 12>, SVector<f64, 6>) {
    let r0 = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
    let g0 = RigidMotions::element(&r0, &Vector3::new(1.0, -2.0, 3.0));
    (g0, SVector::from([1.0, 0.2, 0.8, 0.5, 0.0, 2.0]))
}

/// Error of a falling-body run against the exact solution at its end: the attitude angle
/// |log(R_exactᵀR)|, and position and body velocity relative to their sizes.
fn falling_error(body: &FallingBody, g: &SVector<f64, 12>, xi: &SVector<f64, 6>, t: f64) -> f64 {
    let (g0, xi0) = falling_start();
    let (exact_g, exact_xi) = body.exact(&g0, &xi0, t).unwrap();
    let attitude =
        so3::log(&(RigidMotions::rotation(&exact_g).transpose() * RigidMotions::rotation(g)))
            .norm();
    let position = (RigidMotions::position(g) - RigidMotions::position(&exact_g)).norm()
        / RigidMotions::position(&exact_g).norm();
    let velocity = (xi - exact_xi).norm() / exact_xi.norm();
    attitude.max(position).max(velocity)
}

/// A falling-body run on SE(3) with `points` CGL points to `t_end` in steps of `h`: its error,
/// the largest defect ‖RᵀR − I‖ and the largest energy error relative to the energy's parts.
fn falling_run(body: FallingBody, points: usize, h: f64, t_end: f64) -> (f64, f64, f64) {
    let (g0, xi0) = falling_start();
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> =
        Integrator::new(body, LieSvi::new(points));
    let mut observers = (DefectError::default(), EnergyError::default());
    let run = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            h,
            t_end,
            &mut observers,
        )
        .unwrap();
    let error = falling_error(&body, &run.last.g, &run.last.xi, run.last.t);
    let energy_scale = body.energy(&run.last.g, &run.last.xi).abs().max(1.0)
        + body.gravity * RigidMotions::position(&run.last.g)[2].abs();
    (error, observers.0.max, observers.1.max / energy_scale)
}

#[test]
fn falling_body_on_se3_matches_the_exact_solution_with_its_orders() {
    println!("points  h        error at T = 10   observed order");
    for (points, order, steps) in [
        (2, 2.0, [800, 1600]),
        (3, 4.0, [500, 1000]),
        (4, 6.0, [200, 400]),
    ] {
        let errors: Vec<f64> = steps
            .iter()
            .map(|&n| falling_run(FallingBody::default(), points, 10.0 / n as f64, 10.0).0)
            .collect();
        let observed = (errors[0] / errors[1]).log2();
        println!(
            "{points}       {:<8} {:e}  {observed:.2}",
            10.0 / steps[1] as f64,
            errors[1]
        );
        assert!(
            (observed - order).abs() < 0.2,
            "{points} points: order {observed}"
        );
    }
}

/// The torque-free motion in space (no gravity: the centre of mass moves uniformly).
#[test]
fn free_body_on_se3_to_t_100_within_1e_10() {
    let free = FallingBody {
        gravity: 0.0,
        ..FallingBody::default()
    };
    let (error, defect, energy) = falling_run(free, 3, 0.0035, 100.0);
    println!(
        "SE(3), 3 points, h = 0.0035, T = 100: error {error:e}, ‖RᵀR − I‖ ≤ {defect:e}, relative energy error {energy:e}"
    );
    assert!(error < 1e-10, "{error:e}");
    assert!(defect < 1e-13, "{defect:e}");
    assert!(energy < 1e-13, "{energy:e}");
}

/// The falling body on SO(3) × ℝ³: the position is a separate factor and its body velocity
/// the spatial velocity u = ẋ.
#[derive(Clone, Copy)]
struct FallingOnProduct(FallingBody);

impl GroupLagrangian<6, 12> for FallingOnProduct {
    type Group = RotationsAndTranslations;
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
        let body = &self.0;
        let [i1, i2, i3] = body.inertia;
        let rotation = (xi[0] * xi[0] * i1 + xi[1] * xi[1] * i2 + xi[2] * xi[2] * i3) * 0.5;
        let translation = (xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]) * (0.5 * body.mass);
        rotation + translation - g[11] * (body.mass * body.gravity)
    }
}

#[test]
fn falling_body_on_so3_times_r3_matches_the_exact_solution() {
    let body = FallingBody::default();
    let (g0, xi0) = falling_start();
    let r0 = RigidMotions::rotation(&g0);
    // The same state in the product's coordinates: ξ = (ω, ẋ) with ẋ = Rv.
    let mut xi = xi0;
    let u0 = r0 * xi0.fixed_rows::<3>(3);
    xi.fixed_rows_mut::<3>(3).copy_from(&u0);
    let integrator: GroupIntegrator<_, RotationsAndTranslations, 6, 12> =
        Integrator::new(FallingOnProduct(body), LieSvi::new(3));
    let mut momentum = SpatialMomentumError::<6>::default();
    let run = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi },
            0.004,
            100.0,
            &mut momentum,
        )
        .unwrap();
    // Back to SE(3)'s body velocity for the comparison.
    let r = RigidMotions::rotation(&run.last.g);
    let mut body_xi = run.last.xi;
    let v = r.transpose() * run.last.xi.fixed_rows::<3>(3);
    body_xi.fixed_rows_mut::<3>(3).copy_from(&v);
    let error = falling_error(&body, &run.last.g, &body_xi, run.last.t);
    println!(
        "SO(3) × R³, 3 points, h = 0.004, T = 100: error {error:e}; spatial momentum drift {:?}",
        momentum.max.as_slice()
    );
    assert!(error < 1e-10, "{error:e}");
    // Angular momentum RΠ of the rotation factor (all three components: the rotation is
    // torque-free) and horizontal linear momentum are Noether momenta.
    let scale = 2.5;
    for k in [0, 1, 2, 3, 4] {
        assert!(
            momentum.max[k] < 1e-13 * scale,
            "component {k}: {:e}",
            momentum.max[k]
        );
    }
}

#[test]
fn falling_body_on_se3_conserves_its_noether_momenta() {
    // Symmetries of L on SE(3): translations along x and y and rotations about the vertical
    // through the origin; the spatial momentum is (RΠ + x × mẋ, mẋ).
    let body = FallingBody::default();
    let (g0, xi0) = falling_start();
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> = Integrator::new(body, LieSvi::new(3));
    let mut momentum = SpatialMomentumError::<6>::default();
    integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            0.01,
            50.0,
            &mut momentum,
        )
        .unwrap();
    let initial = momentum.initial.unwrap();
    println!(
        "SE(3) spatial momentum drift {:?} from {:?}",
        momentum.max.as_slice(),
        initial.as_slice()
    );
    // Round-off relative to the size the components reach (x × mẋ grows with the fall).
    let scale = momentum.max.amax();
    for k in [2, 3, 4] {
        assert!(
            momentum.max[k] < 1e-12 * scale,
            "component {k}: {:e}",
            momentum.max[k]
        );
    }
    // The other components change under gravity.
    assert!(momentum.max[5] > 1.0);
}

#[test]
fn bad_input_on_a_group_gives_typed_errors() {
    let body = FallingBody::default();
    let (g0, xi0) = falling_start();
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> = Integrator::new(body, LieSvi::new(3));
    // A configuration that is not a rigid motion: R scaled by 1.01.
    let mut bent = g0;
    for k in 0..9 {
        bent[k] *= 1.01;
    }
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: bent, xi: xi0 },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "initial configuration"),
        "{error}"
    );
    assert!(error.to_string().contains("SE(3)"), "{error}");
    // A reflection.
    let mut mirrored = g0;
    for k in 0..3 {
        mirrored[k] = -mirrored[k];
    }
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity {
                g: mirrored,
                xi: xi0,
            },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "initial configuration"),
        "{error}"
    );
    // A non-finite velocity.
    let mut broken = xi0;
    broken[4] = f64::NAN;
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: broken },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        error.to_string().contains("initial body velocity[4]"),
        "{error}"
    );
    // A step the natural chart cannot reach: |ω| h ≥ π.
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            3.0,
            6.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(error, Error::OutsideChart { step: 0, reach, .. } if reach >= 1.0),
        "{error}"
    );
    assert_eq!(error.kind(), "outside_chart");
    // A singular inertia: the Legendre map cannot be inverted.
    let flat = FallingBody {
        inertia: [0.0, 2.0, 3.0],
        ..body
    };
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> = Integrator::new(flat, LieSvi::new(3));
    let error = integrator
        .run(
            0.0,
            GroupInitial::Momentum {
                g: g0,
                momentum: xi0,
            },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(matches!(error, Error::LegendreMap { .. }), "{error}");
    assert!(error.to_string().contains("singular"), "{error}");
    // The reduced form on a Lagrangian that is not G-invariant.
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> =
        Integrator::new(body, LieSvi::new(3).with_form(Form::Reduced));
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "form"),
        "{error}"
    );
}

#[test]
fn a_wrong_g_invariance_declaration_is_caught() {
    #[derive(Clone, Copy)]
    struct Claims(FallingBody);
    impl GroupLagrangian<6, 12> for Claims {
        type Group = RigidMotions;
        const G_INVARIANT: bool = true;
        fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
            self.0.lagrangian(g, xi)
        }
    }
    let (g0, xi0) = falling_start();
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> =
        Integrator::new(Claims(FallingBody::default()), LieSvi::new(3));
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "G_INVARIANT"),
        "{error}"
    );
}

/// The double spherical pendulum in angles: qᵢ = (sin θᵢ cos φᵢ, sin θᵢ sin φᵢ, −cos θᵢ),
/// coordinates (θ₁, φ₁, θ₂, φ₂), unit lengths and masses.
struct DoublePendulumInAngles {
    gravity: f64,
}

impl svi::Lagrangian<nalgebra::U4> for DoublePendulumInAngles {
    const TIME_DEPENDENT: bool = false;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 4>, v: &SVector<D, 4>) -> D {
        let mut position = SVector::<D, 3>::zeros();
        let mut velocity = SVector::<D, 3>::zeros();
        let mut sum = D::from(0.0);
        for i in 0..2 {
            let (theta, phi, theta_rate, phi_rate) =
                (q[2 * i], q[2 * i + 1], v[2 * i], v[2 * i + 1]);
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            position += SVector::<D, 3>::new(st * cp, st * sp, -ct);
            velocity += SVector::<D, 3>::new(
                ct * cp * theta_rate - st * sp * phi_rate,
                ct * sp * theta_rate + st * cp * phi_rate,
                st * theta_rate,
            );
            sum += velocity.dot(&velocity) * 0.5 - position[2] * self.gravity;
        }
        sum
    }
}

/// Direction and rate of a link in angles.
fn link(theta: f64, phi: f64, theta_rate: f64, phi_rate: f64) -> (Vector3, Vector3) {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    (
        Vector3::new(st * cp, st * sp, -ct),
        Vector3::new(
            ct * cp * theta_rate - st * sp * phi_rate,
            ct * sp * theta_rate + st * cp * phi_rate,
            st * theta_rate,
        ),
    )
}

#[test]
fn double_spherical_pendulum_on_so3_squared_matches_the_angles() {
    let angles = [1.0, 0.3, 1.4, -0.5];
    let rates = [0.2, 1.0, -0.3, 0.8];
    // Reference: SVI with 9 points in the angles (order 18), h = 0.01.
    let reference = Integrator::new(DoublePendulumInAngles { gravity: 9.81 }, svi::Svi::new(9))
        .run_from_velocity(
            0.0,
            SVector::from(angles),
            SVector::from(rates),
            0.01,
            5.0,
            &mut (),
        )
        .unwrap();
    let q = reference.last.q;
    let (first, _) = link(q[0], q[1], 0.0, 0.0);
    let (second, _) = link(q[2], q[3], 0.0, 0.0);
    let exact = [first, first + second];
    // Lie-SVI on SO(3)².
    let chain = DoubleSphericalPendulum::default();
    let links = [
        link(angles[0], angles[1], rates[0], rates[1]),
        link(angles[2], angles[3], rates[2], rates[3]),
    ];
    let (g0, xi0) = chain.state(&[links[0].0, links[1].0], &[links[0].1, links[1].1]);
    let (run, observers) = observed_run(chain, LieSvi::new(5), (g0, xi0), 0.01, 5.0);
    let positions = chain.positions(&run.last.g);
    let error = (0..2)
        .map(|i| (positions[i] - exact[i]).amax())
        .fold(0.0, f64::max);
    // Vertical angular momentum Σ (Rⱼμⱼ)·e₃ and the spins μⱼ,₃.
    let (initial, last) = (
        observers.0.initial.unwrap(),
        run.last.spatial_momentum::<Power<Rotations, 2, 3, 9>>(),
    );
    let vertical = (last[2] + last[5] - initial[2] - initial[5]).abs();
    let spins = run.last.momentum[2].abs().max(run.last.momentum[5].abs());
    println!(
        "double spherical pendulum, lie-svi 5 points, h = 0.01, T = 5: position error {error:e}, \
         vertical momentum {vertical:e}, spins {spins:e}, energy {:e}, ‖RᵀR − I‖ {:e}",
        observers.1.max, observers.2.max
    );
    assert!(error < 1e-9, "{error:e}");
    assert!(vertical < 1e-13, "{vertical:e}");
    assert!(spins < 1e-13, "{spins:e}");
    assert!(observers.2.max < 1e-13);
}

/// SO(3)⁵ with a dense Lagrangian (five free tops): dimension 15.
struct FiveTops;

impl GroupLagrangian<15, 45> for FiveTops {
    type Group = Power<Rotations, 5, 3, 9>;
    fn lagrangian<D: Scalar>(&self, _g: &SVector<D, 45>, xi: &SVector<D, 15>) -> D {
        xi.dot(xi) * 0.5
    }
}

/// Five tops under a force, claiming structured derivatives.
struct FiveForcedTops;

impl GroupLagrangian<15, 45> for FiveForcedTops {
    type Group = Power<Rotations, 5, 3, 9>;
    const STRUCTURED: bool = true;
    const FORCED: bool = true;
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 45>, xi: &SVector<D, 15>) -> D {
        FiveTops.lagrangian(g, xi)
    }
}

/// The error of a run that must fail at its start.
fn failure<L, G, const N: usize, const E: usize>(
    model: L,
    (g, xi): (SVector<f64, E>, SVector<f64, N>),
) -> Error
where
    L: GroupLagrangian<N, E, Group = G>,
    G: svi::lie_group::LieGroup<N, E>,
{
    let integrator: GroupIntegrator<L, G, N, E> = Integrator::new(model, LieSvi::new(2));
    integrator
        .run(0.0, GroupInitial::Velocity { g, xi }, 0.01, 1.0, &mut ())
        .unwrap_err()
}

#[test]
fn a_group_too_large_for_its_derivatives_is_a_typed_error() {
    // Dense derivatives stop at dimension 12.
    let start = (
        SVector::from_fn(|i, _| if i % 9 % 4 == 0 { 1.0 } else { 0.0 }),
        SVector::from_fn(|i, _| 0.1 * i as f64),
    );
    let error = failure(FiveTops, start);
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "group dimension"),
        "{error}"
    );
    assert!(error.to_string().contains("15 exceeds 12"), "{error}");
    // A force is differentiated densely, structure or not.
    let error = failure(FiveForcedTops, start);
    assert!(error.to_string().contains("FORCED"), "{error}");
    // Structured derivatives (a chain's terms) at 96: 33 links are one too many.
    let chain = SphericalChain::<33, 99, 297>::default();
    let start = chain.state(&[-Vector3::z(); 33], &[Vector3::zeros(); 33]);
    let error = failure(chain, start);
    assert!(error.to_string().contains("99 exceeds 96"), "{error}");
}

/// The falling body with linear air drag F = −k ẋ on the centre of mass (Lagrange–d'Alembert
/// on the group), on SO(3) × ℝ³ (`se3 = false`: the force is (0, −k u), u = ẋ) or on SE(3)
/// (the force in the body frame, (0, −k v)).
#[derive(Clone, Copy)]
struct Dragged {
    body: FallingBody,
    drag: f64,
}

impl GroupLagrangian<6, 12> for Dragged {
    type Group = RotationsAndTranslations;
    const FORCED: bool = true;
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
        FallingOnProduct(self.body).lagrangian(g, xi)
    }
    fn external_force<D: Scalar>(
        &self,
        _t: D,
        _g: &SVector<D, 12>,
        xi: &SVector<D, 6>,
    ) -> SVector<D, 6> {
        SVector::from_fn(|i, _| {
            if i < 3 {
                D::from(0.0)
            } else {
                -xi[i] * self.drag
            }
        })
    }
}

/// The same on SE(3).
#[derive(Clone, Copy)]
struct DraggedSe3(Dragged);

impl GroupLagrangian<6, 12> for DraggedSe3 {
    type Group = RigidMotions;
    const FORCED: bool = true;
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
        self.0.body.lagrangian(g, xi)
    }
    fn external_force<D: Scalar>(
        &self,
        t: D,
        g: &SVector<D, 12>,
        xi: &SVector<D, 6>,
    ) -> SVector<D, 6> {
        // The same slots: −k times the velocity of the centre of mass, here in the body frame.
        self.0.external_force(t, g, xi)
    }
}

/// Error of a dragged run at its end against the exact solution: the torque-free rotation and
/// x(t) = x₀ + (u₀ + (g₀/γ)e₃)(1 − e^{−γt})/γ − (g₀/γ) t e₃, γ = k/m.
fn dragged_error(model: &Dragged, g: &SVector<f64, 12>, spatial_velocity: &Vector3, t: f64) -> f64 {
    let (g0, xi0) = falling_start();
    let (exact_g, _) = model.body.exact(&g0, &xi0, t).unwrap();
    let attitude =
        so3::log(&(RigidMotions::rotation(&exact_g).transpose() * RigidMotions::rotation(g)))
            .norm();
    let gamma = model.drag / model.body.mass;
    let terminal = Vector3::z() * (model.body.gravity / gamma);
    let u0 = RigidMotions::rotation(&g0) * xi0.fixed_rows::<3>(3);
    let decay = (-gamma * t).exp();
    let x = RigidMotions::position(&g0) + (u0 + terminal) * ((1.0 - decay) / gamma) - terminal * t;
    let u = (u0 + terminal) * decay - terminal;
    let position = (RigidMotions::position(g) - x).norm() / x.norm();
    let velocity = (spatial_velocity - u).norm() / u.norm();
    attitude.max(position).max(velocity)
}

#[test]
fn drag_on_a_group_matches_the_exact_solution_with_its_order() {
    let model = Dragged {
        body: FallingBody::default(),
        drag: 0.3,
    };
    let (g0, xi0) = falling_start();
    let r0 = RigidMotions::rotation(&g0);
    let mut xi = xi0;
    let u0 = r0 * xi0.fixed_rows::<3>(3);
    xi.fixed_rows_mut::<3>(3).copy_from(&u0);
    let errors: Vec<f64> = [0.02, 0.01]
        .iter()
        .map(|&h| {
            let integrator: GroupIntegrator<_, RotationsAndTranslations, 6, 12> =
                Integrator::new(model, LieSvi::new(3));
            let run = integrator
                .run(0.0, GroupInitial::Velocity { g: g0, xi }, h, 10.0, &mut ())
                .unwrap();
            let u = run.last.xi.fixed_rows::<3>(3).into_owned();
            dragged_error(&model, &run.last.g, &u, run.last.t)
        })
        .collect();
    let order = (errors[0] / errors[1]).log2();
    println!("drag on SO(3) × R³, 3 points, T = 10: errors {errors:?}, order {order:.2}");
    assert!(errors[1] < 1e-9, "{errors:?}");
    assert!((order - 4.0).abs() < 0.3, "{order}");
    // SE(3), the force in the body frame.
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> =
        Integrator::new(DraggedSe3(model), LieSvi::new(4));
    let run = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            0.0125,
            10.0,
            &mut (),
        )
        .unwrap();
    let u = RigidMotions::rotation(&run.last.g) * run.last.xi.fixed_rows::<3>(3);
    let error = dragged_error(&model, &run.last.g, &u, run.last.t);
    println!("drag on SE(3), 4 points, h = 0.0125, T = 10: error {error:e}");
    assert!(error < 1e-10, "{error:e}");
    // A force rules out the reduced form.
    let integrator: GroupIntegrator<_, RigidMotions, 6, 12> =
        Integrator::new(DraggedSe3(model), LieSvi::new(3).with_form(Form::Reduced));
    let error = integrator
        .run(
            0.0,
            GroupInitial::Velocity { g: g0, xi: xi0 },
            0.01,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "form"),
        "{error}"
    );
}

/// The dual-spin satellite on SO(3) × S¹ from rotation near the intermediate axis with a fast
/// rotor, to T = 20 with `points` CGL points and steps `h`: the final state and the observers.
fn dual_spin_run(
    points: usize,
    form: Form,
    h: f64,
) -> (
    svi::lie_group::GroupPoint<4, 11>,
    SpatialMomentumError<4>,
    f64,
    f64,
) {
    type Satellite = svi_models::dual_spin::SatelliteGroup;
    let r0 = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
    let mut g0 = SVector::<f64, 11>::zeros();
    g0.fixed_rows_mut::<9>(0)
        .copy_from(&Rotations::element(&r0));
    g0.fixed_rows_mut::<2>(9).copy_from(&Circle::element(0.4));
    let xi0 = SVector::from([0.05, 1.0, 0.1, 5.0]);
    let method = LieSvi::new(points).with_form(form);
    let (run, observers): (GroupRun<Satellite, 4, 11>, _) =
        observed_run(DualSpin::default(), method, (g0, xi0), h, 20.0);
    (run.last, observers.0, observers.1.max, observers.2.max)
}

#[test]
fn dual_spin_satellite_on_so3_times_s1_keeps_its_momenta_and_converges() {
    let (last, momentum, energy, defect) = dual_spin_run(3, Form::Full, 0.01);
    let scale = momentum.initial.unwrap().amax();
    println!(
        "dual-spin satellite, 3 points, h = 0.01, T = 20: spatial momentum drift {:?} (of {scale}), energy {energy:e}, defect {defect:e}",
        momentum.max.as_slice()
    );
    // Spatial angular momentum (three components) and the rotor's momentum p_φ.
    assert!(momentum.max.amax() < 1e-13 * scale, "{:?}", momentum.max);
    assert!(defect < 1e-13, "{defect:e}");
    // The reduced (Euler–Poincaré) form on the G-invariant satellite agrees.
    let (reduced, ..) = dual_spin_run(3, Form::Reduced, 0.01);
    let difference = (reduced.g - last.g)
        .amax()
        .max((reduced.momentum - last.momentum).amax());
    assert!(difference < 1e-11, "{difference:e}");
    // Order 4 against a 5-point run with h = 0.0025.
    let (reference, ..) = dual_spin_run(5, Form::Full, 0.0025);
    let errors: Vec<f64> = [0.04, 0.02]
        .iter()
        .map(|&h| {
            let (point, ..) = dual_spin_run(3, Form::Full, h);
            (point.g - reference.g)
                .amax()
                .max((point.xi - reference.xi).amax())
        })
        .collect();
    let order = (errors[0] / errors[1]).log2();
    println!("dual-spin satellite, 3 points: errors {errors:?}, order {order:.2}");
    assert!((order - 4.0).abs() < 0.3, "{order}");
}

/// A chain of `K` links with unequal lengths and masses, leaning and moving (no link
/// vertical): the default state of [`GroupDefaults::initial_state`].
fn leaning_chain<const K: usize, const N: usize, const E: usize>()
-> (SphericalChain<K, N, E>, SVector<f64, E>, SVector<f64, N>) {
    let chain = SphericalChain::<K, N, E> {
        lengths: std::array::from_fn(|i| 1.0 + 0.1 * (i % 3) as f64),
        masses: std::array::from_fn(|i| 1.0 + 0.2 * (i % 4) as f64),
        ..SphericalChain::default()
    };
    let (g, xi) = chain.initial_state();
    (chain, g, xi)
}

/// The chain's terms on pairs of links sum to its Lagrangian and give the derivatives that the
/// dense default takes from the whole of it.
#[test]
fn chain_terms_give_the_dense_derivatives() {
    fn check<const K: usize, const N: usize, const E: usize>() {
        let (chain, g, xi) = leaning_chain::<K, N, E>();
        let value = chain.lagrangian(&g, &xi);
        assert!((pair_terms::lagrangian(&chain, &g, &xi) - value).abs() < 1e-13 * value.abs());
        for configuration in [false, true] {
            let (lambda, nu) = chain.local_gradient(&g, &xi, configuration);
            let (dense_lambda, dense_nu) = dense_local_gradient(&chain, &g, &xi, configuration);
            let (mut fast, mut dense) = (LocalDerivatives::zeros(), LocalDerivatives::zeros());
            chain.local_hessian(&g, &xi, configuration, &mut fast);
            dense_local_hessian(&chain, &g, &xi, configuration, &mut dense);
            let scale = dense.ww.amax().max(dense.zz.amax());
            let pairs = [
                (lambda, dense_lambda),
                (nu, dense_nu),
                (fast.lambda, dense.lambda),
                (fast.nu, dense.nu),
            ];
            for (x, y) in pairs {
                assert!((x - y).amax() < 1e-13 * scale, "K = {K}: {x} vs {y}");
            }
            for (x, y) in [
                (fast.zz, dense.zz),
                (fast.zw, dense.zw),
                (fast.ww, dense.ww),
            ] {
                assert!((x - y).amax() < 1e-13 * scale, "K = {K}: {x} vs {y}");
            }
            assert!(dense.zz.amax() > 0.0 || !configuration);
        }
    }
    check::<2, 6, 18>();
    check::<3, 9, 27>();
}

/// A run of the chain of `K` links with Lie-SVI of `points` points: the largest drift of the
/// vertical angular momentum Σⱼ (Rⱼμⱼ)·e₃ and of the spins μⱼ,₃ over the run (relative to
/// the momenta), the energy error (relative) and the largest ‖RᵀR − I‖.
fn chain_run<const K: usize, const N: usize, const E: usize>(
    points: usize,
    h: f64,
    steps: usize,
) -> (f64, f64, f64, f64) {
    let (chain, g0, xi0) = leaning_chain::<K, N, E>();
    let (run, observers) = observed_run(chain, LieSvi::new(points), (g0, xi0), h, h * steps as f64);
    assert_eq!(run.statistics.steps, steps);
    let initial = observers.0.initial.unwrap();
    let last = run.last.spatial_momentum::<Power<Rotations, K, 3, 9>>();
    let vertical = (0..K)
        .map(|j| last[3 * j + 2] - initial[3 * j + 2])
        .sum::<f64>()
        .abs();
    let spins = (0..K).fold(0.0_f64, |worst, j| {
        worst.max(run.last.momentum[3 * j + 2].abs())
    });
    let scale = initial.amax();
    let energy = chain.energy(&g0, &xi0).abs().max(1.0);
    (
        vertical.max(spins) / scale,
        observers.1.max / energy,
        observers.2.max,
        scale,
    )
}

/// A chain of `K` links over `steps` steps of size `h` with 2 points: the vertical angular
/// momentum and the spins to round-off, the relative energy error below `energy_bound`, the
/// links in SO(3).
fn check_chain<const K: usize, const N: usize, const E: usize>(
    h: f64,
    steps: usize,
    energy_bound: f64,
) {
    let (momentum, energy, defect, _) = chain_run::<K, N, E>(2, h, steps);
    println!(
        "chain of {K}, lie-svi 2 points, h = {h}, {steps} steps: momentum drift {momentum:e}, \
         energy {energy:e}, ‖RᵀR − I‖ {defect:e}"
    );
    assert!(momentum < 1e-13, "{K} links: {momentum:e}");
    assert!(energy < energy_bound, "{K} links: {energy:e}");
    assert!(defect < 1e-13, "{K} links: {defect:e}");
}

/// Eight links (dimension 24) and thirty-two (dimension 96, in a test thread's stack), with
/// the structured derivatives of their terms on pairs of links.
#[test]
fn chains_of_eight_and_thirty_two_links_keep_their_momenta() {
    check_chain::<8, 24, 72>(0.002, 2000, 1e-6);
    check_chain::<32, 96, 288>(0.001, 20, 1e-8);
}

/// The long run of issue #38: eight links over 10⁶ steps, the energy error's maximum over
/// the whole run against that over its first 10⁵ steps (bounded: no drift). About half an
/// hour; run with `cargo test --release -p svi --test integration
/// chain_of_eight_links_over -- --ignored --nocapture`.
#[test]
#[ignore = "10⁶ steps: a measurement for the closing note, not a CI test"]
fn chain_of_eight_links_over_a_million_steps() {
    let (_, early, ..) = chain_run::<8, 24, 72>(2, 0.002, 100_000);
    let (momentum, energy, defect, scale) = chain_run::<8, 24, 72>(2, 0.002, 1_000_000);
    println!(
        "chain of 8, lie-svi 2 points, h = 0.002, 10⁶ steps: momentum drift {momentum:e} \
         (relative to {scale:e}), energy {energy:e} (first 10⁵ steps: {early:e}), \
         ‖RᵀR − I‖ {defect:e}"
    );
    assert!(momentum < 1e-12, "{momentum:e}");
    assert!(energy < 2.0 * early, "{energy:e} against {early:e}");
    assert!(defect < 1e-12, "{defect:e}");
}

/// A chain of two links whose one coupling term names a third link that does not exist.
struct MisnumberedChain(DoubleSphericalPendulum);

impl PairTerms<3, 9> for MisnumberedChain {
    type Factor = Rotations;
    fn term_count(&self) -> usize {
        self.0.term_count()
    }
    fn factors(&self, e: usize) -> [usize; 2] {
        let [i, j] = self.0.factors(e);
        if i == j { [i, j] } else { [i, 2] }
    }
    fn term<D: Scalar>(&self, e: usize, g: [&SVector<D, 9>; 2], xi: [&SVector<D, 3>; 2]) -> D {
        self.0.term(e, g, xi)
    }
}

impl GroupLagrangian<6, 18> for MisnumberedChain {
    type Group = Power<Rotations, 2, 3, 9>;
    const STRUCTURED: bool = true;
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 18>, xi: &SVector<D, 6>) -> D {
        self.0.lagrangian(g, xi)
    }
    fn check_structure(&self) -> Result<(), Error> {
        pair_terms::check_factors::<_, 3, 9, 6>(self)
    }
}

#[test]
fn a_pair_term_reading_a_missing_factor_is_a_typed_error() {
    let chain = DoubleSphericalPendulum::default();
    let start = chain.state(&[-Vector3::z(); 2], &[Vector3::x(); 2]);
    let error = failure(MisnumberedChain(chain), start);
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "factors"),
        "{error}"
    );
    assert!(
        error.to_string().contains("term 2 reads factor 2"),
        "{error}"
    );
}

/// The heavy top written on SE(3), its pivot frame in uniform motion (`HeavyTopOnRigidMotions`),
/// against the same top on SO(3): with the pivot at rest the two steps solve the same
/// equations (SE(3)'s dexp is block-triangular, and the translation's momentum is zero); with
/// the pivot moving they are different discretisations of the same motion, and their attitudes
/// and the pivot's position agree to the method's order (4 with 3 points).
#[test]
fn heavy_top_on_se3_agrees_with_the_top_on_so3() {
    let top = HeavyTop::default();
    let on_se3 = HeavyTopOnRigidMotions::default();
    let r0 = so3::exp(&Vector3::new(0.5, 0.0, 0.0));
    let omega0 = Vector3::new(0.0, 0.0, 10.0);
    let t_end = 2.0;
    let difference = |u: Vector3, h: f64| {
        let on_so3 = RigidBodyIntegrator::new(top, LieSvi::new(3))
            .run(
                0.0,
                RigidInitial::Velocity {
                    r: r0,
                    omega: omega0,
                },
                h,
                t_end,
                &mut (),
            )
            .unwrap();
        let v0 = r0.transpose() * u;
        let xi0 = SVector::from([omega0[0], omega0[1], omega0[2], v0[0], v0[1], v0[2]]);
        let g0 = RigidMotions::element(&r0, &Vector3::zeros());
        let (run, (momentum, energy, defect)) =
            observed_run(on_se3, LieSvi::new(3), (g0, xi0), h, t_end);
        // The vertical angular momentum and the three linear momenta are conserved.
        let drift = momentum.max.rows(2, 4).amax();
        assert!(drift < 1e-12, "{drift:e}");
        assert!(
            defect.max < 1e-14 && energy.max < 1e-5,
            "{defect:?} {energy:?}"
        );
        let attitude =
            so3::log(&(on_so3.state.r.transpose() * RigidMotions::rotation(&run.last.g))).norm();
        let position = (RigidMotions::position(&run.last.g) - u * t_end).norm();
        attitude.max(position)
    };
    let at_rest = difference(Vector3::zeros(), 0.01);
    let moving = [0.02, 0.01].map(|h| difference(Vector3::new(0.3, -0.2, 0.1), h));
    let order = (moving[0] / moving[1]).log2();
    println!(
        "heavy top on SE(3) against SO(3), T = 2: pivot at rest {at_rest:e}; moving: {moving:?}, order {order:.2}"
    );
    assert!(at_rest < 1e-12, "{at_rest:e}");
    assert!(
        moving[1] < 1e-5 && (order - 4.0).abs() < 0.3,
        "{moving:?} {order}"
    );
}
