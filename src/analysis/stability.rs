//! Linear stability of one-step methods on the harmonic oscillator (Li, Wu, Leok 2018, §4).
//!
//! # The stability matrix
//! On the oscillator L = q̇²/2 − σ²q²/2 (eq. 26) every method here is a linear map, and in the
//! scaled coordinates (q, h·p) — (q, h·q̇) for collocation; p = q̇ for this L — it depends on
//! h and σ only through z = σ²h²: (q_{k+1}, h p_{k+1}) = S(z) (q_k, h p_k) (eqs. 33, 36).
//!
//! [`stability_matrix`] computes S(z) for any [`Method<U1>`] from its tangent map Φ (the exact
//! Jacobian of one step, [`Method::tangent_map`]) with σ = 1, h = √z, as
//! S = diag(1, h) Φ diag(1, 1/h). The map is linear, so Φ does not depend on the state; it is
//! taken at the equilibrium, where the nonlinear solve of the step is trivially exact.
//!
//! [`svi_closed_form`] and [`collocation_closed_form`] build S₁(z) (eq. 34) and S₂(z)
//! (eq. 37) directly from the basis and quadrature tables, independently of the methods'
//! nonlinear solvers and automatic differentiation. The formulas printed in the paper carry
//! typos, so they are derived again here (σ = 1, z = h²).
//!
//! ## S₁: spectral variational integrator
//! Let l_ν be the Lagrange basis on the s + 1 ascending CGL points x_ν = −cos(νπ/s), (w_μ, τ_μ)
//! the m-point Gauss–Legendre rule, B_{μν} = l_ν(τ_μ), C_{μν} = l̇_ν(τ_μ), W = diag(w_μ), and
//!
//! A = CᵀWC,   F = BᵀWB,   K(z) = 4A − zF   ((s + 1) × (s + 1), symmetric).
//!
//! (The paper's 𝒜 and ℱ are the first s rows of A and F.) With ∂L/∂q = −q and
//! ∂L/∂q̇ = q̇ = (2/h) Σ_j C_{μj} qʲ, the bracket of (8a)–(8c) is
//! g_ν = (2/h)(AQ)_ν − (h/2)(FQ)_ν = (K Q)_ν / (2h), Q = (q⁰, …, qˢ)ᵀ. Hence
//!
//! - (8a), (8b): rows 0..s−1 of K Q equal (−2h p_k, 0, …, 0)ᵀ. Writing those rows of K as
//!   [k₀ | K*] (first column | columns 1..s, so K* = 4𝒜* − zℱ*, k₀ = 4𝒜⁰ − zℱ⁰):
//!   K* Q* = −k₀ q_k − 2 e₁ (h p_k), the corrected eq. (28);
//! - (8c): h p_{k+1} = ½ (K Q)_s = ½ (K_{s0} q_k + K_{s*} Q*), i.e. 𝓑 = ½ K(s, :) in eq. (31).
//!
//! With X = K*⁻¹ [−k₀, −2e₁] (s × 2) and q_{k+1} = qˢ,
//!
//! S₁(z) = [[X_{s,1}, X_{s,2}], [½ (K_{s0} + K_{s*} X_{:,1}), ½ K_{s*} X_{:,2}]].
//!
//! In the paper's symbols the (2,2) entry is −2 𝓑* (4𝒜* − zℱ*)⁻¹(:, 1): (32) and (34) print
//! (s, 1), a single entry, where the whole first column is needed (𝓑* is a row of length s).
//! Also, (33) labels the second coordinate h q̇; it is h p (the same number here).
//!
//! For example, 2 CGL points (degree 1) with 2 Gauss points give
//! A = ½ [[1, −1], [−1, 1]], F = ⅓ [[2, 1], [1, 2]], and
//!
//! S₁(z) = 1/(6 + z) · [[6 − 2z, 6], [−z(12 − z)/2, 6 − 2z]],   det S₁ = 1,
//! tr S₁ = 2 − 6z/(6 + z),
//!
//! so |tr S₁| ≤ 2 exactly for 0 < z ≤ 12: the bound hσ < 2√3 of Porcù and Penati's slides.
//!
//! ## S₂: spectral collocation
//! Let D = D̃⁽¹⁾ be the differentiation matrix at the ascending CGL points, built from the
//! barycentric formulas ([`LagrangeBasis::differentiation_matrix`]). Its corners are
//! D₀₀ = −(2s² + 1)/6 and D_ss = +(2s² + 1)/6; eq. (17) prints the opposite signs because it is
//! quoted for nodes ordered from 1 to −1. With D* = D(1:s, 1:s) and d₀ = D(1:s, 0),
//! Λ* = (2/h) D*, λ₀ = (2/h) d₀ (eq. 21), and f(q) = −q, eqs. (22)–(23) become, after
//! multiplication by h²/4 and with v = q̇,
//!
//! (4D*² + zI) Q* = −4 D* d₀ q_k − 2 d₀ (h v_k),   h v_{k+1} = 2 (D*(s, :) Q* + D_{s0} q_k).
//!
//! With Y = (4D*² + zI)⁻¹ [−4D*d₀, −2d₀] (s × 2),
//!
//! S₂(z) = [[Y_{s,1}, Y_{s,2}], [2 D_{s0} + 2 D*(s, :) Y_{:,1}, 2 D*(s, :) Y_{:,2}]].
//!
//! The (2,1) entry of (37) prints −8 D̃(s, :) …, a full row of D̃ (s + 1 entries); it must be
//! −8 D*(s, :) (4D*² + zI)⁻¹ D* d₀ + 2 D_{s0}, with the last row of D* = D̃(s, 1:s). With two
//! CGL points SC is the implicit Euler method for (q̇, v̇) = (v, −q): S₂ = 1/(1 + z) [[1, 1],
//! [−z, 1]], det S₂ = 1/(1 + z).
//!
//! # Regions (Definition 4.1)
//! S is a real 2 × 2 matrix with characteristic polynomial λ² − Tλ + Δ, T = tr S, Δ = det S.
//! By the Schur–Cohn (Jury) conditions its eigenvalues lie in the closed unit disc exactly when
//! Δ ≤ 1 and |T| ≤ Δ + 1, and in the open disc exactly when Δ < 1 and |T| < Δ + 1. So
//!
//! - R_s = {z > 0 : ρ(S) ≤ 1} = {Δ ≤ 1, |T| − Δ − 1 ≤ 0} (stability region);
//! - R_p = {z > 0 : ρ(S) = 1, T² < 4Δ} (periodicity region: a complex pair on the unit
//!   circle). In R_s with Δ = 1 the eigenvalues are either such a pair or a double eigenvalue
//!   ±1 (T² = 4Δ), so R_p = R_s ∩ {Δ = 1} minus the points where |T| = 2;
//! - R_q = {z > 0 : Δ < 1, |T| < Δ + 1} = {ρ(S) < 1} (strong stability region);
//!
//! and R_p, R_q ⊂ R_s. These conditions are used instead of ρ itself: T and Δ are rational
//! functions of z computed to round-off, while ρ has a square-root branch point exactly where
//! a symplectic method leaves R_s (two eigenvalues collide at ±1), so ρ − 1 is both
//! non-smooth there and only accurate to O(√ε). For a symplectic method ρ = 1 on whole
//! intervals, and the stability boundary is where |T| = 2.
//!
//! **Round-off.** Every condition is decided with the tolerance δ = [`ROUND_OFF`] = 1e−12:
//! Δ = 1 means |Δ − 1| ≤ δ, "≤ 0" means ≤ δ and "< 0" means < −δ. For an eigenvalue on the
//! unit circle this treats |ρ − 1| ≲ 1e−12 as ρ = 1: a symplectic method (Δ = 1 to round-off)
//! is never strongly stable, and a method whose excess Δ − 1 is below δ counts as periodic
//! there (spectral collocation with 5 CGL points for z < 0.0021, see below).
//!
//! **Boundaries.** [`analyse`] samples [z_min, z_max] uniformly and computes where each
//! condition holds, as intervals, and intersects them. A condition changes its verdict
//! (i) between two neighbouring samples, or (ii) inside a narrow band around a sample where
//! its indicator (Δ − 1 ∓ δ, 1 − Δ − δ, |T| − Δ − 1 ∓ δ) has an extremum towards zero, as a
//! symplectic method's |T| − 2 does near the resonances z ≈ (kπ)², where it can poke above
//! zero over a band far narrower than any sampling (Cheb 9 / Gau 18 is unstable on
//! (39.478419, 39.478473)). In case (ii) the extremum is found by Brent's minimisation
//! (argmin's [`BrentOpt`]) and, if it crosses zero, the band is located. Every change is the
//! root of the smooth measure (Δ − 1, |T| − Δ − 1) when that changes sign beyond ±δ, otherwise
//! of the indicator (the edge of the round-off band), by Brent's method (argmin's
//! [`BrentRoot`]) to within 1e−11 + 4ε z. Not reported: bands that leave no such trace in the
//! samples (a peak next to an end of the range, or much sharper than quadratic at the sampling
//! scale), and isolated points — for instance z = 16, the one point where spectral collocation
//! with 5 CGL points is periodic, or the resonances S = ±I of the Gauss–Legendre-type SVIs
//! (tr² = 4 det there, so by the letter of Definition 4.1 they are not in R_p, although every
//! solution is periodic); the region lists hold closed intervals of positive length.
//!
//! # What the analysis finds
//! - SVI is symplectic: det S₁ = 1 to round-off for every configuration.
//! - 2 CGL points with 2 Gauss points: R_s = R_p = (0, 12], from tr S₁ = 2 − 6z/(6 + z).
//! - m = s Gauss points (Cheb 5 / Gau 4, Cheb 9 / Gau 8) give the Gauss–Legendre collocation
//!   method, which conserves q² + p²: ρ = 1 for all z, A-stable and P-stable (up to its
//!   resonances S = ±I, e.g. z = 90 ∓ √6420 and 42 for Cheb 5 / Gau 4).
//! - With m ≥ s + 1 Gauss points the quadrature is exact on the oscillator, and the SVI is
//!   unstable on bands, the first ones narrow and next to the resonances z ≈ (kπ)² of the
//!   exact flow: Cheb 5 / Gau 10 first on (9.8697496, 9.8750975), Cheb 9 / Gau 18 first on
//!   (39.478419, 39.478473) (too narrow to show in Figs. 3–6). The bands of Cheb 5 / Gau 10
//!   end exactly at the resonances 90 − √6420, 42 and 90 + √6420 of Cheb 5 / Gau 4.
//! - Spectral collocation is the s-stage collocation Runge–Kutta method with nodes
//!   (1 + x_ν)/2, ν = 1..s, so det S₂ = |R(i√z)|² for its stability function R. For 3 CGL points
//!   det S₂ − 1 = −z²/(16 |D(i√z)|²) < 0 (D the denominator of R): strongly stable for all z.
//!   For 5 CGL points det S₂ − 1 = z³(16 − z)/(147456 |D(i√z)|²): det S₂ > 1, so ρ > 1, on
//!   (0, 16) — growth of about z³/18432 per step for small z — and strongly stable beyond 16.
//!   With 9 CGL points det S₂ > 1 on (0, 29.933938). So det S₂ does not simply decrease from
//!   1 (Fig. 5): it first rises, by up to 3 % (5 points, z ≈ 12), before falling towards 0.
//!
//! # Example
//! ```
//! use svi::Svi;
//! use svi::stability::analyse;
//!
//! // Degree 1 with 2 Gauss points is stable exactly for z ≤ 12.
//! let report = analyse(&Svi::new(2).with_quadrature(2), 0.01, 20.0, 40).unwrap();
//! assert_eq!(report.stable.len(), 1);
//! assert!((report.stable[0].upper - 12.0).abs() < 1e-9);
//! assert!(!report.a_stable && report.strongly_stable.is_empty());
//! ```
//!
//! # References
//! Li, Wu, Leok, *Construction and comparison of multidimensional spectral variational
//! integrators and spectral collocation methods* (2018), §4, eqs. (26)–(37), Definition 4.1,
//! Figs. 3–6; Porcù, Penati, *Spectral variational integrators* (2013), the bound for degree 1
//! with 2 Gauss points; Lambert, Watson, *Symmetric multistep methods for periodic initial value
//! problems* (1976), periodicity and P-stability.

use crate::error::Error;
use crate::error::require_positive;
use crate::method::Method;
use crate::method::State;
use crate::model::Lagrangian;
use crate::scalar::Scalar;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::quadrature::GaussLegendre;
use crate::spectral::{check_points, check_quadrature};
use argmin::core::{
    CostFunction, Executor, IterState, Solver, State as _, TerminationReason, TerminationStatus,
};
use argmin::solver::brent::{BrentOpt, BrentRoot};
use nalgebra::{DMatrix, DVector, Matrix2, SVector, U1};

/// Round-off tolerance δ of the region conditions: |det S − 1| ≤ δ counts as det S = 1, and the
/// Jury margins and the discriminant are compared with ±δ (see the module docs).
pub const ROUND_OFF: f64 = 1e-12;

/// Absolute tolerance handed to Brent's method; a located boundary is within
/// `BRENT_TOLERANCE + 4ε z` of the crossing of its indicator.
const BRENT_TOLERANCE: f64 = 1e-11;

/// Absolute tolerance of Brent's minimisation when refining an extremum of an indicator (its
/// relative tolerance is √ε).
const EXTREMUM_TOLERANCE: f64 = 1e-10;

/// Iteration cap of Brent's methods (it needs about 50 on the widest bracket of interest; the cap
/// only guards against a logic error).
const BRENT_ITERATIONS: u64 = 1000;

/// The oscillator L = q̇²/2 − q²/2 (σ = 1) on which stability is measured.
///
/// It declares no [`crate::Structure`], so the methods take their Newton path: fixed-point
/// iterations would not converge for the stiff steps (h = √z up to 30) of a stability map.
struct Oscillator;

impl Lagrangian<U1> for Oscillator {
    const TIME_DEPENDENT: bool = false;

    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0]) * 0.5
    }
}

/// The stability matrix S(z) of `method`, from its tangent map on the oscillator with σ = 1 and
/// h = √z, in the coordinates (q, h·p) (or (q, h·q̇) for [`crate::Coordinates::Velocity`]
/// methods; p = q̇ here): S = diag(1, h) Φ diag(1, 1/h).
///
/// # Errors
///
/// [`Error::InvalidParameter`] named `"z"` if z is not finite and positive; the method's own
/// validation errors; a failure of the step's nonlinear solve ([`Error::NonConvergence`],
/// [`Error::SingularMatrix`], reported at step 0, t = 0); [`Error::NonFinite`] if the tangent
/// map is not finite.
pub fn stability_matrix<M: Method<U1>>(method: &M, z: f64) -> Result<Matrix2<f64>, Error> {
    require_positive("z", z)?;
    let h = z.sqrt();
    let mut workspace = method.workspace(&Oscillator, h)?;
    let (_, tangent, _) = method
        .tangent_map(&Oscillator, &mut workspace, 0.0, h, &State::zeros(U1))
        .map_err(|failure| failure.at(0, 0.0))?;
    let matrix = Matrix2::new(
        tangent.qq[(0, 0)],
        tangent.qy[(0, 0)] / h,
        h * tangent.yq[(0, 0)],
        tangent.yy[(0, 0)],
    );
    if matrix.iter().all(|x| x.is_finite()) {
        Ok(matrix)
    } else {
        Err(Error::NonFinite {
            what: format!("stability matrix at z = {z:?}"),
            step: 0,
            t: 0.0,
        })
    }
}

/// The closed form S₁(z) (eq. 34, corrected) of the spectral variational integrator with
/// `points` CGL points and `quadrature` Gauss–Legendre points, built from the basis and
/// quadrature tables (see the module docs for the derivation).
///
/// # Errors
///
/// [`Error::InvalidParameter`] named `"z"` if z is not finite and positive or the stage matrix
/// 4𝒜* − zℱ* is singular at z, `"points"` and `"quadrature"` as the method itself checks
/// them ([`check_points`], [`check_quadrature`]).
pub fn svi_closed_form(points: usize, quadrature: usize, z: f64) -> Result<Matrix2<f64>, Error> {
    require_positive("z", z)?;
    check_points(points)?;
    check_quadrature(points, quadrature)?;
    let s = points - 1;
    let basis = LagrangeBasis::chebyshev_gauss_lobatto(points)?;
    let gauss = GaussLegendre::new(quadrature)?;
    let values = basis.value_matrix(gauss.nodes());
    let derivatives = basis.derivative_matrix(gauss.nodes());
    let weights = DMatrix::from_diagonal(&DVector::from_column_slice(gauss.weights()));
    let a = derivatives.transpose() * &weights * &derivatives;
    let f = values.transpose() * &weights * &values;
    let k = a * 4.0 - f * z;
    // Right-hand sides of K* Q* = −k₀ q_k − 2 e₁ (h p_k), one column per coordinate.
    let mut rhs = DMatrix::zeros(s, 2);
    rhs.column_mut(0).copy_from(&(-k.view((0, 0), (s, 1))));
    rhs[(0, 1)] = -2.0;
    let x = solve(k.view((0, 1), (s, s)).into_owned(), rhs).ok_or_else(|| {
        Error::invalid(
            "z",
            format!(
                "the stage matrix 4A* − zF* of {points} CGL points and {quadrature} Gauss points is singular at z = {z:?}"
            ),
        )
    })?;
    let last = k.view((s, 1), (1, s));
    let momentum = last * &x;
    Ok(Matrix2::new(
        x[(s - 1, 0)],
        x[(s - 1, 1)],
        0.5 * (k[(s, 0)] + momentum[(0, 0)]),
        0.5 * momentum[(0, 1)],
    ))
}

/// The closed form S₂(z) (eq. 37, corrected) of spectral collocation with `points` CGL points,
/// built from the barycentric differentiation matrix (see the module docs for the derivation).
///
/// # Errors
///
/// [`Error::InvalidParameter`] named `"z"` if z is not finite and positive or 4D*² + zI is
/// singular at z, `"points"` as the method itself checks them ([`check_points`]).
pub fn collocation_closed_form(points: usize, z: f64) -> Result<Matrix2<f64>, Error> {
    require_positive("z", z)?;
    check_points(points)?;
    let s = points - 1;
    let d = LagrangeBasis::chebyshev_gauss_lobatto(points)?.differentiation_matrix();
    let d_star = d.view((1, 1), (s, s));
    let d0 = d.view((1, 0), (s, 1));
    let mut rhs = DMatrix::zeros(s, 2);
    rhs.column_mut(0).copy_from(&(d_star * d0 * -4.0));
    rhs.column_mut(1).copy_from(&(d0 * -2.0));
    let stage = d_star * d_star * 4.0 + DMatrix::identity(s, s) * z;
    let y = solve(stage, rhs).ok_or_else(|| {
        Error::invalid(
            "z",
            format!("the stage matrix 4D*² + zI of {points} CGL points is singular at z = {z:?}"),
        )
    })?;
    let velocity = d.view((s, 1), (1, s)) * &y * 2.0;
    Ok(Matrix2::new(
        y[(s - 1, 0)],
        y[(s - 1, 1)],
        2.0 * d[(s, 0)] + velocity[(0, 0)],
        velocity[(0, 1)],
    ))
}

/// Solve `matrix · x = rhs`; `None` if the matrix is singular or the solution not finite.
fn solve(matrix: DMatrix<f64>, rhs: DMatrix<f64>) -> Option<DMatrix<f64>> {
    matrix
        .lu()
        .solve(&rhs)
        .filter(|x| x.iter().all(|v| v.is_finite()))
}

/// The diagnostics of S(z) at one z (the quantities of Figs. 3–6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityPoint {
    /// z = σ²h².
    pub z: f64,
    /// The stability matrix S(z).
    pub matrix: Matrix2<f64>,
    /// Spectral radius ρ(S) (Fig. 3); only accurate to O(√ε) where the eigenvalues nearly
    /// coincide.
    pub rho: f64,
    /// det S (Fig. 5): 1 for a symplectic method.
    pub det: f64,
    /// tr S.
    pub trace: f64,
    /// tr(S)² − 4 det S (Fig. 4): negative for a complex pair of eigenvalues.
    pub discriminant: f64,
    /// |tr S| − det S − 1 (Fig. 6): negative with det S < 1 exactly in R_q.
    pub strong_margin: f64,
}

impl StabilityPoint {
    /// The diagnostics of `matrix` = S(z).
    pub fn new(z: f64, matrix: Matrix2<f64>) -> Self {
        let trace = matrix.trace();
        let det = matrix.determinant();
        let discriminant = trace * trace - 4.0 * det;
        let rho = if discriminant < 0.0 {
            det.sqrt()
        } else {
            0.5 * (trace.abs() + discriminant.sqrt())
        };
        StabilityPoint {
            z,
            matrix,
            rho,
            det,
            trace,
            discriminant,
            strong_margin: trace.abs() - det - 1.0,
        }
    }

    /// Whether z ∈ R_s: det S ≤ 1 and |tr S| − det S − 1 ≤ 0 (ρ(S) ≤ 1), up to [`ROUND_OFF`].
    pub fn is_stable(&self) -> bool {
        Condition::DetAtMostOne.holds(self) && Condition::MarginAtMostZero.holds(self)
    }

    /// Whether z ∈ R_p: stable with det S = 1 (so ρ(S) = 1), and tr² − 4 det < 0, all up to
    /// [`ROUND_OFF`] (a double eigenvalue ±1 is excluded, as in Definition 4.1).
    pub fn is_periodic(&self) -> bool {
        self.is_stable() && Condition::DetAtLeastOne.holds(self) && self.discriminant < -ROUND_OFF
    }

    /// Whether z ∈ R_q: det S < 1 and |tr S| < det S + 1 (ρ(S) < 1), both by more than
    /// [`ROUND_OFF`].
    pub fn is_strongly_stable(&self) -> bool {
        Condition::DetBelowOne.holds(self) && Condition::MarginBelowZero.holds(self)
    }
}

/// A closed interval [lower, upper] of z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Left end.
    pub lower: f64,
    /// Right end.
    pub upper: f64,
}

impl Interval {
    /// Whether `lower ≤ z ≤ upper`.
    pub fn contains(&self, z: f64) -> bool {
        self.lower <= z && z <= self.upper
    }
}

/// The result of [`analyse`].
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityReport {
    /// The analysed range [z_min, z_max].
    pub range: Interval,
    /// The diagnostics at the uniformly spaced samples, in increasing z.
    pub points: Vec<StabilityPoint>,
    /// R_s within the range: disjoint intervals of positive length, in increasing order.
    pub stable: Vec<Interval>,
    /// R_p within the range (its closure; see [`analyse`]).
    pub periodic: Vec<Interval>,
    /// R_q within the range.
    pub strongly_stable: Vec<Interval>,
    /// Whether the whole range lies in R_s (A-stability restricted to the range).
    pub a_stable: bool,
    /// Whether the whole range lies in R_p (P-stability restricted to the range).
    pub p_stable: bool,
}

/// Analyse the linear stability of `method` on z ∈ [z_min, z_max]: S(z) at `samples`
/// uniformly spaced z (both ends included), and the regions R_s, R_p, R_q of Definition 4.1 as
/// unions of closed intervals of positive length, whose ends are located by Brent's method.
///
/// Each region is the intersection of conditions (module docs, "Regions"); R_p is computed as
/// R_s ∩ {det S = 1}, which differs from Definition 4.1 only by the isolated points where
/// tr² = 4 det (a double eigenvalue ±1). A condition's verdict changes either between two
/// samples, or inside a narrow band around a sampled extremum of its indicator (refined by
/// Brent's minimisation); bands that leave no such trace in the samples, and isolated points,
/// are not reported.
///
/// # Errors
///
/// [`Error::InvalidParameter`] named `"z_min"` or `"z_max"` unless 0 < z_min < z_max < ∞,
/// `"samples"` if `samples` < 2; any error of [`stability_matrix`] at a sample or during the
/// refinement.
pub fn analyse<M: Method<U1>>(
    method: &M,
    z_min: f64,
    z_max: f64,
    samples: usize,
) -> Result<StabilityReport, Error> {
    require_positive("z_min", z_min)?;
    require_positive("z_max", z_max)?;
    if z_min >= z_max {
        return Err(Error::invalid(
            "z_max",
            format!("{z_max:?} must exceed z_min = {z_min:?}"),
        ));
    }
    if samples < 2 {
        return Err(Error::invalid(
            "samples",
            format!("{samples} samples; need at least 2"),
        ));
    }
    let spacing = (z_max - z_min) / (samples - 1) as f64;
    let points = (0..samples)
        .map(|i| {
            let z = if i + 1 == samples {
                z_max
            } else {
                z_min + i as f64 * spacing
            };
            Ok(StabilityPoint::new(z, stability_matrix(method, z)?))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let range = Interval {
        lower: z_min,
        upper: z_max,
    };
    let holds = |condition: Condition| condition.intervals(method, &points, range);
    let stable = intersection(
        &holds(Condition::DetAtMostOne)?,
        &holds(Condition::MarginAtMostZero)?,
    );
    let periodic = intersection(&stable, &holds(Condition::DetAtLeastOne)?);
    let strongly_stable = intersection(
        &holds(Condition::DetBelowOne)?,
        &holds(Condition::MarginBelowZero)?,
    );
    Ok(StabilityReport {
        range,
        a_stable: stable == [range],
        p_stable: periodic == [range],
        points,
        stable,
        periodic,
        strongly_stable,
    })
}

/// The intersection of two sorted lists of disjoint intervals, without intervals of zero
/// length.
fn intersection(first: &[Interval], second: &[Interval]) -> Vec<Interval> {
    let mut result = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < first.len() && j < second.len() {
        let lower = first[i].lower.max(second[j].lower);
        let upper = first[i].upper.min(second[j].upper);
        if lower < upper {
            result.push(Interval { lower, upper });
        }
        if first[i].upper < second[j].upper {
            i += 1;
        } else {
            j += 1;
        }
    }
    result
}

/// One condition of a region: it holds where its indicator `measure + shift` is ≤ 0, with a
/// smooth measure (det S − 1, the Jury margin |tr S| − det S − 1) and a round-off shift
/// ±[`ROUND_OFF`].
#[derive(Debug, Clone, Copy)]
enum Condition {
    /// det S − 1 ≤ δ.
    DetAtMostOne,
    /// 1 − det S ≤ δ.
    DetAtLeastOne,
    /// |tr S| − det S − 1 ≤ δ.
    MarginAtMostZero,
    /// det S − 1 ≤ −δ.
    DetBelowOne,
    /// |tr S| − det S − 1 ≤ −δ.
    MarginBelowZero,
}

impl Condition {
    fn measure(self, point: &StabilityPoint) -> f64 {
        match self {
            Condition::DetAtMostOne | Condition::DetBelowOne => point.det - 1.0,
            Condition::DetAtLeastOne => 1.0 - point.det,
            Condition::MarginAtMostZero | Condition::MarginBelowZero => point.strong_margin,
        }
    }

    fn shift(self) -> f64 {
        match self {
            Condition::DetAtMostOne | Condition::DetAtLeastOne | Condition::MarginAtMostZero => {
                -ROUND_OFF
            }
            Condition::DetBelowOne | Condition::MarginBelowZero => ROUND_OFF,
        }
    }

    fn indicator(self, point: &StabilityPoint) -> f64 {
        self.measure(point) + self.shift()
    }

    fn holds(self, point: &StabilityPoint) -> bool {
        self.indicator(point) <= 0.0
    }

    /// Where the condition holds within `range`, from the samples `points`: every change of
    /// verdict between neighbouring samples, and every narrow band around a sampled extremum
    /// of the indicator that [`suggests_excursion`], located by Brent's method.
    fn intervals<M: Method<U1>>(
        self,
        method: &M,
        points: &[StabilityPoint],
        range: Interval,
    ) -> Result<Vec<Interval>, Error> {
        let mut changes = Vec::new();
        for (i, pair) in points.windows(2).enumerate() {
            if self.holds(&pair[0]) != self.holds(&pair[1]) {
                changes.push(self.crossing(method, &pair[0], &pair[1])?);
            }
            if let [before, at, after, ..] = points[i..] {
                let (g0, g1, g2) = (
                    self.indicator(&before),
                    self.indicator(&at),
                    self.indicator(&after),
                );
                if suggests_excursion(g0, g1, g2) {
                    let peak = self.extremum(method, before.z, after.z, g1 <= 0.0)?;
                    if self.holds(&peak) != self.holds(&at) {
                        let (left, right) = if peak.z > at.z {
                            (at, after)
                        } else {
                            (before, at)
                        };
                        changes.push(self.crossing(method, &left, &peak)?);
                        changes.push(self.crossing(method, &peak, &right)?);
                    }
                }
            }
        }
        changes.sort_by(f64::total_cmp);
        let mut intervals = Vec::new();
        let mut start = self.holds(&points[0]).then_some(range.lower);
        for z in changes {
            start = match start {
                Some(lower) => {
                    intervals.push(Interval { lower, upper: z });
                    None
                }
                None => Some(z),
            };
        }
        if let Some(lower) = start {
            intervals.push(Interval {
                lower,
                upper: range.upper,
            });
        }
        intervals.retain(|interval| interval.lower < interval.upper);
        Ok(intervals)
    }

    /// Where the verdict changes between `left` and `right` (it does): the zero of the
    /// measure if it changes sign from beyond the round-off band on one side to beyond it on
    /// the other, else the zero of the indicator (the edge of the band). By Brent's method.
    fn crossing<M: Method<U1>>(
        self,
        method: &M,
        left: &StabilityPoint,
        right: &StabilityPoint,
    ) -> Result<f64, Error> {
        let (from, to) = (self.measure(left), self.measure(right));
        let offset = if from * to < 0.0 && from.abs() > ROUND_OFF && to.abs() > ROUND_OFF {
            0.0
        } else {
            self.shift()
        };
        let problem = Indicator {
            method,
            condition: self,
            offset,
            sign: 1.0,
        };
        let solver = BrentRoot::new(left.z, right.z, BRENT_TOLERANCE);
        let state = run(problem, solver, left.z, right.z)?;
        match (state.get_termination_status(), state.get_param()) {
            (TerminationStatus::Terminated(TerminationReason::SolverConverged), Some(&z)) => Ok(z),
            (status, _) => Err(Error::invalid(
                "z",
                format!(
                    "Brent's method did not locate a boundary in [{:?}, {:?}]: {status:?}",
                    left.z, right.z
                ),
            )),
        }
    }

    /// The largest (`maximum`) or smallest indicator on [lower, upper], by Brent's
    /// minimisation.
    fn extremum<M: Method<U1>>(
        self,
        method: &M,
        lower: f64,
        upper: f64,
        maximum: bool,
    ) -> Result<StabilityPoint, Error> {
        let problem = Indicator {
            method,
            condition: self,
            offset: self.shift(),
            sign: if maximum { -1.0 } else { 1.0 },
        };
        let solver =
            BrentOpt::new(lower, upper).set_tolerance(f64::EPSILON.sqrt(), EXTREMUM_TOLERANCE);
        let state = run(problem, solver, lower, upper)?;
        let z = state
            .get_best_param()
            .copied()
            .unwrap_or(0.5 * (lower + upper));
        Ok(StabilityPoint::new(z, stability_matrix(method, z)?))
    }
}

/// Whether three neighbouring samples g₀, g₁, g₂ of an indicator, all on the same side of
/// zero, hint that it crosses zero between the outer two: g₁ is an extremum towards zero, and
/// its distance to zero is at most four times its rise above the farther neighbour. (A
/// quadratic extremum that does cross zero has distance at most a quarter of that rise.)
fn suggests_excursion(g0: f64, g1: f64, g2: f64) -> bool {
    if g0 <= 0.0 && g1 <= 0.0 && g2 <= 0.0 {
        g1 > g0 && g1 >= g2 && -g1 <= 4.0 * (g1 - g0.min(g2))
    } else if g0 > 0.0 && g1 > 0.0 && g2 > 0.0 {
        g1 < g0 && g1 <= g2 && g1 <= 4.0 * (g0.max(g2) - g1)
    } else {
        false
    }
}

/// Run an argmin solver on an indicator over [lower, upper]; errors of the stability matrix
/// come back as they are.
fn run<'a, M: Method<U1>, S>(
    problem: Indicator<'a, M>,
    solver: S,
    lower: f64,
    upper: f64,
) -> Result<IterState<f64, (), (), (), (), f64>, Error>
where
    S: Solver<Indicator<'a, M>, IterState<f64, (), (), (), (), f64>>,
{
    Executor::new(problem, solver)
        .configure(|state| state.max_iters(BRENT_ITERATIONS))
        .run()
        .map(|result| result.state)
        .map_err(|error| match error.downcast::<Error>() {
            Ok(error) => error,
            Err(other) => Error::invalid(
                "z",
                format!("Brent's method failed on [{lower:?}, {upper:?}]: {other}"),
            ),
        })
}

/// `sign · (measure + offset)` of a condition as a function of z, for argmin.
struct Indicator<'a, M> {
    method: &'a M,
    condition: Condition,
    /// Added to the measure: 0 or the condition's shift.
    offset: f64,
    /// 1, or −1 to maximise with a minimiser.
    sign: f64,
}

impl<M: Method<U1>> CostFunction for Indicator<'_, M> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, z: &f64) -> Result<f64, argmin::core::Error> {
        let point = StabilityPoint::new(*z, stability_matrix(self.method, *z)?);
        Ok(self.sign * (self.condition.measure(&point) + self.offset))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::collocation::SpectralCollocation;
    use crate::method::variational::svi::Svi;

    fn largest_difference(a: &Matrix2<f64>, b: &Matrix2<f64>) -> f64 {
        (a - b).amax() / a.amax().max(1.0)
    }

    #[test]
    fn linear_svi_with_two_gauss_points_matches_the_hand_derivation() {
        for z in [0.01, 1.0, 11.9, 12.0, 12.1, 100.0] {
            let expected =
                Matrix2::new(6.0 - 2.0 * z, 6.0, -z * (12.0 - z) / 2.0, 6.0 - 2.0 * z) / (6.0 + z);
            let closed = svi_closed_form(2, 2, z).unwrap();
            assert!(
                largest_difference(&expected, &closed) < 1e-14,
                "z = {z}: {closed}"
            );
        }
    }

    #[test]
    fn two_point_collocation_is_implicit_euler() {
        for z in [0.01, 1.0, 12.0, 900.0] {
            let expected = Matrix2::new(1.0, 1.0, -z, 1.0) / (1.0 + z);
            let closed = collocation_closed_form(2, z).unwrap();
            assert!(
                largest_difference(&expected, &closed) < 1e-14,
                "z = {z}: {closed}"
            );
            let point = StabilityPoint::new(z, closed);
            assert!((point.det - 1.0 / (1.0 + z)).abs() < 1e-15);
            assert!(point.is_strongly_stable() && point.is_stable() && !point.is_periodic());
        }
    }

    /// The corners of D̃ used by S₂ have the signs of ascending nodes, opposite to eq. (17).
    #[test]
    fn differentiation_corners_are_those_of_ascending_nodes() {
        for points in [3, 5, 9] {
            let s = (points - 1) as f64;
            let d = LagrangeBasis::chebyshev_gauss_lobatto(points)
                .unwrap()
                .differentiation_matrix();
            let corner = (2.0 * s * s + 1.0) / 6.0;
            assert!((d[(0, 0)] + corner).abs() < 1e-12 * corner);
            assert!((d[(points - 1, points - 1)] - corner).abs() < 1e-12 * corner);
        }
    }

    #[test]
    fn closed_forms_match_tangent_maps() {
        for z in [0.1, 4.0, 50.0] {
            for (points, quadrature) in [(2, 2), (3, 6), (4, 3)] {
                let method = Svi::new(points).with_quadrature(quadrature);
                let tangent = stability_matrix(&method, z).unwrap();
                let closed = svi_closed_form(points, quadrature, z).unwrap();
                let difference = largest_difference(&closed, &tangent);
                assert!(
                    difference < 1e-12,
                    "svi {points}/{quadrature}, z = {z}: {difference:e}"
                );
                assert!((closed.determinant() - 1.0).abs() < 1e-12);
            }
            for points in [2, 4] {
                let tangent = stability_matrix(&SpectralCollocation::new(points), z).unwrap();
                let closed = collocation_closed_form(points, z).unwrap();
                let difference = largest_difference(&closed, &tangent);
                assert!(difference < 1e-12, "sc {points}, z = {z}: {difference:e}");
            }
        }
    }

    #[test]
    fn conditions_classify_model_matrices() {
        let rotation =
            |angle: f64| Matrix2::new(angle.cos(), angle.sin(), -angle.sin(), angle.cos());
        let point = |m| StabilityPoint::new(1.0, m);
        let turning = point(rotation(1.0));
        assert!(turning.is_stable() && turning.is_periodic() && !turning.is_strongly_stable());
        assert!((turning.rho - 1.0).abs() < 1e-15);
        // −I and a Jordan block at −1: ρ = 1 but tr² = 4 det, so not periodic.
        for m in [-Matrix2::identity(), Matrix2::new(-1.0, 1.0, 0.0, -1.0)] {
            let p = point(m);
            assert!(
                p.is_stable() && !p.is_periodic() && !p.is_strongly_stable(),
                "{m}"
            );
        }
        let damped = point(rotation(1.0) * 0.9);
        assert!(damped.is_stable() && damped.is_strongly_stable() && !damped.is_periodic());
        assert!((damped.rho - 0.9).abs() < 1e-15);
        let saddle = point(Matrix2::new(2.0, 0.0, 0.0, 0.5));
        assert!(!saddle.is_stable() && !saddle.is_periodic() && !saddle.is_strongly_stable());
        assert_eq!(saddle.rho, 2.0);
        // ρ = 1 + 1e−10 is outside R_s; a round-off excess of 1e−14 is not.
        assert!(!point(rotation(1.0) * (1.0 + 1e-10)).is_stable());
        let noisy = point(rotation(1.0) * (1.0 + 1e-14));
        assert!(noisy.is_stable() && noisy.is_periodic());
    }

    #[test]
    fn intersections_drop_empty_and_degenerate_pieces() {
        let interval = |lower, upper| Interval { lower, upper };
        let first = [interval(0.0, 2.0), interval(3.0, 5.0)];
        assert_eq!(
            intersection(&first, &[interval(1.0, 4.0)]),
            [interval(1.0, 2.0), interval(3.0, 4.0)]
        );
        assert_eq!(intersection(&first, &[interval(2.0, 3.0)]), []);
        assert_eq!(intersection(&first, &[]), []);
        assert_eq!(intersection(&first, &first), first);
    }

    #[test]
    fn excursions_are_suggested_by_extrema_towards_zero() {
        // A quadratic peak 1e−3 − (z − 0.3)² sampled at z = −1, 0, 1 crosses zero unseen.
        let peak = |z: f64| 1e-3 - (z - 0.3) * (z - 0.3);
        assert!(suggests_excursion(peak(-1.0), peak(0.0), peak(1.0)));
        // The same from the failing side, and a shallow bump far below zero.
        assert!(suggests_excursion(1.0, 0.05, 0.5));
        assert!(!suggests_excursion(-1.1, -1.0, -1.05));
        // Round-off noise on the indicator of a symplectic method, monotone samples, and
        // samples on both sides of zero (a plain crossing) suggest nothing.
        assert!(!suggests_excursion(-1e-12 - 1e-15, -1e-12 + 1e-15, -1e-12));
        assert!(!suggests_excursion(-3.0, -2.0, -1.0));
        assert!(!suggests_excursion(-1.0, 0.5, -1.0));
    }

    #[test]
    fn linear_svi_is_stable_up_to_twelve() {
        let report = analyse(&Svi::new(2).with_quadrature(2), 0.5, 20.0, 40).unwrap();
        assert_eq!(report.stable.len(), 1);
        assert_eq!(report.stable[0].lower, 0.5);
        assert!(
            (report.stable[0].upper - 12.0).abs() < 1e-9,
            "{:?}",
            report.stable
        );
        assert_eq!(report.periodic.len(), 1);
        assert!(
            (report.periodic[0].upper - 12.0).abs() < 1e-9,
            "{:?}",
            report.periodic
        );
        assert!(report.strongly_stable.is_empty());
        assert!(!report.a_stable && !report.p_stable);
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        fn name<T: std::fmt::Debug>(result: Result<T, Error>) -> String {
            match result {
                Err(Error::InvalidParameter { name, .. }) => name,
                other => panic!("expected InvalidParameter, got {other:?}"),
            }
        }
        let svi = Svi::new(3);
        for z in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(name(stability_matrix(&svi, z)), "z");
            assert_eq!(name(svi_closed_form(3, 6, z)), "z");
            assert_eq!(name(collocation_closed_form(3, z)), "z");
        }
        assert_eq!(name(svi_closed_form(1, 6, 1.0)), "points");
        assert_eq!(name(svi_closed_form(3, 0, 1.0)), "quadrature");
        assert_eq!(
            name(collocation_closed_form(
                crate::spectral::MAX_POINTS + 1,
                1.0
            )),
            "points"
        );
        assert_eq!(name(analyse(&svi, 0.0, 1.0, 10)), "z_min");
        assert_eq!(name(analyse(&svi, 1.0, f64::NAN, 10)), "z_max");
        assert_eq!(name(analyse(&svi, 2.0, 1.0, 10)), "z_max");
        assert_eq!(name(analyse(&svi, 1.0, 1.0, 10)), "z_max");
        assert_eq!(name(analyse(&svi, 1.0, 2.0, 1)), "samples");
        assert_eq!(name(stability_matrix(&Svi::new(1), 1.0)), "points");
    }
}
