//! Observers of rigid-body runs: the analogue of [`crate::stepping::observer`] on SO(3).
//!
//! They are [`Observer`]s of [`RigidPoint`]s: they see the initial point (step 0) and the
//! points after the steps they ask for, compose as tuples, switch on and off as `Option`, thin
//! out with [`crate::stepping::observer::Every`], and may stop a run with [`ControlFlow::Break`]. A run
//! with no observer (`&mut ()`) completes no points.
//!
//! Provided: [`crate::lie_group::RigidTrajectory`] (the points),
//! [`EnergyError`] and [`InvariantError`] (body Casimirs and other invariants), the observers
//! of [`crate::stepping::observer`] here implemented for rigid bodies, [`AngularMomentumError`] (the
//! spatial angular momenta about the model's symmetry axes) and
//! [`OrthogonalityError`] (‖RᵀR − I‖).

use crate::method::space::RigidPoint;
use crate::model::rigid_body::{
    RigidBodyExt, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries,
};
use crate::model::so3::orthogonality_error;
use crate::stepping::observer::{EnergyError, InvariantError, Observer, worst};
use std::ops::ControlFlow;

impl<L: RigidBodyLagrangian> Observer<L, RigidPoint> for EnergyError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        let energy = point.momentum.dot(&point.omega) - model.value(&point.r, &point.omega);
        let initial = *self.initial.get_or_insert(energy);
        self.max = worst(self.max, (energy - initial).abs());
        ControlFlow::Continue(())
    }
}

/// Largest deviation of the spatial angular momenta a·(RΠ) about the model's symmetry axes
/// (maximum over the axes) over the observed points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AngularMomentumError {
    /// Momenta at the first observed point, one per axis.
    pub initial: Vec<f64>,
    /// ‖Π‖ at the first observed point (the scale for [`AngularMomentumError::relative`]).
    pub scale: f64,
    /// Largest deviation seen.
    pub max: f64,
}

impl AngularMomentumError {
    /// `max` relative to the size ‖π₀‖ = ‖Π₀‖ of the initial angular momentum (or `max`
    /// itself when that is zero).
    pub fn relative(&self) -> f64 {
        if self.scale > 0.0 {
            self.max / self.scale
        } else {
            self.max
        }
    }
}

impl<L: RigidBodySymmetries> Observer<L, RigidPoint> for AngularMomentumError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        let first = self.initial.is_empty();
        let spatial = point.spatial_momentum();
        if first {
            self.scale = point.momentum.norm();
        }
        for i in 0..model.axis_count() {
            let momentum = model.axis(i).dot(&spatial);
            if first {
                self.initial.push(momentum);
            } else {
                self.max = worst(self.max, (momentum - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

/// The model's known invariants (body Casimirs).
impl<L: RigidBodyInvariants> Observer<L, RigidPoint> for InvariantError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        self.record(
            (0..model.invariant_count())
                .map(|i| model.invariant(i, &point.r, &point.omega, &point.momentum)),
        )
    }
}

/// Largest ‖RᵀR − I‖ (Frobenius norm) over the observed points.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OrthogonalityError {
    /// Largest value seen.
    pub max: f64,
    /// Value at the last observed point.
    pub last: f64,
}

impl<L: ?Sized> Observer<L, RigidPoint> for OrthogonalityError {
    fn observe(&mut self, _: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        self.last = orthogonality_error(&point.r);
        self.max = worst(self.max, self.last);
        ControlFlow::Continue(())
    }
}
