//! The classic variational integrators (symplectic Euler and its adjoint, midpoint,
//! trapezoid, Störmer–Verlet), all from one generic integrator of a discrete Lagrangian.
//!
//! References: the harmonic oscillator's closed form (q(t) = cos t for σ = 1, q0 = 1,
//! p0 = 0) and the slides' Störmer–Verlet error table (Porcù–Penati, OctConf 2013:
//! ‖e‖_∞ = 0.22, 0.054, 0.013, 0.0033, 0.00082, 0.00021 for h = 0.8, …, 0.025, orders
//! 2.05, 2.01, 2.00, …); symplecticity ΦᵀJΦ = J of the tangent map and central differences of
//! the step; Noether's theorem (Kepler's angular momentum); the adjoint relation of the two
//! symplectic Euler methods.

use nalgebra::{Const, SVector, U1, U2};
use svi::observer::{MomentumError, SolutionError};
use svi::verify::observed_order;
use svi::{
    AdjointSymplecticEuler, Defaults, Integrator, Lagrangian, Method, Midpoint, State,
    StormerVerlet, SymplecticEuler, Trapezoid, VariationalIntegrator,
};
use svi_models::{DoublePendulum, HarmonicOscillator, Kepler, Pendulum};

/// Runs `body` once for every classic method, with its name.
macro_rules! for_each_method {
    (|$name:ident, $method:ident| $body:block) => {{
        {
            let $name = "symplectic-euler";
            let $method = VariationalIntegrator::new(SymplecticEuler);
            $body
        }
        {
            let $name = "symplectic-euler-adjoint";
            let $method = VariationalIntegrator::new(AdjointSymplecticEuler);
            $body
        }
        {
            let $name = "midpoint";
            let $method = VariationalIntegrator::new(Midpoint);
            $body
        }
        {
            let $name = "trapezoid";
            let $method = VariationalIntegrator::new(Trapezoid);
            $body
        }
        {
            let $name = "verlet";
            let $method = StormerVerlet::default();
            $body
        }
    }};
}

/// Largest position error over [0, t_end] on the oscillator σ = 1 from q0 = 1, p0 = 0.
fn oscillator_error<M: Method<U1>>(method: M, h: f64, t_end: f64) -> f64 {
    let integrator = Integrator::new(HarmonicOscillator::default(), method);
    let mut error = SolutionError::default();
    integrator
        .run_from_momentum(
            0.0,
            SVector::from([1.0]),
            SVector::from([0.0]),
            h,
            t_end,
            &mut error,
        )
        .unwrap();
    error.max.unwrap()
}

#[test]
fn observed_orders_on_the_oscillator_match_the_declared_ones() {
    let steps = [0.2, 0.1, 0.05, 0.025, 0.0125];
    for_each_method!(|name, method| {
        let declared = Method::<U1>::info(&method).order;
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| oscillator_error(method.clone(), h, 10.0))
            .collect();
        let order = observed_order(&steps, &errors, 1e-12).unwrap();
        eprintln!("{name}: declared {declared}, observed {order:.3}, errors {errors:?}");
        assert!(
            (order - declared as f64).abs() < 0.2,
            "{name}: observed order {order:.3}, declared {declared}, errors {errors:?}"
        );
    });
    for (name, expected) in [
        ("symplectic-euler", 1),
        ("symplectic-euler-adjoint", 1),
        ("midpoint", 2),
        ("trapezoid", 2),
        ("verlet", 2),
    ] {
        let order = match name {
            "symplectic-euler" => Method::<U1>::info(&VariationalIntegrator::new(SymplecticEuler)),
            "symplectic-euler-adjoint" => {
                Method::<U1>::info(&VariationalIntegrator::new(AdjointSymplecticEuler))
            }
            "midpoint" => Method::<U1>::info(&VariationalIntegrator::new(Midpoint)),
            "trapezoid" => Method::<U1>::info(&VariationalIntegrator::new(Trapezoid)),
            _ => Method::<U1>::info(&StormerVerlet::default()),
        };
        assert_eq!((order.name, order.order), (name, expected));
        assert!(order.symplectic);
        assert_eq!(order.symmetric, expected == 2, "{name}");
    }
}

#[test]
fn stormer_verlet_reproduces_the_slides_error_table() {
    // The slides' table: M = 1, ω = 1, ‖e‖_∞ over the run, h = 0.8 … 0.025. Its magnitudes
    // (0.22 at h = 0.8, 2.1e-4 at h = 0.025) fit a run of 8 time units from q0 = 1, p0 = 0
    // (the phase error of Störmer–Verlet is h²t/24).
    let steps = [0.8, 0.4, 0.2, 0.1, 0.05, 0.025];
    let slides = [0.22, 0.54e-1, 0.13e-1, 0.33e-2, 0.82e-3, 0.21e-3];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| oscillator_error(StormerVerlet::default(), h, 8.0))
        .collect();
    eprintln!("h        error      slides     order");
    for (k, (h, error)) in steps.iter().zip(&errors).enumerate() {
        let order = (k > 0).then(|| (errors[k - 1] / error).log2());
        eprintln!("{h:<8} {error:.3e}  {:.2e}  {order:.3?}", slides[k]);
        if let Some(order) = order {
            assert!((order - 2.0).abs() < 0.1, "h = {h}: order {order}");
        }
        // Same magnitude as the published table (within 30 %).
        assert!(
            (error / slides[k] - 1.0).abs() < 0.3,
            "h = {h}: {error:e} vs {:e}",
            slides[k]
        );
    }
    let order = observed_order(&steps, &errors, 1e-12).unwrap();
    assert!((order - 2.0).abs() < 0.1, "{order}");
    // The implicit trapezoid has the same discrete equations: the same table.
    for (&h, &error) in steps.iter().zip(&errors) {
        let implicit = oscillator_error(VariationalIntegrator::new(Trapezoid), h, 8.0);
        assert!(
            (implicit - error).abs() < 1e-13,
            "h = {h}: {implicit:e} vs {error:e}"
        );
    }
}

/// Symplecticity error of the tangent map and its largest relative difference from central
/// differences of the step map.
fn tangent_check<L: Lagrangian<Const<N>> + Clone, M: Method<Const<N>> + Clone, const N: usize>(
    model: &L,
    method: &M,
    state: State<Const<N>>,
    h: f64,
) -> (f64, f64) {
    let integrator = Integrator::new(model.clone(), method.clone());
    let (_, tangent) = integrator.tangent_map(0.3, &state, h).unwrap();
    let phi = tangent.matrix();
    let eps = 1e-6;
    let mut worst: f64 = 0.0;
    for j in 0..2 * N {
        let (mut plus, mut minus) = (state, state);
        if j < N {
            plus.q[j] += eps;
            minus.q[j] -= eps;
        } else {
            plus.y[j - N] += eps;
            minus.y[j - N] -= eps;
        }
        let (a, _) = integrator.tangent_map(0.3, &plus, h).unwrap();
        let (b, _) = integrator.tangent_map(0.3, &minus, h).unwrap();
        for i in 0..2 * N {
            let difference = if i < N {
                (a.q[i] - b.q[i]) / (2.0 * eps)
            } else {
                (a.y[i - N] - b.y[i - N]) / (2.0 * eps)
            };
            worst = worst.max((difference - phi[(i, j)]).abs() / (1.0 + phi[(i, j)].abs()));
        }
    }
    (tangent.symplecticity_error(), worst)
}

#[test]
fn every_one_step_map_is_symplectic_on_pendulum_and_kepler() {
    let pendulum = State {
        q: SVector::from([1.2]),
        y: SVector::from([0.3]),
    };
    let kepler = State {
        q: SVector::from([0.5, 0.1]),
        y: SVector::from([-0.2, 1.6]),
    };
    let double = State {
        q: SVector::from([1.0, 0.5]),
        y: SVector::from([0.4, -0.3]),
    };
    for_each_method!(|name, method| {
        let (symplectic, difference) = tangent_check(&Pendulum::default(), &method, pendulum, 0.2);
        eprintln!("{name} pendulum: {symplectic:.1e} {difference:.1e}");
        assert!(symplectic < 1e-12, "{name} pendulum: {symplectic:e}");
        assert!(difference < 1e-6, "{name} pendulum: {difference:e}");
        let (symplectic, difference) = tangent_check(&Kepler::default(), &method, kepler, 0.1);
        eprintln!("{name} kepler: {symplectic:.1e} {difference:.1e}");
        assert!(symplectic < 1e-12, "{name} kepler: {symplectic:e}");
        assert!(difference < 1e-6, "{name} kepler: {difference:e}");
        // A non-separable Lagrangian (configuration-dependent mass matrix): implicit path.
        let (symplectic, difference) =
            tangent_check(&DoublePendulum::default(), &method, double, 0.05);
        assert!(symplectic < 1e-12, "{name} double pendulum: {symplectic:e}");
        assert!(difference < 1e-6, "{name} double pendulum: {difference:e}");
    });
}

#[test]
fn stormer_verlet_on_a_separable_model_is_explicit() {
    // Kepler and the pendulum declare a constant mass matrix: kick–drift–kick, no Newton
    // iteration, one gradient per step (the first step evaluates the initial force too).
    let model = Kepler::default();
    let (t0, q0, v0) = model.initial_state();
    let run = Integrator::new(model, StormerVerlet::default())
        .run_from_velocity(t0, q0, v0, 0.01, 20.0, &mut ())
        .unwrap();
    let statistics = run.statistics;
    assert_eq!(statistics.steps, 2000);
    assert_eq!(statistics.iterations, 0);
    assert_eq!(statistics.evaluations, statistics.steps + 1);
    let implicit = Integrator::new(model, VariationalIntegrator::new(Trapezoid))
        .run_from_velocity(t0, q0, v0, 0.01, 20.0, &mut ())
        .unwrap();
    eprintln!("implicit: {:?}", implicit.statistics);
    assert!(implicit.statistics.iterations >= implicit.statistics.steps);
    let difference = (run.state.q - implicit.state.q)
        .amax()
        .max((run.state.y - implicit.state.y).amax());
    assert!(difference < 1e-11, "explicit vs implicit: {difference:e}");

    let pendulum = Pendulum::default();
    let (t0, q0, v0) = pendulum.initial_state();
    let run = Integrator::new(pendulum, StormerVerlet::default())
        .run_from_velocity(t0, q0, v0, 0.1, 100.0, &mut ())
        .unwrap();
    assert_eq!(run.statistics.iterations, 0);
    assert_eq!(run.statistics.evaluations, 1001);
}

#[test]
fn stormer_verlet_without_constant_mass_is_the_implicit_trapezoid() {
    let model = DoublePendulum::default();
    let (t0, q0, v0) = model.initial_state();
    let verlet = Integrator::new(model, StormerVerlet::default())
        .run_from_velocity(t0, q0, v0, 0.01, 2.0, &mut ())
        .unwrap();
    let trapezoid = Integrator::new(model, VariationalIntegrator::new(Trapezoid))
        .run_from_velocity(t0, q0, v0, 0.01, 2.0, &mut ())
        .unwrap();
    assert_eq!(verlet.state, trapezoid.state);
    assert_eq!(verlet.statistics, trapezoid.statistics);
    assert!(verlet.statistics.iterations > 0);
}

#[test]
fn symmetric_methods_undo_a_step_and_the_euler_methods_undo_each_other() {
    let model = Kepler::default();
    let state = State {
        q: SVector::from([0.5, 0.1]),
        y: SVector::from([-0.2, 1.6]),
    };
    let h = 0.1;
    /// One step of `first` with h, then one of `second` with −h.
    fn there_and_back<A: Method<U2>, B: Method<U2>>(
        model: &Kepler,
        first: &A,
        second: &B,
        state: State<U2>,
        h: f64,
    ) -> f64 {
        let mut increment = State::zeros(U2);
        let mut workspace = first.workspace(model, h).unwrap();
        first
            .step(model, &mut workspace, 0.0, h, &state, &mut increment)
            .unwrap();
        let middle = State {
            q: state.q + increment.q,
            y: state.y + increment.y,
        };
        let mut workspace = second.workspace(model, h).unwrap();
        second
            .step(model, &mut workspace, h, -h, &middle, &mut increment)
            .unwrap();
        let back = State {
            q: middle.q + increment.q,
            y: middle.y + increment.y,
        };
        (back.q - state.q).amax().max((back.y - state.y).amax())
    }
    for_each_method!(|name, method| {
        if Method::<U2>::info(&method).symmetric {
            let error = there_and_back(&model, &method, &method, state, h);
            assert!(error < 1e-14, "{name}: {error:e}");
        }
    });
    let euler = VariationalIntegrator::new(SymplecticEuler);
    let adjoint = VariationalIntegrator::new(AdjointSymplecticEuler);
    assert!(there_and_back(&model, &euler, &adjoint, state, h) < 1e-14);
    assert!(there_and_back(&model, &adjoint, &euler, state, h) < 1e-14);
    // Symplectic Euler is not symmetric: it does not undo itself.
    assert!(there_and_back(&model, &euler, &euler, state, h) > 1e-4);
}

#[test]
fn classic_methods_conserve_keplers_angular_momentum() {
    // The segment rules are invariant under rotations (they act linearly on q): discrete
    // Noether theorem.
    let model = Kepler::default();
    let (t0, q0, v0) = model.initial_state();
    for_each_method!(|name, method| {
        let mut momentum = MomentumError::default();
        Integrator::new(model, method)
            .run_from_velocity(t0, q0, v0, 0.05, 100.0, &mut momentum)
            .unwrap();
        assert!(momentum.max < 1e-12, "{name}: {:e}", momentum.max);
    });
}
