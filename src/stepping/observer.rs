//! Observers: opt-in diagnostics and output of a run.
//!
//! An observer sees the initial point (step 0) and the points after the steps it asks for
//! ([`Observer::wants`]). The stepping loop completes a [`PhasePoint`] (q, q̇ and p) only when
//! some observer wants the step, so a run with no observer (`&mut ()`) computes nothing
//! beyond the steps. Observers compose as tuples, switch on and off as `Option`, thin out with
//! [`Every`], and may stop a run by returning [`ControlFlow::Break`].
//!
//! Provided: [`Points`] and [`Trajectory`] (store points), [`EnergyError`] (max |E − E₀|), [`MomentumError`]
//! (max |J − J₀| over the Noether momenta), [`InvariantError`] (max over known invariants),
//! [`SolutionError`] (max position error against the exact solution).

use crate::dimension::Dimension;
use crate::method::space::PhasePoint;
use crate::model::derived::LagrangianExt;
use crate::model::{ExactSolution, Invariants, Lagrangian, Symmetries};
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::ops::ControlFlow;

/// Receives points of type `P` of a run of model `L`: [`PhasePoint`]s here,
/// [`RigidPoint`](crate::lie_group::RigidPoint)s on SO(3).
pub trait Observer<L: ?Sized, P> {
    /// Whether the point after step `step` (0 = initial point) is wanted.
    fn wants(&self, step: usize) -> bool {
        let _ = step;
        true
    }

    /// Receive the point after step `step`; `Break` stops the run.
    fn observe(&mut self, model: &L, step: usize, point: &P) -> ControlFlow<()>;
}

impl<L: ?Sized, P> Observer<L, P> for () {
    fn wants(&self, _step: usize) -> bool {
        false
    }
    fn observe(&mut self, _: &L, _: usize, _: &P) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
}

impl<L: ?Sized, P, O: Observer<L, P>> Observer<L, P> for Option<O> {
    fn wants(&self, step: usize) -> bool {
        self.as_ref().is_some_and(|o| o.wants(step))
    }
    fn observe(&mut self, model: &L, step: usize, point: &P) -> ControlFlow<()> {
        match self {
            Some(o) if o.wants(step) => o.observe(model, step, point),
            _ => ControlFlow::Continue(()),
        }
    }
}

impl<L: ?Sized, P, O: Observer<L, P> + ?Sized> Observer<L, P> for &mut O {
    fn wants(&self, step: usize) -> bool {
        (**self).wants(step)
    }
    fn observe(&mut self, model: &L, step: usize, point: &P) -> ControlFlow<()> {
        (**self).observe(model, step, point)
    }
}

macro_rules! tuple_observer {
    ($($name:ident),+) => {
        impl<L: ?Sized, P, $($name: Observer<L, P>),+> Observer<L, P> for ($($name,)+) {
            fn wants(&self, step: usize) -> bool {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                false $(|| $name.wants(step))+
            }
            fn observe(&mut self, model: &L, step: usize, point: &P) -> ControlFlow<()> {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                let mut flow = ControlFlow::Continue(());
                $(
                    if $name.wants(step) && $name.observe(model, step, point).is_break() {
                        flow = ControlFlow::Break(());
                    }
                )+
                flow
            }
        }
    };
}

tuple_observer!(A);
tuple_observer!(A, B);
tuple_observer!(A, B, C);
tuple_observer!(A, B, C, D);
tuple_observer!(A, B, C, D, E);
tuple_observer!(A, B, C, D, E, F);

/// Pass every `every`-th step (and the initial point) to the inner observer.
#[derive(Debug, Clone, PartialEq)]
pub struct Every<O> {
    /// Thinning factor (0 and 1 both mean every step).
    pub every: usize,
    /// The observer that receives the thinned points.
    pub inner: O,
}

impl<O> Every<O> {
    /// Thin `inner` to every `every`-th step.
    pub fn new(every: usize, inner: O) -> Self {
        Every { every, inner }
    }
}

impl<L: ?Sized, P, O: Observer<L, P>> Observer<L, P> for Every<O> {
    fn wants(&self, step: usize) -> bool {
        step.is_multiple_of(self.every.max(1)) && self.inner.wants(step)
    }
    fn observe(&mut self, model: &L, step: usize, point: &P) -> ControlFlow<()> {
        self.inner.observe(model, step, point)
    }
}

/// Stores the observed points, of any space (on ℝᴺ: [`Trajectory`]; on SO(3):
/// [`crate::lie_group::RigidTrajectory`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Points<P> {
    /// The points, in order.
    pub points: Vec<P>,
}

impl<P> Points<P> {
    /// An empty record.
    pub fn new() -> Self {
        Points { points: Vec::new() }
    }
}

impl<P> Default for Points<P> {
    fn default() -> Self {
        Points::new()
    }
}

impl<L: ?Sized, P: Clone> Observer<L, P> for Points<P> {
    fn observe(&mut self, _: &L, _: usize, point: &P) -> ControlFlow<()> {
        self.points.push(point.clone());
        ControlFlow::Continue(())
    }
}

/// Stores the observed phase points of a run on ℝᴺ.
pub type Trajectory<N> = Points<PhasePoint<N>>;

/// The larger of a running maximum and a new deviation, where NaN (an overflowed quantity)
/// wins: `f64::max` would drop it and report the maximum before the overflow.
pub(crate) fn worst(max: f64, deviation: f64) -> f64 {
    if deviation.is_nan() || deviation > max {
        deviation
    } else {
        max
    }
}

/// Largest deviation |E(t) − E(t₀)| of the energy E = p·q̇ − L over the observed points
/// (E = Π·Ω − L for rigid bodies, [`crate::lie_group`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EnergyError {
    /// Energy at the first observed point.
    pub initial: Option<f64>,
    /// Largest deviation seen.
    pub max: f64,
}

impl<L: Lagrangian<N>, N: Dimension> Observer<L, PhasePoint<N>> for EnergyError
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, model: &L, _: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        let energy = model.phase_energy(point.t, &point.q, &point.v, &point.p);
        let initial = *self.initial.get_or_insert(energy);
        self.max = worst(self.max, (energy - initial).abs());
        ControlFlow::Continue(())
    }
}

/// Largest deviation of the Noether momenta Jᵢ = p·ξᵢ(q) over the observed points (the
/// maximum over all generators).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MomentumError {
    /// Momenta at the first observed point.
    pub initial: Vec<f64>,
    /// Largest deviation seen.
    pub max: f64,
}

impl<L: Symmetries<N>, N: Dimension> Observer<L, PhasePoint<N>> for MomentumError
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, model: &L, _: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        let count = model.generator_count();
        let first = self.initial.is_empty();
        for i in 0..count {
            let momentum = model.generator_momentum(i, &point.q, &point.p);
            if first {
                self.initial.push(momentum);
            } else {
                self.max = worst(self.max, (momentum - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

/// Largest deviation of the model's known invariants over the observed points (for rigid
/// bodies: [`crate::lie_group::RigidBodyInvariants`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InvariantError {
    /// Invariants at the first observed point.
    pub initial: Vec<f64>,
    /// Largest deviation seen.
    pub max: f64,
}

impl InvariantError {
    /// Record the invariants' values at one point (the first point's are the references).
    pub(crate) fn record(&mut self, values: impl Iterator<Item = f64>) -> ControlFlow<()> {
        let first = self.initial.is_empty();
        for (i, value) in values.enumerate() {
            if first {
                self.initial.push(value);
            } else {
                self.max = worst(self.max, (value - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

impl<L: Invariants<N>, N: Dimension> Observer<L, PhasePoint<N>> for InvariantError
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, model: &L, _: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        self.record(
            (0..model.invariant_count()).map(|i| model.invariant(i, point.t, &point.q, &point.v)),
        )
    }
}

/// Largest Euclidean position error ‖q − q_exact‖ over the observed points, against the exact
/// solution through the first observed point. `max` stays `None` when the model has no
/// closed form for that initial state.
#[derive(Debug, Clone, PartialEq)]
pub struct SolutionError<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The first observed point.
    pub initial: Option<PhasePoint<N>>,
    /// Largest error seen, if the exact solution exists.
    pub max: Option<f64>,
    /// Error at the last observed point.
    pub last: Option<f64>,
}

impl<N: Dimension> Default for SolutionError<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Nothing observed yet.
    fn default() -> Self {
        SolutionError {
            initial: None,
            max: None,
            last: None,
        }
    }
}

impl<L: ExactSolution<N>, N: Dimension> Observer<L, PhasePoint<N>> for SolutionError<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, model: &L, _: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        let start = self.initial.get_or_insert_with(|| point.clone());
        if let Some((q, _)) = model.exact_solution(start.t, &start.q, &start.v, point.t) {
            let error = (&point.q - q).norm();
            self.max = Some(worst(self.max.unwrap_or(0.0), error));
            self.last = Some(error);
        }
        ControlFlow::Continue(())
    }
}
