//! The derived quantities of `svi` (automatic differentiation through
//! [`svi::LagrangianExt`]) against hand-written analytic ones, for every zoo model.
//!
//! For random states (and random parameters) of each model of `svi-models`, property tests
//! compare ∂L/∂q, p = ∂L/∂q̇, the Hessian blocks L_qq, L_qv, L_vv, the energy
//! E = p·q̇ − L and the Euler–Lagrange acceleration with formulas derived by hand from the
//! papers' Lagrangians (for the spring pendulum, the acceleration comes from the Hamilton
//! equations of Leok 2004, §5.7.2; for the double pendulum, from solving M(q) q̈ = f with
//! the analytic mass matrix by Cramer's rule).
//!
//! Tolerances:
//! - AD derivatives vs analytic: relative 1e-12 (both are exact up to round-off), measured
//!   in the max norm relative to max(‖analytic‖, 1);
//! - acceleration Jacobian vs central finite differences of the *analytic* acceleration:
//!   relative 1e-6 (the finite-difference truncation and round-off error);
//! - inverse Legendre map: velocity(t, q, p(q, q̇), guess) = q̇ to relative 1e-12, from a
//!   guess away from q̇.
//!
//! States keep away from the coordinate singularities (|q| ≥ 0.2 for Kepler, l + a ≥ 0.25
//! for the spring pendulum).

use std::f64::consts::PI;

use nalgebra::{Const, SMatrix, SVector};
use proptest::prelude::*;
use svi::{Lagrangian, LagrangianExt};
use svi_models::{DoublePendulum, HarmonicOscillator, Kepler, Pendulum, SpringPendulum};

/// Relative tolerance of AD derivatives against analytic ones.
const DERIVATIVE_TOLERANCE: f64 = 1e-12;
/// Relative tolerance of the AD acceleration Jacobian against finite differences.
const JACOBIAN_TOLERANCE: f64 = 1e-6;
/// Cases per property (keeps the whole file at a few seconds).
const CASES: u32 = 128;

/// Hand-written derivatives of a model's Lagrangian (autonomous: t does not appear).
trait Analytic<const N: usize> {
    /// L.
    fn value(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> f64;
    /// ∂L/∂q.
    fn dl_dq(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N>;
    /// p = ∂L/∂q̇.
    fn momentum(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N>;
    /// ∂²L/∂q∂q.
    fn l_qq(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N>;
    /// ∂²L/∂qᵢ∂q̇ⱼ at (i, j).
    fn l_qv(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N>;
    /// ∂²L/∂q̇∂q̇.
    fn l_vv(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SMatrix<f64, N, N>;
    /// E = T + U.
    fn energy(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> f64;
    /// q̈ from the equations of motion.
    fn acceleration(&self, q: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N>;
}

/// Asserts ‖actual − expected‖_max ≤ tolerance · max(‖expected‖_max, floor).
fn assert_close<const R: usize, const C: usize>(
    what: &str,
    actual: &SMatrix<f64, R, C>,
    expected: &SMatrix<f64, R, C>,
    tolerance: f64,
    floor: f64,
) {
    let error = (actual - expected).amax();
    let scale = expected.amax().max(floor);
    assert!(
        error <= tolerance * scale,
        "{what}: AD {actual:?} vs analytic {expected:?} (error {error:e}, scale {scale:e})"
    );
}

/// Central finite differences of the analytic acceleration: (∂q̈/∂q, ∂q̈/∂q̇).
///
/// Steps: 10⁻⁵ (relative) in q; 10⁻³ in q̇, where q̈ of every zoo model is at most
/// quadratic, so that central differences are exact up to round-off, and a large step
/// keeps the round-off of a large q̈ (the stiff spring: k a/m ~ 10⁴) small.
fn finite_difference_jacobian<A: Analytic<N>, const N: usize>(
    model: &A,
    q: &SVector<f64, N>,
    v: &SVector<f64, N>,
) -> (SMatrix<f64, N, N>, SMatrix<f64, N, N>) {
    let mut dq = SMatrix::<f64, N, N>::zeros();
    let mut dv = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let h = 1e-5 * q[j].abs().max(1.0);
        let mut step = SVector::<f64, N>::zeros();
        step[j] = h;
        let column =
            (model.acceleration(&(q + step), v) - model.acceleration(&(q - step), v)) / (2.0 * h);
        dq.set_column(j, &column);
        let h = 1e-3 * v[j].abs().max(1.0);
        let mut step = SVector::<f64, N>::zeros();
        step[j] = h;
        let column =
            (model.acceleration(q, &(v + step)) - model.acceleration(q, &(v - step))) / (2.0 * h);
        dv.set_column(j, &column);
    }
    (dq, dv)
}

/// Compares every derived quantity of `model` at (t, q, q̇) with its analytic counterpart.
fn check_all<M, const N: usize>(model: &M, t: f64, q: SVector<f64, N>, v: SVector<f64, N>)
where
    M: Lagrangian<Const<N>> + Analytic<N>,
{
    let tol = DERIVATIVE_TOLERANCE;
    let scalar = |x: f64| SMatrix::<f64, 1, 1>::from_element(x);

    let value = LagrangianExt::value(model, t, &q, &v);
    assert_close(
        "L",
        &scalar(value),
        &scalar(Analytic::value(model, &q, &v)),
        tol,
        1.0,
    );

    let first = model.first_derivatives(t, &q, &v);
    assert_close("L (first)", &scalar(first.value), &scalar(value), tol, 1.0);
    assert_close("∂L/∂q", &first.q, &model.dl_dq(&q, &v), tol, 1.0);
    let momentum = Analytic::momentum(model, &q, &v);
    assert_close("∂L/∂q̇", &first.v, &momentum, tol, 1.0);
    assert_close(
        "momentum",
        &LagrangianExt::momentum(model, t, &q, &v),
        &momentum,
        tol,
        1.0,
    );

    let second = model.second_derivatives(t, &q, &v);
    assert_close(
        "L (second)",
        &scalar(second.value),
        &scalar(value),
        tol,
        1.0,
    );
    assert_close("∂L/∂q (second)", &second.q, &first.q, tol, 1.0);
    assert_close("∂L/∂q̇ (second)", &second.v, &first.v, tol, 1.0);
    assert_close("L_qq", &second.qq, &model.l_qq(&q, &v), tol, 1.0);
    assert_close("L_qv", &second.qv, &model.l_qv(&q, &v), tol, 1.0);
    assert_close("L_vv", &second.vv, &model.l_vv(&q, &v), tol, 1.0);

    let energy = Analytic::energy(model, &q, &v);
    assert_close(
        "energy",
        &scalar(LagrangianExt::energy(model, t, &q, &v)),
        &scalar(energy),
        tol,
        1.0,
    );
    // E = p·q̇ − L with the analytic p and L: checks the hand-written energy too.
    assert_close(
        "energy (Legendre)",
        &scalar(momentum.dot(&v) - Analytic::value(model, &q, &v)),
        &scalar(energy),
        tol,
        1.0,
    );

    let acceleration = Analytic::acceleration(model, &q, &v);
    let derived = LagrangianExt::acceleration(model, t, &q, &v).expect("regular mass matrix");
    assert_close("acceleration", &derived, &acceleration, tol, 1.0);

    let jacobian = model
        .acceleration_jacobian(t, &q, &v)
        .expect("regular mass matrix");
    assert_close(
        "acceleration (Jacobian)",
        &jacobian.value,
        &acceleration,
        tol,
        1.0,
    );
    let (dq, dv) = finite_difference_jacobian(model, &q, &v);
    assert_close("∂q̈/∂q", &jacobian.q, &dq, JACOBIAN_TOLERANCE, 1.0);
    assert_close("∂q̈/∂q̇", &jacobian.v, &dv, JACOBIAN_TOLERANCE, 1.0);

    // Inverse Legendre map from a guess away from q̇.
    let guess = v * 0.5 + SVector::from_element(0.3);
    let velocity = model
        .velocity(t, &q, &momentum, &guess)
        .expect("inverse Legendre map converges");
    assert_close("inverse Legendre map", &velocity, &v, tol, 1.0);
}

// ----- harmonic oscillator: L = q̇²/2 − σ²q²/2 -----

impl Analytic<1> for HarmonicOscillator {
    fn value(&self, q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> f64 {
        0.5 * v[0] * v[0] - 0.5 * self.sigma.powi(2) * q[0] * q[0]
    }
    fn dl_dq(&self, q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::from([-self.sigma.powi(2) * q[0]])
    }
    fn momentum(&self, _q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> SVector<f64, 1> {
        *v
    }
    fn l_qq(&self, _q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::from_element(-self.sigma.powi(2))
    }
    fn l_qv(&self, _q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::zeros()
    }
    fn l_vv(&self, _q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::identity()
    }
    fn energy(&self, q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> f64 {
        0.5 * v[0] * v[0] + 0.5 * self.sigma.powi(2) * q[0] * q[0]
    }
    fn acceleration(&self, q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::from([-self.sigma.powi(2) * q[0]])
    }
}

// ----- pendulum: L = ½ m l² θ̇² + m g l cos θ -----

impl Analytic<1> for Pendulum {
    fn value(&self, q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> f64 {
        0.5 * self.m * self.l.powi(2) * v[0].powi(2) + self.m * self.g * self.l * q[0].cos()
    }
    fn dl_dq(&self, q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::from([-self.m * self.g * self.l * q[0].sin()])
    }
    fn momentum(&self, _q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::from([self.m * self.l.powi(2) * v[0]])
    }
    fn l_qq(&self, q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::from_element(-self.m * self.g * self.l * q[0].cos())
    }
    fn l_qv(&self, _q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::zeros()
    }
    fn l_vv(&self, _q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::from_element(self.m * self.l.powi(2))
    }
    fn energy(&self, q: &SVector<f64, 1>, v: &SVector<f64, 1>) -> f64 {
        0.5 * self.m * self.l.powi(2) * v[0].powi(2) - self.m * self.g * self.l * q[0].cos()
    }
    fn acceleration(&self, q: &SVector<f64, 1>, _v: &SVector<f64, 1>) -> SVector<f64, 1> {
        // θ̈ = −(g/l) sin θ.
        SVector::from([-self.g / self.l * q[0].sin()])
    }
}

// ----- spring pendulum (Leok 2004, §5.7.2), q = (a, θ) -----
// L = (m/2)(ȧ² + (l + a)² θ̇²) + m g (l + a) cos θ − (k/2) a².

impl Analytic<2> for SpringPendulum {
    fn value(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        let Self { m, g, k, l } = *self;
        let (a, theta, a_dot, theta_dot) = (q[0], q[1], v[0], v[1]);
        0.5 * m * (a_dot.powi(2) + (l + a).powi(2) * theta_dot.powi(2))
            + m * g * (l + a) * theta.cos()
            - 0.5 * k * a * a
    }
    fn dl_dq(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        let Self { m, g, k, l } = *self;
        let (a, theta, theta_dot) = (q[0], q[1], v[1]);
        SVector::from([
            m * (l + a) * theta_dot.powi(2) + m * g * theta.cos() - k * a,
            -m * g * (l + a) * theta.sin(),
        ])
    }
    fn momentum(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        let (m, l) = (self.m, self.l);
        SVector::from([m * v[0], m * (l + q[0]).powi(2) * v[1]])
    }
    fn l_qq(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        let Self { m, g, k, l } = *self;
        let (a, theta, theta_dot) = (q[0], q[1], v[1]);
        let off = -m * g * theta.sin();
        SMatrix::from([
            [m * theta_dot.powi(2) - k, off],
            [off, -m * g * (l + a) * theta.cos()],
        ])
    }
    fn l_qv(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        // Only ∂²L/∂a∂θ̇ = 2 m (l + a) θ̇ is non-zero (row a, column θ̇).
        let mut qv = SMatrix::zeros();
        qv[(0, 1)] = 2.0 * self.m * (self.l + q[0]) * v[1];
        qv
    }
    fn l_vv(&self, q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        SMatrix::from_diagonal(&SVector::from([self.m, self.m * (self.l + q[0]).powi(2)]))
    }
    fn energy(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        let Self { m, g, k, l } = *self;
        let (a, theta, a_dot, theta_dot) = (q[0], q[1], v[0], v[1]);
        0.5 * m * (a_dot.powi(2) + (l + a).powi(2) * theta_dot.powi(2))
            - m * g * (l + a) * theta.cos()
            + 0.5 * k * a * a
    }
    fn acceleration(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        // Hamilton's equations of §5.7.2:
        //   ȧ = p_a/m, θ̇ = p_θ/(m (l + a)²),
        //   ṗ_a = −k a + g m cos θ + m (l + a) θ̇², ṗ_θ = −g m (l + a) sin θ;
        // so ä = ṗ_a/m and θ̈ = d/dt [p_θ/(m (l + a)²)] = ṗ_θ/(m (l + a)²) − 2 p_θ ȧ/(m (l + a)³).
        let Self { m, g, k, l } = *self;
        let (a, theta, a_dot, theta_dot) = (q[0], q[1], v[0], v[1]);
        let length = l + a;
        let p_theta = m * length.powi(2) * theta_dot;
        let p_a_dot = -k * a + g * m * theta.cos() + m * length * theta_dot.powi(2);
        let p_theta_dot = -g * m * length * theta.sin();
        SVector::from([
            p_a_dot / m,
            p_theta_dot / (m * length.powi(2)) - 2.0 * p_theta * a_dot / (m * length.powi(3)),
        ])
    }
}

// ----- Kepler (Li, Wu, Leok 2018, §5.2): L = |v|²/2 + 1/|q| -----

impl Analytic<2> for Kepler {
    fn value(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        0.5 * v.dot(v) + 1.0 / q.norm()
    }
    fn dl_dq(&self, q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SVector<f64, 2> {
        -q / q.norm().powi(3)
    }
    fn momentum(&self, _q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        *v
    }
    fn l_qq(&self, q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        // ∂²(1/r)/∂qᵢ∂qⱼ = (3 qᵢ qⱼ − r² δᵢⱼ)/r⁵.
        let r = q.norm();
        (q * q.transpose() * 3.0 - SMatrix::identity() * r * r) / r.powi(5)
    }
    fn l_qv(&self, _q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        SMatrix::zeros()
    }
    fn l_vv(&self, _q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        SMatrix::identity()
    }
    fn energy(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        0.5 * v.dot(v) - 1.0 / q.norm()
    }
    fn acceleration(&self, q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SVector<f64, 2> {
        // Eq. (38): v̇ = −q/|q|³.
        -q / q.norm().powi(3)
    }
}

// ----- double pendulum (Porcù, Penati 2013), q = (α₁, α₂) -----
// L = ((m₁+m₂)/2) d₁² α̇₁² + (m₂/2) d₂² α̇₂² + m₂ d₁ d₂ α̇₁ α̇₂ cos(α₁ − α₂)
//     + (m₁+m₂) g d₁ cos α₁ + m₂ g d₂ cos α₂.

/// Shorthands of the double pendulum and its energies.
trait DoublePendulumTerms {
    /// (m₁ + m₂, m₂ d₁ d₂, cos(α₁ − α₂), sin(α₁ − α₂)).
    fn shorthands(&self, q: &SVector<f64, 2>) -> (f64, f64, f64, f64);
    /// The kinetic and potential energies T, U.
    fn kinetic_potential(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> (f64, f64);
}

impl DoublePendulumTerms for DoublePendulum {
    fn shorthands(&self, q: &SVector<f64, 2>) -> (f64, f64, f64, f64) {
        let (sin, cos) = (q[0] - q[1]).sin_cos();
        (self.m1 + self.m2, self.m2 * self.d1 * self.d2, cos, sin)
    }

    fn kinetic_potential(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> (f64, f64) {
        let (total, coupling, cos, _) = self.shorthands(q);
        let Self { m2, d1, d2, g, .. } = *self;
        let kinetic = 0.5 * total * d1 * d1 * v[0].powi(2)
            + 0.5 * m2 * d2 * d2 * v[1].powi(2)
            + coupling * v[0] * v[1] * cos;
        let potential = -total * g * d1 * q[0].cos() - m2 * g * d2 * q[1].cos();
        (kinetic, potential)
    }
}

impl Analytic<2> for DoublePendulum {
    fn value(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        let (kinetic, potential) = self.kinetic_potential(q, v);
        kinetic - potential
    }
    fn dl_dq(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        let (total, coupling, _, sin) = self.shorthands(q);
        let Self { m2, d1, d2, g, .. } = *self;
        SVector::from([
            -coupling * v[0] * v[1] * sin - total * g * d1 * q[0].sin(),
            coupling * v[0] * v[1] * sin - m2 * g * d2 * q[1].sin(),
        ])
    }
    fn momentum(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        self.l_vv(q, v) * v
    }
    fn l_qq(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        let (total, coupling, cos, _) = self.shorthands(q);
        let Self { m2, d1, d2, g, .. } = *self;
        let mixed = coupling * v[0] * v[1] * cos;
        SMatrix::from([
            [-mixed - total * g * d1 * q[0].cos(), mixed],
            [mixed, -mixed - m2 * g * d2 * q[1].cos()],
        ])
    }
    fn l_qv(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        // Row i = ∂/∂αᵢ, column j = ∂/∂α̇ⱼ of L.
        let (_, coupling, _, sin) = self.shorthands(q);
        let (w1, w2) = (v[0], v[1]);
        // nalgebra's From<[[T; R]; C]> takes columns.
        SMatrix::from([
            [-coupling * w2 * sin, coupling * w2 * sin],
            [-coupling * w1 * sin, coupling * w1 * sin],
        ])
    }
    fn l_vv(&self, q: &SVector<f64, 2>, _v: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
        let (total, coupling, cos, _) = self.shorthands(q);
        let Self { m2, d1, d2, .. } = *self;
        SMatrix::from([
            [total * d1 * d1, coupling * cos],
            [coupling * cos, m2 * d2 * d2],
        ])
    }
    fn energy(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> f64 {
        let (kinetic, potential) = self.kinetic_potential(q, v);
        kinetic + potential
    }
    fn acceleration(&self, q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        // M(α) α̈ = f with
        //   f₁ = −m₂ d₁ d₂ α̇₂² sin(α₁ − α₂) − (m₁+m₂) g d₁ sin α₁,
        //   f₂ =  m₂ d₁ d₂ α̇₁² sin(α₁ − α₂) − m₂ g d₂ sin α₂,
        // solved by Cramer's rule.
        let (total, coupling, cos, sin) = self.shorthands(q);
        let Self { m2, d1, d2, g, .. } = *self;
        let f1 = -coupling * v[1].powi(2) * sin - total * g * d1 * q[0].sin();
        let f2 = coupling * v[0].powi(2) * sin - m2 * g * d2 * q[1].sin();
        let (m11, m12, m22) = (total * d1 * d1, coupling * cos, m2 * d2 * d2);
        let det = m11 * m22 - m12 * m12;
        SVector::from([(m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det])
    }
}

// ----- properties -----

/// A vector with entries in `range`.
fn vector<const N: usize>(range: std::ops::Range<f64>) -> impl Strategy<Value = SVector<f64, N>> {
    proptest::array::uniform::<_, N>(range).prop_map(SVector::from)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn oscillator_derivatives_match_analytic(
        sigma in 0.1..5.0f64,
        t in -10.0..10.0f64,
        q in vector::<1>(-3.0..3.0),
        v in vector::<1>(-3.0..3.0),
    ) {
        check_all(&HarmonicOscillator { sigma }, t, q, v);
    }

    #[test]
    fn pendulum_derivatives_match_analytic(
        m in 0.5..2.0f64,
        l in 0.5..2.0f64,
        g in 0.0..10.0f64,
        q in vector::<1>(-7.0..7.0),
        v in vector::<1>(-5.0..5.0),
    ) {
        check_all(&Pendulum { m, l, g }, 0.0, q, v);
    }

    #[test]
    fn spring_pendulum_derivatives_match_hamilton_equations(
        m in 0.5..2.0f64,
        g in 0.0..10.0f64,
        k in 10.0..10_000.0f64,
        l in 0.5..2.0f64,
        a in -0.25..0.5f64,
        theta in -PI..PI,
        v in vector::<2>(-3.0..3.0),
    ) {
        check_all(&SpringPendulum { m, g, k, l }, 0.0, SVector::from([a, theta]), v);
    }

    #[test]
    fn kepler_derivatives_match_analytic(
        radius in 0.2..3.0f64,
        angle in -PI..PI,
        v in vector::<2>(-3.0..3.0),
    ) {
        let model = Kepler::default();
        let q = SVector::from([radius * angle.cos(), radius * angle.sin()]);
        check_all(&model, 0.0, q, v);
        // Noether momentum of the rotation generator = angular momentum q₁v₂ − q₂v₁.
        let angular_momentum = q[0] * v[1] - q[1] * v[0];
        let noether = model.noether_momentum(0, 0.0, &q, &v);
        prop_assert!(
            (noether - angular_momentum).abs()
                <= DERIVATIVE_TOLERANCE * angular_momentum.abs().max(1.0),
            "Noether momentum {noether} vs q₁v₂ − q₂v₁ = {angular_momentum}"
        );
    }

    #[test]
    fn double_pendulum_derivatives_match_analytic(
        m1 in 0.5..2.0f64,
        m2 in 0.5..2.0f64,
        d1 in 0.5..2.0f64,
        d2 in 0.5..2.0f64,
        g in 0.0..10.0f64,
        q in vector::<2>(-PI..PI),
        v in vector::<2>(-3.0..3.0),
    ) {
        check_all(&DoublePendulum { m1, m2, d1, d2, g }, 0.0, q, v);
    }
}

/// The analytic formulas themselves at the models' default states: one fixed,
/// human-checkable case per model (a regression guard for the test's own formulas).
#[test]
fn analytic_formulas_at_simple_states() {
    // Spring pendulum hanging at rest at its static extension: no acceleration.
    let spring = SpringPendulum::default();
    let rest = SVector::from([spring.static_extension(), 0.0]);
    assert!(Analytic::acceleration(&spring, &rest, &SVector::zeros()).amax() < 1e-12);
    // Kepler on the circular orbit of radius 1: centripetal acceleration 1.
    let kepler = Kepler::default();
    let q = SVector::from([1.0, 0.0]);
    assert_eq!(
        Analytic::acceleration(&kepler, &q, &SVector::from([0.0, 1.0])),
        SVector::from([-1.0, 0.0])
    );
    // Double pendulum at rest with the upper rod vertical and the lower one at α₂: the
    // lower rod pulls the upper one, α̈₁ = m₂ g sin α₂ cos α₂ / (d₁ (m₁ + m₂ sin² α₂)).
    let double = DoublePendulum::default();
    let q = SVector::from([0.0, 0.3]);
    let acceleration = Analytic::acceleration(&double, &q, &SVector::zeros());
    let (m1, m2, d1, g) = (double.m1, double.m2, double.d1, double.g);
    let expected = m2 * g * 0.3f64.sin() * 0.3f64.cos() / (d1 * (m1 + m2 * 0.3f64.sin().powi(2)));
    assert!(
        (acceleration[0] - expected).abs() < 1e-14,
        "{acceleration:?} vs {expected}"
    );
}
