//! The phase spaces a method advances on: ℝᴺ ([`Euclidean`]) and the rotation group
//! ([`SO3`]).
//!
//! A method advances a state in its own coordinates ([`Space::State`]: (q, p) or (q, q̇) on
//! ℝᴺ, (R, Π) on SO(3)); observers and results see completed points ([`Space::Point`]:
//! (t, q, q̇, p), (t, R, Ω, Π)). The stepping core needs only the operations of
//! [`StepState`] on states, so one loop ([`crate::stepping::run`]) serves every space.
//!
//! Increments, not new states, come back from a step: the core adds them with compensated
//! (Kahan) summation, so a run of 10⁶ steps keeps the accuracy of its steps (on SO(3) this is
//! what keeps R orthogonal to round-off without re-orthonormalisation).

use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::linalg::{compensated_add, compensated_sum_extent};
use crate::model::so3::{Matrix3, Vector3};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator, OMatrix, OVector, SMatrix, U1};
use std::fmt::Debug;

/// What the stepping core does with a state in a method's coordinates.
pub trait StepState: Clone + Debug + PartialEq {
    /// The zero state of the same shape as `self` (increments and compensations start
    /// here).
    fn zeros_like(&self) -> Self;
    /// `self = other`, reusing `self`'s storage (no allocation for runtime-sized states).
    fn assign(&mut self, other: &Self);
    /// `self + increment`, entry by entry, without compensation.
    fn plus(&self, increment: &Self) -> Self;
    /// `self += increment`, entry by entry, without compensation (no allocation).
    fn add(&mut self, increment: &Self);
    /// `self += increment` with the Kahan compensation carried in `compensation`.
    fn add_compensated(&mut self, compensation: &mut Self, increment: &Self);
    /// [`StepState::add_compensated`] if the sum is finite and, with a `limit`, no component
    /// exceeds it in absolute value; otherwise `self` and `compensation` are left as they
    /// were and the failure says why.
    fn add_checked(
        &mut self,
        compensation: &mut Self,
        increment: &Self,
        limit: Option<f64>,
    ) -> Result<(), StepFailure> {
        add_checked_on_copy(self, compensation, increment, limit)
    }
    /// Whether every component is finite.
    fn is_finite(&self) -> bool;
    /// The largest absolute component (for the divergence limit).
    fn max_abs(&self) -> f64;
    /// ‖self − other‖∞ over all components (for step-doubling error estimates).
    fn distance(&self, other: &Self) -> f64;
}

/// [`StepState::add_checked`] by checking a copy: the sum is formed in a copy of the state
/// and written back only if it passes (a fixed-size state's copy lives on the stack).
fn add_checked_on_copy<S: StepState>(
    state: &mut S,
    compensation: &mut S,
    increment: &S,
    limit: Option<f64>,
) -> Result<(), StepFailure> {
    let (mut next, mut carried) = (state.clone(), compensation.clone());
    next.add_compensated(&mut carried, increment);
    if !next.is_finite() {
        return Err(StepFailure::NonFinite);
    }
    if let Some(limit) = limit {
        let norm = next.max_abs();
        if norm > limit {
            return Err(StepFailure::Diverged { norm, limit });
        }
    }
    state.assign(&next);
    compensation.assign(&carried);
    Ok(())
}

/// A phase space: the types a method and the stepping core exchange on it. Implemented by
/// marker types ([`Euclidean`], [`SO3`]).
pub trait Space: Copy + Debug + PartialEq + Default + 'static {
    /// A state in a method's coordinates.
    type State: StepState;
    /// A state completed for observers and results, with its time.
    type Point: Clone + Debug + PartialEq;
    /// An initial condition.
    type Initial: Clone + Debug + PartialEq;
    /// A velocity, kept from one completed point to the next as the Newton start of the
    /// inverse Legendre map.
    type Velocity: Clone + Debug;
    /// The Jacobian of one step with respect to the state.
    type Tangent: Clone + Debug;
    /// Numbers per interpolation node of a step polynomial from `state` (N on ℝᴺ, 3 on
    /// SO(3)).
    fn node_width(state: &Self::State) -> usize;

    /// The time of a point.
    fn time(point: &Self::Point) -> f64;
    /// The velocity of a point.
    fn velocity(point: &Self::Point) -> Self::Velocity;
    /// Overwrite `velocity` with the point's velocity (no allocation on runtime-sized spaces).
    fn assign_velocity(velocity: &mut Self::Velocity, point: &Self::Point) {
        *velocity = Self::velocity(point);
    }
    /// The first Newton start of the inverse Legendre map for an initial condition.
    fn initial_guess(initial: &Self::Initial) -> Self::Velocity;
    /// The configuration and velocity of a point in words, for error messages.
    fn describe(point: &Self::Point) -> String;
    /// The size of a point's configuration and of its velocity (largest components), from
    /// which a first trial step is guessed.
    fn size_and_speed(point: &Self::Point) -> (f64, f64);

    /// The point's (q, q̇, p) as slices on a vector space; `None` on spaces whose points are
    /// not vectors (SO(3)). Dense output of a whole solve ([`crate::stepping::dense`]) needs them.
    fn point_vectors(point: &Self::Point) -> Option<(&[f64], &[f64], &[f64])> {
        let _ = point;
        None
    }
}

/// ℝᴺ: configurations q ∈ ℝᴺ, models [`crate::Lagrangian`]`<N>`, with N fixed (`Const<N>`)
/// or chosen at run time ([`crate::dimension::Dyn`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Euclidean<N>(std::marker::PhantomData<N>);

impl<N> Default for Euclidean<N> {
    fn default() -> Self {
        Euclidean(std::marker::PhantomData)
    }
}

impl<N: PartialEq> Eq for Euclidean<N> {}

impl<N: Dimension> Space for Euclidean<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type State = State<N>;
    type Point = PhasePoint<N>;
    type Initial = Initial<N>;
    type Velocity = OVector<f64, N>;
    type Tangent = TangentMap<N>;

    fn node_width(state: &State<N>) -> usize {
        state.q.len()
    }

    fn time(point: &PhasePoint<N>) -> f64 {
        point.t
    }

    fn velocity(point: &PhasePoint<N>) -> OVector<f64, N> {
        point.v.clone()
    }

    fn assign_velocity(velocity: &mut OVector<f64, N>, point: &PhasePoint<N>) {
        velocity.copy_from(&point.v);
    }

    fn initial_guess(initial: &Initial<N>) -> OVector<f64, N> {
        match initial {
            Initial::Velocity { v, .. } => v.clone(),
            Initial::Momentum { p, .. } => p.clone(),
        }
    }

    fn describe(point: &PhasePoint<N>) -> String {
        format!("q = {:?}, v = {:?}", point.q.as_slice(), point.v.as_slice())
    }

    fn point_vectors(point: &PhasePoint<N>) -> Option<(&[f64], &[f64], &[f64])> {
        Some((point.q.as_slice(), point.v.as_slice(), point.p.as_slice()))
    }

    fn size_and_speed(point: &PhasePoint<N>) -> (f64, f64) {
        (point.q.amax(), point.v.amax())
    }
}

/// The state a method on ℝᴺ advances: configuration `q` and `y`, which is the momentum p for
/// [`crate::Coordinates::Momentum`] methods and the velocity q̇ for
/// [`crate::Coordinates::Velocity`] ones.
#[derive(Debug, Clone, PartialEq)]
pub struct State<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Configuration q.
    pub q: OVector<f64, N>,
    /// Momentum p or velocity q̇, according to the method's [`crate::Coordinates`].
    pub y: OVector<f64, N>,
}

impl<N: Dimension> Copy for State<N>
where
    DefaultAllocator: Allocator<N>,
    OVector<f64, N>: Copy,
{
}

impl<N: Dimension> State<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The zero state of dimension `n` (used for increments).
    pub fn zeros(n: N) -> Self {
        State {
            q: OVector::zeros_generic(n, U1),
            y: OVector::zeros_generic(n, U1),
        }
    }

    /// The dimension of the state.
    pub fn dimension(&self) -> N {
        self.q.shape_generic().0
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.q.iter().chain(self.y.iter()).all(|x| x.is_finite())
    }
}

impl<N: Dimension> StepState for State<N>
where
    DefaultAllocator: Allocator<N>,
{
    fn zeros_like(&self) -> Self {
        State::zeros(self.dimension())
    }

    fn assign(&mut self, other: &Self) {
        self.q.copy_from(&other.q);
        self.y.copy_from(&other.y);
    }

    fn plus(&self, increment: &Self) -> Self {
        State {
            q: &self.q + &increment.q,
            y: &self.y + &increment.y,
        }
    }

    fn add(&mut self, increment: &Self) {
        self.q += &increment.q;
        self.y += &increment.y;
    }

    fn add_compensated(&mut self, compensation: &mut Self, increment: &Self) {
        compensated_add(
            self.q.as_mut_slice(),
            compensation.q.as_mut_slice(),
            increment.q.as_slice(),
        );
        compensated_add(
            self.y.as_mut_slice(),
            compensation.y.as_mut_slice(),
            increment.y.as_slice(),
        );
    }

    /// At run-time size one read-only pass computes the sums exactly as the compensated
    /// addition will (t = s + (δ − c)) and checks them; only then are they written: no copy
    /// of the state. A fixed size checks a copy on the stack, as every state.
    fn add_checked(
        &mut self,
        compensation: &mut Self,
        increment: &Self,
        limit: Option<f64>,
    ) -> Result<(), StepFailure> {
        if N::try_to_usize().is_some() {
            return add_checked_on_copy(self, compensation, increment, limit);
        }
        add_checked_in_place(
            [self.q.as_mut_slice(), self.y.as_mut_slice()],
            [compensation.q.as_mut_slice(), compensation.y.as_mut_slice()],
            [increment.q.as_slice(), increment.y.as_slice()],
            limit,
        )
    }

    fn is_finite(&self) -> bool {
        State::is_finite(self)
    }

    fn max_abs(&self) -> f64 {
        self.q.amax().max(self.y.amax())
    }

    fn distance(&self, other: &Self) -> f64 {
        let apart = |a: &OVector<f64, N>, b: &OVector<f64, N>| {
            a.iter()
                .zip(b.iter())
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        apart(&self.q, &other.q).max(apart(&self.y, &other.y))
    }
}

/// A complete phase-space point on ℝᴺ: time, configuration, velocity and momentum.
#[derive(Debug, Clone, PartialEq)]
pub struct PhasePoint<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Time t.
    pub t: f64,
    /// Configuration q.
    pub q: OVector<f64, N>,
    /// Velocity q̇.
    pub v: OVector<f64, N>,
    /// Momentum p = ∂L/∂q̇.
    pub p: OVector<f64, N>,
}

/// An initial state on ℝᴺ: configuration with either velocity or momentum.
#[derive(Debug, Clone, PartialEq)]
pub enum Initial<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// (q0, q̇0).
    Velocity {
        /// Configuration.
        q: OVector<f64, N>,
        /// Velocity.
        v: OVector<f64, N>,
    },
    /// (q0, p0).
    Momentum {
        /// Configuration.
        q: OVector<f64, N>,
        /// Momentum.
        p: OVector<f64, N>,
    },
}

/// The Jacobian Φ of one step (q, y) ↦ (q', y') on ℝᴺ, in blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct TangentMap<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// ∂q'/∂q.
    pub qq: OMatrix<f64, N, N>,
    /// ∂q'/∂y.
    pub qy: OMatrix<f64, N, N>,
    /// ∂y'/∂q.
    pub yq: OMatrix<f64, N, N>,
    /// ∂y'/∂y.
    pub yy: OMatrix<f64, N, N>,
}

impl<N: Dimension> Copy for PhasePoint<N>
where
    DefaultAllocator: Allocator<N>,
    OVector<f64, N>: Copy,
{
}

impl<N: Dimension> Copy for Initial<N>
where
    DefaultAllocator: Allocator<N>,
    OVector<f64, N>: Copy,
{
}

impl<N: Dimension> Copy for TangentMap<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
    OMatrix<f64, N, N>: Copy,
{
}

impl<N: Dimension> PhasePoint<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The point of dimension `n` at t = 0 with every coordinate zero (a buffer).
    pub fn zeros(n: N) -> Self {
        PhasePoint {
            t: 0.0,
            q: OVector::zeros_generic(n, U1),
            v: OVector::zeros_generic(n, U1),
            p: OVector::zeros_generic(n, U1),
        }
    }
}

impl<N: Dimension> Initial<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The configuration q0.
    pub fn position(&self) -> &OVector<f64, N> {
        match self {
            Initial::Velocity { q, .. } | Initial::Momentum { q, .. } => q,
        }
    }
}

impl<N: Dimension> TangentMap<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The identity map of dimension `n`.
    pub fn identity(n: N) -> Self {
        TangentMap {
            qq: OMatrix::identity_generic(n, n),
            qy: OMatrix::zeros_generic(n, n),
            yq: OMatrix::zeros_generic(n, n),
            yy: OMatrix::identity_generic(n, n),
        }
    }

    /// The dimension N (the map is 2N × 2N).
    pub fn dimension(&self) -> usize {
        self.qq.nrows()
    }

    /// The full 2N×2N matrix [[qq, qy], [yq, yy]].
    pub fn matrix(&self) -> DMatrix<f64> {
        let n = self.dimension();
        DMatrix::from_fn(2 * n, 2 * n, |i, j| {
            let block = match (i < n, j < n) {
                (true, true) => &self.qq,
                (true, false) => &self.qy,
                (false, true) => &self.yq,
                (false, false) => &self.yy,
            };
            block[(i % n, j % n)]
        })
    }

    /// The Jacobian of this step followed by `next` (the block product next · self).
    pub fn then(&self, next: &TangentMap<N>) -> TangentMap<N> {
        TangentMap {
            qq: &next.qq * &self.qq + &next.qy * &self.yq,
            qy: &next.qq * &self.qy + &next.qy * &self.yy,
            yq: &next.yq * &self.qq + &next.yy * &self.yq,
            yy: &next.yq * &self.qy + &next.yy * &self.yy,
        }
    }

    /// ‖ΦᵀJΦ − J‖_max with J = [[0, I], [−I, 0]]: zero for a symplectic map in (q, p).
    pub fn symplecticity_error(&self) -> f64 {
        let phi = self.matrix();
        let n = self.dimension();
        let mut j = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            j[(i, n + i)] = 1.0;
            j[(n + i, i)] = -1.0;
        }
        (phi.transpose() * &j * &phi - j).amax()
    }
}

/// The rotation group SO(3): attitudes R of a rigid body, models
/// [`crate::lie_group::RigidBodyLagrangian`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SO3;

impl Space for SO3 {
    type State = RigidState;
    type Point = RigidPoint;
    type Initial = RigidInitial;
    type Velocity = Vector3<f64>;
    /// The 6×6 Jacobian in the canonical coordinates (η, p) of T*SO(3) about the step's
    /// input and output (see [`crate::lie_group::LieSvi`]).
    type Tangent = SMatrix<f64, 6, 6>;

    fn node_width(_state: &RigidState) -> usize {
        3
    }

    fn time(point: &RigidPoint) -> f64 {
        point.t
    }

    fn velocity(point: &RigidPoint) -> Vector3<f64> {
        point.omega
    }

    fn initial_guess(initial: &RigidInitial) -> Vector3<f64> {
        match initial {
            RigidInitial::Velocity { omega, .. } => *omega,
            RigidInitial::Momentum { .. } => Vector3::zeros(),
        }
    }

    /// An attitude's size is one radian.
    fn size_and_speed(point: &RigidPoint) -> (f64, f64) {
        (1.0, point.omega.amax())
    }

    fn describe(point: &RigidPoint) -> String {
        format!(
            "quaternion = {:?}, Ω = {:?}",
            point.quaternion(),
            point.omega.as_slice()
        )
    }
}

/// The state of a rigid body in the integrator's coordinates: the attitude R (body to
/// space) and the body angular momentum μ = Π (left-trivialised momentum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidState {
    /// Attitude R ∈ SO(3).
    pub r: Matrix3<f64>,
    /// Body angular momentum Π.
    pub momentum: Vector3<f64>,
}

impl RigidState {
    /// The zero state (used for increments).
    pub fn zeros() -> Self {
        RigidState {
            r: Matrix3::zeros(),
            momentum: Vector3::zeros(),
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.r
            .iter()
            .chain(self.momentum.iter())
            .all(|x| x.is_finite())
    }
}

impl StepState for RigidState {
    fn zeros_like(&self) -> Self {
        RigidState::zeros()
    }

    fn assign(&mut self, other: &Self) {
        *self = *other;
    }

    fn plus(&self, increment: &Self) -> Self {
        RigidState {
            r: self.r + increment.r,
            momentum: self.momentum + increment.momentum,
        }
    }

    fn add(&mut self, increment: &Self) {
        self.r += increment.r;
        self.momentum += increment.momentum;
    }

    fn add_compensated(&mut self, compensation: &mut Self, increment: &Self) {
        compensated_add(
            self.r.as_mut_slice(),
            compensation.r.as_mut_slice(),
            increment.r.as_slice(),
        );
        compensated_add(
            self.momentum.as_mut_slice(),
            compensation.momentum.as_mut_slice(),
            increment.momentum.as_slice(),
        );
    }

    fn is_finite(&self) -> bool {
        RigidState::is_finite(self)
    }

    fn max_abs(&self) -> f64 {
        self.r.amax().max(self.momentum.amax())
    }

    fn distance(&self, other: &Self) -> f64 {
        (self.r - other.r)
            .amax()
            .max((self.momentum - other.momentum).amax())
    }
}

/// A complete rigid-body point: time, attitude, body angular velocity and momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidPoint {
    /// Time t.
    pub t: f64,
    /// Attitude R (body to space).
    pub r: Matrix3<f64>,
    /// Body angular velocity Ω.
    pub omega: Vector3<f64>,
    /// Body angular momentum Π = ∂L/∂Ω.
    pub momentum: Vector3<f64>,
}

impl RigidPoint {
    /// The spatial angular momentum π = R Π.
    pub fn spatial_momentum(&self) -> Vector3<f64> {
        self.r * self.momentum
    }

    /// The attitude as a unit quaternion (w, x, y, z) with w ≥ 0 (Shepperd's method).
    pub fn quaternion(&self) -> [f64; 4] {
        crate::model::so3::quaternion(&self.r)
    }
}

/// An initial rigid-body state: attitude with either angular velocity or momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigidInitial {
    /// (R₀, Ω₀).
    Velocity {
        /// Attitude.
        r: Matrix3<f64>,
        /// Body angular velocity.
        omega: Vector3<f64>,
    },
    /// (R₀, Π₀).
    Momentum {
        /// Attitude.
        r: Matrix3<f64>,
        /// Body angular momentum.
        momentum: Vector3<f64>,
    },
}

/// The checked compensated sum of a run-time-size state ([`StepState::add_checked`]): one
/// read-only pass computes the sums exactly as the compensated addition will (t = s + (δ − c))
/// and checks them; only then are they written: no copy of the state.
fn add_checked_in_place(
    sums: [&mut [f64]; 2],
    compensations: [&mut [f64]; 2],
    increments: [&[f64]; 2],
    limit: Option<f64>,
) -> Result<(), StepFailure> {
    let mut norm: f64 = 0.0;
    for ((sum, compensation), increment) in sums.iter().zip(&compensations).zip(&increments) {
        // A NaN sum is caught by `finite`.
        let (extent, finite) = compensated_sum_extent(sum, compensation, increment);
        if !finite {
            return Err(StepFailure::NonFinite);
        }
        norm = norm.max(extent);
    }
    if let Some(limit) = limit
        && norm > limit
    {
        return Err(StepFailure::Diverged { norm, limit });
    }
    for ((sum, compensation), increment) in sums.into_iter().zip(compensations).zip(increments) {
        compensated_add(sum, compensation, increment);
    }
    Ok(())
}
