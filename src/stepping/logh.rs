//! The logarithmic Hamiltonian: an explicit, symplectic, time-reparametrised splitting for
//! constant-mass Lagrangians with a potential below zero.
//!
//! # Derivation
//! For L = ½q̇ᵀMq̇ − V(q) (constant M, autonomous) write U(q) = −V(q) = L(q, 0) > 0 and
//! T(p) = ½pᵀM⁻¹p, so H = T − U. The Poincaré transformation with the monitor g = 1/U
//! ([`crate::model::reparametrized::Potential`]; Leok, *Generalized Variational
//! Integrators*, §5.6) gives K = (H − E₀)/U in the time τ, dt/dτ = 1/U. Any function f(K)
//! with f(0) = 0, f′(0) = 1 has, on the shell K = 0, the same flow; f = ln(1 + ·) gives
//!
//! Γ(q, p) = ln(1 + K) = ln(T(p) − E₀) − ln U(q),
//!
//! a kinetic part depending on p alone and a potential part depending on q alone
//! (Mikkola & Tanikawa, MNRAS 310 (1999) 745; Preto & Tremaine, AJ 118 (1999) 2532). Their
//! flows are exact and explicit:
//!
//! - drift by σ: q += σ M⁻¹p / (T(p) − E₀), t += σ / (T(p) − E₀) (p fixed);
//! - kick by σ: p += σ ∇U(q) / U(q) (q fixed),
//!
//! and the leapfrog (drift σ/2, kick σ, drift σ/2) is a symmetric, symplectic step of order 2
//! for Γ in (q, p), with t carried along (t is the coordinate conjugate to −E₀, held fixed).
//! Γ is conserved to O(σ²) with no drift (backward error analysis), and with it H: on the
//! Kepler problem the leapfrog's orbit is the exact ellipse, and only the time along it has
//! an error (Mikkola & Tanikawa 1999; tested below). Composed with the fractions of
//! [`crate::method::variational::composition`] the step reaches order 4, 6 or 8 (adjacent
//! drifts merge: one gradient of L per stage).
//!
//! The run needs U > 0 along the way, and T(p) − E₀ > 0 at every drift (on the energy shell
//! it equals U, so only a step that strays far from the shell can violate it); otherwise it
//! stops with a typed error, as it does when the state runs away to non-finite values. ∇U = ∂L/∂q and U come from one sweep of
//! automatic differentiation of L at q̇ = 0.
//!
//! # Physical time
//! t is integrated with the state (compensated sum over the drifts). The last step's size is
//! found by Newton's method on t(σ) = t_end (slope 1/(T − E₀) at its end), so the run ends at
//! t_end with a step's accuracy. Output times inside the span are not served: the splitting
//! has no step polynomial.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::method::Method;
use crate::method::space::{Euclidean, Initial, PhasePoint, State, StepState};
use crate::model::Lagrangian;
use crate::model::Structure;
use crate::model::derived::{LagrangianExt, cached_mass_inverse};
use crate::model::mass_inverse::MassInverse;
use crate::model::reparametrized::{Potential, Reparametrized};
use crate::stepping::observer::Observer;
use crate::stepping::reparam::{Clock, failure_after, land_on_horizon};
use crate::stepping::run::{Cursor, Integrator, RunFailure, Statistics};
use crate::stepping::solve::{Adaptivity, Solution, SolveOptions, Span};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

/// The splitting of Γ for one model at one energy level.
struct Splitting<'a, L, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: &'a L,
    mass_inverse: MassInverse<N>,
    energy: f64,
    fractions: &'a [f64],
}

/// A point of the split flow: the state (q, p) with the compensation of its sums, and the
/// physical time.
#[derive(Debug, Clone)]
struct Point<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    cursor: Cursor<Euclidean<N>>,
    clock: Clock,
}

impl<L: Lagrangian<N>, N: Dimension> Splitting<'_, L, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// 1/(T(p) − E₀): T(p) − E₀ ≤ 0 is an [`Error::InvalidParameter`] named `monitor` (a
    /// step far off the energy shell), a non-finite value an [`Error::NonFinite`] at (`step`,
    /// `t`).
    fn rate(&self, p: &OVector<f64, N>, (step, t): (usize, f64)) -> Result<f64, Error> {
        let excess = 0.5 * p.dot(&self.mass_inverse.apply(p)) - self.energy;
        if !excess.is_finite() {
            Err(Error::NonFinite {
                what: format!("T(p) − E₀ = {excess:e} at p = {:?}", p.as_slice()),
                step,
                t,
            })
        } else if excess > 0.0 {
            Ok(excess.recip())
        } else {
            Err(Error::invalid(
                "monitor",
                format!(
                    "the potential monitor needs T(p) − E₀ > 0 (it equals U > 0 on the energy \
                     shell: a step strayed far from it), but it is {excess:e} at p = {:?}",
                    p.as_slice()
                ),
            ))
        }
    }

    /// U(q) = L(q, 0) and ∇U = ∂L/∂q(q, 0): U ≤ 0 is an [`Error::InvalidParameter`] named
    /// `monitor` (the potential monitor does not apply), a non-finite U or ∇U an
    /// [`Error::NonFinite`] at (`step`, `t`) (the state ran away).
    fn potential(
        &self,
        q: &OVector<f64, N>,
        (step, t): (usize, f64),
    ) -> Result<(f64, OVector<f64, N>), Error> {
        let rest = OVector::zeros_generic(q.shape_generic().0, U1);
        let (potential, gradient) = self.model.value_and_force(0.0, q, &rest);
        if !(potential.is_finite() && gradient.iter().all(|g| g.is_finite())) {
            Err(Error::NonFinite {
                what: format!(
                    "U(q) = {potential:e} or its gradient at q = {:?}",
                    q.as_slice()
                ),
                step,
                t,
            })
        } else if potential > 0.0 {
            Ok((potential, gradient))
        } else {
            Err(Error::invalid(
                "monitor",
                format!(
                    "the potential monitor needs U(q) = L(q, 0) = −V(q) > 0, but U = \
                     {potential:e} at q = {:?}",
                    q.as_slice()
                ),
            ))
        }
    }

    /// One step of size `sigma` from `from`: the composed leapfrog (drift, kick, drift) with
    /// merged drifts. Returns the increment of (q, p) and of t.
    fn step(&self, from: &Point<N>, sigma: f64, k: usize) -> Result<(State<N>, f64), Error> {
        let State { q, y: p } = &from.cursor.state;
        let n = from.cursor.state.dimension();
        let (mut dq, mut dp, mut dt) = (
            OVector::<f64, N>::zeros_generic(n, U1),
            OVector::<f64, N>::zeros_generic(n, U1),
            0.0,
        );
        // Drift by `length` at the momentum p: q += length M⁻¹p/(T − E₀), t += length/(T − E₀).
        let drift = |p: &OVector<f64, N>, length: f64| {
            let rate = self.rate(p, (k, from.clock.t))?;
            Ok::<_, Error>((self.mass_inverse.apply(p) * (length * rate), length * rate))
        };
        // Each stage drifts by half its own size and half the next one's (merged drifts).
        let mut pending = 0.5 * self.fractions[0] * sigma;
        for (i, gamma) in self.fractions.iter().enumerate() {
            let (q_step, t_step) = drift(&(p + &dp), pending)?;
            dq += q_step;
            dt += t_step;
            let (potential, gradient) = self.potential(&(q + &dq), (k, from.clock.t))?;
            dp += gradient * (gamma * sigma / potential);
            pending = 0.5 * (gamma + self.fractions.get(i + 1).unwrap_or(&0.0)) * sigma;
        }
        let (q_step, t_step) = drift(&(p + &dp), pending)?;
        Ok((
            State {
                q: dq + q_step,
                y: dp,
            },
            dt + t_step,
        ))
    }

    /// The physical point (t, q, q̇ = M⁻¹p, p).
    fn physical(&self, point: &Point<N>) -> PhasePoint<N> {
        let State { q, y: p } = &point.cursor.state;
        PhasePoint {
            t: point.clock.t,
            q: q.clone(),
            v: self.mass_inverse.apply(p),
            p: p.clone(),
        }
    }
}

impl<L: Lagrangian<N>, M: Method<N> + Clone, N: Dimension> Integrator<L, M, Euclidean<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// [`Integrator::try_solve_reparametrized`] with the potential monitor and a method that
    /// composes Störmer–Verlet (`fractions`), on a constant-mass model: the logarithmic
    /// Hamiltonian split explicitly (see the module docs).
    pub(crate) fn try_solve_logh<O: Observer<L, PhasePoint<N>>>(
        &self,
        fractions: &[f64],
        span: &Span,
        initial: Initial<N>,
        options: &SolveOptions,
        observer: &mut O,
    ) -> Result<Solution<Euclidean<N>>, RunFailure<Euclidean<N>>> {
        let rejected = RunFailure::rejected;
        debug_assert_eq!(L::STRUCTURE, Structure::ConstantMass);
        span.validate().map_err(rejected)?;
        options.validate_reparametrized().map_err(rejected)?;
        let sigma = options.step().map_err(rejected)?;
        if let Some(&inside) = span.output_times[..span.output_times.len() - 1]
            .iter()
            .find(|&&t| t > span.t0)
        {
            return Err(rejected(Error::invalid(
                "output_times",
                format!(
                    "{inside:?} lies inside the span, and the potential monitor's splitting has \
                     no step polynomial to read it from: ask for output at the ends of the span"
                ),
            )));
        }
        let model = self.model();
        let start = self.start(span.t0, &initial).map_err(rejected)?;
        let first = self
            .phase_point(span.t0, &start.cursor.state, &start.guess)
            .map_err(rejected)?;
        let energy = model.energy(span.t0, &first.q, &first.v);
        // The model must be autonomous and unforced, the energy finite (as for L̃).
        Reparametrized::new(model, &Potential, energy).map_err(rejected)?;
        let mass_inverse = cached_mass_inverse(&mut None, model, span.t0, &first.q, &first.p)
            .cloned()
            .map_err(|_| {
                rejected(Error::invalid(
                    "structure",
                    "the potential monitor's splitting needs an invertible mass matrix",
                ))
            })?;
        let splitting = Splitting {
            model,
            mass_inverse,
            energy,
            fractions,
        };
        splitting
            .potential(&first.q, (0, span.t0))
            .map_err(rejected)?;
        let mut statistics = Statistics::default();
        let mut adaptivity = Adaptivity::default();
        let mut outputs = Vec::with_capacity(2);
        if span.output_times[0] == span.t0 {
            outputs.push(first.clone());
        }
        let mut point = Point {
            cursor: Cursor::new(State {
                q: first.q.clone(),
                y: first.p.clone(),
            }),
            clock: Clock::new(span.t0),
        };
        let mut last = first.clone();
        let failure = failure_after::<N>;
        if observer.wants(0) && observer.observe(model, 0, &first).is_break() {
            return Ok(Solution {
                points: outputs,
                last: first,
                statistics,
                adaptivity,
                stopped: true,
                dense: None,
                events: Vec::new(),
                terminal: None,
            });
        }
        let limit = options.run.divergence_limit;
        let mut k = 0usize;
        loop {
            options
                .budget(k, point.clock.t)
                .map_err(|error| failure(error, &last, statistics))?;
            // The step from `point` with size `size`, added with compensated summation and
            // checked for finite values and against the divergence limit.
            let attempt = |size: f64, statistics: &mut Statistics| {
                let (increment, dt) = splitting.step(&point, size, k)?;
                statistics.evaluations += splitting.fractions.len();
                let mut end = point.clone();
                let Cursor {
                    state,
                    compensation,
                } = &mut end.cursor;
                state
                    .add_checked(compensation, &increment, limit)
                    .map_err(|failure| failure.at(k, point.clock.t))?;
                end.clock.add(dt);
                Ok::<_, Error>(end)
            };
            let mut end = attempt(sigma, &mut statistics)
                .map_err(|error| failure(error, &last, statistics))?;
            let finish = end.clock.t >= span.t_end;
            if finish {
                // dt/dσ = 1/(T − E₀) at the step's end.
                let slope =
                    |end: &Point<N>| splitting.rate(&end.cursor.state.y, (k, point.clock.t));
                let first = slope(&end).map_err(|error| failure(error, &last, statistics))?;
                land_on_horizon(
                    span.t_end,
                    (sigma, end.clock.t - span.t_end, first),
                    (k, point.clock.t),
                    |size| {
                        end = attempt(size, &mut statistics)?;
                        Ok((end.clock.t - span.t_end, slope(&end)?))
                    },
                )
                .map_err(|error| failure(error, &last, statistics))?;
                end.clock.t = span.t_end;
            }
            adaptivity.record(end.clock.t - point.clock.t, None);
            point = end;
            k += 1;
            statistics.steps = k;
            last = splitting.physical(&point);
            if observer.wants(k) && observer.observe(model, k, &last).is_break() {
                return Ok(Solution {
                    points: outputs,
                    last,
                    statistics,
                    adaptivity,
                    stopped: !finish,
                    dense: None,
                    events: Vec::new(),
                    terminal: None,
                });
            }
            if finish {
                if outputs.len() < span.output_times.len() {
                    outputs.push(last.clone());
                }
                return Ok(Solution {
                    points: outputs,
                    last,
                    statistics,
                    adaptivity,
                    stopped: false,
                    dense: None,
                    events: Vec::new(),
                    terminal: None,
                });
            }
        }
    }
}
