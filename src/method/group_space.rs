//! The phase space T*G of a Lie group G ([`GroupSpace`]): states (g, μ) with g ∈ G stored as
//! its entries and μ the left-trivialised (body) momentum, points (t, g, ξ, μ) with the body
//! velocity ξ. Increments g_k (exp ξ − e) and μ_{k+1} − μ_k come back from a step and the
//! stepping core adds them with compensated summation, entry by entry, which keeps g in the
//! group to round-off without projection (as on SO(3), [`crate::method::space::SO3`]).

use crate::linalg::compensated_add;
use crate::method::space::{Space, StepState};
use crate::model::group::LieGroup;
use nalgebra::{DMatrix, SVector};
use std::fmt::Debug;
use std::marker::PhantomData;

/// T*G for a Lie group `G` of dimension `N` stored as `E` numbers: the space of models
/// [`crate::model::group::GroupLagrangian`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GroupSpace<G, const N: usize, const E: usize>(PhantomData<G>);

impl<G: LieGroup<N, E>, const N: usize, const E: usize> Space for GroupSpace<G, N, E> {
    type State = GroupState<N, E>;
    type Point = GroupPoint<N, E>;
    type Initial = GroupInitial<N, E>;
    type Velocity = SVector<f64, N>;
    /// The 2N × 2N Jacobian of a step (not yet computed on general groups).
    type Tangent = DMatrix<f64>;

    fn node_width(_state: &GroupState<N, E>) -> usize {
        N
    }

    fn time(point: &GroupPoint<N, E>) -> f64 {
        point.t
    }

    fn velocity(point: &GroupPoint<N, E>) -> SVector<f64, N> {
        point.xi
    }

    fn initial_guess(initial: &GroupInitial<N, E>) -> SVector<f64, N> {
        match initial {
            GroupInitial::Velocity { xi, .. } => *xi,
            GroupInitial::Momentum { .. } => SVector::zeros(),
        }
    }

    fn describe(point: &GroupPoint<N, E>) -> String {
        format!(
            "g = {:?}, ξ = {:?}",
            point.g.as_slice(),
            point.xi.as_slice()
        )
    }

    fn size_and_speed(point: &GroupPoint<N, E>) -> (f64, f64) {
        (1.0_f64.max(point.g.amax()), point.xi.amax())
    }
}

/// The state on T*G in the integrator's coordinates: the configuration g and the body
/// momentum μ = ∂L/∂ξ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupState<const N: usize, const E: usize> {
    /// Configuration g ∈ G (its stored entries).
    pub g: SVector<f64, E>,
    /// Body momentum μ.
    pub momentum: SVector<f64, N>,
}

impl<const N: usize, const E: usize> GroupState<N, E> {
    /// The zero state (used for increments).
    pub fn zeros() -> Self {
        GroupState {
            g: SVector::zeros(),
            momentum: SVector::zeros(),
        }
    }
}

impl<const N: usize, const E: usize> StepState for GroupState<N, E> {
    fn zeros_like(&self) -> Self {
        GroupState::zeros()
    }

    fn assign(&mut self, other: &Self) {
        *self = *other;
    }

    fn plus(&self, increment: &Self) -> Self {
        GroupState {
            g: self.g + increment.g,
            momentum: self.momentum + increment.momentum,
        }
    }

    fn add(&mut self, increment: &Self) {
        self.g += increment.g;
        self.momentum += increment.momentum;
    }

    fn add_compensated(&mut self, compensation: &mut Self, increment: &Self) {
        compensated_add(
            self.g.as_mut_slice(),
            compensation.g.as_mut_slice(),
            increment.g.as_slice(),
        );
        compensated_add(
            self.momentum.as_mut_slice(),
            compensation.momentum.as_mut_slice(),
            increment.momentum.as_slice(),
        );
    }

    fn is_finite(&self) -> bool {
        self.g
            .iter()
            .chain(self.momentum.iter())
            .all(|x| x.is_finite())
    }

    fn max_abs(&self) -> f64 {
        self.g.amax().max(self.momentum.amax())
    }

    fn distance(&self, other: &Self) -> f64 {
        (self.g - other.g)
            .amax()
            .max((self.momentum - other.momentum).amax())
    }
}

/// A complete point of T*G: time, configuration, body velocity and body momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupPoint<const N: usize, const E: usize> {
    /// Time t.
    pub t: f64,
    /// Configuration g.
    pub g: SVector<f64, E>,
    /// Body velocity ξ = (g⁻¹ġ)^∨.
    pub xi: SVector<f64, N>,
    /// Body momentum μ = ∂L/∂ξ.
    pub momentum: SVector<f64, N>,
}

impl<const N: usize, const E: usize> GroupPoint<N, E> {
    /// The spatial momentum Ad*_{g⁻¹} μ = Ad_{g⁻¹}ᵀ μ: the Noether momentum of the left action
    /// (constant when L(hg, ξ) = L(g, ξ) for all h), whose pairing with a spatial generator ζ
    /// is the momentum conjugate to the symmetry exp(sζ) g.
    pub fn spatial_momentum<G: LieGroup<N, E>>(&self) -> SVector<f64, N> {
        G::adjoint(&G::inverse(&self.g)).transpose() * self.momentum
    }
}

/// An initial condition on T*G: configuration with either body velocity or body momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GroupInitial<const N: usize, const E: usize> {
    /// (g₀, ξ₀).
    Velocity {
        /// Configuration.
        g: SVector<f64, E>,
        /// Body velocity.
        xi: SVector<f64, N>,
    },
    /// (g₀, μ₀).
    Momentum {
        /// Configuration.
        g: SVector<f64, E>,
        /// Body momentum.
        momentum: SVector<f64, N>,
    },
}
