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
//! it), and may read the model. [`Sundman`]: g = |q|^α for central forces (α = 3/2 makes
//! Kepler steps uniform in the mean anomaly's rate of change at pericentre, α = 1 is the
//! eccentric anomaly). [`Force`]: g = |F(q)|^(−β) with F = ∂L/∂q(q, 0), the generalised force
//! at rest (−∇V for L = ½q̇ᵀM(q)q̇ − V(q)), derived from L by automatic differentiation
//! (nested in the integrators' own dual numbers), for any model: steps shrink where the force
//! is strong. For a central force μ/r² it is Sundman's monitor, |F|^(−β) = μ^(−β) r^(2β), so
//! `force:0.75` takes the steps of `sundman:1.5` (Δτ scaled by μ^(3/4)). A point where the
//! force vanishes (an equilibrium) has g = ∞: the run stops there with a typed error.
//! [`Potential`]: g = 1/U with U(q) = L(q, 0) = −V(q) > 0, whose transformed Hamiltonian
//! splits into explicit flows when taken logarithmically (Mikkola & Tanikawa 1999; Preto &
//! Tremaine 1999; [`crate::stepping::logh`]). [`MonitorSpec`] names the monitors the command
//! line knows (`sundman:ALPHA`, `force:BETA`, `potential`).

use crate::dimension::{Dimension, PhaseFunction, Wrt};
use crate::error::Error;
use crate::model::Lagrangian;
use crate::scalar::{Scalar, constant};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};
use std::fmt;
use std::str::FromStr;

/// A time monitor g(q) > 0: dt/dτ = g(q) (small where the motion is fast).
pub trait Monitor<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The value g(q) for `model`, written once generic over the scalar (it is
    /// differentiated). Monitors of the positions alone ignore `model`.
    fn monitor<D: Scalar, L: Lagrangian<N> + ?Sized>(&self, model: &L, q: &OVector<D, N>) -> D;

    /// Whether g = 1/U with U(q) = L(q, 0) (= −V(q)), the monitor whose transformed
    /// Hamiltonian, taken logarithmically, splits into explicit flows
    /// ([`crate::stepping::logh`]). Default `false`.
    fn logarithmic(&self) -> bool {
        false
    }
}

/// x^(α/2) from x = r² ≥ 0: the exponents α = 1/2, 3/4 (the force monitor's default), 1,
/// 3/2, 2 and 3 by square roots and products (a general power costs several `pow` calls on
/// dual numbers: 16 % of a reparametrised Kepler step with α = 1), others by `powf`.
#[inline]
fn half_power<D: Scalar>(x: D, alpha: f64) -> D {
    match alpha {
        0.5 => x.sqrt().sqrt(),
        0.75 => {
            let r = x.sqrt().sqrt();
            r * r.sqrt()
        }
        1.0 => x.sqrt(),
        1.5 => {
            let r = x.sqrt();
            r * r.sqrt()
        }
        2.0 => x,
        3.0 => x * x.sqrt(),
        alpha => x.powf(0.5 * alpha),
    }
}

/// The Sundman monitor g(q) = |q|^α of a central force about the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sundman {
    /// The exponent α (finite).
    pub alpha: f64,
}

impl<N: Dimension> Monitor<N> for Sundman
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// |q|^α from r² = |q|².
    #[inline]
    fn monitor<D: Scalar, L: Lagrangian<N> + ?Sized>(&self, _model: &L, q: &OVector<D, N>) -> D {
        half_power(q.dot(q), self.alpha)
    }
}

/// The force monitor g(q) = |∂L/∂q(q, 0)|^(−β): the generalised force at rest, by automatic
/// differentiation of the model's Lagrangian (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Force {
    /// The exponent β (finite; β = 3/4 is Sundman's 3/2 for an inverse-square force).
    pub beta: f64,
}

/// U(q) = L(0, q, 0), a function of q alone, as a [`PhaseFunction`]: the time and velocity
/// it is handed are not read (t = 0 and q̇ = 0 are put in their place).
struct AtRest<'a, L: ?Sized>(&'a L);

impl<L: Lagrangian<N> + ?Sized, N: Dimension> PhaseFunction<N> for AtRest<'_, L>
where
    DefaultAllocator: Allocator<N>,
{
    #[inline]
    fn eval<S: Scalar>(&self, _t: S, q: &OVector<S, N>, _v: &OVector<S, N>) -> S {
        self.0.lagrangian(
            constant(0.0),
            q,
            &OVector::from_element_generic(q.shape_generic().0, U1, constant(0.0)),
        )
    }
}

impl<N: Dimension> Monitor<N> for Force
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// (|F|²)^(−β/2) from F = ∂L/∂q at q̇ = 0, t = 0 (one gradient of [`Dimension::gradient`]
    /// in dual numbers over the caller's scalar).
    #[inline]
    fn monitor<D: Scalar, L: Lagrangian<N> + ?Sized>(&self, model: &L, q: &OVector<D, N>) -> D {
        // `AtRest` reads neither t nor q̇: `q` stands in for the velocity argument.
        let (_, force) = N::gradient(&AtRest(model), constant(0.0), q, q, Wrt::Position);
        half_power(force.dot(&force), self.beta).recip()
    }
}

/// The potential monitor g(q) = 1/U(q), U(q) = L(q, 0) = −V(q) > 0 for L = ½q̇ᵀM(q)q̇ − V(q)
/// (a potential below zero everywhere, as gravity's −μ/r): dt = dτ/U, so for a central force
/// μ/r² it is Sundman's g = r/μ. On the energy shell the Poincaré Hamiltonian
/// K = (H − E₀)/U has the flow of Γ = ln(1 + K) = ln(T(p) − E₀) − ln U(q), a sum of a kinetic
/// and a potential part: with Störmer–Verlet or one of its compositions on a constant-mass
/// model, a reparametrised run splits Γ explicitly ([`crate::stepping::logh`]); other methods
/// run on [`Reparametrized`] with this g.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Potential;

impl<N: Dimension> Monitor<N> for Potential
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// 1/L(0, q, 0) (no derivative of L: one evaluation in the caller's scalar).
    #[inline]
    fn monitor<D: Scalar, L: Lagrangian<N> + ?Sized>(&self, model: &L, q: &OVector<D, N>) -> D {
        model
            .lagrangian(
                constant(0.0),
                q,
                &OVector::from_element_generic(q.shape_generic().0, U1, constant(0.0)),
            )
            .recip()
    }

    fn logarithmic(&self) -> bool {
        true
    }
}

/// The monitors known by name (the command line's `--monitor`).
///
/// Grammar: `sundman:ALPHA` (g = |q|^ALPHA, ALPHA a finite number, e.g. `sundman:1.5`),
/// `sundman` (α = 3/2), `force:BETA` (g = |∂L/∂q(q, 0)|^(−BETA)), `force` (β = 3/4) or
/// `potential` (g = 1/L(q, 0)).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum MonitorSpec {
    /// [`Sundman`].
    Sundman(Sundman),
    /// [`Force`].
    Force(Force),
    /// [`Potential`].
    Potential(Potential),
}

impl Default for MonitorSpec {
    /// `sundman:1.5`.
    fn default() -> Self {
        MonitorSpec::Sundman(Sundman { alpha: 1.5 })
    }
}

impl<N: Dimension> Monitor<N> for MonitorSpec
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    #[inline]
    fn monitor<D: Scalar, L: Lagrangian<N> + ?Sized>(&self, model: &L, q: &OVector<D, N>) -> D {
        match self {
            MonitorSpec::Sundman(sundman) => sundman.monitor(model, q),
            MonitorSpec::Force(force) => force.monitor(model, q),
            MonitorSpec::Potential(potential) => potential.monitor(model, q),
        }
    }

    fn logarithmic(&self) -> bool {
        matches!(self, MonitorSpec::Potential(_))
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
        let exponent = |default: f64, grammar: &str| -> Result<f64, Error> {
            let value = match argument {
                None => default,
                Some(argument) => argument.parse::<f64>().map_err(|_| {
                    Error::invalid(
                        "monitor",
                        format!("'{argument}' is not a number (expected {grammar})"),
                    )
                })?,
            };
            if value.is_finite() {
                Ok(value)
            } else {
                Err(Error::invalid(
                    "monitor",
                    format!("the exponent of {grammar} must be finite, not {value}"),
                ))
            }
        };
        match name {
            "sundman" => Ok(MonitorSpec::Sundman(Sundman {
                alpha: exponent(1.5, "sundman:ALPHA")?,
            })),
            "force" => Ok(MonitorSpec::Force(Force {
                beta: exponent(0.75, "force:BETA")?,
            })),
            "potential" => match argument {
                None => Ok(MonitorSpec::Potential(Potential)),
                Some(argument) => Err(Error::invalid(
                    "monitor",
                    format!("potential takes no argument, not '{argument}'"),
                )),
            },
            other => Err(Error::invalid(
                "monitor",
                format!(
                    "unknown monitor {other:?}; use sundman:ALPHA (g = |q|^ALPHA), force:BETA \
                     (g = |∂L/∂q(q, 0)|^(−BETA)) or potential (g = 1/L(q, 0) = −1/V(q))"
                ),
            )),
        }
    }
}

impl fmt::Display for MonitorSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MonitorSpec::Sundman(Sundman { alpha }) => write!(f, "sundman:{alpha}"),
            MonitorSpec::Force(Force { beta }) => write!(f, "force:{beta}"),
            MonitorSpec::Potential(Potential) => f.write_str("potential"),
        }
    }
}

/// Why `L` cannot be reparametrized in time, for a model that is time-dependent or forced
/// (the callers test [`Lagrangian::TIME_DEPENDENT`] and [`Lagrangian::FORCED`] themselves,
/// as constants, so that no reparametrized run is compiled for such a model).
pub(crate) fn not_reparametrizable<L: Lagrangian<N>, N: Dimension>() -> Error
where
    DefaultAllocator: Allocator<N>,
{
    if L::TIME_DEPENDENT {
        Error::invalid(
            "adapt",
            "reparam needs an autonomous Lagrangian (TIME_DEPENDENT = false): the Poincaré \
             transformation conserves the energy",
        )
    } else {
        Error::invalid(
            "adapt",
            "reparam needs an unforced model: with an external force the energy is not \
             conserved",
        )
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
    pub fn new<N: Dimension>(model: &'a L, monitor: &'a G, energy: f64) -> Result<Self, Error>
    where
        L: Lagrangian<N>,
        DefaultAllocator: Allocator<N>,
    {
        if L::TIME_DEPENDENT || L::FORCED {
            return Err(not_reparametrizable::<L, N>());
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

    /// The monitor's value g(q) for the model.
    #[inline]
    pub fn monitor_value<D: Scalar, N: Dimension>(&self, q: &OVector<D, N>) -> D
    where
        L: Lagrangian<N>,
        G: Monitor<N>,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        self.monitor.monitor(self.model, q)
    }
}

impl<L: Lagrangian<N>, G: Monitor<N>, N: Dimension> Lagrangian<N> for Reparametrized<'_, L, G>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const TIME_DEPENDENT: bool = false;

    /// The model's number of coordinates.
    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, _tau: D, q: &OVector<D, N>, w: &OVector<D, N>) -> D {
        let g = self.monitor_value(q);
        let inverse = g.recip();
        let v = w.map(|x| x * inverse);
        g * (self.model.lagrangian(constant(0.0), q, &v) + constant::<D>(self.energy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::derived::LagrangianExt;
    use nalgebra::{SVector, U1, U2};

    #[test]
    fn sundman_is_the_power_of_the_distance_for_every_exponent_and_its_derivative() {
        // g = |q|^α at |q| = 5 (q = (3, 4)): 5^α, and ∂g/∂q₀ = α 5^(α−2) · 3.
        use num_dual::Dual64;
        for alpha in [1.0, 1.5, 2.0, 3.0, 0.7, -1.0] {
            let g = Sundman { alpha };
            let q = SVector::from([Dual64::from_re(3.0).derivative(), Dual64::from_re(4.0)]);
            let value = Monitor::<U2>::monitor(&g, &Kepler, &q);
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

    #[test]
    fn the_force_monitor_is_the_force_at_rest_with_its_derivative() {
        // A spring pendulum in (a, θ) with a position-dependent mass matrix: the force at
        // rest F = (−k a + m g cos θ, −m g (l + a) sin θ) ignores the kinetic energy, and
        // g = |F|^(−β); its derivative in a against the closed form.
        use num_dual::Dual64;
        struct Spring;
        const K: f64 = 50.0;
        impl Lagrangian<U2> for Spring {
            fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
                let length = q[0] + 1.0;
                (v[0] * v[0] + length * length * v[1] * v[1]) * 0.5 + length * q[1].cos() * 9.81
                    - q[0] * q[0] * (0.5 * K)
            }
        }
        let (a, theta): (f64, f64) = (0.3, 0.7);
        let force = |a: f64| {
            SVector::<f64, 2>::from([-K * a + 9.81 * theta.cos(), -9.81 * (1.0 + a) * theta.sin()])
        };
        for beta in [0.75, 0.5, 1.0, 0.4] {
            let monitor = Force { beta };
            let q = SVector::from([Dual64::from_re(a).derivative(), Dual64::from_re(theta)]);
            let g = Monitor::<U2>::monitor(&monitor, &Spring, &q);
            let exact = force(a).norm().powf(-beta);
            // d|F|^(−β)/da = −β |F|^(−β−2) F·∂F/∂a, ∂F/∂a = (−k, −g sin θ).
            let slope = -beta
                * force(a).norm().powf(-beta - 2.0)
                * force(a).dot(&SVector::from([-K, -9.81 * theta.sin()]));
            assert!((g.re - exact).abs() <= 1e-15 * exact, "β = {beta}");
            assert!((g.eps - slope).abs() <= 1e-14 * slope.abs(), "β = {beta}");
        }
    }

    /// L = |v|²/2 + 1/|q| (Kepler).
    struct Kepler;
    impl Lagrangian<U2> for Kepler {
        const TIME_DEPENDENT: bool = false;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            v.dot(v) * 0.5 + q.dot(q).sqrt().recip()
        }
    }

    #[test]
    fn monitors_and_the_tau_lagrangian_agree_on_a_run_time_size_model() {
        // Kepler as a `Lagrangian<Dyn>`: every monitor and L̃'s momentum as on `U2`, and L̃
        // reports the model's size.
        use crate::test_models::AsDyn;
        use nalgebra::{DVector, Dyn};
        let dynamic = AsDyn::new(Kepler);
        let (q, w) = (
            SVector::<f64, 2>::from([0.3, -0.4]),
            SVector::<f64, 2>::from([1.1, 0.7]),
        );
        let (q_dyn, w_dyn) = (
            DVector::from_column_slice(q.as_slice()),
            DVector::from_column_slice(w.as_slice()),
        );
        let specs = [
            MonitorSpec::default(),
            MonitorSpec::Force(Force { beta: 0.75 }),
            MonitorSpec::Potential(Potential),
        ];
        for spec in specs {
            let fixed = Monitor::<U2>::monitor(&spec, &Kepler, &q);
            let run_time = Monitor::<Dyn>::monitor(&spec, &dynamic, &q_dyn);
            assert!((fixed - run_time).abs() <= 1e-15 * fixed.abs(), "{spec}");
            let tilde = Reparametrized::new(&Kepler, &spec, -0.6).unwrap();
            let tilde_dyn = Reparametrized::new(&dynamic, &spec, -0.6).unwrap();
            assert_eq!(Lagrangian::<Dyn>::dimension(&tilde_dyn), 2);
            let momentum = tilde.momentum(0.0, &q, &w);
            let momentum_dyn = tilde_dyn.momentum(0.0, &q_dyn, &w_dyn);
            for i in 0..2 {
                assert!((momentum[i] - momentum_dyn[i]).abs() <= 1e-15, "{spec}");
            }
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
        assert_eq!(
            "force".parse::<MonitorSpec>().unwrap(),
            MonitorSpec::Force(Force { beta: 0.75 })
        );
        let spec: MonitorSpec = " force : 0.5 ".parse().unwrap();
        assert_eq!(spec.to_string(), "force:0.5");
        for bad in ["sundman:x", "sundman:inf", "force:nan", "force:", "r^2", ""] {
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
        impl Lagrangian<U1> for Driven {
            fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
                v[0] * v[0] * 0.5 - q[0] * t.cos()
            }
        }
        let monitor = Sundman { alpha: 1.0 };
        assert!(Reparametrized::new(&Driven, &monitor, 0.0).is_err());
        assert!(Reparametrized::new(&Kepler, &monitor, f64::NAN).is_err());
    }
}
