//! Chains written as text (indexed coordinates and sums, `svi::model::text::chain`) against
//! the same chains of the zoo written in Rust: FPUT with fixed ends (`svi_models::Fput`) and
//! the periodic Toda lattice (`svi_models::Toda`), whose closed forms have their own tests;
//! derivatives against hand-derived ones; and every misuse of the grammar as a typed error
//! naming the column and the symbol.

use nalgebra::DVector;
use svi::model::local::{
    LocalDefaults, LocalLagrangian, LocalLagrangianExt, Terms, force_by_terms, value_by_terms,
};
use svi::model::text::{
    Boundary, TextChain, TextChainModel, TextError, TextModel, TextSpec, site_values,
};
use svi::{Initial, Integrator, StormerVerlet, Structure, Svi};
use svi_models::{Fput, Toda};

/// The FPUT chain of the zoo in one line of text (fixed ends).
const FPUT: &str = "sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1]-q[i])^2 \
                    + alpha/3*(q[i+1]-q[i])^3 + beta/4*(q[i+1]-q[i])^4)";

/// A chain spec: `lagrangian` in the family q[1..n] with `parameters`.
fn chain(lagrangian: &str, parameters: &[(&str, f64)]) -> TextSpec {
    TextSpec {
        lagrangian: lagrangian.into(),
        coordinates: vec!["q[1..n]".into()],
        parameters: parameters
            .iter()
            .map(|(name, value)| ((*name).into(), *value))
            .collect(),
        ..TextSpec::default()
    }
}

/// FPUT of n particles written as text, with α = 0.25, β = 0.5.
fn fput_text(n: usize) -> TextChain<2, false, true> {
    let spec = chain(FPUT, &[("n", n as f64), ("alpha", 0.25), ("beta", 0.5)]);
    let model = TextChainModel::new(&spec).unwrap();
    assert_eq!(model.width(), 2);
    assert_eq!(model.structure(), Structure::ConstantMass);
    assert!(!model.time_dependent());
    TextChain::new(model).unwrap()
}

/// The zoo's FPUT of n particles with α = 0.25, β = 0.5.
fn fput_zoo(n: usize) -> Fput {
    let mut model = Fput::default();
    model.set_parameter("n", n as f64).unwrap();
    model.set_parameter("beta", 0.5).unwrap();
    model
}

/// max |a − b|.
fn distance(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax()
}

#[test]
fn fput_as_one_line_of_text_follows_the_zoo_chain_to_round_off() {
    let n = 1000;
    let (text, zoo) = (fput_text(n), fput_zoo(n));
    assert_eq!((text.dimension(), text.term_count()), (n, n + 1));
    // The zoo's initial state (all energy in mode 1) from the per-site expression.
    let (t0, q0, v0) = zoo.initial_state();
    let q = site_values(
        &["sin(pi*i/(n+1))".into()],
        1,
        "initial.q",
        &text.parameters(),
        n,
    )
    .unwrap();
    assert!(distance(&q, &q0) <= 1e-15);
    assert_eq!(v0, DVector::zeros(n));
    // And a rough state that moves every particle at once.
    let v = site_values(
        &["0.3*sin(0.37*i^2)".into()],
        1,
        "initial.v",
        &text.parameters(),
        n,
    )
    .unwrap();
    let (h, steps) = (0.1, 100);
    let t_end = t0 + h * steps as f64;
    for initial in [
        Initial::Velocity {
            q: q.clone(),
            v: v0,
        },
        Initial::Velocity { q, v },
    ] {
        let verlet = StormerVerlet::default();
        let a = Integrator::new(Terms(text.clone()), verlet.clone())
            .run(t0, initial.clone(), h, t_end, &mut ())
            .unwrap();
        let b = Integrator::new(Terms(zoo.clone()), verlet)
            .run(t0, initial.clone(), h, t_end, &mut ())
            .unwrap();
        assert_eq!(a.statistics.steps, steps);
        assert!(distance(&a.last.q, &b.last.q) <= 1e-13);
        assert!(distance(&a.last.p, &b.last.p) <= 1e-13);
        let svi = Svi::default();
        let c = Integrator::new(Terms(text.clone()), svi.clone())
            .run(t0, initial.clone(), h, t_end, &mut ())
            .unwrap();
        let d = Integrator::new(Terms(zoo.clone()), svi)
            .run(t0, initial, h, t_end, &mut ())
            .unwrap();
        assert!(distance(&c.last.q, &d.last.q) <= 1e-13);
        assert!(distance(&c.last.p, &d.last.p) <= 1e-13);
        // The runs went somewhere, and the two methods agree to their accuracy.
        assert!(distance(&a.last.q, &q0) > 1e-4);
        assert!(distance(&a.last.q, &c.last.q) < 1e-2);
    }
}

#[test]
fn the_chains_derivatives_and_mass_are_the_zoo_chains() {
    let (text, zoo) = (fput_text(7), fput_zoo(7));
    let q = DVector::from_fn(7, |i, _| 0.3 * (i as f64 + 1.0).sin());
    let v = DVector::from_fn(7, |i, _| 0.2 * (i as f64 * 0.7).cos());
    let (mut a, mut b) = (DVector::zeros(7), DVector::zeros(7));
    text.force_into(0.0, &q, &v, &mut a);
    zoo.force_into(0.0, &q, &v, &mut b);
    assert!(distance(&a, &b) <= 1e-15, "{a} {b}");
    text.momentum_into(0.0, &q, &v, &mut a);
    assert_eq!(a, v);
    assert!((text.value(0.0, &q, &v) - zoo.value(0.0, &q, &v)).abs() <= 1e-15);
    let mut mass = text.mass_triplets(0.0, &q, &v);
    mass.sort_by_key(|&(i, j, _)| (i, j));
    assert_eq!(mass, (0..7).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
}

/// A chain of two families whose terms use every function and operation of the grammar,
/// with a mass matrix that depends on q (so the force reads q̇ too).
const EVERYTHING: &str = "sum(i, 1, n, 0.5*vx[i]^2 + 0.5*vy[i]^2*(1 + 0.1*x[i]^2) \
     + vx[i]*vy[i+1]*x[i] - sin(x[i+1] - x[i]) - exp(0.1*y[i])*cos(y[i+1]) \
     + sqrt(1 + x[i]^2)*tanh(y[i]) - atan2(x[i], 2 + y[i+1]^2) + abs(x[i] - y[i])^1.5 \
     + ln(2 + x[i+1]^2)/(3 + y[i]^2) + (x[i]^2 + 1)^(0.5*y[i]) + tan(0.1*x[i]) \
     + asin(0.1*y[i]) - acos(0.1*x[i+1]) + atan(x[i])*t + sinh(0.1*y[i])*cosh(0.1*x[i]) \
     + 1/(2 + x[i]^2) + x[i+1]^3/4 - (2 + y[i]^2)^-2 + k*x[i]*y[i+1] - 2 - x[i]) \
     - sum(i, 0, 0, k*x[i+1]^2) + y[n]*vy[n]";

#[test]
fn the_compiled_value_and_force_are_the_term_by_term_ones() {
    let relative = |a: &DVector<f64>, b: &DVector<f64>| (a - b).amax() / b.amax().max(1.0);
    for boundary in [Boundary::Fixed, Boundary::Periodic] {
        for n in [1, 2, 3, 70] {
            let spec = TextSpec {
                lagrangian: EVERYTHING.into(),
                coordinates: vec!["x[1..n]".into(), "y[1..n]".into()],
                parameters: vec![("n".into(), n as f64), ("k".into(), 0.7)],
                boundary,
                ..TextSpec::default()
            };
            let model = TextChainModel::new(&spec).unwrap();
            assert_eq!(model.structure(), Structure::General);
            let text = TextChain::<4>::new(model).unwrap();
            let q = DVector::from_fn(2 * n, |i, _| 0.4 * (1.3 * i as f64 + 0.2).sin());
            let v = DVector::from_fn(2 * n, |i, _| 0.3 * (0.7 * i as f64).cos());
            let (mut compiled, mut by_terms) = (DVector::zeros(2 * n), DVector::zeros(2 * n));
            text.force_into(0.6, &q, &v, &mut compiled);
            force_by_terms(&text, 0.6, &q, &v, &mut by_terms);
            assert!(
                relative(&compiled, &by_terms) < 1e-14,
                "{boundary:?}, n = {n}"
            );
            assert!(by_terms.amax() > 0.1);
        }
    }
    // Toda's exponential on a ring of 1 to 3 sites, where a term's slots repeat a site.
    for n in [1, 2, 3] {
        let mut spec = chain(
            "sum(i, 1, n, 0.5*vq[i]^2 - exp(q[i] - 2*q[i+1]))",
            &[("n", n as f64)],
        );
        spec.boundary = Boundary::Periodic;
        let text = TextChain::<2, false, true>::new(TextChainModel::new(&spec).unwrap()).unwrap();
        let q = DVector::from_fn(n, |i, _| 0.3 * i as f64 - 0.2);
        let v = DVector::zeros(n);
        let (mut compiled, mut by_terms) = (DVector::zeros(n), DVector::zeros(n));
        text.force_into(0.0, &q, &v, &mut compiled);
        force_by_terms(&text, 0.0, &q, &v, &mut by_terms);
        assert!(relative(&compiled, &by_terms) < 1e-15, "n = {n}");
        let (value, reference) = (text.value(0.0, &q, &v), value_by_terms(&text, 0.0, &q, &v));
        assert!(
            (value - reference).abs() <= 1e-15 * reference.abs(),
            "{value} {reference}"
        );
    }
}

#[test]
fn the_periodic_toda_lattice_as_text_follows_the_zoo_lattice() {
    let mut spec = chain(
        "sum(i, 1, n, 0.5*vq[i]^2 - exp(q[i] - q[i+1]))",
        &[("n", 16.0)],
    );
    spec.boundary = Boundary::Periodic;
    let text = TextChain::<2, false, true>::new(TextChainModel::new(&spec).unwrap()).unwrap();
    let zoo = Toda::default();
    assert_eq!(text.term_count(), 16);
    assert_eq!(text.indices(15), [15, 0]);
    let (t0, q0, v0) = zoo.initial_state();
    let initial = Initial::Velocity { q: q0, v: v0 };
    let run = |method: Svi| {
        let a = Integrator::new(Terms(text.clone()), method.clone())
            .run(t0, initial.clone(), 0.1, 20.0, &mut ())
            .unwrap()
            .last;
        let b = Integrator::new(Terms(zoo.clone()), method)
            .run(t0, initial.clone(), 0.1, 20.0, &mut ())
            .unwrap()
            .last;
        assert!(distance(&a.q, &b.q) <= 1e-12 && distance(&a.p, &b.p) <= 1e-12);
    };
    run(Svi::new(6).with_quadrature(5));
}

#[test]
fn terms_outside_sums_pin_named_sites() {
    // Harmonic springs, fixed ends, plus pins of stiffness k at both ends and a drive
    // q₂·cos t: ∂L/∂qⱼ = qⱼ₋₁ − 2qⱼ + qⱼ₊₁ − k(δⱼ₁ + δⱼₙ)qⱼ + δⱼ₂ cos t.
    let spec = chain(
        "sum(i, 1, n, vq[i]^2/2) - sum(i, 0, n, (q[i+1] - q[i])^2/2) \
         - k/2*(q[1]^2 + q[n]^2) + q[2]*cos(t)",
        &[("n", 5.0), ("k", 3.0)],
    );
    let model = TextChainModel::new(&spec).unwrap();
    assert!(model.time_dependent());
    assert_eq!(model.structure(), Structure::ConstantMass);
    assert_eq!((model.width(), model.term_count()), (3, 7));
    let text = TextChain::<3>::new(model.clone()).unwrap();
    assert!(TextChain::<3, false, true>::new(model.clone()).is_err());
    assert!(TextChain::<2>::new(model).is_err());
    let q = DVector::from_vec(vec![0.5, -0.25, 1.0, 0.75, -1.5]);
    let v = DVector::zeros(5);
    let t = 0.3;
    let mut force = DVector::zeros(5);
    text.force_into(t, &q, &v, &mut force);
    let at = |j: isize| {
        if (0..5).contains(&j) {
            q[j as usize]
        } else {
            0.0
        }
    };
    for j in 0..5 {
        let jj = j as isize;
        let mut expected = at(jj - 1) - 2.0 * at(jj) + at(jj + 1);
        if j == 0 || j == 4 {
            expected -= 3.0 * q[j];
        }
        if j == 1 {
            expected += t.cos();
        }
        assert!((force[j] - expected).abs() <= 1e-15, "{j}: {}", force[j]);
    }
}

#[test]
fn the_size_resizes_the_chain_and_is_checked() {
    let mut text = fput_text(10);
    text.set_parameter("n", 100_000.0).unwrap();
    assert_eq!((text.dimension(), text.term_count()), (100_000, 100_001));
    assert_eq!(text.indices(0), [0, 0]);
    assert_eq!(text.indices(100_000), [99_999, 99_999]);
    for bad in [0.0, 2.5, -3.0, 1e9, f64::NAN] {
        let error = text.set_parameter("n", bad).unwrap_err().to_string();
        assert!(error.contains('n'), "{error}");
    }
    assert_eq!(text.dimension(), 100_000);
    for bad in [0.0, 2.5] {
        let error = TextChainModel::new(&chain(FPUT, &[("n", bad), ("alpha", 1.0), ("beta", 1.0)]));
        assert!(
            matches!(error, Err(TextError::InvalidSize { .. })),
            "{error:?}"
        );
    }
    // A sum over 1..5 does not move the sixth particle of n = 6: its velocity is missing.
    let mut short =
        TextChainModel::new(&chain("sum(i, 1, 5, vq[i]^2/2 - q[i]^2/2)", &[("n", 5.0)])).unwrap();
    let error = short.set_parameter("n", 6.0).unwrap_err().to_string();
    assert!(error.contains("vq[6]"), "{error}");
    assert_eq!(short.sites(), 5);
}

/// The error of `lagrangian` as a chain in q[1..n] with parameters n and a.
fn error(lagrangian: &str) -> TextError {
    TextChainModel::new(&chain(lagrangian, &[("n", 8.0), ("a", 1.0)])).unwrap_err()
}

/// The column and symbol of an indexing error.
fn indexing(lagrangian: &str) -> (usize, String) {
    match error(lagrangian) {
        TextError::Indexing { column, symbol, .. } => (column, symbol),
        other => panic!("{lagrangian}: {other}"),
    }
}

#[test]
fn misuses_of_indices_and_sums_are_errors_naming_the_column_and_symbol() {
    let body = "vq[i]^2/2 - q[i]^2/2";
    let cases = [
        // An index inside a sum that is not i + c.
        ("sum(i, 1, n, vq[2*i]^2)", 17, "2*i"),
        ("sum(i, 1, n, vq[i]^2 + q[i+a])", 28, "a"),
        ("sum(i, 1, n, vq[i]^2 + q[2])", 26, "2"),
        ("sum(i, 1, n, vq[i]^2 + q[n])", 26, "n"),
        ("sum(i, 1, n, vq[-i]^2)", 17, "-i"),
        // Bounds that are not integers or n ± c.
        ("sum(i, 1.5, n, vq[i]^2)", 8, "1.5"),
        ("sum(i, 1, a, vq[i]^2)", 11, "a"),
        ("sum(i, 1, 2*n, vq[i]^2)", 11, "2*n"),
        // A sum inside a sum, a product, a power or a function.
        ("sum(i, 1, n, vq[i]^2 + sum(j, 1, n, q[j]))", 24, "sum"),
        ("2*sum(i, 1, n, vq[i]^2)", 3, "sum"),
        ("sum(i, 1, n, vq[i]^2)^2", 1, "sum"),
        ("sin(sum(i, 1, n, vq[i]^2))", 5, "sum"),
        // An indexed coordinate outside a sum with an index that is not constant, or bare.
        ("sum(i, 1, n, vq[i]^2) + q[i]", 27, "i"),
        ("sum(i, 1, n, vq[i]^2) + q", 25, "q"),
        // The index outside brackets, and an index name that is taken.
        ("sum(i, 1, n, i*vq[i]^2)", 14, "i"),
        ("sum(n, 1, n, vq[n]^2)", 5, "n"),
        ("sum(a, 1, n, vq[a]^2)", 5, "a"),
        // A sum whose terms read no site of the chain.
        (
            &format!("sum(i, 1, n, {body}) + sum(i, 1, n+1, {body})"),
            38,
            "sum",
        ),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .filter(|(lagrangian, column, symbol)| {
            indexing(lagrangian) != (*column, symbol.to_string())
        })
        .map(|(lagrangian, _, _)| format!("{lagrangian}: {}", error(lagrangian)))
        .collect();
    assert!(wrong.is_empty(), "{wrong:#?}");
    // The message names the rule.
    let message = error("sum(i, 1, n, vq[2*i]^2)").to_string();
    assert_eq!(
        message,
        "indexing error at column 17 of lagrangian ('2*i'): inside sum(i, ...) an index is i \
         plus or minus an integer (i, i+1, i-2): a term reads its neighbours only"
    );
    // Terms wider than four coordinates.
    let wide = error("sum(i, 1, n, vq[i]^2 - q[i]*q[i+4])");
    assert!(
        matches!(wide, TextError::TooWide { width: 5, .. }),
        "{wide}"
    );
    let mut two = chain(
        "sum(i, 1, n, vx[i]^2 + vy[i]^2 - x[i]*y[i+2])",
        &[("n", 4.0)],
    );
    two.coordinates = vec!["x[1..n]".into(), "y[1..n]".into()];
    let wide = TextChainModel::new(&two).unwrap_err();
    assert!(
        matches!(wide, TextError::TooWide { width: 6, .. }),
        "{wide}"
    );
    // A sum without indexed coordinates.
    let plain = TextSpec {
        lagrangian: "sum(i, 1, 3, vx^2)".into(),
        coordinates: vec!["x".into()],
        ..TextSpec::default()
    };
    assert!(matches!(
        TextModel::new(&plain),
        Err(TextError::Indexing { column: 1, .. })
    ));
    // A bound that runs on, and a sum left open.
    assert!(matches!(
        error("sum(i, 1, n vq[i]^2)"),
        TextError::Indexing { column: 11, .. }
    ));
    assert!(matches!(
        error("sum(i, 1, n, vq[i]^2"),
        TextError::Syntax { column: 4, .. }
    ));
}

#[test]
fn misdeclared_families_are_errors_naming_them() {
    let invalid = |coordinates: &[&str], parameters: &[(&str, f64)]| {
        let mut spec = chain("sum(i, 1, n, vq[i]^2)", parameters);
        spec.coordinates = coordinates.iter().map(|name| (*name).into()).collect();
        match TextChainModel::new(&spec) {
            Err(TextError::InvalidName { name, reason, .. }) => (name, reason),
            other => panic!("{coordinates:?}: {other:?}"),
        }
    };
    let n = [("n", 3.0)];
    assert!(invalid(&["q[0..n]"], &n).1.contains("from 1"));
    assert!(
        invalid(&["q[1..m]"], &n)
            .1
            .contains("'m' is not a parameter")
    );
    assert!(invalid(&["q[1..n]", "x"], &n).1.contains("indexed family"));
    let both = [("n", 3.0), ("m", 3.0)];
    assert!(
        invalid(&["q[1..n]", "p[1..m]"], &both)
            .1
            .contains("share one size")
    );
    assert_eq!(invalid(&["sin[1..n]"], &n).0, "sin");
    // A chain takes no forces or symmetries, and a model on ℝᴺ no boundary rule.
    let mut forced = chain("sum(i, 1, n, vq[i]^2)", &n);
    forced.forces = vec!["0".into()];
    assert!(matches!(
        TextChainModel::new(&forced),
        Err(TextError::Unsupported { field, .. }) if field == "forces"
    ));
    let periodic = TextSpec {
        lagrangian: "vx^2".into(),
        coordinates: vec!["x".into()],
        boundary: Boundary::Periodic,
        ..TextSpec::default()
    };
    assert!(matches!(
        TextModel::new(&periodic),
        Err(TextError::Unsupported { .. })
    ));
    assert!(matches!(
        TextModel::new(&chain("sum(i, 1, n, vq[i]^2)", &n)),
        Err(TextError::InvalidName { .. })
    ));
}

#[test]
fn site_values_evaluate_per_site_and_name_their_errors() {
    let parameters = [("n", 3.0), ("a", 2.0)];
    let values = site_values(&["a*i".into(), "-i".into()], 2, "initial.q", &parameters, 3).unwrap();
    assert_eq!(values.as_slice(), [2.0, -1.0, 4.0, -2.0, 6.0, -3.0]);
    let error = site_values(&["i + b".into()], 1, "initial.q", &parameters, 3).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("unknown symbol 'b' at column 5 of initial.q"),
        "{error}"
    );
    assert!(matches!(
        site_values(&["i".into()], 2, "initial.v", &parameters, 3),
        Err(TextError::Dimension { .. })
    ));
}
