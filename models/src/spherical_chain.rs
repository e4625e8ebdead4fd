//! A chain of spherical pendulums (the 3D pendulum chain of Lee, Leok & McClamroch), each link
//! an attitude in SO(3): configurations in SO(3)ᴷ through the group
//! ([`svi::lie_group::Power`]).
//!
//! # Why through SO(3), and not on S² directly
//! A link's direction q = R e₃ lives on the sphere S² = SO(3)/SO(2). Lie-SVI needs a group;
//! the natural choice is to lift each link to its attitude R ∈ SO(3), where the spin about the
//! link, Ω₃, does not enter the pendulum's Lagrangian (q̇ = R(Ω × e₃) has no Ω₃). A Lagrangian
//! without Ω₃ is degenerate (its Legendre map cannot be inverted), so each link gets a spin
//! energy ½ J Ω₃²: the Lagrangian is that of a chain of symmetric tops with transverse inertia
//! m l² carried by the point masses. The right action R ↦ R exp(θ ê₃) leaves it invariant,
//! so each link's spin momentum J Ω₃ is a Noether momentum, conserved by the continuous flow
//! and — the natural chart being equivariant under right translation too — by Lie-SVI; with
//! Ω₃ = 0 at the start the spin stays zero and the directions q move exactly as the
//! pendulum chain on (S²)ᴷ (Routh reduction: the spin term does not couple to q), whatever
//! J > 0. The discrete directions depend on J only through the method's truncation error.
//! This keeps the method of every other group (its order 2d, the exact Jacobian, the
//! discrete Noether theorem for the rotations about the vertical), where the variational
//! integrator on TS² of Lee, Leok & McClamroch (2009) is of second order only.
//!
//! # Lagrangian
//! Links of length lᵢ with point masses mᵢ at their ends, joints at x₀ = 0,
//! xᵢ = Σ_{j≤i} l_j q_j, q_j = R_j e₃, q̇_j = R_j (Ω_j × e₃), gravity g₀ along −z:
//!
//! L = Σᵢ ½ mᵢ |ẋᵢ|² − Σᵢ mᵢ g₀ xᵢ·e₃ + Σ_j ½ J Ω_{j,3}².
//!
//! Conserved: the energy, the vertical angular momentum Σ_j (R_j μ_j)·e₃ (rotations of the
//! whole chain about the vertical, a left action of the diagonal) and each spin μ_{j,3}.

use nalgebra::{SMatrix, SVector};
use svi::Scalar;
use svi::lie_group::{GroupLagrangian, Power, Rotations, so3};

type Matrix3 = SMatrix<f64, 3, 3>;
type Vector3 = SVector<f64, 3>;

/// A chain of `K` spherical pendulums on SO(3)ᴷ; `N` = 3K and `E` = 9K (checked at compile
/// time; see [`DoubleSphericalPendulum`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphericalChain<const K: usize, const N: usize, const E: usize> {
    /// Link lengths lᵢ (> 0).
    pub lengths: [f64; K],
    /// Point masses mᵢ at the links' ends (> 0).
    pub masses: [f64; K],
    /// Gravitational acceleration g₀ along −z.
    pub gravity: f64,
    /// Spin inertia J of each link about its own axis (> 0; does not change the motion of
    /// the directions, see the module docs).
    pub spin: f64,
}

/// Two spherical pendulums, one hanging from the other.
pub type DoubleSphericalPendulum = SphericalChain<2, 6, 18>;

impl<const K: usize, const N: usize, const E: usize> Default for SphericalChain<K, N, E> {
    /// Unit lengths and masses, g₀ = 9.81, J = 1.
    fn default() -> Self {
        SphericalChain {
            lengths: [1.0; K],
            masses: [1.0; K],
            gravity: 9.81,
            spin: 1.0,
        }
    }
}

impl<const K: usize, const N: usize, const E: usize> GroupLagrangian<N, E>
    for SphericalChain<K, N, E>
{
    type Group = Power<Rotations, K, 3, 9>;

    #[inline]
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, E>, xi: &SVector<D, N>) -> D {
        let mut position = SVector::<D, 3>::zeros();
        let mut velocity = SVector::<D, 3>::zeros();
        let mut sum = D::from(0.0);
        for j in 0..K {
            let r = Rotations::matrix(&g.fixed_rows::<9>(9 * j).into_owned());
            let w = xi.fixed_rows::<3>(3 * j);
            let direction = r.column(2).into_owned();
            let rate = r.column(0) * w[1] - r.column(1) * w[0];
            position += direction * D::from(self.lengths[j]);
            velocity += rate * D::from(self.lengths[j]);
            sum += velocity.dot(&velocity) * (0.5 * self.masses[j])
                - position[2] * (self.masses[j] * self.gravity)
                + w[2] * w[2] * (0.5 * self.spin);
        }
        sum
    }
}

impl<const K: usize, const N: usize, const E: usize> SphericalChain<K, N, E> {
    /// The configuration and body velocity (spin zero) of link directions qᵢ (unit vectors)
    /// and their rates q̇ᵢ (perpendicular to qᵢ): Rᵢ is the rotation about e₃ × qᵢ taking e₃
    /// to qᵢ, and Ωᵢ = Rᵢᵀ(qᵢ × q̇ᵢ).
    pub fn state(
        &self,
        directions: &[Vector3; K],
        rates: &[Vector3; K],
    ) -> (SVector<f64, E>, SVector<f64, N>) {
        let mut g = SVector::<f64, E>::zeros();
        let mut xi = SVector::<f64, N>::zeros();
        for j in 0..K {
            let q = directions[j].normalize();
            let axis = Vector3::z().cross(&q);
            let angle = axis.norm().atan2(q.z);
            let r: Matrix3 = if axis.norm() > 0.0 {
                so3::exp(&(axis.normalize() * angle))
            } else if q.z > 0.0 {
                Matrix3::identity()
            } else {
                so3::exp(&Vector3::new(std::f64::consts::PI, 0.0, 0.0))
            };
            g.fixed_rows_mut::<9>(9 * j)
                .copy_from(&Rotations::element(&r));
            xi.fixed_rows_mut::<3>(3 * j)
                .copy_from(&(r.transpose() * q.cross(&rates[j])));
        }
        (g, xi)
    }

    /// The positions xᵢ of the masses.
    pub fn positions(&self, g: &SVector<f64, E>) -> [Vector3; K] {
        let mut position = Vector3::zeros();
        std::array::from_fn(|j| {
            let r = Rotations::matrix(&g.fixed_rows::<9>(9 * j).into_owned());
            position += r.column(2) * self.lengths[j];
            position
        })
    }
}
