//! The observers of [`crate::stepping::observer`] on runtime-sized ℝⁿ
//! ([`crate::method::DynEuclidean`], models [`LocalLagrangian`]): energy and known
//! invariants, each O(n) per observed point.

use crate::method::space::DynPoint;
use crate::model::local::{LocalInvariants, LocalLagrangian};
use crate::stepping::observer::{EnergyError, InvariantError, Observer, worst};
use std::ops::ControlFlow;

impl<L: LocalLagrangian> Observer<L, DynPoint> for EnergyError {
    fn observe(&mut self, model: &L, _: usize, point: &DynPoint) -> ControlFlow<()> {
        let energy = point.p.dot(&point.v) - model.value(point.t, &point.q, &point.v);
        let initial = *self.initial.get_or_insert(energy);
        self.max = worst(self.max, (energy - initial).abs());
        ControlFlow::Continue(())
    }
}

impl<L: LocalInvariants> Observer<L, DynPoint> for InvariantError {
    fn observe(&mut self, model: &L, _: usize, point: &DynPoint) -> ControlFlow<()> {
        self.record(
            (0..model.invariant_count()).map(|i| model.invariant(i, point.t, &point.q, &point.v)),
        )
    }
}
