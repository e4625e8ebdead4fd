//! SVI on runtime-sized ℝⁿ for [`LocalLagrangian`]s, by one of two stage solvers:
//!
//! - **the Hessian-free fixed point**, for a constant mass matrix: the iteration of
//!   [`crate::Svi`] (see `method/variational/svi.rs`, the tables of the fixed-point
//!   iteration, for the derivation from eqs. (8a)–(8c)) with the stage values stored as m
//!   runtime vectors of length n. With L = ½ q̇ᵀMq̇ − V(t, q),
//!
//!   Q_μ = q_k + c'_μ h M⁻¹p_k + Σ_ν A_μν a_ν,  a_ν = h² M⁻¹ ∂L/∂q(t_ν, Q_ν),
//!
//!   iterated to round-off from the previous step's polynomial extrapolated to the new
//!   quadrature points (Q_μ = q_k + γ_μ h M⁻¹p_{k−1} + Σ_ν E_μν a_ν^{k−1}, one m × m
//!   product); then q_{k+1} − q_k = h M⁻¹p_k + Σ_μ b̄_μ a_μ and
//!   p_{k+1} − p_k = Σ_μ (h/2) w_μ ∂L/∂q(Q_μ) (the discrete momentum balance). The tables
//!   are the fixed-size path's (`NystromTables` of [`crate::method::variational::svi`]), so both
//!   take the same steps to round-off; each iteration costs m assemblies of ∂L/∂q, O(m n).
//! - **sparse Newton** (`crate::method::variational::stage_newton`), for every other
//!   Lagrangian (and for constant mass with [`crate::Solver::Newton`]): the stage equations
//!   (8a)–(8b) in the node offsets with the exact Jacobian assembled term by term, factored by faer's sparse
//!   LU (symbolic analysis once per run, numeric factorisation only when the simplified
//!   Newton iteration stops contracting), started from the previous step's polynomial
//!   extrapolated (or, at a cold start, uniform motion with q̇ from the inverse Legendre map).
//!   p_{k+1} − p_k is the same momentum balance.

use std::cell::RefCell;

use crate::Svi;
use crate::error::{Error, StepFailure};
use crate::method::local::MassInverse;
use crate::method::local::{LocalMethod, cold_velocity, constant_mass};
use crate::method::space::DynState;
use crate::method::variational::stage_newton::StageNewton;
use crate::method::variational::svi::{NystromTables, Solver};
use crate::method::variational::tables::Tables;
use crate::method::{Coordinates, MethodInfo, StepReport};
use crate::model::Structure;
use crate::model::legendre::Legendre;
use crate::model::local::LocalLagrangian;
use crate::nonlinear::{FixedPoint, Jacobian};
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::starting_values::StartingValues;
use nalgebra::DVector;

/// Buffers of an SVI run on runtime-sized ℝⁿ.
#[derive(Debug)]
pub struct LocalSviWorkspace {
    tables: Tables,
    /// The extrapolation table of the previous step's polynomial.
    start: StartingValues,
    path: Path,
}

/// The stage solver of a run and its buffers.
#[derive(Debug)]
enum Path {
    FixedPoint(Box<FixedPointData>),
    Newton(Box<NewtonData>),
}

/// Buffers of the fixed-point iteration.
#[derive(Debug)]
struct FixedPointData {
    nystrom: NystromTables,
    /// M⁻¹, from the first step.
    mass_inverse: Option<MassInverse>,
    /// h M⁻¹p_k of this step, and of the last converged one.
    velocity: DVector<f64>,
    last_velocity: DVector<f64>,
    /// Positions Q_μ, forces ∂L/∂q(Q_μ), scaled accelerations a_μ; and the last converged
    /// step's accelerations.
    positions: Vec<DVector<f64>>,
    forces: Vec<DVector<f64>>,
    accelerations: Vec<DVector<f64>>,
    last_accelerations: Vec<DVector<f64>>,
    scratch: DVector<f64>,
}

/// Buffers of the sparse Newton iteration.
#[derive(Debug)]
struct NewtonData {
    stage: StageNewton,
    /// The inverse Legendre map (cold starts, and completing states for observers).
    legendre: RefCell<Legendre>,
    /// Node offsets Z_1..Z_s (node-major), of this step and of the last.
    offsets: DVector<f64>,
    previous: DVector<f64>,
    /// q̇ at the last cold start (the Newton start of the next inverse Legendre map).
    velocity: DVector<f64>,
    /// Symbolic analyses done when the workspace was built (the stage Jacobian's pattern
    /// and ∂²L/∂q̇²'s), not yet reported.
    analyses: usize,
}

impl LocalMethod for Svi {
    type Workspace = LocalSviWorkspace;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "svi",
            order: 2 * (self.points - 1).min(self.quadrature_points()),
            symmetric: true,
            symplectic: true,
            coordinates: Coordinates::Momentum,
        }
    }

    fn local_workspace<L: LocalLagrangian>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<LocalSviWorkspace, Error> {
        self.validate()?;
        crate::error::require_positive("h", h)?;
        let n = model.dimension();
        let m = self.quadrature_points();
        let s = self.points - 1;
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let tables = Tables::new(&basis, m, h)?;
        let fixed_point = L::STRUCTURE == Structure::ConstantMass && self.solver == Solver::Auto;
        let path = if fixed_point {
            let nystrom = NystromTables::new(&tables).ok_or_else(|| {
                Error::invalid(
                    "quadrature",
                    format!(
                        "{m} Gauss points are too few for {} CGL points (the stiffness matrix is \
                         singular)",
                        self.points
                    ),
                )
            })?;
            let stages = || vec![DVector::zeros(n); m];
            Path::FixedPoint(Box::new(FixedPointData {
                nystrom,
                mass_inverse: None,
                velocity: DVector::zeros(n),
                last_velocity: DVector::zeros(n),
                positions: stages(),
                forces: stages(),
                accelerations: stages(),
                last_accelerations: stages(),
                scratch: DVector::zeros(n),
            }))
        } else {
            Path::Newton(Box::new(NewtonData {
                stage: StageNewton::new(model, n, (s, m), self.linear_solver, self.max_iterations)?,
                legendre: RefCell::new(Legendre::new(model, n, self.linear_solver)?),
                offsets: DVector::zeros(s * n),
                previous: DVector::zeros(s * n),
                velocity: DVector::zeros(n),
                analyses: 2,
            }))
        };
        Ok(LocalSviWorkspace {
            tables,
            start: StartingValues::new(&basis, 0),
            path,
        })
    }

    fn local_step<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &mut LocalSviWorkspace,
        t: f64,
        h: f64,
        state: &DynState,
        increment: &mut DynState,
    ) -> Result<StepReport, StepFailure> {
        let LocalSviWorkspace {
            tables,
            start,
            path,
        } = workspace;
        if tables.h != h {
            tables.rescale(h);
            if let Path::Newton(data) = path {
                data.stage.invalidate();
            }
        }
        match path {
            Path::FixedPoint(data) => {
                fixed_point_step(self, model, tables, start, data, t, h, state, increment)
            }
            Path::Newton(data) => newton_step(model, tables, start, data, t, h, state, increment),
        }
    }

    fn local_restart(&self, workspace: &mut LocalSviWorkspace) {
        workspace.start.invalidate();
    }

    fn local_velocity<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &LocalSviWorkspace,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        v: &mut DVector<f64>,
    ) -> Result<(), Error> {
        match &workspace.path {
            Path::FixedPoint(data) => match &data.mass_inverse {
                Some(inverse) => {
                    inverse.apply_into(p, v);
                    Ok(())
                }
                None => cold_velocity(model, t, q, p, v),
            },
            Path::Newton(data) => data.legendre.borrow_mut().solve(
                model,
                t,
                q.as_slice(),
                p.as_slice(),
                v.as_mut_slice(),
            ),
        }
    }
}

/// One step by sparse Newton (see the module docs).
#[allow(clippy::too_many_arguments)]
fn newton_step<L: LocalLagrangian>(
    model: &L,
    tables: &Tables,
    start: &mut StartingValues,
    data: &mut NewtonData,
    t: f64,
    h: f64,
    state: &DynState,
    increment: &mut DynState,
) -> Result<StepReport, StepFailure> {
    let n = state.q.len();
    let s = tables.degree;
    // Starting values: the last step's polynomial extrapolated, or uniform motion.
    if start.prepare(h) {
        let (table, _) = start.table();
        data.offsets.as_mut_slice().fill(0.0);
        for nu in 0..s {
            for j in 0..s {
                let x = table[nu * s + j];
                let (source, target) = (data.previous.rows(j * n, n), nu * n);
                data.offsets.rows_mut(target, n).axpy(x, &source, 1.0);
            }
        }
    } else {
        data.legendre
            .borrow_mut()
            .solve(
                model,
                t,
                state.q.as_slice(),
                state.y.as_slice(),
                data.velocity.as_mut_slice(),
            )
            .map_err(|_| StepFailure::NonConvergence {
                iterations: 0,
                residual: f64::NAN,
            })?;
        for j in 0..s {
            let c = tables.unit_points[j + 1] * h;
            data.offsets
                .rows_mut(j * n, n)
                .copy_from(&(&data.velocity * c));
        }
    }
    let report = data.stage.solve(
        model,
        tables,
        t,
        (state.q.as_slice(), state.y.as_slice()),
        &mut data.offsets,
        Jacobian::Kept,
    )?;
    increment.q.copy_from(&data.offsets.rows((s - 1) * n, n));
    data.stage.momentum_increment(
        model,
        tables,
        t,
        state.q.as_slice(),
        &data.offsets,
        increment.y.as_mut_slice(),
    );
    std::mem::swap(&mut data.offsets, &mut data.previous);
    start.remember_size(h);
    Ok(StepReport {
        iterations: report.iterations,
        evaluations: tables.weights.len() * data.stage.term_count() * (report.iterations + 1),
        factorizations: report.factorizations,
        analyses: std::mem::take(&mut data.analyses),
    })
}

/// One step by the fixed-point iteration (see the module docs).
#[allow(clippy::too_many_arguments)]
fn fixed_point_step<L: LocalLagrangian>(
    method: &Svi,
    model: &L,
    tables: &Tables,
    start: &mut StartingValues,
    data: &mut FixedPointData,
    t: f64,
    h: f64,
    state: &DynState,
    increment: &mut DynState,
) -> Result<StepReport, StepFailure> {
    if data.mass_inverse.is_none() {
        let inverse =
            constant_mass(model, "svi", t, &state.q).map_err(|_| StepFailure::Unsupported {
                option: "structure",
                reason: "svi's fixed point needs a constant, invertible mass matrix",
            })?;
        data.mass_inverse = Some(inverse);
    }
    let FixedPointData {
        nystrom,
        mass_inverse: Some(mass_inverse),
        velocity,
        last_velocity,
        positions,
        forces,
        accelerations,
        last_accelerations,
        scratch,
    } = data
    else {
        return Err(StepFailure::SingularMatrix);
    };
    let s = tables.degree;
    let m = positions.len();
    mass_inverse.apply_into(&state.y, velocity);
    *velocity *= h;
    // Starting positions: the last step's polynomial extrapolated, or uniform motion.
    if start.prepare(h) {
        let (table, ratio) = start.table();
        if ratio != nystrom.extrapolation_ratio {
            nystrom.build_extrapolation(table, ratio, s);
        }
        for (mu, position) in positions.iter_mut().enumerate() {
            let gamma = nystrom.start_velocity[mu];
            position.zip_zip_apply(&state.q, last_velocity, |x, q, u| *x = q + gamma * u);
            for (e, a) in nystrom.start_matrix[mu * m..(mu + 1) * m]
                .iter()
                .zip(last_accelerations.iter())
            {
                position.axpy(*e, a, 1.0);
            }
        }
    } else {
        for (position, c) in positions.iter_mut().zip(&nystrom.stage_velocity) {
            position.zip_zip_apply(&state.q, velocity, |x, q, u| *x = q + c * u);
        }
    }
    let size = state.q.amax() + velocity.amax();
    let mut control = FixedPoint::new(method.max_iterations);
    loop {
        for (mu, ((force, acceleration), position)) in forces
            .iter_mut()
            .zip(accelerations.iter_mut())
            .zip(positions.iter())
            .enumerate()
        {
            model.force_into(tables.time(t, mu), position, &state.y, force);
            mass_inverse.apply_into(force, acceleration);
            *acceleration *= h * h;
        }
        let mut change: f64 = 0.0;
        for (mu, position) in positions.iter_mut().enumerate() {
            let c = nystrom.stage_velocity[mu];
            scratch.zip_zip_apply(&state.q, velocity, |x, q, u| *x = q + c * u);
            for (a, acceleration) in nystrom.stage_matrix[mu * m..(mu + 1) * m]
                .iter()
                .zip(accelerations.iter())
            {
                scratch.axpy(*a, acceleration, 1.0);
            }
            for (next, old) in scratch.iter().zip(position.iter()) {
                let difference = (next - old).abs();
                if difference > change || difference.is_nan() {
                    change = difference;
                }
            }
            std::mem::swap(position, scratch);
        }
        if control.converged(change, size)? {
            break;
        }
    }
    increment.y.as_mut_slice().fill(0.0);
    for (force, w) in forces.iter().zip(&tables.weights) {
        increment.y.axpy(*w, force, 1.0);
    }
    increment.q.copy_from(velocity);
    for (w, acceleration) in nystrom.end_weights.iter().zip(accelerations.iter()) {
        increment.q.axpy(*w, acceleration, 1.0);
    }
    std::mem::swap(velocity, last_velocity);
    std::mem::swap(accelerations, last_accelerations);
    start.remember_size(h);
    let iterations = control.iterations();
    Ok(StepReport {
        iterations,
        evaluations: m * iterations,
        ..StepReport::default()
    })
}
