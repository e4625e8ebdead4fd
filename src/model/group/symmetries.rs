//! Symmetries of a Lagrangian on a group, and their Noether momenta.
//!
//! A spatial generator ζ ∈ 𝔤 acts on the left, g ↦ exp(sζ) g = g exp(s Ad_{g⁻¹}ζ). If L is
//! invariant under it, the Noether momentum J_ζ = ⟨Ad_{g⁻¹}ᵀμ, ζ⟩ (the spatial momentum
//! paired with ζ, [`crate::method::group_space::GroupPoint::spatial_momentum`]) is conserved
//! by the flow and by Lie-SVI (its discrete Noether theorem, [`crate::method::lie_svi`]).
//! Examples: rotations about the vertical, ζ = (e₃, 0), and horizontal translations,
//! ζ = (0, e₁), of a body falling on SE(3); the vertical rotation of a whole chain on SO(3)ᴷ,
//! ζ = (e₃, …, e₃).

use super::{GroupLagrangian, GroupLagrangianExt, LieGroup};
use crate::error::Error;
use nalgebra::SVector;

/// The spatial symmetry generators of a Lagrangian on a group (module docs).
pub trait GroupSymmetries<const N: usize, const E: usize>: GroupLagrangian<N, E> {
    /// Number of generators (default: none).
    fn generator_count(&self) -> usize {
        0
    }

    /// The name of the momentum of generator `index` (for reports: `"L_z"`, `"p_x"`).
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn momentum_name(&self, index: usize) -> &'static str {
        panic!("no symmetry generator with index {index}")
    }

    /// Generator `index`, a spatial Lie-algebra element ζ (non-zero and finite:
    /// [`check_generators`]).
    ///
    /// # Panics
    /// If `index >= generator_count()` (the default panics for every index).
    fn generator(&self, index: usize) -> SVector<f64, N> {
        panic!("no symmetry generator with index {index}")
    }

    /// The Noether momentum of generator `index` at a configuration `g` with body momentum
    /// `momentum`: ⟨Ad_{g⁻¹}ᵀμ, ζ⟩.
    fn noether_momentum(
        &self,
        index: usize,
        g: &SVector<f64, E>,
        momentum: &SVector<f64, N>,
    ) -> f64 {
        let spatial =
            <Self::Group as LieGroup<N, E>>::adjoint(&<Self::Group as LieGroup<N, E>>::inverse(g))
                .transpose()
                * momentum;
        spatial.dot(&self.generator(index))
    }
}

/// Checks every generator of `model`: a generator with a non-finite entry or of zero length
/// (it generates nothing, and its momentum is identically zero) is an
/// [`Error::InvalidParameter`] naming it and its value.
pub fn check_generators<L: GroupSymmetries<N, E>, const N: usize, const E: usize>(
    model: &L,
) -> Result<(), Error> {
    for index in 0..model.generator_count() {
        let generator = model.generator(index);
        let name = model.momentum_name(index);
        if generator.iter().any(|x| !x.is_finite()) {
            return Err(Error::invalid(
                "symmetry generator",
                format!("the generator of {name} has a non-finite entry: {generator:?}"),
            ));
        }
        if generator.amax() == 0.0 {
            return Err(Error::invalid(
                "symmetry generator",
                format!("the generator of {name} has zero length: it generates no symmetry"),
            ));
        }
    }
    Ok(())
}

/// How far generator `index` is from a symmetry of L at (g, ξ): |d/ds L(exp(sζ)g, ξ)| at
/// s = 0, that is |⟨λ, Ad_{g⁻¹}ζ⟩| with λ the left-trivialised configuration gradient,
/// relative to |λ||Ad_{g⁻¹}ζ| + |L| (zero for a symmetry, up to round-off).
pub fn symmetry_defect<L: GroupSymmetries<N, E>, const N: usize, const E: usize>(
    model: &L,
    index: usize,
    g: &SVector<f64, E>,
    xi: &SVector<f64, N>,
) -> f64 {
    let body = <L::Group as LieGroup<N, E>>::adjoint(&<L::Group as LieGroup<N, E>>::inverse(g))
        * model.generator(index);
    let gradient = model.configuration_gradient(g, xi);
    let scale = gradient.norm() * body.norm() + model.value(g, xi).abs();
    let change = gradient.dot(&body).abs();
    if scale > 0.0 { change / scale } else { change }
}
