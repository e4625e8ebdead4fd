//! [`Step`]: the one contract between a method and the stepping loop, on any [`Space`].
//!
//! The stepping loop ([`crate::stepping::run`]) is generic over the space: it validates the
//! run, keeps the time grid, adds increments with compensated summation, retries failed steps,
//! drives observers and attaches context to failures. What depends on the space and the model
//! comes from here: building the method's state from an initial condition, completing a state
//! to a point for observers (the inverse Legendre map), checking what the model declares about
//! itself, and dense output inside a step.
//!
//! Methods on ℝᴺ implement the simpler [`Method`] and get [`Step`] on [`Euclidean`] from the
//! blanket implementation below; the Lie-group integrator implements [`Step`] on
//! [`crate::method::SO3`] itself ([`crate::lie_group::LieSvi`]).

use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure, require_finite_entries};
use crate::linalg::solve_small;
use crate::method::space::{Euclidean, Initial, PhasePoint, Space, State, TangentMap};
use crate::method::{Coordinates, Equations, Method, MethodInfo, StepReport};
use crate::model::derived::LagrangianExt;
use crate::model::hamiltonian::HamiltonianForm;
use crate::model::{Lagrangian, Structure, TermDerivatives};
use crate::spectral::MAX_POINTS;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};

/// The cubic Hermite basis on a step [t_a, t_b] of length h at s = (time − t_a)/h: the
/// interpolant of (q_a, q̇_a, q_b, q̇_b) is q = w₀q_a + h w₁q̇_a + w₂q_b + h w₃q̇_b, its
/// derivative q̇ = (d₀q_a + d₂q_b)/h + d₁q̇_a + d₃q̇_b (the `interpolate` of the spaces on ℝᴺ
/// and ℝⁿ).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Hermite {
    /// The step length h.
    pub(crate) h: f64,
    /// w₀ … w₃.
    pub(crate) value: [f64; 4],
    /// d₀ … d₃ (the derivatives of the w in s).
    pub(crate) rate: [f64; 4],
}

impl Hermite {
    /// The basis at `time` in [t_a, t_b].
    pub(crate) fn new(t_a: f64, t_b: f64, time: f64) -> Self {
        let h = t_b - t_a;
        let s = (time - t_a) / h;
        let (s2, s3) = (s * s, s * s * s);
        Hermite {
            h,
            value: [
                2.0 * s3 - 3.0 * s2 + 1.0,
                s3 - 2.0 * s2 + s,
                -2.0 * s3 + 3.0 * s2,
                s3 - s2,
            ],
            rate: [
                6.0 * s2 - 6.0 * s,
                3.0 * s2 - 4.0 * s + 1.0,
                -6.0 * s2 + 6.0 * s,
                3.0 * s2 - 2.0 * s,
            ],
        }
    }
}

/// One step of a method on models `L` in the space `S`, and what the stepping loop needs to
/// know about states of `S` under `L`.
pub trait Step<L: ?Sized, S: Space> {
    /// Buffers and precomputed tables of one run.
    type Workspace;

    /// `true` promises that [`Step::points`] is always `None`: degree adaptivity is then
    /// not compiled for the method. The default (`false`) is always correct.
    const WITHOUT_POINTS: bool = false;

    /// Name, order and geometric properties.
    fn info(&self) -> MethodInfo;

    /// Validate the options against the model and build every buffer and table for steps of
    /// size `h`.
    fn workspace(&self, model: &L, h: f64) -> Result<Self::Workspace, Error>;

    /// Advance `state` from `t` to `t + h`, writing the increment into `increment` (the
    /// stepping loop adds it with compensated summation). Allocates nothing.
    fn step(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &S::State,
        increment: &mut S::State,
    ) -> Result<StepReport, StepFailure>;

    /// Drop warm-start data: the next step does not continue the last one.
    fn restart(&self, workspace: &mut Self::Workspace) {
        let _ = workspace;
    }

    /// Perform the step like [`Step::step`] and return the increment, the step's exact
    /// Jacobian with respect to `state` and the work of the step's solve (as
    /// [`Method::tangent_map`]).
    fn tangent_map(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &S::State,
    ) -> Result<(S::State, S::Tangent, StepReport), StepFailure>;

    /// The method's state for an initial condition at `t0`, after checking the condition
    /// (finite values; on SO(3) an orthogonal attitude).
    fn initial_state(&self, model: &L, t0: f64, initial: &S::Initial) -> Result<S::State, Error>;

    /// Check, at the initial state of an integrator's first run, what the model declares
    /// about itself (a constant mass matrix, G-invariance), so a wrong declaration is an
    /// error and not a wrong result.
    fn check_model(&self, model: &L, t0: f64, state: &S::State) -> Result<(), Error> {
        let _ = (model, t0, state);
        Ok(())
    }

    /// Complete a state to a point (the inverse Legendre map started at `guess`, or the
    /// Legendre map, by the method's coordinates). With the `workspace` of the run that
    /// reached the state, a method may complete it from what its steps already hold (a
    /// constant mass matrix's cached inverse) instead of solving for it.
    fn complete(
        &self,
        model: &L,
        workspace: Option<&Self::Workspace>,
        t: f64,
        state: &S::State,
        guess: &S::Velocity,
    ) -> Result<S::Point, Error>;

    /// [`Step::complete`] into `point`, a point of an earlier completion of the same run
    /// (the default overwrites it; runtime-sized spaces reuse its vectors, so observing
    /// every step allocates nothing).
    fn complete_into(
        &self,
        model: &L,
        workspace: Option<&Self::Workspace>,
        t: f64,
        state: &S::State,
        guess: &S::Velocity,
        point: &mut S::Point,
    ) -> Result<(), Error> {
        *point = self.complete(model, workspace, t, state, guess)?;
        Ok(())
    }

    /// The point of a state whose completion failed, with `guess` (the last velocity
    /// completed) standing in for the velocity: the last good state of a failure report.
    fn incomplete(&self, t: f64, state: &S::State, guess: &S::Velocity) -> S::Point;

    /// Whether every number of a completed point is finite.
    fn point_is_finite(&self, point: &S::Point) -> bool;

    /// Dense output of the last step taken (from `start` at `t` with size `h`): the point at
    /// `time` ∈ [t, t + h] from the step's interpolating polynomial; `None` for methods
    /// without a step polynomial.
    fn dense_point(
        &self,
        model: &L,
        workspace: &Self::Workspace,
        t: f64,
        h: f64,
        start: &S::State,
        time: f64,
    ) -> Option<S::Point> {
        let _ = (model, workspace, t, h, start, time);
        None
    }

    /// The point at `time` between two completed points `a` and `b` of one step, by an
    /// interpolant of the space (cubic Hermite on ℝᴺ); `None` where the space has none.
    fn interpolate(&self, model: &L, a: &S::Point, b: &S::Point, time: f64) -> Option<S::Point> {
        let _ = (model, a, b, time);
        None
    }

    /// Number of interpolation points of a spectral method (polynomial degree + 1); `None`
    /// for methods without a degree.
    fn points(&self) -> Option<usize> {
        None
    }

    /// The same method with `points` interpolation points (degree adaptivity); `None` for
    /// methods without a degree.
    fn with_points(&self, points: usize) -> Option<Self>
    where
        Self: Sized,
    {
        let _ = points;
        None
    }

    /// Node values of the last step's polynomial as offsets from its first node, at the
    /// nodes ν = 1, …, s ([`Space::node_width`] numbers per node); `None` for methods without a
    /// degree.
    fn node_offsets<'a>(&self, workspace: &'a mut Self::Workspace) -> Option<&'a [f64]> {
        let _ = workspace;
        None
    }

    /// The discrete energy E_d = −∂L_d/∂h of the last step taken (from `start` at `t` with
    /// size `h`), for methods whose discrete Lagrangian L_d(q_k, q_{k+1}, h) is a Galerkin
    /// action (the energy equation of the symplectic-energy-momentum integrators, Leok
    /// §5.5); `None` for other methods.
    fn discrete_energy(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        start: &S::State,
    ) -> Option<f64> {
        let _ = (model, workspace, t, h, start);
        None
    }
}

/// Most entries of one dense matrix a method on ℝᴺ may hold: 2²⁷ (1 GiB of `f64`). The methods
/// on ℝᴺ keep dense N × N matrices (the mass matrix and its inverse, the tangent map) and the
/// spectral ones a dense (N·P)² Newton matrix; a run-time-size model beyond this is refused
/// before anything is allocated.
pub const MAX_DENSE_ENTRIES: usize = 1 << 27;

/// Refuse `method` with `points` interpolation points on a model of `size` coordinates when
/// its dense Newton matrix, (2·size·points)² entries at most, would exceed
/// [`MAX_DENSE_ENTRIES`]: the error names the method, the size and the reason, and says what
/// serves.
///
/// # Errors
/// [`Error::InvalidParameter`] `model`.
pub fn dense_size(method: &str, size: usize, points: usize) -> Result<(), Error> {
    let rows = size.saturating_mul(points.max(1)).saturating_mul(2);
    let entries = rows.saturating_mul(rows);
    if entries <= MAX_DENSE_ENTRIES {
        return Ok(());
    }
    Err(Error::invalid(
        "model",
        format!(
            "{method} on a model of {size} coordinates would hold a dense {rows} × {rows} \
             matrix ({:.1} GiB, more than the {} GiB a dense method may take); a model this \
             large runs when it is written as a sum of local terms (a chain or lattice: sparse \
             Newton and explicit Störmer–Verlet)",
            entries as f64 * 8.0 / f64::from(1 << 30),
            (MAX_DENSE_ENTRIES * 8) >> 30
        ),
    ))
}

impl<L: Lagrangian<N>, M: Method<N>, N: Dimension> Step<L, Euclidean<N>> for M
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = M::Workspace;
    const WITHOUT_POINTS: bool = <M as Method<N>>::WITHOUT_POINTS;

    fn info(&self) -> MethodInfo {
        Method::info(self)
    }

    /// The method's workspace, after checking that the dense matrices of a run-time-size model
    /// fit ([`dense_size`]).
    fn workspace(&self, model: &L, h: f64) -> Result<M::Workspace, Error> {
        // Only a run-time size can be too large (a fixed one is compiled in), and options out
        // of range are the method's to report.
        if N::try_to_usize().is_none() && !Method::keeps_sparsity(self, model) {
            let points = Method::points(self).unwrap_or(1).min(MAX_POINTS);
            dense_size(Method::info(self).name, model.dimension(), points)?;
        }
        Method::workspace(self, model, h)
    }

    fn step(
        &self,
        model: &L,
        workspace: &mut M::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        Method::step(self, model, workspace, t, h, state, increment)
    }

    fn restart(&self, workspace: &mut M::Workspace) {
        Method::restart(self, workspace);
    }

    fn tangent_map(
        &self,
        model: &L,
        workspace: &mut M::Workspace,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        Method::tangent_map(self, model, workspace, t, h, state)
    }

    fn initial_state(&self, model: &L, t0: f64, initial: &Initial<N>) -> Result<State<N>, Error> {
        euclidean_initial_state(model, Method::info(self).coordinates, t0, initial)
    }

    /// [`check_euclidean_model`] under the method's equations and coordinates.
    fn check_model(&self, model: &L, t: f64, state: &State<N>) -> Result<(), Error> {
        check_euclidean_model(model, &Method::info(self), t, state)
    }

    fn complete(
        &self,
        model: &L,
        workspace: Option<&M::Workspace>,
        t: f64,
        state: &State<N>,
        guess: &OVector<f64, N>,
    ) -> Result<PhasePoint<N>, Error> {
        let mut point = Step::<L, Euclidean<N>>::incomplete(self, t, state, guess);
        self.complete_into(model, workspace, t, state, guess, &mut point)?;
        Ok(point)
    }

    /// In `point`'s vectors (nothing allocated at run-time size, where the velocity comes
    /// from the workspace: a cached M⁻¹ or the run's sparse inverse Legendre map; the
    /// momentum of a method in velocity coordinates from a cached M).
    fn complete_into(
        &self,
        model: &L,
        workspace: Option<&M::Workspace>,
        t: f64,
        state: &State<N>,
        guess: &OVector<f64, N>,
        point: &mut PhasePoint<N>,
    ) -> Result<(), Error> {
        point.t = t;
        point.q.copy_from(&state.q);
        match Method::info(self).coordinates {
            Coordinates::Momentum => {
                point.p.copy_from(&state.y);
                point.v.copy_from(guess);
                let known = match workspace {
                    Some(workspace) => {
                        self.velocity_into(model, workspace, t, &state.q, &state.y, &mut point.v)?
                    }
                    None => false,
                };
                if !known {
                    point.v = model.velocity(t, &state.q, &state.y, guess)?;
                }
            }
            Coordinates::Velocity => {
                point.v.copy_from(&state.y);
                let known = workspace
                    .is_some_and(|workspace| self.momentum_into(workspace, &state.y, &mut point.p));
                if !known {
                    model.momentum_into(t, &state.q, &state.y, &mut point.p);
                }
            }
        }
        Ok(())
    }

    fn incomplete(&self, t: f64, state: &State<N>, guess: &OVector<f64, N>) -> PhasePoint<N> {
        let (v, p) = match Method::info(self).coordinates {
            Coordinates::Momentum => (guess.clone(), state.y.clone()),
            Coordinates::Velocity => (state.y.clone(), guess.clone()),
        };
        PhasePoint {
            t,
            q: state.q.clone(),
            v,
            p,
        }
    }

    fn point_is_finite(&self, point: &PhasePoint<N>) -> bool {
        point.v.iter().chain(point.p.iter()).all(|x| x.is_finite())
    }

    fn dense_point(
        &self,
        model: &L,
        workspace: &M::Workspace,
        t: f64,
        h: f64,
        start: &State<N>,
        time: f64,
    ) -> Option<PhasePoint<N>> {
        let theta = ((time - t) / h).clamp(0.0, 1.0);
        let (q, v) = Method::dense_output(self, workspace, start, h, theta)?;
        let p = match model.hamiltonian_form() {
            // No L: p solves ∂H/∂p(t, q, p) = q̇ by H's derivatives, else the Hermite
            // interpolant of (q, p) serves the time.
            Some(form) if form.without_lagrangian() => {
                field_momentum(form, time, &q, &v, &start.y)?
            }
            _ => model.momentum(time, &q, &v),
        };
        Some(PhasePoint { t: time, q, v, p })
    }

    /// Cubic Hermite interpolation of (q, q̇), with p from the Legendre map; for a model without
    /// a Lagrangian p is interpolated the same way, with ṗ = −∂H/∂q + f_H at the ends.
    fn interpolate(
        &self,
        model: &L,
        a: &PhasePoint<N>,
        b: &PhasePoint<N>,
        time: f64,
    ) -> Option<PhasePoint<N>> {
        let Hermite {
            h,
            value: w,
            rate: d,
        } = Hermite::new(a.t, b.t, time);
        let q = &a.q * w[0] + &a.v * (h * w[1]) + &b.q * w[2] + &b.v * (h * w[3]);
        let v = (&a.q * d[0] + &b.q * d[2]) / h + &a.v * d[1] + &b.v * d[3];
        let p = match model.hamiltonian_form() {
            Some(form) if form.without_lagrangian() => {
                let rate = |point: &PhasePoint<N>| {
                    let (hq, _) = form.gradient(point.t, &point.q, &point.p);
                    form.force(point.t, &point.q, &point.p) - hq
                };
                let (ra, rb) = (rate(a), rate(b));
                &a.p * w[0] + ra * (h * w[1]) + &b.p * w[2] + rb * (h * w[3])
            }
            _ => model.momentum(time, &q, &v),
        };
        Some(PhasePoint { t: time, q, v, p })
    }

    fn points(&self) -> Option<usize> {
        Method::points(self)
    }

    fn with_points(&self, points: usize) -> Option<Self> {
        Method::with_points(self, points)
    }

    fn node_offsets<'a>(&self, workspace: &'a mut M::Workspace) -> Option<&'a [f64]> {
        Method::node_offsets(self, workspace)
    }
    fn discrete_energy(
        &self,
        model: &L,
        workspace: &mut M::Workspace,
        t: f64,
        h: f64,
        start: &State<N>,
    ) -> Option<f64> {
        Method::discrete_energy(self, model, workspace, t, h, start)
    }
}

/// p with ∂H/∂p(t, q, p) = `v` for a model without a Lagrangian (the inverse Legendre map
/// through H's derivatives: Newton's method with ∂²H/∂p² from the field's Jacobian,
/// from `guess`); `None` if it does not converge to round-off in a few iterations.
fn field_momentum<N: Dimension>(
    form: &dyn HamiltonianForm<N>,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
    guess: &OVector<f64, N>,
) -> Option<OVector<f64, N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let scale = 1.0 + v.amax();
    let mut p = guess.clone();
    for _ in 0..FIELD_MOMENTUM_ITERATIONS {
        let residual = form.velocity(t, q, &p) - v;
        if residual.amax() <= 1e-14 * scale {
            return Some(p);
        }
        let step = solve_small(form.second(t, q, &p).pp, residual)?;
        p -= step;
    }
    None
}

/// Most Newton iterations of [`field_momentum`].
const FIELD_MOMENTUM_ITERATIONS: usize = 20;

/// The state of a method on ℝᴺ from an initial condition, in the method's `coordinates`
/// (the Legendre map or its inverse where the condition is in the others), after checking the
/// model's size and index sets and that every number is finite. Generic in the model only, so
/// that it is compiled once per model, not once per model and method.
fn euclidean_initial_state<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    coordinates: Coordinates,
    t0: f64,
    initial: &Initial<N>,
) -> Result<State<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (q, second, name) = match initial {
        Initial::Velocity { q, v } => (q, v, "initial velocity"),
        Initial::Momentum { q, p } => (q, p, "initial momentum"),
    };
    let size = model.dimension();
    dimension_of::<N>(size).map_err(|reason| Error::invalid("model", reason))?;
    if let Some(terms) = model.terms() {
        terms.check_indices(size)?;
    }
    for (what, x) in [("initial position", q), (name, second)] {
        if x.len() != size {
            return Err(Error::invalid(
                "initial state",
                format!(
                    "the {what} has {} entries, the model {size} coordinates",
                    x.len()
                ),
            ));
        }
    }
    require_finite_entries("initial position", q)?;
    require_finite_entries(name, second)?;
    let y = match (coordinates, initial) {
        (Coordinates::Momentum, Initial::Momentum { p, .. }) => p.clone(),
        (Coordinates::Velocity, Initial::Velocity { v, .. }) => v.clone(),
        (Coordinates::Momentum, Initial::Velocity { q, v }) => match model.hamiltonian_form() {
            Some(form) if form.without_lagrangian() => field_momentum(form, t0, q, v, v)
                .ok_or_else(|| {
                    Error::invalid(
                        "initial state",
                        "no momentum p with ∂H/∂p = the initial velocity was found: give \
                         the initial momentum",
                    )
                })?,
            _ => model.momentum(t0, q, v),
        },
        (Coordinates::Velocity, Initial::Momentum { q, p }) => model.velocity(t0, q, p, p)?,
    };
    let state = State { q: q.clone(), y };
    if !state.is_finite() {
        return Err(Error::NonFinite {
            what: format!(
                "{} of the model from the given initial state (its Lagrangian or \
                 derivatives are singular or overflow there)",
                match initial {
                    Initial::Velocity { .. } => "momentum ∂L/∂q̇",
                    Initial::Momentum { .. } => "velocity (inverse Legendre map)",
                }
            ),
            step: 0,
            t: t0,
        });
    }
    Ok(state)
}

/// A [`Structure::ConstantMass`] declaration, L = ½ q̇ᵀMq̇ − V(t, q): L_qv must vanish,
/// L_vv must not change with q̇ nor with q (at 2q̇ + 1 and at 2q + 1), and ∂L/∂q̇ must vanish
/// at q̇ = 0 at both positions (no term linear in q̇: p = Mq̇ exactly, which the fixed-point
/// iteration and the cached q̇ = M⁻¹p rely on). Necessary conditions, checked at the initial
/// state of the integrator's first run. A model written as a Hamiltonian is checked by
/// [`crate::model::hamiltonian::HamiltonianForm::check`] instead.
///
/// Generic in the model only, so that it is compiled once per model, not once per model and
/// method.
fn check_euclidean_model<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    info: &MethodInfo,
    t: f64,
    state: &State<N>,
) -> Result<(), Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    // A model written as H: H finite, ∂²H/∂p² regular and its declared structure, at
    // (q, p) (its Lagrangian's constant mass is ½ q̇ᵀMq̇ by construction).
    if let Some(form) = model.hamiltonian_form() {
        if form.without_lagrangian() && info.equations != Equations::Hamilton {
            return Err(Error::invalid(
                "method",
                format!(
                    "{} discretises the Euler–Lagrange equations, and the model (a \
                     right-hand side of Hamilton's equations, or an H of local terms) has no \
                     Lagrangian: run it with \
                     a method on Hamilton's equations (the methods whose names end in -h, \
                     svi-h the first)",
                    info.name,
                ),
            ));
        }
        let p = match info.coordinates {
            Coordinates::Momentum => state.y.clone(),
            Coordinates::Velocity => model.momentum(t, &state.q, &state.y),
        };
        return form.check(t, &state.q, &p);
    }
    if L::STRUCTURE != Structure::ConstantMass {
        return Ok(());
    }
    // The blocks at (q, q̇), at a shifted q̇ and at a shifted q: M may change with neither
    // (the mixed block alone would not show a q-dependent M, since the Hessian blocks of a
    // model declared constant-mass take it as zero).
    let shifted = state.y.map(|y| 2.0 * y + 1.0);
    let moved = state.q.map(|q| 2.0 * q + 1.0);
    let (scale, coupling, change, drift) = match model.terms() {
        // Term by term, in O(n): no n × n matrix. A term's blocks at q̇ and at the
        // shifted q̇ (a sum whose terms' dependences on q̇ cancel would be refused; no
        // model is written that way).
        Some(terms) => {
            let layout = TermDerivatives {
                width: terms.width(),
            };
            let k = layout.width;
            let mut indices = vec![0; k];
            let mut local = [vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]];
            let mut blocks = [
                vec![0.0; layout.len()],
                vec![0.0; layout.len()],
                vec![0.0; layout.len()],
            ];
            let (mut mass, mut stiffness) = (0.0_f64, 0.0_f64);
            let (mut coupling, mut change, mut drift) = (0.0_f64, 0.0_f64, 0.0_f64);
            for e in 0..terms.term_count() {
                terms.term_indices(e, &mut indices);
                let [q, v, w, r] = &mut local;
                for (a, &i) in indices.iter().enumerate() {
                    (q[a], v[a], w[a], r[a]) = (state.q[i], state.y[i], shifted[i], moved[i]);
                }
                terms.term_derivatives(e, t, q, v, true, &mut blocks[0]);
                terms.term_derivatives(e, t, q, w, true, &mut blocks[1]);
                terms.term_derivatives(e, t, r, v, true, &mut blocks[2]);
                let [first, second, third] = &blocks;
                for a in 0..k {
                    for b in 0..k {
                        let vv = layout.vv(first, a, b);
                        mass = mass.max(vv.abs());
                        stiffness = stiffness.max(layout.qq(first, a, b).abs());
                        coupling = coupling
                            .max(layout.qv(first, a, b).abs())
                            .max(layout.qv(second, a, b).abs());
                        change = change.max((vv - layout.vv(second, a, b)).abs());
                        drift = drift.max((vv - layout.vv(third, a, b)).abs());
                    }
                }
            }
            (1.0 + mass + stiffness, coupling, change, drift)
        }
        None => {
            let first = model.second_derivatives(t, &state.q, &state.y);
            let second = model.second_derivatives(t, &state.q, &shifted);
            let third = model.second_derivatives(t, &moved, &state.y);
            (
                1.0 + first.vv.amax() + first.qq.amax(),
                first.qv.amax().max(second.qv.amax()),
                (&first.vv - &second.vv).amax(),
                (&first.vv - &third.vv).amax(),
            )
        }
    };
    // The Hessian blocks take L_qv as zero, so a term A(q)·q̇ shows only here.
    let rest = state.y.map(|_| 0.0);
    let linear = model
        .momentum(t, &state.q, &rest)
        .amax()
        .max(model.momentum(t, &moved, &rest).amax());
    let tolerance = 1e-12 * scale;
    if coupling > tolerance || change > tolerance || drift > tolerance || linear > tolerance {
        return Err(Error::invalid(
            "structure",
            format!(
                "the model declares a constant mass matrix (L = ½ q̇ᵀMq̇ − V), but \
                 ∂²L/∂q∂q̇ = {coupling:e}, ∂²L/∂q̇² changes by {change:e} with q̇ and by \
                 {drift:e} with q, and ∂L/∂q̇ = {linear:e} at q̇ = 0"
            ),
        ));
    }
    Ok(())
}
