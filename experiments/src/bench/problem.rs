//! The problem of a sweep on a model of fixed size: the initial state, the horizon, the
//! scene's run options, and the final position the error is measured against (the exact
//! solution's, or the resolved reference run's).

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};
use svi::{Dimension, Initial, Integrator, RunOptions};
use svi_models::ZooModel;

use crate::scene::SceneError;

/// The problem of a sweep: initial state, horizon, the scene's run options, the reference
/// final position and the coordinate the error is measured in.
pub(super) struct Problem<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    pub(super) t0: f64,
    pub(super) q0: OVector<f64, N>,
    pub(super) v0: OVector<f64, N>,
    pub(super) t_end: f64,
    pub(super) exact: OVector<f64, N>,
    /// The one coordinate of `--coordinate` (`None`: the Euclidean norm of all).
    pub(super) coordinate: Option<usize>,
    /// The scene's recovery policy and divergence limit (`[run]`), under which the library's
    /// methods run, as in `svi run` of the scene.
    pub(super) run: RunOptions,
}

impl<N: Dimension> Problem<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The initial time and state.
    pub(super) fn start(&self) -> (f64, Initial<N>) {
        (
            self.t0,
            Initial::Velocity {
                q: self.q0.clone(),
                v: self.v0.clone(),
            },
        )
    }

    /// The final error of a run that ends at `q`: in the chosen coordinate, or the Euclidean
    /// position error.
    pub(super) fn error(&self, q: &OVector<f64, N>) -> f64 {
        match self.coordinate {
            Some(i) => (q[i] - self.exact[i]).abs(),
            None => (q - &self.exact).norm(),
        }
    }
}

/// The method of the resolved reference run of a model without an exact solution: SVI with
/// 7 CGL and 6 Gauss points (order 12).
fn reference_method() -> svi::Svi {
    svi::Svi::new(7).with_quadrature(6)
}

/// The final position of a model without an exact solution, from the resolved reference run
/// ([`reference_method`] at the model's default step h and at h/2: the second is the
/// reference, their difference its error estimate, which must be below 10⁻¹¹ relative).
pub(super) fn resolved_reference<M: ZooModel<N>, N: Dimension>(
    model: &M,
    t0: f64,
    q0: &OVector<f64, N>,
    v0: &OVector<f64, N>,
    t_end: f64,
) -> Result<(OVector<f64, N>, f64), SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let integrator = Integrator::new(model.clone(), reference_method());
    let h = model.default_step();
    let run = |h: f64| {
        integrator
            .run_from_velocity(t0, q0.clone(), v0.clone(), h, t_end, &mut ())
            .map(|run| run.state.q)
            .map_err(|error| SceneError::NoReference {
                model: model.name().into(),
                reason: format!("its reference run (svi:7/6 at h = {h:e}) failed: {error}"),
            })
    };
    let (coarse, fine) = (run(h)?, run(0.5 * h)?);
    let discrepancy = (coarse - &fine).amax();
    if discrepancy > 1e-11 * fine.amax().max(1.0) {
        return Err(SceneError::NoReference {
            model: model.name().into(),
            reason: format!(
                "its reference runs (svi:7/6 at h = {h:e} and h/2) differ by {discrepancy:.1e}: \
                 the model's default step does not resolve it"
            ),
        });
    }
    Ok((fine, discrepancy))
}
