//! Sparse Newton for runtime-dimension Lagrangians without a constant mass matrix: the SVI
//! stage equations (8a)–(8b) and the inverse Legendre map, with Jacobians assembled term by
//! term into a sparsity pattern fixed once per run and solved through the linear-solver
//! seam ([`crate::linalg::sparse`]).
//!
//! # The stage equations
//! The unknowns are the node offsets Z_j = qʲ − q_k, j = 1, …, s, stored node-major
//! (Z_j occupies entries (j − 1)n … jn − 1). With b_μν = l_ν(τ_μ), d_μν = (2/h) l̇_ν(τ_μ) and
//! W_μ = (h/2) w_μ, the residual of node ν = 0, …, s − 1 is
//!
//! r_ν = δ_ν0 p_k + Σ_μ W_μ (b_μν ∂L/∂q + d_μν ∂L/∂q̇)(t_μ, q_μ, q̇_μ),
//!
//! q_μ = q_k + Σ_j b_μj Z_j, q̇_μ = Σ_j d_μj Z_j, and its Jacobian block (ν, j) is
//!
//! ∂r_ν/∂Z_j = Σ_μ W_μ [b_μν (L_qq b_μj + L_qq̇ d_μj) + d_μν (L_q̇q b_μj + L_q̇q̇ d_μj)].
//!
//! Every block has the pattern P of L's Hessian (the union of the terms' index sets), so the
//! (s n)² Jacobian has s² n·(nonzeros of P per row) entries; in node-major order the entry
//! ((ν, r), (j, c)) sits at slot colptr((j − 1)n + c) + ν·|P column c| + rank of r in it, which
//! each term precomputes for its K² pairs. Assembly is O(m s² K² · terms); the factorisation
//! is faer's sparse LU (fill-reducing ordering found once, in the symbolic analysis).
//!
//! # Simplified Newton
//! The factored Jacobian is kept across iterations and steps while the iteration contracts
//! (‖Δ_k‖ ≤ ½‖Δ_{k−1}‖), and refactored otherwise or when the step size changes; only the
//! residual defines the solution, so a stale Jacobian costs iterations, never accuracy. The
//! run's statistics count the numeric factorisations and the (one) symbolic analysis.

use crate::error::{Error, StepFailure};
use crate::linalg::sparse::{DenseSolver, LinearSolver, LinearSolverKind, Pattern, SparseLu};
use crate::method::space::DynState;
use crate::method::variational::svi::Tables;
use crate::model::local::{LocalLagrangian, TermDerivatives, TermWidth};
use crate::nonlinear::stalled;
use nalgebra::DVector;

/// A linear solver of either kind.
#[derive(Debug)]
enum AnySolver {
    Sparse(Box<SparseLu>),
    Dense(DenseSolver),
}

impl AnySolver {
    fn new(kind: LinearSolverKind) -> Self {
        match kind {
            LinearSolverKind::Sparse => AnySolver::Sparse(Box::default()),
            LinearSolverKind::Dense => AnySolver::Dense(DenseSolver::default()),
        }
    }

    fn get(&mut self) -> &mut dyn LinearSolver {
        match self {
            AnySolver::Sparse(solver) => solver.as_mut(),
            AnySolver::Dense(solver) => solver,
        }
    }
}

/// The widest term the Newton iterations take (their local buffers are this long).
const MAX_WIDTH: usize = 16;

/// The pattern P of L's Hessian and, per term, the slots of its K² pairs (row slot a,
/// column slot b, at index e·K² + a + K·b).
#[derive(Debug, Clone)]
struct TermPattern {
    pattern: Pattern,
    slots: Vec<usize>,
    width: usize,
}

impl TermPattern {
    fn new<L: LocalLagrangian>(model: &L) -> Result<Self, Error> {
        let n = model.dimension();
        let width = L::Width::WIDTH;
        if width > MAX_WIDTH {
            return Err(Error::invalid(
                "width",
                format!("terms {width} coordinates wide: Newton takes at most {MAX_WIDTH}"),
            ));
        }
        let mut entries = Vec::with_capacity(model.term_count() * width * width);
        for e in 0..model.term_count() {
            let indices = model.indices(e);
            for &col in indices.as_ref() {
                for &row in indices.as_ref() {
                    entries.push((row, col));
                }
            }
        }
        let pattern = Pattern::new(n, &entries)?;
        let slots = entries
            .iter()
            .map(|&(row, col)| pattern.slot(row, col).unwrap_or(usize::MAX))
            .collect();
        Ok(TermPattern {
            pattern,
            slots,
            width,
        })
    }
}

/// The inverse Legendre map q̇ = (∂L/∂q̇)⁻¹(p) by Newton's method with the sparse ∂²L/∂q̇².
#[derive(Debug)]
pub(crate) struct Legendre {
    terms: TermPattern,
    solver: AnySolver,
    values: Vec<f64>,
    derivatives: Vec<f64>,
    residual: DVector<f64>,
    correction: DVector<f64>,
    max_iterations: usize,
}

impl Legendre {
    pub(crate) fn new<L: LocalLagrangian>(
        model: &L,
        kind: LinearSolverKind,
    ) -> Result<Self, Error> {
        let terms = TermPattern::new(model)?;
        let mut solver = AnySolver::new(kind);
        solver.get().analyse(&terms.pattern)?;
        Ok(Legendre {
            values: vec![0.0; terms.pattern.len()],
            derivatives: vec![0.0; TermDerivatives { width: terms.width }.len()],
            residual: DVector::zeros(model.dimension()),
            correction: DVector::zeros(model.dimension()),
            terms,
            solver,
            max_iterations: 50,
        })
    }

    /// ∂L/∂q̇(t, q, v) − p into `self.residual` (and with `matrix` the values of ∂²L/∂q̇²);
    /// its largest absolute entry, NaN when one is not finite.
    fn residual<L: LocalLagrangian>(
        &mut self,
        model: &L,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        v: &DVector<f64>,
        matrix: bool,
    ) -> f64 {
        let layout = TermDerivatives {
            width: self.terms.width,
        };
        let k = self.terms.width;
        let (mut ql, mut vl) = ([0.0; MAX_WIDTH], [0.0; MAX_WIDTH]);
        if matrix {
            self.values.fill(0.0);
        }
        self.residual.copy_from(p);
        self.residual.neg_mut();
        for e in 0..model.term_count() {
            let indices = model.indices(e);
            let indices = indices.as_ref();
            for (a, &i) in indices.iter().enumerate() {
                ql[a] = q[i];
                vl[a] = v[i];
            }
            if matrix {
                L::Width::second_derivatives(
                    model,
                    e,
                    t,
                    &ql[..k],
                    &vl[..k],
                    &mut self.derivatives,
                );
            } else {
                L::Width::first_derivatives(model, e, t, &ql[..k], &vl[..k], &mut self.derivatives);
            }
            for (a, &i) in indices.iter().enumerate() {
                self.residual[i] += layout.v(&self.derivatives, a);
                if matrix {
                    for b in 0..k {
                        let slot = self.terms.slots[e * k * k + a + k * b];
                        self.values[slot] += layout.vv(&self.derivatives, a, b);
                    }
                }
            }
        }
        self.residual
            .iter()
            .try_fold(0.0f64, |m, x| x.is_finite().then(|| m.max(x.abs())))
            .unwrap_or(f64::NAN)
    }

    /// Solve ∂L/∂q̇(t, q, v) = p for v, starting from `v`: Newton's method, each step halved
    /// until ∂L/∂q̇ is finite again (a relativistic kinetic energy is defined only for
    /// |q̇| < c, and a full Newton step from rest can leave that domain).
    pub(crate) fn solve<L: LocalLagrangian>(
        &mut self,
        model: &L,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        v: &mut DVector<f64>,
    ) -> Result<(), Error> {
        let scale = p.amax().max(f64::MIN_POSITIVE);
        let failure = |iterations: usize, residual: f64| Error::LegendreMap {
            t,
            iterations,
            residual,
        };
        let mut size = self.residual(model, t, q, p, v, true);
        let mut previous = f64::INFINITY;
        for iteration in 0..self.max_iterations {
            if !size.is_finite() {
                return Err(failure(iteration, size));
            }
            if size <= 4.0 * f64::EPSILON * scale || stalled(size, previous, 1e-12, scale) {
                return Ok(());
            }
            previous = size;
            self.solver
                .get()
                .factor(&self.terms.pattern, &self.values)
                .map_err(|_| failure(iteration, size))?;
            self.solver
                .get()
                .solve_in_place(&mut self.residual)
                .map_err(|_| failure(iteration, size))?;
            std::mem::swap(&mut self.residual, &mut self.correction);
            let mut fraction = 1.0;
            loop {
                v.axpy(-fraction, &self.correction, 1.0);
                if self.residual(model, t, q, p, v, false).is_finite() || fraction < 1e-6 {
                    break;
                }
                v.axpy(fraction, &self.correction, 1.0);
                fraction *= 0.5;
            }
            size = self.residual(model, t, q, p, v, true);
        }
        Err(failure(self.max_iterations, previous))
    }
}

/// Work of one Newton solve of the stage equations.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct NewtonReport {
    pub(crate) iterations: usize,
    pub(crate) evaluations: usize,
    pub(crate) factorizations: usize,
}

/// The stage equations' pattern, solver and buffers.
#[derive(Debug)]
pub(crate) struct StageNewton {
    n: usize,
    s: usize,
    terms: TermPattern,
    /// The (s n)² Jacobian's pattern and values.
    pattern: Pattern,
    values: Vec<f64>,
    solver: AnySolver,
    /// Whether `solver` holds a factorisation for the current step size.
    factored: bool,
    /// Residual, then Newton correction.
    residual: DVector<f64>,
    /// q_μ and q̇_μ for every quadrature point.
    positions: Vec<DVector<f64>>,
    velocities: Vec<DVector<f64>>,
    derivatives: Vec<f64>,
    max_iterations: usize,
}

impl StageNewton {
    pub(crate) fn new<L: LocalLagrangian>(
        model: &L,
        s: usize,
        m: usize,
        kind: LinearSolverKind,
        max_iterations: usize,
    ) -> Result<Self, Error> {
        let n = model.dimension();
        let terms = TermPattern::new(model)?;
        let small = &terms.pattern;
        let mut entries = Vec::with_capacity(s * s * small.len());
        for j in 0..s {
            for col in 0..n {
                for nu in 0..s {
                    for row in small.column(col) {
                        entries.push((nu * n + row, j * n + col));
                    }
                }
            }
        }
        let pattern = Pattern::new(s * n, &entries)?;
        let mut solver = AnySolver::new(kind);
        solver.get().analyse(&pattern)?;
        Ok(StageNewton {
            n,
            s,
            values: vec![0.0; pattern.len()],
            pattern,
            terms,
            solver,
            factored: false,
            residual: DVector::zeros(s * n),
            positions: vec![DVector::zeros(n); m],
            velocities: vec![DVector::zeros(n); m],
            derivatives: vec![
                0.0;
                TermDerivatives {
                    width: L::Width::WIDTH
                }
                .len()
            ],
            max_iterations,
        })
    }

    /// Forget the factorisation (the step size changed).
    pub(crate) fn invalidate(&mut self) {
        self.factored = false;
    }

    /// The slot of ((ν, row), (j, col)) for term pair (a, b) whose small-pattern slot is
    /// `small_slot` in column `col`.
    #[inline]
    fn slot(&self, nu: usize, j: usize, col: usize, small_slot: usize) -> usize {
        let small = &self.terms.pattern;
        let start = small.column_start(col);
        let count = small.column_start(col + 1) - start;
        self.pattern.column_start(j * self.n + col) + nu * count + (small_slot - start)
    }

    /// q_μ, q̇_μ at every quadrature point from the offsets `z`.
    fn points(&mut self, tables: &Tables, q0: &DVector<f64>, z: &DVector<f64>) {
        let (n, s) = (self.n, self.s);
        for (mu, (q, v)) in self
            .positions
            .iter_mut()
            .zip(&mut self.velocities)
            .enumerate()
        {
            q.copy_from(q0);
            v.as_mut_slice().fill(0.0);
            for j in 1..=s {
                let node = z.rows((j - 1) * n, n);
                q.axpy(tables.values[(mu, j)], &node, 1.0);
                v.axpy(tables.derivatives[(mu, j)], &node, 1.0);
            }
        }
    }

    /// The residual r(z) into `self.residual`, and with `jacobian` the Jacobian's values.
    /// Returns the number of term evaluations.
    fn assemble<L: LocalLagrangian>(
        &mut self,
        model: &L,
        tables: &Tables,
        t: f64,
        state: &DynState,
        z: &DVector<f64>,
        jacobian: bool,
    ) -> usize {
        self.points(tables, &state.q, z);
        let (n, s, k) = (self.n, self.s, self.terms.width);
        let layout = TermDerivatives { width: k };
        self.residual.as_mut_slice().fill(0.0);
        self.residual.rows_mut(0, n).copy_from(&state.y);
        if jacobian {
            self.values.fill(0.0);
        }
        let (mut ql, mut vl) = ([0.0; MAX_WIDTH], [0.0; MAX_WIDTH]);
        let mut derivatives = std::mem::take(&mut self.derivatives);
        for mu in 0..self.positions.len() {
            let w = tables.weights[mu];
            let time = tables.time(t, mu);
            for e in 0..model.term_count() {
                let indices = model.indices(e);
                let indices = indices.as_ref();
                for (a, &i) in indices.iter().enumerate() {
                    ql[a] = self.positions[mu][i];
                    vl[a] = self.velocities[mu][i];
                }
                if jacobian {
                    L::Width::second_derivatives(
                        model,
                        e,
                        time,
                        &ql[..k],
                        &vl[..k],
                        &mut derivatives,
                    );
                } else {
                    L::Width::first_derivatives(
                        model,
                        e,
                        time,
                        &ql[..k],
                        &vl[..k],
                        &mut derivatives,
                    );
                }
                for nu in 0..s {
                    let (b, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
                    for (a, &i) in indices.iter().enumerate() {
                        self.residual[nu * n + i] +=
                            w * (b * layout.q(&derivatives, a) + c * layout.v(&derivatives, a));
                    }
                }
                if !jacobian {
                    continue;
                }
                for (bb, &col) in indices.iter().enumerate() {
                    for a in 0..k {
                        let small_slot = self.terms.slots[e * k * k + a + k * bb];
                        let (qq, qv) = (
                            layout.qq(&derivatives, a, bb),
                            layout.qv(&derivatives, a, bb),
                        );
                        let (vq, vv) = (
                            layout.qv(&derivatives, bb, a),
                            layout.vv(&derivatives, a, bb),
                        );
                        for j in 1..=s {
                            let (bj, cj) = (tables.values[(mu, j)], tables.derivatives[(mu, j)]);
                            let from_q = w * (qq * bj + qv * cj);
                            let from_v = w * (vq * bj + vv * cj);
                            for nu in 0..s {
                                let value = from_q * tables.values[(mu, nu)]
                                    + from_v * tables.derivatives[(mu, nu)];
                                let slot = self.slot(nu, j - 1, col, small_slot);
                                self.values[slot] += value;
                            }
                        }
                    }
                }
            }
        }
        self.derivatives = derivatives;
        self.positions.len() * model.term_count()
    }

    /// Solve the stage equations for the offsets `z` (on entry the starting values).
    pub(crate) fn solve<L: LocalLagrangian>(
        &mut self,
        model: &L,
        tables: &Tables,
        t: f64,
        state: &DynState,
        z: &mut DVector<f64>,
    ) -> Result<NewtonReport, StepFailure> {
        let mut report = NewtonReport::default();
        let mut previous = f64::INFINITY;
        loop {
            let refactor = !self.factored;
            report.evaluations += self.assemble(model, tables, t, state, z, refactor);
            if refactor {
                self.solver
                    .get()
                    .factor(&self.pattern, &self.values)
                    .map_err(|_| StepFailure::SingularMatrix)?;
                self.factored = true;
                report.factorizations += 1;
            }
            if self
                .solver
                .get()
                .solve_in_place(&mut self.residual)
                .is_err()
            {
                self.factored = false;
                return Err(StepFailure::SingularMatrix);
            }
            *z -= &self.residual;
            report.iterations += 1;
            let size = self.residual.amax();
            // The positions the offsets build, as they are now (from rest they start at 0).
            let scale = state.q.amax() + z.amax();
            if !size.is_finite() {
                self.factored = false;
                return Err(StepFailure::NonFinite);
            }
            if size <= 2.0 * f64::EPSILON * scale || stalled(size, previous, 1e-13, scale) {
                return Ok(report);
            }
            if report.iterations >= self.max_iterations {
                self.factored = false;
                return Err(StepFailure::NonConvergence {
                    iterations: report.iterations,
                    residual: size,
                });
            }
            // A stale Jacobian that contracts slowly is refreshed for the next iteration.
            if report.iterations > 1 && size > 0.5 * previous {
                self.factored = false;
            }
            previous = size;
        }
    }

    /// p_{k+1} − p_k = Σ_μ W_μ ∂L/∂q(t_μ, q_μ, q̇_μ) at the offsets `z`, into `dp`.
    pub(crate) fn momentum_increment<L: LocalLagrangian>(
        &mut self,
        model: &L,
        tables: &Tables,
        t: f64,
        q0: &DVector<f64>,
        z: &DVector<f64>,
        dp: &mut DVector<f64>,
    ) {
        self.points(tables, q0, z);
        let k = self.terms.width;
        let layout = TermDerivatives { width: k };
        let (mut ql, mut vl) = ([0.0; MAX_WIDTH], [0.0; MAX_WIDTH]);
        dp.as_mut_slice().fill(0.0);
        for mu in 0..self.positions.len() {
            let (w, time) = (tables.weights[mu], tables.time(t, mu));
            for e in 0..model.term_count() {
                let indices = model.indices(e);
                let indices = indices.as_ref();
                for (a, &i) in indices.iter().enumerate() {
                    ql[a] = self.positions[mu][i];
                    vl[a] = self.velocities[mu][i];
                }
                L::Width::first_derivatives(
                    model,
                    e,
                    time,
                    &ql[..k],
                    &vl[..k],
                    &mut self.derivatives,
                );
                for (a, &i) in indices.iter().enumerate() {
                    dp[i] += w * layout.q(&self.derivatives, a);
                }
            }
        }
    }
}
