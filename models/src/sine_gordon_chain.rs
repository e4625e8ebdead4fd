//! The sine-Gordon equation φ_tt = φ_xx − sin φ discretised in space: a Frenkel–Kontorova
//! chain of n pendulums φᵢ = φ(xᵢ) at spacing a, each coupled to its neighbours by torsion
//! springs (Frenkel & Kontorova 1938; Braun & Kivshar, *The Frenkel–Kontorova model*, 2004):
//!
//! L = Σᵢ a [½ φ̇ᵢ² − (1 − cos φᵢ)] − Σⱼ (φ_{j+1} − φ_j)²/(2a),
//!
//! on x ∈ [−L/2, L/2] with xᵢ = −L/2 + i a, i = 1..n, a = L/(n + 1), and the ends held at the
//! kink's limits φ₀ = 0, φ_{n+1} = 2π. The default state is the continuum kink moving with
//! speed V, φ(x, 0) = 4 arctan exp(γ(x − x₀)), φ_t = −2Vγ sech(γ(x − x₀)), γ = 1/√(1 − V²):
//! for a ≪ 1 the chain carries it with little radiation (the Peierls–Nabarro barrier is
//! exponentially small in 1/a). A sum of local terms of width 2: term e is the spring between
//! pendulums e − 1 and e (the walls at e = 0 and e = n), carrying pendulum e's kinetic and
//! on-site energy.

use crate::chain::{spring_ends, spring_indices};
use crate::params::{finite, positive, size, unknown};
use nalgebra::{Const, DVector, SVector};
use std::f64::consts::PI;
use svi::Error;
use svi::Scalar;
use svi::Structure;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};

/// The discretised sine-Gordon string (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SineGordonChain {
    /// Number of moving pendulums n.
    pub n: usize,
    /// Length of the string.
    pub length: f64,
    /// Speed V of the initial kink (|V| < 1).
    pub speed: f64,
    /// Initial position x₀ of the kink.
    pub position: f64,
}

impl Default for SineGordonChain {
    fn default() -> Self {
        SineGordonChain {
            n: 399,
            length: 40.0,
            speed: 0.5,
            position: -10.0,
        }
    }
}

impl SineGordonChain {
    /// The spacing a = L/(n + 1).
    pub fn spacing(&self) -> f64 {
        self.length / (self.n + 1) as f64
    }

    /// The position of pendulum i (0-based).
    pub fn site(&self, i: usize) -> f64 {
        -0.5 * self.length + (i + 1) as f64 * self.spacing()
    }

    /// The kink's centre: where φ first crosses π, linear between sites (the walls at
    /// φ = 0 and 2π included); NaN when φ does not cross π.
    pub fn kink_position(&self, q: &DVector<f64>) -> f64 {
        let value = |i: usize| match i {
            0 => 0.0,
            i if i == self.n + 1 => 2.0 * PI,
            i => q[i - 1],
        };
        (0..=self.n)
            .find(|&i| value(i) < PI && value(i + 1) >= PI)
            .map_or(f64::NAN, |i| {
                let fraction = (PI - value(i)) / (value(i + 1) - value(i));
                -0.5 * self.length + (i as f64 + fraction) * self.spacing()
            })
    }
}

impl LocalLagrangian for SineGordonChain {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        self.n
    }

    fn term_count(&self) -> usize {
        self.n + 1
    }

    #[inline]
    fn indices(&self, e: usize) -> [usize; 2] {
        spring_indices(e, self.n)
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let a = self.spacing();
        let (left, right) = spring_ends(e, self.n, q, (0.0, 2.0 * PI));
        let stretch = right - left;
        let spring = stretch * stretch * (0.5 / a);
        if e < self.n {
            (v[1] * v[1] * 0.5 - (D::from(1.0) - q[1].cos())) * a - spring
        } else {
            -spring
        }
    }
}

impl LocalInvariants for SineGordonChain {}

impl LocalDefaults for SineGordonChain {
    fn name(&self) -> &'static str {
        "sine-gordon-chain"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("n", self.n as f64),
            ("length", self.length),
            ("speed", self.speed),
            ("position", self.position),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "n" => self.n = size(name, value, 1)?,
            "length" => self.length = positive(name, value)?,
            "speed" => {
                if finite(name, value)?.abs() >= 1.0 {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} must lie in (−1, 1)"),
                    ));
                }
                self.speed = value;
            }
            "position" => self.position = finite(name, value)?,
            _ => {
                return Err(unknown(
                    "sine-gordon-chain",
                    name,
                    &["n", "length", "speed", "position"],
                ));
            }
        }
        Ok(())
    }

    /// The continuum kink at t = 0 moving with speed V.
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let gamma = 1.0 / (1.0 - self.speed * self.speed).sqrt();
        let phase = |i: usize| gamma * (self.site(i) - self.position);
        let q = DVector::from_fn(self.n, |i, _| 4.0 * phase(i).exp().atan());
        let v = DVector::from_fn(self.n, |i, _| -2.0 * self.speed * gamma / phase(i).cosh());
        (0.0, q, v)
    }

    /// A fifth of the spacing (the fastest linear waves travel at speed 1).
    fn default_step(&self) -> f64 {
        0.2 * self.spacing()
    }

    /// The kink crosses 20 of the string's 40 length units.
    fn default_horizon(&self) -> f64 {
        40.0
    }
}
