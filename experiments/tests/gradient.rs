//! A scene's derivatives ([`Scene::gradient`] and the run's sensitivity block) against each
//! other, and the bad losses they refuse.

use svi::MethodSpec;
use svi_experiments::scene::method::SceneMethod;
use svi_experiments::{Control, Scene, SceneError};

/// ℓ_j = (j + 1) q₁ + ½ q̇₂²: a weight per output, q and q̇ both in it.
fn loss(j: usize, _t: f64, q: &[f64], v: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
    let weight = (j + 1) as f64;
    let value = weight * q[0] + 0.5 * v[1] * v[1];
    (value, vec![weight, 0.0], vec![0.0, v[1]])
}

/// Kepler by the midpoint rule, differentiated with respect to e, the phase and q0.
fn kepler() -> Scene {
    let mut kepler = Scene::builtin("kepler").expect("built-in").expect("parses");
    let midpoint: MethodSpec = "midpoint".parse().expect("a method");
    kepler.method.name = Some(SceneMethod::Registry(midpoint));
    kepler.run.h = Some(0.05);
    kepler.run.t_end = Some(2.0);
    kepler.run.sensitivity = Some(vec!["e".into(), "phase".into(), "q0".into()]);
    kepler.run.sensitivity_every = Some(8);
    kepler
}

#[test]
fn a_native_loss_has_the_gradient_of_the_sensitivities_chain_rule() {
    let scene = kepler();
    let summary = scene.run(Control::default()).unwrap();
    let block = summary.sensitivity.unwrap();
    // Σ_j ∇ℓ_j · ∂(q, q̇)(t_j)/∂(column), through the Jacobians of every output.
    let mut chained = vec![0.0; block.columns.len()];
    let mut value = 0.0;
    for (j, output) in block.outputs.iter().enumerate() {
        let (ell, dq, dv) = loss(j, output.t, &output.q, &output.v);
        value += ell;
        let nabla: Vec<f64> = dq.into_iter().chain(dv).collect();
        for (c, total) in chained.iter_mut().enumerate() {
            *total += (0..4)
                .map(|r| nabla[r] * output.jacobian[r][c])
                .sum::<f64>();
        }
    }
    let gradient = scene.gradient(&loss, Some(2)).unwrap();
    assert_eq!(gradient.columns, ["e", "phase", "q0_q1", "q0_q2"]);
    assert!((gradient.value - value).abs() <= 1e-13 * value.abs());
    let largest = chained.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (adjoint, forward) in gradient.gradient.iter().zip(&chained) {
        assert!(
            (adjoint - forward).abs() <= 1e-11 * largest,
            "{adjoint} {forward}"
        );
    }
    assert!(gradient.peak_stored >= 2);
}

#[test]
fn a_loss_that_is_not_finite_or_a_gradient_without_names_is_refused() {
    let nan = |j: usize, _t: f64, q: &[f64], v: &[f64]| {
        let value = if j == 2 { f64::NAN } else { q[0] };
        (value, vec![0.0; q.len()], vec![0.0; v.len()])
    };
    let error = kepler().gradient(&nan, None).unwrap_err().to_string();
    assert!(error.contains("loss at output 2"), "{error}");
    let short = |_j: usize, _t: f64, q: &[f64], _v: &[f64]| (q[0], vec![1.0], vec![]);
    let error = kepler().gradient(&short, None).unwrap_err().to_string();
    assert!(error.contains("loss at output"), "{error}");
    let mut unnamed = kepler();
    unnamed.run.sensitivity = None;
    unnamed.run.sensitivity_every = None;
    assert!(matches!(
        unnamed.gradient(&loss, None),
        Err(SceneError::NotApplicable {
            option: "gradient",
            ..
        })
    ));
    let error = kepler().gradient(&loss, Some(0)).unwrap_err().to_string();
    assert!(error.contains("checkpoints"), "{error}");
}
