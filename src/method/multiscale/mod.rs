//! Multiscale variational integrator: a Galerkin variational integrator whose function space
//! contains the fast oscillation, with the oscillatory action integrated by Filon–Lobatto
//! quadrature (Leok 2004, §5.7.2–5.7.3).
//!
//! # Function space
//!
//! On a step [t_k, t_k + h], t = t_k + (h/2)(1 + x), x ∈ [−1, 1], with the fast phase
//! ψ = ω(t − t_k) = θ(x + 1), θ = hω/2, every coordinate is (§5.7.3: "a function space with
//! both polynomials and oscillatory functions, applied to all the variables")
//!
//! ```text
//! q(x) = Σ_{ν=0}^{s} Z_ν l_ν(x) + Σ_{e=0}^{d} (A_e φ^A_e(x) + B_e φ^B_e(x)),
//! φ^A_e = sin ψ · xᵉ − sin 2θ · l_s(x),   φ^B_e = (cos ψ − 1) xᵉ − (cos 2θ − 1) l_s(x),
//! ```
//!
//! with l_ν the Lagrange basis on the s + 1 Chebyshev–Gauss–Lobatto points. The oscillatory
//! functions vanish at both ends, so q(−1) = Z_0 and q(1) = Z_s, and the space is the
//! polynomials of degree s plus sin ωt and cos ωt times polynomial envelopes of degree d.
//! This is §5.7.2's (Σⱼ pⱼ tʲ)(1 + a₀ sin ωt + a₁ cos ωt) made linear in its unknowns (the
//! product form is singular where Σ pⱼ tʲ = 0, e.g. at zero spring extension): its
//! oscillation amplitude P(t)a₀ becomes the envelope Σ A_e xᵉ. Fixing Z_0 = q_k eliminates
//! §5.7.2's continuity multiplier λ_k, which becomes the momentum −p_{k+1} (below).
//!
//! # Discrete action
//!
//! Along the curve L(t, q, q̇) is L̃(x, ψ) at ψ = θ(x + 1), where L̃(x, ψ) = L(t, Q, Q̇) for
//! Q(x, ψ) = the formula above with ψ free and Q̇ = (2/h) ∂ₓQ + ω ∂_ψQ. L̃ is 2π-periodic in ψ
//! and smooth in x. Its harmonics F_m(x) = (1/K) Σ_κ L̃(x, ψ_κ) e^{−imψ_κ}, ψ_κ = 2πκ/K,
//! K = 2M + 1 (exact when L̃ has no harmonic above M; the spring pendulum's L is quadratic in
//! the spring extension, so its fast part has harmonics 0, ±1, ±2), are integrated against
//! e^{imψ} = e^{imθ} e^{imθx} by the n-node Filon–Lobatto rule ([`crate::spectral::filon`])
//! with weights W_j(mθ) = C_j + i S_j:
//!
//! ```text
//! S_d = (h/2) Σ_j Σ_κ Ω_jκ L̃(x_j, ψ_κ),
//! Ω_jκ = (1/K) [C_j(0) + 2 Σ_{m=1}^{M} (C_j(mθ) cos α − S_j(mθ) sin α)],  α = m(θ − ψ_κ).
//! ```
//!
//! So the action is a weighted sum over the n·K points (x_j, ψ_κ), like SVI's quadrature
//! sum, with weights Ω (Σ_κ Ω_jκ = ρ_j, the Lobatto weights) that depend on hω.
//!
//! # Update map
//!
//! With all unknowns c = (Z_1, …, Z_s, A, B) and g_b = ∂S_d/∂c_b
//! = (h/2) Σ_{jκ} Ω_jκ [∂L/∂q · φ_b + ∂L/∂q̇ · φ̇_b](x_j, ψ_κ), stationarity of the augmented
//! action Σ_k S_d(c_k) + Σ_k λ_k (q_k(1) − q_{k+1}(−1)) in the unknowns of each step, and in
//! the shared node Z_0, gives with p_k = −∂S_d/∂Z_0 (= λ_{k−1}):
//!
//! ```text
//! −p_k = g_0,   0 = g_b (b = 1, …, s − 1 and every oscillatory b),   p_{k+1} = g_s,
//! q_{k+1} = Z_s,
//! ```
//!
//! the discrete Hamiltonian map (q_k, p_k) ↦ (q_{k+1}, p_{k+1}). The unknowns are solved for
//! by the simplified Newton method (Hairer & Wanner, *Solving ODEs II*, §IV.8): the Jacobian,
//! from the Hessian blocks of L at the n·K points, is factorised at a cold start and whenever
//! the contraction rate exceeds 0.4, and kept across steps otherwise; the residuals need only
//! ∂L/∂q and ∂L/∂q̇. A warm step starts from the last step's curve continued over the next
//! one (`Tables::extrapolate`).
//! Since Σ_ν l_ν = 1 and the oscillatory g_b vanish, p_{k+1} − p_k = g_0 + g_s =
//! (h/2) Σ Ω_jκ ∂L/∂q(x_j, ψ_κ), computed without cancellation.
//!
//! # Frequency
//!
//! ω is [`Multiscale::frequency`] if given, else estimated at the first step from the
//! linearisation at the initial state: the largest ω² of K x = ω² M x with M = L_q̇q̇ and
//! K = −L_qq (by automatic differentiation), by power iteration on M⁻¹K (no allocation; it
//! converges at the rate of the scale ratio). It is then fixed for the run (§5.7.2 lists ω
//! among the unknowns; tracking it is not implemented).
//!
//! # Properties
//! - order: nominally that of the polynomial part, 2s, for the slow motion at fixed hω (not
//!   verified by a convergence test; the oscillatory part's error is governed by the Filon
//!   rule, O(θ⁻²) in the large-θ regime);
//! - symmetric: not claimed (the trigonometric quadrature in ψ is exact only up to aliasing,
//!   and its grid is not reflected onto itself);
//! - symplectic: yes, for the fixed ω of a run (a variational integrator of a fixed discrete
//!   Lagrangian).
//!
//! Needs hω ≫ 1: for small θ the oscillatory functions approach polynomials already in the
//! space and the Newton matrix becomes ill-conditioned (harmonic oscillator ω = 1, 4 points,
//! one step from (1, 0): no convergence in 50 Newton iterations for hω ≤ 1, 35 iterations at
//! hω = 2, against 4 per step on the stiff spring pendulum at hω ≈ 31). External forces are
//! not supported.
//!
//! # References
//! M. Leok, *Generalized Variational Integrators*, ch. 5 of *Foundations of Computational
//! Geometric Mechanics*, PhD thesis, Caltech (2004), §5.7.2 (function space, Filon–Lobatto
//! quadrature, augmented discrete action) and §5.7.3; A. Iserles, *On the numerical
//! quadrature of highly-oscillating integrals I: Fourier transforms*, IMA J. Numer. Anal.
//! (2004).

mod tables;

use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure};
use crate::linalg::invert_small;
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::derived::{LagrangianExt, SecondDerivatives};
use crate::nonlinear::{Jacobian, Newton};
use crate::spectral::{MAX_POINTS, check_points};
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};
use tables::Tables;

/// Relative size of a non-decreasing Newton increment that counts as round-off. The Newton
/// matrix's condition grows as hω falls (the oscillatory functions approach polynomials of
/// the space), and with it the round-off level of the unknowns: on the harmonic oscillator
/// with hω = 2.5 and 3 points the increments bounce between 1e-11 and 5e-10 of the unknowns.
const STALLED_INCREMENT: f64 = 1e-9;

/// Contraction rate above which the simplified Newton iteration refactorises. A Jacobian
/// costs the Hessian blocks of L at every point, several residuals' worth. On the stiff
/// spring pendulum (6 points, h = 0.31, T = 100; callgrind): 0.4 takes 126 M instructions,
/// 0.25 141 M, the library's default 0.03 155 M; 0.6 took 109 M but at T = 650 (h = 1/3)
/// iterated 50 times at a rate of 0.56 without reaching round-off.
const REFACTOR_CONTRACTION: f64 = 0.4;

/// Options of the multiscale variational integrator.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Multiscale {
    /// Chebyshev–Gauss–Lobatto points s + 1 of the polynomial part (degree s ≥ 1).
    pub points: usize,
    /// Degree d of the envelopes of sin ωt and cos ωt.
    pub envelope: usize,
    /// Filon–Lobatto nodes n of the action integral (in x); `None`: `points` + 2.
    pub filon: Option<usize>,
    /// Highest harmonic M of the fast phase resolved in the action (K = 2M + 1 phase points).
    pub harmonics: usize,
    /// The fast angular frequency ω; `None`: estimated from the linearisation at the first
    /// step.
    pub frequency: Option<f64>,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for Multiscale {
    /// 4 points (degree 3), linear envelopes, 6 Filon nodes, harmonics up to 2 (exact for a
    /// Lagrangian quadratic in the oscillating coordinates), ω estimated.
    fn default() -> Self {
        Multiscale {
            points: 4,
            envelope: 1,
            filon: None,
            harmonics: 2,
            frequency: None,
            max_iterations: 50,
        }
    }
}

impl Multiscale {
    /// The method with `points` CGL points and the other defaults.
    pub fn new(points: usize) -> Self {
        Multiscale {
            points,
            ..Multiscale::default()
        }
    }

    /// Use the fast angular frequency `frequency` instead of estimating it.
    pub fn with_frequency(mut self, frequency: f64) -> Self {
        self.frequency = Some(frequency);
        self
    }

    /// Use envelopes of degree `envelope`.
    pub fn with_envelope(mut self, envelope: usize) -> Self {
        self.envelope = envelope;
        self
    }

    /// Resolve harmonics up to `harmonics` of the fast phase.
    pub fn with_harmonics(mut self, harmonics: usize) -> Self {
        self.harmonics = harmonics;
        self
    }

    /// Use `filon` Filon–Lobatto nodes.
    pub fn with_filon(mut self, filon: usize) -> Self {
        self.filon = Some(filon);
        self
    }

    /// The number of Filon–Lobatto nodes in use.
    pub fn filon_points(&self) -> usize {
        self.filon
            .unwrap_or(self.points.saturating_add(2).min(MAX_POINTS))
    }

    fn validate(&self) -> Result<(), Error> {
        check_points(self.points)?;
        let n = self.filon_points();
        if !(2..=MAX_POINTS).contains(&n) {
            return Err(Error::invalid(
                "filon",
                format!("{n} Filon–Lobatto nodes; need 2 to {MAX_POINTS}"),
            ));
        }
        if self.envelope >= self.points {
            return Err(Error::invalid(
                "envelope",
                format!(
                    "envelope degree {} for {} points; must be below the number of points",
                    self.envelope, self.points
                ),
            ));
        }
        if !(1..=32).contains(&self.harmonics) {
            return Err(Error::invalid(
                "harmonics",
                format!("{} harmonics; need 1 to 32", self.harmonics),
            ));
        }
        if let Some(omega) = self.frequency {
            crate::error::require_positive("frequency", omega)?;
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        Ok(())
    }
}

/// Buffers of a multiscale run.
#[derive(Debug, Clone)]
pub struct MultiscaleWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    tables: Tables,
    /// Unknowns: offsets Z_ν − q_k (ν = 1..s), then the amplitudes A_e, B_e (N each).
    unknowns: DVector<f64>,
    /// Whether `unknowns` holds the last converged step (a warm start).
    warm: bool,
    /// Scratch of the size of `unknowns` (the extrapolated starting values).
    previous: DVector<f64>,
    /// Second derivatives of L at the quadrature points.
    derivatives: Vec<SecondDerivatives<N>>,
    newton: Newton,
    /// The fast frequency of the run, once known.
    omega: Option<f64>,
}

impl<N: Dimension> MultiscaleWorkspace<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The fast angular frequency ω in use (after the first step, or as given).
    pub fn frequency(&self) -> Option<f64> {
        self.omega
    }
}

/// The largest ω² of K x = ω² M x, M = L_q̇q̇, K = −L_qq at (t, q, q̇), by power iteration on
/// M⁻¹K; `None` if M is singular or no positive ω² dominates.
fn fast_frequency<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    t: f64,
    q: &OVector<f64, N>,
    v: &OVector<f64, N>,
) -> Option<f64>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let d = model.second_derivatives(t, q, v);
    let stiffness: OMatrix<f64, N, N> = -d.qq;
    let operator = invert_small(&d.vv)? * &stiffness;
    let mut x = OVector::<f64, N>::from_element_generic(q.shape_generic().0, U1, 1.0);
    let mut estimate = f64::NAN;
    for _ in 0..500 {
        let y = &operator * &x;
        let norm = y.amax();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        x = y / norm;
        // Rayleigh quotient of the symmetric pencil (K, M).
        let next = x.dot(&(&stiffness * &x)) / x.dot(&(&d.vv * &x));
        if (next - estimate).abs() <= 1e-14 * next.abs() {
            estimate = next;
            break;
        }
        estimate = next;
    }
    (estimate.is_finite() && estimate > 0.0).then(|| estimate.sqrt())
}

/// Residual of the stationarity conditions and, when `jacobian` is `Some`, its Jacobian in
/// the unknowns (the residual alone needs only the first derivatives of L: ∂L/∂q and ∂L/∂q̇
/// at each point, while the Jacobian needs the Hessian blocks).
#[allow(clippy::too_many_arguments)]
fn assemble<L: Lagrangian<N>, N: Dimension>(
    model: &L,
    tables: &Tables,
    derivatives: &mut [SecondDerivatives<N>],
    t: f64,
    state: &State<N>,
    z: &DVector<f64>,
    jacobian: Option<&mut DMatrix<f64>>,
    residual: &mut DVector<f64>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = state.dimension();
    let size = n.value();
    let count = tables.basis;
    let unknowns = count - 1;
    for (p, point) in derivatives.iter_mut().enumerate() {
        let (q, v) = tables.point(p, &state.q, z);
        let time = tables.time(t, p);
        if jacobian.is_some() {
            *point = model.second_derivatives(time, &q, &v);
        } else {
            // Only ∂L/∂q and ∂L/∂q̇ are read below; the Hessian blocks are stale.
            let first = model.first_derivatives(time, &q, &v);
            point.q = first.q;
            point.v = first.v;
        }
    }
    residual.fill(0.0);
    residual
        .generic_view_mut((0, 0), (n, U1))
        .copy_from(&state.y);
    for (p, d) in derivatives.iter().enumerate() {
        let w = tables.weights[p];
        let value = &tables.point_values[p * count..(p + 1) * count];
        let rate = &tables.point_rates[p * count..(p + 1) * count];
        for r in 0..unknowns {
            let b = tables.row_basis(r);
            let mut row = residual.generic_view_mut((r * size, 0), (n, U1));
            row += (&d.q * value[b] + &d.v * rate[b]) * w;
        }
    }
    let Some(jacobian) = jacobian else {
        return;
    };
    jacobian.fill(0.0);
    for (p, d) in derivatives.iter().enumerate() {
        let w = tables.weights[p];
        let value = &tables.point_values[p * count..(p + 1) * count];
        let rate = &tables.point_rates[p * count..(p + 1) * count];
        let qv_t = d.qv.transpose();
        for c in 0..unknowns {
            let bc = tables.column_basis(c);
            let from_q: OMatrix<f64, N, N> = (&d.qq * value[bc] + &d.qv * rate[bc]) * w;
            let from_v: OMatrix<f64, N, N> = (&qv_t * value[bc] + &d.vv * rate[bc]) * w;
            for r in 0..unknowns {
                let b = tables.row_basis(r);
                let block = &from_q * value[b] + &from_v * rate[b];
                let mut target = jacobian.generic_view_mut((r * size, c * size), (n, n));
                target += block;
            }
        }
    }
}

impl<N: Dimension> Method<N> for Multiscale
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;

    type Workspace = MultiscaleWorkspace<N>;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "multiscale",
            order: self.points.saturating_sub(1).saturating_mul(2),
            symmetric: false,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Lagrange,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<MultiscaleWorkspace<N>, Error> {
        self.validate()?;
        crate::error::require_positive("h", h)?;
        if L::FORCED {
            return Err(Error::invalid(
                "method",
                "multiscale does not support external forces (Lagrange–d'Alembert)",
            ));
        }
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        let tables = Tables::new(self)?;
        let size = (tables.basis - 1) * n.value();
        Ok(MultiscaleWorkspace {
            derivatives: vec![SecondDerivatives::zeros(n); tables.points()],
            tables,
            unknowns: DVector::zeros(size),
            previous: DVector::zeros(size),
            warm: false,
            newton: Newton::new(size, self.max_iterations)
                .with_noise(STALLED_INCREMENT)
                .with_refactor(REFACTOR_CONTRACTION),
            omega: self.frequency,
        })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut MultiscaleWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let ws = workspace;
        let n = state.dimension();
        let size = n.value();
        // A cold start (first step, new h, after a restart) needs the velocity: the inverse
        // Legendre map, solved only then.
        let cold = !ws.warm || ws.omega.is_none() || ws.tables.h != h;
        let velocity = if cold {
            model
                .velocity(t, &state.q, &state.y, &state.y)
                .map_err(|_| StepFailure::NonFinite)?
        } else {
            OVector::zeros_generic(n, U1)
        };
        let omega = match ws.omega {
            Some(omega) => omega,
            None => {
                let omega = fast_frequency(model, t, &state.q, &velocity)
                    .ok_or(StepFailure::SingularMatrix)?;
                ws.omega = Some(omega);
                omega
            }
        };
        if ws.tables.h != h || ws.tables.omega != omega {
            ws.tables.rebuild(h, omega);
            ws.warm = false;
            ws.newton.invalidate();
        }
        let s = ws.tables.degree;
        if ws.warm {
            ws.tables.extrapolate(n, &ws.unknowns, &mut ws.previous);
            std::mem::swap(&mut ws.unknowns, &mut ws.previous);
        } else {
            // Uniform motion with the initial velocity, no oscillation.
            ws.unknowns.fill(0.0);
            for nu in 1..=s {
                let offset = &velocity * (0.5 * h * (ws.tables.nodes[nu] + 1.0));
                ws.unknowns
                    .generic_view_mut(((nu - 1) * size, 0), (n, U1))
                    .copy_from(&offset);
            }
        }
        // Warm: the simplified Newton method, with the factors kept across steps. Cold: the
        // starting values are far off, and the Jacobian at them would not contract.
        let jacobian = if ws.warm {
            Jacobian::Kept
        } else {
            Jacobian::Exact
        };
        // The offsets and amplitudes build positions of the size of q_k.
        ws.newton.set_scale_floor(state.q.amax());
        let tables = &ws.tables;
        let derivatives = &mut ws.derivatives;
        let solved = ws
            .newton
            .iterate(&mut ws.unknowns, jacobian, |z, jacobian, residual| {
                assemble(model, tables, derivatives, t, state, z, jacobian, residual)
            })
            .inspect_err(|_| ws.warm = false)?;
        let mut dp = OVector::<f64, N>::zeros_generic(n, U1);
        for p in 0..tables.points() {
            let (q, v) = tables.point(p, &state.q, &ws.unknowns);
            dp += model.force(tables.time(t, p), &q, &v) * tables.weights[p];
        }
        increment
            .q
            .copy_from(&ws.unknowns.generic_view(((s - 1) * size, 0), (n, U1)));
        increment.y = dp;
        ws.warm = true;
        Ok(StepReport {
            iterations: solved.iterations,
            evaluations: tables.points() * (solved.iterations + 1),
            factorizations: solved.factorizations,
            analyses: 0,
        })
    }

    fn restart(&self, workspace: &mut MultiscaleWorkspace<N>) {
        workspace.warm = false;
        workspace.newton.invalidate();
    }

    /// The step and its exact Jacobian by the implicit function theorem: with H the full
    /// block Hessian ∂g_b/∂c_{b′} over all basis functions (Z_0 = q_k included) at the
    /// converged step, the unknowns move by dc = −J⁻¹ (H_{·0} dq_k + E_0 dp_k), J the
    /// Newton matrix, E_0 the unit block of the equation −p_k = g_0; then dq_{k+1} = dZ_s
    /// and dp_{k+1} = H_{s0} dq_k + H_{s·} dc.
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut MultiscaleWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let n = state.dimension();
        let dimension = n.value();
        let mut increment = State::zeros(n);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let tables = &workspace.tables;
        let count = tables.basis;
        let s = tables.degree;
        let mut hessian = DMatrix::<f64>::zeros(count * dimension, count * dimension);
        for p in 0..tables.points() {
            let (q, v) = tables.point(p, &state.q, &workspace.unknowns);
            let d = model.second_derivatives(tables.time(t, p), &q, &v);
            let w = tables.weights[p];
            let value = &tables.point_values[p * count..(p + 1) * count];
            let rate = &tables.point_rates[p * count..(p + 1) * count];
            for c in 0..count {
                let from_q: OMatrix<f64, N, N> = (&d.qq * value[c] + &d.qv * rate[c]) * w;
                let from_v: OMatrix<f64, N, N> =
                    (d.qv.transpose() * value[c] + &d.vv * rate[c]) * w;
                for r in 0..count {
                    let mut target =
                        hessian.generic_view_mut((r * dimension, c * dimension), (n, n));
                    target += &from_q * value[r] + &from_v * rate[r];
                }
            }
        }
        let unknowns = count - 1;
        let size = unknowns * dimension;
        let mut lu = crate::linalg::DenseLu::new(size);
        let mut sensitivity = DMatrix::<f64>::zeros(size, 2 * dimension);
        for r in 0..unknowns {
            let row = tables.row_basis(r);
            for c in 0..unknowns {
                let column = tables.column_basis(c);
                lu.matrix_mut()
                    .generic_view_mut((r * dimension, c * dimension), (n, n))
                    .copy_from(
                        &hessian.generic_view((row * dimension, column * dimension), (n, n)),
                    );
            }
            sensitivity
                .generic_view_mut((r * dimension, 0), (n, n))
                .copy_from(&(-hessian.generic_view((row * dimension, 0), (n, n))));
        }
        for i in 0..dimension {
            sensitivity[(i, dimension + i)] = -1.0;
        }
        lu.factor().map_err(|_| StepFailure::SingularMatrix)?;
        lu.solve_columns_in_place(&mut sensitivity);
        // Z_s is unknown column s − 1: its rows of the sensitivity are dq_{k+1}.
        let last = sensitivity.view(((s - 1) * dimension, 0), (dimension, 2 * dimension));
        let mut momentum = DMatrix::<f64>::zeros(dimension, 2 * dimension);
        for c in 0..unknowns {
            let column = tables.column_basis(c);
            momentum += hessian.view((s * dimension, column * dimension), (dimension, dimension))
                * sensitivity.view((c * dimension, 0), (dimension, 2 * dimension));
        }
        let mut from_q0 = momentum.view_mut((0, 0), (dimension, dimension));
        from_q0 += hessian.view((s * dimension, 0), (dimension, dimension));
        let tangent = TangentMap {
            qq: last.generic_view((0, 0), (n, n)).into_owned(),
            qy: last.generic_view((0, dimension), (n, n)).into_owned(),
            yq: momentum.generic_view((0, 0), (n, n)).into_owned(),
            yy: momentum.generic_view((0, dimension), (n, n)).into_owned(),
        };
        Ok((increment, tangent, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_models::{Damped, HenonHeiles, Oscillator, VariableMass, advance, state};
    use nalgebra::SVector;

    /// The harmonic oscillator's solution cos t lies in the function space, and along it the
    /// integrands of the stationarity conditions, (−q φ_b + q̇ φ̇_b)(x, ψ), are trigonometric
    /// polynomials of degree 2 in ψ (M = 2 harmonics) with coefficients of degree ≤ s = 2 in x
    /// (n = 5 Filon nodes integrate them exactly), so the exact solution solves the discrete
    /// equations for any h: (cos t, −sin t) to round-off after 10 steps of up to 2.2 periods
    /// each. (With n = 2 Filon nodes the error is 1.9, with M = 1 harmonic 4e4.)
    #[test]
    fn oscillator_is_exact_for_steps_of_several_periods() {
        let method = Multiscale::new(3);
        for h in [2.5, 7.0, 14.0] {
            let (end, workspace) =
                advance(&method, &Oscillator::<false>, h, 10, state([1.0], [0.0]));
            let t = 10.0 * h;
            let error = (end.q[0] - t.cos()).abs().max((end.y[0] + t.sin()).abs());
            assert_eq!(workspace.frequency(), Some(1.0));
            assert!(error <= 1e-12, "h = {h}: error {error:e}");
        }
    }

    /// ω² is the largest eigenvalue of K x = ω² M x: for Hénon–Heiles at q = 0, M = [[2, 1],
    /// [1, 3]] and K = I, so ω² = 1/λ_min(M) = 2/(5 − √5).
    #[test]
    fn frequency_from_the_linearisation() {
        let omega = fast_frequency(
            &HenonHeiles::<false>,
            0.0,
            &SVector::zeros(),
            &SVector::zeros(),
        )
        .unwrap();
        let exact = (2.0 / (5.0 - 5f64.sqrt())).sqrt();
        assert!((omega - exact).abs() <= 1e-14, "{omega} vs {exact}");
        // An inverted oscillator has no positive ω².
        struct Inverted;
        impl Lagrangian<nalgebra::U1> for Inverted {
            fn lagrangian<D: crate::scalar::Scalar>(
                &self,
                _t: D,
                q: &SVector<D, 1>,
                v: &SVector<D, 1>,
            ) -> D {
                (v[0] * v[0] + q[0] * q[0]) * 0.5
            }
        }
        assert_eq!(
            fast_frequency(&Inverted, 0.0, &SVector::zeros(), &SVector::zeros()),
            None
        );
    }

    /// The tangent map is symplectic (ΦᵀJΦ = J) and matches central differences of the step,
    /// on a model with a configuration-dependent mass matrix.
    #[test]
    fn tangent_map_is_symplectic_and_matches_differences() {
        let method = Multiscale::new(4).with_frequency(3.0);
        let model = VariableMass;
        let h = 2.0;
        let start = state([0.3, -0.2], [0.1, 0.4]);
        let mut workspace = method.workspace(&model, h).unwrap();
        let (_, tangent, _) = method
            .tangent_map(&model, &mut workspace, 0.0, h, &start)
            .unwrap();
        let symplectic = tangent.symplecticity_error();
        assert!(symplectic <= 1e-10, "ΦᵀJΦ − J: {symplectic:e}");
        let phi = tangent.matrix();
        let delta = 1e-6;
        for j in 0..4 {
            let shifted = |sign: f64| {
                let mut x = start;
                if j < 2 {
                    x.q[j] += sign * delta;
                } else {
                    x.y[j - 2] += sign * delta;
                }
                advance(&method, &model, h, 1, x).0
            };
            let (plus, minus) = (shifted(1.0), shifted(-1.0));
            for i in 0..4 {
                let difference = if i < 2 {
                    (plus.q[i] - minus.q[i]) / (2.0 * delta)
                } else {
                    (plus.y[i - 2] - minus.y[i - 2]) / (2.0 * delta)
                };
                assert!(
                    (difference - phi[(i, j)]).abs() <= 1e-7 * (1.0 + difference.abs()),
                    "({i}, {j}): {difference} vs {}",
                    phi[(i, j)]
                );
            }
        }
    }

    #[test]
    fn invalid_options_are_typed_errors() {
        let name = |method: Multiscale| match Method::<U1>::workspace(
            &method,
            &Oscillator::<false>,
            1.0,
        ) {
            Err(Error::InvalidParameter { name, .. }) => name,
            other => panic!("expected InvalidParameter, got {other:?}"),
        };
        assert_eq!(name(Multiscale::new(1)), "points");
        assert_eq!(name(Multiscale::new(3).with_filon(1)), "filon");
        assert_eq!(name(Multiscale::new(3).with_envelope(3)), "envelope");
        assert_eq!(name(Multiscale::new(3).with_harmonics(0)), "harmonics");
        assert_eq!(
            name(Multiscale::new(3).with_frequency(f64::NAN)),
            "frequency"
        );
        assert_eq!(name(Multiscale::new(3).with_frequency(-1.0)), "frequency");
        assert!(matches!(
            Method::<U1>::workspace(&Multiscale::default(), &Oscillator::<false>, 0.0),
            Err(Error::InvalidParameter { ref name, .. }) if name == "h"
        ));
        assert!(matches!(
            Method::<U1>::workspace(&Multiscale::default(), &Damped::<false> { c: 0.1 }, 1.0),
            Err(Error::InvalidParameter { ref name, .. }) if name == "method"
        ));
    }
}
