//! Lie-group variational integrators for rigid bodies on SO(3), from one Lagrangian L(R, Ω)
//! (Leok, *Generalized Variational Integrators*, §5.3–5.4).
//!
//! The pieces live in their layers ([`crate::model::so3`], [`crate::model::rigid_body`],
//! [`crate::method::lie_svi`], [`crate::stepping::rigid_observer`]); this module gathers them:
//!
//! - [`so3`]: hat/vee, exp, log, Ad, dexp and its inverse, generic over the dual scalar.
//! - the model trait [`RigidBodyLagrangian`] and its companions, and the derived quantities
//!   [`RigidBodyExt`] (momentum, Legendre map, energy, torque);
//! - the integrator [`LieSvi`] (full form §5.3, reduced Euler–Poincaré form §5.4);
//! - the stepping loop, [`crate::Integrator`] on [`SO3`] ([`RigidBodyIntegrator`]);
//! - observers: energy, spatial angular momentum, Casimirs, orthogonality, trajectories.
//!
//! ```
//! use nalgebra::{SMatrix, SVector};
//! use svi::Scalar;
//! use svi::lie_group::{
//!     AngularMomentumError, LieSvi, OrthogonalityError, RigidBodyIntegrator,
//!     RigidBodyLagrangian, RigidBodySymmetries, RigidInitial,
//! };
//!
//! /// A free rigid body with inertia diag(1, 2, 3).
//! struct FreeBody;
//! impl RigidBodyLagrangian for FreeBody {
//!     const G_INVARIANT: bool = true;
//!     fn lagrangian<D: Scalar>(&self, _r: &SMatrix<D, 3, 3>, w: &SVector<D, 3>) -> D {
//!         (w[0] * w[0] + w[1] * w[1] * 2.0 + w[2] * w[2] * 3.0) * 0.5
//!     }
//! }
//! impl RigidBodySymmetries for FreeBody {
//!     fn axis_count(&self) -> usize { 3 }
//!     fn axis_name(&self, i: usize) -> &'static str { ["π_x", "π_y", "π_z"][i] }
//!     fn axis(&self, i: usize) -> SVector<f64, 3> { SVector::<f64, 3>::ith(i, 1.0) }
//! }
//!
//! let integrator = RigidBodyIntegrator::new(FreeBody, LieSvi::new(3));
//! let initial = RigidInitial::Velocity {
//!     r: SMatrix::identity(),
//!     omega: SVector::from([0.3, 1.0, -0.2]),
//! };
//! let mut observers = (AngularMomentumError::default(), OrthogonalityError::default());
//! let run = integrator.run(0.0, initial, 0.05, 5.0, &mut observers).unwrap();
//! assert_eq!(run.statistics.steps, 100);
//! assert!(observers.0.relative() < 1e-14);
//! assert!(observers.1.max < 1e-14);
//! ```

pub use crate::method::group_space::{GroupInitial, GroupPoint, GroupSpace, GroupState};
pub use crate::method::lie_svi::{
    Form, GroupWorkspace, LieSvi, LieWorkspace, ORTHOGONALITY_TOLERANCE,
};
pub use crate::method::space::{RigidInitial, RigidPoint, RigidState, SO3};
pub use crate::model::group::circle::Circle;
pub use crate::model::group::product::{Power, Product, RotationsAndTranslations};
pub use crate::model::group::rigid_motions::RigidMotions;
pub use crate::model::group::rotations::Rotations;
pub use crate::model::group::symmetries::{check_generators, symmetry_defect};
pub use crate::model::group::translations::Translations;
pub use crate::model::group::{
    GroupDefaults, GroupLagrangian, GroupLagrangianExt, GroupSymmetries, LieGroup,
};
pub use crate::model::rigid_body::{
    RigidBodyDefaults, RigidBodyExt, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries,
};
pub use crate::model::so3::{self, quaternion, rotation};
pub use crate::stepping::group_observer::{DefectError, GroupSolutionError, SpatialMomentumError};
pub use crate::stepping::rigid_observer::{AngularMomentumError, OrthogonalityError};

/// A rigid-body model and a [`LieSvi`] method, ready to run: the one
/// [`crate::Integrator`] on [`SO3`].
pub type RigidBodyIntegrator<L> = crate::Integrator<L, LieSvi, SO3>;
/// A model on a Lie group G (dimension `N`, `E` stored numbers) and a [`LieSvi`] method:
/// the [`crate::Integrator`] on [`GroupSpace`].
pub type GroupIntegrator<L, G, const N: usize, const E: usize> =
    crate::Integrator<L, LieSvi, GroupSpace<G, N, E>>;
/// The result of a run on a Lie group.
pub type GroupRun<G, const N: usize, const E: usize> =
    crate::stepping::run::Run<GroupSpace<G, N, E>>;
/// The result of a rigid-body run.
pub type RigidRun = crate::stepping::run::Run<SO3>;
/// Stores the observed points of a rigid-body run.
pub type RigidTrajectory = crate::stepping::observer::Points<RigidPoint>;
