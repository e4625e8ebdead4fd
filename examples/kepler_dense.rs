//! Kepler's problem (e = 0.5) over 100 orbits with SVI 9/8, its dense output evaluated
//! between the steps and compared with the exact orbit.
//!
//! `cargo run --release --example kepler_dense`

use svi::solve::{SolveOptions, Span, solve};
use svi::{Defaults, ExactSolution, Initial, Svi};
use svi_models::Kepler;

fn main() -> Result<(), svi::Error> {
    let model = Kepler::new(0.5)?;
    let (t0, q0, v0) = model.initial_state();
    let t_end = 200.0 * std::f64::consts::PI;
    let mut options = SolveOptions::fixed_step(0.05);
    options.dense = true; // keep every step's polynomial: the solution at any time
    let initial = Initial::Velocity { q: q0, v: v0 };
    let solution = solve(
        model,
        Svi::new(9).with_quadrature(8),
        &Span::new(t0, t_end),
        initial,
        &options,
    )?;
    let dense = solution.dense.expect("asked for");
    let mut worst: f64 = 0.0;
    for k in 0..=10_000 {
        let t = t0 + (t_end - t0) * k as f64 / 10_000.0;
        let point = dense.at(t)?;
        let (exact, _) = model
            .exact_solution(t0, &q0, &v0, t)
            .expect("a bound orbit has a closed form");
        worst = worst.max(
            (point.q[0] - exact[0])
                .abs()
                .max((point.q[1] - exact[1]).abs()),
        );
    }
    println!(
        "{} steps; largest position error at 10 001 times between them: {worst:.1e}",
        solution.statistics.steps
    );
    assert!(worst < 1e-8, "dense output as accurate as the steps");
    Ok(())
}
