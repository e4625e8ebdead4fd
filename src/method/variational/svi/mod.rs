//! Galerkin spectral variational integrators (SVI).
//!
//! # Discrete equations
//! On each step [t, t + h] the curve is a polynomial of degree s through s + 1
//! Chebyshev–Gauss–Lobatto (CGL) nodes, q(τ) = Σ_ν qᵛ l_ν(τ), τ ∈ [−1, 1], and the action is
//! approximated by m-point Gauss–Legendre quadrature (Li, Wu, Leok 2018, eq. 6):
//!
//! L_d(q⁰, …, qˢ) = (h/2) Σ_μ w_μ L(t_μ, Σ_ν qᵛ l_ν(τ_μ), (2/h) Σ_ν qᵛ l̇_ν(τ_μ)).
//!
//! With g_ν = ∂L_d/∂qᵛ = Σ_μ w_μ [(h/2) l_ν(τ_μ) ∂L/∂q + l̇_ν(τ_μ) ∂L/∂q̇] the step
//! (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) solves (eqs. 8a–8c)
//!
//! −p_k = g_0,  0 = g_ν (ν = 1, …, s − 1),  p_{k+1} = g_s,  with q⁰ = q_k, q_{k+1} = qˢ.
//!
//! With an external force f_L ([`crate::Lagrangian::FORCED`], the Lagrange–d'Alembert
//! principle) the discrete forces come from the same quadrature, weighted by the basis
//! functions: f_ν = Σ_μ (h/2) w_μ l_ν(τ_μ) f_L(t_μ, q(τ_μ), q̇(τ_μ)), and the equations read
//!
//! −p_k = g_0 + f_0,  0 = g_ν + f_ν,  p_{k+1} = g_s + f_s.
//!
//! The unknowns q¹, …, qˢ (s·N numbers) are found by Newton's method with the Jacobian
//! ∂g_ν/∂qʲ (+ ∂f_ν/∂qʲ), assembled from the per-point Hessian blocks L_qq, L_qv, L_vv of L
//! and the force Jacobian ∂f_L/∂q, ∂f_L/∂q̇ (never from (s·N)-sized dual numbers): by
//! default the simplified Newton method, which keeps the factorised Jacobian across
//! iterations and steps while the iteration contracts well and otherwise needs only the
//! residual (first derivatives of L), or with [`Solver::Newton`] the exact Jacobian at every
//! iteration (`crate::nonlinear`). A constant mass matrix takes the fixed-point iteration
//! below instead. The iteration starts from the previous step's polynomial extrapolated to
//! the new nodes and runs to round-off. The unknowns are kept as offsets
//! qᵛ − q_k so that the stepping loop can add the increment with compensated summation.
//! The momentum increment is computed without cancellation: summing all g_ν and using
//! Σ_ν l_ν = 1, Σ_ν l̇_ν = 0 and the internal-stage conditions (8b),
//!
//! p_{k+1} − p_k = g_s + g_0 = Σ_μ (h/2) w_μ ∂L/∂q(τ_μ)   (+ Σ_μ (h/2) w_μ f_L(τ_μ) when forced)
//!
//! (the discrete momentum balance; for m = s it is the Nyström update of Gauss–Legendre),
//! whereas g_0 + g_s term by term cancels O(|p|) contributions every step. For the same
//! reason Newton's residual is written relative to p_k: since Σ_μ w_μ l̇_ν(τ_μ) = δ_νs − δ_ν0
//! exactly, rows ν < s of (8a)–(8b) read Σ_μ w_μ [(h/2) l_ν(τ_μ) ∂L/∂q + l̇_ν(τ_μ) (∂L/∂q̇ − p_k)]
//! = 0, and with a constant mass matrix the end point is taken from the converged forces,
//! q_{k+1} − q_k = h M⁻¹p_k + h² M⁻¹ Σ_μ P_sμ ∂L/∂q(τ_μ), as in the fixed-point iteration
//! below. (Summing the O(|p|) terms through the differentiation weights left Newton's
//! energy error random-walking 5–10 times faster than the fixed point's: Kepler, T = 2000,
//! median final errors 4e-11 to 1e-10 against 6e-12.)
//!
//! # Adjoint
//! The discrete adjoint ([`crate::Integrator::gradient`]) applies the transpose of each
//! step's tangent map Φ to a covector λ. On a constant-mass unforced model a step keeps only
//! P_μ = (h/2) w_μ ∂²L/∂q² at its quadrature points and hM⁻¹P_μ
//! ([`crate::StepAdjoint::Stages`]). The step's fixed-point form on the positions at the
//! quadrature points is Q_μ = q + c'_μ hM⁻¹p + Σ_ν K_μν hM⁻¹P̃_ν with P̃_ν = (h/2) w_ν ∂L/∂q(Q_ν),
//! p' = p + Σ_ν P̃_ν and q' = q + hM⁻¹p + Σ_ν d_ν hM⁻¹P̃_ν (Nyström coefficients c', d, K);
//! linearised,
//! Φᵀλ = (λ_q + Σ_μ z_μ, λ_p + hM⁻¹λ_q + hM⁻¹ Σ_μ c'_μ z_μ), where z solves
//! z_ν = P_νᵀ(λ_p + d_ν hM⁻¹λ_q) + (hM⁻¹P_ν)ᵀ Σ_μ K_μν z_μ, the transpose of the step's own
//! iteration, solved the same way. No Jacobian is assembled or factorised; every other model
//! keeps the tangent map.
//!
//! # Properties
//! - order min(2s, 2m) (Galerkin variational error analysis; with m = s Gauss points the SVI
//!   is the s-stage Gauss–Legendre collocation method, order 2s);
//! - symmetric: yes (symmetric nodes and quadrature);
//! - symplectic: yes (a variational integrator), and it conserves the Noether momenta of
//!   symmetries of L that act linearly on q (discrete Noether theorem). With an external
//!   force the step is the discrete Lagrange–d'Alembert map, which is not symplectic (it
//!   dissipates or injects energy as the force does); its order is unchanged.
//!
//! # References
//! Li, Wu, Leok, *Construction and comparison of multidimensional spectral variational
//! integrators and spectral collocation methods* (2018), §2, eqs. (6)–(11); Hall & Leok,
//! *Spectral variational integrators* (2015); forced systems: Marsden & West, *Discrete
//! mechanics and variational integrators*, Acta Numerica (2001), §3.2 (discrete
//! Lagrange–d'Alembert principle), Porcù & Penati (OctConf 2013), "Forced mechanics".

mod adjoint;
mod constant_mass;
mod fixed_point;
mod newton;
mod workspace;

pub use workspace::SviWorkspace;
use workspace::TangentBuffers;

use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::error::StepFailure;
use crate::linalg::sparse::LinearSolverKind;
use crate::method::Method;
use crate::method::adjoint::{
    StepAdjoint, adjoint_by_tangent_map, apply_tangent_map, compose_tangent_map,
};
use crate::method::variational::stage_newton::LazyStageNewton;
use crate::method::variational::tables::Tables;
use crate::method::{Coordinates, Equations, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::Structure;
use crate::model::derived::sparse_terms;
use crate::model::derived::{ForceJacobian, LagrangianExt, cached_mass_inverse};
use crate::model::legendre::LazyLegendre;
use crate::model::term_pattern::check_width;
use crate::nonlinear::{Jacobian, Newton, after_fixed_point};
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::starting_values::StartingValues;
use crate::spectral::{MAX_POINTS, Scratch, check_options};
use constant_mass::ConstantMass;
use fixed_point::fixed_point_step;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};
use newton::solve;
use std::ops::ControlFlow;

/// Options of the spectral variational integrator.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Svi {
    /// Number of Chebyshev–Gauss–Lobatto points s + 1 (polynomial degree s), at least 2.
    pub points: usize,
    /// Number of Gauss–Legendre points m, at least 1; `None` means 2 · `points` as in the
    /// paper's experiments, at most [`MAX_POINTS`].
    pub quadrature: Option<usize>,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
    /// How the stage equations (8a)–(8b) are solved.
    pub solver: Solver,
    /// The linear solver of sparse Newton, which solves the stage equations of an unforced sum
    /// of local terms of run-time size ([`Lagrangian::terms`]); every other model takes svi's
    /// dense LU. The default, [`LinearSolverKind::Auto`], factors small dense patterns (an
    /// N-body system) densely and the others by faer's sparse LU.
    pub linear_solver: LinearSolverKind,
}

/// How SVI solves its stage equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// The fixed-point iteration for a constant mass matrix (Newton where it fails), else
    /// the simplified Newton method, whose factorised Jacobian is kept across iterations and
    /// steps while the iteration contracts by at least a factor 1/0.03 (registry name
    /// `svi`). On the double pendulum it factorises once every 3 steps at h = 0.01 and costs
    /// 10–20 % fewer instructions than [`Solver::Newton`] with 6 or 7 points.
    #[default]
    Auto,
    /// Newton's method with the exact Jacobian at every iteration, for every model
    /// (registry name `svi-newton`).
    Newton,
}

impl Default for Svi {
    fn default() -> Self {
        Svi {
            points: 6,
            quadrature: None,
            max_iterations: 50,
            solver: Solver::Auto,
            linear_solver: LinearSolverKind::Auto,
        }
    }
}

impl Svi {
    /// SVI with `points` CGL points and the default quadrature (2 · `points` Gauss points, at
    /// most [`MAX_POINTS`]).
    pub fn new(points: usize) -> Self {
        Svi {
            points,
            ..Svi::default()
        }
    }

    /// Use `quadrature` Gauss–Legendre points.
    pub fn with_quadrature(mut self, quadrature: usize) -> Self {
        self.quadrature = Some(quadrature);
        self
    }

    /// Solve the stage equations with `solver`.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        self.solver = solver;
        self
    }

    /// Cap Newton iterations per step.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }

    /// Solve Newton's linear systems on runtime-dimension models with `linear_solver`.
    pub fn with_linear_solver(mut self, linear_solver: LinearSolverKind) -> Self {
        self.linear_solver = linear_solver;
        self
    }

    /// The number of Gauss–Legendre points in use.
    pub fn quadrature_points(&self) -> usize {
        self.quadrature
            .unwrap_or(self.points.saturating_mul(2).min(MAX_POINTS))
    }

    pub(crate) fn validate(&self) -> Result<(), Error> {
        check_options(
            self.points,
            Some(self.quadrature_points()),
            self.max_iterations,
        )
    }
}

impl<N: Dimension> Method<N> for Svi
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = SviWorkspace<N>;

    fn info(&self) -> MethodInfo {
        let degree = self.points.saturating_sub(1);
        MethodInfo {
            name: match self.solver {
                Solver::Auto => "svi",
                Solver::Newton => "svi-newton",
            },
            order: degree.min(self.quadrature_points()).saturating_mul(2),
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Lagrange,
        }
    }

    fn workspace<L: Lagrangian<N>>(&self, model: &L, h: f64) -> Result<SviWorkspace<N>, Error> {
        self.validate()?;
        crate::error::require_positive("h", h)?;
        let n = dimension_of::<N>(model.dimension())
            .map_err(|reason| Error::invalid("model", reason))?;
        let m = self.quadrature_points();
        let size = (self.points - 1) * n.value();
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let tables = Tables::new(&basis, m, h)?;
        let constant_mass = match L::STRUCTURE {
            Structure::ConstantMass => ConstantMass::new(&tables, n),
            Structure::General => None,
        };
        if let Some(terms) = sparse_terms(model) {
            check_width(terms.width())?;
        }
        // Newton's buffers exist for every model (a constant-mass model falls back to Newton
        // where the fixed point fails); its n-squared matrices are made at their first use.
        Ok(SviWorkspace {
            tables,
            offsets: DVector::zeros(size),
            start: StartingValues::new(&basis, n.value()),
            // Made by the first Newton solve (none for a fixed point that converges).
            points: Vec::new(),
            // n × n each: only for a forced model.
            forces: match L::FORCED {
                true => vec![ForceJacobian::zeros(n); m],
                false => Vec::new(),
            },
            newton: Newton::new(size, self.max_iterations),
            sparse: LazyStageNewton::default(),
            legendre: LazyLegendre::default(),
            constant_mass,
            newton_only: false,
            tangent: None,
            adjoint: None,
        })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut SviWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let mut spent = 0;
        if self.solver == Solver::Auto
            && workspace.constant_mass.is_some()
            && !workspace.newton_only
        {
            let result = fixed_point_step(
                model,
                self.max_iterations,
                workspace,
                t,
                h,
                state,
                increment,
            );
            match after_fixed_point(result, L::FORCED, &mut workspace.newton_only) {
                ControlFlow::Break(result) => return result,
                ControlFlow::Continue(iterations) => spent = iterations,
            }
        }
        // After a capped fixed point Newton starts from its last iterate; after a diverging
        // one, or for a model that always uses Newton, from the starting values. Factors kept
        // from an earlier fallback belong to another state.
        let warm = spent > 0;
        if self.solver == Solver::Auto && workspace.constant_mass.is_some() {
            workspace.invalidate_newton();
        }
        let jacobian = match self.solver {
            Solver::Auto => Jacobian::Kept,
            Solver::Newton => Jacobian::Exact,
        };
        if let Some(terms) = sparse_terms(model) {
            if !warm {
                workspace.set_step(h);
                workspace.start(model, t, state);
            }
            // Sparse Newton (`stage_newton`), written for `Dyn` only (compiled once).
            let ws = &mut *workspace;
            let (solved, analyses) = ws.sparse.step(
                terms,
                &ws.tables,
                (t, state.q.as_slice(), state.y.as_slice()),
                &mut ws.offsets,
                (increment.q.as_mut_slice(), increment.y.as_mut_slice()),
                jacobian,
                (self.linear_solver, self.max_iterations),
            )?;
            ws.remember(h);
            let iterations = solved.iterations + spent;
            return Ok(StepReport {
                iterations,
                evaluations: ws.tables.weights.len() * (iterations + 1),
                factorizations: solved.factorizations,
                analyses,
            });
        }
        let solved = solve(model, workspace, t, h, state, warm, jacobian)?;
        let iterations = solved.iterations + spent;
        let ws = &mut *workspace;
        let s = ws.tables.degree;
        let n = state.dimension();
        let width = n.value();
        // The momentum increment p_{k+1} − p_k.
        let dp = &mut increment.y;
        dp.fill(0.0);
        // Σ_μ P_sμ (∂L/∂q + f_L)(τ_μ), for the end point of a constant-mass model.
        let mut end_load = ws
            .constant_mass
            .as_ref()
            .map(|_| OVector::<f64, N>::zeros_generic(n, U1));
        for mu in 0..ws.tables.nodes.len() {
            let (q, v) = ws.tables.point(mu, &state.q, &ws.offsets);
            let time = ws.tables.time(t, mu);
            let mut force = model.force(time, &q, &v);
            if L::FORCED {
                force += model.external_force(time, &q, &v);
            }
            add_scaled(dp, ws.tables.weights[mu], &force);
            if let (Some(data), Some(end_load)) = (ws.constant_mass.as_ref(), end_load.as_mut()) {
                add_scaled(end_load, data.nystrom.end_weights[mu], &force);
            }
        }
        // With a constant mass matrix the end point follows from the converged forces without
        // cancellation, q_{k+1} − q_k = h M⁻¹p_k + h² M⁻¹ Σ_μ P_sμ (∂L/∂q + f_L)(τ_μ) (see
        // `ConstantMass`), as p_{k+1} from the momentum balance. The Newton offset Z_s holds
        // the same number up to the round-off of the residual (8a)–(8b), whose O(|p|) terms
        // cancel through the differentiation matrix: taking Z_s made the energy error
        // random-walk 5–10 times faster than the fixed point's (Kepler, T = 2000).
        match (ws.constant_mass.as_mut(), end_load) {
            (Some(data), Some(end_load)) => {
                let inverse =
                    cached_mass_inverse(&mut data.mass_inverse, model, t, &state.q, &state.y)?;
                inverse.apply_into(&(&state.y * h + end_load * (h * h)), &mut increment.q);
            }
            _ => {
                increment.q = OVector::from_column_slice_generic(
                    n,
                    U1,
                    &ws.offsets.as_slice()[(s - 1) * width..s * width],
                );
            }
        }
        ws.remember(h);
        let m = ws.tables.nodes.len();
        Ok(StepReport {
            iterations,
            evaluations: m * (iterations + 1),
            factorizations: solved.factorizations,
            analyses: 0,
        })
    }

    fn restart(&self, workspace: &mut SviWorkspace<N>) {
        workspace.start.invalidate();
        workspace.invalidate_newton();
        if let Some(data) = workspace.constant_mass.as_mut() {
            data.pending = false;
        }
    }

    /// q(τ) = q_k + Σ_j l_j(τ) Z_j and q̇(τ) = (2/h) Σ_j l̇_j(τ) Z_j, τ = 2θ − 1.
    fn dense_output(
        &self,
        workspace: &SviWorkspace<N>,
        state: &State<N>,
        h: f64,
        theta: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        let mut values = Scratch::zeros(workspace.start.points());
        let tau = 2.0 * theta - 1.0;
        let (offset, rate) = match workspace.constant_mass.as_ref() {
            Some(data) if data.pending => workspace
                .start
                .polynomial(tau, &mut values, |j| data.last_offset(j)),
            _ => workspace.start.last_step::<N>(tau, &mut values)?,
        };
        Some((&state.q + offset, rate * (2.0 / h)))
    }

    /// q̇ = M⁻¹p once the fixed-point iteration has cached M⁻¹ (a constant-mass model,
    /// L = ½ q̇ᵀMq̇ − V, so p = Mq̇ exactly; [`Structure::ConstantMass`] is checked by the
    /// integrator's first run); for any other unforced sum of terms of run-time size the
    /// sparse inverse Legendre map the run keeps.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &SviWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        let inverse = workspace
            .constant_mass
            .as_ref()
            .and_then(|data| data.mass_inverse.as_ref());
        if let Some(inverse) = inverse {
            inverse.apply_into(p, v);
            return Ok(true);
        }
        let Some(terms) = sparse_terms(model) else {
            return Ok(false);
        };
        workspace
            .legendre
            .solve(terms, t, q.as_slice(), p.as_slice(), v.as_mut_slice())?;
        Ok(true)
    }

    fn points(&self) -> Option<usize> {
        Some(self.points)
    }

    /// An unforced sum of terms: the fixed point (M⁻¹ from the terms' blocks, forces
    /// assembled in place) for a constant mass, and sparse Newton (`stage_newton`) for every
    /// other one and wherever the fixed point fails.
    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        model.terms().is_some() && !L::FORCED
    }

    /// Keeps an explicit quadrature's offset m − (s + 1) from the number of points.
    fn with_points(&self, points: usize) -> Option<Self> {
        let quadrature = self
            .quadrature
            .map(|m| (m + points).saturating_sub(self.points).max(1));
        Some(Svi {
            points,
            quadrature,
            ..self.clone()
        })
    }

    fn node_offsets<'a>(&self, workspace: &'a mut SviWorkspace<N>) -> Option<&'a [f64]> {
        workspace.settle();
        workspace.start.last_offsets()
    }

    /// E_d = −∂L_d/∂h = Σ_μ (w_μ/2) E(q(c'_μ h), q̇(c'_μ h)) with E = p·q̇ − L: the Gauss
    /// average of the energy along the step polynomial. (With the nodes held fixed,
    /// ∂/∂h [h L(q_μ, (1/h) Σ_ν q^ν l̇_ν(τ_μ))] = L_μ − p_μ·q̇_μ; the interior nodes are
    /// stationary points of L_d, so holding them fixed changes nothing.)
    fn discrete_energy<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut SviWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Option<f64> {
        // The energy of a time-dependent or forced model is not conserved.
        if L::TIME_DEPENDENT || L::FORCED {
            return None;
        }
        workspace.settle();
        if workspace.tables.h != h {
            return None;
        }
        workspace
            .offsets
            .copy_from_slice(workspace.start.last_offsets()?);
        let tables = &workspace.tables;
        let energy = (0..tables.nodes.len())
            .map(|mu| {
                let (q, v) = tables.point(mu, &state.q, &workspace.offsets);
                0.5 * tables.reference_weights[mu] * model.energy(tables.time(t, mu), &q, &v)
            })
            .sum();
        Some(energy)
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut SviWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let mut increment = State::zeros(state.dimension());
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        // The converged node offsets (a fixed-point step leaves them pending).
        workspace.settle();
        if let Some(offsets) = workspace.start.last_offsets() {
            workspace.offsets.copy_from_slice(offsets);
        }
        let SviWorkspace {
            tables,
            offsets,
            tangent: buffers,
            ..
        } = workspace;
        let s = tables.degree;
        let n = state.dimension();
        let w = n.value();
        let TangentBuffers {
            hessian,
            lu,
            sensitivity,
            momentum,
        } = buffers.get_or_insert_with(|| TangentBuffers::new(s, w));
        // Full block Hessian H_{νj} = ∂(g_ν + f_ν)/∂qʲ, ν, j = 0..s, at the converged nodes
        // (the force terms vanish for unforced models).
        hessian.fill(0.0);
        for mu in 0..tables.nodes.len() {
            let (q, v) = tables.point(mu, &state.q, offsets);
            let d = model.second_derivatives(tables.time(t, mu), &q, &v);
            let f = model.external_force_jacobian(tables.time(t, mu), &q, &v);
            let weight = tables.weights[mu];
            for j in 0..=s {
                let (bj, cj) = (tables.values[(mu, j)], tables.derivatives[(mu, j)]);
                let from_q = ((&d.qq + &f.q) * bj + (&d.qv + &f.v) * cj) * weight;
                let from_v = (d.qv.transpose() * bj + &d.vv * cj) * weight;
                for nu in 0..=s {
                    let block =
                        &from_q * tables.values[(mu, nu)] + &from_v * tables.derivatives[(mu, nu)];
                    add_block(hessian, nu * w, j * w, &block);
                }
            }
        }
        let inner = s * w;
        lu.matrix_mut()
            .copy_from(&hessian.view((0, w), (inner, inner)));
        lu.factor().map_err(|_| StepFailure::SingularMatrix)?;
        // Columns: d/dq_k (N), then d/dp_k (N).
        sensitivity.fill(0.0);
        for j in 0..w {
            for i in 0..inner {
                sensitivity[(i, j)] = -hessian[(i, j)];
            }
            sensitivity[(j, w + j)] = -1.0;
        }
        lu.solve_columns_in_place(sensitivity);
        let last = sensitivity.view(((s - 1) * w, 0), (w, 2 * w));
        momentum.gemm(
            1.0,
            &hessian.view((s * w, w), (w, inner)),
            &*sensitivity,
            0.0,
        );
        let tangent = TangentMap {
            qq: OMatrix::from_fn_generic(n, n, |i, j| last[(i, j)]),
            qy: OMatrix::from_fn_generic(n, n, |i, j| last[(i, w + j)]),
            yq: OMatrix::from_fn_generic(n, n, |i, j| momentum[(i, j)] + hessian[(s * w + i, j)]),
            yy: OMatrix::from_fn_generic(n, n, |i, j| momentum[(i, w + j)]),
        };
        Ok((increment, tangent, report))
    }

    /// On a constant-mass unforced model the weighted force Jacobians at the quadrature
    /// points, whose adjoint is the transposed fixed point of the Nyström form (see the
    /// module documentation, *Adjoint*); else the tangent map.
    fn adjoint_step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut SviWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
        adjoint: &mut StepAdjoint<N>,
    ) -> Result<StepReport, StepFailure> {
        let step = |workspace: &mut SviWorkspace<N>, increment: &mut State<N>| {
            self.step(model, workspace, t, h, state, increment)
        };
        if let Some(result) =
            adjoint::adjoint_step(step, model, workspace, t, h, state, increment, adjoint)
        {
            return result;
        }
        adjoint_by_tangent_map(self, model, workspace, t, h, state, increment, adjoint)
    }

    fn adjoint_apply(
        &self,
        workspace: &mut SviWorkspace<N>,
        adjoint: &StepAdjoint<N>,
        lambda: &mut DVector<f64>,
        scratch: &mut DVector<f64>,
    ) -> Result<(), StepFailure> {
        match adjoint {
            StepAdjoint::Stages { .. } => {
                adjoint::adjoint_apply(workspace, self.max_iterations, adjoint, lambda)
            }
            StepAdjoint::Map(_) => apply_tangent_map(adjoint, lambda, scratch),
        }
    }

    fn tangent_apply(
        &self,
        workspace: &mut SviWorkspace<N>,
        adjoint: &StepAdjoint<N>,
        columns: &mut DMatrix<f64>,
        scratch: &mut DMatrix<f64>,
    ) -> Result<(), StepFailure> {
        match adjoint {
            StepAdjoint::Stages { .. } => {
                adjoint::tangent_apply(workspace, self.max_iterations, adjoint, columns)
            }
            StepAdjoint::Map(_) => compose_tangent_map(adjoint, columns, scratch),
        }
    }
}

/// `y += a x`, written out so that it compiles to N fused multiply-adds in the inner loops.
#[inline(always)]
fn add_scaled<N: Dimension>(y: &mut OVector<f64, N>, a: f64, x: &OVector<f64, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    for (y, x) in y.as_mut_slice().iter_mut().zip(x.as_slice()) {
        *y += a * x;
    }
}

/// `matrix[row..row + N, column..column + N] += block`, column by column (a fixed-size
/// block cannot be added to a view of a run-time-size matrix in generic code).
#[inline]
fn add_block<N: Dimension>(
    matrix: &mut DMatrix<f64>,
    row: usize,
    column: usize,
    block: &OMatrix<f64, N, N>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = block.nrows();
    let rows = matrix.nrows();
    let target = matrix.as_mut_slice();
    for (j, source) in block.as_slice().chunks_exact(n).enumerate() {
        let start = (column + j) * rows + row;
        for (x, y) in target[start..start + n].iter_mut().zip(source) {
            *x += y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::verify::observed_order;
    use crate::scalar::Scalar;
    use crate::test_models::{
        AsDyn, Damped, HenonHeiles, Oscillator, VariableMass, advance,
        assert_tangent_matches_central_differences, distance, factorial, state,
    };
    use nalgebra::{Complex, Const, DVector, Dyn, SMatrix, SVector, U1, U2};

    /// The hand-derived Euler–Lagrange equations of [`VariableMass`]:
    /// q̈₀ = (−q₀ − q₀³ − 2 q₁ q̇₁ q̇₀) / (1 + q₁²), q̈₁ = q₁ q̇₀² − q₁.
    fn variable_mass_acceleration(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::from([
            (-q[0] - q[0].powi(3) - 2.0 * q[1] * v[1] * v[0]) / (1.0 + q[1] * q[1]),
            q[1] * v[0] * v[0] - q[1],
        ])
    }

    /// p = ((1 + q₁²) q̇₀, q̇₁) of [`VariableMass`].
    fn variable_mass_momentum(q: &SVector<f64, 2>, v: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::from([(1.0 + q[1] * q[1]) * v[0], v[1]])
    }

    /// The (s, s) Padé approximant of eᶻ, P(z)/P(−z) with
    /// P(z) = Σⱼ (2s − j)! s! / ((2s)! j! (s − j)!) zʲ: the stability function of the
    /// s-stage Gauss method (Hairer, Wanner II, §IV.3).
    fn pade(s: usize, z: Complex<f64>) -> Complex<f64> {
        let numerator = |z: Complex<f64>| {
            (0..=s)
                .map(|j| {
                    let c = factorial(2 * s - j) * factorial(s)
                        / (factorial(2 * s) * factorial(j) * factorial(s - j));
                    z.powu(j as u32) * c
                })
                .sum::<Complex<f64>>()
        };
        numerator(z) / numerator(-z)
    }

    fn assert_pade_step<L: Lagrangian<U1>>(model: &L, s: usize) {
        // SVI with s + 1 CGL points and m = s Gauss points is the s-stage Gauss method. On
        // q̇ = p, ṗ = −q the variable w = q − i p obeys ẇ = i w, so one step maps w to
        // R(ih) w with R the (s, s) Padé approximant, and the local error is
        // |R(ih) − e^{ih}| |w| = C_s h^{2s+1} (1 + O(h²)), C_s = (s!)² / ((2s)! (2s + 1)!).
        let method = Svi::new(s + 1).with_quadrature(s);
        assert_eq!(Method::<U1>::info(&method).order, 2 * s);
        let (h, q0, p0) = (0.5f64, 0.6, 0.8);
        let (after, _) = advance(&method, model, h, 1, state([q0], [p0]));
        let w = pade(s, Complex::new(0.0, h)) * Complex::new(q0, -p0);
        assert!(
            (after.q[0] - w.re).abs() <= 2e-15 && (after.y[0] + w.im).abs() <= 2e-15,
            "s = {s}: step ({}, {}), Padé ({}, {})",
            after.q[0],
            after.y[0],
            w.re,
            -w.im
        );
        let exact = state(
            [q0 * h.cos() + p0 * h.sin()],
            [-q0 * h.sin() + p0 * h.cos()],
        );
        let error = (after.q[0] - exact.q[0]).hypot(after.y[0] - exact.y[0]);
        let bound = factorial(s).powi(2) / (factorial(2 * s) * factorial(2 * s + 1))
            * h.powi(2 * s as i32 + 1);
        // At h = 0.5 the O(h²) correction lowers the error by 1.5% to 3.6%.
        assert!(
            error <= bound && error >= 0.95 * bound,
            "s = {s}: error {error:e}, leading term {bound:e}"
        );
    }

    #[test]
    fn gauss_quadrature_step_of_the_oscillator_is_the_diagonal_pade_map() {
        for s in 1..=4 {
            assert_pade_step(&Oscillator::<false>, s);
            assert_pade_step(&Oscillator::<true>, s);
        }
    }

    /// Observed order (least-squares slope) of `method` on the oscillator from (q, p) = (0, 1)
    /// over [0, 4], against the exact solution (sin t, cos t).
    fn oscillator_order<L: Lagrangian<U1>>(method: &Svi, model: &L) -> f64 {
        let steps = [1.0, 0.5, 0.25, 0.125];
        let errors: Vec<f64> = steps
            .iter()
            .map(|&h| {
                let n = (4.0 / h) as usize;
                let (end, _) = advance(method, model, h, n, state([0.0], [1.0]));
                distance(&end, &state([4f64.sin()], [4f64.cos()]))
            })
            .collect();
        observed_order(&steps, &errors, 1e-13).unwrap()
    }

    #[test]
    fn observed_order_on_the_oscillator_equals_declared_order() {
        for (points, quadrature, declared) in [(3, Some(2), 4), (4, Some(3), 6), (4, None, 6)] {
            let mut method = Svi::new(points);
            method.quadrature = quadrature;
            assert_eq!(Method::<U1>::info(&method).order, declared);
            for order in [
                oscillator_order(&method, &Oscillator::<false>),
                oscillator_order(&method, &Oscillator::<true>),
            ] {
                assert!(
                    (order - declared as f64).abs() < 0.1,
                    "{points}/{quadrature:?}: observed {order:.3}, declared {declared}"
                );
            }
        }
    }

    /// The state of [`VariableMass`] at t = 2 from q = (0.5, −0.3), q̇ = (0.4, 0.6), by
    /// classical Runge–Kutta on the hand-derived equations with h = 1/2000 (global error
    /// about 1e-14).
    fn variable_mass_reference() -> State<U2> {
        let f = |x: &SVector<f64, 4>| {
            let (q, v) = (
                x.fixed_rows::<2>(0).into_owned(),
                x.fixed_rows::<2>(2).into_owned(),
            );
            let a = variable_mass_acceleration(&q, &v);
            SVector::<f64, 4>::from([v[0], v[1], a[0], a[1]])
        };
        let h = 1.0 / 2000.0;
        let mut x = SVector::<f64, 4>::from([0.5, -0.3, 0.4, 0.6]);
        for _ in 0..4000 {
            let k1 = f(&x);
            let k2 = f(&(x + k1 * (0.5 * h)));
            let k3 = f(&(x + k2 * (0.5 * h)));
            let k4 = f(&(x + k3 * h));
            x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
        let (q, v) = (
            x.fixed_rows::<2>(0).into_owned(),
            x.fixed_rows::<2>(2).into_owned(),
        );
        State {
            q,
            y: variable_mass_momentum(&q, &v),
        }
    }

    #[test]
    fn newton_path_with_position_dependent_mass_reaches_declared_order() {
        let reference = variable_mass_reference();
        let q0 = SVector::from([0.5, -0.3]);
        let start = State {
            q: q0,
            y: variable_mass_momentum(&q0, &SVector::from([0.4, 0.6])),
        };
        let steps = [0.4f64, 0.2, 0.1, 0.05];
        // The simplified Newton method (`Auto`) and Newton's method with the exact Jacobian.
        for (points, quadrature, solver) in [
            (3, 2, Solver::Auto),
            (4, 3, Solver::Auto),
            (3, 2, Solver::Newton),
            (4, 3, Solver::Newton),
        ] {
            let method = Svi::new(points)
                .with_quadrature(quadrature)
                .with_solver(solver);
            let errors: Vec<f64> = steps
                .iter()
                .map(|&h| {
                    let n = (2.0 / h).round() as usize;
                    let (end, workspace) = advance(&method, &VariableMass, h, n, start);
                    assert!(workspace.constant_mass.is_none());
                    distance(&end, &reference)
                })
                .collect();
            let order = observed_order(&steps, &errors, 1e-11).unwrap();
            let declared = Method::<U2>::info(&method).order as f64;
            assert!(
                (order - declared).abs() < 0.2,
                "{points}/{quadrature} {solver:?}: observed {order:.3}, declared {declared}, \
                 {errors:?}"
            );
        }
    }

    #[test]
    fn simplified_newton_keeps_its_jacobian_across_steps_and_reaches_newtons_solution() {
        // VariableMass from q = (0.5, −0.3), q̇ = (0.4, 0.6), 200 steps of h = 0.01: the
        // simplified Newton method (`Auto`, the Jacobian refactorised only when the
        // iteration contracts by less than REFACTOR_CONTRACTION) against Newton's method
        // with the exact Jacobian at every iteration. Both solve the same residual to
        // round-off, so they end within 1e-13 of each other, and both within 1e-11 of the
        // RK4 reference at t = 2 (order 10 at h = 0.01: the error is round-off).
        let q0 = SVector::from([0.5, -0.3]);
        let start = State {
            q: q0,
            y: variable_mass_momentum(&q0, &SVector::from([0.4, 0.6])),
        };
        let h = 0.01;
        let mut ends = Vec::new();
        for solver in [Solver::Auto, Solver::Newton] {
            let method = Svi::new(6).with_quadrature(5).with_solver(solver);
            let mut workspace = method.workspace(&VariableMass, h).unwrap();
            let (mut current, mut increment) = (start, State::zeros(U2));
            let mut total = StepReport::default();
            for k in 0..200 {
                let report = method
                    .step(
                        &VariableMass,
                        &mut workspace,
                        k as f64 * h,
                        h,
                        &current,
                        &mut increment,
                    )
                    .unwrap();
                current.q += increment.q;
                current.y += increment.y;
                total.iterations += report.iterations;
                total.factorizations += report.factorizations;
            }
            match solver {
                // Far fewer factorisations than the 200 steps.
                Solver::Auto => assert!(total.factorizations <= 100, "{total:?}"),
                Solver::Newton => assert_eq!(total.factorizations, total.iterations),
            }
            let error = distance(&current, &variable_mass_reference());
            assert!(error <= 1e-11, "{solver:?}: {error:e} from the reference");
            ends.push(current);
        }
        let difference = distance(&ends[0], &ends[1]);
        assert!(difference <= 1e-13, "solvers differ by {difference:e}");
    }

    #[test]
    fn fixed_point_and_newton_paths_agree_on_a_constant_mass_problem() {
        let start = state([0.3, -0.2], [0.1, 0.4]);
        for method in [Svi::new(4).with_quadrature(3), Svi::new(5)] {
            let (fixed, workspace) = advance(&method, &HenonHeiles::<true>, 0.2, 20, start);
            assert!(workspace.constant_mass.is_some());
            let (newton, workspace) = advance(&method, &HenonHeiles::<false>, 0.2, 20, start);
            assert!(workspace.constant_mass.is_none());
            let difference = distance(&fixed, &newton);
            assert!(
                difference <= 1e-13,
                "{method:?}: paths differ by {difference:e}"
            );
        }
    }

    #[test]
    fn a_fixed_point_step_remembers_its_polynomial_without_writing_it() {
        // The step's node offsets stay pending (its velocity term and accelerations) until
        // something reads them: dense output at θ = 1 and the settled last node must both be
        // the step's end point, and the next step's start from the pending data must equal
        // the start from the settled offsets (one more step each way, same result).
        let method = Svi::new(7).with_quadrature(6);
        let model = HenonHeiles::<true>;
        let h = 0.1;
        let (end, mut workspace) = advance(&method, &model, h, 3, state([0.3, -0.2], [0.1, 0.4]));
        let (before, _) = advance(&method, &model, h, 2, state([0.3, -0.2], [0.1, 0.4]));
        assert!(workspace.constant_mass.as_ref().unwrap().pending);
        let (q, v) = Method::<U2>::dense_output(&method, &workspace, &before, h, 1.0).unwrap();
        assert!((q - end.q).amax() <= 1e-15, "{q:?} {:?}", end.q);
        // The end velocity of the step polynomial is M⁻¹p to the method's accuracy.
        let mass_inverse = SMatrix::<f64, 2, 2>::new(0.6, -0.2, -0.2, 0.4);
        assert!((v - mass_inverse * end.y).amax() <= 1e-9, "{v:?}");
        let mut settled = workspace.clone();
        let offsets = Method::<U2>::node_offsets(&method, &mut settled).unwrap();
        let last = SVector::<f64, 2>::from_column_slice(&offsets[offsets.len() - 2..]);
        assert!((before.q + last - end.q).amax() <= 1e-15);
        assert!(!settled.constant_mass.as_ref().unwrap().pending);
        let mut increments = [State::zeros(U2), State::zeros(U2)];
        for (ws, increment) in [&mut workspace, &mut settled]
            .into_iter()
            .zip(&mut increments)
        {
            method
                .step(&model, ws, 3.0 * h, h, &end, increment)
                .unwrap();
        }
        assert!(distance(&increments[0], &increments[1]) <= 1e-15);
    }

    #[test]
    fn the_velocity_of_a_constant_mass_state_is_the_cached_inverse_mass_times_p() {
        // q̇ = M⁻¹p from the workspace, against the inverse Legendre map by Newton.
        let method = Svi::new(6);
        let model = HenonHeiles::<true>;
        let (end, workspace) = advance(&method, &model, 0.1, 4, state([0.3, -0.2], [0.1, 0.4]));
        let from = |workspace: &SviWorkspace<U2>| {
            let mut v = SVector::from([f64::NAN; 2]);
            let known = method
                .velocity_into(&model, workspace, 0.4, &end.q, &end.y, &mut v)
                .unwrap();
            known.then_some(v)
        };
        let known = from(&workspace).unwrap();
        let solved = model
            .velocity(0.4, &end.q, &end.y, &SVector::zeros())
            .unwrap();
        assert!((known - solved).amax() <= 1e-15, "{known:?} {solved:?}");
        // Not before a step has cached M⁻¹, and never for a general Lagrangian of fixed size.
        let fresh = Method::<U2>::workspace(&method, &model, 0.1).unwrap();
        assert!(from(&fresh).is_none());
        let (_, general) = advance(
            &method,
            &VariableMass,
            0.1,
            2,
            state([0.3, -0.2], [0.1, 0.4]),
        );
        let mut v = SVector::zeros();
        let known = method
            .velocity_into(&VariableMass, &general, 0.4, &end.q, &end.y, &mut v)
            .unwrap();
        assert!(!known);
    }

    #[test]
    fn a_capped_fixed_point_hands_the_step_to_newton_from_its_last_iterate() {
        // Two fixed-point iterations per step are far from converged (h = 0.2); Newton takes
        // over from the last iterate in every step, reaches the same solution as the
        // iteration run to round-off, and the next step tries the fixed point again.
        let start = state([0.3, -0.2], [0.1, 0.4]);
        let method = Svi::new(5);
        let (converged, _) = advance(&method, &HenonHeiles::<true>, 0.2, 20, start);
        let capped = method.clone().with_max_iterations(2);
        let (fallback, workspace) = advance(&capped, &HenonHeiles::<true>, 0.2, 20, start);
        assert!(!workspace.newton_only);
        let difference = distance(&converged, &fallback);
        assert!(difference <= 1e-13, "paths differ by {difference:e}");
        // The step's report counts both iterations.
        let mut workspace = capped.workspace(&HenonHeiles::<true>, 0.2).unwrap();
        let mut increment = State::zeros(U2);
        let report = capped
            .step(
                &HenonHeiles::<true>,
                &mut workspace,
                0.0,
                0.2,
                &start,
                &mut increment,
            )
            .unwrap();
        assert!(report.iterations > 2, "{report:?}");
    }

    #[test]
    fn forced_fixed_point_falls_back_to_newton_only_when_it_fails() {
        let method = Svi::new(4).with_quadrature(3);
        let start = state([1.0], [0.0]);
        // Weak friction (h c = 0.025): the fixed point converges and matches Newton.
        let (fixed, workspace) = advance(&method, &Damped::<true> { c: 0.1 }, 0.25, 8, start);
        assert!(!workspace.newton_only);
        let (newton, _) = advance(&method, &Damped::<false> { c: 0.1 }, 0.25, 8, start);
        assert!(distance(&fixed, &newton) <= 1e-14, "{fixed:?} {newton:?}");
        // Strong friction (h c = 20): the fixed point diverges, the step is redone by Newton
        // from the same starting values, and the run stays on Newton.
        let (fallback, workspace) = advance(&method, &Damped::<true> { c: 40.0 }, 0.5, 4, start);
        assert!(workspace.newton_only);
        let (newton, _) = advance(&method, &Damped::<false> { c: 40.0 }, 0.5, 4, start);
        assert!(
            distance(&fallback, &newton) <= 1e-14,
            "{fallback:?} {newton:?}"
        );
    }

    fn assert_symplectic<L: Lagrangian<U2>>(method: &Svi, model: &L, start: State<U2>) {
        let h = 0.3;
        let mut workspace = method.workspace(model, h).unwrap();
        let (_, tangent, _) = method
            .tangent_map(model, &mut workspace, 0.0, h, &start)
            .unwrap();
        let error = tangent.symplecticity_error();
        assert!(error <= 1e-13, "{method:?}: ‖ΦᵀJΦ − J‖ = {error:e}");
    }

    #[test]
    fn tangent_map_is_symplectic() {
        let start = state([0.5, -0.3], [0.4, 0.6]);
        for method in [Svi::new(3).with_quadrature(2), Svi::default()] {
            assert_symplectic(&method, &VariableMass, start);
            assert_symplectic(&method, &HenonHeiles::<true>, start);
            assert_symplectic(&method, &HenonHeiles::<false>, start);
        }
    }

    #[test]
    fn tangent_map_matches_central_differences_of_the_step_map() {
        let method = Svi::new(4).with_quadrature(3);
        assert_tangent_matches_central_differences(
            &method,
            &VariableMass,
            state([0.5, -0.3], [0.4, 0.6]),
        );
        // The force Jacobian enters too (the forced map is not symplectic).
        assert_tangent_matches_central_differences(
            &method,
            &Damped::<false> { c: 0.7 },
            state([1.0], [-0.5]),
        );
    }

    #[test]
    fn invalid_options_are_invalid_parameters_named_after_the_option() {
        let mut zero_quadrature = Svi::new(4);
        zero_quadrature.quadrature = Some(0);
        let cases = [
            (Svi::new(1), "points"),
            (Svi::new(MAX_POINTS + 1), "points"),
            (zero_quadrature, "quadrature"),
            (Svi::new(4).with_quadrature(MAX_POINTS + 1), "quadrature"),
            (Svi::new(4).with_max_iterations(0), "max_iterations"),
        ];
        for (method, expected) in cases {
            match method.workspace(&Oscillator::<false>, 0.1) {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, expected),
                other => panic!("{method:?}: expected InvalidParameter, got {other:?}"),
            }
        }
        // The largest valid configuration is accepted (its default quadrature is capped at
        // MAX_POINTS, not 2 · MAX_POINTS), and the step size is checked too.
        assert_eq!(Svi::new(MAX_POINTS).quadrature_points(), MAX_POINTS);
        assert_eq!(Svi::new(100).quadrature_points(), 200);
        assert!(
            Svi::new(MAX_POINTS)
                .workspace(&Oscillator::<false>, 0.1)
                .is_ok()
        );
        assert!(matches!(
            Svi::new(4).workspace(&Oscillator::<false>, 0.0),
            Err(Error::InvalidParameter { name, .. }) if name == "h"
        ));
    }

    /// `state` as a state of a run-time-size model.
    fn run_time<const K: usize>(state: &State<Const<K>>) -> State<Dyn> {
        State {
            q: DVector::from_column_slice(state.q.as_slice()),
            y: DVector::from_column_slice(state.y.as_slice()),
        }
    }

    /// ‖a − b‖∞ over q and y, between a fixed-size state and a run-time-size one.
    fn apart<const K: usize>(a: &State<Const<K>>, b: &State<Dyn>) -> f64 {
        assert_eq!(b.q.len(), K);
        let a = a.q.iter().chain(a.y.iter());
        a.zip(b.q.iter().chain(b.y.iter()))
            .fold(0.0, |m, (x, y)| m.max((x - y).abs()))
    }

    /// Steps and tangent map of `method` on `model` and on the same model seen as a
    /// run-time-size one agree to round-off (the derivatives are taken by other sweeps).
    fn assert_run_time_size_agrees<L: Lagrangian<Const<K>>, const K: usize>(
        method: &Svi,
        model: L,
        start: State<Const<K>>,
    ) {
        let h = 0.1;
        let (fixed, fixed_workspace) = advance(method, &model, h, 10, start);
        let mut workspace = method.workspace(&model, h).unwrap();
        let (_, tangent, _) = method
            .tangent_map(&model, &mut workspace, 0.0, h, &start)
            .unwrap();
        // The cached M⁻¹p of a constant-mass model.
        let mut a = OVector::<f64, Const<K>>::zeros();
        let known = method
            .velocity_into(&model, &fixed_workspace, 1.0, &fixed.q, &fixed.y, &mut a)
            .unwrap();
        let dynamic = AsDyn::<L, Const<K>>::new(model);
        let (other, other_workspace) = advance(method, &dynamic, h, 10, run_time(&start));
        assert_eq!(
            fixed_workspace.constant_mass.is_some(),
            other_workspace.constant_mass.is_some()
        );
        let difference = apart(&fixed, &other);
        assert!(difference <= 1e-13, "{method:?}: {difference:e}");
        // Dense output (of the last step, taken from either end state) and the velocity.
        let (q, v) =
            Method::<Const<K>>::dense_output(method, &fixed_workspace, &fixed, h, 0.3).unwrap();
        let (p, w) = Method::<Dyn>::dense_output(method, &other_workspace, &other, h, 0.3).unwrap();
        assert!((DVector::from_column_slice(q.as_slice()) - p).amax() <= 1e-13);
        assert!((DVector::from_column_slice(v.as_slice()) - w).amax() <= 1e-12);
        let mut b = DVector::zeros(K);
        let other_known = method
            .velocity_into(&dynamic, &other_workspace, 1.0, &other.q, &other.y, &mut b)
            .unwrap();
        assert_eq!(known, other_known);
        if known {
            assert!((DVector::from_column_slice(a.as_slice()) - b).amax() <= 1e-13);
        }
        let mut other_workspace = method.workspace(&dynamic, h).unwrap();
        let (_, other_tangent, _) = method
            .tangent_map(&dynamic, &mut other_workspace, 0.0, h, &run_time(&start))
            .unwrap();
        let difference = (tangent.matrix() - other_tangent.matrix()).amax();
        assert!(
            difference <= 1e-12,
            "{method:?}: tangent maps differ by {difference:e}"
        );
    }

    /// A model on ℝ² that says it has three coordinates.
    struct Misdeclared;
    impl Lagrangian<U2> for Misdeclared {
        fn dimension(&self) -> usize {
            3
        }
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            VariableMass.lagrangian(t, q, v)
        }
    }

    #[test]
    fn a_run_time_size_model_takes_the_same_steps() {
        let start = state([0.5, -0.3], [0.4, 0.6]);
        for method in [
            Svi::new(4).with_quadrature(3),
            Svi::new(5),
            Svi::new(5).with_solver(Solver::Newton),
        ] {
            assert_run_time_size_agrees(&method, VariableMass, start);
            assert_run_time_size_agrees(&method, HenonHeiles::<true>, start);
            assert_run_time_size_agrees(&method, HenonHeiles::<false>, start);
            let start = state([1.0], [0.2]);
            assert_run_time_size_agrees(&method, Damped::<true> { c: 0.3 }, start);
            assert_run_time_size_agrees(&method, Damped::<false> { c: 0.3 }, start);
        }
        // A model whose size contradicts its dimension type is refused by name.
        match Method::<U2>::workspace(&Svi::new(4), &Misdeclared, 0.1) {
            Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "model"),
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }
}
