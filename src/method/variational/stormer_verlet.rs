//! The Störmer–Verlet method: the variational integrator of the trapezoidal discrete
//! Lagrangian, explicit where the Lagrangian allows it.
//!
//! # Discrete equations
//! The discrete Lagrangian is [`Trapezoid`], L_d = ½h L(t_k, q_k, v) + ½h L(t_k + h, q_{k+1}, v)
//! with v = (q_{k+1} − q_k)/h, and the discrete forces are f_d⁻ = (h/2) f_L(t_k, q_k, v),
//! f_d⁺ = (h/2) f_L(t_k + h, q_{k+1}, v) (slides' "Störmer–Verlet"; Marsden & West 2001,
//! §2.7). For a [`crate::Structure::ConstantMass`] Lagrangian, L = ½ q̇ᵀMq̇ − V(t, q), the
//! implicit discrete Euler–Lagrange equations solve explicitly (kick–drift–kick,
//! [`crate::method::variational::kick_drift_kick`] with [`Kicks::Split`]):
//!
//! p_{k+½} = p_k + (h/2) (∂L/∂q(t_k, q_k) + f_L(t_k, q_k, v)),
//! q_{k+1} = q_k + h v,  v = M⁻¹ p_{k+½},
//! p_{k+1} = p_{k+½} + (h/2) (∂L/∂q(t_k + h, q_{k+1}) + f_L(t_k + h, q_{k+1}, v)).
//!
//! Without a force this needs no Newton iteration and no Hessian, and one gradient ∂L/∂q
//! per step: the force at q_{k+1} is reused as the force at q_k of the next step. With a
//! force f_L that depends on q̇ the first kick is implicit in v only (Newton's method on N
//! unknowns, no Hessian of L). Every other Lagrangian takes the implicit path of
//! [`VariationalIntegrator`]`<`[`Trapezoid`]`>` (for a mass matrix that depends on q not the
//! Lobatto IIIA–IIIB pair, see [`Trapezoid`]): the same
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

use crate::dimension::Dimension;
use crate::error::Error;
use crate::error::StepFailure;
use crate::method::Method;
use crate::method::variational::discrete_lagrangian::{Kicks, Trapezoid};
use crate::method::variational::variational_integrator::{
    VariationalIntegrator, VariationalWorkspace,
};
use crate::method::{Coordinates, Equations, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};

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

/// Buffers of a Störmer–Verlet run: those of the variational integrator of [`Trapezoid`],
/// on its explicit path ([`Kicks::Split`]) for a constant-mass Lagrangian.
pub type StormerVerletWorkspace<N> = VariationalWorkspace<N>;

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
            equations: Equations::Lagrange,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<StormerVerletWorkspace<N>, Error> {
        self.implicit().workspace_with(model, h, Some(Kicks::Split))
    }

    /// The explicit kick–drift–kick step for a constant mass, else the implicit trapezoid.
    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut StormerVerletWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        self.implicit()
            .step(model, workspace, t, h, state, increment)
    }

    fn verlet_fractions(&self) -> Option<&[f64]> {
        Some(&[1.0])
    }

    /// An unforced sum of terms: the explicit path (M⁻¹ from the terms' blocks, forces
    /// assembled in place) for a constant mass, else the implicit trapezoid by sparse Newton.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        model.terms().is_some() && !L::FORCED
    }

    /// q̇ = M⁻¹p from the explicit path's cached inverse (a constant mass matrix, checked by
    /// the integrator's first run); the implicit path's kept map otherwise.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &StormerVerletWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        self.implicit().velocity_into(model, workspace, t, q, p, v)
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut StormerVerletWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        self.implicit().tangent_map(model, workspace, t, h, state)
    }
}
