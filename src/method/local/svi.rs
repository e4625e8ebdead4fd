//! SVI on runtime-sized ℝⁿ for constant-mass [`LocalLagrangian`]s: the Hessian-free
//! fixed-point iteration of [`crate::Svi`] (see `method/variational/svi.rs`, "Tables and
//! buffers of the fixed-point iteration", for the derivation from eqs. (8a)–(8c)) with the
//! stage values stored as m runtime vectors of length n.
//!
//! With L = ½ q̇ᵀMq̇ − V(t, q) the stage equations at the m Gauss points reduce to
//!
//! Q_μ = q_k + c'_μ h M⁻¹p_k + Σ_ν A_μν a_ν,  a_ν = h² M⁻¹ ∂L/∂q(t_ν, Q_ν),
//!
//! iterated to round-off from the previous step's polynomial extrapolated to the new
//! quadrature points (Q_μ = q_k + γ_μ h M⁻¹p_{k−1} + Σ_ν E_μν a_ν^{k−1}, one m × m product);
//! then q_{k+1} − q_k = h M⁻¹p_k + Σ_μ b̄_μ a_μ and p_{k+1} − p_k = Σ_μ (h/2) w_μ ∂L/∂q(Q_μ)
//! (the discrete momentum balance, free of cancellation). The tables are the fixed-size
//! path's ([`crate::method::variational::svi::NystromTables`]), so both paths take the same
//! steps to round-off. Each iteration costs m assemblies of ∂L/∂q, O(m n); no matrix of size
//! n appears (M⁻¹ is applied as a diagonal, or factored once for moderate n).

use crate::Svi;
use crate::error::{Error, StepFailure};
use crate::method::local::mass::MassInverse;
use crate::method::local::{LocalMethod, constant_mass};
use crate::method::space::DynState;
use crate::method::variational::svi::{NystromTables, Tables};
use crate::method::{Coordinates, MethodInfo, StepReport};
use crate::model::local::{LocalLagrangian, LocalLagrangianExt};
use crate::nonlinear::FixedPoint;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::starting_values::StartingValues;
use nalgebra::DVector;

/// Buffers of an SVI run on runtime-sized ℝⁿ.
#[derive(Debug, Clone)]
pub struct LocalSviWorkspace {
    tables: Tables,
    nystrom: NystromTables,
    /// The extrapolation table of the previous step's polynomial (offsets unused).
    start: StartingValues,
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
    /// One vector of scratch.
    scratch: DVector<f64>,
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
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let tables = Tables::new(&basis, m, h)?;
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
        Ok(LocalSviWorkspace {
            tables,
            nystrom,
            start: StartingValues::new(&basis, 0),
            mass_inverse: None,
            velocity: DVector::zeros(n),
            last_velocity: DVector::zeros(n),
            positions: stages(),
            forces: stages(),
            accelerations: stages(),
            last_accelerations: stages(),
            scratch: DVector::zeros(n),
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
        if workspace.mass_inverse.is_none() {
            let inverse =
                constant_mass(model, "svi", t, &state.q).map_err(|_| StepFailure::Unsupported {
                    option: "structure",
                    reason: "svi on a runtime-dimension model needs a constant, invertible mass \
                             matrix (the sparse Newton path is not built yet)",
                })?;
            workspace.mass_inverse = Some(inverse);
        }
        if workspace.tables.h != h {
            workspace.tables.rescale(h);
        }
        let LocalSviWorkspace {
            tables,
            nystrom,
            start,
            mass_inverse: Some(mass_inverse),
            velocity,
            last_velocity,
            positions,
            forces,
            accelerations,
            last_accelerations,
            scratch,
        } = workspace
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
        let mut control = FixedPoint::new(self.max_iterations);
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
        increment.y.fill(0.0);
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
        })
    }

    fn local_restart(&self, workspace: &mut LocalSviWorkspace) {
        workspace.start.invalidate();
    }

    fn mass_inverse<'a>(&self, workspace: &'a LocalSviWorkspace) -> Option<&'a MassInverse> {
        workspace.mass_inverse.as_ref()
    }
}
