//! Lagrangians written as text against the same models written in Rust (the zoo): their
//! derivatives agree to round-off, and a whole run of the paper's Kepler scene agrees to
//! 1e-10 in q. The references are the zoo models, whose closed forms have their own tests.

use nalgebra::{Const, DVector, SVector, U1, U2};
use svi::model::text::{TextLagrangian, TextModel, TextSpec};
use svi::{Defaults, Dyn, Integrator, LagrangianExt, Structure, Svi, Symmetries};
use svi_models::{DampedOscillator, Kepler, Pendulum};

/// A text spec from its parts.
fn spec(lagrangian: &str, coordinates: &[&str], parameters: &[(&str, f64)]) -> TextSpec {
    TextSpec {
        lagrangian: lagrangian.into(),
        coordinates: coordinates.iter().map(|name| (*name).into()).collect(),
        parameters: parameters
            .iter()
            .map(|(name, value)| ((*name).into(), *value))
            .collect(),
        ..TextSpec::default()
    }
}

/// Kepler as in `experiments/scenes/kepler-text.toml`.
fn kepler_text() -> TextLagrangian<U2, false, false, true> {
    let mut spec = spec(
        "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)",
        &["x", "y"],
        &[("mu", 1.0)],
    );
    spec.symmetries = vec![vec!["-y".into(), "x".into()]];
    let model = TextModel::new(&spec).unwrap();
    assert_eq!(model.structure(), Structure::ConstantMass);
    assert!(!model.time_dependent() && !model.forced());
    TextLagrangian::new(model).unwrap()
}

/// |a − b| ≤ tolerance · max(1, |b|) entry by entry.
fn assert_close<const R: usize, const C: usize>(
    a: &nalgebra::SMatrix<f64, R, C>,
    b: &nalgebra::SMatrix<f64, R, C>,
    tolerance: f64,
    what: &str,
) {
    for (x, y) in a.iter().zip(b.iter()) {
        assert!(
            (x - y).abs() <= tolerance * y.abs().max(1.0),
            "{what}: {a} against {b}"
        );
    }
}

/// Value, gradients and Hessian blocks of `text` and `rust` agree to 1e-14 at `points`.
fn same_derivatives<A, B, const N: usize>(text: &A, rust: &B, points: &[(f64, [f64; N], [f64; N])])
where
    A: LagrangianExt<Const<N>>,
    B: LagrangianExt<Const<N>>,
{
    for &(t, q, v) in points {
        let (q, v) = (SVector::from(q), SVector::from(v));
        let (a, b) = (
            text.second_derivatives(t, &q, &v),
            rust.second_derivatives(t, &q, &v),
        );
        let value = |x: f64| nalgebra::SMatrix::<f64, 1, 1>::new(x);
        assert_close(&value(a.value), &value(b.value), 1e-14, "L");
        assert_close(&a.q, &b.q, 1e-14, "∂L/∂q");
        assert_close(&a.v, &b.v, 1e-14, "∂L/∂q̇");
        assert_close(&a.qq, &b.qq, 1e-14, "∂²L/∂q²");
        assert_close(&a.qv, &b.qv, 1e-14, "∂²L/∂q∂q̇");
        assert_close(&a.vv, &b.vv, 1e-14, "∂²L/∂q̇²");
        assert_close(
            &text.force(t, &q, &v),
            &rust.force(t, &q, &v),
            1e-14,
            "force",
        );
        let (ea, eb) = (text.energy(t, &q, &v), rust.energy(t, &q, &v));
        assert_close(&value(ea), &value(eb), 1e-14, "energy");
        let (aa, ab) = (
            text.acceleration(t, &q, &v).unwrap(),
            rust.acceleration(t, &q, &v).unwrap(),
        );
        assert_close(&aa, &ab, 1e-13, "acceleration");
    }
}

#[test]
fn kepler_from_text_has_the_zoo_models_derivatives() {
    let text = kepler_text();
    same_derivatives(
        &text,
        &Kepler::default(),
        &[
            (0.0, [0.5, 0.0], [0.0, 3f64.sqrt()]),
            (1.3, [-0.7, 1.1], [0.4, -0.9]),
            (7.0, [2.0, -0.01], [-1.5, 0.2]),
        ],
    );
    // The generator is the zoo's: rotations, with the angular momentum as Noether momentum.
    let q = SVector::from([0.3, -1.2]);
    assert_eq!(text.generator(0, &q), Kepler::default().generator(0, &q));
    assert_eq!(text.generator_count(), 1);
    assert_eq!(text.momentum_name(0), "J1");
}

#[test]
fn pendulum_from_text_has_the_zoo_models_derivatives() {
    let zoo = Pendulum::default();
    let parameters: Vec<(&str, f64)> = zoo.parameters();
    let spec = spec(
        "0.5*m*l^2*vtheta^2 + m*g*l*cos(theta)",
        &["theta"],
        &parameters,
    );
    let model = TextModel::new(&spec).unwrap();
    assert_eq!(model.structure(), Structure::ConstantMass);
    let text = TextLagrangian::<U1, false, false, true>::new(model).unwrap();
    same_derivatives(
        &text,
        &zoo,
        &[
            (0.0, [0.3], [1.1]),
            (2.0, [-2.9], [-0.4]),
            (5.0, [1.0e-3], [3.0]),
        ],
    );
}

#[test]
fn a_forced_model_from_text_has_the_zoo_models_force() {
    let zoo = DampedOscillator::default();
    let parameters = zoo.parameters();
    let (sigma, zeta) = (parameters[0].1, parameters[1].1);
    assert_eq!((parameters[0].0, parameters[1].0), ("sigma", "zeta"));
    let mut spec = spec(
        "(vq^2 - q^2*sigma^2)/2",
        &["q"],
        &[("sigma", sigma), ("zeta", zeta)],
    );
    spec.forces = vec!["-2*zeta*sigma*vq".into()];
    let text = TextLagrangian::<U1>::new(TextModel::new(&spec).unwrap()).unwrap();
    let points = [(0.0, [0.3], [1.1]), (2.0, [-2.9], [-0.4])];
    same_derivatives(&text, &zoo, &points);
    // A short run with the force: the same states to round-off.
    fn run<L: svi::Lagrangian<U1>>(model: L) -> svi::PhasePoint<U1> {
        Integrator::new(model, Svi::new(6))
            .run_from_velocity(
                0.0,
                SVector::from([1.0]),
                SVector::from([0.0]),
                0.1,
                10.0,
                &mut (),
            )
            .unwrap()
            .last
    }
    let (a, b) = (run(text), run(zoo));
    assert!((a.q - b.q).amax() < 1e-13, "{} against {}", a.q, b.q);
}

/// The acceptance test of issue #20: the built-in `kepler` scene (e = 0.5, SVI with 6 CGL
/// and 12 GL points, h = 0.2, T = 2000) run from text ends within 1e-10 of the zoo model.
#[test]
fn kepler_from_text_matches_the_zoo_model_at_t_2000() {
    let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
    let (t0, zoo_q, zoo_v) = Kepler::default().initial_state();
    assert_eq!((t0, zoo_q, zoo_v), (0.0, q, v));
    let text = Integrator::new(kepler_text(), Svi::new(6))
        .run_from_velocity(0.0, q, v, 0.2, 2000.0, &mut ())
        .unwrap();
    let zoo = Integrator::new(Kepler::default(), Svi::new(6))
        .run_from_velocity(0.0, q, v, 0.2, 2000.0, &mut ())
        .unwrap();
    assert_eq!(text.statistics.steps, 10_000);
    let difference = (text.last.q - zoo.last.q).amax();
    assert!(difference < 1e-10, "|Δq| = {difference:e}");
    // Of run-time size, as `svi run` takes it: the force by the compiled program with the
    // quadrature points as lanes (`Lagrangian::batch_force`).
    let run_time =
        TextLagrangian::<Dyn, false, false, true>::new(kepler_text().model().clone()).unwrap();
    let (q, v) = (
        DVector::from_column_slice(&[0.5, 0.0]),
        DVector::from_column_slice(&[0.0, 3f64.sqrt()]),
    );
    let text = Integrator::new(run_time, Svi::new(6))
        .run_from_velocity(0.0, q, v, 0.2, 2000.0, &mut ())
        .unwrap();
    let difference = (text.last.q - DVector::from_column_slice(zoo.last.q.as_slice())).amax();
    assert!(difference < 1e-10, "run-time size: |Δq| = {difference:e}");
}

/// A Lagrangian in which a velocity does not appear has a singular mass matrix: refused at
/// parse, naming the velocity, instead of an inverse Legendre map that "did not converge".
#[test]
fn a_lagrangian_without_a_velocity_is_refused_naming_it() {
    let error = TextModel::new(&spec("0.5*vx^2 - x^2 - y^2", &["x", "y"], &[])).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("the lagrangian does not depend on vy"),
        "{error}"
    );
    let error = TextModel::new(&spec("-0.5*x^2", &["x"], &[])).unwrap_err();
    assert!(error.to_string().contains("vx"), "{error}");
}

/// Integer powers beyond num-dual's i32 factor arithmetic (n(n − 1)(n − 2) overflows for
/// n ≳ 1290): L = ½ẋ² − x¹⁰⁰⁰⁰¹/100001 has ∂L/∂x = −x¹⁰⁰⁰⁰⁰ and ∂²L/∂x² = −100000 x⁹⁹⁹⁹⁹,
/// against their closed forms at x = 1 − 10⁻⁵.
#[test]
fn huge_integer_powers_have_the_closed_form_derivatives() {
    let model = TextModel::new(&spec("0.5*vx^2 - x^100001/100001", &["x"], &[])).unwrap();
    let model = TextLagrangian::<U1>::new(model).unwrap();
    let x = 1.0 - 1e-5;
    let second = model.second_derivatives(0.0, &SVector::from([x]), &SVector::from([0.0]));
    let force = -x.powi(100_000);
    let stiffness = -100_000.0 * x.powi(99_999);
    assert!(
        (second.q[0] - force).abs() <= 1e-10 * force.abs(),
        "{}",
        second.q[0]
    );
    assert!(
        (second.qq[(0, 0)] - stiffness).abs() <= 1e-9 * stiffness.abs(),
        "{} against {stiffness}",
        second.qq[(0, 0)]
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

    /// Any text — tokens of the grammar in any order, and arbitrary characters — is a model
    /// or a typed error, never a panic; a model evaluates (and differentiates) without
    /// panicking, and its declarations hold where they are claimed.
    #[test]
    fn arbitrary_text_is_a_model_or_an_error(
        text in "([-+*/^(), .]|[0-9]|1e3|x|y|vx|vy|t|mu|sin|atan2|sqrt|pi|e|[a-zα]){0,40}",
        q in proptest::array::uniform2(-3.0..3.0f64),
        v in proptest::array::uniform2(-3.0..3.0f64),
    ) {
        let spec = spec(&text, &["x", "y"], &[("mu", 0.5)]);
        let Ok(model) = TextModel::new(&spec) else { return Ok(()) };
        let structure = model.structure();
        let split = (structure == Structure::ConstantMass)
            .then(|| TextLagrangian::<U2, true, true, true>::new(model.clone()).unwrap());
        let text_model = TextLagrangian::<U2>::new(model).unwrap();
        let (q, v) = (SVector::from(q), SVector::from(v));
        let value = text_model.value(0.3, &q, &v);
        let second = text_model.second_derivatives(0.3, &q, &v);
        if structure == Structure::ConstantMass && second.qv.iter().all(|x| x.is_finite()) {
            proptest::prop_assert_eq!(second.qv, nalgebra::SMatrix::<f64, 2, 2>::zeros(), "{}", text);
        }
        // The same value, up to the rounding of num-dual's own powers (x⁴ is x·x·x·x there,
        // powi in f64).
        proptest::prop_assert!(
            value.is_nan() || (value - second.value).abs() <= 8.0 * f64::EPSILON * value.abs(),
            "{}: {} against {}", text, value, second.value
        );
        // ½q̇ᵀMq̇ + U(t, q) is L.
        if let Some(split) = split {
            let other = split.value(0.3, &q, &v);
            proptest::prop_assert!(
                !value.is_finite() || (other - value).abs() <= 1e-12 * value.abs().max(1.0),
                "{}: {} against {}", text, other, value
            );
        }
    }
}
