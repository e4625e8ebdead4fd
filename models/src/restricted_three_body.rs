//! The planar circular restricted three-body problem in the frame rotating with the
//! primaries: an asteroid (a test particle) moved by the Sun and Jupiter on their circular
//! orbit, the classic model of resonances and chaos in the asteroid belt.
//!
//! # Units and frame
//!
//! The primaries' distance, their total mass, the gravitational constant and their angular
//! velocity are 1 (so their period is 2π). The frame rotates with them about their centre of
//! mass: the primary of mass 1 − μ (the Sun) rests at (−μ, 0), the one of mass μ (Jupiter) at
//! (1 − μ, 0).
//!
//! # Lagrangian
//!
//! L(x, y, ẋ, ẏ) = ½(ẋ² + ẏ²) + (x ẏ − y ẋ) + Ω(x, y),
//! Ω(x, y) = ½(x² + y²) + (1 − μ)/r₁ + μ/r₂,
//!
//! with r₁ = √((x + μ)² + y²) and r₂ = √((x − 1 + μ)² + y²): the inertial kinetic energy
//! ½|q̇ + ω × q|² written in the rotating frame, plus the potential of the primaries
//! (Murray & Dermott 1999, §3.3; Szebehely 1967, §1.3).
//!
//! # Equations of motion
//!
//! ẍ − 2ẏ = ∂Ω/∂x, ÿ + 2ẋ = ∂Ω/∂y: the Coriolis terms come from x ẏ − y ẋ, the part of L
//! linear in the velocity (a gyroscopic term, like a charge in a magnetic field).
//!
//! # Structure
//!
//! [`Structure::General`]. The mass matrix L_q̇q̇ is the identity, but L is not ½q̇ᵀMq̇ − V(q):
//! the momentum p = ∂L/∂q̇ = (ẋ − y, ẏ + x) is not Mq̇, and ∂L/∂q = (ẏ + ∂Ω/∂x, −ẋ + ∂Ω/∂y)
//! depends on the velocity (L_qq̇ ≠ 0). [`Structure::ConstantMass`] promises both (SVI's
//! Hessian-free fixed point reads the force without q̇, and q̇ = M⁻¹p is cached; the explicit
//! Störmer–Verlet kick uses ∂L/∂q at the old velocity), so it would be false here, and the
//! stepping loop's check at run start refuses it (∂L/∂q̇ ≠ 0 at q̇ = 0, L_qq̇ ≠ 0). The methods
//! therefore solve their stage equations by Newton's method with the full Hessian blocks.
//! L does not depend on t (`TIME_DEPENDENT = false`), and there is no external force.
//!
//! # Invariants
//!
//! The energy function E = p·q̇ − L = ½(ẋ² + ẏ²) − Ω(x, y) is conserved; the Jacobi constant
//! C = 2Ω − (ẋ² + ẏ²) = −2E is its usual astronomical form ([`RestrictedThreeBody::jacobi`],
//! the model's one invariant, `jacobi`). There is no continuous symmetry (the primaries fix
//! the frame), and no closed-form solution except at μ = 0, where the particle moves on a
//! Kepler ellipse about the origin seen in the rotating frame ([`RestrictedThreeBody`]'s
//! [`ExactSolution`] gives that case and `None` otherwise).
//!
//! # Initial state
//!
//! The particle's osculating heliocentric elements at t = 0 are `a` (semi-major axis) and
//! `e` (eccentricity): the two-body Kepler orbit about the primary of mass 1 − μ alone (G M =
//! 1 − μ), prograde, with its pericentre on the +x axis (the line from the Sun through
//! Jupiter) and the particle at that pericentre. Heliocentric position and velocity are
//! (r_p, 0) and (0, v_p), r_p = a(1 − e), v_p = √((1 − μ)(1 + e)/(a(1 − e))). In the
//! inertial frame whose axes coincide with the rotating frame's at t = 0 (centre of mass at
//! rest), the Sun is at (−μ, 0) with velocity (0, −μ), so the particle is at
//! r = (r_p − μ, 0) with velocity v_inertial = (0, v_p − μ); in the rotating frame
//! r_rot = r and v_rot = v_inertial − ω × r = (0, v_p − r_p).
//!
//! # Defaults
//!
//! μ = 1/(1 + 1047.348644) = 9.5388 · 10⁻⁴, the ratio m_J/(m_S + m_J) from the IAU's
//! mass ratio M_Sun/M_Jupiter = 1047.348644 (IAU 2009 System of Astronomical Constants,
//! Luzum et al. 2011, Table 1). a = 0.6, e = 0.1: an
//! asteroid at 3.1 AU, between the 3:1 (a = 0.48) and 2:1 (a = 0.63) resonances with Jupiter,
//! on a regular orbit (REBOUND's MEGNO ≈ 2, `benches/megno_map_rebound.py`). Step h = 0.05
//! (about 60 steps per orbit of the particle), horizon T = 2π · 100 (100 periods of the
//! primaries).
//!
//! # References
//!
//! C. D. Murray, S. F. Dermott, *Solar System Dynamics*, Cambridge University Press (1999),
//! ch. 3 (eqs. 3.15–3.17 and 3.22–3.28: the rotating-frame equations and the Jacobi
//! constant). V. Szebehely, *Theory of Orbits*, Academic Press (1967), ch. 1 and 4. B. Luzum
//! et al., *The IAU 2009 system of astronomical constants*, Celest. Mech. Dyn. Astron. 110
//! (2011) 293–304.

use nalgebra::{SVector, U2};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::kepler::KeplerOrbit;
use crate::params;

/// The planar circular restricted three-body problem in the rotating frame,
/// L = ½|q̇|² + (x ẏ − y ẋ) + ½|q|² + (1 − μ)/r₁ + μ/r₂; the elements `a` and `e` only select
/// the default initial state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestrictedThreeBody {
    /// Mass ratio μ = m₂/(m₁ + m₂) of the smaller primary, 0 < μ ≤ ½.
    pub mu: f64,
    /// Osculating heliocentric semi-major axis of the particle at t = 0 (> 0).
    pub a: f64,
    /// Osculating heliocentric eccentricity of the particle at t = 0, 0 ≤ e < 1.
    pub e: f64,
}

impl RestrictedThreeBody {
    /// Registry name of the model.
    pub const NAME: &'static str = "restricted-three-body";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 3] = ["mu", "a", "e"];
    /// The Sun–Jupiter mass ratio m_J/(m_S + m_J) = 1/(1 + 1047.348644) (IAU 2009).
    pub const SUN_JUPITER: f64 = 1.0 / (1.0 + 1047.348644);
    /// The smallest distance of the initial pericentre from either primary that
    /// [`Defaults::set_parameter`] accepts (in units of the primaries' distance).
    pub const MIN_DISTANCE: f64 = 1e-3;

    /// A model with mass ratio `mu` and the particle's initial elements `a`, `e`, checked as
    /// [`Defaults::set_parameter`] checks them.
    pub fn new(mu: f64, a: f64, e: f64) -> Result<Self, Error> {
        let mut model = Self::default();
        model.set_parameter("mu", mu)?;
        // a and e together: the pericentre checked after only one of them could refuse a
        // valid pair.
        let model = Self {
            a: params::positive("a", a)?,
            e: eccentricity("e", e)?,
            ..model
        };
        model.check_elements("a")?;
        Ok(model)
    }

    /// The effective potential Ω(x, y) = ½(x² + y²) + (1 − μ)/r₁ + μ/r₂.
    pub fn effective_potential(&self, x: f64, y: f64) -> f64 {
        let mu = self.mu;
        let r1 = (x + mu).hypot(y);
        let r2 = (x - 1.0 + mu).hypot(y);
        0.5 * (x * x + y * y) + (1.0 - mu) / r1 + mu / r2
    }

    /// The gradient (∂Ω/∂x, ∂Ω/∂y) of the effective potential.
    pub fn effective_potential_gradient(&self, x: f64, y: f64) -> SVector<f64, 2> {
        let mu = self.mu;
        let (dx1, dx2) = (x + mu, x - 1.0 + mu);
        let r1 = dx1.hypot(y);
        let r2 = dx2.hypot(y);
        let (k1, k2) = ((1.0 - mu) / r1.powi(3), mu / r2.powi(3));
        SVector::from([x - k1 * dx1 - k2 * dx2, y - k1 * y - k2 * y])
    }

    /// The Jacobi constant C = 2Ω(x, y) − (ẋ² + ẏ²) (−2 times the energy p·q̇ − L).
    pub fn jacobi(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        2.0 * self.effective_potential(q[0], q[1]) - v.norm_squared()
    }

    /// The particle's heliocentric pericentre distance a(1 − e) and pericentre speed
    /// √((1 − μ)(1 + e)/(a(1 − e))) of the two-body orbit about the primary of mass 1 − μ.
    pub fn pericentre(&self) -> (f64, f64) {
        let distance = self.a * (1.0 - self.e);
        let speed = ((1.0 - self.mu) * (1.0 + self.e) / distance).sqrt();
        (distance, speed)
    }

    /// Check the elements a, e (the error names `name`): a > 0, 0 ≤ e < 1, and the
    /// pericentre at least [`Self::MIN_DISTANCE`] from both primaries.
    fn check_elements(&self, name: &str) -> Result<(), Error> {
        let (distance, _) = self.pericentre();
        let from_second = (distance - 1.0).abs();
        if distance < Self::MIN_DISTANCE || from_second < Self::MIN_DISTANCE {
            return Err(Error::invalid(
                name,
                format!(
                    "a = {:?}, e = {:?} put the initial pericentre at distance {distance:?} \
                     from the primary of mass 1 - mu and {from_second:?} from the other; \
                     both must be at least {:?}",
                    self.a,
                    self.e,
                    Self::MIN_DISTANCE
                ),
            ));
        }
        Ok(())
    }
}

impl Default for RestrictedThreeBody {
    /// μ = Sun–Jupiter ([`RestrictedThreeBody::SUN_JUPITER`]), a = 0.6, e = 0.1.
    fn default() -> Self {
        Self {
            mu: Self::SUN_JUPITER,
            a: 0.6,
            e: 0.1,
        }
    }
}

impl Lagrangian<U2> for RestrictedThreeBody {
    const TIME_DEPENDENT: bool = false;
    // Not `ConstantMass`: p = q̇ + (−y, x) and ∂L/∂q depends on q̇ (see the module docs).
    const STRUCTURE: Structure = Structure::General;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let (x, y) = (q[0], q[1]);
        let (vx, vy) = (v[0], v[1]);
        let mu = self.mu;
        let (dx1, dx2) = (x + mu, x + (mu - 1.0));
        let (s1, s2) = (dx1 * dx1 + y * y, dx2 * dx2 + y * y);
        // 1/r written as r·r⁻², as in `Kepler`: one division instead of two under AD.
        let gravity = s1.sqrt() * s1.recip() * (1.0 - mu) + s2.sqrt() * s2.recip() * mu;
        (vx * vx + vy * vy) * 0.5 + (x * vy - y * vx) + (x * x + y * y) * 0.5 + gravity
    }
}

/// No continuous symmetry: the primaries fix the rotating frame.
impl Symmetries<U2> for RestrictedThreeBody {}

impl Invariants<U2> for RestrictedThreeBody {
    /// One: the Jacobi constant.
    fn invariant_count(&self) -> usize {
        1
    }

    /// `"jacobi"`.
    ///
    /// # Panics
    /// If `index > 0`.
    fn invariant_name(&self, index: usize) -> &'static str {
        match index {
            0 => "jacobi",
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }

    /// C = 2Ω − |q̇|² ([`RestrictedThreeBody::jacobi`]).
    ///
    /// # Panics
    /// If `index > 0`.
    fn invariant(&self, index: usize, _t: f64, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        match index {
            0 => self.jacobi(q, v),
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
}

/// Check that an eccentricity is finite and in [0, 1).
fn eccentricity(name: &str, value: f64) -> Result<f64, Error> {
    params::finite(name, value)?;
    if !(0.0..1.0).contains(&value) {
        return Err(Error::invalid(
            name,
            format!("{value:?} is outside [0, 1) (the orbit must be bound)"),
        ));
    }
    Ok(value)
}

/// Rotation of the plane by the angle with cosine `cos` and sine `sin`.
fn rotate(w: &SVector<f64, 2>, cos: f64, sin: f64) -> SVector<f64, 2> {
    SVector::from([cos * w[0] - sin * w[1], sin * w[0] + cos * w[1]])
}

impl ExactSolution<U2> for RestrictedThreeBody {
    /// For μ = 0 only: the Kepler orbit (G M = 1) about the origin through (q₀, v₀) seen in
    /// the rotating frame, q(t) = R(−t) q_in(t), q̇(t) = R(−t)(v_in(t) − ω × q_in(t)), with
    /// the inertial state (q_in, v_in) of [`KeplerOrbit`] from q_in(t₀) = R(t₀) q₀,
    /// v_in(t₀) = R(t₀)(v₀ + ω × q₀). `None` for μ > 0 (no closed form), unbound or radial
    /// orbits, and non-finite input.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 2>,
        v0: &SVector<f64, 2>,
        t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        if self.mu != 0.0 || !(t - t0).is_finite() {
            return None;
        }
        let cross = |q: &SVector<f64, 2>| SVector::from([-q[1], q[0]]);
        let (sin0, cos0) = t0.sin_cos();
        let q_inertial = rotate(q0, cos0, sin0);
        let v_inertial = rotate(&(v0 + cross(q0)), cos0, sin0);
        let (q, v) = KeplerOrbit::from_state(&q_inertial, &v_inertial)?.state_after(t - t0);
        let (sin, cos) = t.sin_cos();
        let q_rotating = rotate(&q, cos, -sin);
        let v_rotating = rotate(&(v - cross(&q)), cos, -sin);
        Some((q_rotating, v_rotating))
    }
}

impl Defaults<U2> for RestrictedThreeBody {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["x", "y"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("mu", self.mu), ("a", self.a), ("e", self.e)]
    }

    /// `mu` finite in (0, ½]; `a` finite and positive; `e` finite in [0, 1); and the
    /// initial pericentre a(1 − e) on the +x axis at least [`Self::MIN_DISTANCE`] from both
    /// primaries. A refused value leaves the model unchanged.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let trial = match name {
            "mu" => {
                let mu = params::positive(name, value)?;
                if mu > 0.5 {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} exceeds 1/2 (mu is the smaller primary's share)"),
                    ));
                }
                Self { mu, ..*self }
            }
            "a" => Self {
                a: params::positive(name, value)?,
                ..*self
            },
            "e" => Self {
                e: eccentricity(name, value)?,
                ..*self
            },
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        };
        trial.check_elements(name)?;
        *self = trial;
        Ok(())
    }

    /// t₀ = 0, q₀ = (a(1 − e) − μ, 0), q̇₀ = (0, v_p − a(1 − e)) with
    /// v_p = √((1 − μ)(1 + e)/(a(1 − e))): the particle at the pericentre of its heliocentric
    /// orbit, on the +x axis (see the module docs).
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        let (distance, speed) = self.pericentre();
        (
            0.0,
            SVector::from([distance - self.mu, 0.0]),
            SVector::from([0.0, speed - distance]),
        )
    }

    /// h = 0.05.
    fn default_step(&self) -> f64 {
        0.05
    }

    /// T = 2π · 100 (100 periods of the primaries).
    fn default_horizon(&self) -> f64 {
        std::f64::consts::TAU * 100.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use svi::model::derived::LagrangianExt;

    /// Deterministic pseudo-random numbers in [0, 1) (a 64-bit LCG, Knuth's MMIX constants).
    fn uniform(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn accelerations_are_the_textbook_equations_of_motion() {
        let mut seed = 41;
        for mu in [RestrictedThreeBody::SUN_JUPITER, 0.012_150_58, 0.3, 0.5] {
            let model = RestrictedThreeBody { mu, a: 0.6, e: 0.1 };
            for _ in 0..50 {
                let q = SVector::from([
                    3.0 * uniform(&mut seed) - 1.5,
                    3.0 * uniform(&mut seed) - 1.5,
                ]);
                let v = SVector::from([
                    4.0 * uniform(&mut seed) - 2.0,
                    4.0 * uniform(&mut seed) - 2.0,
                ]);
                let acceleration = model.acceleration(0.0, &q, &v).unwrap();
                let gradient = model.effective_potential_gradient(q[0], q[1]);
                // ẍ − 2ẏ = Ω_x, ÿ + 2ẋ = Ω_y.
                let expected = SVector::from([gradient[0] + 2.0 * v[1], gradient[1] - 2.0 * v[0]]);
                let scale = expected.amax().max(1.0);
                assert!(
                    (acceleration - expected).amax() < 1e-13 * scale,
                    "μ = {mu}, q = {q}, v = {v}: {acceleration} vs {expected}"
                );
                // The momentum is q̇ + ω × q and the mass matrix the identity.
                let p = model.momentum(0.0, &q, &v);
                assert_relative_eq!(p[0], v[0] - q[1], epsilon = 1e-15);
                assert_relative_eq!(p[1], v[1] + q[0], epsilon = 1e-15);
            }
        }
    }

    #[test]
    fn the_energy_is_minus_half_the_jacobi_constant() {
        let model = RestrictedThreeBody::default();
        let mut seed = 7;
        for _ in 0..20 {
            let q = SVector::from([uniform(&mut seed) * 2.0 - 1.0, uniform(&mut seed) + 0.1]);
            let v = SVector::from([uniform(&mut seed) - 0.5, uniform(&mut seed) - 0.5]);
            let energy = model.energy(0.0, &q, &v);
            assert_relative_eq!(energy, -0.5 * model.jacobi(&q, &v), epsilon = 1e-14);
            assert_eq!(model.invariant(0, 0.0, &q, &v), model.jacobi(&q, &v));
        }
    }

    #[test]
    fn initial_state_is_the_heliocentric_pericentre() {
        let model = RestrictedThreeBody::new(0.01, 0.7, 0.2).unwrap();
        let (t0, q, v) = model.initial_state();
        assert_eq!(t0, 0.0);
        // Heliocentric inertial state at t = 0: position relative to the Sun at (−μ, 0),
        // velocity v_rot + ω × q minus the Sun's inertial velocity (0, −μ).
        let relative = SVector::from([q[0] + 0.01, q[1]]);
        let velocity = SVector::from([v[0] - q[1], v[1] + q[0] + 0.01]);
        let gm = 0.99;
        let energy = 0.5 * velocity.norm_squared() - gm / relative.norm();
        assert_relative_eq!(-gm / (2.0 * energy), 0.7, epsilon = 1e-14);
        // Eccentricity from the angular momentum h: h² = G M a (1 − e²).
        let h = relative[0] * velocity[1] - relative[1] * velocity[0];
        assert_relative_eq!((1.0 - h * h / (gm * 0.7)).sqrt(), 0.2, epsilon = 1e-14);
        assert_relative_eq!(relative[0], 0.7 * 0.8, epsilon = 1e-15);
        assert_eq!(relative[1], 0.0);
        assert_eq!(velocity[0], 0.0);
    }

    #[test]
    fn parameters_are_checked() {
        let mut model = RestrictedThreeBody::default();
        for (name, value) in [
            ("mu", 0.0),
            ("mu", 0.6),
            ("mu", f64::NAN),
            ("a", 0.0),
            ("a", -1.0),
            ("e", 1.0),
            ("e", -0.1),
            // Pericentre on Jupiter: a(1 − e) = 1.
            ("a", 1.0 / 0.9),
            ("a", 1.0 / 0.9 + 1e-4),
        ] {
            match model.set_parameter(name, value) {
                Err(Error::InvalidParameter { name: got, .. }) => assert_eq!(got, name),
                other => panic!("{name} = {value}: {other:?}"),
            }
            assert_eq!(model, RestrictedThreeBody::default());
        }
        assert!(model.set_parameter("mu", 0.5).is_ok());
        assert!(model.set_parameter("e", 0.0).is_ok());
        assert!(model.set_parameter("a", 2.5).is_ok());
        assert!(model.set_parameter("m", 1.0).is_err());
        assert!(RestrictedThreeBody::new(0.1, 1.0, 0.0).is_err());
        assert!(RestrictedThreeBody::new(0.1, 2.0, 0.5).is_err());
        assert!(RestrictedThreeBody::new(0.1, 2.0, 0.4).is_ok());
        assert_relative_eq!(RestrictedThreeBody::SUN_JUPITER, 9.5388e-4, epsilon = 1e-8);
    }

    #[test]
    fn the_mu_zero_solution_starts_at_the_initial_state() {
        let model = RestrictedThreeBody {
            mu: 0.0,
            a: 0.8,
            e: 0.3,
        };
        let (t0, q0, v0) = model.initial_state();
        let (q, v) = model.exact_solution(t0, &q0, &v0, t0).unwrap();
        assert!(
            (q - q0).amax() < 1e-15 && (v - v0).amax() < 1e-14,
            "{q} {v}"
        );
        assert!(
            RestrictedThreeBody::default()
                .exact_solution(t0, &q0, &v0, 1.0)
                .is_none()
        );
    }
}
