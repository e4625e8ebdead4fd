//! Holonomic constraints: RATTLE and its compositions on the spherical pendulum and the planar
//! double pendulum in Cartesian coordinates, against independent references (the zoo's double
//! pendulum in its angles), with the conservation laws and the bad input of constraints.

use nalgebra::{Const, OVector, SVector, U2, U3, U4};
use svi::method::constrained::{
    ConstrainedDel, ConstrainedIntegrator, ConstrainedMethod, ConstrainedPoint, ConstrainedSvi,
    ConstraintPoints, Rattle, SegmentRule,
};
use svi::model::constraint::{ConstraintScratch, Constraints, ConstraintsExt};
use svi::{Integrator, Lagrangian, Scalar, Scheme, Structure, Svi};
use svi_models::double_pendulum::DoublePendulum;
use svi_models::pendulum::Pendulum;

/// A point of mass m in gravity g along −z: L = ½ m |q̇|² − m g z.
struct FallingPoint {
    m: f64,
    g: f64,
}

impl Lagrangian<U3> for FallingPoint {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 3>, v: &SVector<D, 3>) -> D {
        v.dot(v) * (0.5 * self.m) - q[2] * (self.m * self.g)
    }
}

/// The sphere |q|² − l² = 0.
struct Sphere {
    l: f64,
}

impl Constraints<U3> for Sphere {
    fn count(&self) -> usize {
        1
    }
    fn constraints<D: Scalar>(&self, q: &SVector<D, 3>, g: &mut [D]) {
        g[0] = q.dot(q) - D::from(self.l * self.l);
    }
}

const L: f64 = 1.0;
const M: f64 = 1.0;
const G: f64 = 9.81;

fn spherical(method: Rattle) -> ConstrainedIntegrator<FallingPoint, Sphere> {
    ConstrainedIntegrator::new(FallingPoint { m: M, g: G }, Sphere { l: L }, method).unwrap()
}

/// A swing 0.8 rad out, moving sideways: a non-planar orbit that precesses.
fn spherical_initial() -> (SVector<f64, 3>, SVector<f64, 3>) {
    let angle: f64 = 0.8;
    let q = SVector::from([L * angle.sin(), 0.0, -L * angle.cos()]);
    let p = SVector::from([0.0, M * 2.0, 0.0]);
    (q, p)
}

/// The final configuration of `method` over [0, t_end] in `steps` steps.
fn spherical_final(method: Rattle, t_end: f64, steps: usize) -> SVector<f64, 3> {
    let (q0, p0) = spherical_initial();
    spherical(method)
        .run(0.0, &q0, &p0, t_end / steps as f64, steps, |_| {})
        .map(|run| run.last.q)
        .unwrap_or_else(|e| {
            println!("{e}");
            SVector::repeat(f64::NAN)
        })
}

#[test]
fn rattle_and_its_compositions_have_orders_2_4_6_8_on_the_sphere() {
    let t_end = 1.0;
    let reference = spherical_final(Rattle::composed(Scheme::KahanLi8), t_end, 400);
    let cases = [
        (Rattle::default(), 100, 2.0),
        (Rattle::composed(Scheme::Yoshida4), 50, 4.0),
        (Rattle::composed(Scheme::KahanLi6), 20, 6.0),
        (Rattle::composed(Scheme::KahanLi8), 10, 8.0),
    ];
    for (method, steps, order) in cases {
        let coarse = (spherical_final(method.clone(), t_end, steps) - reference).norm();
        let fine = (spherical_final(method.clone(), t_end, 2 * steps) - reference).norm();
        let observed = (coarse / fine).log2();
        println!(
            "{}: {coarse:.3e} → {fine:.3e}, order {observed:.2}",
            method.name()
        );
        assert!(
            (observed - order).abs() < 0.3,
            "{}: observed order {observed:.2}, expected {order} ({coarse:e}, {fine:e})",
            method.name()
        );
        assert!(
            fine > 1e-14,
            "{}: below round-off, the order says nothing",
            method.name()
        );
    }
}

#[test]
fn a_long_rattle_run_stays_on_the_sphere_and_keeps_energy_and_vertical_momentum() {
    let (q0, p0) = spherical_initial();
    let energy =
        |point: &ConstrainedPoint<U3>| point.p.dot(&point.p) / (2.0 * M) + M * G * point.q[2];
    let vertical = |point: &ConstrainedPoint<U3>| point.q[0] * point.p[1] - point.q[1] * point.p[0];
    let (e0, lz0) = (energy_of(&q0, &p0, energy), q0[0] * p0[1] - q0[1] * p0[0]);
    let steps = 1_000_000;
    let h = 0.01;
    let (mut energy_error, mut lz_error): (f64, f64) = (0.0, 0.0);
    let mut early: f64 = 0.0;
    // Least-squares line through the energy error e(t): sums of t, e, t², t e.
    let mut sums = [0.0_f64; 5];
    let run = spherical(Rattle::default())
        .run(0.0, &q0, &p0, h, steps, |point| {
            let signed = energy(point) - e0;
            let error = signed.abs();
            energy_error = energy_error.max(error);
            if point.t <= 100.0 {
                early = early.max(error);
            }
            lz_error = lz_error.max((vertical(point) - lz0).abs());
            let t = point.t;
            for (sum, term) in sums.iter_mut().zip([1.0, t, signed, t * t, t * signed]) {
                *sum += term;
            }
        })
        .unwrap();
    let [count, st, se, stt, ste] = sums;
    let slope = (count * ste - st * se) / (count * stt - st * st);
    let horizon = steps as f64 * h;
    println!(
        "10⁶ RATTLE steps: |g| {:.1e}, |G q̇| {:.1e}, Lz {lz_error:.1e}, energy error {energy_error:.2e} \
         (first 100: {early:.2e}), fitted drift over the run {:.1e}",
        run.constraint_error_max,
        run.velocity_constraint_error_max,
        slope * horizon
    );
    assert!(
        (slope * horizon).abs() < early,
        "energy drifts by {:e} over the run, oscillation {early:e}",
        slope * horizon
    );
    assert_eq!(run.steps, steps);
    assert!(
        run.constraint_error_max <= 1e-12,
        "|g| = {:e}",
        run.constraint_error_max
    );
    assert!(
        run.velocity_constraint_error_max <= 1e-12,
        "|G q̇| = {:e}",
        run.velocity_constraint_error_max
    );
    assert!(
        lz_error <= 1e-12,
        "vertical angular momentum moved by {lz_error:e}"
    );
    // Bounded, no drift: over 10⁴ time units the error is what it was in the first 100.
    assert!(
        energy_error < 2.0 * early,
        "energy error {energy_error:e} after {early:e}"
    );
    assert!(
        energy_error < 1e-2 * e0.abs(),
        "energy error {energy_error:e}"
    );
}

fn energy_of(
    q: &SVector<f64, 3>,
    p: &SVector<f64, 3>,
    energy: impl Fn(&ConstrainedPoint<U3>) -> f64,
) -> f64 {
    energy(&ConstrainedPoint {
        t: 0.0,
        q: *q,
        p: *p,
        multipliers: nalgebra::DVector::zeros(1),
    })
}

#[test]
fn inconsistent_initial_data_is_projected_and_says_how_far() {
    let (q0, p0) = spherical_initial();
    let off = q0 * (1.0 + 1e-3);
    let radial = p0 + q0 * 0.5;
    let run = spherical(Rattle::default())
        .run(0.0, &off, &radial, 0.01, 10, |_| {})
        .unwrap();
    assert!((run.initial.q.norm() - L).abs() < 1e-15);
    assert!(
        (run.initial.moved_q - 1e-3 * L).abs() < 1e-9,
        "{}",
        run.initial.moved_q
    );
    // The radial part of p is removed: p ends tangent to the sphere, as it started.
    assert!(run.initial.q.dot(&run.initial.p).abs() < 1e-14);
    assert!(
        (run.initial.moved_p - 0.5 * L).abs() < 1e-3,
        "{}",
        run.initial.moved_p
    );
}

/// Constraints for the bad-input cases: the sphere written `copies` times, or a constant.
struct Bad {
    copies: usize,
    constant: bool,
}

impl Constraints<U3> for Bad {
    fn count(&self) -> usize {
        self.copies
    }
    fn constraints<D: Scalar>(&self, q: &SVector<D, 3>, g: &mut [D]) {
        for gi in g.iter_mut() {
            *gi = if self.constant {
                D::from(0.0)
            } else {
                q.dot(q) - D::from(1.0)
            };
        }
    }
    fn constraint_name(&self, index: usize) -> String {
        format!("bad[{index}]")
    }
}

#[test]
fn redundant_constant_and_too_many_constraints_are_typed_errors_naming_them() {
    let (q0, p0) = spherical_initial();
    let run = |copies, constant| {
        ConstrainedIntegrator::new(
            FallingPoint { m: M, g: G },
            Bad { copies, constant },
            Rattle::default(),
        )
        .and_then(|integrator| integrator.run(0.0, &q0, &p0, 0.01, 10, |_| {}))
        .unwrap_err()
        .to_string()
    };
    let redundant = run(2, false);
    assert!(
        redundant.contains("bad[1]") && redundant.contains("redundant"),
        "{redundant}"
    );
    let constant = run(1, true);
    assert!(
        constant.contains("bad[0]") && constant.contains("does not depend on q"),
        "{constant}"
    );
    let too_many = run(3, false);
    assert!(
        too_many.contains("3 constraints on 3 coordinates"),
        "{too_many}"
    );
    let none = run(0, false);
    assert!(none.contains("none given"), "{none}");
    let bad_step = spherical(Rattle::default())
        .run(0.0, &q0, &p0, 0.0, 10, |_| {})
        .unwrap_err()
        .to_string();
    assert!(bad_step.contains('h'), "{bad_step}");
}

/// Two points in the plane (x₁, y₁, x₂, y₂) in gravity along −y.
struct TwoPoints {
    m1: f64,
    m2: f64,
    g: f64,
}

impl Lagrangian<U4> for TwoPoints {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 4>, v: &SVector<D, 4>) -> D {
        let kinetic = (v[0] * v[0] + v[1] * v[1]) * (0.5 * self.m1)
            + (v[2] * v[2] + v[3] * v[3]) * (0.5 * self.m2);
        kinetic - q[1] * (self.m1 * self.g) - q[3] * (self.m2 * self.g)
    }
}

/// Rods of lengths d₁ (pivot to point 1) and d₂ (point 1 to point 2).
struct Rods {
    d1: f64,
    d2: f64,
}

impl Constraints<U4> for Rods {
    fn count(&self) -> usize {
        2
    }
    fn constraints<D: Scalar>(&self, q: &SVector<D, 4>, g: &mut [D]) {
        g[0] = q[0] * q[0] + q[1] * q[1] - D::from(self.d1 * self.d1);
        let (dx, dy) = (q[2] - q[0], q[3] - q[1]);
        g[1] = dx * dx + dy * dy - D::from(self.d2 * self.d2);
    }
}

/// The Cartesian positions of the angles α (from the downward vertical).
fn cartesian(zoo: &DoublePendulum, a: &OVector<f64, Const<2>>) -> SVector<f64, 4> {
    let (x1, y1) = (zoo.d1 * a[0].sin(), -zoo.d1 * a[0].cos());
    SVector::from([x1, y1, x1 + zoo.d2 * a[1].sin(), y1 - zoo.d2 * a[1].cos()])
}

#[test]
fn the_cartesian_double_pendulum_is_the_zoo_double_pendulum_in_its_angles() {
    let zoo = DoublePendulum::default();
    let (a0, w0) = (SVector::from([1.0, 0.5]), SVector::from([0.0, 0.0]));
    let t_end = 10.0;
    // The reference: the zoo model in its angles, SVI of degree 12 at a converged step.
    let reference = Integrator::new(zoo, Svi::new(13))
        .run_from_velocity(0.0, a0, w0, 0.01, t_end, &mut ())
        .unwrap()
        .last;
    let expected = cartesian(&zoo, &reference.q);
    let q0 = cartesian(&zoo, &a0);
    let p0 = SVector::zeros();
    let model = TwoPoints {
        m1: zoo.m1,
        m2: zoo.m2,
        g: zoo.g,
    };
    let rods = Rods {
        d1: zoo.d1,
        d2: zoo.d2,
    };
    let integrator =
        ConstrainedIntegrator::new(model, rods, Rattle::composed(Scheme::KahanLi8)).unwrap();
    let steps = 4000;
    let run = integrator
        .run(0.0, &q0, &p0, t_end / steps as f64, steps, |_| {})
        .unwrap();
    let error = (run.last.q - expected).amax();
    println!("kahan-li8 RATTLE, {steps} steps: {error:.2e} from the zoo's angles");
    assert!(error <= 1e-10, "{error:e}");
    assert!(run.constraint_error_max <= 1e-12 && run.velocity_constraint_error_max <= 1e-12);
    let rods = Rods {
        d1: zoo.d1,
        d2: zoo.d2,
    };
    let model = TwoPoints {
        m1: zoo.m1,
        m2: zoo.m2,
        g: zoo.g,
    };
    let steps = 1000;
    let run = ConstrainedIntegrator::new(model, rods, ConstrainedSvi::new(7, 6))
        .unwrap()
        .run(0.0, &q0, &p0, t_end / steps as f64, steps, |_| {})
        .unwrap();
    let error = (run.last.q - expected).amax();
    println!("constrained svi:7/6, {steps} steps: {error:.2e} from the zoo's angles");
    assert!(error <= 1e-10, "{error:e}");
    assert!(run.constraint_error_max <= 1e-12 && run.velocity_constraint_error_max <= 1e-12);
}

/// The final configuration of the constrained method `method` on the spherical pendulum.
fn spherical_final_of(method: ConstrainedMethod, t_end: f64, steps: usize) -> SVector<f64, 3> {
    let (q0, p0) = spherical_initial();
    ConstrainedIntegrator::new(FallingPoint { m: M, g: G }, Sphere { l: L }, method)
        .unwrap()
        .run(0.0, &q0, &p0, t_end / steps as f64, steps, |_| {})
        .unwrap()
        .last
        .q
}

#[test]
fn the_constrained_midpoint_and_svi_have_their_measured_orders_on_the_sphere() {
    let t_end = 1.0;
    let reference = spherical_final(Rattle::composed(Scheme::KahanLi8), t_end, 400);
    let nodes = |points, quadrature| {
        ConstrainedSvi::new(points, quadrature).constrained_at(ConstraintPoints::Nodes)
    };
    // (method, steps, expected order): at the Gauss points 2s, then 2s − 2; at the nodes
    // irregular.
    let cases = [
        (ConstrainedSvi::new(2, 1), 20, 2.0),
        (ConstrainedSvi::new(3, 2), 10, 4.0),
        (ConstrainedSvi::new(4, 3), 10, 4.0),
        (ConstrainedSvi::new(5, 4), 10, 6.0),
        (ConstrainedSvi::new(6, 5), 5, 8.0),
        (ConstrainedSvi::new(7, 6), 5, 10.0),
        (nodes(4, 3), 10, 4.0),
        (nodes(5, 4), 10, 6.0),
        (nodes(6, 5), 10, 4.0),
    ];
    for (method, steps, order) in cases {
        let name = method.name();
        let coarse = (spherical_final_of(method.clone().into(), t_end, steps) - reference).norm();
        let fine = (spherical_final_of(method.clone().into(), t_end, 2 * steps) - reference).norm();
        let observed = (coarse / fine).log2();
        println!(
            "{name}: {steps} → {} steps: {coarse:.2e} → {fine:.2e}, order {observed:.2}",
            2 * steps
        );
        assert!(
            (observed - order).abs() < 0.3,
            "{name}: observed order {observed:.2}, expected {order}"
        );
        assert!(
            fine > 1e-13,
            "{name}: below round-off, the order says nothing"
        );
        assert!(
            method.order() as f64 <= order,
            "{name} claims order {}",
            method.order()
        );
    }
}

#[test]
fn the_constrained_svi_keeps_the_sphere_and_the_vertical_momentum() {
    let (q0, p0) = spherical_initial();
    let lz0 = q0[0] * p0[1] - q0[1] * p0[0];
    let mut lz_error: f64 = 0.0;
    let run = ConstrainedIntegrator::new(
        FallingPoint { m: M, g: G },
        Sphere { l: L },
        ConstrainedSvi::new(5, 4),
    )
    .unwrap()
    .run(0.0, &q0, &p0, 0.05, 20_000, |point| {
        lz_error = lz_error.max((point.q[0] * point.p[1] - point.q[1] * point.p[0] - lz0).abs());
    })
    .unwrap();
    println!(
        "svi:5/4, 20 000 steps: |g| {:.1e}, |G q̇| {:.1e}, Lz {lz_error:.1e}",
        run.constraint_error_max, run.velocity_constraint_error_max
    );
    assert!(run.constraint_error_max <= 1e-12 && run.velocity_constraint_error_max <= 1e-12);
    // Noether's theorem holds to the round-off of the stage sums (their terms are s² times the
    // momentum and cancel): a random walk of ~1e-14 per step, not a drift of the method.
    assert!(lz_error <= 2e-11, "{lz_error:e}");
}

/// A pendulum in polar coordinates (r, θ), θ from the downward vertical: a mass matrix
/// diag(m, m r²) that depends on q, held at r = l by one constraint.
#[derive(Debug, Clone, Copy)]
struct Polar {
    m: f64,
    g: f64,
}

impl Lagrangian<U2> for Polar {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::General;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let kinetic = (v[0] * v[0] + q[0] * q[0] * v[1] * v[1]) * (0.5 * self.m);
        kinetic + q[0] * q[1].cos() * (self.m * self.g)
    }
}

/// r − l = 0.
#[derive(Debug)]
struct Radius {
    l: f64,
}

impl Constraints<U2> for Radius {
    fn count(&self) -> usize {
        1
    }
    fn constraints<D: Scalar>(&self, q: &SVector<D, 2>, g: &mut [D]) {
        g[0] = q[0] - D::from(self.l);
    }
}

#[test]
fn a_mass_matrix_that_depends_on_q_runs_the_constrained_svi_and_matches_the_zoo_pendulum() {
    let zoo = Pendulum::default();
    let (theta0, omega0, t_end) = (1.2, 0.0, 5.0);
    let reference = Integrator::new(zoo, Svi::new(13))
        .run_from_velocity(
            0.0,
            SVector::from([theta0]),
            SVector::from([omega0]),
            0.01,
            t_end,
            &mut (),
        )
        .unwrap()
        .last;
    let polar = Polar { m: zoo.m, g: zoo.g };
    let q0 = SVector::from([zoo.l, theta0]);
    let p0 = SVector::from([0.0, zoo.m * zoo.l * zoo.l * omega0]);
    let run = ConstrainedIntegrator::new(polar, Radius { l: zoo.l }, ConstrainedSvi::new(7, 6))
        .unwrap()
        .run(0.0, &q0, &p0, 0.01, 500, |_| {})
        .unwrap();
    let error = (run.last.q[1] - reference.q[0]).abs();
    println!("polar pendulum, svi:7/6: θ(5) off by {error:.1e}");
    assert!(error <= 1e-11, "{error:e}");
    assert!(run.constraint_error_max <= 1e-13);
    // RATTLE refuses it: its mass matrix is not constant.
    let refused =
        ConstrainedIntegrator::new(polar, Radius { l: zoo.l }, Rattle::default()).unwrap_err();
    assert!(refused.to_string().contains("constant mass"), "{refused}");
}

#[test]
fn constrained_svi_numbers_out_of_range_are_typed_errors() {
    let (q0, p0) = spherical_initial();
    let error = |method: ConstrainedSvi| {
        ConstrainedIntegrator::new(FallingPoint { m: M, g: G }, Sphere { l: L }, method)
            .unwrap()
            .run(0.0, &q0, &p0, 0.1, 3, |_| {})
            .unwrap_err()
            .to_string()
    };
    let single = error(ConstrainedSvi::new(1, 1));
    assert!(single.contains("at least 2 nodes"), "{single}");
    let empty = error(ConstrainedSvi::new(5, 0));
    assert!(empty.contains("quadrature"), "{empty}");
    let huge = error(ConstrainedSvi::new(500, 4));
    assert!(huge.contains("points"), "{huge}");
    for name in ConstrainedMethod::names() {
        let method = ConstrainedMethod::named(&name).unwrap();
        assert_eq!(method.name(), name);
    }
    assert!(ConstrainedMethod::named("svi:5").is_none());
}

#[test]
fn the_weighted_constraint_hessian_is_exact() {
    let rods = Rods { d1: 1.0, d2: 0.7 };
    let q = SVector::from([0.3, -0.9, 0.8, -1.2]);
    let mut hessian = nalgebra::DMatrix::zeros(4, 4);
    let mut scratch = ConstraintScratch::new(&q, 2);
    rods.weighted_hessian_into(&q, &[2.0, -3.0], &mut scratch, &mut hessian);
    // 2 ∇²(x₁² + y₁²) − 3 ∇²((x₂ − x₁)² + (y₂ − y₁)²).
    let expected = nalgebra::DMatrix::from_row_slice(
        4,
        4,
        &[
            4.0 - 6.0,
            0.0,
            6.0,
            0.0,
            0.0,
            4.0 - 6.0,
            0.0,
            6.0,
            6.0,
            0.0,
            -6.0,
            0.0,
            0.0,
            6.0,
            0.0,
            -6.0,
        ],
    );
    assert!((hessian - expected).amax() < 1e-14);
}

#[test]
fn the_constrained_segment_rules_have_orders_1_1_2_2_on_the_sphere() {
    let t_end = 1.0;
    let reference = spherical_final(Rattle::composed(Scheme::KahanLi8), t_end, 400);
    for rule in SegmentRule::ALL {
        let method = ConstrainedMethod::from(ConstrainedDel::new(rule));
        let (steps, order) = (200, rule.order() as f64);
        let coarse = (spherical_final_of(method.clone(), t_end, steps) - reference).norm();
        let fine = (spherical_final_of(method.clone(), t_end, 2 * steps) - reference).norm();
        let observed = (coarse / fine).log2();
        println!(
            "{}: {coarse:.2e} → {fine:.2e}, order {observed:.2}",
            rule.name()
        );
        assert!(
            (observed - order).abs() < 0.15,
            "{}: observed order {observed:.2}, expected {order}",
            rule.name()
        );
    }
}

/// The end of `steps` steps of `method` on the spherical pendulum at h = 0.05.
fn spherical_end(method: impl Into<ConstrainedMethod>, steps: usize) -> ConstrainedPoint<U3> {
    let (q0, p0) = spherical_initial();
    ConstrainedIntegrator::new(FallingPoint { m: M, g: G }, Sphere { l: L }, method)
        .unwrap()
        .run(0.0, &q0, &p0, 0.05, steps, |_| {})
        .unwrap()
        .last
}

#[test]
fn the_constrained_trapezoid_is_rattle_and_the_midpoint_rule_is_the_two_node_svi() {
    // Independent implementations of one method each: the bordered Newton system of the
    // segment rule against RATTLE's explicit kicks and drifts, and against the Galerkin step.
    let steps = 200;
    let trapezoid = spherical_end(ConstrainedDel::new(SegmentRule::Trapezoid), steps);
    let rattle = spherical_end(Rattle::default(), steps);
    let midpoint = spherical_end(ConstrainedDel::new(SegmentRule::Midpoint), steps);
    let galerkin = spherical_end(ConstrainedSvi::new(2, 1), steps);
    let pairs = [
        ("trapezoid − rattle", trapezoid, rattle),
        ("midpoint − svi:2/1", midpoint, galerkin),
    ];
    for (name, a, b) in pairs {
        let gap = (a.q - b.q).amax().max((a.p - b.p).amax());
        println!("{name}: {gap:.1e} after {steps} steps");
        assert!(gap < 1e-12, "{name}: {gap:e}");
    }
}

#[test]
fn an_observer_stops_every_constrained_method_at_the_point_it_saw() {
    use std::ops::ControlFlow;
    let (q0, p0) = spherical_initial();
    let methods: [ConstrainedMethod; 4] = [
        Rattle::default().into(),
        Rattle::composed(Scheme::Yoshida4).into(),
        ConstrainedDel::new(SegmentRule::Midpoint).into(),
        ConstrainedSvi::new(5, 4).into(),
    ];
    for method in methods {
        let name = method.name();
        let run = ConstrainedIntegrator::new(FallingPoint { m: M, g: G }, Sphere { l: L }, method)
            .unwrap()
            .run(0.0, &q0, &p0, 0.01, 1000, |point| {
                if point.t >= 0.1 - 1e-12 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .unwrap();
        assert!(run.stopped, "{name}");
        assert_eq!(run.steps, 10, "{name}");
        assert!((run.last.t - 0.1).abs() < 1e-12, "{name}");
        assert!(run.evaluations > 0 && run.factorizations > 0, "{name}");
    }
}
