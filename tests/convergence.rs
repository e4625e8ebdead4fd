//! Convergence of SVI and SC against exact solutions.
//!
//! References: the harmonic oscillator's closed form q(t) = sin t (σ = 1, q0 = 0, p0 = 1) and
//! the Kepler problem's solution through Kepler's equation (`svi_models::Kepler`).

use nalgebra::{SVector, U1};
use svi::observer::SolutionError;
use svi::verify::observed_order;
use svi::{Integrator, Method, SpectralCollocation, Svi};
use svi_models::{HarmonicOscillator, Kepler};

/// Final position error of a method on the oscillator q0 = 0, p0 = 1 over [0, 10].
fn oscillator_error<M: Method<U1>>(method: M, h: f64) -> f64 {
    let integrator = Integrator::new(HarmonicOscillator::default(), method);
    let run = integrator
        .run_from_velocity(
            0.0,
            SVector::from([0.0]),
            SVector::from([1.0]),
            h,
            10.0,
            &mut (),
        )
        .unwrap();
    (run.last.q[0] - 10f64.sin()).abs()
}

#[test]
fn svi_with_one_more_gauss_point_than_its_degree_has_order_twice_the_degree() {
    // Porcù–Penati's table: degree 1/2 nodes → 2, degree 2/3 nodes → 4, degree 4/5 → 8.
    let steps = [1.0, 0.5, 0.25, 0.125, 0.0625];
    for degree in 1..=4usize {
        let method = Svi::new(degree + 1).with_quadrature(degree + 1);
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| oscillator_error(method.clone(), h))
            .collect();
        let order = observed_order(&steps, &errors, 1e-12).unwrap();
        let declared = Method::<U1>::info(&method).order;
        assert_eq!(declared, 2 * degree);
        assert!(
            (order - declared as f64).abs() < 0.3,
            "degree {degree}: observed order {order:.3}, errors {errors:?}"
        );
    }
}

#[test]
fn svi_with_paper_quadrature_reaches_its_declared_order() {
    // m = 2·points (the paper's choice): order 2s with degree s.
    let steps = [2.0, 1.0, 0.5, 0.25];
    for points in [3usize, 4] {
        let method = Svi::new(points);
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| oscillator_error(method.clone(), h))
            .collect();
        let order = observed_order(&steps, &errors, 1e-12).unwrap();
        let declared = Method::<U1>::info(&method).order as f64;
        assert!(
            (order - declared).abs() < 0.3,
            "points {points}: {order} vs {declared}"
        );
    }
}

#[test]
fn collocation_reaches_its_declared_order() {
    let steps = [0.5, 0.25, 0.125, 0.0625];
    for points in 3..=7usize {
        let method = SpectralCollocation::new(points);
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| oscillator_error(method.clone(), h))
            .collect();
        let order = observed_order(&steps, &errors, 1e-12).unwrap();
        let declared = Method::<U1>::info(&method).order as f64;
        assert!(
            (order - declared).abs() < 0.35,
            "points {points}: observed {order:.3}, declared {declared}, errors {errors:?}"
        );
    }
}

/// Max position error over the run of the paper's oscillator (h = 1, T = 100).
fn oscillator_max_error<M: Method<U1>>(method: M) -> f64 {
    let integrator = Integrator::new(HarmonicOscillator::default(), method);
    let mut error = SolutionError::default();
    integrator
        .run_from_velocity(
            0.0,
            SVector::from([0.0]),
            SVector::from([1.0]),
            1.0,
            100.0,
            &mut error,
        )
        .unwrap();
    error.max.unwrap()
}

#[test]
fn both_methods_converge_geometrically_in_the_number_of_points() {
    // Li–Wu–Leok Fig. 10: at fixed h = 1 the error falls geometrically with the number of
    // CGL points until round-off. Two more points must buy at least a factor 20 while the
    // error is above 1e-11, and both methods must reach 1e-11 by 12 points.
    for (name, errors) in [
        (
            "svi",
            (3..=12)
                .map(|n| oscillator_max_error(Svi::new(n)))
                .collect::<Vec<_>>(),
        ),
        (
            "sc",
            (3..=12)
                .map(|n| oscillator_max_error(SpectralCollocation::new(n)))
                .collect(),
        ),
    ] {
        for pair in errors.windows(3) {
            if pair[2] > 1e-11 {
                assert!(pair[2] < pair[0] / 20.0, "{name}: {errors:?}");
            }
        }
        assert!(errors[errors.len() - 1] < 1e-11, "{name}: {errors:?}");
    }
}

#[test]
fn svi_converges_geometrically_on_kepler() {
    // Fig. 16: Kepler e = 0.5, h = 0.2, T = 20 (about three periods).
    let model = Kepler::default();
    let (t0, q0, v0) = svi::Defaults::initial_state(&model);
    let mut errors = Vec::new();
    for points in [3usize, 5, 7, 9] {
        let integrator = Integrator::new(model, Svi::new(points));
        let mut error = SolutionError::default();
        integrator
            .run_from_velocity(t0, q0, v0, 0.2, 20.0, &mut error)
            .unwrap();
        errors.push(error.max.unwrap());
    }
    for pair in errors.windows(2) {
        assert!(pair[1] < pair[0] / 50.0, "{errors:?}");
    }
    assert!(errors[3] < 1e-10, "{errors:?}");
}
