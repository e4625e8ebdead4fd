//! Field theories in 1 + 1 dimensions, each a Lagrangian density ℒ(x, t, u, u_t, u_x) with a
//! domain, a boundary condition and a closed-form solution, for the multisymplectic
//! integrators of [`svi::field`]:
//!
//! - [`Wave`]: ℒ = ½u_t² − ½c²u_x², u_tt = c²u_xx, periodic on [0, 2π], d'Alembert's solution
//!   u = ½[f(x − ct) + f(x + ct)] of u(x, 0) = f(x) = exp(sin x), u_t(x, 0) = 0;
//! - [`SineGordonKink`] and [`SineGordonBreather`]: ℒ = ½u_t² − ½u_x² − (1 − cos u),
//!   u_tt = u_xx − sin u, the kink u = 4 atan exp((x − x₀ − vt)/√(1 − v²)) and the breather
//!   u = 4 atan((√(1 − ω²)/ω) sin(ωt) / cosh(√(1 − ω²) x)), held at their limits at the ends
//!   of [−20, 20];
//! - [`Phi4Kink`]: ℒ = ½u_t² − ½u_x² − ¼(u² − 1)², u_tt = u_xx + u − u³, the kink
//!   u = tanh(γ(x − x₀ − vt)/√2), γ = 1/√(1 − v²) (the static kink tanh(x/√2), Lorentz-boosted),
//!   held at ∓1 at the ends of [−20, 20].
//!
//! On the finite domain the kinks and the breather are exact up to their tails,
//! exp(−20√(1 − ω²)) or less at the ends.

use crate::params::{finite, positive, unknown};
use nalgebra::SVector;
use std::f64::consts::{PI, SQRT_2};
use svi::Error;
use svi::Scalar;
use svi::model::density::{
    Boundary, DensityStructure, Domain, ExactField, FieldDefaults, LagrangianDensity,
};

/// Check that `value` lies in (−1, 1) (a speed in units of the speed of light).
fn subluminal(name: &str, value: f64) -> Result<f64, Error> {
    if finite(name, value)?.abs() >= 1.0 {
        return Err(Error::invalid(
            name,
            format!("{value:?} must lie in (−1, 1)"),
        ));
    }
    Ok(value)
}

/// [−20, 20], the domain of the kinks and the breather.
fn wide() -> Domain {
    Domain::new(-20.0, 20.0).expect("a valid interval")
}

/// Dirichlet values of a scalar field.
fn held(left: f64, right: f64) -> Boundary<1> {
    Boundary::Dirichlet {
        left: SVector::from([left]),
        right: SVector::from([right]),
    }
}

/// The linear wave equation u_tt = c²u_xx on [0, 2π], periodic.
#[derive(Debug, Clone, PartialEq)]
pub struct Wave {
    /// The wave speed c.
    pub speed: f64,
}

impl Default for Wave {
    fn default() -> Self {
        Wave { speed: 1.0 }
    }
}

impl Wave {
    /// The initial profile f(x) = exp(sin x).
    fn profile(x: f64) -> f64 {
        x.sin().exp()
    }
}

impl LagrangianDensity<1> for Wave {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;

    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        _u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        (u_t[0] * u_t[0] - u_x[0] * u_x[0] * (self.speed * self.speed)) * 0.5
    }
}

impl FieldDefaults<1> for Wave {
    fn name(&self) -> &'static str {
        "wave"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("c", self.speed)]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "c" => self.speed = positive(name, value)?,
            _ => return Err(unknown("wave", name, &["c"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        Domain::new(0.0, 2.0 * PI).expect("a valid interval")
    }
    fn boundary(&self) -> Boundary<1> {
        Boundary::Periodic
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 1>, SVector<f64, 1>) {
        (SVector::from([Self::profile(x)]), SVector::zeros())
    }
    fn default_points(&self) -> usize {
        128
    }
    fn default_step(&self) -> f64 {
        0.5 * 2.0 * PI / 128.0 / self.speed
    }
    fn default_horizon(&self) -> f64 {
        2.0 * PI / self.speed
    }
}

impl ExactField<1> for Wave {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 1> {
        let shift = self.speed * t;
        SVector::from([0.5 * (Self::profile(x - shift) + Self::profile(x + shift))])
    }
}

/// ℒ = ½u_t² − ½u_x² − (1 − cos u), shared by the sine-Gordon models.
#[inline]
fn sine_gordon<D: Scalar>(u: &SVector<D, 1>, u_t: &SVector<D, 1>, u_x: &SVector<D, 1>) -> D {
    (u_t[0] * u_t[0] - u_x[0] * u_x[0]) * 0.5 - (D::from(1.0) - u[0].cos())
}

/// The sine-Gordon kink moving with speed v from x₀, on [−20, 20] held at 0 and 2π.
#[derive(Debug, Clone, PartialEq)]
pub struct SineGordonKink {
    /// The speed v, |v| < 1.
    pub speed: f64,
    /// The position x₀ at t = 0.
    pub position: f64,
}

impl Default for SineGordonKink {
    fn default() -> Self {
        SineGordonKink {
            speed: 0.5,
            position: -5.0,
        }
    }
}

impl SineGordonKink {
    /// (u, u_t) of the kink at (x, t).
    fn state(&self, x: f64, t: f64) -> (f64, f64) {
        let gamma = 1.0 / (1.0 - self.speed * self.speed).sqrt();
        let xi = gamma * (x - self.position - self.speed * t);
        (4.0 * xi.exp().atan(), -2.0 * gamma * self.speed / xi.cosh())
    }
}

impl LagrangianDensity<1> for SineGordonKink {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;

    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        sine_gordon(u, u_t, u_x)
    }
}

impl FieldDefaults<1> for SineGordonKink {
    fn name(&self) -> &'static str {
        "sine-gordon-kink"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("speed", self.speed), ("position", self.position)]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "speed" => self.speed = subluminal(name, value)?,
            "position" => self.position = finite(name, value)?,
            _ => return Err(unknown("sine-gordon-kink", name, &["speed", "position"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        wide()
    }
    fn boundary(&self) -> Boundary<1> {
        held(0.0, 2.0 * PI)
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 1>, SVector<f64, 1>) {
        let (u, u_t) = self.state(x, 0.0);
        (SVector::from([u]), SVector::from([u_t]))
    }
    fn default_points(&self) -> usize {
        401
    }
    fn default_step(&self) -> f64 {
        0.05
    }
    fn default_horizon(&self) -> f64 {
        20.0
    }
}

impl ExactField<1> for SineGordonKink {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 1> {
        SVector::from([self.state(x, t).0])
    }
}

/// The sine-Gordon breather of frequency ω, centred at x = 0, on [−20, 20] held at 0.
#[derive(Debug, Clone, PartialEq)]
pub struct SineGordonBreather {
    /// The frequency ω, 0 < ω < 1.
    pub frequency: f64,
}

impl Default for SineGordonBreather {
    fn default() -> Self {
        SineGordonBreather { frequency: 0.5 }
    }
}

impl SineGordonBreather {
    /// (u, u_t) of the breather at (x, t).
    fn state(&self, x: f64, t: f64) -> (f64, f64) {
        let omega = self.frequency;
        let k = (1.0 - omega * omega).sqrt();
        let a = k / omega * (omega * t).sin() / (k * x).cosh();
        let a_t = k * (omega * t).cos() / (k * x).cosh();
        (4.0 * a.atan(), 4.0 * a_t / (1.0 + a * a))
    }
}

impl LagrangianDensity<1> for SineGordonBreather {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;

    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        sine_gordon(u, u_t, u_x)
    }
}

impl FieldDefaults<1> for SineGordonBreather {
    fn name(&self) -> &'static str {
        "sine-gordon-breather"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("omega", self.frequency)]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "omega" => {
                if positive(name, value)? >= 1.0 {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} must lie in (0, 1)"),
                    ));
                }
                self.frequency = value;
            }
            _ => return Err(unknown("sine-gordon-breather", name, &["omega"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        wide()
    }
    fn boundary(&self) -> Boundary<1> {
        held(0.0, 0.0)
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 1>, SVector<f64, 1>) {
        let (u, u_t) = self.state(x, 0.0);
        (SVector::from([u]), SVector::from([u_t]))
    }
    fn default_points(&self) -> usize {
        401
    }
    fn default_step(&self) -> f64 {
        0.05
    }
    fn default_horizon(&self) -> f64 {
        4.0 * PI / self.frequency
    }
}

impl ExactField<1> for SineGordonBreather {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 1> {
        SVector::from([self.state(x, t).0])
    }
}

/// The sine-Gordon kink–antikink pair approaching each other with speed v, colliding at
/// x = 0 at t = t_c, on [−20, 20] held at 0.
#[derive(Debug, Clone, PartialEq)]
pub struct SineGordonKinkAntikink {
    /// The speed v of each, 0 < v < 1.
    pub speed: f64,
    /// The time t_c of the collision.
    pub collision: f64,
}

impl Default for SineGordonKinkAntikink {
    fn default() -> Self {
        SineGordonKinkAntikink {
            speed: 0.4,
            collision: 10.0,
        }
    }
}

impl SineGordonKinkAntikink {
    /// (u, u_t) of the pair at (x, t).
    fn state(&self, x: f64, t: f64) -> (f64, f64) {
        let v = self.speed;
        let gamma = 1.0 / (1.0 - v * v).sqrt();
        let phase = gamma * v * (t - self.collision);
        let a = phase.sinh() / (v * (gamma * x).cosh());
        let a_t = gamma * phase.cosh() / (gamma * x).cosh();
        (4.0 * a.atan(), 4.0 * a_t / (1.0 + a * a))
    }
}

impl LagrangianDensity<1> for SineGordonKinkAntikink {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;

    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        sine_gordon(u, u_t, u_x)
    }
}

impl FieldDefaults<1> for SineGordonKinkAntikink {
    fn name(&self) -> &'static str {
        "sine-gordon-kink-antikink"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("speed", self.speed), ("collision", self.collision)]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "speed" => {
                if subluminal(name, value)? <= 0.0 {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} must lie in (0, 1)"),
                    ));
                }
                self.speed = value;
            }
            "collision" => self.collision = finite(name, value)?,
            _ => {
                return Err(unknown(
                    "sine-gordon-kink-antikink",
                    name,
                    &["speed", "collision"],
                ));
            }
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        wide()
    }
    fn boundary(&self) -> Boundary<1> {
        held(0.0, 0.0)
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 1>, SVector<f64, 1>) {
        let (u, u_t) = self.state(x, 0.0);
        (SVector::from([u]), SVector::from([u_t]))
    }
    fn default_points(&self) -> usize {
        401
    }
    fn default_step(&self) -> f64 {
        0.05
    }
    fn default_horizon(&self) -> f64 {
        2.0 * self.collision
    }
}

impl ExactField<1> for SineGordonKinkAntikink {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 1> {
        SVector::from([self.state(x, t).0])
    }
}

/// The φ⁴ kink ℒ = ½u_t² − ½u_x² − ¼(u² − 1)², moving with speed v from x₀, on [−20, 20]
/// held at −1 and 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Phi4Kink {
    /// The speed v, |v| < 1.
    pub speed: f64,
    /// The position x₀ at t = 0.
    pub position: f64,
}

impl Default for Phi4Kink {
    fn default() -> Self {
        Phi4Kink {
            speed: 0.3,
            position: -3.0,
        }
    }
}

impl Phi4Kink {
    /// (u, u_t) of the kink at (x, t).
    fn state(&self, x: f64, t: f64) -> (f64, f64) {
        let gamma = 1.0 / (1.0 - self.speed * self.speed).sqrt();
        let xi = gamma * (x - self.position - self.speed * t) / SQRT_2;
        let sech = 1.0 / xi.cosh();
        (xi.tanh(), -gamma * self.speed / SQRT_2 * sech * sech)
    }
}

impl LagrangianDensity<1> for Phi4Kink {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;

    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        let well = u[0] * u[0] - 1.0;
        (u_t[0] * u_t[0] - u_x[0] * u_x[0]) * 0.5 - well * well * 0.25
    }
}

impl FieldDefaults<1> for Phi4Kink {
    fn name(&self) -> &'static str {
        "phi4-kink"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("speed", self.speed), ("position", self.position)]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "speed" => self.speed = subluminal(name, value)?,
            "position" => self.position = finite(name, value)?,
            _ => return Err(unknown("phi4-kink", name, &["speed", "position"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        wide()
    }
    fn boundary(&self) -> Boundary<1> {
        held(-1.0, 1.0)
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 1>, SVector<f64, 1>) {
        let (u, u_t) = self.state(x, 0.0);
        (SVector::from([u]), SVector::from([u_t]))
    }
    fn default_points(&self) -> usize {
        401
    }
    fn default_step(&self) -> f64 {
        0.05
    }
    fn default_horizon(&self) -> f64 {
        20.0
    }
}

impl ExactField<1> for Phi4Kink {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 1> {
        SVector::from([self.state(x, t).0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::model::density::{Jet, LagrangianDensityExt};

    /// The residual ∂ℒ/∂u − u_tt + u_xx of the field equation of a scalar density with
    /// ℒ = ½u_t² − ½u_x² − V(u), at (x, t), by central differences of the exact solution.
    fn field_equation_residual<F: LagrangianDensity<1> + ExactField<1>>(
        model: &F,
        x: f64,
        t: f64,
    ) -> f64 {
        let h = 1e-3;
        let u = |x: f64, t: f64| model.exact_field(x, t)[0];
        let u_tt = (u(x, t + h) - 2.0 * u(x, t) + u(x, t - h)) / (h * h);
        let u_xx = (u(x + h, t) - 2.0 * u(x, t) + u(x - h, t)) / (h * h);
        let jet = Jet {
            u: SVector::from([u(x, t)]),
            u_t: SVector::zeros(),
            u_x: SVector::zeros(),
        };
        model.gradient(x, t, &jet).u[0] - u_tt + u_xx
    }

    #[test]
    fn the_exact_solutions_solve_their_field_equations() {
        let kink = SineGordonKink::default();
        let breather = SineGordonBreather::default();
        let phi4 = Phi4Kink::default();
        let pair = SineGordonKinkAntikink::default();
        for (x, t) in [
            (-4.0, 0.3),
            (-5.2, 1.1),
            (0.4, 2.0),
            (1.3, 5.0),
            (0.2, 10.1),
        ] {
            assert!(field_equation_residual(&kink, x, t).abs() < 1e-5);
            assert!(field_equation_residual(&pair, x, t).abs() < 1e-5);
            assert!(field_equation_residual(&breather, x, t).abs() < 1e-5);
            assert!(field_equation_residual(&phi4, x, t).abs() < 1e-5);
        }
        // The wave equation with c = 2: u_tt = 4 u_xx.
        let wave = Wave { speed: 2.0 };
        let (x, t, h) = (0.7, 0.9, 1e-3);
        let u = |x: f64, t: f64| wave.exact_field(x, t)[0];
        let u_tt = (u(x, t + h) - 2.0 * u(x, t) + u(x, t - h)) / (h * h);
        let u_xx = (u(x + h, t) - 2.0 * u(x, t) + u(x - h, t)) / (h * h);
        assert!((u_tt - 4.0 * u_xx).abs() < 1e-5);
    }

    #[test]
    fn the_initial_velocities_are_the_time_derivatives_of_the_solutions() {
        let h = 1e-6;
        let kink = SineGordonKink::default();
        let breather = SineGordonBreather::default();
        let phi4 = Phi4Kink::default();
        let pair = SineGordonKinkAntikink::default();
        for x in [-6.0, -4.5, 0.0, 2.5] {
            let d = |u: &dyn Fn(f64) -> f64| (u(h) - u(-h)) / (2.0 * h);
            assert!((pair.initial_field(x).1[0] - d(&|t| pair.exact_field(x, t)[0])).abs() < 1e-8);
            assert!((kink.initial_field(x).1[0] - d(&|t| kink.exact_field(x, t)[0])).abs() < 1e-8);
            assert!(
                (breather.initial_field(x).1[0] - d(&|t| breather.exact_field(x, t)[0])).abs()
                    < 1e-8
            );
            assert!((phi4.initial_field(x).1[0] - d(&|t| phi4.exact_field(x, t)[0])).abs() < 1e-8);
        }
        // The static φ⁴ kink is tanh(x/√2).
        let still = Phi4Kink {
            speed: 0.0,
            position: 0.0,
        };
        assert!((still.exact_field(1.0, 3.0)[0] - (1.0 / SQRT_2).tanh()).abs() < 1e-15);
    }

    #[test]
    fn every_field_model_is_visited_by_its_name() {
        /// The model's own name.
        struct Name;
        impl crate::FieldModelVisitor for Name {
            type Output = &'static str;
            fn visit<M: crate::FieldZooModel>(self, model: M) -> &'static str {
                model.name()
            }
        }
        for name in crate::FIELD_MODEL_NAMES {
            assert_eq!(crate::visit_field_model(name, Name), Some(*name));
        }
        assert_eq!(crate::visit_field_model("kepler", Name), None);
    }

    #[test]
    fn parameters_out_of_range_are_errors() {
        assert!(
            SineGordonKink::default()
                .set_parameter("speed", 1.0)
                .is_err()
        );
        assert!(Phi4Kink::default().set_parameter("speed", -1.5).is_err());
        assert!(
            SineGordonKinkAntikink::default()
                .set_parameter("speed", 0.0)
                .is_err()
        );
        assert!(
            SineGordonBreather::default()
                .set_parameter("omega", 1.0)
                .is_err()
        );
        assert!(
            SineGordonBreather::default()
                .set_parameter("omega", 0.0)
                .is_err()
        );
        assert!(Wave::default().set_parameter("c", 0.0).is_err());
        assert!(Wave::default().set_parameter("mass", 1.0).is_err());
        let mut wave = Wave::default();
        wave.set_parameter("c", 2.0).unwrap();
        assert_eq!(wave.parameters(), vec![("c", 2.0)]);
    }
}
