//! The registry of the provided groups, [`GROUPS`]: one line per group, with its name, shape,
//! a one-line summary and its [`check_group`] at the [`sample_points`] (`svi list` prints it;
//! the registry's test runs every check). A new group is one file implementing [`LieGroup`]
//! and one line here.

use super::LieGroup;
use super::check::{GroupCheckFailure, check_group, sample_points};
use super::circle::Circle;
use super::product::{Power, Product, RotationsAndTranslations};
use super::rigid_motions::RigidMotions;
use super::rotations::Rotations;
use super::translations::Translations;

/// One group of the registry [`GROUPS`].
#[derive(Debug, Clone, Copy)]
pub struct GroupEntry {
    /// The group's name in listings (`"SE(3)"`).
    pub name: &'static str,
    /// The dimension N of the group (of its Lie algebra ℝᴺ).
    pub dimension: usize,
    /// The number E of stored entries of an element.
    pub stored: usize,
    /// One line: what the group is and how it is stored.
    pub summary: &'static str,
    /// [`check_group`] on the group at the [`sample_points`].
    pub check: fn() -> Result<(), GroupCheckFailure>,
}

/// [`check_group`] on `G` at the [`sample_points`].
fn check_samples<G: LieGroup<N, E>, const N: usize, const E: usize>()
-> Result<(), GroupCheckFailure> {
    check_group::<G, N, E>(&sample_points::<N>())
}

/// The registry line of `G`, named by [`LieGroup::NAME`].
pub const fn entry<G: LieGroup<N, E>, const N: usize, const E: usize>(
    summary: &'static str,
) -> GroupEntry {
    named::<G, N, E>(G::NAME, summary)
}

/// The registry line of `G` under `name` (for products and powers, whose
/// [`LieGroup::NAME`] does not name their factors). A shape `N`, `E` other than the sum (or
/// multiple) of the factors' is a compile-time error.
pub const fn named<G: LieGroup<N, E>, const N: usize, const E: usize>(
    name: &'static str,
    summary: &'static str,
) -> GroupEntry {
    GroupEntry {
        name,
        dimension: N,
        stored: E,
        summary,
        check: check_samples::<G, N, E>,
    }
}

/// The provided groups, one line each (kept one line each by hand: `rustfmt::skip`).
#[rustfmt::skip]
pub const GROUPS: &[GroupEntry] = &[
    entry::<Rotations, 3, 9>("rotations of space, R stored by columns; closed-form exp, log, dexp, dexp⁻¹"),
    entry::<RigidMotions, 6, 12>("rigid motions (R, x), algebra (ω, v); closed-form exp, log, dexp, dexp⁻¹"),
    named::<Translations<3>, 3, 3>("R^3", "translations of ℝ³ under addition, stored as the vector"),
    entry::<Circle, 1, 2>("rotations of the plane (angles) ≅ S¹, stored as (cos θ, sin θ)"),
    named::<RotationsAndTranslations, 6, 12>("SO(3) x R^3", "attitude and position as separate factors, stored as R then x"),
    named::<Product<Rotations, Circle, 3, 9, 1, 2>, 4, 11>("SO(3) x S^1", "a platform with a rotor (the dual-spin satellite), stored as R then (cos θ, sin θ)"),
    named::<Power<Rotations, 8, 3, 9>, 24, 72>("SO(3)^8", "8 rigid links (the 8-link spherical chain), stored as 8 rotations one after the other"),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Every registered group passes its check, its shape is that of its type's const
    /// generics and the names are unique.
    #[test]
    fn every_registered_group_passes_its_check() {
        for group in GROUPS {
            if let Err(failure) = (group.check)() {
                panic!("{}: {failure}", group.name);
            }
            assert!(!group.summary.is_empty() && !group.summary.contains('\n'));
        }
        for (i, group) in GROUPS.iter().enumerate() {
            assert!(
                GROUPS[..i].iter().all(|other| other.name != group.name),
                "{} twice",
                group.name
            );
        }
        let shape = |name: &str| {
            let group = GROUPS.iter().find(|group| group.name == name).unwrap();
            (group.dimension, group.stored)
        };
        assert_eq!(shape("SO(3)"), (3, 9));
        assert_eq!(shape("SE(3)"), (6, 12));
        assert_eq!(shape("R^3"), (3, 3));
        assert_eq!(shape("SO(2)"), (1, 2));
        assert_eq!(shape("SO(3) x R^3"), (6, 12));
        assert_eq!(shape("SO(3) x S^1"), (4, 11));
        assert_eq!(shape("SO(3)^8"), (24, 72));
        assert_eq!(GROUPS.len(), 7);
    }
}
