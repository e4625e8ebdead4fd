//! Tests of the methods on Hamilton's equations: orders against an independent reference,
//! the coincidences with the variational integrators, the explicit separable path,
//! symplecticity, forces and bad input.

use super::{ImplicitMidpoint, Partitioned};
use crate::analysis::verify::observed_order;
use crate::error::Error;
use crate::method::variational::composition::{Composition, Scheme};
use crate::method::variational::discrete_lagrangian::{
    AdjointSymplecticEuler, Midpoint, SymplecticEuler, Trapezoid,
};
use crate::method::{Initial, Method, State};
use crate::model::hamiltonian::{Canonical, Hamiltonian, HamiltonianStructure};
use crate::model::{Lagrangian, Structure};
use crate::scalar::Scalar;
use crate::stepping::run::Integrator;
use crate::test_models::{
    Damped, VariableMass, advance, assert_tangent_matches_central_differences, distance, state,
};
use crate::{StormerVerlet, VariationalIntegrator};
use nalgebra::{DMatrix, SVector, U1, U2};

/// A relativistic oscillator H = √(1 + p²) + q²/2, declared separable (`SEPARABLE`) or not.
struct Relativistic<const SEPARABLE: bool>;

impl<const SEPARABLE: bool> Hamiltonian<U1> for Relativistic<SEPARABLE> {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = if SEPARABLE {
        HamiltonianStructure::Separable
    } else {
        HamiltonianStructure::General
    };
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
        (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
    }
}

/// [`VariableMass`] written as H: p₀²/(2(1 + q₁²)) + p₁²/2 + (q₀² + q₁²)/2 + q₀⁴/4 (not
/// separable).
struct VariableMassH;

impl Hamiltonian<U2> for VariableMassH {
    const TIME_DEPENDENT: bool = false;
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
        p[0] * p[0] / ((q[1] * q[1] + 1.0) * 2.0)
            + p[1] * p[1] * 0.5
            + (q[0] * q[0] + q[1] * q[1]) * 0.5
            + q[0].powi(4) * 0.25
    }
}

/// The pendulum H = p²/2 − cos q, and as L = q̇²/2 + cos q.
struct PendulumH;

impl Hamiltonian<U1> for PendulumH {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
        p[0] * p[0] * 0.5 - q[0].cos()
    }
}

struct Pendulum;

impl Lagrangian<U1> for Pendulum {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        v[0] * v[0] * 0.5 + q[0].cos()
    }
}

/// The damped oscillator H = (p² + q²)/2 with f_H = −c p: [`Damped`] written as H.
struct DampedH {
    c: f64,
}

impl Hamiltonian<U1> for DampedH {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
    const FORCED: bool = true;
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
        (p[0] * p[0] + q[0] * q[0]) * 0.5
    }
    fn external_force<D: Scalar>(
        &self,
        _t: D,
        _q: &SVector<D, 1>,
        p: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        p.map(|x| x * (-self.c))
    }
}

/// The seven methods, by registry name.
fn methods() -> Vec<(&'static str, usize, Method7)> {
    vec![
        (
            "symplectic-euler-h",
            1,
            Method7::Partitioned(Partitioned::symplectic_euler()),
        ),
        (
            "symplectic-euler-adjoint-h",
            1,
            Method7::Partitioned(Partitioned::adjoint_symplectic_euler()),
        ),
        (
            "midpoint-h",
            2,
            Method7::Midpoint(ImplicitMidpoint::default()),
        ),
        (
            "verlet-h",
            2,
            Method7::Partitioned(Partitioned::stormer_verlet()),
        ),
        (
            "yoshida4-h",
            4,
            Method7::Composition(Composition::hamiltonian(Scheme::Yoshida4)),
        ),
        (
            "kahan-li6-h",
            6,
            Method7::Composition(Composition::hamiltonian(Scheme::KahanLi6)),
        ),
        (
            "kahan-li8-h",
            8,
            Method7::Composition(Composition::hamiltonian(Scheme::KahanLi8)),
        ),
    ]
}

/// One of the methods as a value (the tests' own small `AnyMethod`).
enum Method7 {
    Partitioned(Partitioned),
    Midpoint(ImplicitMidpoint),
    Composition(Composition<Partitioned>),
}

impl Method7 {
    /// `steps` steps of size `h` from `start` (at t = 0): the end state.
    fn advance<L: Lagrangian<nalgebra::Const<K>>, const K: usize>(
        &self,
        model: &L,
        h: f64,
        steps: usize,
        start: State<nalgebra::Const<K>>,
    ) -> State<nalgebra::Const<K>> {
        match self {
            Method7::Partitioned(m) => advance(m, model, h, steps, start).0,
            Method7::Midpoint(m) => advance(m, model, h, steps, start).0,
            Method7::Composition(m) => advance(m, model, h, steps, start).0,
        }
    }

    /// The tangent map of one step of size `h` from `start`.
    fn tangent<L: Lagrangian<nalgebra::Const<K>>, const K: usize>(
        &self,
        model: &L,
        h: f64,
        start: &State<nalgebra::Const<K>>,
    ) -> DMatrix<f64> {
        fn one<M: Method<nalgebra::Const<K>>, L: Lagrangian<nalgebra::Const<K>>, const K: usize>(
            method: &M,
            model: &L,
            h: f64,
            start: &State<nalgebra::Const<K>>,
        ) -> DMatrix<f64> {
            let mut workspace = method.workspace(model, h).unwrap();
            let (_, tangent, _) = method
                .tangent_map(model, &mut workspace, 0.0, h, start)
                .unwrap();
            tangent.matrix()
        }
        match self {
            Method7::Partitioned(m) => one(m, model, h, start),
            Method7::Midpoint(m) => one(m, model, h, start),
            Method7::Composition(m) => one(m, model, h, start),
        }
    }
}

/// Hamilton's equations integrated by the classical Runge–Kutta method of order 4 with the
/// field `field` written by hand: an independent reference (h = 1e-4: error ~ 1e-16).
fn reference<const K: usize>(
    field: impl Fn(&SVector<f64, K>, &SVector<f64, K>) -> (SVector<f64, K>, SVector<f64, K>),
    start: State<nalgebra::Const<K>>,
    t_end: f64,
) -> State<nalgebra::Const<K>> {
    let steps = (t_end / 1e-4).round() as usize;
    let h = t_end / steps as f64;
    let (mut q, mut p) = (start.q, start.y);
    for _ in 0..steps {
        let (a1, b1) = field(&q, &p);
        let (a2, b2) = field(&(q + a1 * (h / 2.0)), &(p + b1 * (h / 2.0)));
        let (a3, b3) = field(&(q + a2 * (h / 2.0)), &(p + b2 * (h / 2.0)));
        let (a4, b4) = field(&(q + a3 * h), &(p + b3 * h));
        q += (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (h / 6.0);
        p += (b1 + b2 * 2.0 + b3 * 2.0 + b4) * (h / 6.0);
    }
    State { q, y: p }
}

/// `numbers` in scientific notation.
fn scientific(numbers: &[f64]) -> String {
    let numbers: Vec<String> = numbers.iter().map(|x| format!("{x:.3e}")).collect();
    numbers.join(" ")
}

/// The observed order of each method at T = 1 over steps 1/4 … 1/64 (compositions: from 1/2),
/// against the reference.
fn assert_orders<H: Hamiltonian<nalgebra::Const<K>>, const K: usize>(
    model: H,
    start: State<nalgebra::Const<K>>,
    exact: State<nalgebra::Const<K>>,
) -> Vec<(&'static str, f64)> {
    let model = Canonical::new(model);
    let mut observed = Vec::new();
    for (name, order, method) in methods() {
        let counts: &[usize] = match order {
            8 => &[4, 6, 8, 10],
            6 => &[4, 6, 8, 12],
            4 => &[8, 16, 32, 64],
            _ => &[16, 32, 64, 128],
        };
        let steps: Vec<f64> = counts.iter().map(|&n| 1.0 / n as f64).collect();
        let errors: Vec<f64> = counts
            .iter()
            .map(|&n| distance(&method.advance(&model, 1.0 / n as f64, n, start), &exact))
            .collect();
        let slope = observed_order(&steps, &errors, 1e-12).unwrap();
        assert!(
            (slope - order as f64).abs() < 0.3,
            "{name}: observed order {slope:.2}, errors {}",
            scientific(&errors)
        );
        eprintln!("{name}: errors {}, order {slope:.2}", scientific(&errors));
        observed.push((name, slope));
    }
    observed
}

#[test]
fn orders_on_a_relativistic_oscillator_and_a_variable_mass() {
    let start = state([1.2], [0.3]);
    let exact = reference(|q, p| (p.map(|p| p / (1.0 + p * p).sqrt()), -q), start, 1.0);
    let separable = assert_orders(Relativistic::<true>, start, exact);
    let general = assert_orders(Relativistic::<false>, start, exact);
    let start = state([0.5, -0.3], [0.4, 0.6]);
    let exact = reference(
        |q, p| {
            let m = 1.0 + q[1] * q[1];
            (
                SVector::from([p[0] / m, p[1]]),
                SVector::from([-q[0] - q[0].powi(3), -q[1] + p[0] * p[0] * q[1] / (m * m)]),
            )
        },
        start,
        1.0,
    );
    let variable = assert_orders(VariableMassH, start, exact);
    eprintln!(
        "observed orders: separable {separable:.2?}\ngeneral {general:.2?}\nvariable mass {variable:.2?}"
    );
}

/// ‖a − b‖ of `steps` steps of two runs, printed and returned.
fn gap<const K: usize>(
    what: &str,
    a: &State<nalgebra::Const<K>>,
    b: &State<nalgebra::Const<K>>,
) -> f64 {
    let gap = distance(a, b);
    eprintln!("{what}: {gap:.1e}");
    gap
}

#[test]
fn the_hamiltonian_maps_are_the_variational_ones_through_the_legendre_map() {
    let (h, steps) = (0.1, 100);
    // Variable mass: symplectic Euler, its adjoint and the midpoint rule for every L.
    let start = state([0.5, -0.3], [0.4, 0.6]);
    let written = Canonical::new(VariableMassH);
    let pairs: [(&str, State<U2>, State<U2>); 3] = [
        (
            "symplectic-euler",
            advance(&Partitioned::symplectic_euler(), &written, h, steps, start).0,
            advance(
                &VariationalIntegrator::new(SymplecticEuler),
                &VariableMass,
                h,
                steps,
                start,
            )
            .0,
        ),
        (
            "symplectic-euler-adjoint",
            advance(
                &Partitioned::adjoint_symplectic_euler(),
                &written,
                h,
                steps,
                start,
            )
            .0,
            advance(
                &VariationalIntegrator::new(AdjointSymplecticEuler),
                &VariableMass,
                h,
                steps,
                start,
            )
            .0,
        ),
        (
            "midpoint",
            advance(&ImplicitMidpoint::default(), &written, h, steps, start).0,
            advance(
                &VariationalIntegrator::new(Midpoint),
                &VariableMass,
                h,
                steps,
                start,
            )
            .0,
        ),
    ];
    for (name, a, b) in &pairs {
        assert!(gap(&format!("{name}-h on H vs {name} on L"), a, b) < 1e-13);
    }
    // Störmer–Verlet: the adjoint variational symplectic Euler of step h/2 after the
    // variational symplectic Euler of step h/2; not the trapezoid for a variable mass.
    let verlet = advance(&Partitioned::stormer_verlet(), &written, h, steps, start).0;
    let mut composed = start;
    for k in 0..steps {
        let mut increment = State::zeros(nalgebra::Const::<2>);
        for (i, rule) in [true, false].into_iter().enumerate() {
            let t = (k as f64 + 0.5 * i as f64) * h;
            if rule {
                let method = VariationalIntegrator::new(SymplecticEuler);
                let mut workspace = method.workspace(&VariableMass, h / 2.0).unwrap();
                method
                    .step(
                        &VariableMass,
                        &mut workspace,
                        t,
                        h / 2.0,
                        &composed,
                        &mut increment,
                    )
                    .unwrap();
            } else {
                let method = VariationalIntegrator::new(AdjointSymplecticEuler);
                let mut workspace = method.workspace(&VariableMass, h / 2.0).unwrap();
                method
                    .step(
                        &VariableMass,
                        &mut workspace,
                        t,
                        h / 2.0,
                        &composed,
                        &mut increment,
                    )
                    .unwrap();
            }
            composed.q += &increment.q;
            composed.y += &increment.y;
        }
    }
    assert!(
        gap(
            "verlet-h on H vs adjoint(h/2) ∘ euler(h/2) on L",
            &verlet,
            &composed
        ) < 1e-13
    );
    let trapezoid = advance(
        &VariationalIntegrator::new(Trapezoid),
        &VariableMass,
        h,
        steps,
        start,
    )
    .0;
    assert!(
        gap(
            "verlet-h vs trapezoid, variable mass (O(h²) apart)",
            &verlet,
            &trapezoid
        ) > 1e-6
    );
    // The pendulum, a constant mass: verlet-h is Störmer–Verlet and the trapezoid.
    let start = state([1.0], [0.5]);
    let verlet = advance(
        &Partitioned::stormer_verlet(),
        &Canonical::new(PendulumH),
        h,
        steps,
        start,
    )
    .0;
    let lagrangian = advance(&StormerVerlet::default(), &Pendulum, h, steps, start).0;
    let trapezoid = advance(
        &VariationalIntegrator::new(Trapezoid),
        &Pendulum,
        h,
        steps,
        start,
    )
    .0;
    assert!(
        gap(
            "verlet-h on H vs verlet on L, pendulum",
            &verlet,
            &lagrangian
        ) < 1e-13
    );
    assert!(
        gap(
            "verlet-h on H vs trapezoid on L, pendulum",
            &verlet,
            &trapezoid
        ) < 1e-13
    );
}

#[test]
fn a_model_written_as_l_runs_the_same_steps_as_written_as_h() {
    let (h, steps) = (0.1, 50);
    let start = state([0.5, -0.3], [0.4, 0.6]);
    for (name, _, method) in methods() {
        let from_h = method.advance(&Canonical::new(VariableMassH), h, steps, start);
        let from_l = method.advance(&VariableMass, h, steps, start);
        assert!(gap(&format!("{name}: L vs H, variable mass"), &from_h, &from_l) < 1e-12);
    }
    let start = state([1.0], [0.5]);
    for (name, _, method) in methods() {
        let from_h = method.advance(&Canonical::new(PendulumH), h, steps, start);
        let from_l = method.advance(&Pendulum, h, steps, start);
        assert!(gap(&format!("{name}: L vs H, pendulum"), &from_h, &from_l) < 1e-13);
    }
}

#[test]
fn a_separable_h_is_explicit_and_takes_the_implicit_paths_steps() {
    let (h, start) = (0.1, state([1.2], [0.3]));
    for method in [
        Partitioned::symplectic_euler(),
        Partitioned::adjoint_symplectic_euler(),
        Partitioned::stormer_verlet(),
    ] {
        let model = Canonical::new(Relativistic::<true>);
        let mut workspace = Method::<U1>::workspace(&method, &model, h).unwrap();
        let (mut current, mut increment) = (start, start);
        for k in 0..100 {
            let report = method
                .step(
                    &model,
                    &mut workspace,
                    k as f64 * h,
                    h,
                    &current,
                    &mut increment,
                )
                .unwrap();
            assert_eq!(report.iterations, 0);
            current.q += increment.q;
            current.y += increment.y;
        }
        let (general, _) = advance(
            &method,
            &Canonical::new(Relativistic::<false>),
            h,
            100,
            start,
        );
        let name = Method::<U1>::info(&method).name;
        assert!(gap(&format!("{name}: explicit vs Newton"), &current, &general) < 1e-13);
    }
    // Bounded energy over 10⁵ steps of verlet-h.
    let model = Canonical::new(Relativistic::<true>);
    let energy = |s: &State<U1>| (1.0 + s.y[0] * s.y[0]).sqrt() + 0.5 * s.q[0] * s.q[0];
    let method = Partitioned::stormer_verlet();
    let mut workspace = Method::<U1>::workspace(&method, &model, h).unwrap();
    let (mut current, mut increment) = (start, start);
    let (e0, mut early, mut late) = (energy(&start), 0.0_f64, 0.0_f64);
    for k in 0..100_000 {
        method
            .step(
                &model,
                &mut workspace,
                k as f64 * h,
                h,
                &current,
                &mut increment,
            )
            .unwrap();
        current.q += increment.q;
        current.y += increment.y;
        let error = (energy(&current) - e0).abs();
        if k < 10_000 {
            early = early.max(error);
        } else if k >= 90_000 {
            late = late.max(error);
        }
    }
    eprintln!(
        "relativistic verlet-h, h = 0.1: max |ΔE| {early:.2e} over the first 1e4 steps, \
         {late:.2e} over the last 1e4 of 1e5"
    );
    // Bounded, no drift: the error of the last steps is the error of the first ones.
    assert!(early < 5e-3 && late < 1.1 * early, "{early:e} {late:e}");
}

#[test]
fn every_step_is_symplectic_on_a_non_separable_h() {
    let start = state([0.5, -0.3], [0.4, 0.6]);
    let model = Canonical::new(VariableMassH);
    let omega = DMatrix::from_fn(4, 4, |i, j| match (i, j) {
        (0, 2) | (1, 3) => 1.0,
        (2, 0) | (3, 1) => -1.0,
        _ => 0.0,
    });
    for (name, _, method) in methods() {
        let phi = method.tangent(&model, 0.3, &start);
        let defect = (phi.transpose() * &omega * &phi - &omega).amax();
        eprintln!("{name}: |ΦᵀΩΦ − Ω| = {defect:.1e}");
        assert!(defect < 1e-12, "{name}: {defect:e}");
    }
    assert_tangent_matches_central_differences(&Partitioned::symplectic_euler(), &model, start);
    assert_tangent_matches_central_differences(
        &Partitioned::adjoint_symplectic_euler(),
        &model,
        start,
    );
    assert_tangent_matches_central_differences(&Partitioned::stormer_verlet(), &model, start);
    assert_tangent_matches_central_differences(&ImplicitMidpoint::default(), &model, start);
    // Forced (and a model written as L): the tangent map is still the step's Jacobian.
    let start = state([0.8], [-0.4]);
    let model = Canonical::new(DampedH { c: 0.3 });
    assert_tangent_matches_central_differences(&Partitioned::stormer_verlet(), &model, start);
    assert_tangent_matches_central_differences(&ImplicitMidpoint::default(), &model, start);
    assert_tangent_matches_central_differences(
        &Partitioned::symplectic_euler(),
        &Damped::<false> { c: 0.3 },
        start,
    );
}

#[test]
fn a_damped_oscillator_in_h_form_is_the_lagrange_dalembert_run() {
    let (c, h, steps) = (0.3, 0.05, 200);
    let start = state([1.0], [0.0]);
    let model = Canonical::new(DampedH { c });
    let lagrangian = Damped::<true> { c };
    let pairs: [(&str, State<U1>, State<U1>); 4] = [
        (
            "symplectic-euler",
            advance(&Partitioned::symplectic_euler(), &model, h, steps, start).0,
            advance(
                &VariationalIntegrator::new(SymplecticEuler),
                &lagrangian,
                h,
                steps,
                start,
            )
            .0,
        ),
        (
            "symplectic-euler-adjoint",
            advance(
                &Partitioned::adjoint_symplectic_euler(),
                &model,
                h,
                steps,
                start,
            )
            .0,
            advance(
                &VariationalIntegrator::new(AdjointSymplecticEuler),
                &lagrangian,
                h,
                steps,
                start,
            )
            .0,
        ),
        (
            "midpoint",
            advance(&ImplicitMidpoint::default(), &model, h, steps, start).0,
            advance(
                &VariationalIntegrator::new(Midpoint),
                &lagrangian,
                h,
                steps,
                start,
            )
            .0,
        ),
        (
            "verlet",
            advance(&Partitioned::stormer_verlet(), &model, h, steps, start).0,
            advance(&StormerVerlet::default(), &lagrangian, h, steps, start).0,
        ),
    ];
    for (name, a, b) in &pairs {
        assert!(gap(&format!("{name}-h vs {name}, damped"), a, b) < 1e-13);
    }
    // The energy E = (p² + q²)/2 at T = 10 against the exact solution
    // q = e^{−ct/2} (cos ωt + c/(2ω) sin ωt), ω² = 1 − c²/4: the error falls with the order.
    let t_end = 10.0;
    let omega = (1.0 - c * c / 4.0).sqrt();
    let decay = (-c * t_end / 2.0).exp();
    let (cos, sin) = ((omega * t_end).cos(), (omega * t_end).sin());
    let q = decay * (cos + c / (2.0 * omega) * sin);
    let p = -decay * sin / omega;
    let exact = 0.5 * (q * q + p * p);
    for (name, order, method) in methods() {
        let counts: &[usize] = match order {
            8 => &[10, 15, 20, 30],
            6 => &[20, 30, 40, 60],
            4 => &[50, 100, 200, 400],
            _ => &[200, 400, 800, 1600],
        };
        let errors: Vec<f64> = counts
            .iter()
            .map(|&n| {
                let end = method.advance(&model, t_end / n as f64, n, start);
                (0.5 * (end.q[0].powi(2) + end.y[0].powi(2)) - exact).abs()
            })
            .collect();
        let steps: Vec<f64> = counts.iter().map(|&n| t_end / n as f64).collect();
        let slope = observed_order(&steps, &errors, 1e-13).unwrap();
        eprintln!(
            "{name}: energy errors at T = 10 {}, order {slope:.2}",
            scientific(&errors)
        );
        assert!(slope > order as f64 - 0.3, "{name}: {slope} {errors:?}");
    }
}

#[test]
fn a_singular_h_is_a_typed_error() {
    /// H linear in p: ∂²H/∂p² = 0.
    struct Linear;
    impl Hamiltonian<U1> for Linear {
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            p[0] * q[0] + q[0] * q[0]
        }
    }
    let initial = Initial::Momentum {
        q: SVector::from([0.5]),
        p: SVector::from([0.3]),
    };
    for (name, _, method) in methods() {
        let error = match method {
            Method7::Partitioned(m) => Integrator::new(Canonical::new(Linear), m)
                .run(0.0, initial, 0.1, 1.0, &mut ())
                .map(|_| ()),
            Method7::Midpoint(m) => Integrator::new(Canonical::new(Linear), m)
                .run(0.0, initial, 0.1, 1.0, &mut ())
                .map(|_| ()),
            Method7::Composition(m) => Integrator::new(Canonical::new(Linear), m)
                .run(0.0, initial, 0.1, 1.0, &mut ())
                .map(|_| ()),
        }
        .unwrap_err();
        assert!(
            matches!(&error, Error::InvalidParameter { name, reason } if name == "model" && reason.contains("∂²H/∂p² is singular")),
            "{name}: {error}"
        );
    }
}
