//! Named parameters and defaults of a model on a group (the analogue of [`crate::Defaults`]
//! on ℝᴺ and [`crate::lie_group::RigidBodyDefaults`] on SO(3)): what the command line and
//! scene files need to run a model by name.

use super::GroupLagrangian;
use crate::error::Error;
use nalgebra::SVector;

/// Named parameters and defaults of a model on a group.
pub trait GroupDefaults<const N: usize, const E: usize>: GroupLagrangian<N, E> {
    /// Short name (as used by the command line, e.g. `"falling-body"`).
    fn name(&self) -> &'static str;
    /// Current parameter values, by name.
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// Set one parameter; an unknown name or an out-of-range value is an
    /// [`Error::InvalidParameter`].
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error>;
    /// Default initial state (g₀, ξ₀) for the current parameters.
    fn initial_state(&self) -> (SVector<f64, E>, SVector<f64, N>);
    /// Default step size.
    fn default_step(&self) -> f64;
    /// Default final time (the start time is 0).
    fn default_horizon(&self) -> f64;
    /// The exact state (g, ξ) at time `t` of the motion from (g₀, ξ₀) at time 0, where it is
    /// known (default: `None`).
    fn exact_solution(
        &self,
        g0: &SVector<f64, E>,
        xi0: &SVector<f64, N>,
        t: f64,
    ) -> Option<(SVector<f64, E>, SVector<f64, N>)> {
        let _ = (g0, xi0, t);
        None
    }
}
