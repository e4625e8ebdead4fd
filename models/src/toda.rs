//! The periodic Toda lattice: n unit masses on a ring, neighbours joined by exponential
//! springs (Toda 1967; Flaschka, *The Toda lattice II*, Prog. Theor. Phys. 1974).
//!
//! L = Σᵢ ½ q̇ᵢ² − Σᵢ exp(qᵢ − q_{i+1}),  q_{n+1} = q₁.
//!
//! A sum of local terms ([`LocalLagrangian`], width 2): term i is the spring from particle i to
//! i + 1 (mod n), carrying particle i's kinetic energy.
//!
//! The lattice is integrable. In Flaschka's variables aᵢ = ½ exp((qᵢ − q_{i+1})/2),
//! bᵢ = −½ pᵢ, the Lax matrix 𝕃 is the symmetric periodic tridiagonal matrix with diagonal
//! bᵢ and off-diagonal entries aᵢ (𝕃_{i,i+1} = 𝕃_{i+1,i} = aᵢ, indices mod n), and the
//! traces tr 𝕃ᵏ, k = 1, …, n, are conserved; [`LocalInvariants`] reports k = 1, …, 4
//! (tr 𝕃 = −½ Σ pᵢ is the total momentum, tr 𝕃² = H/2). They are computed with 𝕃 as a sum
//! of shifted diagonals, 𝕃 = Σ_d D_d S^d (S the cyclic shift), in O(n k²), exact for every n
//! (for n ≤ 2k the shifts wrap around and the trace collects every d ≡ 0 mod n).

use crate::params::{finite, size, unknown};
use nalgebra::{Const, DVector, SVector};
use svi::Error;
use svi::Scalar;
use svi::Structure;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian};

/// The periodic Toda lattice (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Toda {
    /// Number of particles n (at least 2).
    pub n: usize,
    /// Amplitude of the initial velocity profile q̇ᵢ = A sin(2πi/n).
    pub amplitude: f64,
}

impl Default for Toda {
    fn default() -> Self {
        Toda {
            n: 16,
            amplitude: 1.0,
        }
    }
}

/// The largest power of the Lax matrix whose trace is reported.
const TRACES: usize = 4;

impl Toda {
    /// tr 𝕃ᵏ for k = 1, …, `powers` at (q, p) (unit masses: p = q̇).
    pub fn lax_traces(&self, q: &DVector<f64>, p: &DVector<f64>, powers: usize) -> Vec<f64> {
        let n = self.n;
        // 𝕃 as shifted diagonals: offsets −1, 0, 1, each a vector over rows.
        let a: Vec<f64> = (0..n)
            .map(|i| 0.5 * ((q[i] - q[(i + 1) % n]) * 0.5).exp())
            .collect();
        let lax: Vec<(isize, Vec<f64>)> = vec![
            (-1, (0..n).map(|i| a[(i + n - 1) % n]).collect()),
            (0, (0..n).map(|i| -0.5 * p[i]).collect()),
            (1, a.clone()),
        ];
        let mut power = lax.clone();
        let mut traces = Vec::with_capacity(powers);
        for k in 1..=powers {
            if k > 1 {
                power = multiply(&power, &lax, n);
            }
            let trace = power
                .iter()
                .filter(|(d, _)| d.rem_euclid(n as isize) == 0)
                .map(|(_, diagonal)| diagonal.iter().sum::<f64>())
                .sum();
            traces.push(trace);
        }
        traces
    }
}

/// The product of two sums of shifted diagonals, (Σ_d A_d S^d)(Σ_e B_e S^e) =
/// Σ_{d,e} (A_d ∘ S^d B_e) S^{d+e}, with (S^d x)ᵢ = x_{i+d mod n}.
fn multiply(a: &[(isize, Vec<f64>)], b: &[(isize, Vec<f64>)], n: usize) -> Vec<(isize, Vec<f64>)> {
    let mut product: Vec<(isize, Vec<f64>)> = Vec::new();
    for (d, left) in a {
        for (e, right) in b {
            let offset = d + e;
            let index = match product.iter().position(|(o, _)| *o == offset) {
                Some(index) => index,
                None => {
                    product.push((offset, vec![0.0; n]));
                    product.len() - 1
                }
            };
            let target = &mut product[index].1;
            for i in 0..n {
                let j = (i as isize + d).rem_euclid(n as isize) as usize;
                target[i] += left[i] * right[j];
            }
        }
    }
    product
}

impl LocalLagrangian for Toda {
    type Width = Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        self.n
    }

    fn term_count(&self) -> usize {
        self.n
    }

    #[inline]
    fn indices(&self, i: usize) -> [usize; 2] {
        [i, (i + 1) % self.n]
    }

    #[inline]
    fn term<D: Scalar>(&self, _i: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        v[0] * v[0] * 0.5 - (q[0] - q[1]).exp()
    }
}

impl LocalInvariants for Toda {
    fn invariant_count(&self) -> usize {
        TRACES
    }

    fn invariant_name(&self, index: usize) -> &'static str {
        ["trace_lax_1", "trace_lax_2", "trace_lax_3", "trace_lax_4"][index]
    }

    fn invariant(&self, index: usize, _t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        self.lax_traces(q, v, index + 1)[index]
    }
}

impl LocalDefaults for Toda {
    fn name(&self) -> &'static str {
        "toda"
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("n", self.n as f64), ("amplitude", self.amplitude)]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "n" => self.n = size(name, value, 2)?,
            "amplitude" => self.amplitude = finite(name, value)?,
            _ => return Err(unknown("toda", name, &["n", "amplitude"])),
        }
        Ok(())
    }

    /// At rest at equal spacing, with velocities q̇ᵢ = A sin(2πi/n) (zero total momentum).
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let n = self.n;
        let v = DVector::from_fn(n, |i, _| {
            self.amplitude * (2.0 * std::f64::consts::PI * i as f64 / n as f64).sin()
        });
        (0.0, DVector::zeros(n), v)
    }

    fn default_step(&self) -> f64 {
        0.1
    }

    fn default_horizon(&self) -> f64 {
        1000.0
    }
}
