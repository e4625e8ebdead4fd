//! What is particular to scenes on a Lie group other than SO(3) (`svi_models::GROUP_MODEL_NAMES`:
//! a body falling on SE(3), the dual-spin satellite on SO(3) × S¹, a chain of spherical
//! pendulums on SO(3)⁸): the initial configuration and body velocity of `[initial]`. The
//! method is the Lie-group integrator of the rigid bodies ([`super::rigid::method`]), with
//! its form.
//!
//! ```toml
//! model = "falling-body"
//!
//! [initial]             # optional; absent fields come from the model's default state
//! log = [0.1, -0.2, 0.3, 1.0, -2.0, 3.0]   # g0 = exp(log), N numbers; or g = [...], the
//!                                          # E stored entries of g0
//! xi = [1.0, 0.2, 0.8, 0.5, 0.0, 2.0]      # body velocity, N numbers; or momentum = [...]
//!
//! [method]
//! name = "lie-svi:3"
//!
//! [output]
//! trajectory = "body.csv"   # t, g (E entries), ξ, μ (N each), energy
//! diagnostics = ["energy", "momentum", "solution"]   # the group defect unless "none"
//! ```
//!
//! Stored entries `g` that are not in the group (a rotation block that is not orthogonal)
//! are refused by the integrator, naming the defect.

use nalgebra::SVector;
use svi::lie_group::{GroupInitial, LieGroup};

use crate::scene::error::SceneError;
use crate::scene::rigid::fixed;
use crate::scene::schema::InitialSection;

/// The initial state of `section` on the group `G`: g₀ from its entries or its logarithm
/// (else `default_g`), with the body velocity or momentum (else `default_xi`). An error names
/// a field of the wrong length.
pub fn initial<G: LieGroup<N, E>, const N: usize, const E: usize>(
    section: &InitialSection,
    default_g: SVector<f64, E>,
    default_xi: SVector<f64, N>,
) -> Result<GroupInitial<N, E>, SceneError> {
    let g = match (&section.g, &section.log) {
        (Some(g), _) => fixed::<E>("g", g)?,
        (None, Some(log)) => G::exp(&fixed::<N>("log", log)?),
        (None, None) => default_g,
    };
    Ok(match (&section.xi, &section.momentum) {
        (Some(xi), _) => GroupInitial::Velocity {
            g,
            xi: fixed::<N>("xi", xi)?,
        },
        (None, Some(momentum)) => GroupInitial::Momentum {
            g,
            momentum: fixed::<N>("momentum", momentum)?,
        },
        (None, None) => GroupInitial::Velocity { g, xi: default_xi },
    })
}

/// Check the fields of `[initial]` on a group other than SO(3): none of ℝᴺ's or SO(3)'s, and
/// not both of a pair that exclude each other.
pub fn check_initial(section: &InitialSection, model: &str) -> Result<(), SceneError> {
    let foreign = [
        (section.q.is_some(), "initial.q"),
        (section.v.is_some(), "initial.v"),
        (section.p.is_some(), "initial.p"),
        (section.rotation.is_some(), "initial.rotation"),
        (section.quaternion.is_some(), "initial.quaternion"),
        (section.omega.is_some(), "initial.omega"),
    ];
    if let Some((_, option)) = foreign.into_iter().find(|(given, _)| *given) {
        return Err(SceneError::NotApplicable {
            option,
            reason: format!(
                "the model '{model}' lives on a Lie group: it takes g or log, and xi or momentum"
            ),
        });
    }
    for (both, pair) in [
        (section.g.is_some() && section.log.is_some(), "g and log"),
        (
            section.xi.is_some() && section.momentum.is_some(),
            "xi and momentum",
        ),
    ] {
        if both {
            return Err(svi::Error::invalid(
                "initial",
                format!("both {pair} are given: give one of them"),
            )
            .into());
        }
    }
    Ok(())
}
