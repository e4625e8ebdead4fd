//! The multiscale variational integrator on the stiff spring pendulum (Leok 2004, §5.7.2).

use svi::method::multiscale::Multiscale;
use svi::observer::EnergyError;
use svi::{Defaults, Integrator, Svi};
use svi_models::SpringPendulum;

#[test]
fn explore() {
    let model = SpringPendulum::default();
    let (t0, q0, v0) = model.initial_state();
    let t_end = 10.0;
    let reference = Integrator::new(model, Svi::new(7).with_quadrature(6))
        .run_from_velocity(t0, q0, v0, 1e-3, t_end, &mut ())
        .unwrap();
    eprintln!("reference: {:?}", reference.state.q);
    for h in [0.05, 0.1, 0.2, 0.3125, 0.5] {
        for points in [3, 4, 5] {
            let mut energy = EnergyError::default();
            let run = Integrator::new(model, Multiscale::new(points)).run_from_velocity(
                t0,
                q0,
                v0,
                h,
                t_end,
                &mut energy,
            );
            match run {
                Ok(run) => eprintln!(
                    "h = {h}, points {points}: q = {:?}, θ error {:.2e}, energy error {:.2e}, iterations {}",
                    run.state.q,
                    (run.state.q[1] - reference.state.q[1]).abs(),
                    energy.max,
                    run.statistics.iterations
                ),
                Err(e) => eprintln!("h = {h}, points {points}: {e}"),
            }
        }
    }
}
