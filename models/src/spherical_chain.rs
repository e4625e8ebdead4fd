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

use crate::params;
use nalgebra::{SMatrix, SVector};
use svi::lie_group::{GroupDefaults, GroupLagrangian, GroupSymmetries, Power, Rotations, so3};
use svi::model::group::LocalDerivatives;
use svi::model::group::pair_terms::{self, PairTerms};
use svi::{Error, Scalar};

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

/// The chain of eight links that the command line runs as `spherical-chain`.
pub type SphericalChain8 = SphericalChain<8, 24, 72>;

/// The names of the link lengths, `l1` to `l32` (a chain has at most 32 links).
const LENGTH_NAMES: [&str; 32] = [
    "l1", "l2", "l3", "l4", "l5", "l6", "l7", "l8", "l9", "l10", "l11", "l12", "l13", "l14", "l15",
    "l16", "l17", "l18", "l19", "l20", "l21", "l22", "l23", "l24", "l25", "l26", "l27", "l28",
    "l29", "l30", "l31", "l32",
];

/// The names of the masses, `m1` to `m32`.
const MASS_NAMES: [&str; 32] = [
    "m1", "m2", "m3", "m4", "m5", "m6", "m7", "m8", "m9", "m10", "m11", "m12", "m13", "m14", "m15",
    "m16", "m17", "m18", "m19", "m20", "m21", "m22", "m23", "m24", "m25", "m26", "m27", "m28",
    "m29", "m30", "m31", "m32",
];

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
    const STRUCTURED: bool = true;

    /// Its terms' factor indices ([`PairTerms`]).
    fn check_structure(&self) -> Result<(), svi::Error> {
        pair_terms::check_factors::<_, 3, 9, N>(self)
    }

    /// Term by term ([`PairTerms`]).
    fn local_gradient(
        &self,
        g: &SVector<f64, E>,
        w: &SVector<f64, N>,
        configuration: bool,
    ) -> (SVector<f64, N>, SVector<f64, N>) {
        pair_terms::local_gradient(self, g, w, configuration)
    }

    /// Term by term ([`PairTerms`]).
    fn local_hessian(
        &self,
        g: &SVector<f64, E>,
        w: &SVector<f64, N>,
        configuration: bool,
        out: &mut LocalDerivatives<N>,
    ) {
        pair_terms::local_hessian(self, g, w, configuration, out);
    }

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

/// The chain's Lagrangian as terms on pairs of links: with Mⱼ = Σ_{i≥j} mᵢ (the mass at and
/// below joint j), |ẋᵢ|² = Σ_{j,k≤i} l_j l_k q̇_j·q̇_k and xᵢ·e₃ = Σ_{j≤i} l_j q_j·e₃ give
///
/// L = Σ_j [½ M_j l_j² |q̇_j|² + ½ J Ω_{j,3}² − g₀ M_j l_j q_j·e₃] + Σ_{j<k} M_k l_j l_k q̇_j·q̇_k,
///
/// K terms on one link (e < K: link e) and K(K − 1)/2 on pairs (j, k), j < k, in the order
/// (0, 1), (0, 2), …, (1, 2), ….
impl<const K: usize, const N: usize, const E: usize> PairTerms<3, 9> for SphericalChain<K, N, E> {
    type Factor = Rotations;

    fn term_count(&self) -> usize {
        K * (K + 1) / 2
    }

    fn factors(&self, e: usize) -> [usize; 2] {
        if e < K {
            return [e, e];
        }
        let mut rest = e - K;
        for j in 0..K {
            let row = K - 1 - j;
            if rest < row {
                return [j, j + 1 + rest];
            }
            rest -= row;
        }
        [K - 1, K - 1]
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, g: [&SVector<D, 9>; 2], xi: [&SVector<D, 3>; 2]) -> D {
        let [j, k] = self.factors(e);
        let below = |k: usize| self.masses[k..].iter().sum::<f64>();
        let rate = |g: &SVector<D, 9>, w: &SVector<D, 3>| {
            let r = Rotations::matrix(g);
            r.column(0) * w[1] - r.column(1) * w[0]
        };
        if j == k {
            let (mass, length) = (below(j), self.lengths[j]);
            let q_rate = rate(g[0], xi[0]);
            let height = Rotations::matrix(g[0])[(2, 2)];
            q_rate.dot(&q_rate) * (0.5 * mass * length * length)
                + xi[0][2] * xi[0][2] * (0.5 * self.spin)
                - height * (self.gravity * mass * length)
        } else {
            rate(g[0], xi[0]).dot(&rate(g[1], xi[1]))
                * (below(k) * self.lengths[j] * self.lengths[k])
        }
    }
}

/// The rotations of the whole chain about the vertical, ζ = (e₃, …, e₃): the vertical
/// angular momentum Σ_j (R_j μ_j)·e₃ is conserved.
impl<const K: usize, const N: usize, const E: usize> GroupSymmetries<N, E>
    for SphericalChain<K, N, E>
{
    #[inline]
    fn generator_count(&self) -> usize {
        1
    }

    fn momentum_name(&self, index: usize) -> &'static str {
        match index {
            0 => "L_z",
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }

    #[inline]
    fn generator(&self, index: usize) -> SVector<f64, N> {
        match index {
            0 => SVector::from_fn(|i, _| if i % 3 == 2 { 1.0 } else { 0.0 }),
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }
}

impl<const K: usize, const N: usize, const E: usize> GroupDefaults<N, E>
    for SphericalChain<K, N, E>
{
    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// `l1` … `lK`, `m1` … `mK`, `g`, `j`.
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        let lengths = LENGTH_NAMES.iter().zip(&self.lengths);
        let masses = MASS_NAMES.iter().zip(&self.masses);
        lengths
            .chain(masses)
            .map(|(name, value)| (*name, *value))
            .chain([("g", self.gravity), ("j", self.spin)])
            .collect()
    }

    /// Lengths, masses and `j` finite and positive; `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        if let Some(i) = LENGTH_NAMES.iter().take(K).position(|n| *n == name) {
            self.lengths[i] = params::positive(name, value)?;
        } else if let Some(i) = MASS_NAMES.iter().take(K).position(|n| *n == name) {
            self.masses[i] = params::positive(name, value)?;
        } else if name == "g" {
            self.gravity = params::non_negative(name, value)?;
        } else if name == "j" {
            self.spin = params::positive(name, value)?;
        } else {
            let known: Vec<&str> = self.parameters().iter().map(|(n, _)| *n).collect();
            return Err(params::unknown(Self::NAME, name, &known));
        }
        Ok(())
    }

    /// Link i (from 0) leans by 0.3 + 0.05 i from the downward vertical, turned by 0.5 i
    /// about it, with rate (0.2, −0.1 i, 0.05) less its component along the link; no spin.
    fn initial_state(&self) -> (SVector<f64, E>, SVector<f64, N>) {
        let directions: [Vector3; K] = std::array::from_fn(|i| {
            let (tilt, turn) = (0.3 + 0.05 * i as f64, 0.5 * i as f64);
            Vector3::new(
                tilt.sin() * turn.cos(),
                tilt.sin() * turn.sin(),
                -tilt.cos(),
            )
        });
        let rates: [Vector3; K] = std::array::from_fn(|i| {
            let v = Vector3::new(0.2, -0.1 * i as f64, 0.05);
            v - directions[i] * directions[i].dot(&v)
        });
        self.state(&directions, &rates)
    }

    /// h = 0.002.
    fn default_step(&self) -> f64 {
        0.002
    }

    /// T = 2.
    fn default_horizon(&self) -> f64 {
        2.0
    }
}

impl<const K: usize, const N: usize, const E: usize> SphericalChain<K, N, E> {
    /// The model's name (for every number of links; the command line runs
    /// [`SphericalChain8`]).
    pub const NAME: &'static str = "spherical-chain";

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
