//! A rigid body falling freely in space, on SE(3), with its exact solution.
//!
//! # Lagrangian
//!
//! A body of mass m and principal moments of inertia I₁, I₂, I₃ about its centre of mass
//! (the body origin), configuration g = (R, x) ∈ SE(3) (attitude and position of the centre of
//! mass), body velocity ξ = (ω, v) with Ṙ = Rω̂ and ẋ = Rv, in uniform gravity g₀ along −z:
//!
//! L(g, ξ) = ½ ωᵀ diag(I₁, I₂, I₃) ω + ½ m |v|² − m g₀ x₃.
//!
//! # Exact solution
//!
//! The centre of mass falls on a parabola, x(t) = x₀ + u₀t − ½ g₀ t² e₃ with u₀ = R₀v₀, and
//! v(t) = R(t)ᵀ(u₀ − g₀ t e₃). The rotation is torque-free (Euler's top). For
//! I₁ < I₂ < I₃ and M² > 2E I₂ (M = |Π|, E = ½ Ω·IΩ; rotation about the axis of largest
//! inertia) the body angular velocity is (Landau & Lifshitz, *Mechanics*, §37)
//!
//! Ω₁ = a₁ cn τ,  Ω₂ = a₂ sn τ,  Ω₃ = a₃ dn τ,  τ = λt + τ₀,
//!
//! a₁² = (2EI₃ − M²)/(I₁(I₃ − I₁)), a₂² = (2EI₃ − M²)/(I₂(I₃ − I₂)),
//! a₃² = (M² − 2EI₁)/(I₃(I₃ − I₁)), λ² = (I₃ − I₂)(M² − 2EI₁)/(I₁I₂I₃), and parameter
//! m = (I₂ − I₁)(2EI₃ − M²)/((I₃ − I₂)(M² − 2EI₁)); τ₀ = F(atan2(Ω₂/a₂, Ω₁/a₁) | m) fits the
//! initial phase (if Ω₃(0) < 0, the solution is that of (Ω₁, −Ω₂, −Ω₃), turned by π about the
//! first body axis). The attitude is R = Q R_z(φ) R_x(θ) R_z(ψ) in Euler angles about the
//! fixed angular momentum (Q e₃ = π/M): cos θ = Π₃/M, ψ = atan2(Π₁, Π₂), and the precession
//! φ̇ = M (Π₁²/I₁ + Π₂²/I₂)/(Π₁² + Π₂²), integrated by composite Gauss–Legendre quadrature
//! to round-off. The tests check the formulas against Euler's equations and Ṙ = RΩ̂ by central
//! differences.

use crate::elliptic::{amplitude, complete_first_kind, first_kind};
use crate::params;
use nalgebra::{SMatrix, SVector};
use svi::lie_group::{GroupDefaults, GroupLagrangian, GroupSymmetries, RigidMotions, so3};
use svi::spectral::quadrature::GaussLegendre;
use svi::{Error, Scalar};

type Matrix3 = SMatrix<f64, 3, 3>;
type Vector3 = SVector<f64, 3>;

/// A rigid body falling freely under gravity, on SE(3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FallingBody {
    /// Mass m (> 0).
    pub mass: f64,
    /// Principal moments of inertia about the centre of mass (> 0).
    pub inertia: [f64; 3],
    /// Gravitational acceleration g₀ along −z.
    pub gravity: f64,
}

impl Default for FallingBody {
    /// m = 1, I = diag(1, 2, 3), g₀ = 9.81.
    fn default() -> Self {
        FallingBody {
            mass: 1.0,
            inertia: [1.0, 2.0, 3.0],
            gravity: 9.81,
        }
    }
}

impl GroupLagrangian<6, 12> for FallingBody {
    type Group = RigidMotions;

    #[inline]
    fn lagrangian<D: Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
        let [i1, i2, i3] = self.inertia;
        let rotation = (xi[0] * xi[0] * i1 + xi[1] * xi[1] * i2 + xi[2] * xi[2] * i3) * 0.5;
        let translation = (xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]) * (0.5 * self.mass);
        rotation + translation - RigidMotions::position(g)[2] * (self.mass * self.gravity)
    }
}

impl FallingBody {
    /// The model's name.
    pub const NAME: &'static str = "falling-body";
    /// The parameter names.
    pub const PARAMETERS: [&'static str; 5] = ["m", "i1", "i2", "i3", "g"];
}

/// Gravity along −z leaves the rotations about the vertical through the origin, ζ = (e₃, 0),
/// and the horizontal translations, ζ = (0, e₁) and (0, e₂), as symmetries: the vertical
/// angular momentum (orbital and spin) and the horizontal linear momenta are conserved.
impl GroupSymmetries<6, 12> for FallingBody {
    #[inline]
    fn generator_count(&self) -> usize {
        3
    }

    fn momentum_name(&self, index: usize) -> &'static str {
        match index {
            0 => "L_z",
            1 => "p_x",
            2 => "p_y",
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }

    #[inline]
    fn generator(&self, index: usize) -> SVector<f64, 6> {
        match index {
            0 => SVector::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
            1 => SVector::from([0.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
            2 => SVector::from([0.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }
}

impl GroupDefaults<6, 12> for FallingBody {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        let [i1, i2, i3] = self.inertia;
        vec![
            ("m", self.mass),
            ("i1", i1),
            ("i2", i2),
            ("i3", i3),
            ("g", self.gravity),
        ]
    }

    /// `m`, `i1`, `i2`, `i3` finite and positive; `g` finite and non-negative.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m" => self.mass = params::positive(name, value)?,
            "i1" => self.inertia[0] = params::positive(name, value)?,
            "i2" => self.inertia[1] = params::positive(name, value)?,
            "i3" => self.inertia[2] = params::positive(name, value)?,
            "g" => self.gravity = params::non_negative(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// R₀ = exp(0.1, −0.2, 0.3), x₀ = (1, −2, 3), ω₀ = (1, 0.2, 0.8), v₀ = (0.5, 0, 2): a
    /// tumble about the axis of largest inertia while the body is thrown upwards.
    fn initial_state(&self) -> (SVector<f64, 12>, SVector<f64, 6>) {
        let r0 = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
        (
            RigidMotions::element(&r0, &Vector3::new(1.0, -2.0, 3.0)),
            SVector::from([1.0, 0.2, 0.8, 0.5, 0.0, 2.0]),
        )
    }

    /// h = 0.01.
    fn default_step(&self) -> f64 {
        0.01
    }

    /// T = 10.
    fn default_horizon(&self) -> f64 {
        10.0
    }

    /// [`FallingBody::exact`].
    fn exact_solution(
        &self,
        g0: &SVector<f64, 12>,
        xi0: &SVector<f64, 6>,
        t: f64,
    ) -> Option<(SVector<f64, 12>, SVector<f64, 6>)> {
        self.exact(g0, xi0, t)
    }
}

/// Rotation by `angle` about the z axis.
fn about_z(angle: f64) -> Matrix3 {
    so3::exp(&Vector3::new(0.0, 0.0, angle))
}

/// Rotation by `angle` about the x axis.
fn about_x(angle: f64) -> Matrix3 {
    so3::exp(&Vector3::new(angle, 0.0, 0.0))
}

/// The torque-free motion from (R₀, Ω₀) with Ω₃(0) ≥ 0 (module docs).
struct EulerTop {
    inertia: [f64; 3],
    amplitudes: [f64; 3],
    rate: f64,
    phase: f64,
    parameter: f64,
    quarter_period: f64,
    momentum: f64,
    frame: Matrix3,
}

/// Gauss points per unit of τ in the precession integral.
const PRECESSION_PANELS_PER_UNIT: f64 = 8.0;

impl EulerTop {
    fn new(inertia: [f64; 3], r0: &Matrix3, omega: &Vector3) -> Option<Self> {
        let [i1, i2, i3] = inertia;
        if !(0.0 < i1 && i1 < i2 && i2 < i3) {
            return None;
        }
        let pi = Vector3::from_fn(|k, _| inertia[k] * omega[k]);
        let m2 = pi.norm_squared();
        let e2 = pi.dot(omega);
        if m2 <= e2 * i2 || omega[2] < 0.0 {
            return None;
        }
        let amplitudes = [
            ((e2 * i3 - m2) / (i1 * (i3 - i1))).sqrt(),
            ((e2 * i3 - m2) / (i2 * (i3 - i2))).sqrt(),
            ((m2 - e2 * i1) / (i3 * (i3 - i1))).sqrt(),
        ];
        let parameter = (i2 - i1) * (e2 * i3 - m2) / ((i3 - i2) * (m2 - e2 * i1));
        let quarter_period = complete_first_kind(parameter);
        let start = (omega[1] / amplitudes[1]).atan2(omega[0] / amplitudes[0]);
        let mut top = EulerTop {
            inertia,
            amplitudes,
            rate: ((i3 - i2) * (m2 - e2 * i1) / (i1 * i2 * i3)).sqrt(),
            phase: first_kind(start, parameter, quarter_period),
            parameter,
            quarter_period,
            momentum: m2.sqrt(),
            frame: Matrix3::identity(),
        };
        let (theta, psi) = top.nutation(&top.body_momentum(0.0));
        top.frame = r0 * (about_x(theta) * about_z(psi)).transpose();
        Some(top)
    }

    /// Ω(t).
    fn omega(&self, t: f64) -> Vector3 {
        let am = amplitude(
            self.rate * t + self.phase,
            self.parameter,
            self.quarter_period,
        );
        let (sn, cn) = am.sin_cos();
        let dn = (1.0 - self.parameter * sn * sn).sqrt();
        let [a1, a2, a3] = self.amplitudes;
        Vector3::new(a1 * cn, a2 * sn, a3 * dn)
    }

    /// Π(t).
    fn body_momentum(&self, t: f64) -> Vector3 {
        let omega = self.omega(t);
        Vector3::from_fn(|k, _| self.inertia[k] * omega[k])
    }

    /// The Euler angles (θ, ψ) of a body momentum.
    fn nutation(&self, pi: &Vector3) -> (f64, f64) {
        (
            (pi[2] / self.momentum).clamp(-1.0, 1.0).acos(),
            pi[0].atan2(pi[1]),
        )
    }

    /// φ̇ at time t.
    fn precession_rate(&self, t: f64) -> f64 {
        let pi = self.body_momentum(t);
        let planar = pi[0] * pi[0] + pi[1] * pi[1];
        self.momentum * (pi[0] * pi[0] / self.inertia[0] + pi[1] * pi[1] / self.inertia[1]) / planar
    }

    /// R(t).
    fn attitude(&self, t: f64) -> Matrix3 {
        let gauss = GaussLegendre::new(10).expect("ten Gauss points");
        let panels = ((self.rate * t.abs() * PRECESSION_PANELS_PER_UNIT).ceil() as usize).max(1);
        let width = t / panels as f64;
        let mut phi = 0.0;
        for panel in 0..panels {
            let centre = (panel as f64 + 0.5) * width;
            for (x, w) in gauss.nodes().iter().zip(gauss.weights()) {
                phi += 0.5 * width * w * self.precession_rate(centre + 0.5 * width * x);
            }
        }
        let (theta, psi) = self.nutation(&self.body_momentum(t));
        self.frame * about_z(phi) * about_x(theta) * about_z(psi)
    }
}

impl FallingBody {
    /// The exact configuration and body velocity at time `t` from (g₀, ξ₀) at time 0 (module
    /// docs); `None` where the closed form does not apply (inertia not ordered
    /// I₁ < I₂ < I₃, or M² ≤ 2EI₂).
    pub fn exact(
        &self,
        g0: &SVector<f64, 12>,
        xi0: &SVector<f64, 6>,
        t: f64,
    ) -> Option<(SVector<f64, 12>, SVector<f64, 6>)> {
        let r0 = RigidMotions::rotation(g0);
        let x0 = RigidMotions::position(g0);
        let omega0 = xi0.fixed_rows::<3>(0).into_owned();
        let v0 = xi0.fixed_rows::<3>(3).into_owned();
        // Ω₃ < 0: the solution of (Ω₁, −Ω₂, −Ω₃) turned by π about the first body axis.
        let turn = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        let flipped = omega0[2] < 0.0;
        let (start, omega_start) = if flipped {
            (r0 * turn, turn * omega0)
        } else {
            (r0, omega0)
        };
        let top = EulerTop::new(self.inertia, &start, &omega_start)?;
        let (mut r, mut omega) = (top.attitude(t), top.omega(t));
        if flipped {
            r *= turn;
            omega = turn * omega;
        }
        let u0 = r0 * v0;
        let fall = Vector3::new(0.0, 0.0, self.gravity * t);
        let x = x0 + u0 * t - fall * (0.5 * t);
        let v = r.transpose() * (u0 - fall);
        let g = RigidMotions::element(&r, &x);
        let xi = SVector::from_iterator(omega.iter().chain(v.iter()).copied());
        Some((g, xi))
    }

    /// The energy ½ ω·Iω + ½ m|v|² + m g₀ x₃.
    pub fn energy(&self, g: &SVector<f64, 12>, xi: &SVector<f64, 6>) -> f64 {
        let rotation: f64 = (0..3).map(|k| 0.5 * self.inertia[k] * xi[k] * xi[k]).sum();
        let translation = 0.5 * self.mass * xi.fixed_rows::<3>(3).norm_squared();
        rotation + translation + self.mass * self.gravity * RigidMotions::position(g)[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> (SVector<f64, 12>, SVector<f64, 6>) {
        let r0 = so3::exp(&Vector3::new(0.1, -0.2, 0.3));
        let g0 = RigidMotions::element(&r0, &Vector3::new(1.0, -2.0, 3.0));
        (g0, SVector::from([1.0, 0.2, 0.8, 0.5, 0.0, 2.0]))
    }

    /// The closed form satisfies Euler's equations, Ṙ = RΩ̂ and ẋ = Rv (central differences,
    /// step 10⁻⁴: truncation about 10⁻⁹), at times up to 100, for both signs of Ω₃.
    #[test]
    fn the_exact_solution_solves_the_equations_of_motion() {
        let body = FallingBody::default();
        let (g0, xi0) = start();
        let mut mirrored = xi0;
        mirrored[2] = -mirrored[2];
        for xi in [xi0, mirrored] {
            let (g, back) = body.exact(&g0, &xi, 0.0).unwrap();
            assert!((g - g0).amax() < 1e-14 && (back - xi).amax() < 1e-14);
            for t in [0.3, 7.0, 61.5, 100.0] {
                let d = 1e-4;
                let (gp, xp) = body.exact(&g0, &xi, t + d).unwrap();
                let (gm, xm) = body.exact(&g0, &xi, t - d).unwrap();
                let (g, x) = body.exact(&g0, &xi, t).unwrap();
                let r = RigidMotions::rotation(&g);
                let omega = x.fixed_rows::<3>(0).into_owned();
                let pi = Vector3::from_fn(|k, _| body.inertia[k] * omega[k]);
                let rate = |a: &SVector<f64, 6>, b: &SVector<f64, 6>| {
                    Vector3::from_fn(|k, _| body.inertia[k] * (a[k] - b[k]) / (2.0 * d))
                };
                let euler = rate(&xp, &xm) - pi.cross(&omega);
                assert!(euler.amax() < 1e-7, "Euler's equations at t = {t}: {euler}");
                let r_dot = (RigidMotions::rotation(&gp) - RigidMotions::rotation(&gm)) / (2.0 * d);
                let kinematics = r_dot - r * so3::hat(&omega);
                assert!(kinematics.amax() < 1e-7, "Ṙ = RΩ̂ at t = {t}: {kinematics}");
                let x_dot = (RigidMotions::position(&gp) - RigidMotions::position(&gm)) / (2.0 * d);
                let v = x.fixed_rows::<3>(3).into_owned();
                assert!((x_dot - r * v).amax() < 1e-7, "ẋ = Rv at t = {t}");
                assert!(so3::orthogonality_error(&r) < 1e-13);
                // Relative to the sizes of the kinetic and potential parts (10⁵ at t = 100).
                let scale = 1.0
                    + 0.5 * x.norm_squared()
                    + body.gravity * RigidMotions::position(&g)[2].abs();
                let energy = body.energy(&g, &x) - body.energy(&g0, &xi);
                assert!(
                    energy.abs() < 1e-15 * scale,
                    "energy at t = {t}: {energy:e}"
                );
            }
        }
    }
}
