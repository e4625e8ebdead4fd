//! Observers of runs on a Lie group ([`GroupPoint`]s): the energy μ·ξ − L
//! ([`EnergyError`]), the distance of the configuration from the group ([`DefectError`],
//! ‖RᵀR − I‖ of each rotation factor) and the spatial momentum Ad_{g⁻¹}ᵀμ, the Noether
//! momentum of the left action ([`SpatialMomentumError`], per component), and the Noether
//! momenta of the model's declared symmetry generators ([`MomentumError`],
//! [`GroupSymmetries`]), and the distance from the exact solution where the model knows it
//! ([`GroupSolutionError`]).

use crate::method::group_space::GroupPoint;
use crate::model::group::{
    GroupDefaults, GroupLagrangian, GroupLagrangianExt, GroupSymmetries, LieGroup,
};
use crate::stepping::observer::{EnergyError, MomentumError, Observer, worst};
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

/// The Noether momenta ⟨Ad_{g⁻¹}ᵀμ, ζᵢ⟩ of the model's symmetry generators
/// ([`GroupSymmetries::noether_momentum`]).
impl<L: GroupSymmetries<N, E>, const N: usize, const E: usize> Observer<L, GroupPoint<N, E>>
    for MomentumError
{
    fn observe(&mut self, model: &L, _: usize, point: &GroupPoint<N, E>) -> ControlFlow<()> {
        let first = self.initial.is_empty();
        for i in 0..model.generator_count() {
            let momentum = model.noether_momentum(i, &point.g, &point.momentum);
            if first {
                self.initial.push(momentum);
            } else {
                self.max = worst(self.max, (momentum - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

/// Largest distance ‖g − g_exact(t)‖ (Euclidean, over the stored entries) of the observed
/// configurations from the exact motion from the first observed point
/// ([`GroupDefaults::exact_solution`], for an autonomous model: the motion from (g₀, ξ₀) at
/// t₀ is that from time 0 shifted by t₀). `max` stays `None` where the model has no exact
/// solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupSolutionError<const N: usize, const E: usize> {
    /// The first observed point (t₀, g₀, ξ₀).
    pub start: Option<(f64, SVector<f64, E>, SVector<f64, N>)>,
    /// Largest distance seen.
    pub max: Option<f64>,
}

impl<const N: usize, const E: usize> Default for GroupSolutionError<N, E> {
    fn default() -> Self {
        GroupSolutionError {
            start: None,
            max: None,
        }
    }
}

impl<L: GroupDefaults<N, E>, const N: usize, const E: usize> Observer<L, GroupPoint<N, E>>
    for GroupSolutionError<N, E>
{
    fn observe(&mut self, model: &L, _: usize, point: &GroupPoint<N, E>) -> ControlFlow<()> {
        let (t0, g0, xi0) = *self.start.get_or_insert((point.t, point.g, point.xi));
        if let Some((g, _)) = model.exact_solution(&g0, &xi0, point.t - t0) {
            let distance = (point.g - g).norm();
            self.max = Some(self.max.map_or(distance, |max| worst(max, distance)));
        }
        ControlFlow::Continue(())
    }
}
