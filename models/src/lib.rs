//! # svi-models — the model zoo of `svi`
//!
//! Classical test problems for structure-preserving integrators, each written once against
//! `svi`'s public traits (a user's model looks exactly the same):
//!
//! | name | model | N | symmetry | invariants | exact solution |
//! | --- | --- | --- | --- | --- | --- |
//! | `oscillator` | [`HarmonicOscillator`] | 1 | — | — | yes |
//! | `pendulum` | [`Pendulum`] | 1 | — | — | yes (Jacobi elliptic) |
//! | `spring-pendulum` | [`SpringPendulum`] | 2 | — | — | — |
//! | `kepler` | [`Kepler`] | 2 | rotation | Runge–Lenz | yes (Kepler's equation) |
//! | `double-pendulum` | [`DoublePendulum`] | 2 | — | — | — |
//! | `damped-oscillator` | [`DampedOscillator`] | 1 | — | — | yes |
//! | `damped-pendulum` | [`DampedPendulum`] | 1 | — | — | only undamped (c = 0) |
//! | `driven-oscillator` | [`DrivenOscillator`] | 1 | — | — | yes |
//! | `henon-heiles` | [`HenonHeiles`] | 2 | — | — | — |
//! | `restricted-three-body` | [`RestrictedThreeBody`] | 2 | — | Jacobi constant | only μ = 0 (Kepler, rotating frame) |
//! | `nbody` | [`NBody`] | 18 (d per body, at run time: [`svi::Dyn`]) | translations, rotations | — | — |
//!
//! Models written as a Hamiltonian H(t, q, p) ([`svi::Hamiltonian`], with the H-side
//! companions of [`svi::model::hamiltonian`]) are registered as [`Canonical`]`<H>`, which is a
//! [`Lagrangian`] with the same companions, so they run by every method and front door:
//!
//! | name | model | N | H | symmetry | invariants | exact solution |
//! | --- | --- | --- | --- | --- | --- | --- |
//! | `kepler-h` | [`KeplerH`] | 2 | ∣p∣²/2 − 1/∣q∣ | rotation | Runge–Lenz | yes (Kepler's equation) |
//! | `pendulum-h` | [`PendulumH`] | 1 | p²/(2ml²) − mgl cos θ | — | — | yes (Jacobi elliptic) |
//! | `henon-heiles-h` | [`HenonHeilesH`] | 2 | ∣p∣²/2 + ∣q∣²/2 + λ(x²y − y³/3) | — | — | — |
//! | `magnetic-bottle` | [`MagneticBottle`] | 3 | ∣p − eA(x)∣²/(2m) (non-separable) | rotation about the axis (p_φ) | magnetic moment (adiabatic) | — |
//!
//! The first three are the Lagrangian models `kepler`, `pendulum` and `henon-heiles` in
//! canonical variables, with their parameters, defaults and exact solutions.
//!
//! Chains and lattices have their dimension n at run time (a parameter, `n`): each is a sum
//! of local terms ([`svi::model::local::LocalLagrangian`]) on runtime-sized ℝⁿ, run as
//! `svi::model::local::Terms(model)` by every method (in O(n) per step by those that keep
//! the terms' sparsity: `svi`, `verlet` and its compositions, the segment-rule VIs):
//!
//! | name | model | n (default) | invariants | observables (trajectory CSV) |
//! | --- | --- | --- | --- | --- |
//! | `fput` | [`Fput`] | 32 | — | energies of the first min(n, 8) normal modes, `mode_1`, … |
//! | `fput-stiff` | [`FputStiff`] | 6 (m = 3) | — | the stiff springs' oscillatory energies `oscillatory_1`, … (at most 8) and their sum `oscillatory_sum` |
//! | `toda` | [`Toda`] | 16 | tr 𝕃ᵏ, k = 1…4 (Lax traces) | the four Lax traces |
//! | `relativistic-chain` | [`RelativisticChain`] | 32 | — | the largest speed, max ∣q̇ᵢ∣/c |
//!
//! They implement [`LocalZooModel`] and are handed to a [`LocalModelVisitor`] by
//! [`visit_local_model`] (names: [`LOCAL_MODEL_NAMES`]).
//!
//! A chain with holonomic constraints is a sum of local terms plus local constraints
//! ([`svi::model::constraint::local`]), run by the constrained integrators
//! ([`svi::method::constrained`]) rather than by every method, so it is not among
//! [`LOCAL_MODEL_NAMES`] (run without its constraints it would be another system):
//!
//! | name | model | n (default) | constraints | invariants | observables |
//! | --- | --- | --- | --- | --- | --- |
//! | `polymer` | [`Polymer`] | 64 beads in ℝ³ | n − 1 rigid bonds ([`polymer::Bonds`]) | momenta (x, y; z without gravity), angular momentum about z | `end_to_end`, `gyration_radius` |
//!
//! The last three are forced (`Lagrangian::FORCED`): their non-conservative force (friction,
//! a time-dependent drive) is part of the model, [`svi::Lagrangian::external_force`], and
//! every integrator of `svi` solves their Lagrange–d'Alembert equations.
//!
//! Every model implements [`Lagrangian`], [`Symmetries`], [`Invariants`],
//! [`ExactSolution`] and [`Defaults`] (together: [`ZooModel`]), with literature defaults for
//! parameters, initial state, step and horizon.
//!
//! A model chosen by name at run time is handed, as its concrete type, to a
//! [`ModelVisitor`] by [`visit_model`]: no trait objects, so everything stays monomorphised
//! (the model dimension `N` is a type: `U1`, `U2`, … for most of the zoo, [`svi::Dyn`] for
//! `nbody`, sized by its bodies, and for text models).
//!
//! ```
//! use nalgebra::DefaultAllocator;
//! use nalgebra::allocator::Allocator;
//! use svi::{Defaults, Dimension, Lagrangian};
//! use svi_models::{ModelVisitor, ZooModel, visit_model};
//!
//! /// Reports a model's name and dimension.
//! struct Describe;
//!
//! impl ModelVisitor for Describe {
//!     type Output = String;
//!     fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> String
//!     where
//!         DefaultAllocator: Allocator<N> + Allocator<N, N>,
//!     {
//!         format!("{} (N = {})", model.name(), model.dimension())
//!     }
//! }
//!
//! assert_eq!(visit_model("kepler", Describe).unwrap(), "kepler (N = 2)");
//! assert!(visit_model("pendulm", Describe).is_err());
//! ```
//!
//! A Lagrangian written as text ([`svi::model::text`]) has its dimension and declarations
//! known only at run time: [`visit_text_model`] hands it to the same visitor as a
//! [`TextLagrangian`] of run-time dimension ([`svi::Dyn`], any number of coordinates) with
//! its declarations. A chain written as text (indexed coordinates and sums,
//! [`svi::model::text::chain`]) goes to a [`LocalModelVisitor`] by [`visit_text_chain`], as a
//! [`TextChain`] of its width with its declarations.
//!
//! Field theories in 1 + 1 dimensions are Lagrangian densities ℒ(x, t, u, u_t, u_x)
//! ([`svi::model::density`]) on a domain with a boundary condition, integrated by the
//! multisymplectic integrator of [`svi::field`] ([`fields`]):
//!
//! | name | model | ℒ | domain, boundary | exact solution |
//! | --- | --- | --- | --- | --- |
//! | `wave` | [`Wave`] | ½u_t² − ½c²u_x² | [0, 2π], periodic | d'Alembert |
//! | `sine-gordon-kink` | [`SineGordonKink`] | ½u_t² − ½u_x² − (1 − cos u) | [−20, 20], u = 0, 2π | moving kink |
//! | `sine-gordon-breather` | [`SineGordonBreather`] | ½u_t² − ½u_x² − (1 − cos u) | [−20, 20], u = 0 | breather |
//! | `sine-gordon-kink-antikink` | [`SineGordonKinkAntikink`] | ½u_t² − ½u_x² − (1 − cos u) | [−20, 20], u = 0 | kink–antikink collision |
//! | `phi4-kink` | [`Phi4Kink`] | ½u_t² − ½u_x² − ¼(u² − 1)² | [−20, 20], u = ∓1 | boosted kink |
//!
//! They implement [`FieldZooModel`] and are handed to a [`FieldModelVisitor`] by
//! [`visit_field_model`] (names: [`FIELD_MODEL_NAMES`]).
//!
//! Complex fields ψ = a + ib with a density first order in time (ħ = m = 1), integrated by the
//! pseudospectral integrators of [`svi::field::pseudospectral`] ([`schrodinger`]):
//!
//! | name | model | equation | domain | exact solution |
//! | --- | --- | --- | --- | --- |
//! | `schrodinger-packet` | [`SchrodingerPacket`] | iψ_t + ½ψ_xx = 0 | [−π, π], periodic | periodised Gaussian |
//! | `nls-soliton` | [`NlsSoliton`] | iψ_t + ½ψ_xx + ∣ψ∣²ψ = 0 | [−40, 40], periodic | soliton |
//!
//! They implement [`SpectralZooModel`] and are handed to a [`SpectralModelVisitor`] by
//! [`visit_spectral_model`] (names: [`SPECTRAL_MODEL_NAMES`]).

mod any_chain;
mod chain;
mod elliptic;
mod params;

pub mod damped_oscillator;
pub mod damped_pendulum;
pub mod double_pendulum;
pub mod driven_oscillator;
pub mod fields;
pub mod fput;
pub mod fput_stiff;
pub mod henon_heiles;
pub mod henon_heiles_h;
pub mod kepler;
pub mod kepler_h;
pub mod magnetic_bottle;
pub mod nbody;
pub mod oscillator;
pub mod pendulum;
pub mod pendulum_h;
pub mod polymer;
pub mod relativistic_chain;
pub mod restricted_three_body;
pub mod schrodinger;
pub mod sine_gordon_chain;
pub mod spherical_chain;
pub mod spring_pendulum;
pub mod toda;

pub mod dual_spin;
pub mod falling_body;
pub mod heavy_top;
pub mod pendulum_3d;
pub mod rigid_body;

pub use any_chain::{AnyChain, ChainView};
pub use damped_oscillator::DampedOscillator;
pub use damped_pendulum::DampedPendulum;
pub use double_pendulum::DoublePendulum;
pub use driven_oscillator::DrivenOscillator;
pub use fields::{Phi4Kink, SineGordonBreather, SineGordonKink, SineGordonKinkAntikink, Wave};
pub use fput::Fput;
pub use fput_stiff::FputStiff;
pub use henon_heiles::HenonHeiles;
pub use henon_heiles_h::HenonHeilesH;
pub use kepler::{Kepler, KeplerOrbit};
pub use kepler_h::KeplerH;
pub use magnetic_bottle::MagneticBottle;
pub use nbody::{Body, NBody};
pub use oscillator::HarmonicOscillator;
pub use pendulum::Pendulum;
pub use pendulum_h::PendulumH;
pub use polymer::Polymer;
pub use relativistic_chain::{RelativisticChain, RelativisticChainH};
pub use restricted_three_body::RestrictedThreeBody;
pub use schrodinger::{NlsSoliton, SchrodingerPacket};
pub use sine_gordon_chain::SineGordonChain;
pub use spherical_chain::{DoubleSphericalPendulum, SphericalChain, SphericalChain8};
pub use spring_pendulum::SpringPendulum;
pub use toda::Toda;

pub use dual_spin::DualSpin;
pub use falling_body::FallingBody;
pub use heavy_top::{HeavyTop, HeavyTopOnRigidMotions};
pub use pendulum_3d::Pendulum3d;
pub use rigid_body::FreeRigidBody;

use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator};
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};
use svi::model::text::{
    MAX_WIDTH, TextChain, TextChainModel, TextError, TextHamiltonian, TextLagrangian, TextModel,
};
use svi::{
    Canonical, Defaults, Dimension, Dyn, ExactSolution, HamiltonianStructure, Invariants,
    Lagrangian, Structure, Symmetries,
};

/// Everything a zoo model implements (blanket impl for any type with all the bounds).
pub trait ZooModel<N: Dimension>:
    Lagrangian<N>
    + Symmetries<N>
    + Invariants<N>
    + ExactSolution<N>
    + Defaults<N>
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
where
    DefaultAllocator: Allocator<N>,
{
}

impl<T, N: Dimension> ZooModel<N> for T
where
    DefaultAllocator: Allocator<N>,
    T: Lagrangian<N>
        + Symmetries<N>
        + Invariants<N>
        + ExactSolution<N>
        + Defaults<N>
        + Clone
        + Send
        + Sync
        + std::fmt::Debug
        + 'static,
{
}

/// Receives a concrete model chosen by name at run time (see [`visit_model`]).
pub trait ModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type and dimension.
    fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>;
}

/// The zoo on ℝᴺ: [`MODEL_NAMES`] and [`visit_model`] from two lists of model types, the
/// Lagrangians and then the Hamiltonians, which are visited as [`Canonical`]`<H>` (adding a
/// model is its file and one entry here).
macro_rules! vector_zoo {
    ($($model:ident),+ ; hamiltonians: $($hamiltonian:ident),+ $(,)?) => {
        /// Names of all models, in a stable order (each equals the model's
        /// [`Defaults::name`]).
        pub const MODEL_NAMES: &[&str] = &[$($model::NAME,)+ $($hamiltonian::NAME),+];

        /// Build the named model with its defaults and hand it to the visitor (a model
        /// written as a Hamiltonian H as [`Canonical`]`<H>`).
        ///
        /// # Errors
        /// [`UnknownModel`] if `name` is not one of [`MODEL_NAMES`].
        pub fn visit_model<V: ModelVisitor>(
            name: &str,
            visitor: V,
        ) -> Result<V::Output, UnknownModel> {
            $(
                if name == $model::NAME {
                    return Ok(visitor.visit($model::default()));
                }
            )+
            $(
                if name == $hamiltonian::NAME {
                    return Ok(visitor.visit(Canonical::new($hamiltonian::default())));
                }
            )+
            Err(UnknownModel {
                name: name.to_owned(),
            })
        }
    };
}

vector_zoo!(
    HarmonicOscillator,
    Pendulum,
    SpringPendulum,
    Kepler,
    DoublePendulum,
    DampedOscillator,
    DampedPendulum,
    DrivenOscillator,
    NBody,
    HenonHeiles,
    RestrictedThreeBody;
    hamiltonians:
    KeplerH,
    PendulumH,
    HenonHeilesH,
    MagneticBottle,
);

/// Receives a zoo model whose parameters can be differentiated ([`svi::Parametric`]), as its
/// concrete type and dimension.
pub trait ParametricModelVisitor {
    /// What the visit returns.
    type Output;

    /// Called once with the model, as its concrete type and dimension.
    fn visit<M: ZooModel<N> + svi::Parametric<N>, N: Dimension>(self, model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>;
}

/// Names of the zoo models whose parameters can be differentiated ([`svi::Parametric`]): the
/// models of `svi run --sensitivity`, with the parameters each offers.
///
/// | name | parameters | the start moves with |
/// | --- | --- | --- |
/// | `kepler` | `e` | `e` (the pericentre of the orbit of eccentricity e) |
/// | `damped-pendulum` | `m`, `l`, `g`, `c` | — |
pub const PARAMETRIC_MODEL_NAMES: &[&str] = &[Kepler::NAME, DampedPendulum::NAME];

/// Build the named parametric model with its defaults and hand it to the visitor; `None` if
/// `name` is not one of [`PARAMETRIC_MODEL_NAMES`].
pub fn visit_parametric_model<V: ParametricModelVisitor>(
    name: &str,
    visitor: V,
) -> Option<V::Output> {
    match name {
        Kepler::NAME => Some(visitor.visit(Kepler::default())),
        DampedPendulum::NAME => Some(visitor.visit(DampedPendulum::default())),
        _ => None,
    }
}

/// Hand a text model to the visitor as a [`TextLagrangian`] of run-time dimension ([`Dyn`]:
/// any number of coordinates), with the tightest declarations it allows among three:
/// autonomous, unforced and constant-mass (`TextLagrangian<Dyn, false, false, true>`: the
/// Hessian-free iterations and explicit Störmer–Verlet); autonomous and unforced
/// (`TextLagrangian<Dyn, false, false, false>`: energy is conserved, and checked); anything
/// else (`TextLagrangian<Dyn>`: time-dependent and forced, correct for every model).
/// A model written as a Hamiltonian goes the same way as
/// [`Canonical`]`<`[`TextHamiltonian`]`<Dyn, …>>`, with the same three choices
/// (quadratic kinetic energy ½pᵀAp with constant A in place of the constant mass).
///
/// # Errors
/// [`TextError::Declaration`] if the model breaks a declaration (which cannot happen for the
/// one chosen here).
pub fn visit_text_model<V: ModelVisitor>(
    model: TextModel,
    visitor: V,
) -> Result<V::Output, TextError> {
    let conservative = !model.time_dependent() && !model.forced();
    if model.is_hamiltonian() {
        let quadratic = model.hamiltonian_structure() == HamiltonianStructure::QuadraticKinetic;
        return Ok(match (conservative, quadratic) {
            (true, true) => {
                visitor.visit(Canonical::new(
                    TextHamiltonian::<Dyn, false, false, true>::new(model)?,
                ))
            }
            (true, false) => {
                visitor.visit(Canonical::new(
                    TextHamiltonian::<Dyn, false, false, false>::new(model)?,
                ))
            }
            (false, _) => visitor.visit(Canonical::new(TextHamiltonian::<Dyn>::new(model)?)),
        });
    }
    Ok(match (conservative, model.structure()) {
        (true, Structure::ConstantMass) => {
            visitor.visit(TextLagrangian::<Dyn, false, false, true>::new(model)?)
        }
        (true, Structure::General) => {
            visitor.visit(TextLagrangian::<Dyn, false, false, false>::new(model)?)
        }
        (false, _) => visitor.visit(TextLagrangian::<Dyn>::new(model)?),
    })
}

/// Hand a chain written as text to the visitor as a [`TextChain`] of its width K (1 to
/// [`MAX_WIDTH`]: one monomorphisation each) with the tighter of two declarations it allows:
/// autonomous and constant-mass (`TextChain<K, false, true>`: Störmer–Verlet explicit, SVI's
/// Hessian-free fixed point), or general (`TextChain<K>`: time-dependent, SVI by sparse
/// Newton; correct for every chain).
///
/// # Errors
/// [`TextError::Declaration`] if the model breaks a declaration (which cannot happen for the
/// one chosen here), [`TextError::TooWide`] beyond [`MAX_WIDTH`] (which
/// [`TextChainModel::new`] has refused already).
pub fn visit_text_chain<V: LocalModelVisitor>(
    model: TextChainModel,
    visitor: V,
) -> Result<V::Output, TextError> {
    let explicit = !model.time_dependent() && model.structure() == Structure::ConstantMass;
    macro_rules! widths {
        ($($width:literal),+) => {
            match (model.width(), explicit) {
                $(
                    ($width, true) => visitor.visit(TextChain::<$width, false, true>::new(model)?),
                    ($width, false) => visitor.visit(TextChain::<$width>::new(model)?),
                )+
                (width, _) => {
                    return Err(TextError::TooWide {
                        width,
                        what: "the chain's terms".into(),
                        limit: MAX_WIDTH,
                    })
                }
            }
        };
    }
    Ok(widths!(1, 2, 3, 4))
}

/// A model name that is not in [`MODEL_NAMES`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown model '{name}' (known: {})", MODEL_NAMES.join(", "))]
pub struct UnknownModel {
    /// The name that was asked for.
    pub name: String,
}

/// Everything a rigid-body zoo model implements (blanket impl for any type with all the
/// bounds): the models on SO(3), integrated by [`svi::lie_group::LieSvi`].
pub trait RigidZooModel:
    svi::lie_group::RigidBodyLagrangian
    + svi::lie_group::RigidBodySymmetries
    + svi::lie_group::RigidBodyInvariants
    + svi::lie_group::RigidBodyDefaults
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
}

impl<T> RigidZooModel for T where
    T: svi::lie_group::RigidBodyLagrangian
        + svi::lie_group::RigidBodySymmetries
        + svi::lie_group::RigidBodyInvariants
        + svi::lie_group::RigidBodyDefaults
        + Clone
        + Send
        + Sync
        + std::fmt::Debug
        + 'static
{
}

/// Receives a concrete rigid-body model chosen by name at run time (see
/// [`visit_rigid_model`]).
pub trait RigidModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type.
    fn visit<M: RigidZooModel>(self, model: M) -> Self::Output;
}

/// Names of the rigid-body models on SO(3), in a stable order (each equals the model's
/// [`svi::lie_group::RigidBodyDefaults::name`]).
///
/// | name | model | G-invariant | conserved momenta | invariants |
/// | --- | --- | --- | --- | --- |
/// | `rigid-body` | [`FreeRigidBody`] | yes | spatial angular momentum (3) | ‖Π‖² |
/// | `heavy-top` | [`HeavyTop`] | no | vertical angular momentum | spin Π₃ |
/// | `pendulum-3d` | [`Pendulum3d`] | no | vertical angular momentum | — |
pub const RIGID_MODEL_NAMES: &[&str] = &[FreeRigidBody::NAME, HeavyTop::NAME, Pendulum3d::NAME];

/// Build the named rigid-body model with its defaults and hand it to the visitor; `None`
/// if `name` is not one of [`RIGID_MODEL_NAMES`].
pub fn visit_rigid_model<V: RigidModelVisitor>(name: &str, visitor: V) -> Option<V::Output> {
    match name {
        FreeRigidBody::NAME => Some(visitor.visit(FreeRigidBody::default())),
        HeavyTop::NAME => Some(visitor.visit(HeavyTop::default())),
        Pendulum3d::NAME => Some(visitor.visit(Pendulum3d::default())),
        _ => None,
    }
}

/// Everything a zoo model on a Lie group implements (blanket impl for any type with all the
/// bounds): the models on a group G of dimension `N` stored as `E` numbers, integrated by
/// [`svi::lie_group::LieSvi`] ([`svi::lie_group::GroupIntegrator`]).
pub trait GroupZooModel<const N: usize, const E: usize>:
    svi::lie_group::GroupLagrangian<N, E>
    + svi::lie_group::GroupSymmetries<N, E>
    + svi::lie_group::GroupDefaults<N, E>
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
}

impl<T, const N: usize, const E: usize> GroupZooModel<N, E> for T where
    T: svi::lie_group::GroupLagrangian<N, E>
        + svi::lie_group::GroupSymmetries<N, E>
        + svi::lie_group::GroupDefaults<N, E>
        + Clone
        + Send
        + Sync
        + std::fmt::Debug
        + 'static
{
}

/// Receives a concrete model on a Lie group chosen by name at run time (see
/// [`visit_group_model`]).
pub trait GroupModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type.
    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(
        self,
        model: M,
    ) -> Self::Output;
}

/// Names of the models on Lie groups other than SO(3), in a stable order (each equals the
/// model's [`svi::lie_group::GroupDefaults::name`]).
///
/// | name | model | group | G-invariant | conserved momenta | exact solution |
/// | --- | --- | --- | --- | --- | --- |
/// | `falling-body` | [`FallingBody`] | SE(3) | no | `L_z`, `p_x`, `p_y` | yes |
/// | `dual-spin` | [`DualSpin`] | SO(3) × S¹ | yes | `L_x`, `L_y`, `L_z`, `p_rotor` | no |
/// | `spherical-chain` | [`SphericalChain8`] (8 links) | SO(3)⁸ | no | `L_z` | no |
pub const GROUP_MODEL_NAMES: &[&str] = &[FallingBody::NAME, DualSpin::NAME, SphericalChain8::NAME];

/// Build the named model on a group with its defaults and hand it to the visitor; `None` if
/// `name` is not one of [`GROUP_MODEL_NAMES`]. One line per model.
pub fn visit_group_model<V: GroupModelVisitor>(name: &str, visitor: V) -> Option<V::Output> {
    match name {
        FallingBody::NAME => Some(visitor.visit(FallingBody::default())),
        DualSpin::NAME => Some(visitor.visit(DualSpin::default())),
        SphericalChain8::NAME => Some(visitor.visit(SphericalChain8::default())),
        _ => None,
    }
}

/// Everything a runtime-dimension zoo model implements: a Lagrangian on ℝⁿ written as a sum
/// of local terms with its defaults and invariants, plus the named *observables* that a
/// trajectory writes besides time and energy (n coordinates per row would make a file of
/// 10⁵ columns; a few quantities that summarise the state are written instead).
///
/// Every one is also an [`AnyChain`] (`Into<AnyChain>`): one type for every chain, so that a
/// program running a chain chosen at run time compiles its methods once per declaration, not
/// per chain.
pub trait LocalZooModel:
    LocalLagrangian
    + LocalDefaults
    + LocalInvariants
    + Into<AnyChain>
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
    /// The names of the observables, in the order of [`LocalZooModel::observables_into`]
    /// (CSV column names: letters, digits and `_`).
    fn observable_names(&self) -> Vec<String>;

    /// The observables at (t, q, q̇), appended to `out` (as many as
    /// [`LocalZooModel::observable_names`]; O(n) each).
    fn observables_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>);
}

/// The number of normal-mode energies an FPUT trajectory writes (at most n).
pub const FPUT_OBSERVED_MODES: usize = 8;

impl LocalZooModel for Fput {
    /// `mode_1`, …, `mode_k` with k = min(n, [`FPUT_OBSERVED_MODES`]).
    fn observable_names(&self) -> Vec<String> {
        (1..=self.n.min(FPUT_OBSERVED_MODES))
            .map(|k| format!("mode_{k}"))
            .collect()
    }

    /// The harmonic energies of the first modes ([`Fput::mode_energies`]).
    fn observables_into(&self, _: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>) {
        out.extend(self.mode_energies(q, v, FPUT_OBSERVED_MODES));
    }
}

/// The number of stiff springs whose oscillatory energies a stiff–soft FPU trajectory writes
/// (their sum covers all m).
pub const FPUT_STIFF_OBSERVED_SPRINGS: usize = 8;

impl LocalZooModel for FputStiff {
    /// `oscillatory_1`, …, `oscillatory_k` with k = min(m, [`FPUT_STIFF_OBSERVED_SPRINGS`]),
    /// and `oscillatory_sum`.
    fn observable_names(&self) -> Vec<String> {
        (1..=self.m.min(FPUT_STIFF_OBSERVED_SPRINGS))
            .map(|i| format!("oscillatory_{i}"))
            .chain(std::iter::once("oscillatory_sum".to_owned()))
            .collect()
    }

    /// The oscillatory energies of the first springs and their sum over all m
    /// ([`FputStiff::oscillatory_energies`]).
    fn observables_into(&self, _: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>) {
        let energies = self.oscillatory_energies(q, v);
        out.extend(energies.iter().take(FPUT_STIFF_OBSERVED_SPRINGS));
        out.push(energies.iter().sum());
    }
}

impl LocalZooModel for Toda {
    /// The invariants' names, `trace_lax_1`, …, `trace_lax_4`.
    fn observable_names(&self) -> Vec<String> {
        (0..self.invariant_count())
            .map(|k| self.invariant_name(k).to_owned())
            .collect()
    }

    /// tr 𝕃ᵏ, k = 1…4 ([`Toda::lax_traces`], one pass for all four).
    fn observables_into(&self, _: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>) {
        out.extend(self.lax_traces(q, v, self.invariant_count()));
    }
}

impl LocalZooModel for RelativisticChain {
    /// `speed_max`.
    fn observable_names(&self) -> Vec<String> {
        vec!["speed_max".into()]
    }

    /// The largest speed as a fraction of c, max ∣q̇ᵢ∣/c (below 1 on every valid state).
    fn observables_into(&self, _: f64, _: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>) {
        out.push(v.amax() / self.c);
    }
}

impl LocalZooModel for SineGordonChain {
    /// `kink_position`.
    fn observable_names(&self) -> Vec<String> {
        vec!["kink_position".into()]
    }

    /// Where φ first crosses π (linear between sites): the kink's centre; NaN without a
    /// crossing.
    fn observables_into(&self, _: f64, q: &DVector<f64>, _: &DVector<f64>, out: &mut Vec<f64>) {
        out.push(self.kink_position(q));
    }
}

impl LocalZooModel for Polymer {
    /// `end_to_end` and `gyration_radius`.
    fn observable_names(&self) -> Vec<String> {
        vec!["end_to_end".into(), "gyration_radius".into()]
    }

    /// The distance between the ends ([`Polymer::end_to_end`]) and the radius of gyration
    /// ([`Polymer::gyration_radius`]).
    fn observables_into(&self, _: f64, q: &DVector<f64>, _: &DVector<f64>, out: &mut Vec<f64>) {
        out.extend([self.end_to_end(q), self.gyration_radius(q)]);
    }
}

/// A chain written as text, in the declarations [`visit_text_chain`] hands out (those an
/// [`AnyChain`] holds).
impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> LocalZooModel
    for TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
where
    TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>: Into<AnyChain>,
{
    /// None: a chain written as text names no summary of its state.
    fn observable_names(&self) -> Vec<String> {
        Vec::new()
    }

    fn observables_into(&self, _: f64, _: &DVector<f64>, _: &DVector<f64>, _: &mut Vec<f64>) {}
}

/// Receives a concrete runtime-dimension model chosen by name at run time (see
/// [`visit_local_model`]).
pub trait LocalModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type (with its default parameters).
    fn visit<M: LocalZooModel>(self, model: M) -> Self::Output;
}

/// The runtime-dimension zoo: [`LOCAL_MODEL_NAMES`] and [`visit_local_model`] from one list
/// of (name, model type) pairs; each name equals the model's [`LocalDefaults::name`] (a
/// test checks it).
macro_rules! local_zoo {
    ($($name:literal => $model:ident),+ $(,)?) => {
        /// Names of the runtime-dimension models (chains, lattices), in a stable order.
        pub const LOCAL_MODEL_NAMES: &[&str] = &[$($name),+];

        /// Build the named runtime-dimension model with its defaults and hand it to the
        /// visitor; `None` if `name` is not one of [`LOCAL_MODEL_NAMES`].
        pub fn visit_local_model<V: LocalModelVisitor>(name: &str, visitor: V) -> Option<V::Output> {
            match name {
                $($name => Some(visitor.visit($model::default())),)+
                _ => None,
            }
        }
    };
}

local_zoo!(
    "fput" => Fput,
    "fput-stiff" => FputStiff,
    "toda" => Toda,
    "relativistic-chain" => RelativisticChain,
    "sine-gordon-chain" => SineGordonChain,
);

/// Everything a field model of the zoo implements (blanket impl): a scalar Lagrangian
/// density with its defaults and exact solution, integrated by
/// [`svi::field::multisymplectic::Multisymplectic`].
pub trait FieldZooModel:
    svi::model::density::LagrangianDensity<1>
    + svi::model::density::FieldDefaults<1>
    + svi::model::density::ExactField<1>
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
}

impl<T> FieldZooModel for T where
    T: svi::model::density::LagrangianDensity<1>
        + svi::model::density::FieldDefaults<1>
        + svi::model::density::ExactField<1>
        + Clone
        + Send
        + Sync
        + std::fmt::Debug
        + 'static
{
}

/// Receives a field model chosen by name at run time (see [`visit_field_model`]).
pub trait FieldModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type (with its default parameters).
    fn visit<M: FieldZooModel>(self, model: M) -> Self::Output;
}

/// The field zoo: [`FIELD_MODEL_NAMES`] and [`visit_field_model`] from one list.
macro_rules! field_zoo {
    ($($name:literal => $model:ident),+ $(,)?) => {
        /// Names of the field models (each equals the model's `FieldDefaults::name`).
        pub const FIELD_MODEL_NAMES: &[&str] = &[$($name),+];

        /// Build the named field model with its defaults and hand it to the visitor; `None`
        /// if `name` is not one of [`FIELD_MODEL_NAMES`].
        pub fn visit_field_model<V: FieldModelVisitor>(name: &str, visitor: V) -> Option<V::Output> {
            match name {
                $($name => Some(visitor.visit($model::default())),)+
                _ => None,
            }
        }
    };
}

field_zoo!(
    "wave" => Wave,
    "sine-gordon-kink" => SineGordonKink,
    "sine-gordon-breather" => SineGordonBreather,
    "sine-gordon-kink-antikink" => SineGordonKinkAntikink,
    "phi4-kink" => Phi4Kink,
);

/// Everything a complex (Schrödinger-type) field model of the zoo implements (blanket impl):
/// a density of u = (a, b) with its defaults and exact solution, integrated by
/// [`svi::field::pseudospectral::Pseudospectral`].
pub trait SpectralZooModel:
    svi::model::density::LagrangianDensity<2>
    + svi::model::density::FieldDefaults<2>
    + svi::model::density::ExactField<2>
    + Clone
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
}

impl<T> SpectralZooModel for T where
    T: svi::model::density::LagrangianDensity<2>
        + svi::model::density::FieldDefaults<2>
        + svi::model::density::ExactField<2>
        + Clone
        + Send
        + Sync
        + std::fmt::Debug
        + 'static
{
}

/// Receives a complex field model chosen by name at run time (see [`visit_spectral_model`]).
pub trait SpectralModelVisitor {
    /// What the visit produces.
    type Output;

    /// Called once with the model, as its concrete type (with its default parameters).
    fn visit<M: SpectralZooModel>(self, model: M) -> Self::Output;
}

/// Names of the complex field models (each equals the model's `FieldDefaults::name`).
pub const SPECTRAL_MODEL_NAMES: &[&str] = &["schrodinger-packet", "nls-soliton"];

/// Build the named complex field model with its defaults and hand it to the visitor; `None`
/// if `name` is not one of [`SPECTRAL_MODEL_NAMES`].
pub fn visit_spectral_model<V: SpectralModelVisitor>(name: &str, visitor: V) -> Option<V::Output> {
    match name {
        "schrodinger-packet" => Some(visitor.visit(SchrodingerPacket::default())),
        "nls-soliton" => Some(visitor.visit(NlsSoliton::default())),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reports a model's name, dimension and observables.
    struct Describe;

    impl LocalModelVisitor for Describe {
        type Output = (&'static str, usize, Vec<String>, usize);
        fn visit<M: LocalZooModel>(self, model: M) -> Self::Output {
            let (t0, q, v) = model.initial_state();
            let mut values = Vec::new();
            model.observables_into(t0, &q, &v, &mut values);
            (
                model.name(),
                model.dimension(),
                model.observable_names(),
                values.len(),
            )
        }
    }

    #[test]
    fn local_names_are_the_models_names_and_observables_match_their_names() {
        for name in LOCAL_MODEL_NAMES {
            let (own, n, names, count) = visit_local_model(name, Describe).unwrap();
            assert_eq!(own, *name);
            assert_eq!(names.len(), count, "{name}");
            assert!(n >= 2, "{name}");
        }
        assert!(visit_local_model("kepler", Describe).is_none());
        let (_, n, names, _) = visit_local_model("fput", Describe).unwrap();
        assert_eq!(n, 32);
        assert_eq!(names.first().map(String::as_str), Some("mode_1"));
        assert_eq!(names.last().map(String::as_str), Some("mode_8"));
        let (_, n, names, _) = visit_local_model("fput-stiff", Describe).unwrap();
        assert_eq!(n, 6);
        assert_eq!(
            names,
            [
                "oscillatory_1",
                "oscillatory_2",
                "oscillatory_3",
                "oscillatory_sum"
            ]
        );
        let (_, _, names, _) = visit_local_model("toda", Describe).unwrap();
        assert_eq!(
            names,
            ["trace_lax_1", "trace_lax_2", "trace_lax_3", "trace_lax_4"]
        );
    }

    #[test]
    fn the_stiff_soft_chain_observes_its_first_springs_and_the_sum_of_all() {
        // HLW's initial state puts I₁ = ½(ẋ₁² + ω² x₁²) = ½(1 + 1) = 1 in the first stiff
        // spring and nothing in the others; with m = 10 the file holds 8 springs and the sum
        // of all 10.
        let mut chain = FputStiff::default();
        chain.set_parameter("m", 10.0).unwrap();
        let names = chain.observable_names();
        assert_eq!(names.len(), 9);
        assert_eq!(names[7], "oscillatory_8");
        let (t0, q, v) = chain.initial_state();
        let mut values = Vec::new();
        chain.observables_into(t0, &q, &v, &mut values);
        assert_eq!(values.len(), 9);
        assert!((values[0] - 1.0).abs() < 1e-14, "{values:?}");
        assert!(values[1..8].iter().all(|&i| i == 0.0), "{values:?}");
        assert!((values[8] - 1.0).abs() < 1e-14, "{values:?}");
        for bad in [0.0, -1.0, 2.5, f64::NAN] {
            assert!(chain.set_parameter("m", bad).is_err(), "m = {bad}");
        }
        assert!(chain.set_parameter("omega", 0.0).is_err());
    }

    #[test]
    fn a_short_chain_observes_every_mode_it_has() {
        let mut fput = Fput::default();
        fput.set_parameter("n", 3.0).unwrap();
        assert_eq!(fput.observable_names(), ["mode_1", "mode_2", "mode_3"]);
        let (t0, q, v) = fput.initial_state();
        let mut values = Vec::new();
        fput.observables_into(t0, &q, &v, &mut values);
        // All the energy starts in mode 1: E₁ = ½ ω₁² (A √((n+1)/2))², the others zero.
        let amplitude = fput.amplitude * (4.0f64 / 2.0).sqrt();
        let expected = 0.5 * (fput.mode_frequency(1) * amplitude).powi(2);
        assert!(
            (values[0] - expected).abs() < 1e-12,
            "{values:?} {expected}"
        );
        assert!(
            values[1].abs() < 1e-24 && values[2].abs() < 1e-24,
            "{values:?}"
        );
    }
}
