//! A planar chain of 12 pendulums written as text (12 angles, a mass matrix that depends on
//! them) against the same chain written in Rust (`Lagrangian<Const<12>>`): the implicit
//! methods of ℝᴺ that serve a non-constant mass end at the same state to 1e-12, and keep the
//! energy error bounded.
//!
//! The chain: unit masses on massless rods of unit length, hinged one below the other, the
//! angles θ₁ … θ₁₂ measured from the downward vertical. Mass i sits at
//! xᵢ = Σ_{j≤i} sin θⱼ, yᵢ = −Σ_{j≤i} cos θⱼ, so
//! L = Σᵢ ½ (ẋᵢ² + ẏᵢ²) − g Σᵢ yᵢ with ẋᵢ = Σ_{j≤i} cos θⱼ θ̇ⱼ, ẏᵢ = Σ_{j≤i} sin θⱼ θ̇ⱼ.
//! The text is that formula written out term by term, as a user would generate it.

use nalgebra::{DVector, SVector};
use svi::model::text::{TextLagrangian, TextModel, TextSpec};
use svi::observer::EnergyError;
use svi::{Dimension, Dyn, Integrator, Lagrangian, LagrangianExt, Method, Scalar, Structure};

/// Links of the chain.
const LINKS: usize = 12;
/// Gravity.
const G: f64 = 9.81;

/// The chain in Rust.
struct Chain;

impl Lagrangian<nalgebra::Const<LINKS>> for Chain {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::General;

    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, LINKS>, v: &SVector<D, LINKS>) -> D {
        let (mut vx, mut vy, mut y) = (D::zero(), D::zero(), D::zero());
        let mut lagrangian = D::zero();
        for j in 0..LINKS {
            vx += q[j].cos() * v[j];
            vy += q[j].sin() * v[j];
            y -= q[j].cos();
            lagrangian += (vx * vx + vy * vy) * 0.5 - y * G;
        }
        lagrangian
    }
}

/// The chain as text: the same sums written out.
fn chain_as_text() -> TextLagrangian<Dyn> {
    let partial = |i: usize, term: &dyn Fn(usize) -> String| {
        (1..=i).map(term).collect::<Vec<_>>().join(" + ")
    };
    let lagrangian = (1..=LINKS)
        .map(|i| {
            let vx = partial(i, &|j| format!("cos(th{j})*vth{j}"));
            let vy = partial(i, &|j| format!("sin(th{j})*vth{j}"));
            let height = partial(i, &|j| format!("cos(th{j})"));
            format!("0.5*(({vx})^2 + ({vy})^2) + g*({height})")
        })
        .collect::<Vec<_>>()
        .join(" + ");
    let spec = TextSpec {
        lagrangian,
        coordinates: (1..=LINKS).map(|j| format!("th{j}")).collect(),
        parameters: vec![("g".into(), G)],
        ..TextSpec::default()
    };
    let model = TextModel::new(&spec).unwrap();
    assert_eq!(model.structure(), Structure::General);
    TextLagrangian::new(model).unwrap()
}

/// The initial angles: a zig-zag, released at rest.
fn initial_angles() -> Vec<f64> {
    (0..LINKS)
        .map(|j| 0.4 * if j % 2 == 0 { 1.0 } else { -0.7 })
        .collect()
}

/// `steps` steps of size `h` of `method` on `model` from [`initial_angles`] at rest: (q, q̇) at
/// the end and the largest |E − E₀|.
fn run<L: Lagrangian<N>, N: Dimension, M: Method<N>>(
    model: L,
    method: M,
    h: f64,
    steps: usize,
) -> (Vec<f64>, f64)
where
    nalgebra::DefaultAllocator:
        nalgebra::allocator::Allocator<N> + nalgebra::allocator::Allocator<N, N>,
{
    let n = N::from_usize(LINKS);
    let q0 =
        nalgebra::OVector::<f64, N>::from_column_slice_generic(n, nalgebra::U1, &initial_angles());
    let v0 = nalgebra::OVector::<f64, N>::zeros_generic(n, nalgebra::U1);
    let mut energy = EnergyError::default();
    let run = Integrator::new(model, method)
        .run_from_velocity(0.0, q0, v0, h, h * steps as f64, &mut energy)
        .unwrap();
    let state = run
        .last
        .q
        .iter()
        .chain(run.last.v.iter())
        .copied()
        .collect();
    (state, energy.max)
}

#[test]
fn a_twelve_link_pendulum_chain_written_as_text_runs_as_the_rust_one() {
    // The energy scale: the chain's potential energy at the start.
    let q0 = DVector::from_vec(initial_angles());
    let scale = chain_as_text()
        .energy(0.0, &q0, &DVector::zeros(LINKS))
        .abs();
    let h = 0.005;
    let steps = 20;
    for name in ["svi", "svi-newton", "sc", "midpoint", "trapezoid"] {
        let spec = svi::method::registry::find(name).unwrap().spec();
        let method = spec.vector_method().unwrap();
        // SC's Newton matrix is the Jacobian of the acceleration, taken at run-time size by
        // scalar sweeps through second derivatives of L (a slow Newton matrix at this size): a
        // few steps.
        let steps = if name == "sc" { 4 } else { steps };
        let (rust, rust_energy) = run(Chain, method.clone(), h, steps);
        let (text, text_energy) = run(chain_as_text(), method, h, steps);
        let gap = rust
            .iter()
            .zip(&text)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(gap <= 1e-12, "{name}: {gap:e}");
        assert!((rust_energy - text_energy).abs() <= 1e-10 * scale, "{name}");
        // The chain has swung: the state is not where it started.
        let moved = (0..LINKS)
            .map(|j| (text[j] - q0[j]).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-4, "{name}: {moved:e}");
        // Bounded energy error: the spectral methods to their order, the second-order ones
        // to O(h²).
        let bound = if name.starts_with("svi") || name == "sc" {
            1e-9
        } else {
            1e-4
        };
        assert!(
            text_energy <= bound * scale,
            "{name}: {:e}",
            text_energy / scale
        );
    }
}
