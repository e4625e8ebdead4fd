//! Observers of runs on a Lie group ([`GroupPoint`]s): the energy μ·ξ − L
//! ([`EnergyError`]), the distance of the configuration from the group ([`DefectError`],
//! ‖RᵀR − I‖ of each rotation factor) and the spatial momentum Ad_{g⁻¹}ᵀμ, the Noether
//! momentum of the left action ([`SpatialMomentumError`], per component).

use crate::method::group_space::GroupPoint;
use crate::model::group::{GroupLagrangian, GroupLagrangianExt, LieGroup};
use crate::stepping::observer::{EnergyError, Observer, worst};
use nalgebra::SVector;
use std::ops::ControlFlow;

impl<L: GroupLagrangian<N, E>, const N: usize, const E: usize> Observer<L, GroupPoint<N, E>>
    for EnergyError
{
    fn observe(&mut self, model: &L, _: usize, point: &GroupPoint<N, E>) -> ControlFlow<()> {
        let energy = point.momentum.dot(&point.xi) - model.value(&point.g, &point.xi);
        let initial = *self.initial.get_or_insert(energy);
        self.max = worst(self.max, (energy - initial).abs());
        ControlFlow::Continue(())
    }
}

/// Largest [`LieGroup::defect`] of the configuration over the observed points.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DefectError {
    /// Largest value seen.
    pub max: f64,
}

impl<L: GroupLagrangian<N, E>, const N: usize, const E: usize> Observer<L, GroupPoint<N, E>>
    for DefectError
{
    fn observe(&mut self, _: &L, _: usize, point: &GroupPoint<N, E>) -> ControlFlow<()> {
        self.max = worst(self.max, L::Group::defect(&point.g));
        ControlFlow::Continue(())
    }
}

/// Largest change of each component of the spatial momentum Ad_{g⁻¹}ᵀμ over the observed
/// points. A component along a symmetry of L (a spatial generator ζ with L(exp(sζ)g, ξ) =
/// L(g, ξ)) is conserved by the continuous flow and by Lie-SVI (discrete Noether theorem).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpatialMomentumError<const N: usize> {
    /// The spatial momentum at the first observed point.
    pub initial: Option<SVector<f64, N>>,
    /// Largest change of each component.
    pub max: SVector<f64, N>,
}

impl<const N: usize> Default for SpatialMomentumError<N> {
    fn default() -> Self {
        SpatialMomentumError {
            initial: None,
            max: SVector::zeros(),
        }
    }
}

impl<L: GroupLagrangian<N, E>, const N: usize, const E: usize> Observer<L, GroupPoint<N, E>>
    for SpatialMomentumError<N>
{
    fn observe(&mut self, _: &L, _: usize, point: &GroupPoint<N, E>) -> ControlFlow<()> {
        let momentum = point.spatial_momentum::<L::Group>();
        let initial = *self.initial.get_or_insert(momentum);
        for (max, (now, first)) in self.max.iter_mut().zip(momentum.iter().zip(&initial)) {
            *max = worst(*max, (now - first).abs());
        }
        ControlFlow::Continue(())
    }
}
