//! Time reparametrisation: a monitor g(q) > 0 and the Lagrangian in computational time τ.
//!
//! # The Poincaré transformation (Leok, *Generalized Variational Integrators*, §5.6)
//! For an autonomous L(q, q̇) with energy H and a monitor g(q) > 0, the Hamiltonian in τ
//!
//! K(q, p) = g(q) (H(q, p) − E₀)
//!
//! has, on its level set K = 0 (the initial energy E₀), the flow of H with dt/dτ = g(q):
//! where g is small, a uniform step in τ is a short step in t. Its Legendre transform is the
//! τ-Lagrangian
//!
//! L̃(q, q') = g(q) (L(q, q'/g(q)) + E₀),
//!
//! with q' = dq/dτ = g q̇. The momentum is unchanged, p̃ = ∂L̃/∂q' = g ∂L/∂q̇ / g = p, and the
//! energy of L̃ is p·q' − L̃ = g (p·q̇ − L − E₀) = K. (For L = ½m|q̇|² − V: L̃ = m|q'|²/(2g) −
//! g(V − E₀), whose Legendre transform is g(|p|²/(2m) + V − E₀) = K.)
//!
//! So a reparametrised variational integrator is any method applied to [`Reparametrized`]
//! with a fixed step in τ: a symplectic method stays symplectic (for K, in τ), its energy
//! error K stays bounded, and so does H − E₀ = K/g; the physical time is the quadrature
//! t(τ) = t₀ + ∫ g(q(σ)) dσ ([`crate::stepping::reparam`]). L̃ has a position-dependent mass
//! matrix (g in the denominator), so the spectral methods solve their stages by Newton's
//! method.
//!
//! # Monitors
//! A [`Monitor`] is written once, generic over [`Scalar`] (the integrators differentiate
//! it). [`Sundman`]: g = |q|^α for central forces (α = 3/2 makes Kepler steps uniform in the
//! mean anomaly's rate of change at pericentre, α = 1 is the eccentric anomaly).
//! [`MonitorSpec`] names the monitors the command line knows (`sundman:ALPHA`).

use crate::error::Error;
use crate::model::Lagrangian;
use crate::scalar::{Scalar, constant};
use nalgebra::SVector;
use std::fmt;
use std::str::FromStr;

/// A time monitor g(q) > 0: dt/dτ = g(q) (small where the motion is fast).
pub trait Monitor<const N: usize> {
    /// The value g(q), written once generic over the scalar (it is differentiated).
    fn monitor<D: Scalar>(&self, q: &SVector<D, N>) -> D;
}

/// The Sundman monitor g(q) = |q|^α of a central force about the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sundman {
    /// The exponent α (finite).
    pub alpha: f64,
}

impl<const N: usize> Monitor<N> for Sundman {
    /// |q|^α from r² = |q|²; the exponents 1, 3/2, 2 and 3 by square roots and products (a
    /// general power costs several `pow` calls on dual numbers: 16 % of a reparametrised
    /// Kepler step with α = 1).
    #[inline]
    fn monitor<D: Scalar>(&self, q: &SVector<D, N>) -> D {
        let r2 = q.dot(q);
        match self.alpha {
            1.0 => r2.sqrt(),
            1.5 => {
                let r = r2.sqrt();
                r * r.sqrt()
            }
            2.0 => r2,
            3.0 => r2 * r2.sqrt(),
            alpha => r2.powf(0.5 * alpha),
        }
    }
}

/// The monitors known by name (the command line's `--monitor`).
///
/// Grammar: `sundman:ALPHA` (g = |q|^ALPHA, ALPHA a finite number, e.g. `sundman:1.5`) or
/// `sundman` (α = 3/2).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum MonitorSpec {
    /// [`Sundman`].
    Sundman(Sundman),
}

impl Default for MonitorSpec {
    /// `sundman:1.5`.
    fn default() -> Self {
        MonitorSpec::Sundman(Sundman { alpha: 1.5 })
    }
}

impl<const N: usize> Monitor<N> for MonitorSpec {
    #[inline]
    fn monitor<D: Scalar>(&self, q: &SVector<D, N>) -> D {
        match self {
            MonitorSpec::Sundman(sundman) => sundman.monitor(q),
        }
    }
}

impl FromStr for MonitorSpec {
    type Err = Error;
    fn from_str(text: &str) -> Result<Self, Error> {
        let text = text.trim();
        let (name, argument) = match text.split_once(':') {
            Some((name, argument)) => (name.trim(), Some(argument.trim())),
            None => (text, None),
        };
        match name {
            "sundman" => {
                let alpha = match argument {
                    None => 1.5,
                    Some(argument) => argument.parse::<f64>().map_err(|_| {
                        Error::invalid(
                            "monitor",
                            format!("'{argument}' is not a number (expected sundman:ALPHA)"),
                        )
                    })?,
                };
                if !alpha.is_finite() {
                    return Err(Error::invalid(
                        "monitor",
                        format!("the exponent of sundman:ALPHA must be finite, not {alpha}"),
                    ));
                }
                Ok(MonitorSpec::Sundman(Sundman { alpha }))
            }
            other => Err(Error::invalid(
                "monitor",
                format!("unknown monitor {other:?}; use sundman:ALPHA (g = |q|^ALPHA)"),
            )),
        }
    }
}

impl fmt::Display for MonitorSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MonitorSpec::Sundman(Sundman { alpha }) => write!(f, "sundman:{alpha}"),
        }
    }
}

/// The τ-Lagrangian L̃(q, q') = g(q) (L(q, q'/g(q)) + E₀) of an autonomous, unforced `L`
/// with the monitor `G` on the energy level E₀ (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct Reparametrized<'a, L, G> {
    model: &'a L,
    monitor: &'a G,
    energy: f64,
}

impl<'a, L, G> Reparametrized<'a, L, G> {
    /// L̃ for `model` with `monitor` on the energy level `energy` (the initial energy E₀).
    /// `model` must be autonomous and unforced (`TIME_DEPENDENT` and `FORCED` false) and
    /// `energy` finite: otherwise [`Error::InvalidParameter`].
    pub fn new<const N: usize>(model: &'a L, monitor: &'a G, energy: f64) -> Result<Self, Error>
    where
        L: Lagrangian<N>,
    {
        if L::TIME_DEPENDENT {
            return Err(Error::invalid(
                "adapt",
                "reparam needs an autonomous Lagrangian (TIME_DEPENDENT = false): the \
                 Poincaré transformation conserves the energy",
            ));
        }
        if L::FORCED {
            return Err(Error::invalid(
                "adapt",
                "reparam needs an unforced model: with an external force the energy is not \
                 conserved",
            ));
        }
        if !energy.is_finite() {
            return Err(Error::invalid(
                "energy",
                format!("the initial energy is {energy}"),
            ));
        }
        Ok(Reparametrized {
            model,
            monitor,
            energy,
        })
    }

    /// The energy level E₀.
    pub fn energy_level(&self) -> f64 {
        self.energy
    }
}

impl<L: Lagrangian<N>, G: Monitor<N>, const N: usize> Lagrangian<N> for Reparametrized<'_, L, G> {
    const TIME_DEPENDENT: bool = false;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _tau: D, q: &SVector<D, N>, w: &SVector<D, N>) -> D {
        let g = self.monitor.monitor(q);
        let inverse = g.recip();
        let v = w.map(|x| x * inverse);
        g * (self.model.lagrangian(constant(0.0), q, &v) + constant::<D>(self.energy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::derived::LagrangianExt;

    #[test]
    fn sundman_is_the_power_of_the_distance_for_every_exponent_and_its_derivative() {
        // g = |q|^α at |q| = 5 (q = (3, 4)): 5^α, and ∂g/∂q₀ = α 5^(α−2) · 3.
        use num_dual::Dual64;
        for alpha in [1.0, 1.5, 2.0, 3.0, 0.7, -1.0] {
            let g = Sundman { alpha };
            let q = SVector::from([Dual64::from_re(3.0).derivative(), Dual64::from_re(4.0)]);
            let value = Monitor::<2>::monitor(&g, &q);
            let (exact, slope) = (5f64.powf(alpha), alpha * 5f64.powf(alpha - 2.0) * 3.0);
            assert!(
                (value.re - exact).abs() <= 4.0 * f64::EPSILON * exact,
                "α = {alpha}"
            );
            assert!(
                (value.eps - slope).abs() <= 8.0 * f64::EPSILON * slope.abs(),
                "α = {alpha}"
            );
        }
    }

    /// L = |v|²/2 + 1/|q| (Kepler).
    struct Kepler;
    impl Lagrangian<2> for Kepler {
        const TIME_DEPENDENT: bool = false;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            v.dot(v) * 0.5 + q.dot(q).sqrt().recip()
        }
    }

    #[test]
    fn the_momentum_is_unchanged_and_the_energy_is_the_poincare_hamiltonian() {
        let monitor = Sundman { alpha: 1.5 };
        let (q, v) = (SVector::from([0.3, -0.4]), SVector::from([1.1, 0.7]));
        let e0 = -0.6;
        let tilde = Reparametrized::new(&Kepler, &monitor, e0).unwrap();
        let g = 0.5f64.powf(1.5);
        let w = v * g;
        let difference = tilde.momentum(0.0, &q, &w) - Kepler.momentum(0.0, &q, &v);
        assert!(difference.norm() < 1e-14, "{difference}");
        let k = g * (Kepler.energy(0.0, &q, &v) - e0);
        assert!((tilde.energy(0.0, &q, &w) - k).abs() < 1e-14);
        // The closed form m|q'|²/(2g) − g(V − E₀) with V = −1/|q|.
        let closed = w.dot(&w) / (2.0 * g) - g * (-2.0 - e0);
        assert!((tilde.value(0.0, &q, &w) - closed).abs() < 1e-14);
    }

    #[test]
    fn monitor_specs_parse_and_bad_ones_are_named() {
        let spec: MonitorSpec = "sundman:1".parse().unwrap();
        assert_eq!(spec, MonitorSpec::Sundman(Sundman { alpha: 1.0 }));
        assert_eq!(spec.to_string(), "sundman:1");
        assert_eq!(
            "sundman".parse::<MonitorSpec>().unwrap(),
            MonitorSpec::default()
        );
        for bad in ["sundman:x", "sundman:inf", "r^2", ""] {
            let error = bad.parse::<MonitorSpec>().unwrap_err();
            assert!(
                matches!(&error, Error::InvalidParameter { name, .. } if name == "monitor"),
                "{bad}: {error}"
            );
        }
    }

    #[test]
    fn time_dependent_models_and_non_finite_energies_are_refused() {
        struct Driven;
        impl Lagrangian<1> for Driven {
            fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
                v[0] * v[0] * 0.5 - q[0] * t.cos()
            }
        }
        let monitor = Sundman { alpha: 1.0 };
        assert!(Reparametrized::new(&Driven, &monitor, 0.0).is_err());
        assert!(Reparametrized::new(&Kepler, &monitor, f64::NAN).is_err());
    }
}
