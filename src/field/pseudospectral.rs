//! Pseudospectral variational integrators of Schrödinger-type fields (Leok §5.8): a complex
//! field ψ = a + ib on a periodic domain, discrete Fourier series in space, and in time either
//! a Galerkin polynomial of degree s (s = 1: the seed's linear interpolation; s ≥ 2: the
//! spectral-in-time SVI the seed proposes, §5.8 and §5.2), or, for comparison, the Strang
//! split-step Fourier method.
//!
//! # The density and the semi-discrete Lagrangian (§5.8.1)
//! The density is a [`LagrangianDensity<2>`] of u = (a, b), first order in time:
//!
//! ℒ = c (b a_t − a b_t) − W(x, t, u, u_x).
//!
//! The Schrödinger density of §5.8.1, (iħ/2)(ψ_t ψ̄ − ψ ψ̄_t) − (ħ²/2m)|ψ_x|² − V|ψ|², is
//! this with c = ħ (ψ_t ψ̄ − ψψ̄_t = 2i(a_t b − a b_t), times iħ/2: ħ(b a_t − a b_t)) and
//! W = (ħ²/2m)(a_x² + b_x²) + V(a² + b²); the focusing cubic NLS adds −(κ/2)(a² + b²)² to W.
//! The integrator reads c off ∂ℒ/∂u_t (it checks ∂ℒ/∂u_t = c(b, −a) on the initial field) and
//! the kinetic coefficient α = −∂²ℒ/∂a_x² (for the preconditioner and the Strang split).
//!
//! On the nodes x_j (M of them, [`Fourier`]) with u_x replaced by the spectral derivative D u,
//! the semi-discrete Lagrangian L(q, q̇) = Δx Σ_j ℒ(x_j, t, u_j, u̇_j, (Du)_j) is linear in
//! the velocities, L = θ(q)·q̇ − H(q), θ(q) = A q with A = cΔx [[0, I], [−I, 0]] (acting on
//! q = (a, b)) and H(q) = −Δx Σ_j ℒ(x_j, t, u_j, 0, (Du)_j). Its Euler–Lagrange equation is
//! (θ′ − θ′ᵀ) q̇ = −∇H, that is 2A q̇ = −∇H, and with Dᵀ = −D
//!
//! ∇_{u_j} H = −Δx [∂ℒ/∂u − D ∂ℒ/∂u_x]_j, so ψ̇_j = (i/2c) [G_u − D G_x]_j =: f(ψ)_j,
//!
//! G_u = ∂ℒ/∂a + i ∂ℒ/∂b and G_x = ∂ℒ/∂a_x + i ∂ℒ/∂b_x at (u_j, u_t = 0, (Du)_j), taken
//! pointwise by automatic differentiation (four `Dual64` sweeps per node) and four FFTs per
//! evaluation of f. For NLS, f = i(½ψ_xx + κ|ψ|²ψ). The linear part of f is
//! ψ̂_k ↦ −iω_k ψ̂_k, ω_k = (α/2c) κ_k², diagonal in Fourier space.
//!
//! # Linear interpolation in time: the seed's scheme, made one-step (§5.8.2)
//! With q(τ) linear on [t_l, t_{l+1}] the kinetic part of the action, θ(q)·q̇, is linear in τ
//! and any rule exact for degree 1 integrates it exactly; H(q(τ)) is where the quadrature
//! matters. The seed integrates it exactly (weights ⅓, ⅙, ⅓ on v̂ˡv̄ˡ, v̂ˡv̄ˡ⁺¹, v̂ˡ⁺¹v̄ˡ⁺¹
//! for the quadratic Hamiltonian), and the discrete Euler–Lagrange equation
//! D₂L_d(q_{l−1}, q_l) + D₁L_d(q_l, q_{l+1}) = 0 is then A(q_{l−1} − q_{l+1}) =
//! (h/6)S(q_{l−1} + 4q_l + q_{l+1}) for ∇H = Sq, per Fourier mode
//! ψ̂_{l+1} − ψ̂_{l−1} = −(iωh/3)(ψ̂_{l−1} + 4ψ̂_l + ψ̂_{l+1}): the Milne–Simpson two-step
//! recursion, with a parasitic root of modulus 1 (≈ −1), because L is
//! degenerate: the discrete Legendre maps p_l = −D₁L_d(q_l, q_{l+1}) and
//! p_{l+1} = D₂L_d(q_l, q_{l+1}) do not reproduce the constraint p = θ(q) of the continuous
//! problem. The sound formulation is one-step: impose p_l = θ(q_l), solve
//! −D₁L_d(q_l, q_{l+1}) = θ(q_l) for q_{l+1}, and check that D₂L_d(q_l, q_{l+1}) = θ(q_{l+1})
//! (the constraint propagates). With the one-point Gauss (midpoint) rule,
//! L_d = θ(q̄)·(q_{l+1} − q_l) − h H(q̄), q̄ = (q_l + q_{l+1})/2, one finds
//! −D₁L_d = A q_{l+1} + (h/2)∇H(q̄) and D₂L_d = A q_l − (h/2)∇H(q̄), so −D₁L_d = θ(q_l) is
//! the implicit midpoint rule q_{l+1} − q_l = h f(q̄), and then D₂L_d = A q_{l+1} = θ(q_{l+1})
//! holds exactly: the constraint is preserved, and the three-level DEL is the sum of two
//! consecutive midpoint steps. For the linear Schrödinger equation the step is diagonal in
//! Fourier space, ψ̂_{l+1} = (1 − iωh/2)/(1 + iωh/2) ψ̂_l (Crank–Nicolson), unitary: the
//! norm is conserved exactly and the seed's Lagrange multiplier of the normalisation
//! constraint ⟨ψ_l, ψ_l⟩ = 1 vanishes identically (its equation is satisfied with λ_l = 0).
//! This scheme is [`TimeScheme::Galerkin`] with `degree` 1.
//!
//! # Galerkin in time: SVI with Fourier in space
//! q(τ) a polynomial of degree s through s + 1 Chebyshev–Gauss–Lobatto nodes, the action by
//! s-point Gauss quadrature (nodes c_m, weights b_m on [0, 1]). The kinetic term θ(q)·q̇ has
//! degree 2s − 1 and is integrated exactly. Varying the interior nodes and imposing
//! p_l = θ(q_l) at the left end gives, for each of the s Lagrange polynomials ℓ_i, i < s,
//!
//! Σ_m b_m ℓ_i(c_m) [2A q̇(c_m) + ∇H(q(c_m))] = 0;
//!
//! the s × s matrix ℓ_i(c_m) (i < s) is invertible (a degree-s polynomial vanishing at all
//! Gauss nodes is a multiple of the Gauss node polynomial, which does not vanish at τ = 1), so
//! q̇(c_m) = f(q(c_m)) at every Gauss node: **the Galerkin SVI of degree s with s Gauss
//! points is s-stage Gauss–Legendre collocation** (the Runge–Kutta method with
//! a_mj = ∫₀^{c_m} ℓ_j, b_j), and the right-end Legendre map D₂L_d = θ(q_{l+1}) follows from
//! collocation. Order 2s, symmetric, symplectic; the mass Σ|ψ̂_k|² (a quadratic invariant of
//! the semi-discrete system for a gauge-invariant density) is conserved exactly by every
//! Gauss method, up to the iteration tolerance and round-off. The test
//! `galerkin_stationarity_holds_on_the_collocation_step` in `tests/pseudospectral.rs` checks
//! the equivalence on the discrete action itself.
//!
//! The stage equations Z_m = h Σ_j a_mj f(ψ_l + Z_j) are solved by a simplified Newton
//! iteration whose matrix keeps only the linear part of f: per Fourier mode the s × s complex
//! system (I + ihω_k A) ΔẐ = R̂ (inverted once per run). Each iteration costs s evaluations of
//! f (4 FFTs each) and 2s FFTs for the correction; the linear equation converges in one
//! iteration (a second one confirms it). The start is the previous step's collocation
//! polynomial extrapolated to the new stage times (Hairer's GNI_IRK2), the new value
//! ψ_{l+1} = ψ_l + Σ_j d_j Z_j with dᵀ = bᵀA⁻¹ (no further evaluation of f).
//!
//! # Strang split-step Fourier (the comparison)
//! For W = (α/2)|u_x|² + P(x, t, |u|²) (checked on the initial field), the local
//! part of f, (i/2c)G_u with u_x = 0, is a phase rotation iγψ with γ = Im(ψ̄ f)/|ψ|² real and
//! |ψ| constant along it: exactly solvable. One step is a half step of the rotation, the
//! exact linear step ψ̂_k ↦ e^{−iω_k h} ψ̂_k, and another half rotation: 2 FFTs per step,
//! order 2, symmetric, unitary (the norm is conserved to round-off).
//!
//! # References
//! Leok, *Generalized Variational Integrators*, §5.8 (pseudospectral VIs, the Schrödinger
//! Lagrangian) and §5.2 (spectral variational integrators); Hairer, Lubich & Wanner,
//! *Geometric Numerical Integration*, II.1.3 (Gauss collocation), IV.2 (quadratic invariants),
//! VIII.6 (GNI_IRK2 starting values); Weideman & Herbst 1986 (split-step Fourier for NLS).

use nalgebra::{DMatrix, SVector};
use num_dual::Dual64;
use rustfft::num_complex::Complex64;

use crate::error::{Error, require_finite, require_positive};
use crate::field::fourier::Fourier;
use crate::model::density::{Boundary, Domain, Jet, LagrangianDensity, LagrangianDensityExt};
use crate::quadrature::GaussLegendre;

/// The largest Galerkin degree in time.
pub const MAX_DEGREE: usize = 16;

/// The time discretisation of [`Pseudospectral`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeScheme {
    /// Galerkin in time: a polynomial of degree s (s + 1 CGL nodes) and s-point Gauss
    /// quadrature, equivalent to s-stage Gauss collocation, order 2s. Degree 1 is the seed's
    /// linear interpolation (the Crank–Nicolson midpoint map).
    Galerkin {
        /// The degree s ≥ 1 of the polynomial in time.
        degree: usize,
    },
    /// Strang split-step Fourier, order 2.
    Strang,
}

impl TimeScheme {
    /// The order of accuracy in time.
    pub fn order(self) -> usize {
        match self {
            TimeScheme::Galerkin { degree } => 2 * degree,
            TimeScheme::Strang => 2,
        }
    }
}

/// Options of [`Pseudospectral`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct PseudospectralOptions {
    /// The time discretisation.
    pub scheme: TimeScheme,
    /// Iteration cap of the stage equations per step.
    pub max_iterations: usize,
    /// The iteration stops when the largest stage increment ≤ tolerance · (1 + max|ψ|).
    pub tolerance: f64,
}

impl Default for PseudospectralOptions {
    fn default() -> Self {
        PseudospectralOptions {
            scheme: TimeScheme::Galerkin { degree: 1 },
            max_iterations: 50,
            tolerance: 1e-14,
        }
    }
}

/// What [`Pseudospectral::run`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralRun {
    /// ψ at the last level, node by node.
    pub last: Vec<Complex64>,
    /// The mass N = Δx Σ_j |ψ_j|² of the initial field (= Σ|ψ̂_k|²·Δx/M by Parseval).
    pub norm_initial: f64,
    /// max_l |N_l − N_0| / N_0 over all levels (0 for a zero field).
    pub norm_error_max: f64,
    /// The semi-discrete energy H(q) = −Δx Σ_j ℒ(x_j, t, u_j, 0, (Du)_j) at the start.
    pub energy_initial: f64,
    /// H at the last level.
    pub energy_final: f64,
    /// FFTs over the run (the two energy evaluations included).
    pub ffts: usize,
    /// Iterations of the stage equations over the run (0 for Strang).
    pub iterations: usize,
}

/// The pseudospectral integrator of a Schrödinger-type [`LagrangianDensity<2>`] on a
/// periodic domain (see the module documentation).
#[derive(Debug, Clone)]
pub struct Pseudospectral<F> {
    density: F,
    fourier: Fourier,
    h: f64,
    options: PseudospectralOptions,
    /// c of ℒ = c(b a_t − a b_t) − W.
    symplectic: f64,
    /// α = −∂²ℒ/∂a_x².
    kinetic: f64,
    /// ω_k per FFT slot.
    frequencies: Vec<f64>,
    /// e^{−iω_k h} per FFT slot (the exact linear step of Strang; empty otherwise).
    propagator: Vec<Complex64>,
    gauss: Option<GaussTableau>,
}

/// The Gauss collocation data of a Galerkin scheme of degree s.
#[derive(Debug, Clone)]
struct GaussTableau {
    stages: usize,
    /// c_m on [0, 1].
    nodes: Vec<f64>,
    /// a_mj, row-major.
    a: Vec<f64>,
    /// dᵀ = bᵀA⁻¹.
    d: Vec<f64>,
    /// Z_new,m = Σ_j e_mj Z_old,j (the collocation polynomial extrapolated), row-major.
    extrapolation: Vec<f64>,
    /// (I + ihω_k A)⁻¹ per FFT slot, s × s row-major each.
    preconditioner: Vec<Complex64>,
}

/// Every buffer of a run, allocated once.
struct Workspace {
    /// Stage increments Z_m (s × M), their rates F_m, the residual/correction.
    z: Vec<Complex64>,
    rates: Vec<Complex64>,
    correction: Vec<Complex64>,
    stage: Vec<Complex64>,
    derivative: Vec<Complex64>,
    next: Vec<Complex64>,
}

/// The inverse of the s × s matrix with entries `entry(m, j)`, row-major; `None` if singular.
fn inverse_row_major<T: nalgebra::ComplexField + Copy>(
    s: usize,
    entry: impl Fn(usize, usize) -> T,
) -> Option<Vec<T>> {
    let inverse = DMatrix::from_fn(s, s, entry).try_inverse()?;
    Some(inverse.transpose().iter().copied().collect())
}

/// The Lagrange basis polynomial of `nodes[j]` at τ.
fn lagrange(nodes: &[f64], j: usize, tau: f64) -> f64 {
    nodes
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != j)
        .map(|(_, &node)| (tau - node) / (nodes[j] - node))
        .product()
}

impl GaussTableau {
    fn new(degree: usize, h: f64, frequencies: &[f64]) -> Result<Self, Error> {
        let rule = GaussLegendre::new(degree)?;
        let s = degree;
        let nodes: Vec<f64> = rule.nodes().iter().map(|x| 0.5 * (x + 1.0)).collect();
        let weights: Vec<f64> = rule.weights().iter().map(|w| 0.5 * w).collect();
        let mut a = vec![0.0; s * s];
        for m in 0..s {
            for j in 0..s {
                a[m * s + j] = nodes[m]
                    * (0..s)
                        .map(|q| weights[q] * lagrange(&nodes, j, nodes[m] * nodes[q]))
                        .sum::<f64>();
            }
        }
        let singular = || Error::invalid("degree", "singular Gauss collocation matrix");
        let a_inverse = inverse_row_major(s, |m, j| a[m * s + j]).ok_or_else(singular)?;
        let d = (0..s)
            .map(|j| (0..s).map(|m| weights[m] * a_inverse[m * s + j]).sum())
            .collect();
        let mut with_zero = vec![0.0];
        with_zero.extend(&nodes);
        let mut extrapolation = vec![0.0; s * s];
        for m in 0..s {
            for j in 0..s {
                extrapolation[m * s + j] =
                    lagrange(&with_zero, j + 1, 1.0 + nodes[m]) - lagrange(&with_zero, j + 1, 1.0);
            }
        }
        let mut preconditioner = Vec::with_capacity(frequencies.len() * s * s);
        for &omega in frequencies {
            let block = inverse_row_major(s, |m, j| {
                Complex64::new(f64::from(m == j), h * omega * a[m * s + j])
            });
            preconditioner.extend(block.ok_or_else(singular)?);
        }
        Ok(GaussTableau {
            stages: s,
            nodes,
            a,
            d,
            extrapolation,
            preconditioner,
        })
    }
}

/// The largest |z| of a slice.
fn max_abs(values: &[Complex64]) -> f64 {
    values.iter().map(|v| v.norm()).fold(0.0, f64::max)
}

impl<F: LagrangianDensity<2>> Pseudospectral<F> {
    /// The integrator of `density` with `modes` Fourier modes on `domain` and time step `h`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `boundary` (not periodic), `modes` (odd, or out of
    /// range: [`Fourier::new`]), `h` (not finite and positive), `degree` (0 or above
    /// [`MAX_DEGREE`]), `max_iterations` (0), `tolerance` (not finite and positive) or
    /// `density` (not of the form c(b a_t − a b_t) − W with c ≠ 0 and a finite kinetic
    /// coefficient).
    pub fn new(
        density: F,
        domain: Domain,
        boundary: Boundary<2>,
        modes: usize,
        h: f64,
        options: PseudospectralOptions,
    ) -> Result<Self, Error> {
        if boundary != Boundary::Periodic {
            return Err(Error::invalid(
                "boundary",
                "a Fourier series in space needs a periodic domain",
            ));
        }
        let fourier = Fourier::new(domain, modes)?;
        require_positive("h", h)?;
        if options.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        require_positive("tolerance", options.tolerance)?;
        if let TimeScheme::Galerkin { degree } = options.scheme
            && !(1..=MAX_DEGREE).contains(&degree)
        {
            return Err(Error::invalid(
                "degree",
                format!("{degree}: the Galerkin degree in time must lie in 1..={MAX_DEGREE}"),
            ));
        }
        let x = domain.left();
        let unit_b = Jet {
            u: SVector::from([0.0, 1.0]),
            u_t: SVector::zeros(),
            u_x: SVector::zeros(),
        };
        let symplectic = density.gradient(x, 0.0, &unit_b).u_t[0];
        let kinetic = -density.hessian(x, 0.0, &unit_b).blocks[2][2][(0, 0)];
        if !(symplectic.is_finite() && symplectic != 0.0 && kinetic.is_finite()) {
            return Err(Error::invalid(
                "density",
                format!(
                    "not of the Schrödinger form c(b a_t − a b_t) − W(x, t, u, u_x) with c ≠ 0 \
                     (c = {symplectic:?}, α = {kinetic:?})"
                ),
            ));
        }
        let frequencies: Vec<f64> = (0..modes)
            .map(|slot| {
                let k = fourier.derivative_wavenumber(slot);
                kinetic / (2.0 * symplectic) * k * k
            })
            .collect();
        let (gauss, propagator) = match options.scheme {
            TimeScheme::Galerkin { degree } => (
                Some(GaussTableau::new(degree, h, &frequencies)?),
                Vec::new(),
            ),
            TimeScheme::Strang => (
                None,
                frequencies
                    .iter()
                    .map(|omega| Complex64::from_polar(1.0, -omega * h))
                    .collect(),
            ),
        };
        Ok(Pseudospectral {
            density,
            fourier,
            h,
            options,
            symplectic,
            kinetic,
            frequencies,
            propagator,
            gauss,
        })
    }

    /// The Fourier grid (nodes, wavenumbers, FFT count).
    pub fn fourier(&self) -> &Fourier {
        &self.fourier
    }

    /// The time step.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The order of the time discretisation ([`TimeScheme::order`]).
    pub fn order(&self) -> usize {
        self.options.scheme.order()
    }

    /// ∂ℒ/∂u and ∂ℒ/∂u_x at (x, t, u, u_t = 0, u_x) as complex numbers (real part: the a
    /// component), and ℒ: four `Dual64` sweeps, or two (∂ℒ/∂u only, ∂ℒ/∂u_x returned as 0)
    /// when `with_slope` is false.
    #[inline]
    fn local_gradient(
        &self,
        x: f64,
        t: f64,
        u: Complex64,
        u_x: Complex64,
        with_slope: bool,
    ) -> (Complex64, Complex64, f64) {
        let base = [u.re, u.im, u_x.re, u_x.im];
        let mut derivative = [0.0; 4];
        let mut value = 0.0;
        let zero = SVector::<Dual64, 2>::zeros();
        let directions = if with_slope { 4 } else { 2 };
        for (direction, slot) in derivative.iter_mut().enumerate().take(directions) {
            let mut lifted = base.map(Dual64::from_re);
            lifted[direction].eps = 1.0;
            let result = self.density.density(
                x,
                t,
                &SVector::from([lifted[0], lifted[1]]),
                &zero,
                &SVector::from([lifted[2], lifted[3]]),
            );
            value = result.re;
            *slot = result.eps;
        }
        (
            Complex64::new(derivative[0], derivative[1]),
            Complex64::new(derivative[2], derivative[3]),
            value,
        )
    }

    /// f(ψ) into `out` (see the module documentation): four FFTs. Returns H(ψ).
    fn rate(
        &mut self,
        t: f64,
        psi: &[Complex64],
        out: &mut [Complex64],
        derivative: &mut [Complex64],
    ) -> f64 {
        derivative.copy_from_slice(psi);
        self.fourier.derivative_in_place(derivative);
        let mut density_sum = 0.0;
        for j in 0..psi.len() {
            let x = self.fourier.x(j);
            let (g_u, g_x, value) = self.local_gradient(x, t, psi[j], derivative[j], true);
            out[j] = g_u;
            derivative[j] = g_x;
            density_sum += value;
        }
        self.fourier.derivative_in_place(derivative);
        let scale = Complex64::new(0.0, 0.5 / self.symplectic);
        for (value, d) in out.iter_mut().zip(derivative.iter()) {
            *value = scale * (*value - d);
        }
        -self.fourier.dx() * density_sum
    }

    /// Check the density's form on the initial field: ∂ℒ/∂u_t = c(b, −a) everywhere, and for
    /// Strang ∂ℒ/∂u_x = −α u_x, ∂ℒ/∂u independent of u_x and the local part a phase rotation.
    fn check_structure(
        &mut self,
        t0: f64,
        psi: &[Complex64],
        derivative: &mut [Complex64],
    ) -> Result<(), Error> {
        derivative.copy_from_slice(psi);
        self.fourier.derivative_in_place(derivative);
        let scale = 1.0 + max_abs(psi) + max_abs(derivative);
        let tolerance = 1e-10 * scale * (1.0 + self.symplectic.abs() + self.kinetic.abs());
        for (j, (&u, &u_x)) in psi.iter().zip(derivative.iter()).enumerate() {
            let x = self.fourier.x(j);
            let jet = Jet {
                u: SVector::from([u.re, u.im]),
                u_t: SVector::zeros(),
                u_x: SVector::from([u_x.re, u_x.im]),
            };
            let momentum = self.density.gradient(x, t0, &jet).u_t;
            let expected = SVector::from([u.im, -u.re]) * self.symplectic;
            if (momentum - expected).amax() > tolerance {
                return Err(Error::invalid(
                    "density",
                    format!(
                        "∂ℒ/∂u_t ≠ c(b, −a) at x = {x:?}: not first order in time as \
                         c(b a_t − a b_t) − W(x, t, u, u_x)"
                    ),
                ));
            }
            if self.options.scheme == TimeScheme::Strang {
                let (g_u, g_x, _) = self.local_gradient(x, t0, u, u_x, true);
                let (g_u0, _, _) = self.local_gradient(x, t0, u, Complex64::default(), false);
                let rotation = (u.conj() * g_u0).im.abs();
                if (g_x + u_x * self.kinetic).norm() > tolerance
                    || (g_u - g_u0).norm() > tolerance
                    || rotation > tolerance * (1.0 + g_u0.norm())
                {
                    return Err(Error::invalid(
                        "method",
                        format!(
                            "Strang splitting needs W = (α/2)|u_x|² + P(x, t, |u|²); the density \
                             breaks it at x = {x:?}"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Δx Σ|ψ_j|².
    fn norm(&self, psi: &[Complex64]) -> f64 {
        self.fourier.dx() * psi.iter().map(|v| v.norm_sqr()).sum::<f64>()
    }

    /// Run `steps` steps from t0 and the nodal values `initial` (ψ at the nodes
    /// [`Fourier::x`]). `observe(l, t_l, ψ_l)` sees every level, the initial one included.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite t0 (`t0`), initial values of the wrong
    /// length or not finite (`initial`), a density that is not of the form the scheme needs
    /// (`density`, `method`), or a step above the convergence limit of the stage iteration
    /// (`h`). During the run: [`Error::NonConvergence`] or [`Error::NonFinite`] with the
    /// step and its time.
    pub fn run(
        &mut self,
        t0: f64,
        initial: &[Complex64],
        steps: usize,
        mut observe: impl FnMut(usize, f64, &[Complex64]),
    ) -> Result<SpectralRun, Error> {
        require_finite("t0", t0)?;
        let modes = self.fourier.modes();
        if initial.len() != modes {
            return Err(Error::invalid(
                "initial",
                format!("{} values for {modes} nodes", initial.len()),
            ));
        }
        if let Some(j) = initial
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(Error::invalid(
                "initial",
                format!(
                    "the initial field is not finite at x = {:?}",
                    self.fourier.x(j)
                ),
            ));
        }
        let stages = self.gauss.as_ref().map_or(1, |g| g.stages);
        let mut work = Workspace {
            z: vec![Complex64::default(); stages * modes],
            rates: vec![Complex64::default(); stages * modes],
            correction: vec![Complex64::default(); stages * modes],
            stage: vec![Complex64::default(); modes],
            derivative: vec![Complex64::default(); modes],
            next: vec![Complex64::default(); modes],
        };
        let ffts_before = self.fourier.ffts();
        let mut current = initial.to_vec();
        self.check_structure(t0, &current, &mut work.derivative)?;
        let energy_initial = self.rate(t0, &current, &mut work.stage, &mut work.derivative);
        if self.gauss.is_some() {
            self.check_step(t0, &current, &mut work)?;
        }
        let norm_initial = self.norm(&current);
        let mut norm_error_max = 0.0f64;
        let mut iterations = 0;
        observe(0, t0, &current);
        for step in 0..steps {
            let t = t0 + step as f64 * self.h;
            if self.gauss.is_some() {
                iterations += self.gauss_step(step, t, &current, &mut work)?;
            } else {
                self.strang_step(t, &current, &mut work.next);
            }
            if !work
                .next
                .iter()
                .all(|v| v.re.is_finite() && v.im.is_finite())
            {
                return Err(Error::NonFinite {
                    what: "field".into(),
                    step,
                    t,
                });
            }
            std::mem::swap(&mut current, &mut work.next);
            norm_error_max = norm_error_max.max(
                (self.norm(&current) - norm_initial).abs() / norm_initial.max(f64::MIN_POSITIVE),
            );
            observe(step + 1, t0 + (step + 1) as f64 * self.h, &current);
        }
        let t_end = t0 + steps as f64 * self.h;
        let energy_final = self.rate(t_end, &current, &mut work.stage, &mut work.derivative);
        Ok(SpectralRun {
            last: current,
            norm_initial,
            norm_error_max,
            energy_initial,
            energy_final,
            ffts: self.fourier.ffts() - ffts_before,
            iterations,
        })
    }

    /// Refuse a step for which the stage iteration (exact on the linear part) cannot contract:
    /// h · 3ν ≥ 2, ν = max_j |N(ψ)_j| / |ψ_j| the size of the nonlinear part N = f − (linear
    /// part) on the initial field (3ν bounds its derivative for a cubic nonlinearity).
    fn check_step(&mut self, t: f64, psi: &[Complex64], work: &mut Workspace) -> Result<(), Error> {
        self.rate(t, psi, &mut work.next, &mut work.derivative);
        work.stage.copy_from_slice(psi);
        self.fourier.forward_in_place(&mut work.stage);
        for (value, omega) in work.stage.iter_mut().zip(&self.frequencies) {
            *value *= Complex64::new(0.0, -omega);
        }
        self.fourier.inverse_in_place(&mut work.stage);
        let floor = 1e-6 * max_abs(psi);
        let nu = psi
            .iter()
            .zip(work.next.iter().zip(&work.stage))
            .filter(|(v, _)| v.norm() > floor)
            .map(|(v, (f, linear))| (f - linear).norm() / v.norm())
            .fold(0.0, f64::max);
        if self.h * 3.0 * nu >= 2.0 {
            return Err(Error::invalid(
                "h",
                format!(
                    "{:?} is above the convergence limit 2/(3ν) = {:.3e} of the stage iteration \
                     (ν = {nu:.3e}, the size of the nonlinear part)",
                    self.h,
                    2.0 / (3.0 * nu)
                ),
            ));
        }
        Ok(())
    }

    /// One Gauss collocation step from `current` into `work.next`; returns the iterations.
    fn gauss_step(
        &mut self,
        step: usize,
        t: f64,
        current: &[Complex64],
        work: &mut Workspace,
    ) -> Result<usize, Error> {
        let modes = self.fourier.modes();
        let Some(gauss) = self.gauss.take() else {
            return Ok(0);
        };
        let s = gauss.stages;
        // The start: the previous collocation polynomial extrapolated (zero at the first step).
        if step == 0 {
            work.z.iter_mut().for_each(|z| *z = Complex64::default());
        } else {
            work.correction.copy_from_slice(&work.z);
            for m in 0..s {
                for n in 0..modes {
                    work.z[m * modes + n] = (0..s)
                        .map(|j| work.correction[j * modes + n] * gauss.extrapolation[m * s + j])
                        .sum();
                }
            }
        }
        let scale = 1.0 + max_abs(current);
        let mut result = Err(0.0);
        for iteration in 1..=self.options.max_iterations {
            for m in 0..s {
                let stage_z = &work.z[m * modes..(m + 1) * modes];
                for ((stage, value), z) in work.stage.iter_mut().zip(current).zip(stage_z) {
                    *stage = value + z;
                }
                let rates = &mut work.rates[m * modes..(m + 1) * modes];
                self.rate(
                    t + gauss.nodes[m] * self.h,
                    &work.stage,
                    rates,
                    &mut work.derivative,
                );
            }
            for m in 0..s {
                for n in 0..modes {
                    let sum: Complex64 = (0..s)
                        .map(|j| work.rates[j * modes + n] * gauss.a[m * s + j])
                        .sum();
                    work.correction[m * modes + n] = sum * self.h - work.z[m * modes + n];
                }
                self.fourier
                    .forward_in_place(&mut work.correction[m * modes..(m + 1) * modes]);
            }
            for n in 0..modes {
                let block = &gauss.preconditioner[n * s * s..(n + 1) * s * s];
                for (m, value) in work.stage.iter_mut().take(s).enumerate() {
                    *value = (0..s)
                        .map(|j| block[m * s + j] * work.correction[j * modes + n])
                        .sum();
                }
                for m in 0..s {
                    work.correction[m * modes + n] = work.stage[m];
                }
            }
            let mut increment = 0.0f64;
            for m in 0..s {
                let slice = &mut work.correction[m * modes..(m + 1) * modes];
                self.fourier.inverse_in_place(slice);
                for (z, dz) in work.z[m * modes..(m + 1) * modes]
                    .iter_mut()
                    .zip(slice.iter())
                {
                    *z += dz;
                    increment = increment.max(dz.norm());
                }
            }
            if !increment.is_finite() {
                result = Err(increment);
                break;
            }
            if increment <= self.options.tolerance * scale {
                result = Ok(iteration);
                break;
            }
            result = Err(increment);
        }
        let outcome = match result {
            Ok(iterations) => {
                for (n, (next, value)) in work.next.iter_mut().zip(current).enumerate() {
                    *next = value
                        + (0..s)
                            .map(|j| work.z[j * modes + n] * gauss.d[j])
                            .sum::<Complex64>();
                }
                Ok(iterations)
            }
            Err(residual) if residual.is_finite() => Err(Error::NonConvergence {
                step,
                t,
                iterations: self.options.max_iterations,
                residual,
            }),
            Err(_) => Err(Error::NonFinite {
                what: "stage values".into(),
                step,
                t,
            }),
        };
        self.gauss = Some(gauss);
        outcome
    }

    /// The phase rotation ψ ↦ ψ e^{iγ τ} of the local part over time `tau`, in place.
    fn rotate(&self, t: f64, tau: f64, psi: &mut [Complex64]) {
        let scale = 0.5 / self.symplectic;
        for (j, value) in psi.iter_mut().enumerate() {
            let squared = value.norm_sqr();
            if squared == 0.0 {
                continue;
            }
            let (g_u, _, _) =
                self.local_gradient(self.fourier.x(j), t, *value, Complex64::default(), false);
            // f_loc = (i/2c) G_u = iγψ: γ = Re(ψ̄ G_u)/(2c|ψ|²).
            let gamma = (value.conj() * g_u).re * scale / squared;
            *value *= Complex64::from_polar(1.0, gamma * tau);
        }
    }

    /// One Strang step from `current` into `next`: two FFTs.
    fn strang_step(&mut self, t: f64, current: &[Complex64], next: &mut [Complex64]) {
        let h = self.h;
        next.copy_from_slice(current);
        self.rotate(t, 0.5 * h, next);
        self.fourier.forward_in_place(next);
        for (value, phase) in next.iter_mut().zip(&self.propagator) {
            *value *= phase;
        }
        self.fourier.inverse_in_place(next);
        self.rotate(t + h, 0.5 * h, next);
    }
}
