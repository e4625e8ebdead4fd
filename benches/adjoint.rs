//! The cost of a gradient by the discrete adjoint against the forward run it differentiates
//! (issue #40: at most 4× on a 10⁵-step SVI 7/6 Kepler run, with O(√K) stored states).
//!
//! Kepler e = 0.5 from its pericentre, SVI with 7 points and 6 Gauss–Legendre nodes, h = 0.02,
//! K = 10⁵ steps (T = 2000). Timed as [`ROUNDS`] rounds of a forward run then the run
//! measured, each figure the median over the rounds, each ratio the median of the rounds'
//! ratios:
//! - `forward`: the plain run of the model ([`Integrator::run`], no observer);
//! - `gradient`: the gradient of J = Σ_j q₁(t_j) over outputs every 1000 steps with respect
//!   to (q₀, q̇₀) and e ([`Integrator::gradient`], default checkpoints);
//! - `sensitivities`: the forward sensitivities at the same outputs.
//!
//! It prints the times, the ratios to `forward`, the checkpoints and steps' adjoints held at the
//! peak and their bytes, and how far the gradient is from the forward sensitivities' (J's
//! gradient by the chain rule through them). Run with `cargo bench --bench adjoint`.

use nalgebra::{DVector, SVector};
use std::time::Instant;
use svi::sensitivity::{Checkpoints, Loss, SensitivityRun, Start};
use svi::{Initial, Integrator, Scalar, Svi};
use svi_models::Kepler;

/// Whole runs timed per measurement (the median is reported).
const ROUNDS: usize = 9;
const STEPS: usize = 100_000;
const T_END: f64 = 2000.0;

/// J = Σ_j q₁(t_j).
struct FirstCoordinate;

impl Loss for FirstCoordinate {
    fn loss<D: Scalar>(&self, _output: usize, _t: f64, q: &[D], _v: &[D]) -> D {
        q[0]
    }
}

/// The seconds `run` takes.
fn seconds(run: &mut impl FnMut()) -> f64 {
    let start = Instant::now();
    run();
    start.elapsed().as_secs_f64()
}

/// The median of a list of numbers.
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// `ROUNDS` rounds of `forward` then `other`, one after the other: the median times of both
/// and the median of the rounds' ratios (pairs keep the ratio meaningful when the machine's
/// speed drifts during the bench).
fn paired(mut forward: impl FnMut(), mut other: impl FnMut()) -> (f64, f64, f64) {
    let rounds: Vec<(f64, f64)> = (0..ROUNDS)
        .map(|_| (seconds(&mut forward), seconds(&mut other)))
        .collect();
    (
        median(rounds.iter().map(|r| r.0).collect()),
        median(rounds.iter().map(|r| r.1).collect()),
        median(rounds.iter().map(|r| r.1 / r.0).collect()),
    )
}

fn main() {
    let model = Kepler::new(0.5).unwrap();
    let integrator = Integrator::new(model, Svi::new(7).with_quadrature(6));
    let h = T_END / STEPS as f64;
    let initial = Initial::Velocity {
        q: SVector::from([0.5, 0.0]),
        v: SVector::from([0.0, 3.0_f64.sqrt()]),
    };
    let forward = || {
        integrator.run(0.0, initial, h, T_END, &mut ()).unwrap();
    };
    let run = SensitivityRun::new(0.0, Start::Model, h, T_END)
        .with_parameters(&["e"])
        .with_outputs_every(1000);
    let mut last = None;
    let (forward_time, gradient, gradient_ratio) = paired(forward, || {
        last = Some(
            integrator
                .gradient(&run, &FirstCoordinate, Checkpoints::default())
                .unwrap(),
        );
    });
    let mut forward_sensitivities = None;
    let (_, sensitivities, sensitivities_ratio) = paired(forward, || {
        forward_sensitivities = Some(integrator.sensitivities(&run).unwrap());
    });
    // dJ/d(q₀, q̇₀, e) by the chain rule through the forward sensitivities: the sum of the
    // q₁ rows of the outputs' Jacobians.
    let by_sensitivities = forward_sensitivities
        .unwrap()
        .outputs
        .iter()
        .fold(DVector::zeros(5), |sum, point| {
            sum + point.jacobian.row(0).transpose()
        });
    let last = last.unwrap();
    println!("Kepler e = 0.5, SVI 7/6, {STEPS} steps of h = {h}:");
    println!("  forward        {:8.2} ms", forward_time * 1e3);
    println!(
        "  gradient       {:8.2} ms  {:5.2}× forward",
        gradient * 1e3,
        gradient_ratio
    );
    println!(
        "  sensitivities  {:8.2} ms  {:5.2}× forward",
        sensitivities * 1e3,
        sensitivities_ratio
    );
    println!(
        "  peak stored: {} states and steps' adjoints, {} bytes (√K = {:.0})",
        last.peak_stored,
        last.peak_bytes,
        (STEPS as f64).sqrt()
    );
    println!(
        "  dJ/de = {:.6e}, dJ/dq0 = {:.6e} {:.6e}",
        last.parameters[0], last.initial[0], last.initial[1]
    );
    let by_adjoint =
        DVector::from_iterator(5, last.initial.iter().chain(&last.parameters).copied());
    println!(
        "  gradient against the forward sensitivities' chain rule: {:.1e} relative to its \
         largest entry",
        (&by_adjoint - &by_sensitivities).amax() / by_sensitivities.amax()
    );
}
