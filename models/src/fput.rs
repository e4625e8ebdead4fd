//! The Fermi–Pasta–Ulam–Tsingou chain: n unit masses joined by n + 1 nonlinear springs,
//! both ends fixed (Fermi, Pasta, Ulam 1955; Dauxois, *Fermi, Pasta, Ulam, and a mysterious
//! lady*, Physics Today 2008).
//!
//! L = Σᵢ ½ q̇ᵢ² − Σⱼ V(q_{j+1} − q_j),  V(r) = r²/2 + α r³/3 + β r⁴/4,
//!
//! with q₀ = q_{n+1} = 0 (the walls; particles are numbered 1..n here and 0..n−1 in the
//! vectors). A sum of local terms ([`LocalLagrangian`], width 2): term e is spring e between
//! particles e − 1 and e, carrying particle e's kinetic energy.
//!
//! The linear normal modes are Q_k = √(2/(n+1)) Σᵢ qᵢ sin(πik/(n+1)) with frequencies
//! ω_k = 2 sin(πk/(2(n+1))); [`Fput::mode_energies`] gives E_k = ½(Q̇_k² + ω_k² Q_k²). The
//! default state puts all energy in mode 1 (qᵢ = A sin(πi/(n+1)), q̇ = 0: Fermi's run with
//! n = 32, α = 0.25, A = 1), and the energy flows to the next few modes and returns to mode 1
//! near the recurrence time (about 157 periods of mode 1 there).

use crate::chain::{spring_ends, spring_indices};
use crate::params::{finite, non_negative, size, unknown};
use nalgebra::{Const, DVector, SVector};
use svi::Error;
use svi::Scalar;
use svi::Structure;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};

/// The FPUT chain (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Fput {
    /// Number of moving particles n.
    pub n: usize,
    /// Cubic coefficient α.
    pub alpha: f64,
    /// Quartic coefficient β.
    pub beta: f64,
    /// Amplitude A of the initial mode-1 displacement.
    pub amplitude: f64,
}

impl Default for Fput {
    fn default() -> Self {
        Fput {
            n: 32,
            alpha: 0.25,
            beta: 0.0,
            amplitude: 1.0,
        }
    }
}

impl Fput {
    /// The spring potential V(r) = r²/2 + α r³/3 + β r⁴/4.
    #[inline]
    fn spring<D: Scalar>(&self, r: D) -> D {
        let r2 = r * r;
        r2 * (D::from(0.5) + r * (self.alpha / 3.0) + r2 * (self.beta * 0.25))
    }

    /// ω_k = 2 sin(πk/(2(n+1))), k = 1..n.
    pub fn mode_frequency(&self, k: usize) -> f64 {
        2.0 * (std::f64::consts::PI * k as f64 / (2.0 * (self.n + 1) as f64)).sin()
    }

    /// The harmonic energies E_k = ½(Q̇_k² + ω_k² Q_k²) of the first `modes` normal modes
    /// (O(n) each).
    pub fn mode_energies(&self, q: &DVector<f64>, v: &DVector<f64>, modes: usize) -> Vec<f64> {
        let n = self.n;
        let scale = (2.0 / (n + 1) as f64).sqrt();
        (1..=modes.min(n))
            .map(|k| {
                let (mut position, mut velocity) = (0.0, 0.0);
                for i in 0..n {
                    let s = (std::f64::consts::PI * ((i + 1) * k) as f64 / (n + 1) as f64).sin();
                    position += q[i] * s;
                    velocity += v[i] * s;
                }
                let (position, velocity) = (scale * position, scale * velocity);
                let omega = self.mode_frequency(k);
                0.5 * (velocity * velocity + omega * omega * position * position)
            })
            .collect()
    }
}

impl LocalLagrangian for Fput {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        self.n
    }

    fn term_count(&self) -> usize {
        self.n + 1
    }

    /// Spring e joins particles e − 1 and e; at a wall the neighbour's index is repeated (and
    /// the term ignores that slot).
    #[inline]
    fn indices(&self, e: usize) -> [usize; 2] {
        spring_indices(e, self.n)
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let zero = D::from(0.0);
        let (left, right) = spring_ends(e, self.n, q, (0.0, 0.0));
        let kinetic = if e < self.n { v[1] * v[1] * 0.5 } else { zero };
        kinetic - self.spring(right - left)
    }
}

impl LocalInvariants for Fput {}

impl LocalDefaults for Fput {
    fn name(&self) -> &'static str {
        "fput"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("n", self.n as f64),
            ("alpha", self.alpha),
            ("beta", self.beta),
            ("amplitude", self.amplitude),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "n" => self.n = size(name, value, 1)?,
            "alpha" => self.alpha = finite(name, value)?,
            "beta" => self.beta = non_negative(name, value)?,
            "amplitude" => self.amplitude = finite(name, value)?,
            _ => return Err(unknown("fput", name, &["n", "alpha", "beta", "amplitude"])),
        }
        Ok(())
    }

    /// All energy in mode 1: qᵢ = A sin(πi/(n+1)), q̇ = 0.
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let n = self.n;
        let q = DVector::from_fn(n, |i, _| {
            self.amplitude * (std::f64::consts::PI * (i + 1) as f64 / (n + 1) as f64).sin()
        });
        (0.0, q, DVector::zeros(n))
    }

    /// A tenth of the shortest linear period 2π/ω_n ≥ π (the highest mode is resolved).
    fn default_step(&self) -> f64 {
        0.1
    }

    /// Past the recurrence of Fermi's run (n = 32, α = 0.25): about 160 periods of mode 1.
    fn default_horizon(&self) -> f64 {
        12_000.0
    }
}
