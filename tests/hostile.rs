//! Hostile input to the public API: random and malformed numbers (NaN, ±∞, subnormals,
//! ±f64::MAX, huge and tiny steps), sizes, eccentricities ≥ 1. Nothing may panic or hang;
//! every rejection is a typed error with a message.
//!
//! Case counts are set per test for a short CI run (about 12 000 inputs in all, see
//! [`cases`]); `SVI_HOSTILE_CASES=N` multiplies them by N for a longer search.
//! Runs are bounded by an observer that stops after [`STEP_CAP`] steps, so a tiny step over
//! a long horizon cannot hang a test.

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, SVector};
use proptest::prelude::*;
use std::ops::ControlFlow;
use svi::basis::{LagrangeBasis, chebyshev_gauss_lobatto};
use svi::drift::EnergyWindows;
use svi::observer::{EnergyError, Observer};
use svi::quadrature::GaussLegendre;
use svi::{
    Defaults, Dimension, Error, Initial, Integrator, Lagrangian, Method, Midpoint, PhasePoint,
    Recovery, RunOptions, SpectralCollocation, StormerVerlet, Svi, VariationalIntegrator,
};
use svi_models::{DoublePendulum, Kepler, ModelVisitor, Pendulum, ZooModel, visit_model};

/// Steps after which every hostile run is stopped.
const STEP_CAP: usize = 60;

use crate::hostile_cases;
use hostile_cases::cases;

/// Any f64, biased towards the hostile ones.
fn hostile() -> impl Strategy<Value = f64> {
    prop_oneof![
        2 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(f64::MAX),
        1 => Just(f64::MIN),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(5e-324),
        4 => (-320i32..320, -9.99f64..9.99).prop_map(|(e, m)| m * 10f64.powi(e)),
        4 => -10.0f64..10.0,
        2 => any::<f64>(),
    ]
}

/// A step: mostly positive and moderate, sometimes hostile.
fn step() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => (-8i32..2, 1.0f64..9.99).prop_map(|(e, m)| m * 10f64.powi(e)),
        1 => hostile(),
    ]
}

/// Stops a run after [`STEP_CAP`] steps and records that every observed point is finite.
#[derive(Default)]
struct Cap {
    points: usize,
    finite: bool,
}

impl<L, N: Dimension> Observer<L, PhasePoint<N>> for Cap
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, _: &L, step: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        if self.points == 0 {
            self.finite = true;
        }
        self.points += 1;
        self.finite &= point
            .q
            .iter()
            .chain(&point.v)
            .chain(&point.p)
            .all(|x| x.is_finite());
        if step >= STEP_CAP {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// Run with hostile inputs; any outcome but a panic is fine, and the outcome is consistent.
fn hostile_run<L: Lagrangian<Const<N>> + Clone, M: Method<Const<N>>, const N: usize>(
    model: L,
    method: M,
    inputs: &Inputs<N>,
) -> Result<(), TestCaseError> {
    let integrator = Integrator::new(model, method);
    let initial = if inputs.momentum {
        Initial::Momentum {
            q: inputs.q,
            p: inputs.y,
        }
    } else {
        Initial::Velocity {
            q: inputs.q,
            v: inputs.y,
        }
    };
    let options = match inputs.halvings {
        Some(max_halvings) => RunOptions::default()
            .with_recovery(Recovery::HalveStep { max_halvings })
            .with_divergence_limit(1e8),
        None => RunOptions::default(),
    };
    let mut cap = Cap::default();
    match integrator.try_run(
        inputs.t0,
        initial,
        inputs.h,
        inputs.t_end,
        &options,
        &mut cap,
    ) {
        Ok(run) => {
            prop_assert!(run.statistics.steps <= STEP_CAP);
            prop_assert!(run.state.is_finite());
            prop_assert!(cap.finite);
        }
        Err(failure) => {
            prop_assert!(!failure.to_string().is_empty());
            if let Some(partial) = &failure.partial {
                prop_assert!(partial.state.is_finite());
                prop_assert!(partial.statistics.steps <= STEP_CAP);
            } else {
                // Rejected before the first step: invalid input, named.
                let typed = matches!(
                    failure.error,
                    Error::InvalidParameter { .. }
                        | Error::NonFinite { .. }
                        | Error::LegendreMap { .. }
                );
                prop_assert!(typed, "{}", failure);
            }
        }
    }
    Ok(())
}

/// Inputs of one hostile run.
#[derive(Debug, Clone)]
struct Inputs<const N: usize> {
    t0: f64,
    h: f64,
    t_end: f64,
    q: SVector<f64, N>,
    y: SVector<f64, N>,
    momentum: bool,
    halvings: Option<usize>,
}

fn inputs<const N: usize>() -> impl Strategy<Value = Inputs<N>> {
    (
        prop_oneof![4 => Just(0.0), 1 => hostile()],
        step(),
        prop_oneof![4 => 0.0f64..100.0, 1 => hostile()],
        proptest::collection::vec(prop_oneof![4 => -3.0f64..3.0, 1 => hostile()], N),
        proptest::collection::vec(prop_oneof![4 => -3.0f64..3.0, 1 => hostile()], N),
        any::<bool>(),
        prop_oneof![3 => Just(None), 1 => (0usize..6).prop_map(Some)],
    )
        .prop_map(|(t0, h, t_end, q, y, momentum, halvings)| Inputs {
            t0,
            h,
            t_end,
            q: SVector::from_iterator(q),
            y: SVector::from_iterator(y),
            momentum,
            halvings,
        })
}

/// Spectral options: mostly small, sometimes out of range.
fn points() -> impl Strategy<Value = usize> {
    prop_oneof![8 => 0usize..9, 1 => Just(100_000), 1 => Just(usize::MAX)]
}

proptest! {
    #![proptest_config(cases(1500))]

    #[test]
    fn kepler_runs_never_panic(
        e in prop_oneof![3 => 0.0f64..0.999, 1 => hostile()],
        inputs in inputs::<2>(),
        points in points(),
        quadrature in prop_oneof![3 => Just(None), 1 => points().prop_map(Some)],
        method in 0usize..4,
    ) {
        // Eccentricities outside [0, 1) are rejected by name.
        let model = match Kepler::new(e) {
            Ok(model) => model,
            Err(error) => {
                prop_assert!(!(0.0..1.0).contains(&e), "{e}: {error}");
                let named_e = matches!(&error, Error::InvalidParameter { name, .. } if name == "e");
                prop_assert!(named_e, "{}", error);
                return Ok(());
            }
        };
        match method {
            0 => {
                let mut svi = Svi::new(points);
                if let Some(m) = quadrature {
                    svi = svi.with_quadrature(m);
                }
                hostile_run(model, svi, &inputs)?
            }
            1 => hostile_run(model, SpectralCollocation::new(points), &inputs)?,
            2 => hostile_run(model, VariationalIntegrator::new(Midpoint), &inputs)?,
            _ => hostile_run(model, StormerVerlet::default(), &inputs)?,
        }
    }

    #[test]
    fn pendulum_runs_never_panic(
        inputs in inputs::<2>(),
        points in points(),
        method in 0usize..3,
    ) {
        // The double pendulum: position-dependent mass matrix, Newton everywhere.
        let model = DoublePendulum::default();
        match method {
            0 => hostile_run(model, Svi::new(points), &inputs)?,
            1 => hostile_run(model, SpectralCollocation::new(points), &inputs)?,
            _ => hostile_run(model, StormerVerlet::default(), &inputs)?,
        }
    }
}

/// Sets a hostile parameter on a zoo model and, if accepted, runs it briefly.
struct SetParameter {
    name: String,
    value: f64,
    h: f64,
}

impl ModelVisitor for SetParameter {
    type Output = Result<(), TestCaseError>;

    fn visit<M: ZooModel<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let known: Vec<&str> = model.parameters().iter().map(|(n, _)| *n).collect();
        match model.set_parameter(&self.name, self.value) {
            Ok(()) => {
                prop_assert!(known.contains(&self.name.as_str()));
                prop_assert!(self.value.is_finite());
                let (t0, q, v) = model.initial_state();
                let integrator = Integrator::new(model, Svi::new(4));
                let mut energy = EnergyError::default();
                let mut cap = (Cap::default(), &mut energy);
                let _ = integrator.run_from_velocity(t0, q, v, self.h, t0 + 1.0, &mut cap);
            }
            Err(error) => {
                let message = error.to_string();
                prop_assert!(
                    message.contains(&self.name) || self.name.is_empty(),
                    "{message}"
                );
            }
        }
        Ok(())
    }
}

proptest! {
    #![proptest_config(cases(2000))]

    #[test]
    fn zoo_parameters_are_validated(
        model in proptest::sample::select(svi_models::MODEL_NAMES.to_vec()),
        name in prop_oneof![
            3 => proptest::sample::select(vec!["e", "sigma", "m", "g", "k", "l", "m1", "m2", "d1", "d2", "c", "zeta", "drive", "amplitude"]).prop_map(String::from),
            1 => ".{0,12}",
        ],
        value in hostile(),
        h in step(),
    ) {
        visit_model(model, SetParameter { name, value, h }).unwrap()?;
    }

    #[test]
    fn sizes_of_bases_and_rules_are_validated(
        points in prop_oneof![4 => 0usize..80, 1 => any::<usize>()],
        nodes in proptest::collection::vec(hostile(), 0..12),
        x in hostile(),
    ) {
        match chebyshev_gauss_lobatto(points) {
            Ok(nodes) => prop_assert_eq!(nodes.len(), points),
            Err(error) => prop_assert!(error.to_string().contains("points")),
        }
        match GaussLegendre::new(points) {
            Ok(rule) => {
                prop_assert_eq!(rule.len(), points);
                let sum: f64 = rule.weights().iter().sum();
                prop_assert!((sum - 2.0).abs() < 1e-12);
            }
            Err(error) => prop_assert!(error.to_string().contains("quadrature")),
        }
        if let Ok(basis) = LagrangeBasis::new(nodes.clone()) {
            prop_assert!(nodes.iter().all(|x| x.is_finite()));
            let mut out = vec![0.0; basis.len()];
            basis.values_into(x, &mut out);
            basis.derivatives_into(x, &mut out);
        }
    }

    #[test]
    fn drift_windows_take_any_samples(
        samples in proptest::collection::vec((hostile(), hostile()), 0..200),
        size in 0usize..20,
    ) {
        let mut windows = EnergyWindows::new(size);
        for (t, e) in &samples {
            windows.push(*t, *e);
        }
        let all = windows.all();
        prop_assert_eq!(all.iter().map(|w| w.samples).sum::<usize>(), samples.len());
        if let Some(fit) = windows.fit() {
            prop_assert!(fit.slope.is_finite() || fit.horizon.is_finite() || fit.windows >= 2);
        }
    }

    #[test]
    fn step_counts_are_capped(span in hostile(), h in hostile()) {
        match svi::step_count(span, h) {
            Ok(n) => prop_assert!((1..=1_000_000_000_001).contains(&n)),
            Err(error) => prop_assert!(error.to_string().contains('h')),
        }
    }

    #[test]
    fn stability_matrices_take_any_z(z in hostile(), points in 0usize..8) {
        for result in [
            svi::stability::stability_matrix(&Svi::new(points), z),
            svi::stability::stability_matrix(&SpectralCollocation::new(points), z),
            svi::stability::svi_closed_form(points, points, z),
            svi::stability::collocation_closed_form(points, z),
        ] {
            if let Err(error) = result {
                prop_assert!(!error.to_string().is_empty());
            }
        }
    }
}

#[test]
fn eccentricities_of_unbound_orbits_are_rejected_by_name() {
    for e in [1.0, 1.5, -0.1, f64::NAN, f64::INFINITY] {
        let error = Kepler::new(e).unwrap_err();
        assert!(error.to_string().starts_with("invalid e:"), "{error}");
    }
    let mut pendulum = Pendulum::default();
    let error = pendulum.set_parameter("length", 1.0).unwrap_err();
    assert!(error.to_string().contains("no such parameter"), "{error}");
}

/// Found by `kepler_runs_never_panic` (SVI_HOSTILE_CASES=10): a finite state whose momentum
/// overflows is reported, not returned as a result with an infinite momentum. The pendulum
/// with l = 2 has p = m l² q̇ = 4 q̇, so q̇ = f64::MAX/2 gives p = ∞: at the initial state
/// (∂L/∂q̇ by automatic differentiation) and after a step (p = M q̇ from SC's kept mass
/// matrix).
#[test]
fn an_overflowing_momentum_is_a_non_finite_error() {
    let pendulum = Pendulum {
        m: 1.0,
        l: 2.0,
        g: 1.0,
    };
    let integrator = Integrator::new(pendulum, SpectralCollocation::new(2));
    let start = Initial::Velocity {
        q: SVector::from([0.3]),
        v: SVector::from([f64::MAX / 2.0]),
    };
    let mut trajectory = svi::observer::Trajectory::new();
    let failure = integrator
        .try_run(
            0.0,
            start,
            1.0,
            2.2250738585072014e-308,
            &RunOptions::default(),
            &mut trajectory,
        )
        .unwrap_err();
    assert!(
        matches!(&failure.error, Error::NonFinite { what, step: 0, .. } if what == "velocity or momentum"),
        "{failure}"
    );
    assert!(trajectory.points.is_empty());
    let failure = integrator
        .try_run(0.0, start, 1.0, 1e-300, &RunOptions::default(), &mut ())
        .unwrap_err();
    assert!(
        matches!(failure.error, Error::NonFinite { step: 1, .. }),
        "{failure}"
    );
}
