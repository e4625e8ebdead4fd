//! Observers of rigid-body runs: the analogue of [`crate::stepping::observer`] on SO(3).
//!
//! They are [`Observer`]s of [`RigidPoint`]s: they see the initial point (step 0) and the
//! points after the steps they ask for, compose as tuples, switch on and off as `Option`, thin
//! out with [`crate::stepping::observer::Every`], and may stop a run with [`ControlFlow::Break`]. A run
//! with no observer (`&mut ()`) completes no points.
//!
//! Provided: [`RigidTrajectory`] (rotation matrix, quaternion and Ω per point),
//! [`EnergyError`] and [`InvariantError`] (body Casimirs and other invariants), the observers
//! of [`crate::stepping::observer`] here implemented for rigid bodies, [`AngularMomentumError`] (the
//! spatial angular momenta about the model's symmetry axes) and
//! [`OrthogonalityError`] (‖RᵀR − I‖).

use crate::model::rigid_body::{
    RigidBodyExt, RigidBodyInvariants, RigidBodyLagrangian, RigidBodySymmetries,
};
use crate::model::so3::{Matrix3, Vector3, orthogonality_error};
use crate::stepping::observer::{EnergyError, InvariantError, Observer};
use std::ops::ControlFlow;

/// A complete rigid-body point: time, attitude, body angular velocity and momentum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidPoint {
    /// Time t.
    pub t: f64,
    /// Attitude R (body to space).
    pub r: Matrix3<f64>,
    /// Body angular velocity Ω.
    pub omega: Vector3<f64>,
    /// Body angular momentum Π = ∂L/∂Ω.
    pub momentum: Vector3<f64>,
}

impl RigidPoint {
    /// The spatial angular momentum π = R Π.
    pub fn spatial_momentum(&self) -> Vector3<f64> {
        self.r * self.momentum
    }

    /// The attitude as a unit quaternion (w, x, y, z) with w ≥ 0 (Shepperd's method).
    pub fn quaternion(&self) -> [f64; 4] {
        quaternion(&self.r)
    }
}

/// The unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix (Shepperd's method: the
/// largest of the four squared components is taken first, so no division by a small number).
pub fn quaternion(r: &Matrix3<f64>) -> [f64; 4] {
    let trace = r[(0, 0)] + r[(1, 1)] + r[(2, 2)];
    let candidates = [trace, r[(0, 0)], r[(1, 1)], r[(2, 2)]];
    let mut k = 0;
    for i in 1..4 {
        if candidates[i] > candidates[k] {
            k = i;
        }
    }
    let mut q = match k {
        0 => {
            let w = 0.5 * (1.0 + trace).max(0.0).sqrt();
            let f = 0.25 / w;
            [
                w,
                (r[(2, 1)] - r[(1, 2)]) * f,
                (r[(0, 2)] - r[(2, 0)]) * f,
                (r[(1, 0)] - r[(0, 1)]) * f,
            ]
        }
        1 => {
            let x = 0.5 * (1.0 + 2.0 * r[(0, 0)] - trace).max(0.0).sqrt();
            let f = 0.25 / x;
            [
                (r[(2, 1)] - r[(1, 2)]) * f,
                x,
                (r[(0, 1)] + r[(1, 0)]) * f,
                (r[(0, 2)] + r[(2, 0)]) * f,
            ]
        }
        2 => {
            let y = 0.5 * (1.0 + 2.0 * r[(1, 1)] - trace).max(0.0).sqrt();
            let f = 0.25 / y;
            [
                (r[(0, 2)] - r[(2, 0)]) * f,
                (r[(0, 1)] + r[(1, 0)]) * f,
                y,
                (r[(1, 2)] + r[(2, 1)]) * f,
            ]
        }
        _ => {
            let z = 0.5 * (1.0 + 2.0 * r[(2, 2)] - trace).max(0.0).sqrt();
            let f = 0.25 / z;
            [
                (r[(1, 0)] - r[(0, 1)]) * f,
                (r[(0, 2)] + r[(2, 0)]) * f,
                (r[(1, 2)] + r[(2, 1)]) * f,
                z,
            ]
        }
    };
    if q[0] < 0.0 {
        q.iter_mut().for_each(|c| *c = -*c);
    }
    q
}

/// The rotation matrix of a unit quaternion (w, x, y, z), the inverse of [`quaternion`] (q and
/// −q give the same rotation).
pub fn rotation(q: &[f64; 4]) -> Matrix3<f64> {
    let [w, x, y, z] = *q;
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// Stores the observed points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RigidTrajectory {
    /// The points, in order.
    pub points: Vec<RigidPoint>,
}

impl RigidTrajectory {
    /// An empty trajectory.
    pub fn new() -> Self {
        RigidTrajectory::default()
    }
}

impl<L: ?Sized> Observer<L, RigidPoint> for RigidTrajectory {
    fn observe(&mut self, _: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        self.points.push(*point);
        ControlFlow::Continue(())
    }
}

/// The energy E = Π·Ω − L.
impl<L: RigidBodyLagrangian> Observer<L, RigidPoint> for EnergyError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        let energy = point.momentum.dot(&point.omega) - model.value(&point.r, &point.omega);
        let initial = *self.initial.get_or_insert(energy);
        self.max = self.max.max((energy - initial).abs());
        ControlFlow::Continue(())
    }
}

/// Largest deviation of the spatial angular momenta a·(RΠ) about the model's symmetry axes
/// (maximum over the axes) over the observed points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AngularMomentumError {
    /// Momenta at the first observed point, one per axis.
    pub initial: Vec<f64>,
    /// ‖Π‖ at the first observed point (the scale for [`AngularMomentumError::relative`]).
    pub scale: f64,
    /// Largest deviation seen.
    pub max: f64,
}

impl AngularMomentumError {
    /// `max` relative to the size ‖π₀‖ = ‖Π₀‖ of the initial angular momentum (or `max`
    /// itself when that is zero).
    pub fn relative(&self) -> f64 {
        if self.scale > 0.0 {
            self.max / self.scale
        } else {
            self.max
        }
    }
}

impl<L: RigidBodySymmetries> Observer<L, RigidPoint> for AngularMomentumError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        let first = self.initial.is_empty();
        let spatial = point.spatial_momentum();
        if first {
            self.scale = point.momentum.norm();
        }
        for i in 0..model.axis_count() {
            let momentum = model.axis(i).dot(&spatial);
            if first {
                self.initial.push(momentum);
            } else {
                self.max = self.max.max((momentum - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

/// The model's known invariants (body Casimirs).
impl<L: RigidBodyInvariants> Observer<L, RigidPoint> for InvariantError {
    fn observe(&mut self, model: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        let first = self.initial.is_empty();
        for i in 0..model.invariant_count() {
            let value = model.invariant(i, &point.r, &point.omega, &point.momentum);
            if first {
                self.initial.push(value);
            } else {
                self.max = self.max.max((value - self.initial[i]).abs());
            }
        }
        ControlFlow::Continue(())
    }
}

/// Largest ‖RᵀR − I‖ (Frobenius norm) over the observed points.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OrthogonalityError {
    /// Largest value seen.
    pub max: f64,
    /// Value at the last observed point.
    pub last: f64,
}

impl<L: ?Sized> Observer<L, RigidPoint> for OrthogonalityError {
    fn observe(&mut self, _: &L, _: usize, point: &RigidPoint) -> ControlFlow<()> {
        self.last = orthogonality_error(&point.r);
        self.max = self.max.max(self.last);
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::so3::exp;

    #[test]
    fn quaternion_matches_the_rotation_vector() {
        for x in [
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(0.0, 3.0, 0.1),
            Vector3::new(2.9, 0.0, 0.0),
            Vector3::new(0.0, 0.0, -3.1),
        ] {
            let q = quaternion(&exp(&x));
            let angle = x.norm();
            let mut expected = [
                (0.5 * angle).cos(),
                x[0] / angle * (0.5 * angle).sin(),
                x[1] / angle * (0.5 * angle).sin(),
                x[2] / angle * (0.5 * angle).sin(),
            ];
            if expected[0] < 0.0 {
                expected.iter_mut().for_each(|c| *c = -*c);
            }
            for i in 0..4 {
                assert!(
                    (q[i] - expected[i]).abs() < 1e-14,
                    "{x:?}: {q:?} vs {expected:?}"
                );
            }
        }
    }

    #[test]
    fn rotation_inverts_quaternion() {
        for x in [Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.0, 3.0, 0.1)] {
            let r = exp(&x);
            assert!((rotation(&quaternion(&r)) - r).amax() < 1e-15);
            let q = quaternion(&r).map(|c| -c);
            assert!((rotation(&q) - r).amax() < 1e-15);
        }
    }
}
