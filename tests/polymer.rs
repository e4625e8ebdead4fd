//! The polymer chain (`svi_models::Polymer`): n beads in ℝ³ with rigid bonds as local
//! constraints, run by RATTLE on the sparse path — against the dense path of the same
//! constraints, over long runs (bonds, energy, momenta), composed with kahan-li8, at 10⁴
//! beads, without allocating per step, and with bad constraints as typed errors.

use crate::allocations;

use nalgebra::{Const, DVector, SVector};
use svi::method::constrained::{ConstrainedIntegrator, ConstrainedRun, Rattle};
use svi::model::constraint::Constraints;
use svi::model::constraint::local::{LocalConstraints, SparseConstraints};
use svi::model::local::{LocalDefaults, Terms};
use svi::{Dyn, LagrangianExt, Scalar, Scheme};
use svi_models::Polymer;
use svi_models::polymer::Bonds;

/// The same bonds without their locality: the dense path of `Constraints`.
struct Dense(SparseConstraints<Bonds>);

impl Constraints<Dyn> for Dense {
    fn count(&self) -> usize {
        self.0.count()
    }
    fn constraints<D: Scalar>(&self, q: &DVector<D>, g: &mut [D]) {
        self.0.constraints(q, g);
    }
}

fn polymer(n: usize, gravity: f64) -> Polymer {
    let mut polymer = Polymer::default();
    polymer.set_parameter("n", n as f64).unwrap();
    polymer.set_parameter("gravity", gravity).unwrap();
    polymer.set_parameter("mass", 1.5).unwrap();
    polymer
}

/// The default state as (q₀, p₀).
fn initial(polymer: &Polymer) -> (DVector<f64>, DVector<f64>) {
    let (_, q, v) = polymer.initial_state();
    (q, v * polymer.mass)
}

/// `steps` steps of size `h` of `method` on `constraints`, with every point seen.
fn run<C: Constraints<Dyn>>(
    polymer: &Polymer,
    constraints: C,
    method: Rattle,
    h: f64,
    steps: usize,
    observe: impl FnMut(&svi::method::constrained::ConstrainedPoint<Dyn>),
) -> ConstrainedRun<Dyn> {
    let (q0, p0) = initial(polymer);
    ConstrainedIntegrator::new(Terms(polymer.clone()), constraints, method)
        .unwrap()
        .run(0.0, &q0, &p0, h, steps, observe)
        .unwrap()
}

/// Every point's (q, p) of a run.
type Trajectory = Vec<(DVector<f64>, DVector<f64>)>;

/// The trajectory of a run of 300 steps, and the run.
fn trajectory<C: Constraints<Dyn>>(
    polymer: &Polymer,
    constraints: C,
    method: Rattle,
) -> (Trajectory, ConstrainedRun<Dyn>) {
    let mut points = Vec::new();
    let run = run(polymer, constraints, method, 0.01, 300, |point| {
        points.push((point.q.clone(), point.p.clone()));
    });
    (points, run)
}

#[test]
fn the_sparse_path_equals_the_dense_path() {
    for (n, gravity, method) in [
        (5, 0.0, Rattle::default()),
        (8, 9.81, Rattle::default()),
        (6, 9.81, Rattle::composed(Scheme::KahanLi8)),
    ] {
        let polymer = polymer(n, gravity);
        let (sparse, sparse_run) =
            trajectory(&polymer, SparseConstraints(polymer.bonds()), method.clone());
        let (dense, dense_run) = trajectory(
            &polymer,
            Dense(SparseConstraints(polymer.bonds())),
            method.clone(),
        );
        let difference = sparse
            .iter()
            .zip(&dense)
            .map(|((qs, ps), (qd, pd))| (qs - qd).amax().max((ps - pd).amax()))
            .fold(0.0, f64::max);
        println!(
            "{} beads, {}: sparse and dense differ by {difference:.1e} over 300 steps",
            n,
            method.name()
        );
        assert!(difference < 1e-13, "{difference:e}");
        assert_eq!(sparse.len(), 301);
        assert!((sparse_run.initial.q.clone() - dense_run.initial.q).amax() < 1e-15);
        assert!(sparse_run.constraint_error_max < 1e-13);
        assert!(sparse_run.velocity_constraint_error_max < 1e-13);
    }
}

#[test]
fn a_long_run_keeps_the_bonds_the_energy_and_the_momenta() {
    let polymer = polymer(40, 0.0);
    let terms = Terms(polymer.clone());
    let energy = |q: &DVector<f64>, p: &DVector<f64>| terms.energy(0.0, q, &(p / polymer.mass));
    let (q0, p0) = initial(&polymer);
    let (e0, momentum0, angular0) = (
        energy(&q0, &p0),
        polymer.momentum(&p0) / polymer.mass,
        polymer.angular_momentum(&q0, &p0) / polymer.mass,
    );
    let (mut energy_error, mut early, mut momentum_error, mut angular_error) =
        (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    let steps = 50_000;
    let run = run(
        &polymer,
        SparseConstraints(polymer.bonds()),
        Rattle::default(),
        0.01,
        steps,
        |point| {
            let error = (energy(&point.q, &point.p) - e0).abs();
            energy_error = energy_error.max(error);
            if point.t <= 50.0 {
                early = early.max(error);
            }
            let momentum = polymer.momentum(&point.p) / polymer.mass;
            momentum_error = momentum_error.max((momentum - momentum0).amax());
            let angular = polymer.angular_momentum(&point.q, &point.p) / polymer.mass;
            angular_error = angular_error.max((angular - angular0).amax());
        },
    );
    println!(
        "40 beads, {steps} RATTLE steps: |g| {:.1e}, |G q̇| {:.1e}, energy error {energy_error:.2e} \
         (first 50 time units {early:.2e}, E₀ = {e0:.3}), momentum {momentum_error:.1e}, angular \
         momentum {angular_error:.1e}, {:.1} Newton iterations a step",
        run.constraint_error_max,
        run.velocity_constraint_error_max,
        run.iterations as f64 / steps as f64
    );
    assert_eq!(run.steps, steps);
    assert!(run.constraint_error_max <= 1e-12);
    assert!(run.velocity_constraint_error_max <= 1e-12);
    assert!(momentum_error <= 1e-12, "{momentum_error:e}");
    assert!(angular_error <= 1e-11, "{angular_error:e}");
    assert!(
        energy_error < 2.0 * early,
        "energy error {energy_error:e} after {early:e}"
    );
    assert!(energy_error < 1e-2 * e0.abs(), "{energy_error:e}");
}

#[test]
fn rattle_composed_with_kahan_li8_converges_with_order_8() {
    let polymer = polymer(12, 9.81);
    let t_end = 2.0;
    let last = |steps: usize| {
        run(
            &polymer,
            SparseConstraints(polymer.bonds()),
            Rattle::composed(Scheme::KahanLi8),
            t_end / steps as f64,
            steps,
            |_| {},
        )
    };
    let reference = last(160).last.q;
    let (coarse, fine) = (last(10), last(20));
    let (coarse_error, fine_error) = (
        (&coarse.last.q - &reference).amax(),
        (&fine.last.q - &reference).amax(),
    );
    let order = (coarse_error / fine_error).log2();
    println!(
        "kahan-li8 RATTLE on 12 beads: {coarse_error:.2e} → {fine_error:.2e}, order {order:.2}"
    );
    assert!((order - 8.0).abs() < 0.5, "order {order}");
    assert!(
        fine_error > 1e-13,
        "below round-off, the order says nothing"
    );
    assert!(fine.constraint_error_max < 1e-12 && fine.velocity_constraint_error_max < 1e-12);
}

#[test]
fn ten_thousand_beads_step_on_the_sparse_path() {
    let polymer = polymer(10_000, 9.81);
    let run = run(
        &polymer,
        SparseConstraints(polymer.bonds()),
        Rattle::default(),
        0.01,
        5,
        |_| {},
    );
    assert!(
        run.constraint_error_max < 1e-11,
        "{}",
        run.constraint_error_max
    );
    assert!(run.velocity_constraint_error_max < 1e-11);
}

#[test]
fn sparse_steps_allocate_nothing() {
    let polymer = polymer(20, 9.81);
    let allocations_of = |steps: usize| {
        let before = allocations::count();
        run(
            &polymer,
            SparseConstraints(polymer.bonds()),
            Rattle::default(),
            0.01,
            steps,
            |_| {},
        );
        allocations::count() - before
    };
    let (short, long) = (allocations_of(10), allocations_of(500));
    assert_eq!(
        short, long,
        "{short} allocations for 10 steps, {long} for 500"
    );
}

/// The bonds with one more constraint: the bond between beads 0 and 1 again, a constant, a
/// coordinate outside q, or x₀ + x₁ = const (with the bonds' neighbours, dependent on them
/// only through the sum of two more constraints, see `Linear`).
struct Extra {
    bonds: Bonds,
    kind: Kind,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Duplicate,
    Constant,
    Outside,
}

impl LocalConstraints for Extra {
    type Width = Const<6>;
    fn count(&self) -> usize {
        self.bonds.count() + 1
    }
    fn indices(&self, i: usize) -> [usize; 6] {
        match (i == self.bonds.count(), self.kind) {
            (true, Kind::Outside) => [0, 1, 2, 3, 4, 3 * self.bonds.n],
            (true, _) => self.bonds.indices(0),
            (false, _) => self.bonds.indices(i),
        }
    }
    fn constraint<D: Scalar>(&self, i: usize, q: &SVector<D, 6>) -> D {
        if i == self.bonds.count() && self.kind == Kind::Constant {
            return D::from(0.0);
        }
        self.bonds.constraint(0, q)
    }
    fn constraint_name(&self, i: usize) -> String {
        if i == self.bonds.count() {
            "extra".into()
        } else {
            self.bonds.constraint_name(i)
        }
    }
}

/// Three linear constraints on two coordinates' sums, pairwise independent but dependent
/// together: x₀ = 1, x₁ = 2, x₀ + x₁ = 3 (x₀, x₁ the first coordinates of beads 0 and 1).
struct Linear;

impl LocalConstraints for Linear {
    type Width = Const<2>;
    fn count(&self) -> usize {
        3
    }
    fn indices(&self, i: usize) -> [usize; 2] {
        [[0, 0], [3, 3], [0, 3]][i]
    }
    fn constraint<D: Scalar>(&self, i: usize, q: &SVector<D, 2>) -> D {
        match i {
            0 => q[0] - D::from(1.0),
            1 => q[0] - D::from(2.0),
            _ => q[0] + q[1] - D::from(3.0),
        }
    }
}

/// The error message of a run of `constraints` on the polymer of `n` beads.
fn error_of<C: Constraints<Dyn>>(n: usize, constraints: C) -> String {
    let polymer = polymer(n, 0.0);
    let (q0, p0) = initial(&polymer);
    ConstrainedIntegrator::new(Terms(polymer), constraints, Rattle::default())
        .and_then(|integrator| integrator.run(0.0, &q0, &p0, 0.01, 10, |_| {}))
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_local_constraints_are_typed_errors_naming_them() {
    let extra = |kind| {
        error_of(
            6,
            SparseConstraints(Extra {
                bonds: polymer(6, 0.0).bonds(),
                kind,
            }),
        )
    };
    let duplicate = extra(Kind::Duplicate);
    assert!(
        duplicate.contains("extra is redundant") && duplicate.contains("bond[0]"),
        "{duplicate}"
    );
    let constant = extra(Kind::Constant);
    assert!(
        constant.contains("extra") && constant.contains("does not depend on q"),
        "{constant}"
    );
    let outside = extra(Kind::Outside);
    assert!(outside.contains("extra reads coordinate 18"), "{outside}");
    let dependent = error_of(3, SparseConstraints(Linear));
    assert!(dependent.contains("singular"), "{dependent}");
    let too_many = error_of(
        2,
        SparseConstraints(Extra {
            bonds: Bonds { n: 7, bond: 1.0 },
            kind: Kind::Duplicate,
        }),
    );
    assert!(
        too_many.contains("7 constraints on 6 coordinates"),
        "{too_many}"
    );
}

#[test]
fn inconsistent_initial_data_is_projected_on_the_sparse_path() {
    let polymer = polymer(50, 9.81);
    let (q0, p0) = initial(&polymer);
    let off = q0.map(|x| x * (1.0 + 1e-3));
    let pushed = &p0 + DVector::from_fn(q0.len(), |i, _| (0.37 * i as f64).sin());
    let run = ConstrainedIntegrator::new(
        Terms(polymer.clone()),
        SparseConstraints(polymer.bonds()),
        Rattle::default(),
    )
    .unwrap()
    .run(0.0, &off, &pushed, 0.01, 10, |_| {})
    .unwrap();
    let bonds = SparseConstraints(polymer.bonds());
    let rate = svi::model::constraint::ConstraintsExt::jacobian(&bonds, &run.initial.q)
        * (&run.initial.p / polymer.mass);
    assert!(run.initial.moved_q > 1e-4 && run.initial.moved_p > 1.0);
    assert!(svi::model::constraint::ConstraintsExt::values(&bonds, &run.initial.q).amax() < 1e-13);
    assert!(rate.amax() < 1e-13, "{}", rate.amax());
    // The dense projection of the same data lands on the same point.
    let dense = ConstrainedIntegrator::new(
        Terms(polymer.clone()),
        Dense(SparseConstraints(polymer.bonds())),
        Rattle::default(),
    )
    .unwrap()
    .run(0.0, &off, &pushed, 0.01, 0, |_| {})
    .unwrap();
    assert!((&dense.initial.q - &run.initial.q).amax() < 1e-13);
    assert!((&dense.initial.p - &run.initial.p).amax() < 1e-13);
}
