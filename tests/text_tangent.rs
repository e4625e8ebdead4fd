//! The exact tangent map and linear stability on a 50-coordinate model written as text: a chain
//! of 50 unit masses joined by unit springs, ends fixed,
//! L = Σᵢ ½ q̇ᵢ² − ½ Σᵢ (qᵢ₊₁ − qᵢ)² (q₀ = q₅₁ = 0), written out term by term.
//!
//! References: central differences of the step (the tangent map), the symplectic form
//! ΦᵀJΦ = J, and the chain's normal modes ω_k = 2 sin(kπ/102): Störmer–Verlet is stable iff
//! h ω_max < 2, i.e. h < 1/sin(50π/102) = 1.000474…, and its tangent map's eigenvalues then lie
//! on the unit circle.

use nalgebra::{DMatrix, DVector};
use svi::method::registry::find;
use svi::method::{State, TangentMap};
use svi::model::text::{TextLagrangian, TextModel, TextSpec};
use svi::{Dyn, Integrator, Method};

/// Coordinates of the chain.
const N: usize = 50;

/// The chain as text.
fn chain() -> TextLagrangian<Dyn, false, false, true> {
    let kinetic: Vec<String> = (1..=N).map(|i| format!("0.5*vq{i}^2")).collect();
    let springs: Vec<String> = (0..=N)
        .map(|i| match i {
            0 => "0.5*q1^2".to_string(),
            N => format!("0.5*q{N}^2"),
            _ => format!("0.5*(q{}-q{i})^2", i + 1),
        })
        .collect();
    let spec = TextSpec {
        lagrangian: format!("{} - ({})", kinetic.join(" + "), springs.join(" + ")),
        coordinates: (1..=N).map(|i| format!("q{i}")).collect(),
        ..TextSpec::default()
    };
    TextLagrangian::new(TextModel::new(&spec).unwrap()).unwrap()
}

/// A state away from the equilibrium (the map is linear, so any state serves).
fn state() -> State<Dyn> {
    State {
        q: DVector::from_fn(N, |i, _| 0.3 * (0.7 * i as f64).sin()),
        y: DVector::from_fn(N, |i, _| 0.2 * (1.3 * i as f64).cos()),
    }
}

/// The tangent map as one 2N × 2N matrix.
fn matrix(tangent: &TangentMap<Dyn>) -> DMatrix<f64> {
    let mut phi = DMatrix::zeros(2 * N, 2 * N);
    phi.view_mut((0, 0), (N, N)).copy_from(&tangent.qq);
    phi.view_mut((0, N), (N, N)).copy_from(&tangent.qy);
    phi.view_mut((N, 0), (N, N)).copy_from(&tangent.yq);
    phi.view_mut((N, N), (N, N)).copy_from(&tangent.yy);
    phi
}

/// The tangent map of one step of `method` with step `h`.
fn tangent<M: Method<Dyn>>(method: M, h: f64) -> DMatrix<f64> {
    let (_, tangent) = Integrator::new(chain(), method)
        .tangent_map(0.0, &state(), h)
        .unwrap();
    matrix(&tangent)
}

/// The largest modulus of the eigenvalues of `phi`.
fn spectral_radius(phi: &DMatrix<f64>) -> f64 {
    phi.complex_eigenvalues()
        .iter()
        .map(|lambda| lambda.norm())
        .fold(0.0, f64::max)
}

#[test]
fn the_tangent_map_of_a_fifty_coordinate_text_model_is_the_steps_derivative() {
    let h = 0.3;
    for name in ["svi", "verlet", "midpoint"] {
        let method = find(name).unwrap().spec().vector_method().unwrap();
        let integrator = Integrator::new(chain(), method.clone());
        let phi = tangent(method, h);
        // Central differences of the step, column by column.
        let epsilon = 1e-6;
        let mut gap: f64 = 0.0;
        for j in 0..2 * N {
            let shifted = |sign: f64| {
                let mut start = state();
                if j < N {
                    start.q[j] += sign * epsilon;
                } else {
                    start.y[j - N] += sign * epsilon;
                }
                let (end, _) = integrator.step(0.0, &start, h).unwrap();
                end
            };
            let (plus, minus) = (shifted(1.0), shifted(-1.0));
            for i in 0..N {
                let dq = (plus.q[i] - minus.q[i]) / (2.0 * epsilon);
                let dy = (plus.y[i] - minus.y[i]) / (2.0 * epsilon);
                gap = gap.max((phi[(i, j)] - dq).abs());
                gap = gap.max((phi[(N + i, j)] - dy).abs());
            }
        }
        assert!(gap <= 1e-7, "{name}: {gap:e}");
        // Symplectic in (q, p): ΦᵀJΦ = J.
        let mut j = DMatrix::zeros(2 * N, 2 * N);
        j.view_mut((0, N), (N, N)).fill_with_identity();
        j.view_mut((N, 0), (N, N))
            .copy_from(&(-DMatrix::<f64>::identity(N, N)));
        let defect = (phi.transpose() * &j * &phi - &j).amax();
        assert!(defect <= 1e-12, "{name}: {defect:e}");
    }
}

#[test]
fn linear_stability_on_the_text_chain_follows_its_fastest_mode() {
    let bound = 1.0 / (50.0 * std::f64::consts::PI / 102.0).sin();
    assert!((bound - 1.000474).abs() < 1e-6);
    let verlet = || find("verlet").unwrap().spec().vector_method().unwrap();
    // Below the bound every eigenvalue of the step lies on the unit circle …
    let stable = spectral_radius(&tangent(verlet(), 0.99 * bound));
    assert!((stable - 1.0).abs() <= 1e-9, "{stable}");
    // … above it the fastest mode grows.
    let unstable = spectral_radius(&tangent(verlet(), 1.01 * bound));
    assert!(unstable > 1.1, "{unstable}");
    // The implicit midpoint rule is stable at any step.
    let midpoint = find("midpoint").unwrap().spec().vector_method().unwrap();
    let radius = spectral_radius(&tangent(midpoint, 5.0));
    assert!((radius - 1.0).abs() <= 1e-9, "{radius}");
}
