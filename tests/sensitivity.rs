//! Derivatives of whole runs (`svi::sensitivity`): the discrete adjoint's gradient against
//! central differences of independent plain runs of the original model (1e-7 relative) and
//! against the forward sensitivities (1e-10 relative), for SVI, SC, midpoint, Störmer–Verlet
//! and a composition, on Kepler (with respect to e, which moves the start, and q₀) and on the
//! damped pendulum (with respect to its length, its friction and θ₀).

use nalgebra::{Const, DVector, SVector};
use svi::observer::{Every, Trajectory};
use svi::sensitivity::{Checkpoints, Loss, SensitivityRun, Start};
use svi::{
    Composition, Defaults, Dyn, Error, Initial, Integrator, Method, Midpoint, Parametric, Scalar,
    Scheme, SpectralCollocation, StormerVerlet, Svi, VariationalIntegrator,
};
use svi_models::{DampedPendulum, Kepler};

/// ℓ_j = Σᵢ (aᵢ (j + 1) qᵢ + bᵢ q̇ᵢ) + ½ q₀² / (j + 1): smooth, different at every output.
struct Weighted;

impl Loss for Weighted {
    fn loss<D: Scalar>(&self, output: usize, _t: f64, q: &[D], v: &[D]) -> D {
        let j = (output + 1) as f64;
        let mut sum = q[0] * q[0] * (0.5 / j);
        for i in 0..q.len() {
            sum += q[i] * (0.3 + 0.1 * i as f64) * j + v[i] * (0.2 - 0.15 * i as f64);
        }
        sum
    }
}

/// ∇ℓ_j with respect to (q, q̇), by hand.
fn weighted_gradient(output: usize, q: &DVector<f64>) -> DVector<f64> {
    let n = q.len();
    let j = (output + 1) as f64;
    DVector::from_fn(2 * n, |k, _| {
        if k < n {
            (0.3 + 0.1 * k as f64) * j + if k == 0 { q[0] / j } else { 0.0 }
        } else {
            0.2 - 0.15 * (k - n) as f64
        }
    })
}

/// J of a plain run of `model` from `initial` (outputs every `every` steps; K a multiple).
fn plain_loss<L, M, const N: usize>(
    model: L,
    method: &M,
    initial: Initial<Const<N>>,
    (h, t_end, every): (f64, f64, usize),
) -> f64
where
    L: Parametric<Const<N>>,
    M: Method<Const<N>> + Clone,
{
    let integrator = Integrator::new(model, method.clone());
    let mut trajectory = Every::new(every, Trajectory::new());
    integrator
        .run(0.0, initial, h, t_end, &mut trajectory)
        .expect("the plain run");
    trajectory
        .inner
        .points
        .iter()
        .enumerate()
        .map(|(j, point)| Weighted.loss(j, point.t, point.q.as_slice(), point.v.as_slice()))
        .sum()
}

/// |a − b| ≤ tol ‖b‖∞ entry by entry, with a message naming `what`; the relative difference
/// is printed (`-- --nocapture`).
fn assert_close(a: &DVector<f64>, b: &DVector<f64>, tol: f64, what: &str) {
    let scale = b.amax();
    let worst = (a - b).amax() / scale;
    eprintln!("{what}: {worst:.1e} relative (tolerance {tol:.0e})");
    assert!(
        worst <= tol,
        "{what}: {a} against {b}, {worst:.1e} relative (tolerance {tol:.0e})"
    );
}

/// The gradient by the adjoint, against the forward sensitivities and against central
/// differences of plain runs; `perturbed(k, δ)` builds the model and initial state with
/// gradient entry k (q₀, then q̇₀, then the parameters) moved by δ.
fn check<L, M, const N: usize>(
    integrator: &Integrator<L, M, svi::Euclidean<Const<N>>>,
    run: &SensitivityRun<Const<N>>,
    perturbed: impl Fn(usize, f64) -> (L, Initial<Const<N>>),
    steps: &[f64],
    what: &str,
) where
    L: Parametric<Const<N>>,
    M: Method<Const<N>> + Method<Dyn> + Clone,
{
    let gradient = integrator
        .gradient(run, &Weighted, Checkpoints::default())
        .unwrap_or_else(|error| panic!("{what}: {error}"));
    let mut adjoint = gradient.initial.clone();
    adjoint.extend(gradient.parameters.iter().copied());
    // Forward: Σ_j ∇ℓ_jᵀ ∂(q, q̇)_j/∂(…).
    let sensitivities = integrator.sensitivities(run).unwrap();
    let mut forward = DVector::zeros(adjoint.len());
    for (j, output) in sensitivities.outputs.iter().enumerate() {
        forward += output.jacobian.tr_mul(&weighted_gradient(j, &output.q));
    }
    assert_close(
        &adjoint,
        &forward,
        1e-10,
        &format!("{what}: adjoint against forward"),
    );
    // Central differences of plain runs of the original model.
    let grid = (run.h, run.t_end, run.every);
    let method = integrator.method();
    let differences = DVector::from_fn(adjoint.len(), |k, _| {
        let delta = steps[k];
        let (plus, from_plus) = perturbed(k, delta);
        let (minus, from_minus) = perturbed(k, -delta);
        (plain_loss(plus, method, from_plus, grid) - plain_loss(minus, method, from_minus, grid))
            / (2.0 * delta)
    });
    assert_close(
        &adjoint,
        &differences,
        1e-7,
        &format!("{what}: adjoint against differences"),
    );
    let plain = {
        let (model, initial) = perturbed(0, 0.0);
        plain_loss(model, method, initial, grid)
    };
    assert!(
        (gradient.value - plain).abs() <= 1e-12 * plain.abs(),
        "{what}: J = {} against the plain run's {plain}",
        gradient.value
    );
}

/// Kepler, e = 0.5, from mean anomaly 0.4: with respect to q₀, q̇₀, e and the phase (which
/// move q₀, q̇₀).
fn check_kepler<M: Method<Const<2>> + Method<Dyn> + Clone>(method: M, h: f64, what: &str) {
    let (e, phase) = (0.5, 0.4);
    let model = |e: f64, phase: f64| {
        let mut model = Kepler::new(e).unwrap();
        model.set_parameter("phase", phase).unwrap();
        model
    };
    let integrator = Integrator::new(model(e, phase), method);
    let run = SensitivityRun::new(0.0, Start::Model, h, 4.0)
        .with_parameters(&["e", "phase"])
        .with_outputs_every(10);
    let perturbed = |k: usize, delta: f64| {
        let model = model(
            if k == 4 { e + delta } else { e },
            if k == 5 { phase + delta } else { phase },
        );
        let (_, mut q, mut v) = model.initial_state();
        match k {
            0 | 1 => q[k] += delta,
            2 | 3 => v[k - 2] += delta,
            _ => {}
        }
        (model, Initial::Velocity { q, v })
    };
    // δ = 2e-6: the differences' truncation error δ²f'''/6 is about 2e-9 of the gradient
    // (6e-8 at δ = 1e-5, which scales as δ²), their round-off about 1e-10.
    check(&integrator, &run, perturbed, &[2e-6; 6], what);
}

/// The damped pendulum (m = g = 1, l = 1.3, c = 0.2) from θ₀ = 1 at rest: with respect to
/// θ₀, θ̇₀, l and c.
fn check_pendulum<M: Method<Const<1>> + Method<Dyn> + Clone>(method: M, h: f64, what: &str) {
    let model = DampedPendulum {
        l: 1.3,
        c: 0.2,
        ..DampedPendulum::default()
    };
    let start = Initial::Velocity {
        q: SVector::from([1.0]),
        v: SVector::from([0.0]),
    };
    let integrator = Integrator::new(model, method);
    let run = SensitivityRun::new(0.0, Start::Given(start), h, 6.0)
        .with_parameters(&["l", "c"])
        .with_outputs_every(5);
    let perturbed = |k: usize, delta: f64| {
        let mut model = model;
        let (mut q, mut v) = (SVector::from([1.0]), SVector::from([0.0]));
        match k {
            0 => q[0] += delta,
            1 => v[0] += delta,
            2 => model.l += delta,
            _ => model.c += delta,
        }
        (model, Initial::Velocity { q, v })
    };
    check(&integrator, &run, perturbed, &[1e-5; 4], what);
}

#[test]
fn svi_gradients_agree_with_differences_and_forward_sensitivities() {
    check_kepler(Svi::new(5), 0.1, "svi 5 points on Kepler");
    check_pendulum(Svi::new(4), 0.2, "svi 4 points on the damped pendulum");
}

#[test]
fn sc_gradients_agree_with_differences_and_forward_sensitivities() {
    check_kepler(SpectralCollocation::new(5), 0.1, "sc 5 points on Kepler");
    check_pendulum(
        SpectralCollocation::new(4),
        0.2,
        "sc 4 points on the damped pendulum",
    );
}

#[test]
fn midpoint_gradients_agree_with_differences_and_forward_sensitivities() {
    check_kepler(
        VariationalIntegrator::new(Midpoint),
        0.02,
        "midpoint on Kepler",
    );
    check_pendulum(
        VariationalIntegrator::new(Midpoint),
        0.05,
        "midpoint on the damped pendulum",
    );
}

#[test]
fn verlet_gradients_agree_with_differences_and_forward_sensitivities() {
    check_kepler(StormerVerlet::default(), 0.02, "verlet on Kepler");
    check_pendulum(
        StormerVerlet::default(),
        0.05,
        "verlet on the damped pendulum",
    );
}

#[test]
fn composition_gradients_agree_with_differences_and_forward_sensitivities() {
    check_kepler(
        Composition::new(Scheme::Yoshida4),
        0.05,
        "yoshida4 on Kepler",
    );
    check_pendulum(
        Composition::new(Scheme::Yoshida4),
        0.1,
        "yoshida4 on the damped pendulum",
    );
}

#[test]
fn checkpoint_budgets_give_one_gradient_and_the_default_keeps_about_two_square_roots() {
    let integrator = Integrator::new(Kepler::new(0.5).unwrap(), Svi::new(4));
    let run = SensitivityRun::new(0.0, Start::Model, 0.1, 40.0)
        .with_parameters(&["e"])
        .with_outputs_every(7);
    let steps = 400;
    let reference = integrator
        .gradient(&run, &Weighted, Checkpoints::Budget(steps))
        .unwrap();
    for checkpoints in [
        Checkpoints::Sqrt,
        Checkpoints::Budget(1),
        Checkpoints::Budget(3),
    ] {
        let gradient = integrator.gradient(&run, &Weighted, checkpoints).unwrap();
        let mut a = gradient.initial.clone();
        a.extend(gradient.parameters.iter().copied());
        let mut b = reference.initial.clone();
        b.extend(reference.parameters.iter().copied());
        // Each segment starts its solves cold (the last step's warm start belongs to a later
        // segment): the states differ in round-off, the gradient (≈ 7e3) by 1e-12 of itself.
        assert_close(&a, &b, 1e-10, &format!("{checkpoints:?}"));
    }
    let default = integrator
        .gradient(&run, &Weighted, Checkpoints::Sqrt)
        .unwrap();
    // ⌈√400⌉ = 20 checkpoints and segments of 20 maps.
    assert_eq!(default.peak_stored, 40);
    assert_eq!(reference.peak_stored, steps + 1);
}

#[test]
fn bad_derivative_requests_are_typed_errors_naming_them() {
    let integrator = Integrator::new(Kepler::new(0.5).unwrap(), Svi::new(4));
    let run = SensitivityRun::new(0.0, Start::Model, 0.1, 1.0);
    let unknown = integrator
        .sensitivities(&run.clone().with_parameters(&["mass"]))
        .unwrap_err();
    assert!(
        matches!(&unknown, Error::InvalidParameter { name, reason }
            if name == "parameters" && reason.contains("'mass'") && reason.contains("e")),
        "{unknown}"
    );
    let budget = integrator
        .gradient(&run, &Weighted, Checkpoints::Budget(0))
        .unwrap_err();
    assert!(
        matches!(&budget, Error::InvalidParameter { name, .. } if name == "checkpoints"),
        "{budget}"
    );
    struct Singular;
    impl Loss for Singular {
        fn loss<D: Scalar>(&self, output: usize, _t: f64, q: &[D], _v: &[D]) -> D {
            // Finite until the last output, then a pole.
            if output == 1 {
                q[0].recip() * 0.0 / 0.0
            } else {
                q[0]
            }
        }
    }
    let nan = integrator
        .gradient(&run, &Singular, Checkpoints::default())
        .unwrap_err();
    assert!(
        matches!(&nan, Error::NonFinite { what, .. } if what.contains("loss at output 1")),
        "{nan}"
    );
    let no_start = Integrator::new(DampedPendulum::default(), Svi::new(4))
        .sensitivities(&SensitivityRun::new(0.0, Start::Model, 0.1, 1.0))
        .unwrap_err();
    assert!(
        matches!(&no_start, Error::InvalidParameter { name, .. } if name == "start"),
        "{no_start}"
    );
}

/// A parameter declared not to enter L ([`Parametric::enters_lagrangian`]) that does is
/// refused at the start, naming it; the same model with the honest default differentiates.
#[test]
fn a_parameter_that_enters_l_against_its_declaration_is_refused() {
    /// L = ½ q̇² − ½ k q², with k in L; `honest` says so.
    struct Spring {
        honest: bool,
    }
    impl svi::Lagrangian<nalgebra::U1> for Spring {
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            self.lagrangian_with(&[D::from(2.0)], t, q, v)
        }
    }
    impl Parametric<nalgebra::U1> for Spring {
        fn parameter_names(&self) -> Vec<String> {
            vec!["k".into()]
        }
        fn parameter_values(&self) -> Vec<f64> {
            vec![2.0]
        }
        fn lagrangian_with<D: Scalar>(
            &self,
            theta: &[D],
            _t: D,
            q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> D {
            (v[0] * v[0] - theta[0] * q[0] * q[0]) * 0.5
        }
        fn enters_lagrangian(&self, _index: usize) -> bool {
            self.honest
        }
    }
    let start = Initial::Velocity {
        q: SVector::from([1.0]),
        v: SVector::from([0.0]),
    };
    let run = SensitivityRun::new(0.0, Start::Given(start), 0.1, 1.0).with_parameters(&["k"]);
    let error = Integrator::new(
        Spring { honest: false },
        VariationalIntegrator::new(Midpoint),
    )
    .sensitivities(&run)
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, reason }
            if name == "parameters" && reason.contains("'k'")),
        "{error}"
    );
    // ∂q(1)/∂k of q = cos(√k t) is −t sin(√k t)/(2√k), to the midpoint rule's O(h²).
    let sensitivities = Integrator::new(
        Spring { honest: true },
        VariationalIntegrator::new(Midpoint),
    )
    .sensitivities(&run)
    .unwrap();
    let last = sensitivities.outputs.last().unwrap();
    let root = 2.0_f64.sqrt();
    let exact = -root.sin() / (2.0 * root);
    assert!(
        (last.jacobian[(0, 2)] - exact).abs() < 1e-2,
        "{} vs {exact}",
        last.jacobian
    );
}
