//! A polymer chain: n beads in ℝ³ joined by rigid bonds, with bending springs and gravity
//! (the freely rotating chain with bending stiffness, e.g. Doi & Edwards, *The Theory of
//! Polymer Dynamics*, 1986, §2.2; the bonds held by RATTLE as in molecular dynamics,
//! Andersen 1983).
//!
//! L = Σᵢ ½ m |ẋᵢ|² − Σ_{i=1}^{n−2} k (1 − cos θᵢ) − Σᵢ m g zᵢ,
//!
//! with bead i at xᵢ = (q_{3i}, q_{3i+1}, q_{3i+2}) (3n coordinates), θᵢ the angle between the
//! bonds dᵢ₋₁ = xᵢ − xᵢ₋₁ and dᵢ = xᵢ₊₁ − xᵢ at the interior bead i
//! (cos θᵢ = dᵢ₋₁·dᵢ / (|dᵢ₋₁| |dᵢ|): a straight chain has no bending energy), and the n − 1
//! rigid bonds
//!
//! g_i(q) = |xᵢ₊₁ − xᵢ|² − b² = 0,  i = 0, …, n − 2.
//!
//! The Lagrangian is a sum of local terms ([`LocalLagrangian`], width 9): term i reads beads
//! i − 1, i, i + 1 (at the ends the missing neighbour's index repeats bead i's and its slots
//! are ignored) and carries bead i's kinetic and gravitational energy and, at an interior
//! bead, its bending spring. The bonds are local constraints ([`Bonds`], width 6: the two
//! beads of a bond), run as [`SparseConstraints`]: RATTLE then takes O(n) per step (see
//! `benches/polymer.rs`). Both the bonds and the springs are invariant under translations and
//! rotations, so without gravity the total momentum and angular momentum are conserved; with
//! gravity along −z, the horizontal momenta and the angular momentum about the z axis.
//!
//! The default state is a helix on the constraint manifold — radius 0.6 b, a turn of 2π/5
//! per bead, the rise that makes every bond b long — moving with velocities tangent to it
//! (each bond turned at its own rate: ẋᵢ₊₁ − ẋᵢ = ωᵢ × dᵢ keeps dᵢ·(ẋᵢ₊₁ − ẋᵢ) = 0), with no
//! total momentum.

use crate::params::{finite, non_negative, positive, size, unknown};
use nalgebra::{Const, DVector, SVector, Vector3};
use svi::Error;
use svi::Scalar;
use svi::Structure;
use svi::model::constraint::local::{LocalConstraints, SparseConstraints};
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian, Terms};

/// The polymer chain (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Polymer {
    /// Number of beads n (at least 2).
    pub n: usize,
    /// Mass m of each bead.
    pub mass: f64,
    /// Bond length b.
    pub bond: f64,
    /// Bending stiffness k.
    pub stiffness: f64,
    /// Gravitational acceleration g along −z (0: none).
    pub gravity: f64,
    /// Scale of the initial angular velocities of the bonds, |ωᵢ| (the beads' speeds are of
    /// order `speed` · b).
    pub speed: f64,
}

impl Default for Polymer {
    fn default() -> Self {
        Polymer {
            n: 64,
            mass: 1.0,
            bond: 1.0,
            stiffness: 1.0,
            gravity: 0.0,
            speed: 0.5,
        }
    }
}

/// The helix of the default state: its radius over b and the turn per bead.
const HELIX_RADIUS: f64 = 0.6;
const HELIX_TURN: f64 = 2.0 * std::f64::consts::PI / 5.0;

impl Polymer {
    /// The rigid bonds as local constraints.
    pub fn bonds(&self) -> Bonds {
        Bonds {
            n: self.n,
            bond: self.bond,
        }
    }

    /// The chain as `ConstrainedIntegrator::new` takes it: the Lagrangian as a sum of terms
    /// and the bonds as sparse constraints.
    pub fn constrained(&self) -> (Terms<Polymer>, SparseConstraints<Bonds>) {
        (Terms(self.clone()), SparseConstraints(self.bonds()))
    }

    /// Bead `i` of `q`.
    pub fn bead(q: &DVector<f64>, i: usize) -> Vector3<f64> {
        Vector3::new(q[3 * i], q[3 * i + 1], q[3 * i + 2])
    }

    /// The total momentum Σ m ẋᵢ.
    pub fn momentum(&self, v: &DVector<f64>) -> Vector3<f64> {
        (0..self.n).map(|i| Self::bead(v, i) * self.mass).sum()
    }

    /// The total angular momentum Σ m xᵢ × ẋᵢ about the origin.
    pub fn angular_momentum(&self, q: &DVector<f64>, v: &DVector<f64>) -> Vector3<f64> {
        (0..self.n)
            .map(|i| Self::bead(q, i).cross(&Self::bead(v, i)) * self.mass)
            .sum()
    }

    /// The distance between the first and the last bead.
    pub fn end_to_end(&self, q: &DVector<f64>) -> f64 {
        (Self::bead(q, self.n - 1) - Self::bead(q, 0)).norm()
    }

    /// The radius of gyration √(Σ |xᵢ − x̄|² / n).
    pub fn gyration_radius(&self, q: &DVector<f64>) -> f64 {
        let centre: Vector3<f64> =
            (0..self.n).map(|i| Self::bead(q, i)).sum::<Vector3<f64>>() / self.n as f64;
        let spread: f64 = (0..self.n)
            .map(|i| (Self::bead(q, i) - centre).norm_squared())
            .sum();
        (spread / self.n as f64).sqrt()
    }

    /// The invariants for the current parameters: the momenta along x and y and the angular
    /// momentum about z always, the momentum along z without gravity.
    fn invariant_names(&self) -> &'static [&'static str] {
        if self.gravity == 0.0 {
            &[
                "momentum_x",
                "momentum_y",
                "momentum_z",
                "angular_momentum_z",
            ]
        } else {
            &["momentum_x", "momentum_y", "angular_momentum_z"]
        }
    }
}

impl LocalLagrangian for Polymer {
    type Width = Const<9>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        3 * self.n
    }

    fn term_count(&self) -> usize {
        self.n
    }

    /// Beads i − 1, i, i + 1, three coordinates each (at an end, bead i stands in for the
    /// missing neighbour).
    #[inline]
    fn indices(&self, i: usize) -> [usize; 9] {
        let beads = [i.saturating_sub(1), i, (i + 1).min(self.n - 1)];
        std::array::from_fn(|slot| 3 * beads[slot / 3] + slot % 3)
    }

    #[inline]
    fn term<D: Scalar>(&self, i: usize, _t: D, q: &SVector<D, 9>, v: &SVector<D, 9>) -> D {
        let speed_squared = v[3] * v[3] + v[4] * v[4] + v[5] * v[5];
        let mut term = speed_squared * (0.5 * self.mass) - q[5] * (self.mass * self.gravity);
        if i > 0 && i + 1 < self.n {
            let before: [D; 3] = std::array::from_fn(|a| q[3 + a] - q[a]);
            let after: [D; 3] = std::array::from_fn(|a| q[6 + a] - q[3 + a]);
            let dot = |x: &[D; 3], y: &[D; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
            let cosine =
                dot(&before, &after) / (dot(&before, &before) * dot(&after, &after)).sqrt();
            term -= (D::from(1.0) - cosine) * self.stiffness;
        }
        term
    }
}

/// The rigid bonds of a [`Polymer`], |xᵢ₊₁ − xᵢ|² − b² = 0 for i = 0, …, n − 2: local
/// constraints of width 6 (the two beads of a bond).
#[derive(Debug, Clone, PartialEq)]
pub struct Bonds {
    /// Number of beads n.
    pub n: usize,
    /// Bond length b.
    pub bond: f64,
}

impl LocalConstraints for Bonds {
    type Width = Const<6>;

    fn count(&self) -> usize {
        self.n.saturating_sub(1)
    }

    /// Beads i and i + 1.
    #[inline]
    fn indices(&self, i: usize) -> [usize; 6] {
        std::array::from_fn(|slot| 3 * i + slot)
    }

    #[inline]
    fn constraint<D: Scalar>(&self, _i: usize, q: &SVector<D, 6>) -> D {
        let (dx, dy, dz) = (q[3] - q[0], q[4] - q[1], q[5] - q[2]);
        dx * dx + dy * dy + dz * dz - D::from(self.bond * self.bond)
    }

    fn constraint_name(&self, i: usize) -> String {
        format!("bond[{i}] (beads {i} and {})", i + 1)
    }
}

impl LocalInvariants for Polymer {
    fn invariant_count(&self) -> usize {
        self.invariant_names().len()
    }

    fn invariant_name(&self, index: usize) -> &'static str {
        self.invariant_names()
            .get(index)
            .copied()
            .unwrap_or_else(|| crate::params::no_such_index("invariant", "polymer", index))
    }

    fn invariant(&self, index: usize, _t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        match self.invariant_name(index) {
            "momentum_x" => self.momentum(v).x,
            "momentum_y" => self.momentum(v).y,
            "momentum_z" => self.momentum(v).z,
            _ => self.angular_momentum(q, v).z,
        }
    }
}

impl LocalDefaults for Polymer {
    fn name(&self) -> &'static str {
        "polymer"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("n", self.n as f64),
            ("mass", self.mass),
            ("bond", self.bond),
            ("stiffness", self.stiffness),
            ("gravity", self.gravity),
            ("speed", self.speed),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "n" => self.n = size(name, value, 2)?,
            "mass" => self.mass = positive(name, value)?,
            "bond" => self.bond = positive(name, value)?,
            "stiffness" => self.stiffness = non_negative(name, value)?,
            "gravity" => self.gravity = finite(name, value)?,
            "speed" => self.speed = finite(name, value)?,
            _ => {
                return Err(unknown(
                    "polymer",
                    name,
                    &["n", "mass", "bond", "stiffness", "gravity", "speed"],
                ));
            }
        }
        Ok(())
    }

    /// The helix of the module docs, with tangent velocities and no total momentum.
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let (n, b) = (self.n, self.bond);
        let radius = HELIX_RADIUS * b;
        let chord_squared = 2.0 * radius * radius * (1.0 - HELIX_TURN.cos());
        let rise = (b * b - chord_squared).sqrt();
        let mut q = DVector::zeros(3 * n);
        for i in 0..n {
            let angle = HELIX_TURN * i as f64;
            q[3 * i] = radius * angle.cos();
            q[3 * i + 1] = radius * angle.sin();
            q[3 * i + 2] = rise * i as f64;
        }
        // ẋᵢ₊₁ = ẋᵢ + ωᵢ × dᵢ, the ωᵢ alternating in sign (so the velocities stay of order
        // speed · b along the chain) and turning with i.
        let mut v = DVector::zeros(3 * n);
        for i in 0..n - 1 {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            let phase = 0.9 * i as f64;
            let omega =
                Vector3::new(phase.cos(), phase.sin(), 0.5).normalize() * (sign * self.speed);
            let step = omega.cross(&(Self::bead(&q, i + 1) - Self::bead(&q, i)));
            for a in 0..3 {
                v[3 * (i + 1) + a] = v[3 * i + a] + step[a];
            }
        }
        let mean = self.momentum(&v) / (self.mass * n as f64);
        for i in 0..n {
            for a in 0..3 {
                v[3 * i + a] -= mean[a];
            }
        }
        (0.0, q, v)
    }

    /// A hundredth of a time unit: the bending modes' periods are a few units (√(m b²/k)
    /// sets their scale), the bonds turn at about `speed` radians per unit.
    fn default_step(&self) -> f64 {
        0.01
    }

    /// A hundred units: many bending periods.
    fn default_horizon(&self) -> f64 {
        100.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::U12;
    use svi::model::constraint::{Constraints, ConstraintsExt};
    use svi::{Lagrangian, LagrangianExt};

    /// Four beads written as one Lagrangian of fixed size (12 coordinates), independently of
    /// the terms: the reference for the sum of terms.
    struct FourBeads(Polymer);

    impl Lagrangian<U12> for FourBeads {
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 12>, v: &SVector<D, 12>) -> D {
            let p = &self.0;
            let bead = |x: &SVector<D, 12>, i: usize| x.fixed_rows::<3>(3 * i).into_owned();
            let kinetic = v.dot(v) * (0.5 * p.mass);
            let height = (q[2] + q[5] + q[8] + q[11]) * (p.mass * p.gravity);
            let mut bending = D::from(0.0);
            for i in 1..3 {
                let before = bead(q, i) - bead(q, i - 1);
                let after = bead(q, i + 1) - bead(q, i);
                let cosine = before.dot(&after) / (before.dot(&before) * after.dot(&after)).sqrt();
                bending += (D::from(1.0) - cosine) * p.stiffness;
            }
            kinetic - height - bending
        }
    }

    fn four_beads() -> Polymer {
        Polymer {
            n: 4,
            gravity: 9.81,
            stiffness: 2.5,
            mass: 1.5,
            ..Polymer::default()
        }
    }

    /// The sum of terms equals the fixed-size Lagrangian: value, force, momentum.
    #[test]
    fn the_terms_sum_to_the_fixed_size_lagrangian() {
        let polymer = four_beads();
        let (_, q, v) = polymer.initial_state();
        let fixed = FourBeads(polymer.clone());
        let (qs, vs) = (
            SVector::<f64, 12>::from_column_slice(q.as_slice()),
            SVector::<f64, 12>::from_column_slice(v.as_slice()),
        );
        let terms = Terms(polymer);
        assert!(
            (terms.lagrangian(0.0_f64, &q, &v) - fixed.lagrangian(0.0, &qs, &vs)).abs() < 1e-13
        );
        let force = terms.force(0.0, &q, &v);
        let expected = fixed.force(0.0, &qs, &vs);
        let difference = (force - DVector::from_column_slice(expected.as_slice())).amax();
        assert!(difference < 1e-13, "{difference:e}");
        let momentum = terms.momentum(0.0, &q, &v);
        assert!((momentum - &v * 1.5).amax() < 1e-15);
    }

    /// The default state lies on the bonds, with tangent velocities and no total momentum.
    #[test]
    fn the_default_helix_is_on_the_bonds_and_moves_tangentially() {
        for n in [2, 3, 10, 200] {
            let polymer = Polymer {
                n,
                ..Polymer::default()
            };
            let (_, q, v) = polymer.initial_state();
            let (_, bonds) = polymer.constrained();
            assert_eq!(bonds.count(), n - 1);
            // Round-off of differences of coordinates up to q.amax().
            let tolerance = 4.0 * f64::EPSILON * q.amax().max(1.0);
            assert!(bonds.values(&q).amax() < tolerance, "n = {n}");
            let rate = bonds.jacobian(&q) * &v;
            assert!(rate.amax() < tolerance, "n = {n}: {}", rate.amax());
            // A sum of n velocities of order `speed`: round-off grows with n.
            assert!(polymer.momentum(&v).amax() < 1e-15 * n as f64, "n = {n}");
            let speeds = (0..n).map(|i| Polymer::bead(&v, i).norm());
            assert!(speeds.fold(0.0, f64::max) < 2.0 * polymer.speed * polymer.bond);
        }
    }

    /// The bending energy k (1 − cos θ): zero on a straight chain, k at a right angle.
    #[test]
    fn bending_is_zero_when_straight_and_k_at_a_right_angle() {
        let polymer = Polymer {
            n: 3,
            stiffness: 3.0,
            ..Polymer::default()
        };
        let zero = DVector::zeros(9);
        let straight = DVector::from_vec(vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
        let bent = DVector::from_vec(vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
        let terms = Terms(polymer);
        assert!(terms.lagrangian(0.0_f64, &straight, &zero).abs() < 1e-15);
        assert!((terms.lagrangian(0.0_f64, &bent, &zero) + 3.0).abs() < 1e-15);
    }

    /// Parameters by name; sizes below two beads and unknown names are errors.
    #[test]
    fn parameters_are_checked() {
        let mut polymer = Polymer::default();
        polymer.set_parameter("n", 1000.0).unwrap();
        assert_eq!(polymer.dimension(), 3000);
        assert!(polymer.set_parameter("n", 1.0).is_err());
        assert!(polymer.set_parameter("mass", 0.0).is_err());
        assert!(polymer.set_parameter("colour", 1.0).is_err());
        polymer.set_parameter("gravity", 9.81).unwrap();
        assert_eq!(polymer.invariant_count(), 3);
        assert_eq!(polymer.invariant_name(2), "angular_momentum_z");
    }
}
