//! The variational integrator of any discrete Lagrangian.
//!
//! # Discrete equations
//! For a discrete Lagrangian L_d ([`DiscreteLagrangian`]) with discrete forces f_d^±, the
//! step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) solves the implicit discrete Euler–Lagrange
//! equations (Li, Wu, Leok 2018, eq. 5; forced: Marsden & West 2001, eq. 3.2.6)
//!
//! p_k = −D1 L_d(q_k, q_{k+1}) − f_d⁻(q_k, q_{k+1}),
//! p_{k+1} = D2 L_d(q_k, q_{k+1}) + f_d⁺(q_k, q_{k+1}).
//!
//! The first is solved for q_{k+1} by Newton's method with the exact Jacobian
//! D12 L_d + ∂f_d⁻/∂q_{k+1} (num-dual: one `partial_hessian` sweep gives D1 L_d, D2 L_d and
//! D12 L_d together; one `jacobian` sweep gives f_d⁻ and its derivative), iterated to
//! round-off with the stopping rule shared by all implicit methods of `svi`. The unknown is
//! the increment q_{k+1} − q_k. The first step starts from the Taylor predictor
//! q_k + h q̇ + (h²/2) q̈ (q̇ from the inverse Legendre map of p_k, q̈ from the forced
//! Euler–Lagrange equations); later steps extrapolate the increments of the two previous
//! steps linearly, 2Δ_{k−1} − Δ_{k−2} (an O(h³) guess, at no cost).
//!
//! The momentum is updated without cancellation: adding the two equations,
//!
//! p_{k+1} − p_k = (D1 + D2) L_d(q_k, q_{k+1}) + f_d⁻ + f_d⁺,
//!
//! and (D1 + D2) L_d is the derivative of ε ↦ L_d(q_k + ε, q_{k+1} + ε), computed by one
//! gradient sweep in which the discrete velocity carries no derivative at all: for the
//! segment rules of [`crate::method::variational::discrete_lagrangian`] it is h Σ_i b_i ∂L/∂q(τ_i), the discrete
//! momentum balance, whereas D2 L_d + D1 L_d term by term cancels O(|p|) each step.
//!
//! # Properties
//! The order and symmetry of the discrete Lagrangian ([`DiscreteLagrangianInfo`]);
//! symplectic (L_d is a type-I generating function of the step), and Noether momenta of
//! symmetries of L_d are conserved. With an external force the step is the discrete
//! Lagrange–d'Alembert map: not symplectic, same order.
//!
//! # References
//! Li, Wu, Leok (2018), eqs. (4)–(5); Marsden & West, *Discrete mechanics and variational
//! integrators*, Acta Numerica (2001), §1.2, §2.7 and §3.2; Porcù & Penati (OctConf 2013),
//! "Discrete mechanics" and "Forced mechanics".

use crate::error::Error;
use crate::error::StepFailure;
use crate::linalg::invert_small;
use crate::method::Method;
use crate::method::variational::discrete_lagrangian::{DiscreteLagrangian, DiscreteLagrangianInfo};
use crate::method::{Coordinates, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::nonlinear::Newton;
use nalgebra::{Const, DVector, SMatrix, SVector};
use num_dual::{Dual2Vec, DualSVec64, DualVec, HyperDualVec, gradient, hessian, jacobian};

/// Hyper-dual numbers for the mixed second derivative D12 L_d.
type Hyper<const N: usize> = HyperDualVec<f64, Const<N>, Const<N>>;

/// Options of the variational integrator of a discrete Lagrangian.
///
/// ```
/// use nalgebra::SVector;
/// use svi::{Integrator, Lagrangian, Midpoint, Scalar, VariationalIntegrator};
///
/// struct Oscillator;
/// impl Lagrangian<1> for Oscillator {
///     const TIME_DEPENDENT: bool = false;
///     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
///         (v[0] * v[0] - q[0] * q[0]) * 0.5
///     }
/// }
///
/// let integrator = Integrator::new(Oscillator, VariationalIntegrator::new(Midpoint));
/// let run = integrator
///     .run_from_velocity(0.0, SVector::from([1.0]), SVector::from([0.0]), 0.01, 1.0, &mut ())
///     .unwrap();
/// assert!((run.last.q[0] - 1f64.cos()).abs() < 1e-5);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct VariationalIntegrator<Ld> {
    /// The discrete Lagrangian (and with it the discrete forces).
    pub discrete_lagrangian: Ld,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl<Ld: Default> Default for VariationalIntegrator<Ld> {
    fn default() -> Self {
        VariationalIntegrator::new(Ld::default())
    }
}

impl<Ld> VariationalIntegrator<Ld> {
    /// The variational integrator of `discrete_lagrangian`.
    pub fn new(discrete_lagrangian: Ld) -> Self {
        VariationalIntegrator {
            discrete_lagrangian,
            max_iterations: 50,
        }
    }

    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }
}

/// The increments of the previous steps, for the predictor.
#[derive(Debug, Clone)]
struct History<const N: usize> {
    /// Step size of the recorded steps.
    h: f64,
    /// Where the last step ended: the next step continues the run if it starts there.
    end: SVector<f64, N>,
    /// Round-off tolerance for recognising `end`.
    tolerance: f64,
    /// Δ_{k−1}.
    last: SVector<f64, N>,
    /// Δ_{k−2}, if the step before the last one was recorded too.
    before: Option<SVector<f64, N>>,
}

/// A tolerance for recognising a position after the stepping loop's compensated summation:
/// its result differs from the plain sum q + Δ by the rounding of the two additions.
pub(crate) fn continuation_tolerance<const N: usize>(
    start: &SVector<f64, N>,
    end: &SVector<f64, N>,
) -> f64 {
    4.0 * f64::EPSILON * start.amax().max(end.amax())
}

/// Buffers of a run of a [`VariationalIntegrator`].
#[derive(Debug, Clone)]
pub struct VariationalWorkspace<const N: usize> {
    /// The unknown increment q_{k+1} − q_k.
    offset: DVector<f64>,
    newton: Newton,
    history: Option<History<N>>,
}

impl<const N: usize> VariationalWorkspace<N> {
    pub(crate) fn new(max_iterations: usize) -> Self {
        VariationalWorkspace {
            offset: DVector::zeros(N),
            newton: Newton::new(N, max_iterations),
            history: None,
        }
    }

    /// The predicted increment: extrapolated from the previous steps when this step
    /// continues them, else the Taylor polynomial of the continuous flow.
    fn predict<L: Lagrangian<N>>(
        &self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> SVector<f64, N> {
        if let Some(history) = &self.history
            && history.h == h
            && (state.q - history.end).amax() <= history.tolerance
        {
            return match history.before {
                Some(before) => history.last * 2.0 - before,
                None => history.last,
            };
        }
        let v = model
            .velocity(t, &state.q, &state.y, &state.y)
            .unwrap_or_else(|_| SVector::zeros());
        let a = model
            .acceleration(t, &state.q, &v)
            .unwrap_or_else(SVector::zeros);
        v * h + a * (0.5 * h * h)
    }

    /// Record a completed step.
    pub(crate) fn remember(&mut self, h: f64, state: &State<N>, increment: &SVector<f64, N>) {
        let end = state.q + increment;
        let before = match &self.history {
            Some(history)
                if history.h == h && (state.q - history.end).amax() <= history.tolerance =>
            {
                Some(history.last)
            }
            _ => None,
        };
        self.history = Some(History {
            h,
            end,
            tolerance: continuation_tolerance(&state.q, &end),
            last: *increment,
            before,
        });
    }
}

impl<Ld: DiscreteLagrangian, const N: usize> Method<N> for VariationalIntegrator<Ld> {
    const WITHOUT_POINTS: bool = true;

    type Workspace = VariationalWorkspace<N>;

    fn info(&self) -> MethodInfo {
        let DiscreteLagrangianInfo {
            name,
            order,
            symmetric,
            ..
        } = self.discrete_lagrangian.info();
        MethodInfo {
            name,
            order,
            symmetric,
            symplectic: true,
            coordinates: Coordinates::Momentum,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        _model: &L,
        h: f64,
    ) -> Result<VariationalWorkspace<N>, Error> {
        crate::error::require_positive("h", h)?;
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        Ok(VariationalWorkspace::new(self.max_iterations))
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut VariationalWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let iterations = solve_position(&self.discrete_lagrangian, model, workspace, t, h, state)?;
        let offset = SVector::<f64, N>::from_column_slice(workspace.offset.as_slice());
        let q1 = state.q + offset;
        increment.q = offset;
        increment.y = momentum_increment(&self.discrete_lagrangian, model, t, h, &state.q, &q1);
        workspace.remember(h, state, &offset);
        let points = self.discrete_lagrangian.info().points;
        Ok(StepReport {
            iterations,
            evaluations: points * (iterations + 1),
            factorizations: iterations,
            analyses: 0,
        })
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut VariationalWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>), StepFailure> {
        let mut increment = State::zeros();
        self.step(model, workspace, t, h, state, &mut increment)?;
        let q1 = state.q + increment.q;
        let tangent = discrete_tangent_map(&self.discrete_lagrangian, model, t, h, &state.q, &q1)?;
        Ok((increment, tangent))
    }
}

/// Solve p_k + D1 L_d(q_k, q_k + Δ) + f_d⁻ = 0 for Δ (left in `workspace.offset`); returns
/// the Newton iterations.
fn solve_position<Ld: DiscreteLagrangian, L: Lagrangian<N>, const N: usize>(
    discrete: &Ld,
    model: &L,
    workspace: &mut VariationalWorkspace<N>,
    t: f64,
    h: f64,
    state: &State<N>,
) -> Result<usize, StepFailure> {
    let guess = workspace.predict(model, t, h, state);
    workspace.offset.copy_from_slice(guess.as_slice());
    let (q0, p0) = (state.q, state.y);
    workspace
        .newton
        .solve(&mut workspace.offset, |z, matrix, residual| {
            let q1 = q0 + SVector::<f64, N>::from_column_slice(z.as_slice());
            let (d1, _, d12) = mixed_derivatives(discrete, model, t, h, &q0, &q1);
            let mut value = p0 + d1;
            let mut jacobian_matrix = d12;
            if L::FORCED {
                let (minus, d_minus) = jacobian(
                    |y: SVector<DualSVec64<N>, N>| {
                        discrete
                            .discrete_forces(
                                model,
                                DualVec::from_re(t),
                                DualVec::from_re(h),
                                &q0.map(DualVec::from_re),
                                &y,
                            )
                            .minus
                    },
                    &q1,
                );
                value += minus;
                jacobian_matrix += d_minus;
            }
            residual.copy_from_slice(value.as_slice());
            matrix.copy_from(&jacobian_matrix);
        })
}

/// D1 L_d, D2 L_d and D12 L_d (entry (i, j) = ∂²L_d/∂q0_i∂q1_j) in one sweep.
fn mixed_derivatives<Ld: DiscreteLagrangian, L: Lagrangian<N>, const N: usize>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &SVector<f64, N>,
    q1: &SVector<f64, N>,
) -> (SVector<f64, N>, SVector<f64, N>, SMatrix<f64, N, N>) {
    let (_, d1, d2, d12) = num_dual::partial_hessian(
        |(x, y): (SVector<Hyper<N>, N>, SVector<Hyper<N>, N>)| {
            discrete.discrete_lagrangian(model, Hyper::from_re(t), Hyper::from_re(h), &x, &y)
        },
        (q0, q1),
    );
    (d1, d2, d12)
}

/// p_{k+1} − p_k = (D1 + D2) L_d(q0, q1) + f_d⁻ + f_d⁺, with (D1 + D2) L_d the derivative of
/// L_d along the common shift (q0 + ε, q1 + ε): no O(|p|) cancellation.
pub(crate) fn momentum_increment<Ld: DiscreteLagrangian, L: Lagrangian<N>, const N: usize>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &SVector<f64, N>,
    q1: &SVector<f64, N>,
) -> SVector<f64, N> {
    let (_, mut increment) = gradient(
        |shift: SVector<DualSVec64<N>, N>| {
            let start = q0.map(DualVec::from_re) + shift;
            let end = q1.map(DualVec::from_re) + shift;
            discrete.discrete_lagrangian(
                model,
                DualVec::from_re(t),
                DualVec::from_re(h),
                &start,
                &end,
            )
        },
        &SVector::zeros(),
    );
    if L::FORCED {
        let forces = discrete.discrete_forces(model, t, h, q0, q1);
        increment += forces.minus + forces.plus;
    }
    increment
}

/// The exact Jacobian of the step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) of a discrete Lagrangian at
/// a solved step (implicit function theorem on the discrete Euler–Lagrange equations):
///
/// ∂q_{k+1}/∂q_k = −J⁻¹ (D11 L_d + ∂f_d⁻/∂q_k),  ∂q_{k+1}/∂p_k = −J⁻¹,
/// ∂p_{k+1}/∂(·) = (D21 L_d + ∂f_d⁺/∂q_k) ∂q_k/∂(·) + (D22 L_d + ∂f_d⁺/∂q_{k+1}) ∂q_{k+1}/∂(·),
///
/// with J = D12 L_d + ∂f_d⁻/∂q_{k+1}.
pub(crate) fn discrete_tangent_map<Ld: DiscreteLagrangian, L: Lagrangian<N>, const N: usize>(
    discrete: &Ld,
    model: &L,
    t: f64,
    h: f64,
    q0: &SVector<f64, N>,
    q1: &SVector<f64, N>,
) -> Result<TangentMap<N>, StepFailure> {
    let (_, _, d12) = mixed_derivatives(discrete, model, t, h, q0, q1);
    let second = |first: bool| {
        hessian(
            |x: SVector<Dual2Vec<f64, Const<N>>, N>| {
                let (a, b) = if first {
                    (x, q1.map(Dual2Vec::from_re))
                } else {
                    (q0.map(Dual2Vec::from_re), x)
                };
                discrete.discrete_lagrangian(
                    model,
                    Dual2Vec::from_re(t),
                    Dual2Vec::from_re(h),
                    &a,
                    &b,
                )
            },
            if first { q0 } else { q1 },
        )
        .2
    };
    let (d11, d22) = (second(true), second(false));
    let mut minus_q0 = SMatrix::<f64, N, N>::zeros();
    let mut minus_q1 = SMatrix::<f64, N, N>::zeros();
    let mut plus_q0 = SMatrix::<f64, N, N>::zeros();
    let mut plus_q1 = SMatrix::<f64, N, N>::zeros();
    if L::FORCED {
        let forces = |plus: bool, first: bool| {
            jacobian(
                |x: SVector<DualSVec64<N>, N>| {
                    let (a, b) = if first {
                        (x, q1.map(DualVec::from_re))
                    } else {
                        (q0.map(DualVec::from_re), x)
                    };
                    let f = discrete.discrete_forces(
                        model,
                        DualVec::from_re(t),
                        DualVec::from_re(h),
                        &a,
                        &b,
                    );
                    if plus { f.plus } else { f.minus }
                },
                if first { q0 } else { q1 },
            )
            .1
        };
        minus_q0 = forces(false, true);
        minus_q1 = forces(false, false);
        plus_q0 = forces(true, true);
        plus_q1 = forces(true, false);
    }
    let inverse = invert_small(&(d12 + minus_q1)).ok_or(StepFailure::SingularMatrix)?;
    let qq = -(inverse * (d11 + minus_q0));
    let qy = -inverse;
    let end = d22 + plus_q1;
    let yq = d12.transpose() + plus_q0 + end * qq;
    let yy = end * qy;
    Ok(TangentMap { qq, qy, yq, yy })
}
