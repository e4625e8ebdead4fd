//! Schrödinger-type fields ψ = a + ib in 1 + 1 dimensions (ħ = m = 1), each a Lagrangian
//! density of u = (a, b) on a periodic domain with a closed-form solution, for the
//! pseudospectral integrators of [`svi::field::pseudospectral`]:
//!
//! ℒ = (b a_t − a b_t) − ½(a_x² + b_x²) + (κ/2)(a² + b²)²,
//!
//! whose Euler–Lagrange equations are the real and imaginary parts of
//! iψ_t + ½ψ_xx + κ|ψ|²ψ = 0 (varying a: 2b_t − a_xx − 2κ|ψ|²a = 0, the real part).
//!
//! - [`SchrodingerPacket`]: κ = 0, the free particle, a Gaussian packet of width σ and mean
//!   wavenumber k₀ on [−π, π]; the exact solution is the periodised free Gaussian
//!   Σ_n G(x + 2πn, t), G = (σ²/(σ² + it))^{1/2} exp(−(x − x₀ − k₀t)²/(2(σ² + it)) +
//!   ik₀(x − x₀) − ik₀²t/2), summed over every image within nine widths of the point, or,
//!   where that takes more terms (a wide packet, a long time), as its Fourier series
//!   (σ/√(2π)) Σ_k e^{−σ²(k − k₀)²/2 − ik²t/2 + ik(x − x₀)} (exact to round-off at every t,
//!   for σ ≥ [`MIN_PACKET_WIDTH`]).
//! - [`NlsSoliton`]: κ = 1, the focusing cubic NLS soliton
//!   ψ = η sech(η(x − x₀ − ct)) exp(i(c(x − x₀) + (η² − c²)t/2)) on [−40, 40]; at the ends of
//!   the domain |ψ| ≤ 2η e^{−η(40 − |x₀ + ct|)}, below 10⁻¹³ for the defaults up to t = 10
//!   (x₀ + ct ≤ 5, 2e^{−35} = 1.3·10⁻¹⁵).

use crate::params::{finite, positive, unknown};
use nalgebra::SVector;
use std::f64::consts::PI;
use svi::Error;
use svi::Scalar;
use svi::field::fourier::Complex64;
use svi::model::density::{Boundary, Domain, ExactField, FieldDefaults, LagrangianDensity};

/// ℒ = (b a_t − a b_t) − ½|u_x|² + (κ/2)|u|⁴.
#[inline]
fn schrodinger_density<D: Scalar>(
    kappa: f64,
    u: &SVector<D, 2>,
    u_t: &SVector<D, 2>,
    u_x: &SVector<D, 2>,
) -> D {
    let mass = u.dot(u);
    u[1] * u_t[0] - u[0] * u_t[1] - u_x.dot(u_x) * 0.5 + mass * mass * (0.5 * kappa)
}

/// ψ as the pair (a, b).
fn pair(psi: Complex64) -> SVector<f64, 2> {
    SVector::from([psi.re, psi.im])
}

/// The free Gaussian packet on [−π, π], periodic (κ = 0).
#[derive(Debug, Clone, PartialEq)]
pub struct SchrodingerPacket {
    /// The initial width σ.
    pub width: f64,
    /// The mean wavenumber k₀.
    pub wavenumber: f64,
    /// The initial centre x₀.
    pub centre: f64,
}

impl Default for SchrodingerPacket {
    fn default() -> Self {
        SchrodingerPacket {
            width: 0.5,
            wavenumber: 5.0,
            centre: 0.0,
        }
    }
}

/// The smallest packet width σ: the Fourier series of the packet needs about 2√80/σ terms
/// (18 000 at the bound), and no grid of the default 64 nodes on [−π, π] resolves less.
pub const MIN_PACKET_WIDTH: f64 = 1e-3;

impl SchrodingerPacket {
    /// ψ and ψ_xx of the periodised packet at (x, t): the image sum Σ_n G(x − 2πn, t) or its
    /// Poisson dual, the Fourier series, whichever takes fewer terms. The images within
    /// nine widths σ_t = |σ² + it|/σ of x are many when σ_t is large (a wide packet, a long
    /// time); the Fourier terms |k − k₀| ≤ √80/σ (the others below e⁻⁴⁰) are many only when
    /// σ is small, at any t.
    fn field(&self, x: f64, t: f64) -> (Complex64, Complex64) {
        let (sigma, k0) = (self.width, self.wavenumber);
        let length = 2.0 * PI;
        let spread = Complex64::new(sigma * sigma, t);
        let centre = self.centre + k0 * t;
        let reach = 9.0 * spread.norm() / sigma + length;
        let first = ((x - centre - reach) / length).floor();
        let last = ((x - centre + reach) / length).ceil();
        let band = 80f64.sqrt() / sigma;
        let (low, high) = ((k0 - band).ceil(), (k0 + band).floor());
        if last - first <= high - low {
            self.image_sum(x, t, first as i64, last as i64)
        } else {
            self.fourier_sum(x, t, low as i64, high as i64)
        }
    }

    /// Σ_{n = first..=last} of G(x − 2πn, t) and its second derivative, G = (σ²/(σ² +
    /// it))^{1/2} exp(−(y − x₀ − k₀t)²/(2(σ² + it)) + ik₀(y − x₀) − ik₀²t/2).
    fn image_sum(&self, x: f64, t: f64, first: i64, last: i64) -> (Complex64, Complex64) {
        let (sigma, k0) = (self.width, self.wavenumber);
        let spread = Complex64::new(sigma * sigma, t);
        let amplitude = (Complex64::new(sigma * sigma, 0.0) / spread).sqrt();
        let centre = self.centre + k0 * t;
        let (mut psi, mut psi_xx) = (Complex64::default(), Complex64::default());
        for n in first..=last {
            let y = x - n as f64 * 2.0 * PI;
            let offset = y - centre;
            let phase = Complex64::new(0.0, k0 * (y - self.centre) - 0.5 * k0 * k0 * t);
            let g = amplitude * (-(offset * offset) / (2.0 * spread) + phase).exp();
            let slope = -offset / spread + Complex64::new(0.0, k0);
            psi += g;
            psi_xx += g * (slope * slope - 1.0 / spread);
        }
        (psi, psi_xx)
    }

    /// The same periodised packet as its Fourier series (Poisson summation with Ĝ(k, 0) =
    /// σ√(2π) e^{−σ²(k − k₀)²/2 − ikx₀} and the free evolution e^{−ik²t/2}):
    /// (σ/√(2π)) Σ_{k = low..=high} e^{−σ²(k − k₀)²/2 − ik²t/2 + ik(x − x₀)}, and its second
    /// derivative (each term times −k²).
    fn fourier_sum(&self, x: f64, t: f64, low: i64, high: i64) -> (Complex64, Complex64) {
        let (sigma, k0) = (self.width, self.wavenumber);
        let (mut psi, mut psi_xx) = (Complex64::default(), Complex64::default());
        for k in low..=high {
            let k = k as f64;
            let term = Complex64::new(
                -0.5 * sigma * sigma * (k - k0) * (k - k0),
                k * (x - self.centre) - 0.5 * k * k * t,
            )
            .exp();
            psi += term;
            psi_xx -= term * (k * k);
        }
        let scale = sigma / (2.0 * PI).sqrt();
        (psi * scale, psi_xx * scale)
    }
}

impl LagrangianDensity<2> for SchrodingerPacket {
    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 2>,
        u_t: &SVector<D, 2>,
        u_x: &SVector<D, 2>,
    ) -> D {
        schrodinger_density(0.0, u, u_t, u_x)
    }
}

impl FieldDefaults<2> for SchrodingerPacket {
    fn name(&self) -> &'static str {
        "schrodinger-packet"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("sigma", self.width),
            ("k0", self.wavenumber),
            ("x0", self.centre),
        ]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "sigma" => {
                if positive(name, value)? < MIN_PACKET_WIDTH {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} is narrower than {MIN_PACKET_WIDTH:?}"),
                    ));
                }
                self.width = value;
            }
            "k0" => self.wavenumber = finite(name, value)?,
            "x0" => self.centre = finite(name, value)?,
            _ => return Err(unknown(self.name(), name, &["sigma", "k0", "x0"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        Domain::new(-PI, PI).expect("a valid interval")
    }
    fn boundary(&self) -> Boundary<2> {
        Boundary::Periodic
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 2>, SVector<f64, 2>) {
        let (psi, psi_xx) = self.field(x, 0.0);
        // ψ_t = (i/2) ψ_xx.
        (pair(psi), pair(Complex64::new(0.0, 0.5) * psi_xx))
    }
    fn default_points(&self) -> usize {
        64
    }
    fn default_step(&self) -> f64 {
        0.01
    }
    fn default_horizon(&self) -> f64 {
        1.0
    }
}

impl ExactField<2> for SchrodingerPacket {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 2> {
        pair(self.field(x, t).0)
    }
}

/// The soliton of the focusing cubic NLS iψ_t + ½ψ_xx + |ψ|²ψ = 0 on [−40, 40], periodic.
#[derive(Debug, Clone, PartialEq)]
pub struct NlsSoliton {
    /// The amplitude η.
    pub amplitude: f64,
    /// The speed c.
    pub speed: f64,
    /// The initial position x₀.
    pub position: f64,
}

impl Default for NlsSoliton {
    fn default() -> Self {
        NlsSoliton {
            amplitude: 1.0,
            speed: 0.5,
            position: 0.0,
        }
    }
}

impl NlsSoliton {
    /// ψ and ψ_t at (x, t).
    fn field(&self, x: f64, t: f64) -> (Complex64, Complex64) {
        let (eta, c) = (self.amplitude, self.speed);
        let xi = eta * (x - self.position - c * t);
        let sech = 1.0 / xi.cosh();
        let phase =
            Complex64::from_polar(1.0, c * (x - self.position) + 0.5 * (eta * eta - c * c) * t);
        let psi = phase * (eta * sech);
        // ∂_t sech(ξ) = ηc sech tanh; ∂_t of the phase: i(η² − c²)/2.
        let psi_t = phase
            * Complex64::new(
                eta * eta * c * sech * xi.tanh(),
                0.5 * (eta * eta - c * c) * eta * sech,
            );
        (psi, psi_t)
    }
}

impl LagrangianDensity<2> for NlsSoliton {
    #[inline]
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 2>,
        u_t: &SVector<D, 2>,
        u_x: &SVector<D, 2>,
    ) -> D {
        schrodinger_density(1.0, u, u_t, u_x)
    }
}

impl FieldDefaults<2> for NlsSoliton {
    fn name(&self) -> &'static str {
        "nls-soliton"
    }
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("eta", self.amplitude),
            ("c", self.speed),
            ("x0", self.position),
        ]
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "eta" => self.amplitude = positive(name, value)?,
            "c" => self.speed = finite(name, value)?,
            "x0" => self.position = finite(name, value)?,
            _ => return Err(unknown(self.name(), name, &["eta", "c", "x0"])),
        }
        Ok(())
    }
    fn domain(&self) -> Domain {
        Domain::new(-40.0, 40.0).expect("a valid interval")
    }
    fn boundary(&self) -> Boundary<2> {
        Boundary::Periodic
    }
    fn initial_field(&self, x: f64) -> (SVector<f64, 2>, SVector<f64, 2>) {
        let (psi, psi_t) = self.field(x, 0.0);
        (pair(psi), pair(psi_t))
    }
    fn default_points(&self) -> usize {
        512
    }
    fn default_step(&self) -> f64 {
        0.01
    }
    fn default_horizon(&self) -> f64 {
        10.0
    }
}

impl ExactField<2> for NlsSoliton {
    fn exact_field(&self, x: f64, t: f64) -> SVector<f64, 2> {
        pair(self.field(x, t).0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::model::density::{Jet, LagrangianDensityExt};

    /// The residual of the Euler–Lagrange equation of a density at (x, t), varying a and b:
    /// ∂_t ∂ℒ/∂u_t + ∂_x ∂ℒ/∂u_x − ∂ℒ/∂u, with the derivatives of the exact solution by
    /// central differences (step δ).
    fn residual<F: LagrangianDensity<2> + ExactField<2>>(model: &F, x: f64, t: f64) -> f64 {
        let d = 1e-4;
        let u = |x: f64, t: f64| model.exact_field(x, t);
        let jet = |x: f64, t: f64| Jet {
            u: u(x, t),
            u_t: (u(x, t + d) - u(x, t - d)) / (2.0 * d),
            u_x: (u(x + d, t) - u(x - d, t)) / (2.0 * d),
        };
        let g = |x: f64, t: f64| model.gradient(x, t, &jet(x, t));
        let time = (g(x, t + d).u_t - g(x, t - d).u_t) / (2.0 * d);
        let space = (g(x + d, t).u_x - g(x - d, t).u_x) / (2.0 * d);
        (time + space - g(x, t).u).amax()
    }

    #[test]
    fn the_exact_solutions_solve_their_euler_lagrange_equations() {
        let packet = SchrodingerPacket::default();
        let soliton = NlsSoliton::default();
        for (x, t) in [(-1.0, 0.3), (0.4, 0.9), (2.5, 0.1)] {
            // Nested central differences: O(δ²|ψ''''|), |ψ''''| ≈ k₀⁴ ≈ 10³ for the packet.
            assert!(
                residual(&packet, x, t) < 1e-4,
                "{}",
                residual(&packet, x, t)
            );
            assert!(
                residual(&soliton, x, t) < 1e-5,
                "{}",
                residual(&soliton, x, t)
            );
        }
    }

    #[test]
    fn the_initial_velocities_are_the_time_derivatives_and_the_packet_is_periodic() {
        let d = 1e-6;
        let packet = SchrodingerPacket::default();
        let soliton = NlsSoliton::default();
        for x in [-2.0, 0.1, 1.7] {
            let fd = |m: &dyn Fn(f64) -> SVector<f64, 2>| (m(d) - m(-d)) / (2.0 * d);
            let p = fd(&|t| packet.exact_field(x, t));
            assert!((packet.initial_field(x).1 - p).amax() < 1e-6);
            let s = fd(&|t| soliton.exact_field(x, t));
            assert!((soliton.initial_field(x).1 - s).amax() < 1e-7);
        }
        for t in [0.0, 0.7, 5.0] {
            let gap = packet.exact_field(-PI, t) - packet.exact_field(PI, t);
            assert!(gap.amax() < 1e-14, "{gap}");
        }
        // The soliton's tails at the ends of the domain, up to t = 10.
        for t in [0.0, 10.0] {
            assert!(soliton.exact_field(-40.0, t).amax() < 1e-13);
            assert!(soliton.exact_field(40.0, t).amax() < 1e-13);
        }
    }

    #[test]
    fn the_image_sum_and_the_fourier_series_of_the_packet_agree() {
        // Poisson summation: both forms of the periodised packet, each with every term that
        // matters, agree to round-off; `field` takes the one with fewer terms.
        for (sigma, k0, x0) in [(0.5, 5.0, 0.0), (0.3, -2.5, 1.0), (1.5, 0.7, -2.0)] {
            let packet = SchrodingerPacket {
                width: sigma,
                wavenumber: k0,
                centre: x0,
            };
            for t in [0.0, 0.4, 3.0] {
                for x in [-3.0, -0.2, 1.1, 3.1] {
                    let images = packet.image_sum(x, t, -60, 60);
                    let fourier = packet.fourier_sum(x, t, -200, 200);
                    assert!((images.0 - fourier.0).norm() < 1e-13, "{sigma} {t} {x}");
                    assert!((images.1 - fourier.1).norm() < 1e-10, "{sigma} {t} {x}");
                    assert!((packet.field(x, t).0 - fourier.0).norm() < 1e-13);
                }
            }
        }
        // A wide packet at a late time takes a few Fourier terms, not ~10¹⁴ images: for an
        // integer k₀ only k = k₀ counts, ψ = (σ/√(2π)) e^{ik₀(x − x₀) − ik₀²t/2}.
        let wide = SchrodingerPacket {
            width: 1e6,
            wavenumber: 3.0,
            centre: 0.0,
        };
        let (psi, psi_xx) = wide.field(0.7, 1e8);
        let plane = Complex64::new(0.0, 3.0 * 0.7 - 4.5 * 1e8).exp() * (1e6 / (2.0 * PI).sqrt());
        assert!((psi - plane).norm() < 1e-6 * plane.norm(), "{psi} {plane}");
        assert!((psi_xx + plane * 9.0).norm() < 1e-6 * 9.0 * plane.norm());
    }

    #[test]
    fn parameters_out_of_range_are_errors() {
        let mut packet = SchrodingerPacket::default();
        assert!(packet.set_parameter("sigma", 1e-4).is_err());
        assert_eq!(packet.width, 0.5);
        packet.set_parameter("sigma", MIN_PACKET_WIDTH).unwrap();
        assert!(
            SchrodingerPacket::default()
                .set_parameter("sigma", 0.0)
                .is_err()
        );
        assert!(
            SchrodingerPacket::default()
                .set_parameter("k0", f64::NAN)
                .is_err()
        );
        assert!(NlsSoliton::default().set_parameter("eta", -1.0).is_err());
        assert!(NlsSoliton::default().set_parameter("kappa", 1.0).is_err());
    }
}
