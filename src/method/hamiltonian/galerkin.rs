//! The Galerkin Hamiltonian variational integrator (`svi-h`): the discrete right Hamiltonian
//! of Leok & Zhang (2011) with SVI's Chebyshev–Gauss–Lobatto curve and Gauss–Legendre rule.
//!
//! # Discrete equations
//! On [t, t + h] the curve is q(τ) = Σ_ν qᵛ l_ν(τ) through s + 1 CGL nodes, τ ∈ [−1, 1],
//! q⁰ = q_k, and the momenta are free numbers P_μ at the m Gauss points τ_μ (weights w_μ).
//! The type II generating function is the extremum
//!
//! H_d⁺(q_k, p_{k+1}) = ext [ p_{k+1}·qˢ − (h/2) Σ_μ w_μ ( P_μ·q̇(τ_μ) − H(t_μ, q(τ_μ), P_μ) ) ]
//!
//! over q¹, …, qˢ and P_1, …, P_m, with q̇(τ_μ) = (2/h) Σ_ν qᵛ l̇_ν(τ_μ), and the step is
//! q_{k+1} = D₂H_d⁺ = qˢ, p_k = D₁H_d⁺ (the discrete right Hamilton equations; a type II
//! generating function, so the map is symplectic). Setting the derivatives to zero, with
//! G_ν = −Σ_μ w_μ l̇_ν(τ_μ) P_μ + (h/2) Σ_μ w_μ l_ν(τ_μ) ∂H/∂q(μ):
//!
//! - ∂/∂P_μ: (2/h) Σ_ν qᵛ l̇_ν(τ_μ) = ∂H/∂p(t_μ, q(τ_μ), P_μ)  (Hamilton's first equation at
//!   each Gauss point);
//! - ∂/∂qᵛ, 0 < ν < s: G_ν = 0;  ∂/∂q⁰: p_k = G_0;  ∂/∂qˢ: p_{k+1} = −G_s.
//!
//! A force f_H enters as SVI's discrete Lagrange–d'Alembert forces
//! f_ν = (h/2) Σ_μ w_μ l_ν(τ_μ) f_H(μ): p_k = G_0 − f_0, G_ν = f_ν, p_{k+1} = f_s − G_s.
//! As in SVI the unknowns are offsets, Δᵛ = qᵛ − q_k and Π_μ = P_μ − p_k, and because
//! Σ_μ w_μ l̇_ν(τ_μ) = δ_νs − δ_ν0 exactly (m ≥ s), rows ν < s read
//!
//! −Σ_μ w_μ l̇_ν(τ_μ) Π_μ + (h/2) Σ_μ w_μ l_ν(τ_μ) (∂H/∂q − f_H)(μ) = 0,
//!
//! and the momentum update is the sum of all rows, free of cancellation:
//! p_{k+1} − p_k = −(h/2) Σ_μ w_μ (∂H/∂q − f_H)(μ).
//!
//! # When it is SVI
//! With P_μ = ∂L/∂q̇ and ∂H/∂q = −∂L/∂q at Legendre-related points, G_ν = −g_ν and the
//! equations are SVI's (8a)–(8c) term by term: for a hyperregular L the two discrete maps
//! coincide (Leok & Zhang 2011, the Galerkin discrete Hamiltonian and Lagrangian give the same
//! map when the Legendre transform is global). For H = ½ pᵀM⁻¹p + V(t, q)
//! ([`HamiltonianStructure::QuadraticKinetic`]) the first equation gives P_μ = M q̇(τ_μ)
//! explicitly and the rest are SVI's constant-mass equations, which this method then solves
//! with SVI's fixed-point iteration (the force −∂V/∂q is H's, by automatic differentiation;
//! no Legendre map is solved). Otherwise Newton's method solves the N(s + m) equations with
//! the Jacobian from H's Hessian blocks.
//!
//! # Properties
//! Order min(2(s), 2m) as SVI; symmetric; symplectic without forces.
//!
//! # References
//! Leok & Zhang, *Discrete Hamiltonian variational integrators*, IMA J. Numer. Anal. 31
//! (2011); Porcù & Penati's `spectralvarint` (`002`), the Hamiltonian form of the spectral
//! variational integrator.

use super::{Derivatives, Linearised, Pair};
use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure};
use crate::method::variational::svi::{Svi, SviWorkspace};
use crate::method::variational::tables::Tables;
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::model::canonical;
use crate::model::hamiltonian::HamiltonianStructure;
use crate::nonlinear::{Jacobian, Newton, Solved};
use crate::spectral::basis::LagrangeBasis;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Options of the Galerkin Hamiltonian variational integrator (`svi-h:P/M`).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct HamiltonianGalerkin {
    /// Number of Chebyshev–Gauss–Lobatto points s + 1 (polynomial degree s), at least 2.
    pub points: usize,
    /// Number of Gauss–Legendre points m; `None` as [`Svi::quadrature`].
    pub quadrature: Option<usize>,
    /// Cap on Newton (or fixed-point) iterations per step.
    pub max_iterations: usize,
}

impl Default for HamiltonianGalerkin {
    fn default() -> Self {
        let svi = Svi::default();
        HamiltonianGalerkin {
            points: svi.points,
            quadrature: svi.quadrature,
            max_iterations: svi.max_iterations,
        }
    }
}

impl HamiltonianGalerkin {
    /// `points` CGL points and the default quadrature.
    pub fn new(points: usize) -> Self {
        HamiltonianGalerkin {
            points,
            ..Self::default()
        }
    }

    /// Use `quadrature` Gauss–Legendre points.
    pub fn with_quadrature(mut self, quadrature: usize) -> Self {
        self.quadrature = Some(quadrature);
        self
    }

    /// SVI with the same points, quadrature and iteration cap: the same discrete map on a
    /// quadratic kinetic energy.
    fn svi(&self) -> Svi {
        let svi = Svi::new(self.points).with_max_iterations(self.max_iterations);
        match self.quadrature {
            Some(m) => svi.with_quadrature(m),
            None => svi,
        }
    }
}

/// The buffers of one run.
#[derive(Debug)]
pub enum HamiltonianGalerkinWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// H = ½ pᵀM⁻¹p + V: SVI's constant-mass step.
    Quadratic(Box<SviWorkspace<N>>),
    /// Any other H: Newton's method on (Δ, Π).
    General(Box<GeneralWorkspace<N>>),
}

/// Buffers of the Newton path.
#[derive(Debug)]
pub struct GeneralWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    tables: Tables,
    newton: Newton,
    /// (Δ¹, …, Δˢ, Π_1, …, Π_m), N numbers each.
    unknowns: DVector<f64>,
    /// The step of the last converged solve, whose unknowns (still in `unknowns`) start
    /// the next one.
    last_h: Option<f64>,
    /// The configuration that solve started from: with `last_h`, which step the unknowns
    /// describe (the dense output reads them only for that step).
    last_start: OVector<f64, N>,
    /// The CGL basis l_ν of the curve q(τ) = q_k + Σ_ν l_ν(τ) Δᵛ (dense output).
    basis: LagrangeBasis,
    /// H's derivatives at the Gauss points.
    derivatives: Derivatives<N>,
    /// (q(τ_μ), P_μ) at each Gauss point.
    q: Vec<OVector<f64, N>>,
    p: Vec<OVector<f64, N>>,
}

impl<N: Dimension> Method<N> for HamiltonianGalerkin
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = HamiltonianGalerkinWorkspace<N>;

    fn info(&self) -> MethodInfo {
        let svi = self.svi();
        MethodInfo {
            name: "svi-h",
            order: Method::<N>::info(&svi).order,
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
            equations: Equations::Hamilton,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<HamiltonianGalerkinWorkspace<N>, Error> {
        let svi = self.svi();
        if canonical::structure(model) == HamiltonianStructure::QuadraticKinetic
            && L::STRUCTURE == crate::model::Structure::ConstantMass
        {
            return Ok(HamiltonianGalerkinWorkspace::Quadratic(Box::new(
                Method::<N>::workspace(&svi, model, h)?,
            )));
        }
        svi.validate()?;
        crate::error::require_positive("h", h)?;
        let n = dimension_of::<N>(model.dimension())
            .map_err(|reason| Error::invalid("model", reason))?;
        let (s, m) = (self.points - 1, svi.quadrature_points());
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let tables = Tables::new(&basis, m, h)?;
        let size = (s + m) * n.value();
        let zero = OVector::zeros_generic(n, U1);
        Ok(HamiltonianGalerkinWorkspace::General(Box::new(
            GeneralWorkspace {
                tables,
                newton: Newton::new(size, self.max_iterations),
                unknowns: DVector::zeros(size),
                last_h: None,
                last_start: zero.clone(),
                basis,
                derivatives: Derivatives::new(model, n),
                q: vec![zero.clone(); m],
                p: vec![zero; m],
            },
        )))
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut HamiltonianGalerkinWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        match workspace {
            HamiltonianGalerkinWorkspace::Quadratic(svi) => {
                Method::<N>::step(&self.svi(), model, svi, t, h, state, increment)
            }
            HamiltonianGalerkinWorkspace::General(general) => {
                let solved = general.solve(model, t, h, state)?;
                general.increment(model, t, state, solved, increment)
            }
        }
    }

    fn restart(&self, workspace: &mut HamiltonianGalerkinWorkspace<N>) {
        match workspace {
            HamiltonianGalerkinWorkspace::Quadratic(svi) => Method::<N>::restart(&self.svi(), svi),
            HamiltonianGalerkinWorkspace::General(general) => {
                general.last_h = None;
                general.newton.invalidate();
            }
        }
    }

    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &HamiltonianGalerkinWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        match workspace {
            HamiltonianGalerkinWorkspace::Quadratic(svi) => {
                Method::<N>::velocity_into(&self.svi(), model, svi, t, q, p, v)
            }
            HamiltonianGalerkinWorkspace::General(general) => {
                Ok(general.derivatives.velocity_into(model, t, q, p, v))
            }
        }
    }

    /// The step's curve: SVI's polynomial for H = ½pᵀM⁻¹p + V, else the CGL polynomial of the
    /// last solve's node offsets, q(τ) = q_k + Σ_ν l_ν(τ) Δᵛ, if that solve was this step.
    fn dense_output(
        &self,
        workspace: &HamiltonianGalerkinWorkspace<N>,
        state: &State<N>,
        h: f64,
        theta: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        match workspace {
            HamiltonianGalerkinWorkspace::Quadratic(svi) => {
                Method::<N>::dense_output(&self.svi(), svi, state, h, theta)
            }
            HamiltonianGalerkinWorkspace::General(general) => {
                if general.last_h != Some(h) || general.last_start != state.q {
                    return None;
                }
                let points = general.basis.len();
                let (mut values, mut rates) = (vec![0.0; points], vec![0.0; points]);
                let tau = 2.0 * theta - 1.0;
                general.basis.values_into(tau, &mut values);
                general.basis.derivatives_into(tau, &mut rates);
                let (mut q, mut v) = (
                    state.q.clone(),
                    OVector::zeros_generic(state.q.shape_generic().0, U1),
                );
                let w = state.q.len();
                for nu in 1..points {
                    let offset = &general.unknowns.as_slice()[(nu - 1) * w..nu * w];
                    for i in 0..w {
                        q[i] += values[nu] * offset[i];
                        v[i] += rates[nu] * (2.0 / h) * offset[i];
                    }
                }
                Some((q, v))
            }
        }
    }

    fn points(&self) -> Option<usize> {
        Some(self.points)
    }

    fn with_points(&self, points: usize) -> Option<Self> {
        Some(HamiltonianGalerkin {
            points,
            ..self.clone()
        })
    }

    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut HamiltonianGalerkinWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        match workspace {
            HamiltonianGalerkinWorkspace::Quadratic(svi) => {
                Method::<N>::tangent_map(&self.svi(), model, svi, t, h, state)
            }
            HamiltonianGalerkinWorkspace::General(general) => {
                let solved = general.solve(model, t, h, state)?;
                let mut increment = State::zeros(state.q.shape_generic().0);
                let report = general.increment(model, t, state, solved, &mut increment)?;
                let tangent = general.tangent(model, t, state)?;
                Ok((increment, tangent, report))
            }
        }
    }
}

impl<N: Dimension> GeneralWorkspace<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Fill the Gauss points' (q(τ_μ), P_μ) from the unknowns.
    fn points(&mut self, state: &State<N>, unknowns: &DVector<f64>) {
        let (tables, w) = (&self.tables, state.q.len());
        let s = tables.degree;
        for (mu, (q, p)) in self.q.iter_mut().zip(self.p.iter_mut()).enumerate() {
            q.copy_from(&state.q);
            for nu in 1..=s {
                let offset = &unknowns.as_slice()[(nu - 1) * w..nu * w];
                let value = tables.values[(mu, nu)];
                for i in 0..w {
                    q[i] += value * offset[i];
                }
            }
            let pi = &unknowns.as_slice()[(s + mu) * w..(s + mu + 1) * w];
            for i in 0..w {
                p[i] = state.y[i] + pi[i];
            }
        }
    }

    /// (∂H/∂q − f_H, ∂H/∂p) at Gauss point `mu`.
    fn field_at<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        mu: usize,
    ) -> Result<Pair<N>, StepFailure> {
        let time = t + self.tables.h * self.tables.unit_nodes[mu];
        self.derivatives
            .field(model, time, &self.q[mu], &self.p[mu])
    }

    /// The field and its derivatives at Gauss point `mu`.
    fn linearised_at<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        mu: usize,
    ) -> Result<Linearised<N>, StepFailure> {
        let time = t + self.tables.h * self.tables.unit_nodes[mu];
        self.derivatives
            .linearised(model, time, &self.q[mu], &self.p[mu])
    }

    /// Solve the stage equations for the unknowns by the simplified Newton method (the
    /// factorised Jacobian kept across iterations and steps while it contracts well).
    fn solve<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<Solved, StepFailure> {
        if h != self.tables.h {
            // The kept factors belong to another step size.
            self.tables.rescale(h);
            self.newton.invalidate();
        }
        self.derivatives.start(model, t, &state.q, &state.y)?;
        self.start(model, t, state)?;
        let mut unknowns = std::mem::take(&mut self.unknowns);
        let mut newton = std::mem::replace(&mut self.newton, Newton::new(0, 1));
        let mut failure = None;
        let result = newton.iterate(&mut unknowns, Jacobian::Kept, |z, jacobian, residual| {
            if let Err(error) = self.residual(model, t, state, z, jacobian, residual) {
                failure = Some(error);
                residual.fill(f64::NAN);
            }
        });
        self.newton = newton;
        self.unknowns = unknowns;
        if let Some(error) = failure {
            return Err(error);
        }
        let solved = result?;
        self.last_h = Some(h);
        self.last_start.copy_from(&state.q);
        Ok(solved)
    }

    /// Starting values: the last step's unknowns rescaled to this step (Δ ∝ h, Π ∝ h), or
    /// else the explicit Euler guess Δᵛ = (h/2)(x_ν + 1) ∂H/∂p, Π_μ = −(h/2)(τ_μ + 1) ∂H/∂q.
    fn start<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        state: &State<N>,
    ) -> Result<(), StepFailure> {
        let h = self.tables.h;
        // A failed solve leaves `last_h` at `None`: its unknowns are not a solution.
        if let Some(last_h) = self.last_h.take() {
            self.unknowns *= h / last_h;
            return Ok(());
        }
        let (hq, hp) = self.derivatives.field(model, t, &state.q, &state.y)?;
        let w = state.q.len();
        let s = self.tables.degree;
        for nu in 1..=s {
            let fraction = self.tables.unit_points[nu];
            for i in 0..w {
                self.unknowns[(nu - 1) * w + i] = h * fraction * hp[i];
            }
        }
        for (mu, &fraction) in self.tables.unit_nodes.iter().enumerate() {
            for i in 0..w {
                self.unknowns[(s + mu) * w + i] = -h * fraction * hq[i];
            }
        }
        Ok(())
    }

    /// The residual of the stage equations at `z`, and their Jacobian when asked.
    fn residual<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        state: &State<N>,
        z: &DVector<f64>,
        jacobian: Option<&mut DMatrix<f64>>,
        residual: &mut DVector<f64>,
    ) -> Result<(), StepFailure> {
        self.points(state, z);
        let w = state.q.len();
        let (s, m) = (self.tables.degree, self.tables.nodes.len());
        let half_h = 0.5 * self.tables.h;
        residual.fill(0.0);
        let mut jacobian = jacobian;
        if let Some(matrix) = jacobian.as_deref_mut() {
            matrix.fill(0.0);
        }
        for mu in 0..m {
            let (linear, (g, hp)) = if jacobian.is_some() {
                let linear = self.linearised_at(model, t, mu)?;
                let field = (linear.g.clone(), linear.hp.clone());
                (Some(linear), field)
            } else {
                (None, self.field_at(model, t, mu)?)
            };
            let tables = &self.tables;
            let (weight, reference_weight) = (tables.weights[mu], tables.reference_weights[mu]);
            // Rows ν < s: −Σ_μ w_μ l̇_ν Π_μ + Σ_μ (h/2) w_μ l_ν (∂H/∂q − f_H).
            let pi = &z.as_slice()[(s + mu) * w..(s + mu + 1) * w];
            for nu in 0..s {
                let (value, rate) = (
                    tables.values[(mu, nu)],
                    tables.reference_derivatives[(mu, nu)],
                );
                for i in 0..w {
                    residual[nu * w + i] +=
                        -reference_weight * rate * pi[i] + weight * value * g[i];
                }
            }
            // Rows of Gauss point μ: Σ_ν Δᵛ l̇_ν(τ_μ) − (h/2) ∂H/∂p.
            let row = (s + mu) * w;
            for nu in 1..=s {
                let rate = tables.reference_derivatives[(mu, nu)];
                for i in 0..w {
                    residual[row + i] += rate * z[(nu - 1) * w + i];
                }
            }
            for i in 0..w {
                residual[row + i] -= half_h * hp[i];
            }
            let (Some(matrix), Some(linear)) = (jacobian.as_deref_mut(), &linear) else {
                continue;
            };
            // ∂g/∂q, ∂g/∂p, ∂²H/∂q∂p (its transpose is ∂(∂H/∂p)/∂q) and ∂²H/∂p².
            let (qq, qp, pq, pp) = (&linear.gq, &linear.gp, &linear.qp, &linear.pp);
            let column_pi = (s + mu) * w;
            for nu in 0..s {
                let (value, rate) = (
                    tables.values[(mu, nu)],
                    tables.reference_derivatives[(mu, nu)],
                );
                // ∂/∂Δʲ: (h/2) w_μ l_ν l_j (H_qq − f_q).
                for j in 1..=s {
                    let factor = weight * value * tables.values[(mu, j)];
                    for b in 0..w {
                        for a in 0..w {
                            matrix[(nu * w + a, (j - 1) * w + b)] += factor * qq[(a, b)];
                        }
                    }
                }
                // ∂/∂Π_μ: −w_μ l̇_ν I + (h/2) w_μ l_ν (H_qp − f_p).
                for b in 0..w {
                    for a in 0..w {
                        matrix[(nu * w + a, column_pi + b)] += weight * value * qp[(a, b)];
                    }
                    matrix[(nu * w + b, column_pi + b)] -= reference_weight * rate;
                }
            }
            for j in 1..=s {
                let (value, rate) = (
                    tables.values[(mu, j)],
                    tables.reference_derivatives[(mu, j)],
                );
                // ∂/∂Δʲ: l̇_j I − (h/2) l_j H_pq.
                for b in 0..w {
                    for a in 0..w {
                        matrix[(row + a, (j - 1) * w + b)] -= half_h * value * pq[(b, a)];
                    }
                    matrix[(row + b, (j - 1) * w + b)] += rate;
                }
            }
            // ∂/∂Π_μ: −(h/2) H_pp.
            for b in 0..w {
                for a in 0..w {
                    matrix[(row + a, column_pi + b)] -= half_h * pp[(a, b)];
                }
            }
        }
        Ok(())
    }

    /// The increment of the converged step (after the work `solved`): Δˢ and
    /// −(h/2) Σ_μ w_μ (∂H/∂q − f_H)(μ).
    fn increment<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        state: &State<N>,
        solved: Solved,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let unknowns = std::mem::take(&mut self.unknowns);
        self.points(state, &unknowns);
        let w = state.q.len();
        let (s, m) = (self.tables.degree, self.tables.nodes.len());
        increment
            .q
            .as_mut_slice()
            .copy_from_slice(&unknowns.as_slice()[(s - 1) * w..s * w]);
        self.unknowns = unknowns;
        increment.y.fill(0.0);
        for mu in 0..m {
            let (g, _) = self.field_at(model, t, mu)?;
            increment.y.axpy(-self.tables.weights[mu], &g, 1.0);
        }
        Ok(StepReport {
            iterations: solved.iterations,
            evaluations: self.derivatives.evaluations,
            factorizations: solved.factorizations,
            analyses: 0,
        })
    }

    /// The step's Jacobian in (q_k, p_k) at the converged unknowns, by the implicit function
    /// theorem on the stage equations.
    fn tangent<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        state: &State<N>,
    ) -> Result<TangentMap<N>, StepFailure> {
        let w = state.q.len();
        let (s, m) = (self.tables.degree, self.tables.nodes.len());
        let size = (s + m) * w;
        let unknowns = self.unknowns.clone();
        let mut jacobian = DMatrix::zeros(size, size);
        let mut residual = DVector::zeros(size);
        self.residual(
            model,
            t,
            state,
            &unknowns,
            Some(&mut jacobian),
            &mut residual,
        )?;
        // ∂R/∂(q_k, p_k): the Gauss points move with q_k (∂q(τ_μ)/∂q_k = I) and P_μ with p_k.
        let mut sources = DMatrix::zeros(size, 2 * w);
        let mut derivatives = Vec::with_capacity(m);
        for mu in 0..m {
            let d = self.linearised_at(model, t, mu)?;
            let (qq, qp, pq, pp) = (&d.gq, &d.gp, &d.qp, &d.pp);
            let weight = self.tables.weights[mu];
            for nu in 0..s {
                let value = self.tables.values[(mu, nu)];
                for b in 0..w {
                    for a in 0..w {
                        sources[(nu * w + a, b)] += weight * value * qq[(a, b)];
                        sources[(nu * w + a, w + b)] += weight * value * qp[(a, b)];
                    }
                }
            }
            let row = (s + mu) * w;
            let half_h = 0.5 * self.tables.h;
            for b in 0..w {
                for a in 0..w {
                    sources[(row + a, b)] -= half_h * pq[(b, a)];
                    sources[(row + a, w + b)] -= half_h * pp[(a, b)];
                }
            }
            derivatives.push(d);
        }
        let lu = jacobian.lu();
        let sensitivity = -lu.solve(&sources).ok_or(StepFailure::SingularMatrix)?;
        let n = state.q.shape_generic().0;
        let mut tangent = TangentMap {
            qq: OMatrix::identity_generic(n, n),
            qy: OMatrix::zeros_generic(n, n),
            yq: OMatrix::zeros_generic(n, n),
            yy: OMatrix::identity_generic(n, n),
        };
        for a in 0..w {
            for b in 0..w {
                tangent.qq[(a, b)] += sensitivity[((s - 1) * w + a, b)];
                tangent.qy[(a, b)] += sensitivity[((s - 1) * w + a, w + b)];
            }
        }
        // p_{k+1} = p_k − Σ_μ (h/2) w_μ g_μ with g = ∂H/∂q − f_H at (q(τ_μ), P_μ).
        for (mu, d) in derivatives.iter().enumerate() {
            let (qq, qp) = (&d.gq, &d.gp);
            let weight = self.tables.weights[mu];
            // d q(τ_μ)/d(q_k, p_k) and d P_μ/d(q_k, p_k), N × 2N.
            let mut dq = DMatrix::zeros(w, 2 * w);
            let mut dp = DMatrix::zeros(w, 2 * w);
            for i in 0..w {
                dq[(i, i)] = 1.0;
                dp[(i, w + i)] = 1.0;
            }
            for nu in 1..=s {
                let value = self.tables.values[(mu, nu)];
                for i in 0..w {
                    for c in 0..2 * w {
                        dq[(i, c)] += value * sensitivity[((nu - 1) * w + i, c)];
                    }
                }
            }
            for i in 0..w {
                for c in 0..2 * w {
                    dp[(i, c)] += sensitivity[((s + mu) * w + i, c)];
                }
            }
            for a in 0..w {
                for c in 0..2 * w {
                    let mut change = 0.0;
                    for b in 0..w {
                        change += qq[(a, b)] * dq[(b, c)] + qp[(a, b)] * dp[(b, c)];
                    }
                    if c < w {
                        tangent.yq[(a, c)] -= weight * change;
                    } else {
                        tangent.yy[(a, c - w)] -= weight * change;
                    }
                }
            }
        }
        Ok(tangent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Initial;
    use crate::analysis::verify::observed_order;
    use crate::model::hamiltonian::{Canonical, Hamiltonian};
    use crate::scalar::Scalar;
    use crate::stepping::run::Integrator;
    use crate::test_models::{
        Damped, VariableMass, VariableMassH, advance, assert_tangent_matches_central_differences,
        distance, state,
    };
    use nalgebra::{SVector, U1, U2};

    /// The pendulum H = p²/2 − cos q, declared quadratic (`QUADRATIC`) or general.
    struct Pendulum<const QUADRATIC: bool>;
    impl<const QUADRATIC: bool> Hamiltonian<U1> for Pendulum<QUADRATIC> {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: HamiltonianStructure = if QUADRATIC {
            HamiltonianStructure::QuadraticKinetic
        } else {
            HamiltonianStructure::General
        };
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            p[0] * p[0] * 0.5 - q[0].cos()
        }
    }

    /// A relativistic oscillator H = √(1 + p²) + q²/2 (no closed-form Lagrangian is used).
    struct Relativistic;
    impl Hamiltonian<U1> for Relativistic {
        const TIME_DEPENDENT: bool = false;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
        }
    }

    /// [`Damped`] in Hamiltonian form: H = (p² + q²)/2, f_H = −c p, declared general.
    struct DampedH {
        c: f64,
    }
    impl Hamiltonian<U1> for DampedH {
        const TIME_DEPENDENT: bool = false;
        const FORCED: bool = true;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + q[0] * q[0]) * 0.5
        }
        fn external_force<D: Scalar>(
            &self,
            _t: D,
            _q: &SVector<D, 1>,
            p: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            p.map(|x| x * (-self.c))
        }
    }

    #[test]
    fn the_newton_path_is_svi_on_the_same_system_to_round_off() {
        // Leok–Zhang: for a hyperregular L the Galerkin discrete Hamiltonian and Lagrangian
        // maps coincide. H written by hand, H derived from L, and SVI on L.
        let start = state([0.5, -0.3], [0.4, 0.6]);
        for (points, quadrature) in [(3, 2), (5, 4), (7, 6)] {
            let svi = Svi::new(points).with_quadrature(quadrature);
            let galerkin = HamiltonianGalerkin::new(points).with_quadrature(quadrature);
            let (expected, _) = advance(&svi, &VariableMass, 0.1, 40, start);
            let (written, _) = advance(&galerkin, &Canonical::new(VariableMassH), 0.1, 40, start);
            let (derived, _) = advance(&galerkin, &VariableMass, 0.1, 40, start);
            for (what, state) in [("H written", written), ("H from L", derived)] {
                let error = distance(&state, &expected);
                assert!(error < 1e-13, "{points}/{quadrature} {what}: {error:e}");
            }
        }
    }

    #[test]
    fn a_forced_run_is_svis_lagrange_dalembert_run() {
        let start = state([1.0], [0.0]);
        let galerkin = HamiltonianGalerkin::new(4).with_quadrature(3);
        let svi = Svi::new(4).with_quadrature(3);
        let (expected, _) = advance(&svi, &Damped::<false> { c: 0.3 }, 0.2, 50, start);
        let (forced, _) = advance(
            &galerkin,
            &Canonical::new(DampedH { c: 0.3 }),
            0.2,
            50,
            start,
        );
        let error = distance(&forced, &expected);
        assert!(error < 1e-13, "{error:e}");
        // And both are the damped oscillator: q = e^{−ct/2}(cos ωt + c/(2ω) sin ωt),
        // ω = √(1 − c²/4), at t = 10 (order 6, h = 0.2).
        let (c, t) = (0.3f64, 10.0f64);
        let omega = (1.0 - c * c / 4.0).sqrt();
        let exact =
            (-c * t / 2.0).exp() * ((omega * t).cos() + c / (2.0 * omega) * (omega * t).sin());
        assert!(
            (forced.q[0] - exact).abs() < 1e-6,
            "{} {exact}",
            forced.q[0]
        );
    }

    #[test]
    fn a_quadratic_kinetic_energy_takes_the_fixed_point_and_the_same_map() {
        let start = state([2.0], [0.3]);
        let galerkin = HamiltonianGalerkin::new(6).with_quadrature(5);
        let (fixed, workspace) = advance(
            &galerkin,
            &Canonical::new(Pendulum::<true>),
            0.25,
            80,
            start,
        );
        assert!(matches!(
            workspace,
            HamiltonianGalerkinWorkspace::Quadratic(_)
        ));
        let (newton, workspace) = advance(
            &galerkin,
            &Canonical::new(Pendulum::<false>),
            0.25,
            80,
            start,
        );
        assert!(matches!(
            workspace,
            HamiltonianGalerkinWorkspace::General(_)
        ));
        let error = distance(&fixed, &newton);
        assert!(error < 1e-13, "{error:e}");
    }

    #[test]
    fn observed_orders_are_twice_the_degree() {
        // The relativistic oscillator to T = 4 at h = 0.2 and 0.1 against 9 points at h/8.
        let start = state([1.0], [0.5]);
        let model = Canonical::new(Relativistic);
        let end = 4.0f64;
        let reference = {
            let method = HamiltonianGalerkin::new(9).with_quadrature(8);
            advance(&method, &model, 0.0125, 320, start).0
        };
        for (points, order) in [(2, 2), (3, 4), (4, 6)] {
            let method = HamiltonianGalerkin::new(points).with_quadrature(points - 1);
            assert_eq!(Method::<U1>::info(&method).order, order);
            let steps = [0.2, 0.1];
            let errors: Vec<f64> = steps
                .iter()
                .map(|&h| {
                    let count = (end / h).round() as usize;
                    distance(&advance(&method, &model, h, count, start).0, &reference)
                })
                .collect();
            let observed = observed_order(&steps, &errors, 1e-13).unwrap();
            let listed: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
            eprintln!(
                "svi-h {points}/{}: errors at h = 0.2, 0.1: {}; observed order {observed:.2}",
                points - 1,
                listed.join(", ")
            );
            assert!(
                (observed - order as f64).abs() < 0.3,
                "{points} points: observed {observed:.2}, errors {errors:?}"
            );
        }
    }

    #[test]
    fn the_tangent_map_is_exact_and_symplectic() {
        let method = HamiltonianGalerkin::new(4).with_quadrature(3);
        let model = Canonical::new(VariableMassH);
        let start = state([0.5, -0.3], [0.4, 0.6]);
        assert_tangent_matches_central_differences(&method, &model, start);
        let mut workspace = Method::<U2>::workspace(&method, &model, 0.3).unwrap();
        let (_, tangent, _) = method
            .tangent_map(&model, &mut workspace, 0.0, 0.3, &start)
            .unwrap();
        let error = tangent.symplecticity_error();
        assert!(error < 1e-13, "{error:e}");
    }

    #[test]
    fn a_singular_hamiltonian_is_a_typed_error_naming_it() {
        /// H = p q + q²: linear in p.
        struct Singular;
        impl Hamiltonian<U1> for Singular {
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                p[0] * q[0] + q[0] * q[0]
            }
        }
        let integrator = Integrator::new(Canonical::new(Singular), HamiltonianGalerkin::new(3));
        let initial = Initial::Momentum {
            q: SVector::from([0.5]),
            p: SVector::from([0.2]),
        };
        let error = integrator
            .run(0.0, initial, 0.1, 1.0, &mut ())
            .unwrap_err()
            .to_string();
        assert!(error.contains("∂²H/∂p² is singular"), "{error}");
    }
}
