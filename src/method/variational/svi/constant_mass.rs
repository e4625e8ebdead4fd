//! The tables and buffers of the fixed-point iteration for constant-mass Lagrangians,
//! L = ½ q̇ᵀMq̇ − V(t, q): the stage equations (8a)–(8b) solved for the node offsets, and the
//! iteration run on the positions at the quadrature points (the Nyström form of the
//! Gauss–Legendre method for m = s; see [`NystromTables`]).

use super::add_scaled;
use crate::dimension::Dimension;
use crate::linalg::combination::{Rows, Start};
use crate::linalg::invert;
use crate::method::variational::tables::{Tables, unit_nodes};
use crate::model::mass_inverse::MassInverse;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::quadrature::GaussLegendre;
use crate::spectral::starting_values::StartingValues;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator, OVector, U1};

/// Tables and buffers of the fixed-point iteration for
/// [`Structure::ConstantMass`](crate::model::Structure::ConstantMass) Lagrangians,
/// L = ½ q̇ᵀMq̇ − V(t, q).
///
/// Then g_ν = Σ_j K_νj M qʲ + Σ_μ (h/2) w_μ l_ν(τ_μ) ∂L/∂q(τ_μ) with the stiffness matrix
/// K = (2/h) K̃, K̃_νj = Σ_μ w_μ l̇_ν(τ_μ) l̇_j(τ_μ), and (8a)–(8b) solve to
///
/// Z_j = h c_j M⁻¹p_k + h² Σ_μ P_jμ M⁻¹ ∂L/∂q(τ_μ),  j = 1, …, s,
///
/// for the offsets Z_j = qʲ − q_k, with c_j = −½ (K̃*⁻¹)_j0 and
/// P_jμ = −¼ Σ_ν (K̃*⁻¹)_jν w_μ l_ν(τ_μ), where K̃* keeps rows 0..s−1 and columns 1..s of K̃.
/// The iteration runs on the positions at the quadrature points, Q_μ = q_k + Σ_j l_j(τ_μ) Z_j:
///
/// Q_μ ← q_k + h c'_μ M⁻¹p_k + h² Σ_ν A_μν M⁻¹ ∂L/∂q(t_ν, Q_ν),  c' = l c,  A = l P,
///
/// so only the force ∂L/∂q is evaluated, never a Hessian: for m = s this is the Nyström form
/// of the Gauss–Legendre method.
///
/// It runs on the kicks L_μ = h b_μ ∂L/∂q(τ_μ) (b_μ = w_μ/2), the very numbers the momentum
/// update adds, p_{k+1} = p_k + Σ_μ L_μ:
///
/// Q_μ ← q_k + h c'_μ M⁻¹p_k + h Σ_ν K_μν M⁻¹L_ν,  q_{k+1} = q_k + h M⁻¹p_k + h Σ_ν d_ν M⁻¹L_ν,
///
/// with d_ν = 1 − c'_ν and K_μν = A_μν / b_ν = d_ν − G_μν. The step is symplectic for any
/// weights b exactly when c' + d = 1 and G is symmetric (the conditions b̄ = b(1 − c) and
/// b_i(b̄_j − A_ij) = b_j(b̄_i − A_ji) of a symplectic Runge–Kutta–Nyström method, divided by
/// b_i b_j), and both are made to hold in floating point: the rounded weights h b_μ are then
/// shared by the two updates instead of entering them once as h b_μ and once inside h²A and
/// h² b̄, whose different roundings broke the conditions by an ulp at every step, the same way
/// every time. Together with an iteration run to its noise ([`crate::nonlinear`]'s
/// `FixedPoint::to_noise`) the energy error of a long run random-walks (Brouwer's law)
/// instead of drifting: Kepler e = 0.5, SVI 13/12 with h = 0.143, largest energy error
/// 5.0e-14 after 1.4·10⁶ steps (6.7e-12 before), final position error at T = 2·10⁵ 3e-8
/// (3.5e-6 before); see Antoñana, Makazaga & Murua, *Reducing and monitoring round-off error
/// propagation for symplectic implicit Runge–Kutta schemes*, Numer. Algorithms 76 (2017).
///
/// With an external force f_L the discrete forces enter exactly like ∂L/∂q (same weights
/// l_ν(τ_μ) (h/2) w_μ), so the same iteration holds with ∂L/∂q + f_L(t_μ, Q_μ, V_μ). The
/// velocities at the quadrature points, V_μ = (2/h) Σ_j l̇_j(τ_μ) Z_j, are linear in the
/// same data (with h² M⁻¹ (∂L/∂q + f_L) = h M⁻¹L_ν / b_ν):
///
/// V_μ ← c''_μ M⁻¹p_k + h Σ_ν B_μν M⁻¹ (∂L/∂q + f_L)(t_ν, Q_ν, V_ν),
///
/// c''_μ = 2 Σ_j l̇_j(τ_μ) c_j, B_μν = 2 Σ_j l̇_j(τ_μ) P_jν, and are updated alongside Q_μ
/// (the stopping rule stays on Q_μ, so that a zero force reproduces the unforced iteration
/// bit for bit). The velocity dependence makes the iteration contract only by a factor
/// O(h ‖M⁻¹ ∂f_L/∂q̇‖) instead of O(h²‖M⁻¹ L_qq‖): a forced model whose iteration does not
/// converge (strong friction) falls back to Newton's method for the rest of the run.
/// The dimension-free tables of the fixed-point iteration (see [`ConstantMass`]).
#[derive(Debug, Clone)]
pub(crate) struct NystromTables {
    /// K_μν = d_ν − G_μν, row-major m × m: the stage map on the kicks (see [`ConstantMass`]).
    pub(crate) kick_matrix: Vec<f64>,
    /// Kᵀ, row-major: the adjoint's stage sums (`super::adjoint`).
    pub(crate) transposed_kick_matrix: Vec<f64>,
    /// d_μ = 1 − c'_μ, with c'_μ + d_μ = 1 exactly: the end point's weights on the kicks.
    pub(crate) end_fractions: Vec<f64>,
    /// c_j, j = 1..s.
    pub(crate) velocity_coefficients: Vec<f64>,
    /// P_jμ, row-major s × m.
    pub(crate) propagation: Vec<f64>,
    /// P_sμ in closed form, w_μ (1 − τ_μ)/4: the end-point update
    /// q_{k+1} − q_k = h M⁻¹p_k + h² Σ_μ P_sμ M⁻¹ ∂L/∂q(τ_μ) (the Nyström b̄ weights).
    pub(crate) end_weights: Vec<f64>,
    /// c'_μ.
    pub(crate) stage_velocity: Vec<f64>,
    /// l_j(τ_μ), row-major m × s (j = 1..s).
    pub(crate) stage_values: Vec<f64>,
    /// c''_μ (velocities at the quadrature points, forced models).
    pub(crate) stage_rate: Vec<f64>,
    /// B_μν, row-major m × m (velocities at the quadrature points, forced models).
    pub(crate) rate_matrix: Vec<f64>,
    /// W = l X, row-major m × s: the positions at this step's quadrature points from the
    /// previous step's node offsets, Q_μ = q_k + Σ_j W_μj Z_j (the starting values of
    /// [`StartingValues`] taken straight to the quadrature points).
    pub(crate) stage_extrapolation: Vec<f64>,
    /// E = W P, row-major m × m, and γ = W c: the same positions from the previous step's
    /// velocity term and accelerations, Q_μ = q_k + γ_μ h M⁻¹p_{k−1} + Σ_ν E_μν a_ν, so that
    /// a step needs no node offsets at all while nobody reads its polynomial.
    pub(crate) start_matrix: Vec<f64>,
    /// γ, see `start_matrix`.
    pub(crate) start_velocity: Vec<f64>,
    /// The step ratio `stage_extrapolation`, `start_matrix` and `start_velocity` were built
    /// for.
    pub(crate) extrapolation_ratio: f64,
}

/// The fixed-point iteration's tables and buffers on ℝᴺ (the iteration is described above
/// [`NystromTables`]).
#[derive(Debug, Clone)]
pub(super) struct ConstantMass<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The dimension-free tables.
    pub(super) nystrom: NystromTables,
    /// h M⁻¹p_k of the last converged step.
    pub(super) last_velocity: OVector<f64, N>,
    /// The scaled accelerations h² M⁻¹ ∂L/∂q(τ_μ) of the last converged step: with
    /// `last_velocity` they determine its node offsets, Z_j = c_j h M⁻¹p_k + Σ_μ P_jμ a_μ.
    pub(super) last_accelerations: Vec<OVector<f64, N>>,
    /// Whether the last step is remembered only by `last_velocity` and `last_accelerations`:
    /// its node offsets in [`StartingValues`] are still to be written ([`ConstantMass::settle`])
    /// before anything reads them.
    pub(super) pending: bool,
    /// M⁻¹, from the first step.
    pub(super) mass_inverse: Option<MassInverse<N>>,
    /// h M⁻¹p_k of this step.
    pub(super) velocity: OVector<f64, N>,
    /// The times of the quadrature points in this step.
    pub(super) times: Vec<f64>,
    /// ∂L/∂q at the quadrature points.
    pub(super) forces: Vec<OVector<f64, N>>,
    /// M⁻¹ ∂L/∂q at the quadrature points.
    pub(super) accelerations: Vec<OVector<f64, N>>,
    /// The momentum kicks L_μ = h b_μ ∂L/∂q(τ_μ) (b = w/2 on the unit interval).
    pub(super) loads: Vec<OVector<f64, N>>,
    /// h M⁻¹ L_μ.
    pub(super) kicks: Vec<OVector<f64, N>>,
    /// Σ_μ d_μ h M⁻¹ L_μ (the end point's part from the kicks).
    pub(super) end_kick: OVector<f64, N>,
    /// Positions Q_μ at the quadrature points.
    pub(super) positions: Vec<OVector<f64, N>>,
    /// q_k + h c'_μ M⁻¹p_k, the force-free part of Q_μ (fixed within a step).
    pub(super) bases: Vec<OVector<f64, N>>,
    /// Velocities V_μ at the quadrature points (forced models).
    pub(super) velocities: Vec<OVector<f64, N>>,
}

impl NystromTables {
    /// `None` when K̃* is singular (too few Gauss points): Newton's method is used instead.
    pub(crate) fn new(tables: &Tables) -> Option<Self> {
        let s = tables.degree;
        let m = tables.nodes.len();
        let d = &tables.reference_derivatives;
        let stiffness = DMatrix::from_fn(s, s, |nu, j| {
            (0..m)
                .map(|mu| tables.reference_weights[mu] * d[(mu, nu)] * d[(mu, j + 1)])
                .sum::<f64>()
        });
        let inverse = invert(&stiffness).ok()?;
        if !inverse.iter().all(|x| x.is_finite()) {
            return None;
        }
        // c_j = −½ (K̃*⁻¹)_j0 equals the node position (x_j + 1)/2 (a free particle moves
        // uniformly); the closed form avoids the inverse's round-off.
        let velocity_coefficients: Vec<f64> = tables.interpolation_nodes[1..]
            .iter()
            .map(|x| 0.5 * (x + 1.0))
            .collect();
        let propagation: Vec<f64> = (0..s * m)
            .map(|k| {
                let (j, mu) = (k / m, k % m);
                let load: f64 = (0..s)
                    .map(|nu| inverse[(j, nu)] * tables.values[(mu, nu)])
                    .sum();
                -0.25 * tables.reference_weights[mu] * load
            })
            .collect();
        let stage_values: Vec<f64> = (0..m * s)
            .map(|k| tables.values[(k / s, k % s + 1)])
            .collect();
        // c'_μ = Σ_j l_j(τ_μ) c_j is the quadrature node's position (τ_μ + 1)/2, and
        // d_μ = 1 − c_μ with c_μ + d_μ = 1 exactly (one of the two is at least ½, so that the
        // other is its exact difference from 1).
        let mut stage_velocity = unit_nodes(&tables.nodes);
        let end_fractions: Vec<f64> = stage_velocity
            .iter_mut()
            .map(|c| {
                let d = 1.0 - *c;
                *c = 1.0 - d;
                d
            })
            .collect();
        let stage_matrix = if m == s {
            gauss_nystrom_matrix(&tables.nodes)?
        } else {
            (0..m * m)
                .map(|k| {
                    let (mu, nu) = (k / m, k % m);
                    (0..s)
                        .map(|j| stage_values[mu * s + j] * propagation[j * m + nu])
                        .sum()
                })
                .collect()
        };
        // G_μν = d_ν − A_μν / b_ν (b = w/2), symmetric for a symplectic method: made so
        // exactly, then K = d − G.
        let mut symmetric = vec![0.0; m * m];
        for mu in 0..m {
            for nu in 0..m {
                let b = 0.5 * tables.reference_weights[nu];
                symmetric[mu * m + nu] = end_fractions[nu] - stage_matrix[mu * m + nu] / b;
            }
        }
        for mu in 0..m {
            for nu in mu + 1..m {
                let mean = 0.5 * (symmetric[mu * m + nu] + symmetric[nu * m + mu]);
                symmetric[mu * m + nu] = mean;
                symmetric[nu * m + mu] = mean;
            }
        }
        let kick_matrix: Vec<f64> = (0..m * m)
            .map(|k| end_fractions[k % m] - symmetric[k])
            .collect();
        let transposed_kick_matrix = (0..m * m)
            .map(|k| kick_matrix[(k % m) * m + k / m])
            .collect();
        let rate = |mu: usize, j: usize| 2.0 * d[(mu, j + 1)];
        let stage_rate = (0..m)
            .map(|mu| (0..s).map(|j| rate(mu, j) * velocity_coefficients[j]).sum())
            .collect();
        let rate_matrix = (0..m * m)
            .map(|k| {
                let (mu, nu) = (k / m, k % m);
                (0..s).map(|j| rate(mu, j) * propagation[j * m + nu]).sum()
            })
            .collect();
        let end_weights = unit_nodes(&tables.nodes)
            .iter()
            .zip(&tables.reference_weights)
            .map(|(c, w)| 0.5 * w * (1.0 - c))
            .collect();
        Some(NystromTables {
            kick_matrix,
            transposed_kick_matrix,
            end_fractions,
            velocity_coefficients,
            end_weights,
            propagation,
            stage_velocity,
            stage_values,
            stage_rate,
            rate_matrix,
            stage_extrapolation: vec![0.0; m * s],
            start_matrix: vec![0.0; m * m],
            start_velocity: vec![0.0; m],
            extrapolation_ratio: f64::NAN,
        })
    }

    /// W = l X, E = W P and γ = W c for the starting values' extrapolation table X (s × s)
    /// of step ratio `ratio`.
    pub(crate) fn build_extrapolation(&mut self, table: &[f64], ratio: f64, s: usize) {
        let m = self.stage_velocity.len();
        for mu in 0..m {
            for j in 0..s {
                self.stage_extrapolation[mu * s + j] = (0..s)
                    .map(|nu| self.stage_values[mu * s + nu] * table[nu * s + j])
                    .sum();
            }
            let row = &self.stage_extrapolation[mu * s..(mu + 1) * s];
            for nu in 0..m {
                self.start_matrix[mu * m + nu] =
                    (0..s).map(|j| row[j] * self.propagation[j * m + nu]).sum();
            }
            self.start_velocity[mu] = (0..s).map(|j| row[j] * self.velocity_coefficients[j]).sum();
        }
        self.extrapolation_ratio = ratio;
    }
}

impl<N: Dimension> ConstantMass<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Buffers of dimension `n`; `None` when K̃* is singular (too few Gauss points):
    /// Newton's method is used instead.
    pub(super) fn new(tables: &Tables, n: N) -> Option<Self> {
        let m = tables.nodes.len();
        let zero = OVector::zeros_generic(n, U1);
        Some(ConstantMass {
            nystrom: NystromTables::new(tables)?,
            last_velocity: zero.clone(),
            velocity: zero.clone(),
            last_accelerations: vec![zero.clone(); m],
            pending: false,
            mass_inverse: None,
            times: vec![0.0; m],
            forces: vec![zero.clone(); m],
            accelerations: vec![zero.clone(); m],
            loads: vec![zero.clone(); m],
            kicks: vec![zero.clone(); m],
            end_kick: zero.clone(),
            positions: vec![zero.clone(); m],
            bases: vec![zero.clone(); m],
            velocities: vec![zero; m],
        })
    }
}

impl<N: Dimension> ConstantMass<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Q_μ = q_k + Σ_j T_μj Z_j for node offsets Z_j (j = 1..s, stacked), with T the
    /// extrapolation W (`extrapolated`) or the interpolation l_j(τ_μ).
    pub(super) fn set_positions(
        &mut self,
        q: &OVector<f64, N>,
        extrapolated: bool,
        offsets: &[f64],
        s: usize,
    ) {
        let table = if extrapolated {
            &self.nystrom.stage_extrapolation
        } else {
            &self.nystrom.stage_values
        };
        for (position, row) in self.positions.iter_mut().zip(table.chunks_exact(s)) {
            sum_into(position, q, |sum| {
                for (w, offset) in row.iter().zip(offsets.chunks_exact(q.len())) {
                    for (total, x) in sum.as_mut_slice().iter_mut().zip(offset) {
                        *total += w * x;
                    }
                }
            });
        }
    }

    /// Q_μ = q_k + γ_μ h M⁻¹p_{k−1} + Σ_ν E_μν a_ν from the last step's pending data.
    pub(super) fn extrapolate_positions(&mut self, q: &OVector<f64, N>) {
        let rows = Rows {
            start: Start::Common(q),
            lead: Some((&self.nystrom.start_velocity, &self.last_velocity)),
            matrix: &self.nystrom.start_matrix,
            inputs: &self.last_accelerations,
        };
        N::combine_rows(&mut self.positions, rows);
    }

    /// Node offset Z_j (j = 0..s − 1 for the nodes 1..s) of the last converged step, from
    /// its velocity term and accelerations.
    pub(super) fn last_offset(&self, j: usize) -> OVector<f64, N> {
        let m = self.last_accelerations.len();
        let mut offset = &self.last_velocity * self.nystrom.velocity_coefficients[j];
        let row = &self.nystrom.propagation[j * m..(j + 1) * m];
        for (p, acceleration) in row.iter().zip(&self.last_accelerations) {
            add_scaled(&mut offset, *p, acceleration);
        }
        offset
    }

    /// Write the pending node offsets of the last step into `start` (see `pending`).
    pub(super) fn settle(&mut self, start: &mut StartingValues) {
        if !self.pending {
            return;
        }
        let width = self.last_velocity.len();
        for (j, target) in start.previous_mut().chunks_exact_mut(width).enumerate() {
            target.copy_from_slice(self.last_offset(j).as_slice());
        }
        self.pending = false;
    }
}

/// Ā = A² of the Gauss–Legendre collocation method on the nodes c_μ = (τ_μ + 1)/2, with
/// A_μν = ∫₀^{c_μ} ℓ_ν (ℓ the Lagrange basis on c), row-major.
///
/// With m = s the SVI stage map is this Nyström matrix. Computed from its definition it is
/// accurate to a few ulps, whereas the same matrix obtained through the inverse stiffness
/// matrix carries ~10⁻¹⁴ relative errors, and coefficient errors of that size, repeated
/// every step, put a floor near 10⁻¹¹ under long-run errors (Kepler, T = 2000).
fn gauss_nystrom_matrix(nodes: &[f64]) -> Option<Vec<f64>> {
    let m = nodes.len();
    let c = unit_nodes(nodes);
    let basis = LagrangeBasis::new(c.clone()).ok()?;
    let gauss = GaussLegendre::new(m).ok()?;
    let mut values = vec![0.0; m];
    let mut a = vec![0.0; m * m];
    for (i, ci) in c.iter().enumerate() {
        for (x, w) in gauss.nodes().iter().zip(gauss.weights()) {
            basis.values_into(0.5 * ci * (x + 1.0), &mut values);
            for (target, value) in a[i * m..(i + 1) * m].iter_mut().zip(&values) {
                *target += 0.5 * ci * w * value;
            }
        }
    }
    Some(
        (0..m * m)
            .map(|k| {
                let (i, j) = (k / m, k % m);
                (0..m).map(|l| a[i * m + l] * a[l * m + j]).sum()
            })
            .collect(),
    )
}

/// `target` = `start` + what `accumulate` adds to it: summed in a local for a fixed size
/// (kept in registers, not written through the reference), in place at run-time size (no
/// allocation).
#[inline(always)]
fn sum_into<N: Dimension>(
    target: &mut OVector<f64, N>,
    start: &OVector<f64, N>,
    accumulate: impl FnOnce(&mut OVector<f64, N>),
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if N::try_to_usize().is_some() {
        let mut sum = start.clone();
        accumulate(&mut sum);
        *target = sum;
    } else {
        target.copy_from(start);
        accumulate(target);
    }
}
