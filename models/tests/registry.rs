//! The registry and the `Defaults` contract of every zoo model: names, parameter
//! validation, default states.

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::{Defaults, Dimension, Error, Invariants, Symmetries};
use svi_models::{
    DoublePendulum, HarmonicOscillator, Kepler, MODEL_NAMES, ModelVisitor, Pendulum,
    SpringPendulum, UnknownModel, ZooModel, visit_model,
};

/// The name of the parameter an `InvalidParameter` error is about.
fn invalid_name(result: Result<(), Error>) -> Option<String> {
    match result {
        Err(Error::InvalidParameter { name, .. }) => Some(name),
        _ => None,
    }
}

/// Returns the model's `name()`.
struct Name;

impl ModelVisitor for Name {
    type Output = &'static str;
    fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> &'static str
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        model.name()
    }
}

#[test]
fn every_registered_name_visits_the_model_of_that_name() {
    assert_eq!(
        MODEL_NAMES,
        [
            "oscillator",
            "pendulum",
            "spring-pendulum",
            "kepler",
            "double-pendulum",
            "damped-oscillator",
            "damped-pendulum",
            "driven-oscillator",
            "nbody",
            "henon-heiles",
            "restricted-three-body",
            "kepler-h",
            "pendulum-h",
            "henon-heiles-h",
            "magnetic-bottle"
        ]
    );
    for &name in MODEL_NAMES {
        assert_eq!(visit_model(name, Name), Ok(name));
    }
}

#[test]
fn an_unknown_name_is_an_error_listing_the_known_ones() {
    let error = visit_model("pendulm", Name).unwrap_err();
    assert_eq!(
        error,
        UnknownModel {
            name: "pendulm".into()
        }
    );
    assert_eq!(
        error.to_string(),
        "unknown model 'pendulm' (known: oscillator, pendulum, spring-pendulum, kepler, \
         double-pendulum, damped-oscillator, damped-pendulum, driven-oscillator, nbody, \
         henon-heiles, restricted-three-body, kepler-h, pendulum-h, henon-heiles-h, \
         magnetic-bottle)"
    );
    assert!(visit_model("", Name).is_err());
    assert!(visit_model("Kepler", Name).is_err());
}

/// Checks the `Defaults`, `Symmetries` and `Invariants` contracts on a model; returns the
/// number of parameters checked.
struct CheckContract;

impl ModelVisitor for CheckContract {
    type Output = usize;

    fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> usize
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let name = model.name();

        // Default state, step and horizon.
        let (t0, q0, v0) = model.initial_state();
        assert!(t0.is_finite(), "{name}: t0");
        assert!(
            q0.iter().chain(v0.iter()).all(|x| x.is_finite()),
            "{name}: state"
        );
        let (step, horizon) = (model.default_step(), model.default_horizon());
        assert!(
            step > 0.0 && horizon > step,
            "{name}: step {step}, horizon {horizon}"
        );
        let coordinates = model.coordinate_names();
        for (i, coordinate) in coordinates.iter().enumerate() {
            assert!(!coordinate.is_empty(), "{name}: coordinate name {i}");
            assert!(
                !coordinates[..i].contains(coordinate),
                "{name}: duplicate {coordinate}"
            );
        }

        // Names of momenta and invariants exist for every index.
        for i in 0..model.generator_count() {
            assert!(!model.momentum_name(i).is_empty());
            assert!(model.generator(i, &q0).iter().all(|x| x.is_finite()));
        }
        for i in 0..model.invariant_count() {
            assert!(!model.invariant_name(i).is_empty());
            assert!(model.invariant(i, t0, &q0, &v0).is_finite());
        }

        // Parameters: the current value is accepted, bad values are rejected by name and
        // leave the model unchanged, unknown names are rejected.
        let parameters = model.parameters();
        for &(parameter, value) in &parameters {
            let mut changed = model.clone();
            assert_eq!(
                changed.set_parameter(parameter, value),
                Ok(()),
                "{name}.{parameter}"
            );
            assert_eq!(changed.parameters(), parameters);

            // Hénon–Heiles' y0 and vy0 are coordinates of the initial point on its surface.
            let may_be_zero = matches!(
                parameter,
                "g" | "e" | "zeta" | "c" | "amplitude" | "y0" | "vy0"
            );
            // Kepler's phase (a mean anomaly) takes any finite value.
            let any_finite = parameter == "phase";
            let mut bad = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
            if !any_finite {
                bad.push(-1.0);
            }
            if !(may_be_zero || any_finite) {
                bad.push(0.0);
                bad.push(-0.0);
            }
            for bad_value in bad {
                let mut changed = model.clone();
                assert_eq!(
                    invalid_name(changed.set_parameter(parameter, bad_value)).as_deref(),
                    Some(parameter),
                    "{name}.{parameter} = {bad_value} must be rejected"
                );
                assert_eq!(changed.parameters(), parameters, "{name}: changed on error");
            }
            if may_be_zero || any_finite {
                let mut changed = model.clone();
                assert_eq!(changed.set_parameter(parameter, 0.0), Ok(()));
            }
            if any_finite {
                let mut changed = model.clone();
                assert_eq!(changed.set_parameter(parameter, -1.0), Ok(()));
            }
            let mut changed = model.clone();
            let other = match parameter {
                "e" => 0.25,
                // A mass ratio is at most 1/2.
                "mu" => 0.25,
                // Hénon–Heiles' initial point stays on its energy surface E = 1/8.
                "y0" | "vy0" => 0.1,
                _ => 2.0 * value + 1.0,
            };
            changed.set_parameter(parameter, other).unwrap();
            let updated = changed.parameters();
            assert!(
                updated.contains(&(parameter, other)),
                "{name}.{parameter}: {updated:?}"
            );
        }
        let mut changed = model.clone();
        assert_eq!(
            invalid_name(changed.set_parameter("no_such_parameter", 1.0)).as_deref(),
            Some("no_such_parameter"),
            "{name}"
        );
        parameters.len()
    }
}

#[test]
fn every_model_honours_the_defaults_contract() {
    let counts: Vec<usize> = MODEL_NAMES
        .iter()
        .map(|name| visit_model(name, CheckContract).unwrap())
        .collect();
    assert_eq!(counts, [1, 3, 4, 2, 5, 2, 4, 4, 1, 4, 3, 2, 3, 4, 5]);
}

#[test]
fn literature_defaults() {
    assert_eq!(HarmonicOscillator::default().sigma, 1.0);
    assert_eq!(HarmonicOscillator::default().initial_state().2[0], 1.0);
    assert_eq!(Kepler::default().e, 0.5);
    assert_eq!(Kepler::default().default_step(), 0.2);
    assert_eq!(Kepler::default().default_horizon(), 2000.0);
    let spring = SpringPendulum::default();
    assert_eq!(
        (spring.m, spring.g, spring.k, spring.l),
        (1.0, 9.81, 10_000.0, 1.0)
    );
    assert!((spring.scale_ratio() - 0.0313).abs() < 1e-4);
    let double = DoublePendulum::default();
    assert_eq!(
        (double.m1, double.m2, double.d1, double.d2, double.g),
        (1.0, 1.0, 1.0, 1.0, 9.81)
    );
    assert_eq!(Pendulum::default().frequency(), 1.0);
}

#[test]
fn kepler_eccentricity_must_give_a_bound_orbit() {
    for e in [1.0, 1.5, -0.1, -f64::MIN_POSITIVE, f64::NAN] {
        assert_eq!(
            invalid_name(Kepler::default().set_parameter("e", e)).as_deref(),
            Some("e"),
            "e = {e}"
        );
        assert!(Kepler::new(e).is_err());
    }
    for e in [0.0, 0.5, 0.99, 1.0 - f64::EPSILON] {
        assert_eq!(Kepler::new(e).map(|model| model.e), Ok(e));
    }
    let error = Kepler::new(1.0).unwrap_err().to_string();
    assert!(
        error.contains("invalid e") && error.contains("[0, 1)"),
        "{error}"
    );
}

#[test]
fn error_messages_name_the_model_and_the_known_parameters() {
    let error = SpringPendulum::default()
        .set_parameter("stiffness", 1.0)
        .unwrap_err()
        .to_string();
    assert!(error.contains("invalid stiffness"), "{error}");
    assert!(
        error.contains("spring-pendulum") && error.contains("m, g, k, l"),
        "{error}"
    );
    let error = HarmonicOscillator::new(-2.0).unwrap_err().to_string();
    // Numbers print with `{:?}`: 1e300, never 300 digits (issue #14, item 8).
    assert_eq!(error, "invalid sigma: -2.0 must be positive");
    let error = DoublePendulum::default()
        .set_parameter("d2", f64::INFINITY)
        .unwrap_err()
        .to_string();
    assert_eq!(error, "invalid d2: inf is not finite");
}

#[test]
#[should_panic(expected = "no symmetry generator with index 0")]
fn asking_for_a_missing_generator_panics() {
    Pendulum::default().momentum_name(0);
}

#[test]
#[should_panic(expected = "no invariant with index 3")]
fn asking_for_a_missing_invariant_panics() {
    Kepler::default().invariant_name(3);
}
