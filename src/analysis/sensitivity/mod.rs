//! Derivatives of a whole run: forward sensitivities and the discrete adjoint, with respect
//! to the initial state and to a model's parameters.
//!
//! # The discrete map and its derivatives
//! A fixed-step run is the composition x_K = Φ_{K−1} ∘ ⋯ ∘ Φ_0 (x_0) of the method's step
//! maps on the state x = (q, y) (y = p or q̇, the method's [`crate::Coordinates`]). Its
//! derivatives are those of the discrete map, not of the differential equation: the
//! product of the steps' exact tangent maps ∂x_{k+1}/∂x_k
//! ([`crate::method::Method::tangent_map`], the implicit function theorem on each step's
//! converged equations).
//!
//! Parameters θ that enter L join the state as coordinates with θ̇ = 0 held by a force
//! ([`crate::model::parametric::WithParameters`]), so that the same tangent maps carry the
//! columns ∂x_{k+1}/∂θ, by automatic differentiation of L(t, q, q̇; θ)
//! ([`crate::model::parametric::Parametric`]). Write X = (z, y) for the state of the
//! lifted run, z = (q, θ). Parameters that only choose the start
//! ([`crate::model::parametric::Parametric::enters_lagrangian`] `false`, Kepler's e) enter
//! through C alone: the run is then the model's own, z = q, at its size and with its
//! structure (a constant-mass model keeps its Hessian-free steps).
//!
//! - **Forward sensitivities** ([`crate::Integrator::sensitivities`]):
//!   ∂(q, q̇)(t_k)/∂(q₀, q̇₀ or p₀, θ) = G_k Φ_{k−1} ⋯ Φ_0 C, where C = ∂X_0/∂(q₀, q̇₀ or p₀, θ)
//!   is the start (the Legendre map for methods in momenta, and the model's initial state as
//!   a function of θ for [`Start::Model`]) and G_k = ∂(q, q̇)/∂X_k the end (the inverse
//!   Legendre map: ∂q̇ = M⁻¹(∂p − L_{q̇z} ∂z)). One product per step: cheap for few
//!   parameters and small systems. Each step keeps what [`crate::Method::adjoint_step`]
//!   keeps and applies Φ_k to the product so far ([`crate::Method::tangent_apply`]): for
//!   constant-mass SVI the step's own fixed-point iteration, linearised, on each column,
//!   whose round-off does not grow as 1/h as the factorised tangent map's does (on 10⁵
//!   Kepler steps the product of tangent maps was off by 7·10⁻⁶, the stage form by 10⁻¹⁰,
//!   `cargo bench --bench adjoint`).
//! - **The discrete adjoint** ([`crate::Integrator::gradient`]): for a loss
//!   J = Σ_j ℓ_j(t_{k_j}, q, q̇) over output steps k_j, λ_K = G_Kᵀ∇ℓ, then
//!   λ_k = Φ_kᵀ λ_{k+1} + G_kᵀ∇ℓ_k down to λ_0, and ∇J = Cᵀλ_0. This is the exact gradient
//!   of the discrete J, and for a symplectic method the adjoint recursion is itself the
//!   method's symplectic partner (Sanz-Serna, SIAM Review 58, 2016). The states of the
//!   forward run are kept at checkpoints ([`Checkpoints`], default ⌈√K⌉ of them); each
//!   segment between two is run again, keeping what each step's adjoint needs
//!   ([`crate::Method::adjoint_step`]: its tangent map, or for constant-mass SVI the force
//!   Jacobians at its quadrature points, whose Φᵀλ is a transposed fixed point), and swept
//!   back, so at most about 2√K states and steps' adjoints are held at once.
//!
//! Outputs are the grid steps k with k mod `every` = 0 and the last step (the grid of
//! [`crate::Integrator::try_run`]: t_k = t₀ + k h, the last step shortened to end at t_end).
//!
//! # Example
//! The harmonic oscillator L = ½ q̇² − ½ ω² q², written once with ω as a parameter: the
//! gradient of q(T) with respect to q₀, q̇₀ and ω, against the exact
//! q(T) = q₀ cos ωT + (q̇₀/ω) sin ωT (the midpoint rule's phase error is O(h²)).
//! ```
//! use nalgebra::{SVector, U1};
//! use svi::sensitivity::{Checkpoints, Loss, SensitivityRun, Start};
//! use svi::{Initial, Integrator, Lagrangian, Midpoint, Parametric, Scalar, VariationalIntegrator};
//!
//! struct Oscillator {
//!     omega: f64,
//! }
//!
//! impl Lagrangian<U1> for Oscillator {
//!     const TIME_DEPENDENT: bool = false;
//!     fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
//!         self.lagrangian_with(&[D::from(self.omega)], t, q, v)
//!     }
//! }
//!
//! impl Parametric<U1> for Oscillator {
//!     fn parameter_names(&self) -> Vec<String> {
//!         vec!["omega".into()]
//!     }
//!     fn parameter_values(&self) -> Vec<f64> {
//!         vec![self.omega]
//!     }
//!     fn lagrangian_with<D: Scalar>(&self, theta: &[D], _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
//!         (v[0] * v[0] - theta[0] * theta[0] * q[0] * q[0]) * 0.5
//!     }
//! }
//!
//! /// J = q(T): the last of the two outputs (the start is output 0).
//! struct Final;
//! impl Loss for Final {
//!     fn loss<D: Scalar>(&self, output: usize, _t: f64, q: &[D], _v: &[D]) -> D {
//!         if output == 1 { q[0] } else { D::from(0.0) }
//!     }
//! }
//!
//! let (omega, t_end) = (2.0, 3.0);
//! let integrator = Integrator::new(Oscillator { omega }, VariationalIntegrator::new(Midpoint));
//! let start = Initial::Velocity { q: SVector::from([1.0]), v: SVector::from([0.5]) };
//! let run = SensitivityRun::new(0.0, Start::Given(start), 1e-3, t_end).with_parameters(&["omega"]);
//! let gradient = integrator.gradient(&run, &Final, Checkpoints::default())?;
//! // ∂q(T)/∂q₀ = cos ωT, ∂q(T)/∂q̇₀ = sin(ωT)/ω, ∂q(T)/∂ω = −q₀T sin ωT + q̇₀(T cos ωT/ω − sin ωT/ω²).
//! let (c, s) = ((omega * t_end).cos(), (omega * t_end).sin());
//! let exact = [c, s / omega, -t_end * s + 0.5 * (t_end * c / omega - s / (omega * omega))];
//! let got = [gradient.initial[0], gradient.initial[1], gradient.parameters[0]];
//! for (got, exact) in got.iter().zip(exact) {
//!     assert!((got - exact).abs() < 1e-4, "{got} against {exact}");
//! }
//! # Ok::<(), svi::Error>(())
//! ```

mod adjoint;
mod forward;
mod lifted;

pub use adjoint::{Checkpoints, Gradient, Loss};
pub use forward::{Sensitivities, SensitivityPoint};

use crate::dimension::Dimension;
use crate::method::space::Initial;
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;

/// Where a differentiated run starts.
#[derive(Debug, Clone, PartialEq)]
pub enum Start<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The given state: the derivatives are taken with respect to its q₀ and its q̇₀ or p₀.
    Given(Initial<N>),
    /// The model's own initial state as a function of its parameters
    /// ([`crate::model::parametric::Parametric::initial_state_with`]): the derivatives are
    /// taken with respect to q₀, q̇₀ and θ, θ moving the start as well.
    Model,
}

/// A fixed-step run whose derivatives are asked for: its span, step, start, the parameters
/// differentiated, and which steps are outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityRun<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// Start time.
    pub t0: f64,
    /// The initial state.
    pub start: Start<N>,
    /// The step h.
    pub h: f64,
    /// The end of the span.
    pub t_end: f64,
    /// The names of the parameters differentiated (none: only the initial state).
    pub parameters: Vec<String>,
    /// Every how many steps an output is taken (the start and the last step always are).
    pub every: usize,
}

impl<N: Dimension> SensitivityRun<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// A run from `t0` to `t_end` with step `h` from `start`, differentiated with respect to
    /// the initial state only, with outputs at the start and the end.
    pub fn new(t0: f64, start: Start<N>, h: f64, t_end: f64) -> Self {
        SensitivityRun {
            t0,
            start,
            h,
            t_end,
            parameters: Vec::new(),
            every: usize::MAX,
        }
    }

    /// The same run, differentiated with respect to the parameters `names` as well.
    pub fn with_parameters(mut self, names: &[&str]) -> Self {
        self.parameters = names.iter().map(|&name| name.to_owned()).collect();
        self
    }

    /// The same run with an output every `every` steps.
    pub fn with_outputs_every(mut self, every: usize) -> Self {
        self.every = every;
        self
    }
}
