//! The Störmer–Verlet method: the variational integrator of the trapezoidal discrete
//! Lagrangian, explicit where the Lagrangian allows it.
//!
//! # Discrete equations
//! The discrete Lagrangian is [`Trapezoid`], L_d = ½h L(t_k, q_k, v) + ½h L(t_k + h, q_{k+1}, v)
//! with v = (q_{k+1} − q_k)/h, and the discrete forces are f_d⁻ = (h/2) f_L(t_k, q_k, v),
//! f_d⁺ = (h/2) f_L(t_k + h, q_{k+1}, v) (slides' "Störmer–Verlet"; Marsden & West 2001,
//! §2.7). For a [`Structure::ConstantMass`] Lagrangian, L = ½ q̇ᵀMq̇ − V(t, q), the implicit
//! discrete Euler–Lagrange equations solve explicitly (kick–drift–kick):
//!
//! p_{k+½} = p_k + (h/2) (∂L/∂q(t_k, q_k) + f_L(t_k, q_k, v)),
//! q_{k+1} = q_k + h v,  v = M⁻¹ p_{k+½},
//! p_{k+1} = p_{k+½} + (h/2) (∂L/∂q(t_k + h, q_{k+1}) + f_L(t_k + h, q_{k+1}, v)).
//!
//! Without a force this needs no Newton iteration and no Hessian, and one gradient ∂L/∂q
//! per step: the force at q_{k+1} is kept in the workspace and reused as the force at q_k of
//! the next step (recognised by position, to within the rounding of the stepping loop's
//! compensated summation). The momentum increment is (h/2)(F_k + F_{k+1}), free of
//! cancellation. With a force f_L (which may depend on q̇, like friction) the first kick is
//! implicit in v only: p_{k+½} = r + (h/2) f_L(t_k, q_k, M⁻¹p_{k+½}), r = p_k + (h/2) ∂L/∂q,
//! solved by Newton's method on N unknowns with the Jacobian I − (h/2) ∂f_L/∂q̇ M⁻¹ (no
//! Hessian of L; one iteration when f_L does not depend on q̇, and none of it changes
//! anything when f_L = 0). Every other Lagrangian takes the implicit path of
//! [`VariationalIntegrator`]`<`[`Trapezoid`]`>` (the Lobatto IIIA–IIIB pair): the same
//! discrete equations, solved by Newton's method on q_{k+1}.
//!
//! # Properties
//! Order 2; symmetric; symplectic (without forces). The step equals
//! `VariationalIntegrator::new(Trapezoid)`'s to round-off.
//!
//! # References
//! Porcù & Penati (OctConf 2013), "Variational integrators" 3) and the Störmer–Verlet
//! error table on the harmonic oscillator; Hairer, Lubich, Wanner, *Geometric numerical
//! integration* (2006), §I.3 and eq. VI.6.9; Hairer, Lubich, Wanner, *Geometric numerical
//! integration illustrated by the Störmer–Verlet method*, Acta Numerica (2003).

use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::error::StepFailure;
use crate::method::Method;
use crate::method::variational::discrete_lagrangian::Trapezoid;
use crate::method::variational::variational_integrator::VariationalIntegrator;
use crate::method::variational::variational_integrator::{
    VariationalWorkspace, discrete_tangent_map,
};
use crate::method::{Coordinates, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::Structure;
use crate::model::derived::LagrangianExt;
use crate::model::derived::cached_mass_inverse;
use crate::model::mass_inverse::MassInverse;
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Options of the Störmer–Verlet method.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct StormerVerlet {
    /// Cap on Newton iterations per step (implicit path and forced kicks only).
    pub max_iterations: usize,
}

impl Default for StormerVerlet {
    fn default() -> Self {
        StormerVerlet { max_iterations: 50 }
    }
}

impl StormerVerlet {
    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }

    /// The implicit method with the same discrete equations.
    fn implicit(&self) -> VariationalIntegrator<Trapezoid> {
        VariationalIntegrator::new(Trapezoid).with_max_iterations(self.max_iterations)
    }
}

/// Buffers of the explicit kick–drift–kick path, sized once per run.
#[derive(Debug, Clone)]
struct Explicit<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// M⁻¹, from the first step.
    mass_inverse: Option<MassInverse<N>>,
    /// ∂L/∂q at the start of the step; after a step, at its end (the next step's start when
    /// it starts there, see `reusable`).
    start_force: OVector<f64, N>,
    end_force: OVector<f64, N>,
    /// Where `start_force` was evaluated after the last step: (t, tolerance on q) and the
    /// position in `reusable_at`; `None` when it is not reusable.
    reusable: Option<(f64, f64)>,
    reusable_at: OVector<f64, N>,
    /// The half-step momentum, and q̇ = M⁻¹ of it.
    kick: OVector<f64, N>,
    velocity: OVector<f64, N>,
    /// The end position q_{k+1}.
    end: OVector<f64, N>,
    /// Newton on the half-step momentum (forced models only; n × n, made on first use).
    newton: Option<Newton>,
    max_iterations: usize,
    half: DVector<f64>,
}

/// Buffers of a Störmer–Verlet run.
#[derive(Debug, Clone)]
pub struct StormerVerletWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The implicit path (Lagrangians without constant mass matrix).
    implicit: Option<VariationalWorkspace<N>>,
    /// The explicit path ([`Structure::ConstantMass`]).
    explicit: Option<Explicit<N>>,
}

impl<N: Dimension> Method<N> for StormerVerlet
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;
    const COMPOSES_VERLET: bool = true;

    type Workspace = StormerVerletWorkspace<N>;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "verlet",
            order: 2,
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<StormerVerletWorkspace<N>, Error> {
        // The implicit path's buffers (a Newton matrix of n × n) only where it runs.
        let implicit = match L::STRUCTURE {
            Structure::General => Some(self.implicit().workspace(model, h)?),
            Structure::ConstantMass => None,
        };
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        let zero = || OVector::<f64, N>::zeros_generic(n, U1);
        let explicit = (L::STRUCTURE == Structure::ConstantMass).then(|| Explicit {
            mass_inverse: None,
            start_force: zero(),
            end_force: zero(),
            reusable: None,
            reusable_at: zero(),
            kick: zero(),
            velocity: zero(),
            end: zero(),
            newton: None,
            max_iterations: self.max_iterations,
            half: DVector::zeros(if L::FORCED { n.value() } else { 0 }),
        });
        Ok(StormerVerletWorkspace { implicit, explicit })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut StormerVerletWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        match (&mut workspace.explicit, &mut workspace.implicit) {
            (Some(explicit), _) => kick_drift_kick(model, explicit, t, h, state, increment),
            (None, Some(implicit)) => self
                .implicit()
                .step(model, implicit, t, h, state, increment),
            (None, None) => Err(StepFailure::Unsupported {
                option: "workspace",
                reason: "a Störmer–Verlet workspace has neither path",
            }),
        }
    }

    fn verlet_fractions(&self) -> Option<&[f64]> {
        Some(&[1.0])
    }

    /// An unforced sum of terms: the explicit path (M⁻¹ from the terms' blocks, forces
    /// assembled in place) for a constant mass, else the implicit trapezoid by sparse Newton.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        model.terms().is_some() && !L::FORCED
    }

    /// q̇ = M⁻¹p from the explicit path's cached inverse (a constant mass matrix, checked once
    /// per run); the implicit path's kept map otherwise.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &StormerVerletWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        match (&workspace.explicit, &workspace.implicit) {
            (Some(explicit), _) => Ok(match &explicit.mass_inverse {
                Some(inverse) => {
                    inverse.apply_into(p, v);
                    true
                }
                None => false,
            }),
            (None, Some(implicit)) => self.implicit().velocity_into(model, implicit, t, q, p, v),
            (None, None) => Ok(false),
        }
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut StormerVerletWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let mut increment = State::zeros(state.dimension());
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let q1 = &state.q + &increment.q;
        let tangent = discrete_tangent_map(&Trapezoid, model, t, h, &state.q, &q1)?;
        Ok((increment, tangent, report))
    }
}

/// One explicit step of a constant-mass Lagrangian, in the workspace's buffers (nothing
/// allocated per step).
fn kick_drift_kick<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    explicit: &mut Explicit<N>,
    t: f64,
    h: f64,
    state: &State<N>,
    increment: &mut State<N>,
) -> Result<StepReport, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = state.dimension();
    let Explicit {
        mass_inverse,
        start_force,
        end_force,
        reusable,
        reusable_at,
        kick,
        velocity,
        end,
        newton,
        max_iterations,
        half: half_momentum,
    } = explicit;
    let mass_inverse = cached_mass_inverse(mass_inverse, model, t, &state.q, &state.y)?;
    let half = 0.5 * h;
    let mut evaluations = 1;
    // The force at q_k is the last step's end force when the step starts where that one
    // ended (to within the rounding of the stepping loop's compensated summation); the
    // position is checked inside the kick.
    let check = reusable.take().and_then(|(time, tolerance)| {
        (!L::TIME_DEPENDENT || (time - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(time.abs()))
            .then_some(tolerance)
    });
    let reused = check.is_some()
        && kick_at(
            mass_inverse,
            half,
            state,
            start_force,
            check.map(|tolerance| (&*reusable_at, tolerance)),
            kick,
            velocity,
        );
    if !reused {
        evaluations += 1;
        mass_inverse.apply_into(&state.y, velocity);
        model.force_into(t, &state.q, velocity, start_force);
        // Unchecked, the kick always succeeds.
        kick_at(mass_inverse, half, state, start_force, None, kick, velocity);
    }
    let mut iterations = 0;
    if L::FORCED {
        // Kick: p_{k+½} = p_k + (h/2)(∂L/∂q + f_L(t_k, q_k, M⁻¹p_{k+½})), implicit in the
        // half-step momentum.
        let rest = kick.clone();
        let predicted =
            &rest + model.external_force(t, &state.q, &mass_inverse.apply(&rest)) * half;
        half_momentum.copy_from_slice(predicted.as_slice());
        let dense = mass_inverse.to_dense();
        iterations = newton
            .get_or_insert_with(|| Newton::new(n.value(), *max_iterations))
            .solve(half_momentum, |z, matrix, residual| {
                let momentum = OVector::<f64, N>::from_column_slice_generic(n, U1, z.as_slice());
                let force = model.external_force_jacobian(t, &state.q, &(&dense * &momentum));
                let value = &momentum - &rest - force.value * half;
                residual.copy_from_slice(value.as_slice());
                let jacobian =
                    OMatrix::<f64, N, N>::identity_generic(n, n) - &force.v * &dense * half;
                // Both column-major and N × N.
                matrix.as_mut_slice().copy_from_slice(jacobian.as_slice());
            })?;
        kick.copy_from_slice(half_momentum.as_slice());
        *start_force += model.external_force(t, &state.q, &mass_inverse.apply(kick));
        mass_inverse.apply_into(kick, velocity);
    }
    // Drift: q_{k+1} = q_k + h M⁻¹p_{k+½}, and the largest |q| at either end.
    let mut extent: f64 = 0.0;
    for (((d, e), q), v) in increment
        .q
        .as_mut_slice()
        .iter_mut()
        .zip(end.as_mut_slice())
        .zip(state.q.as_slice())
        .zip(velocity.as_slice())
    {
        *d = h * v;
        *e = q + *d;
        extent = extent.max(q.abs()).max(e.abs());
    }
    let end_t = t + h;
    // Kick: p_{k+1} = p_{k+½} + (h/2)(∂L/∂q + f_L) at the end; the momentum increment is
    // (h/2)(F_k + F_{k+1}), F = ∂L/∂q + f_L.
    // `end_force` keeps ∂L/∂q alone: it is the next step's start force.
    model.force_into(end_t, end, velocity, end_force);
    for ((d, a), b) in increment
        .y
        .as_mut_slice()
        .iter_mut()
        .zip(start_force.as_slice())
        .zip(end_force.as_slice())
    {
        *d = half * (a + b);
    }
    if L::FORCED {
        increment
            .y
            .axpy(half, &model.external_force(end_t, end, velocity), 1.0);
    }
    // A NaN position never matches (its extent is NaN, and so is the tolerance).
    *reusable = Some((end_t, 4.0 * f64::EPSILON * extent));
    std::mem::swap(reusable_at, end);
    std::mem::swap(start_force, end_force);
    Ok(StepReport {
        iterations,
        evaluations,
        // Newton's method factorises at every iteration.
        factorizations: iterations,
        analyses: 0,
    })
}

/// The kick p_{k+½} = p_k + (h/2) F_k into `kick` and the velocity M⁻¹p_{k+½} into
/// `velocity`, in one pass for a diagonal M. With `check = Some((at, tolerance))`, `force`
/// is the force at `at`, and the pass also checks that q_k is `at` to within `tolerance`
/// entry by entry; it returns `false` if not (the kick is then not the one of q_k).
#[inline]
fn kick_at<N: Dimension>(
    mass_inverse: &MassInverse<N>,
    half: f64,
    state: &State<N>,
    force: &OVector<f64, N>,
    check: Option<(&OVector<f64, N>, f64)>,
    kick: &mut OVector<f64, N>,
    velocity: &mut OVector<f64, N>,
) -> bool
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let kicks = kick
        .as_mut_slice()
        .iter_mut()
        .zip(state.y.as_slice())
        .zip(force.as_slice());
    let same = match (mass_inverse, check) {
        (MassInverse::Diagonal(inverse), None) => {
            for (((k, p), f), (v, m)) in
                kicks.zip(velocity.as_mut_slice().iter_mut().zip(inverse.as_slice()))
            {
                *k = p + half * f;
                *v = *k * m;
            }
            return true;
        }
        (MassInverse::Diagonal(inverse), Some((at, tolerance))) => {
            let mut same = true;
            for ((((k, p), f), (v, m)), (q, a)) in kicks
                .zip(velocity.as_mut_slice().iter_mut().zip(inverse.as_slice()))
                .zip(state.q.as_slice().iter().zip(at.as_slice()))
            {
                *k = p + half * f;
                *v = *k * m;
                same &= (q - a).abs() <= tolerance;
            }
            return same;
        }
        (_, None) => {
            for ((k, p), f) in kicks {
                *k = p + half * f;
            }
            true
        }
        (_, Some((at, tolerance))) => {
            let mut same = true;
            for (((k, p), f), (q, a)) in kicks.zip(state.q.as_slice().iter().zip(at.as_slice())) {
                *k = p + half * f;
                same &= (q - a).abs() <= tolerance;
            }
            same
        }
    };
    if same {
        mass_inverse.apply_into(kick, velocity);
    }
    same
}
