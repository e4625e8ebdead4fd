//! Symplectic Euler, its adjoint and Störmer–Verlet on Hamilton's equations: one kick, drift,
//! kick step with the weights (a, b) of [`Kicks`].
//!
//! # Discrete equations
//! With g = ∂H/∂q − f_H and t' = t_k + h (the module docs of [`crate::method::hamiltonian`]):
//!
//! P = p_k − a h g(t_k, q_k, P),
//! q_{k+1} = q_k + a h ∂H/∂p(t_k, q_k, P) + b h ∂H/∂p(t', q_{k+1}, P),
//! p_{k+1} = P − b h g(t', q_{k+1}, P).
//!
//! (a, b) = (1, 0) is the symplectic Euler method (HLW eq. VI.3.1), (0, 1) its adjoint
//! (VI.3.2), (½, ½) Störmer–Verlet (VI.3.4). The first kick starts from the explicit kick
//! P = p_k − a h g(t_k, q_k, p_k) and, unless g does not depend on p (a separable H without a
//! force), is solved by Newton's method for P − p_k with the Jacobian
//! I + a h ∂g/∂p; the drift, unless ∂H/∂p does not depend on q (a separable H) or b = 0,
//! by Newton's method for q_{k+1} − q_k from h ∂H/∂p(t_k, q_k, P) with the Jacobian
//! I − b h (∂²H/∂q∂p)ᵀ. The increments are the unknowns themselves and the kicks' sums
//! −a h g − b h g: no cancellation of O(|p|) or O(|q|).
//!
//! # Properties
//! Symplectic Euler and its adjoint: order 1, not symmetric (each is the other's adjoint);
//! Störmer–Verlet: order 2, symmetric. All symplectic without a force.
//!
//! # References
//! Hairer, Lubich, Wanner, *Geometric numerical integration* (2006), eqs. VI.3.1, VI.3.2 and
//! VI.3.4, Theorems VI.3.3 and VI.3.4; Leok & Zhang, IMA J. Numer. Anal. 31 (2011), §3.

use super::{Derivatives, identity_plus, offset, solve};
use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure, require_positive};
use crate::linalg::invert_small;
use crate::method::variational::composition::{Composable, Composition, Scheme};
use crate::method::variational::discrete_lagrangian::Kicks;
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::canonical;
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OMatrix, OVector};

/// Options of the partitioned methods on Hamilton's equations: symplectic Euler, its adjoint
/// or Störmer–Verlet (see the module docs).
///
/// ```
/// use nalgebra::{SVector, U1};
/// use svi::method::hamiltonian::Partitioned;
/// use svi::{Canonical, Hamiltonian, HamiltonianStructure, Integrator, Scalar};
///
/// /// A relativistic oscillator, H = √(1 + p²) + q²/2.
/// struct Relativistic;
/// impl Hamiltonian<U1> for Relativistic {
///     const TIME_DEPENDENT: bool = false;
///     const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;
///     fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
///         (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
///     }
/// }
///
/// let integrator = Integrator::new(Canonical::new(Relativistic), Partitioned::stormer_verlet());
/// let run = integrator
///     .run(0.0, svi::Initial::Momentum { q: SVector::from([1.0]), p: SVector::from([0.0]) },
///          0.01, 10.0, &mut ())
///     .unwrap();
/// assert!(run.last.q[0].abs() <= 1.0);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Partitioned {
    kicks: Kicks,
    /// Cap on Newton iterations per solve.
    pub max_iterations: usize,
}

impl Default for Partitioned {
    /// Störmer–Verlet.
    fn default() -> Self {
        Partitioned::stormer_verlet()
    }
}

impl Partitioned {
    /// The method with the kicks `kicks`.
    fn with_kicks(kicks: Kicks) -> Self {
        Partitioned {
            kicks,
            max_iterations: 50,
        }
    }

    /// Symplectic Euler, p_{k+1} = p_k − h g(t_k, q_k, p_{k+1}),
    /// q_{k+1} = q_k + h ∂H/∂p(t_k, q_k, p_{k+1}) (HLW eq. VI.3.1).
    pub fn symplectic_euler() -> Self {
        Partitioned::with_kicks(Kicks::Start)
    }

    /// The adjoint symplectic Euler method, q_{k+1} = q_k + h ∂H/∂p(t', q_{k+1}, p_k),
    /// p_{k+1} = p_k − h g(t', q_{k+1}, p_k) (HLW eq. VI.3.2).
    pub fn adjoint_symplectic_euler() -> Self {
        Partitioned::with_kicks(Kicks::End)
    }

    /// Störmer–Verlet (HLW eq. VI.3.4).
    pub fn stormer_verlet() -> Self {
        Partitioned::with_kicks(Kicks::Split)
    }

    /// Cap Newton iterations per solve.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }

    /// The weights of the two kicks.
    pub fn kicks(&self) -> Kicks {
        self.kicks
    }
}

impl Composable for Partitioned {
    /// `yoshida4-h`, `kahan-li6-h`, `kahan-li8-h` (compositions of Störmer–Verlet).
    fn composed_name(&self, scheme: Scheme) -> &'static str {
        match scheme {
            Scheme::Yoshida4 => "yoshida4-h",
            Scheme::KahanLi6 => "kahan-li6-h",
            Scheme::KahanLi8 => "kahan-li8-h",
        }
    }
}

impl Composition<Partitioned> {
    /// The composition `scheme` of Störmer–Verlet on Hamilton's equations
    /// ([`Partitioned::stormer_verlet`]).
    pub fn hamiltonian(scheme: Scheme) -> Self {
        Composition::with_base(scheme, Partitioned::stormer_verlet())
    }
}

/// Buffers of a run of a [`Partitioned`] method.
#[derive(Debug, Clone)]
pub struct PartitionedWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    derivatives: Derivatives<N>,
    /// Whether H = T(p) + V(t, q).
    separable: bool,
    /// Newton's method on N unknowns (the first kick's P − p_k, the drift's q_{k+1} − q_k).
    newton: Newton,
    unknown: DVector<f64>,
    /// P, the momentum after the first kick of the last step.
    kick: OVector<f64, N>,
}

impl<N: Dimension> Method<N> for Partitioned
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;

    type Workspace = PartitionedWorkspace<N>;

    fn info(&self) -> MethodInfo {
        let (name, order, symmetric) = match self.kicks {
            Kicks::Start => ("symplectic-euler-h", 1, false),
            Kicks::End => ("symplectic-euler-adjoint-h", 1, false),
            Kicks::Split => ("verlet-h", 2, true),
        };
        MethodInfo {
            name,
            order,
            symmetric,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Hamilton,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<PartitionedWorkspace<N>, Error> {
        require_positive("h", h)?;
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        let separable = canonical::structure(model).is_separable();
        // The explicit steps of a separable unforced H solve nothing: no n × n matrix.
        let unknowns = if separable && !canonical::forced(model) {
            0
        } else {
            n.value()
        };
        Ok(PartitionedWorkspace {
            derivatives: Derivatives::new(model, n),
            separable,
            newton: Newton::new(unknowns, self.max_iterations),
            unknown: DVector::zeros(n.value()),
            kick: OVector::zeros_generic(n, nalgebra::U1),
        })
    }

    /// On a separable unforced H without a Lagrangian (a sum of local terms,
    /// [`crate::model::local_hamiltonian`]) the steps are explicit and every derivative is
    /// assembled term by term: O(n) memory, no n × n matrix.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        canonical::structure(model).is_separable()
            && !canonical::forced(model)
            && model
                .hamiltonian_form()
                .is_some_and(|form| form.without_lagrangian())
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut PartitionedWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let PartitionedWorkspace {
            derivatives,
            separable,
            newton,
            unknown,
            kick,
        } = workspace;
        let (q0, p0) = (&state.q, &state.y);
        derivatives.start(model, t, q0, p0)?;
        let (a, b) = self.kicks.weights();
        let (a, b, end) = (a * h, b * h, t + h);
        if *separable && !derivatives.forced {
            // Explicit: each kick takes ∂H/∂q = ∂V/∂q alone, the drift ∂H/∂p = T′(p) alone.
            increment.y.fill(0.0);
            if a != 0.0 {
                let g = derivatives.position_gradient(model, t, q0, p0)?;
                increment.y.zip_apply(&g, |d, g| *d = -a * g);
            }
            kick.zip_zip_apply(p0, &increment.y, |k, p, d| *k = p + d);
            let velocity = derivatives.velocity(model, t, q0, kick)?;
            increment.q.zip_apply(&velocity, |d, v| *d = h * v);
            if b != 0.0 {
                let q1 = offset(q0, 1.0, increment.q.as_slice());
                let g = derivatives.position_gradient(model, end, &q1, kick)?;
                increment.y.zip_apply(&g, |d, g| *d -= b * g);
            }
            return Ok(StepReport {
                iterations: 0,
                evaluations: derivatives.evaluations,
                factorizations: 0,
                analyses: 0,
            });
        }
        let mut iterations = 0;
        // The first kick, its offset P − p_k in `increment.y`.
        if a == 0.0 {
            increment.y.fill(0.0);
        } else {
            let (g, _) = derivatives.field(model, t, q0, p0)?;
            increment.y.zip_apply(&g, |d, g| *d = -a * g);
            if !*separable || derivatives.forced {
                unknown.copy_from_slice(increment.y.as_slice());
                iterations += solve(newton, unknown, |z, jacobian, residual| {
                    let p = offset(p0, 1.0, z.as_slice());
                    let field = derivatives.linearised(model, t, q0, &p)?;
                    for ((r, z), g) in residual.iter_mut().zip(z.iter()).zip(field.g.iter()) {
                        *r = z + a * g;
                    }
                    identity_plus(a, &field.gp, jacobian.as_mut_slice());
                    Ok(())
                })?;
                increment.y.copy_from_slice(unknown.as_slice());
            }
        }
        kick.zip_zip_apply(p0, &increment.y, |k, p, d| *k = p + d);
        let kick: &OVector<f64, N> = kick;
        // The drift, from h ∂H/∂p(t_k, q_k, P) (exact for a separable H, or b = 0).
        let (_, velocity) = derivatives.gradient(model, t, q0, kick)?;
        increment.q.zip_apply(&velocity, |d, v| *d = h * v);
        if !*separable && b != 0.0 {
            unknown.copy_from_slice(increment.q.as_slice());
            iterations += solve(newton, unknown, |z, jacobian, residual| {
                let q = offset(q0, 1.0, z.as_slice());
                let second = derivatives.second(model, end, &q, kick)?;
                for (((r, z), start), end) in residual
                    .iter_mut()
                    .zip(z.iter())
                    .zip(velocity.iter())
                    .zip(second.hp.iter())
                {
                    *r = z - a * start - b * end;
                }
                identity_plus(-b, &second.qp.transpose(), jacobian.as_mut_slice());
                Ok(())
            })?;
            increment.q.copy_from_slice(unknown.as_slice());
        }
        // The second kick.
        if b != 0.0 {
            let q1 = offset(q0, 1.0, increment.q.as_slice());
            let (g, _) = derivatives.field(model, end, &q1, kick)?;
            increment.y.zip_apply(&g, |d, g| *d -= b * g);
        }
        Ok(StepReport {
            iterations,
            evaluations: derivatives.evaluations,
            factorizations: iterations,
            analyses: 0,
        })
    }

    /// q̇ = ∂H/∂p: H's gradient for a model written as H, the cached M⁻¹p for a constant
    /// mass.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &PartitionedWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        Ok(workspace.derivatives.velocity_into(model, t, q, p, v))
    }

    /// The implicit function theorem on the three lines of the step: with S the derivatives
    /// at (t_k, q_k, P) and E at (t', q_{k+1}, P),
    ///
    /// dP = (I + a h S_gp)⁻¹ (dp_k − a h S_gq dq_k),
    /// (I − b h E_qpᵀ) dq_{k+1} = (I + a h S_qpᵀ) dq_k + (a h S_pp + b h E_pp) dP,
    /// dp_{k+1} = dP − b h (E_gq dq_{k+1} + E_gp dP).
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut PartitionedWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let mut increment = State::zeros(state.dimension());
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let (a, b) = self.kicks.weights();
        let (a, b) = (a * h, b * h);
        let n = state.dimension();
        let identity = OMatrix::<f64, N, N>::identity_generic(n, n);
        let kick = workspace.kick.clone();
        let derivatives = &mut workspace.derivatives;
        // ∂P/∂q_k, ∂P/∂p_k and the drift's dependence on q_k and P.
        let (mut pq, mut pp) = (OMatrix::zeros_generic(n, n), identity.clone());
        let (mut drift_q, mut drift_p) = (identity.clone(), OMatrix::zeros_generic(n, n));
        if a != 0.0 {
            let start = derivatives.linearised(model, t, &state.q, &kick)?;
            let inverse =
                invert_small(&(&identity + &start.gp * a)).ok_or(StepFailure::SingularMatrix)?;
            pq = -(&inverse * &start.gq) * a;
            pp = inverse;
            drift_q += start.qp.transpose() * a;
            drift_p += start.pp * a;
        }
        let (qq, qy, yq, yy) = if b != 0.0 {
            let q1 = &state.q + &increment.q;
            let end = derivatives.linearised(model, t + h, &q1, &kick)?;
            drift_p += &end.pp * b;
            let inverse = invert_small(&(&identity - end.qp.transpose() * b))
                .ok_or(StepFailure::SingularMatrix)?;
            let qq = &inverse * (drift_q + &drift_p * &pq);
            let qy = &inverse * &drift_p * &pp;
            let yq = &pq - (&end.gq * &qq + &end.gp * &pq) * b;
            let yy = &pp - (&end.gq * &qy + &end.gp * &pp) * b;
            (qq, qy, yq, yy)
        } else {
            (drift_q + &drift_p * &pq, &drift_p * &pp, pq, pp)
        };
        Ok((increment, TangentMap { qq, qy, yq, yy }, report))
    }
}
