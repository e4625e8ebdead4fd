//! A charged particle in an axisymmetric magnetic bottle: a non-separable Hamiltonian.
//!
//! # Field
//!
//! On the axis the field is B_z(0, 0, z) = B₀(1 + z²/L²): weakest at the centre, growing
//! towards both ends (the mirrors). Off the axis it is the field of the azimuthal vector
//! potential A = A_φ(r, z) φ̂ with A_φ = (r/2) B₀(1 + z²/L²), in Cartesian coordinates
//!
//! A(x, y, z) = (B₀/2)(1 + z²/L²) (−y, x, 0),
//!
//! whose curl is, exactly (not only near the axis),
//!
//! B = ∇ × A = B₀ (−x z/L², −y z/L², 1 + z²/L²),
//!
//! divergence-free identically (∇·B = −2B₀z/L² + 2B₀z/L² = 0) and axisymmetric
//! (B_r = −B₀ r z/L² = −∂A_φ/∂z, B_z = (1/r)∂(r A_φ)/∂r). It is not a vacuum field:
//! ∇ × B = −(B₀ r/L²) φ̂ ≠ 0, the field of a volume current density (which does not enter
//! the particle's motion).
//!
//! # Hamiltonian
//!
//! A particle of mass m and charge e at x ∈ ℝ³ with canonical momentum p:
//!
//! H(x, p) = |p − e A(x)|²/(2m),
//!
//! non-separable ([`HamiltonianStructure::General`]: ∂²H/∂x∂p ≠ 0). Its Legendre transform is
//! L = ½ m|ẋ|² + e ẋ·A(x), with p = m ẋ + e A.
//!
//! # Equations of motion
//!
//! ẋ = (p − eA)/m = v and ṗ = (e/m) (∂A/∂x)ᵀ(p − eA), that is the Lorentz force
//! m v̇ = e v × B. Conserved: the energy H = ½ m|v|² and, by the rotational symmetry about
//! the axis (generator ξ(x) = (−y, x, 0)), the canonical angular momentum
//! p_φ = x p_y − y p_x = m(x v_y − y v_x) + e r A_φ (Noether). The magnetic moment
//! μ = m v_⊥²/(2|B|), v_⊥ the velocity across B, is an *adiabatic* invariant: conserved
//! to O(ε) oscillations with no secular drift over exponentially long times while the
//! gyroradius ρ is small against L, ε = ρ/L ≪ 1 (Kruskal; Northrop 1963). It is the
//! invariant `magnetic_moment_adiabatic`: only approximately constant, also along the exact
//! solution.
//!
//! # Why the particle is trapped
//!
//! With μ and the energy conserved, the motion along B is that of a particle in the
//! potential μ|B|: ½ m v_∥² + μ|B| = ½ m|v|². On the axis μ B₀(1 + z²/L²) is a harmonic
//! well, so the guiding centre bounces between the mirror points where |B| = m|v|²/(2μ) =
//! B₀/sin²α₀ (α₀ the pitch angle at z = 0), with the bounce frequency ω_b = v_⊥₀/L whatever
//! the amplitude, while it gyrates with Ω = e|B|/m. Since |B| grows without bound along the
//! axis, every particle with v_⊥ ≠ 0 is trapped (there is no loss cone). The ratio of
//! gyrations to bounces is Ω₀/ω_b = e B₀ L/(m v_⊥₀) = L/ρ₀ = 1/ε.
//!
//! # Defaults
//!
//! m = e = B₀ = 1 (the gyration at the centre has Ω₀ = eB₀/m = 1, period 2π), L = 10 and
//! ε = ρ₀/L = 1/40. The particle starts at z = 0 off the axis, x₀ = (L/4, 0, 0), with
//! v₀ = (0, v_⊥₀, v_∥₀), v_⊥₀ = v_∥₀ = εΩ₀L = 0.25: pitch angle 45°, so the mirror points
//! are where |B| = 2B₀, near z = ±L (on the axis exactly ±L), and the gyroradius ρ₀ = 0.25
//! is small against L, so μ is well conserved: 40 gyrations per bounce. Step
//! h = 2π/(32 Ω₀) (32 steps per gyration at the centre, 16 at the mirrors, where |B| is
//! doubled), horizon T = 10 bounce periods 10 · 2π/(εΩ₀) ≈ 2513 (12 800 steps). The
//! parameters keep these ratios: step and horizon follow Ω₀ and ε.
//!
//! # Measured
//!
//! `svi run magnetic-bottle --t-end 196349.54084936207 --every 25 --out bottle.csv` (SVI with
//! 6 CGL points, 10⁶ default steps, 784 bounces): energy error 1.9e-13 (3e-12 of E), p_φ
//! error 1.3e-13, μ within 2.8 % of μ₀ throughout (ε = 2.5 %), its means over single bounces
//! within 8e-4 of each other, with a least-squares drift of 9e-7 of μ₀ over the run.
//!
//! # References
//!
//! F. F. Chen, *Introduction to Plasma Physics and Controlled Fusion* (3rd ed., 2016), §2.3.3
//! (magnetic mirrors) and §2.8 (adiabatic invariants); T. G. Northrop, *The Adiabatic Motion
//! of Charged Particles* (1963).

use std::f64::consts::TAU;

use nalgebra::{SVector, U3};
use svi::model::hamiltonian::{
    HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants, HamiltonianStructure,
    HamiltonianSymmetries,
};
use svi::{Error, Hamiltonian, Scalar};

use crate::params;

/// Steps per gyration period at the centre of the bottle, for the default step.
const STEPS_PER_GYRATION: f64 = 32.0;
/// Bounce periods in the default horizon.
const BOUNCES: f64 = 10.0;

/// A particle of mass m and charge e in the magnetic bottle B = ∇ × A,
/// A = (B₀/2)(1 + z²/L²)(−y, x, 0): H = |p − eA(x)|²/(2m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MagneticBottle {
    /// Mass m (> 0).
    pub m: f64,
    /// Charge e (> 0; a negative charge is the mirror image, gyrating the other way).
    pub charge: f64,
    /// Field strength B₀ at the centre (> 0).
    pub b0: f64,
    /// Length L over which the field doubles along the axis (> 0).
    pub l: f64,
    /// Adiabaticity ε = ρ₀/L of the default initial state: its gyroradius at the centre over
    /// L (> 0; μ is an adiabatic invariant for ε ≪ 1).
    pub epsilon: f64,
}

impl MagneticBottle {
    /// Registry name of the model.
    pub const NAME: &'static str = "magnetic-bottle";
    /// Parameter names, in the order of [`HamiltonianDefaults::parameters`].
    pub const PARAMETERS: [&'static str; 5] = ["m", "charge", "b0", "l", "epsilon"];

    /// The vector potential A(x) = (B₀/2)(1 + z²/L²)(−y, x, 0), in any scalar.
    #[inline]
    pub fn vector_potential<D: Scalar>(&self, x: &SVector<D, 3>) -> SVector<D, 3> {
        let scale = (x[2] * x[2] * (self.l * self.l).recip() + 1.0) * (0.5 * self.b0);
        SVector::from([-x[1] * scale, x[0] * scale, D::zero()])
    }

    /// The field B(x) = ∇ × A = B₀(−x z/L², −y z/L², 1 + z²/L²), in any scalar.
    pub fn magnetic_field<D: Scalar>(&self, x: &SVector<D, 3>) -> SVector<D, 3> {
        let gradient = x[2] * (self.b0 / (self.l * self.l));
        SVector::from([
            -x[0] * gradient,
            -x[1] * gradient,
            x[2] * gradient + self.b0,
        ])
    }

    /// The velocity v = (p − eA(x))/m.
    pub fn velocity(&self, x: &SVector<f64, 3>, p: &SVector<f64, 3>) -> SVector<f64, 3> {
        (p - self.vector_potential(x) * self.charge) / self.m
    }

    /// The canonical momentum p = m v + eA(x).
    pub fn momentum(&self, x: &SVector<f64, 3>, v: &SVector<f64, 3>) -> SVector<f64, 3> {
        v * self.m + self.vector_potential(x) * self.charge
    }

    /// The magnetic moment μ = m v_⊥²/(2|B|), v_⊥ the velocity across B.
    pub fn magnetic_moment(&self, x: &SVector<f64, 3>, p: &SVector<f64, 3>) -> f64 {
        let v = self.velocity(x, p);
        let field = self.magnetic_field(x);
        let strength = field.norm();
        let across = v.cross(&field) / strength;
        0.5 * self.m * across.norm_squared() / strength
    }

    /// The gyration frequency Ω₀ = eB₀/m at the centre.
    pub fn gyration_frequency(&self) -> f64 {
        self.charge * self.b0 / self.m
    }

    /// The speeds v_⊥₀ = v_∥₀ = εΩ₀L of the default initial state.
    fn initial_speed(&self) -> f64 {
        self.epsilon * self.gyration_frequency() * self.l
    }

    /// The bounce period 2π/ω_b = 2πL/v_⊥₀ of the default initial state (in the adiabatic
    /// limit ε → 0).
    pub fn bounce_period(&self) -> f64 {
        TAU * self.l / self.initial_speed()
    }
}

impl Default for MagneticBottle {
    /// m = e = B₀ = 1, L = 10, ε = 1/40.
    fn default() -> Self {
        Self {
            m: 1.0,
            charge: 1.0,
            b0: 1.0,
            l: 10.0,
            epsilon: 0.025,
        }
    }
}

impl Hamiltonian<U3> for MagneticBottle {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::General;

    #[inline]
    fn hamiltonian<D: Scalar>(&self, _t: D, x: &SVector<D, 3>, p: &SVector<D, 3>) -> D {
        let kinetic = p - self.vector_potential(x) * D::from(self.charge);
        kinetic.dot(&kinetic) * (0.5 / self.m)
    }
}

impl HamiltonianSymmetries<U3> for MagneticBottle {
    /// One: rotations about the axis.
    #[inline]
    fn generator_count(&self) -> usize {
        1
    }

    /// `"p_phi"`.
    ///
    /// # Panics
    /// If `index > 0`.
    fn momentum_name(&self, index: usize) -> &'static str {
        match index {
            0 => "p_phi",
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }

    /// ξ(x) = (−y, x, 0), so that p·ξ = x p_y − y p_x.
    ///
    /// # Panics
    /// If `index > 0`.
    #[inline]
    fn generator(&self, index: usize, x: &SVector<f64, 3>) -> SVector<f64, 3> {
        match index {
            0 => SVector::from([-x[1], x[0], 0.0]),
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }
}

impl HamiltonianInvariants<U3> for MagneticBottle {
    /// One, adiabatic: the magnetic moment.
    fn invariant_count(&self) -> usize {
        1
    }

    /// `"magnetic_moment_adiabatic"`: μ is conserved only approximately (to O(ε), without
    /// drift), also by the exact flow.
    ///
    /// # Panics
    /// If `index > 0`.
    fn invariant_name(&self, index: usize) -> &'static str {
        match index {
            0 => "magnetic_moment_adiabatic",
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }

    /// μ = m v_⊥²/(2|B|) ([`MagneticBottle::magnetic_moment`]).
    ///
    /// # Panics
    /// If `index > 0`.
    fn invariant(&self, index: usize, _t: f64, x: &SVector<f64, 3>, p: &SVector<f64, 3>) -> f64 {
        match index {
            0 => self.magnetic_moment(x, p),
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
}

impl HamiltonianExactSolution<U3> for MagneticBottle {
    /// Always `None`: the motion has no closed form.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &SVector<f64, 3>,
        _p0: &SVector<f64, 3>,
        _t: f64,
    ) -> Option<(SVector<f64, 3>, SVector<f64, 3>)> {
        None
    }
}

impl HamiltonianDefaults<U3> for MagneticBottle {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["x", "y", "z"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("m", self.m),
            ("charge", self.charge),
            ("b0", self.b0),
            ("l", self.l),
            ("epsilon", self.epsilon),
        ]
    }

    /// Every parameter must be finite and positive.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let field = match name {
            "m" => &mut self.m,
            "charge" => &mut self.charge,
            "b0" => &mut self.b0,
            "l" => &mut self.l,
            "epsilon" => &mut self.epsilon,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        };
        *field = params::positive(name, value)?;
        Ok(())
    }

    /// t₀ = 0, x₀ = (L/4, 0, 0), p₀ = m v₀ + eA(x₀) with v₀ = (0, v_⊥₀, v_∥₀),
    /// v_⊥₀ = v_∥₀ = εΩ₀L.
    fn initial_state(&self) -> (f64, SVector<f64, 3>, SVector<f64, 3>) {
        let x = SVector::from([0.25 * self.l, 0.0, 0.0]);
        let speed = self.initial_speed();
        let v = SVector::from([0.0, speed, speed]);
        (0.0, x, self.momentum(&x, &v))
    }

    /// h = 2π/(32 Ω₀).
    fn default_step(&self) -> f64 {
        TAU / (STEPS_PER_GYRATION * self.gyration_frequency())
    }

    /// T = 10 bounce periods, 10 · 2πL/v_⊥₀.
    fn default_horizon(&self) -> f64 {
        BOUNCES * self.bounce_period()
    }
}
