//! The Kepler two-body problem in the plane.
//!
//! # Lagrangian
//!
//! One body fixed at the origin, the other at q ∈ ℝ² with velocity v = q̇, in units with
//! G M = 1 (Li, Wu, Leok 2018, §5.2):
//!
//! L(q, v) = |v|²/2 + 1/|q|.
//!
//! # Equations of motion
//!
//! q̈ = −q/|q|³ (eq. 38). Conserved: the energy E = |v|²/2 − 1/|q|, the angular momentum
//! M = q₁v₂ − q₂v₁ (the Noether momentum of the rotation generator ξ(q) = (−q₂, q₁)), and
//! the Runge–Lenz vector A = (v₂M − q₁/|q|, −v₁M − q₂/|q|), of length the eccentricity e.
//!
//! # Exact solution
//!
//! [`KeplerOrbit`]: the orbital elements of any bound state (E < 0, M ≠ 0), propagated by
//! Kepler's equation E − e sin E = M₀ + n(t − t₀), solved by safeguarded Newton iteration.
//! Written for accuracy near round-off over long times (see [`KeplerOrbit`]).
//!
//! # Defaults
//!
//! e = 0.5; q(0) = (1 − e, 0), v(0) = (0, √((1 + e)/(1 − e))) (perihelion of an orbit with
//! semi-major axis 1, period 2π, E = −1/2, M = √(1 − e²)); step 0.2, horizon 2000: the
//! setting of Figs. 13–17 of the paper.
//!
//! # References
//!
//! J. Li, B. Wu, M. Leok, *Construction and comparison of multidimensional spectral
//! variational integrators and spectral collocation methods*, Appl. Numer. Math. (2018),
//! §5.2, eq. (38). Kepler's equation and the perifocal frame: e.g. R. H. Battin, *An
//! Introduction to the Mathematics and Methods of Astrodynamics* (1999), ch. 4–5.

use nalgebra::{SVector, U2};
use svi::{
    Defaults, Error, ExactSolution, Invariants, Lagrangian, Parametric, Scalar, Structure,
    Symmetries,
};

use crate::params;

/// The double nearest 2π (6.283185307179586).
const TAU_HIGH: f64 = std::f64::consts::TAU;
/// 2π − [`TAU_HIGH`], so that TAU_HIGH + TAU_LOW is 2π to about 10⁻³² (Cody–Waite).
const TAU_LOW: f64 = 2.449_293_598_294_706_4e-16;
/// Iteration cap of the Kepler-equation solver (bisection alone would converge in 60).
const MAX_NEWTON_ITERATIONS: usize = 100;

/// The planar Kepler problem L = |v|²/2 + 1/|q|; the eccentricity `e` and the `phase` only
/// select the default initial state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kepler {
    /// Eccentricity of the default orbit, 0 ≤ e < 1.
    pub e: f64,
    /// Mean anomaly of the default initial state, in radians: 0 (the default) starts at the
    /// pericentre, π at the apocentre; the orbit reaches the pericentre at t = −phase.
    pub phase: f64,
}

impl Kepler {
    /// Registry name of the model.
    pub const NAME: &'static str = "kepler";
    /// Parameter names, in the order of [`Defaults::parameters`].
    pub const PARAMETERS: [&'static str; 2] = ["e", "phase"];

    /// A Kepler model whose default orbit has eccentricity `e` ∈ [0, 1).
    pub fn new(e: f64) -> Result<Self, Error> {
        let mut model = Self::default();
        model.set_parameter("e", e)?;
        Ok(model)
    }

    /// The angular momentum q₁v₂ − q₂v₁.
    pub fn angular_momentum(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        q[0] * v[1] - q[1] * v[0]
    }

    /// The energy |v|²/2 − 1/|q|.
    pub fn energy(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        0.5 * v.dot(v) - q.norm().recip()
    }

    /// The Runge–Lenz vector A = v × (q × v) − q/|q| = (v₂M − q₁/|q|, −v₁M − q₂/|q|):
    /// it points to the pericentre and has length e.
    pub fn runge_lenz(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        let momentum = Self::angular_momentum(q, v);
        let radius = q.norm();
        SVector::from([
            v[1] * momentum - q[0] / radius,
            -v[0] * momentum - q[1] / radius,
        ])
    }
}

impl Default for Kepler {
    /// e = 0.5 (Li, Wu, Leok 2018, Figs. 13–15), starting at the pericentre (phase 0).
    fn default() -> Self {
        Self { e: 0.5, phase: 0.0 }
    }
}

impl Lagrangian<U2> for Kepler {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    #[inline]
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        // 1/|q| written as |q|·|q|⁻²: with dual numbers the square root's derivative needs
        // 1/|q|² anyway, so this form costs one division where `r2.sqrt().recip()` costs two
        // (the force's AD tax falls from 1.5× to 1.1× of the hand-written −q/|q|³,
        // `cargo bench --bench derivatives -- kepler/force`).
        let r2 = q.dot(q);
        v.dot(v) * 0.5 + r2.sqrt() * r2.recip()
    }
}

/// The state at mean anomaly M (`phase`) on the orbit of eccentricity e, semi-major axis 1
/// and pericentre on the positive q₁ axis, moving counter-clockwise: with E the eccentric
/// anomaly (E − e sin E = M),
///
/// q = (cos E − e, β sin E),  q̇ = (−sin E, β cos E)/(1 − e cos E) = s (−sin E/β, cos E),
///
/// β = √(1 − e²), s = k (1 − e)/(1 − e cos E) with k = √((1 + e)/(1 − e)) the speed at the
/// pericentre (β = k (1 − e)): written so that M = 0 gives [`Defaults::initial_state`]'s
/// pericentre bit for bit, q̇ = (0, k).
///
/// M is reduced modulo 2π; E is solved in `f64` ([`solve_kepler_equation`]) and corrected by one Newton step in the
/// scalar D, E = E₀ + (M − E₀ + e sin E₀)/(1 − e cos E₀): with E₀ the root, the step changes
/// no value and gives dual numbers the derivatives of the implicit function, ∂E/∂M =
/// 1/(1 − e cos E) and ∂E/∂e = sin E/(1 − e cos E).
fn orbit_start<D: Scalar>(e: D, phase: D) -> (SVector<D, 2>, SVector<D, 2>) {
    let one = D::one();
    let root = D::from(solve_kepler_equation(e.re(), 1.0 - e.re(), phase.re()));
    let slope = one - e * root.cos();
    let anomaly = root + (phase - root + e * root.sin()) / slope;
    let (sin, cos) = (anomaly.sin(), anomaly.cos());
    let beta = (one - e * e).sqrt();
    let speed = ((one + e) / (one - e)).sqrt() * ((one - e) / (one - e * cos));
    (
        SVector::from([cos - e, beta * sin]),
        SVector::from([D::zero() - sin * speed / beta, cos * speed]),
    )
}

/// θ = (e, phase): neither enters L; they move the model's initial state (`orbit_start`).
impl Parametric<U2> for Kepler {
    fn parameter_names(&self) -> Vec<String> {
        Self::PARAMETERS.map(String::from).to_vec()
    }

    fn parameter_values(&self) -> Vec<f64> {
        vec![self.e, self.phase]
    }

    #[inline]
    fn lagrangian_with<D: Scalar>(
        &self,
        _theta: &[D],
        t: D,
        q: &SVector<D, 2>,
        v: &SVector<D, 2>,
    ) -> D {
        self.lagrangian(t, q, v)
    }

    /// [`Defaults::initial_state`] as a function of e and the phase.
    fn initial_state_with<D: Scalar>(&self, theta: &[D]) -> Option<(SVector<D, 2>, SVector<D, 2>)> {
        Some(orbit_start(theta[0], theta[1]))
    }

    /// Neither e nor the phase enters L: their derivatives run on Kepler itself.
    fn enters_lagrangian(&self, _index: usize) -> bool {
        false
    }
}

impl Symmetries<U2> for Kepler {
    /// One: rotations about the origin.
    #[inline]
    fn generator_count(&self) -> usize {
        1
    }

    /// `"angular_momentum"`.
    ///
    /// # Panics
    /// If `index > 0`.
    fn momentum_name(&self, index: usize) -> &'static str {
        match index {
            0 => "angular_momentum",
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }

    /// ξ(q) = (−q₂, q₁), so that p·ξ = q₁v₂ − q₂v₁.
    ///
    /// # Panics
    /// If `index > 0`.
    #[inline]
    fn generator(&self, index: usize, q: &SVector<f64, 2>) -> SVector<f64, 2> {
        match index {
            0 => SVector::from([-q[1], q[0]]),
            _ => params::no_such_index("symmetry generator", Self::NAME, index),
        }
    }
}

impl Invariants<U2> for Kepler {
    /// Three: the length of the Runge–Lenz vector (the eccentricity) and its two
    /// components (their drift measures the precession of the pericentre).
    fn invariant_count(&self) -> usize {
        3
    }

    /// `"runge_lenz"` (|A|), `"runge_lenz_x"` (A₁), `"runge_lenz_y"` (A₂).
    ///
    /// # Panics
    /// If `index > 2`.
    fn invariant_name(&self, index: usize) -> &'static str {
        match index {
            0 => "runge_lenz",
            1 => "runge_lenz_x",
            2 => "runge_lenz_y",
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }

    /// # Panics
    /// If `index > 2`.
    fn invariant(&self, index: usize, _t: f64, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        let runge_lenz = Self::runge_lenz(q, v);
        match index {
            0 => runge_lenz.norm(),
            1 => runge_lenz[0],
            2 => runge_lenz[1],
            _ => params::no_such_index("invariant", Self::NAME, index),
        }
    }
}

impl ExactSolution<U2> for Kepler {
    /// The bound orbit through (q₀, v₀) at t₀ ([`KeplerOrbit`]); `None` for unbound
    /// (E ≥ 0) or radial (M = 0) states, a state at the origin, or non-finite input.
    fn exact_solution(
        &self,
        t0: f64,
        q0: &SVector<f64, 2>,
        v0: &SVector<f64, 2>,
        t: f64,
    ) -> Option<(SVector<f64, 2>, SVector<f64, 2>)> {
        let elapsed = t - t0;
        if !elapsed.is_finite() {
            return None;
        }
        Some(KeplerOrbit::from_state(q0, v0)?.state_after(elapsed))
    }
}

impl Defaults<U2> for Kepler {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        ["q1", "q2"].map(String::from).to_vec()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("e", self.e), ("phase", self.phase)]
    }

    /// `e` must be finite and in [0, 1); `phase` finite.
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "e" => {
                params::finite(name, value)?;
                if !(0.0..1.0).contains(&value) {
                    return Err(Error::invalid(
                        name,
                        format!("{value:?} is outside [0, 1) (the orbit must be bound)"),
                    ));
                }
                self.e = value;
            }
            "phase" => {
                params::finite(name, value)?;
                self.phase = value;
            }
            _ => return Err(params::unknown(Self::NAME, name, &Self::PARAMETERS)),
        }
        Ok(())
    }

    /// t₀ = 0 and the state at mean anomaly `phase` (`orbit_start`) of an orbit with
    /// semi-major axis 1 (period 2π, E = −1/2, M = √(1 − e²)); at phase 0 the pericentre
    /// q₀ = (1 − e, 0), v₀ = (0, √((1 + e)/(1 − e))).
    fn initial_state(&self) -> (f64, SVector<f64, 2>, SVector<f64, 2>) {
        let (q, v) = orbit_start(self.e, self.phase);
        (0.0, q, v)
    }

    /// h = 0.2 (Figs. 13–15).
    fn default_step(&self) -> f64 {
        0.2
    }

    /// T = 2000 (Figs. 13–15).
    fn default_horizon(&self) -> f64 {
        2000.0
    }
}

/// The orbital elements of a bound Kepler orbit (G M = 1), and its state at any time.
///
/// Position and velocity in the perifocal frame (P towards the pericentre, Q = P rotated a
/// quarter turn in the direction of motion), with a the semi-major axis, e the
/// eccentricity, β = √(1 − e²) and E the eccentric anomaly:
///
/// q = a (cos E − e) P + a β sin E Q,  v = (√a/r)(−sin E P + β cos E Q),
/// r = a (1 − e cos E),  E − e sin E = M₀ + n (t − t₀),  n = a^(−3/2).
///
/// Numerical care, so that the solution is a reference to about 10⁻¹⁵ even for e → 1 and
/// t − t₀ ~ 10³:
/// - 1 − e = β²/(1 + e) with β = |M|/√a, and cos E − e = (1 − e) − 2 sin²(E/2),
///   1 − e cos E = (1 − e) + 2e sin²(E/2): no cancellation near the pericentre;
/// - P is the direction of the Runge–Lenz vector (q₀/|q₀| for a circular orbit), and E₀
///   is measured geometrically from P, so a nearly circular orbit (P ill-determined) still
///   passes through q₀;
/// - n (t − t₀) is formed exactly (product plus its fused-multiply-add error) and reduced
///   modulo 2π with a two-part 2π (Cody–Waite);
/// - Kepler's equation is solved by Newton's method safeguarded by bisection on
///   [M − e, M + e], to round-off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeplerOrbit {
    /// Semi-major axis a.
    pub semi_major_axis: f64,
    /// Eccentricity e ∈ [0, 1).
    pub eccentricity: f64,
    /// β = √(1 − e²), computed from the angular momentum.
    pub beta: f64,
    /// Mean motion n = a^(−3/2) (the period is 2π/n).
    pub mean_motion: f64,
    /// Mean anomaly M₀ at the epoch (the time of the state the orbit was built from).
    pub mean_anomaly: f64,
    /// Unit vector P towards the pericentre.
    pub periapsis: SVector<f64, 2>,
    /// Unit vector Q ⊥ P, in the direction of motion at the pericentre.
    pub normal: SVector<f64, 2>,
}

impl KeplerOrbit {
    /// The orbit through the state (q, v); `None` unless the state is finite, q ≠ 0, the
    /// energy is negative and the angular momentum is non-zero.
    pub fn from_state(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> Option<Self> {
        if !(q.iter().chain(v.iter()).all(|x| x.is_finite())) {
            return None;
        }
        let radius = q.norm();
        let momentum = Kepler::angular_momentum(q, v);
        if radius == 0.0 || momentum == 0.0 {
            return None;
        }
        // 1/a = 2/r − |v|² (vis-viva); bound iff positive.
        let inverse_axis = 2.0 / radius - v.dot(v);
        if inverse_axis <= 0.0 {
            return None;
        }
        let axis = inverse_axis.recip();
        let beta = momentum.abs() * inverse_axis.sqrt();
        let runge_lenz = Kepler::runge_lenz(q, v);
        let eccentricity = runge_lenz.norm();
        if eccentricity >= 1.0 {
            return None;
        }
        let periapsis = if eccentricity > 0.0 {
            runge_lenz / eccentricity
        } else {
            q / radius
        };
        let normal = SVector::from([-periapsis[1], periapsis[0]]) * momentum.signum();
        let mut orbit = Self {
            semi_major_axis: axis,
            eccentricity,
            beta,
            mean_motion: inverse_axis * inverse_axis.sqrt(),
            mean_anomaly: 0.0,
            periapsis,
            normal,
        };
        // q = a (cos E − e) P + a β sin E Q.
        let cos_anomaly = q.dot(&periapsis) / axis + eccentricity;
        let sin_anomaly = q.dot(&normal) / (axis * beta);
        let anomaly = sin_anomaly.atan2(cos_anomaly);
        orbit.mean_anomaly = anomaly - eccentricity * anomaly.sin();
        Some(orbit)
    }

    /// The period 2π/n.
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU / self.mean_motion
    }

    /// 1 − e, without cancellation for e → 1.
    fn one_minus_eccentricity(&self) -> f64 {
        self.beta * self.beta / (1.0 + self.eccentricity)
    }

    /// M₀ + n·elapsed, reduced to about (−π, π].
    pub fn mean_anomaly_after(&self, elapsed: f64) -> f64 {
        let product = self.mean_motion * elapsed;
        // n·elapsed = product + product_error exactly.
        let product_error = self.mean_motion.mul_add(elapsed, -product);
        let turns = ((product + self.mean_anomaly) / std::f64::consts::TAU).round();
        (-turns).mul_add(TAU_HIGH, product) - turns * TAU_LOW + (product_error + self.mean_anomaly)
    }

    /// The eccentric anomaly E solving E − e sin E = `mean_anomaly`.
    pub fn eccentric_anomaly(&self, mean_anomaly: f64) -> f64 {
        solve_kepler_equation(
            self.eccentricity,
            self.one_minus_eccentricity(),
            mean_anomaly,
        )
    }

    /// The state (q, v) at `elapsed` time after the epoch.
    pub fn state_after(&self, elapsed: f64) -> (SVector<f64, 2>, SVector<f64, 2>) {
        let anomaly = self.eccentric_anomaly(self.mean_anomaly_after(elapsed));
        self.state_at_anomaly(anomaly)
    }

    /// The state (q, v) at eccentric anomaly E.
    pub fn state_at_anomaly(&self, anomaly: f64) -> (SVector<f64, 2>, SVector<f64, 2>) {
        let (a, e, beta) = (self.semi_major_axis, self.eccentricity, self.beta);
        let one_minus_e = self.one_minus_eccentricity();
        let (sin, cos) = anomaly.sin_cos();
        let versine = 2.0 * (0.5 * anomaly).sin().powi(2);
        let radius = a * (one_minus_e + e * versine);
        let q = self.periapsis * (a * (one_minus_e - versine)) + self.normal * (a * beta * sin);
        let v = (self.periapsis * (-sin) + self.normal * (beta * cos)) * (a.sqrt() / radius);
        (q, v)
    }
}

/// The eccentric anomaly E solving Kepler's equation E − e sin E = `mean_anomaly` for
/// 0 ≤ e < 1 (`one_minus_e` = 1 − e, passed without cancellation for e → 1): Newton's
/// method safeguarded by bisection on [M − e, M + e], to round-off.
fn solve_kepler_equation(e: f64, one_minus_e: f64, mean_anomaly: f64) -> f64 {
    if e == 0.0 {
        return mean_anomaly;
    }
    // E − M = e sin E, so E lies in [M − e, M + e].
    let (mut low, mut high) = (mean_anomaly - e, mean_anomaly + e);
    let mut anomaly = (mean_anomaly + e * mean_anomaly.sin()).clamp(low, high);
    for _ in 0..MAX_NEWTON_ITERATIONS {
        let residual = anomaly - e * anomaly.sin() - mean_anomaly;
        if residual == 0.0 {
            return anomaly;
        }
        if residual > 0.0 {
            high = anomaly;
        } else {
            low = anomaly;
        }
        // 1 − e cos E = (1 − e) + 2e sin²(E/2) > 0.
        let slope = one_minus_e + 2.0 * e * (0.5 * anomaly).sin().powi(2);
        let mut next = anomaly - residual / slope;
        if !(next > low && next < high) {
            next = 0.5 * (low + high);
        }
        let converged = (next - anomaly).abs() <= 2.0 * f64::EPSILON * next.abs().max(1.0);
        anomaly = next;
        if converged || low >= high {
            break;
        }
    }
    anomaly
}
