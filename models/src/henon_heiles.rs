//! The Hénon–Heiles system: a star in an axisymmetric galaxy, the classic test of
//! chaos in a Hamiltonian system with two degrees of freedom.
//!
//! # Lagrangian
//!
//! L(x, y, ẋ, ẏ) = ½(ẋ² + ẏ²) − ½(x² + y²) − λ(x² y − y³/3), λ > 0 (λ = 1 is the system of
//! Hénon & Heiles 1964).
//!
//! # Equations of motion
//!
//! ẍ = −x − 2λ x y, ÿ = −y − λ(x² − y²). The energy E = ½(ẋ² + ẏ²) + V(x, y) with
//! V = ½(x² + y²) + λ(x² y − y³/3) is conserved; the motion is bounded for E < 1/(6λ²),
//! the height of the potential's three saddles. The potential has the symmetry of the
//! triangle (rotations by 2π/3 and a reflection), no continuous one: E is the only integral.
//!
//! # Chaos
//!
//! For λ = 1 most orbits are regular at E = 1/12 and about half of the surface of section
//! x = 0 is a chaotic sea at E = 1/8 (Hénon & Heiles, Fig. 3–5). The default initial point
//! (x, y, ẏ) = (0, −0.2, 0) with ẋ > 0 on E = 1/8 lies in that sea: its maximal Lyapunov
//! exponent is about 0.05 (two-trajectory renormalisation with DOP853).
//!
//! # Defaults
//!
//! λ = 1; the default initial point (0, y₀, ẋ₀, ẏ₀) on the surface of section x = 0 is given
//! by the parameters `energy` = 1/8, `y0` = −0.2 and `vy0` = 0, with ẋ₀ > 0 from the energy
//! (so an ensemble over y0 and vy0 covers one energy surface); step h = 0.1, horizon
//! T = 1000.
//!
//! # References
//!
//! M. Hénon, C. Heiles, *The applicability of the third integral of motion: some numerical
//! experiments*, Astron. J. 69 (1964) 73–79.

use nalgebra::{SVector, U2};
use svi::{Defaults, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries};

use crate::params;

/// The Hénon–Heiles Lagrangian L = ½|q̇|² − ½|q|² − λ(x²y − y³/3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenonHeiles {
    /// Strength λ of the cubic term (> 0).
    pub lambda: f64,
    /// Energy E of the default initial point, at least V(0, y₀) + ½ẏ₀² (see
    /// [`HenonHeiles::initial_speed`]); orbits stay bounded for E < 1/(6λ²).
    pub energy: f64,
    /// y₀ of the default initial point (x₀ = 0) on the surface of section x = 0.
    pub y0: f64,
    /// ẏ₀ of the default initial point.
    pub vy0: f64,
}

impl HenonHeiles {
    /// Registry name of the model.
    pub const NAME: &'static str = "henon-heiles";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 4] = ["lambda", "energy", "y0", "vy0"];

    /// The potential V(x, y) = ½(x² + y²) + λ(x² y − y³/3).
    pub fn potential(&self, x: f64, y: f64) -> f64 {
        0.5 * (x * x + y * y) + self.lambda * (x * x * y - y * y * y / 3.0)
    }

    /// The energy ½|q̇|² + V(q).
    pub fn energy_of(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        0.5 * v.norm_squared() + self.potential(q[0], q[1])
    }

    /// ẋ₀ > 0 of the default initial point (0, y₀, ẋ₀, ẏ₀) on the energy surface E:
    /// √(2(E − V(0, y₀)) − ẏ₀²), or an error naming the energy if the point (0, y₀, ·, ẏ₀)
    /// does not reach the surface (E < V(0, y₀) + ½ẏ₀²).
    pub fn initial_speed(&self) -> Result<f64, Error> {
        let squared = 2.0 * (self.energy - self.potential(0.0, self.y0)) - self.vy0 * self.vy0;
        if squared.is_finite() && squared >= 0.0 {
            Ok(squared.sqrt())
        } else {
            Err(Error::invalid(
                "energy",
                format!(
                    "E = {} lies below V(0, y0) + vy0²/2 = {} at y0 = {}, vy0 = {}: the point \
                     is not on that energy surface",
                    self.energy,
                    self.potential(0.0, self.y0) + 0.5 * self.vy0 * self.vy0,
                    self.y0,
                    self.vy0
                ),
            ))
        }
    }
}

impl Default for HenonHeiles {
    /// λ = 1, E = 1/8, y₀ = −0.2, ẏ₀ = 0.
    fn default() -> Self {
        Self {
            lambda: 1.0,
            energy: 0.125,
            y0: -0.2,
            vy0: 0.0,
        }
    }
}

impl Lagrangian<U2> for HenonHeiles {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let (x, y) = (q[0], q[1]);
        let kinetic = (v[0] * v[0] + v[1] * v[1]) * 0.5;
        let potential = (x * x + y * y) * 0.5 + (x * x * y - y * y * y / 3.0) * self.lambda;
        kinetic - potential
    }
}

/// No continuous symmetry (the potential's symmetry group is finite).
impl Symmetries<U2> for HenonHeiles {}

/// No integral besides the energy.
impl Invariants<U2> for HenonHeiles {}

impl ExactSolution<U2> for HenonHeiles {
    /// Always `None`: the system is not integrable.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &SVector<f64, 2>,
        _v0: &SVector<f64, 2>,
        _t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        None
    }
}

impl Defaults<U2> for HenonHeiles {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["x", "y"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("lambda", self.lambda),
            ("energy", self.energy),
            ("y0", self.y0),
            ("vy0", self.vy0),
        ]
    }

    /// `lambda` must be finite and positive; `energy`, `y0` and `vy0` finite, with the
    /// default initial point on the energy surface (E ≥ V(0, y₀) + ½ẏ₀²; an ensemble over
    /// y0 and vy0 reports the points off the surface as rejected members).
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let mut trial = *self;
        match name {
            "lambda" => trial.lambda = params::positive(name, value)?,
            "energy" => trial.energy = params::finite(name, value)?,
            "y0" => trial.y0 = params::finite(name, value)?,
            "vy0" => trial.vy0 = params::finite(name, value)?,
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        // Off the energy surface, the error names the parameter that moved the point off it.
        trial.initial_speed().map_err(|error| match error {
            Error::InvalidParameter { reason, .. } => Error::invalid(name, reason),
            other => other,
        })?;
        *self = trial;
        Ok(())
    }

    /// t₀ = 0, (x, y) = (0, y₀), (ẋ, ẏ) = (√(2(E − V(0, y₀)) − ẏ₀²), ẏ₀).
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        // `set_parameter` keeps the point on its surface; a struct built by hand off it
        // starts with ẋ₀ = 0.
        let speed = self.initial_speed().unwrap_or(0.0);
        (
            0.0,
            SVector::from([0.0, self.y0]),
            SVector::from([speed, self.vy0]),
        )
    }

    /// h = 0.1 (about 60 steps per period 2π of the small oscillations).
    fn default_step(&self) -> f64 {
        0.1
    }

    /// T = 1000 (about 160 crossings of the section x = 0).
    fn default_horizon(&self) -> f64 {
        1000.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use svi::model::derived::LagrangianExt;

    #[test]
    fn default_point_lies_on_its_energy_surface() {
        let model = HenonHeiles::default();
        let (_, q, v) = model.initial_state();
        assert_relative_eq!(model.energy_of(&q, &v), 0.125, epsilon = 1e-16);
        // ẋ₀² = 2(1/8 − (0.02 + 0.008/3)).
        assert_relative_eq!(v[0] * v[0], 0.25 - 0.04 - 0.016 / 3.0, epsilon = 1e-15);
    }

    #[test]
    fn forces_are_the_textbook_accelerations() {
        let model = HenonHeiles {
            lambda: 0.7,
            ..HenonHeiles::default()
        };
        let (x, y) = (0.3, -0.4);
        let q = SVector::from([x, y]);
        let v = SVector::from([0.1, 0.2]);
        let force = model.force(0.0, &q, &v);
        assert_relative_eq!(force[0], -x - 2.0 * 0.7 * x * y, epsilon = 1e-15);
        assert_relative_eq!(force[1], -y - 0.7 * (x * x - y * y), epsilon = 1e-15);
    }

    #[test]
    fn energy_below_the_default_point_is_refused() {
        let mut model = HenonHeiles::default();
        let error = model.set_parameter("energy", 0.01).unwrap_err();
        assert!(error.to_string().contains("energy"), "{error}");
        assert_eq!(model, HenonHeiles::default());
        // (0, 0.2, ·, 0.5) lies above E = 1/8: ½·0.25 + V > 1/8.
        model.set_parameter("y0", 0.2).unwrap();
        assert!(model.set_parameter("vy0", 0.5).is_err());
        model.set_parameter("vy0", 0.3).unwrap();
        let (_, q, v) = model.initial_state();
        assert_relative_eq!(model.energy_of(&q, &v), 0.125, epsilon = 1e-16);
        assert!(model.set_parameter("energy", f64::NAN).is_err());
        assert!(model.set_parameter("lambda", 0.0).is_err());
    }
}
