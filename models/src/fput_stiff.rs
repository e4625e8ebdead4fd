//! The Fermi–Pasta–Ulam chain with alternating stiff and soft springs, the classic test of
//! integrators for multiscale oscillations (Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration*, 2nd ed., §I.5 and §XIII.2; Galgani, Giorgilli, Martinoli & Vanessi, Physica D
//! 59 (1992) 334–348).
//!
//! # Lagrangian
//! 2m unit masses q₁, …, q_{2m} between two walls (q₀ = q_{2m+1} = 0), joined alternately by
//! soft nonlinear springs and stiff harmonic ones (HLW (I.5.1)):
//!
//! L = Σᵢ ½ q̇ᵢ² − (ω²/4) Σ_{i=1}^{m} (q_{2i} − q_{2i−1})² − Σ_{i=0}^{m} (q_{2i+1} − q_{2i})⁴,
//!
//! with ω ≫ 1 the stiff springs' frequency. A sum of local terms ([`LocalLagrangian`], width
//! 2, the layout of [`crate::Fput`]): term e is spring e between particles e − 1 and e
//! (vector indices; 1-based particles e and e + 1), stiff for odd e, soft for even e, carrying
//! particle e's kinetic energy.
//!
//! # Oscillatory energies
//! In the coordinates of each stiff spring's centre and elongation, x_{0,i} = (q_{2i} +
//! q_{2i−1})/√2 and x_{1,i} = (q_{2i} − q_{2i−1})/√2 (the same for the velocities y), the
//! stiff springs are harmonic oscillators x₁'' = −ω² x₁ + O(1) with the energies
//!
//! I_i = ½ (ẋ_{1,i}² + ω² x_{1,i}²),
//!
//! ([`FputStiff::oscillatory_energies`]). Their sum I = Σ I_i is an adiabatic invariant,
//! I(t) = I(0) + O(ω⁻¹) over times exponentially long in ω, while energy flows between the
//! stiff springs on the slow time scale ω (HLW §I.5.1, Fig. I.5.2; §XIII.6): an integrator
//! that steps over the fast oscillation must keep I, and one that resolves it shows the
//! exchange.
//!
//! # Defaults
//! HLW's run: m = 3, ω = 50, x_{0,1}(0) = 1, ẋ_{0,1}(0) = 1, x_{1,1}(0) = ω⁻¹,
//! ẋ_{1,1}(0) = 1, all other coordinates zero (I(0) = 1); step 10⁻³ (hω = 0.05), horizon 200.

use crate::chain::{spring_ends, spring_indices};
use crate::params::{positive, size, unknown};
use nalgebra::{Const, DVector, SVector};
use std::f64::consts::FRAC_1_SQRT_2;
use svi::Error;
use svi::Scalar;
use svi::Structure;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};

/// The stiff–soft FPU chain (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FputStiff {
    /// Number of stiff springs m (2m moving particles).
    pub m: usize,
    /// Frequency ω of the stiff springs (> 0).
    pub omega: f64,
}

impl Default for FputStiff {
    /// m = 3, ω = 50 (HLW §I.5.1).
    fn default() -> Self {
        FputStiff { m: 3, omega: 50.0 }
    }
}

impl FputStiff {
    /// Registry name of the model.
    pub const NAME: &'static str = "fput-stiff";

    /// The oscillatory energies I_i = ½(ẋ_{1,i}² + ω² x_{1,i}²), i = 1..m, of the stiff
    /// springs (see the module docs).
    pub fn oscillatory_energies(&self, q: &DVector<f64>, v: &DVector<f64>) -> Vec<f64> {
        (0..self.m)
            .map(|i| {
                let x = FRAC_1_SQRT_2 * (q[2 * i + 1] - q[2 * i]);
                let y = FRAC_1_SQRT_2 * (v[2 * i + 1] - v[2 * i]);
                0.5 * (y * y + self.omega * self.omega * x * x)
            })
            .collect()
    }
}

impl LocalLagrangian for FputStiff {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        2 * self.m
    }

    fn term_count(&self) -> usize {
        2 * self.m + 1
    }

    /// Spring e joins particles e − 1 and e; at a wall the neighbour's index is repeated (and
    /// the term ignores that slot).
    #[inline]
    fn indices(&self, e: usize) -> [usize; 2] {
        spring_indices(e, 2 * self.m)
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let n = 2 * self.m;
        let (left, right) = spring_ends(e, n, q, (0.0, 0.0));
        let r = right - left;
        let potential = if e % 2 == 1 {
            r * r * (0.25 * self.omega * self.omega)
        } else {
            let r2 = r * r;
            r2 * r2
        };
        let kinetic = if e < n {
            v[1] * v[1] * 0.5
        } else {
            D::from(0.0)
        };
        kinetic - potential
    }
}

/// I is only an adiabatic invariant (conserved up to O(ω⁻¹)): no exact invariants besides
/// the energy.
impl LocalInvariants for FputStiff {}

impl LocalDefaults for FputStiff {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("m", self.m as f64), ("omega", self.omega)]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "m" => self.m = size(name, value, 1)?,
            "omega" => self.omega = positive(name, value)?,
            _ => return Err(unknown(Self::NAME, name, &["m", "omega"])),
        }
        Ok(())
    }

    /// HLW's initial state: x_{0,1} = 1, ẋ_{0,1} = 1, x_{1,1} = ω⁻¹, ẋ_{1,1} = 1, the rest 0
    /// (q₁ = (x₀ − x₁)/√2, q₂ = (x₀ + x₁)/√2).
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let n = 2 * self.m;
        let (x0, x1) = (1.0, self.omega.recip());
        let (y0, y1) = (1.0, 1.0);
        let mut q = DVector::zeros(n);
        let mut v = DVector::zeros(n);
        q[0] = FRAC_1_SQRT_2 * (x0 - x1);
        q[1] = FRAC_1_SQRT_2 * (x0 + x1);
        v[0] = FRAC_1_SQRT_2 * (y0 - y1);
        v[1] = FRAC_1_SQRT_2 * (y0 + y1);
        (0.0, q, v)
    }

    /// 10⁻³ for ω = 50: hω = 0.05, the stiff springs resolved.
    fn default_step(&self) -> f64 {
        0.05 / self.omega
    }

    /// 200: the energy exchange between the stiff springs (HLW Fig. I.5.2).
    fn default_horizon(&self) -> f64 {
        200.0
    }
}
