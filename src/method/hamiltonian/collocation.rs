//! Spectral collocation on Hamilton's equations (`sc-h`): SC's Chebyshev–Gauss–Lobatto
//! collocation ([`crate::SpectralCollocation`]) of the first-order system in z = (q, p).
//!
//! On [t, t + h] both q and p are polynomials of degree s through the s + 1 CGL nodes
//! c_0, …, c_s with z(c_0) = z_k, collocated at c_1, …, c_s: with the differentiation
//! weights Λ = D̃⁽¹⁾(1:s, 0:s) on [−1, 1] (Li, Wu, Leok 2018, eq. 21),
//!
//! Σ_j Λ_νj z_j = (h/2) F(t_ν, z_ν),  F = (∂H/∂p, −∂H/∂q + f_H),  ν = 1, …, s,
//!
//! and z_{k+1} = z_s. The unknowns are the offsets Δ_ν = z_ν − z_k (Σ_j Λ_νj = 0 takes z_k
//! out of the equations exactly), solved by Newton's method with the Jacobian
//! Λ_νj I − δ_νj (h/2) ∂F/∂z(ν), ∂F/∂z = [[∂²H/∂p∂q, ∂²H/∂p²], [−∂g/∂q, −∂g/∂p]] with
//! g = ∂H/∂q − f_H, from H's Hessian blocks ([`super::Derivatives`]).
//!
//! # Properties
//! The same collocation nodes as SC, so the same order (s for s + 1 points: the order of the
//! interpolatory quadrature on c_1, …, c_s), neither symmetric nor symplectic. Where the
//! Legendre map is linear, p = M q̇ with a constant M, the collocation polynomials of (q, p)
//! and of (q, q̇) are the same up to M, so `sc-h` on H and `sc` on L take the same steps
//! (tested to round-off).
//!
//! # References
//! Li, Wu, Leok (2018), §3, eqs. (12)–(25), written for Hamilton's equations as Porcù &
//! Penati's `spectralvarint` (`002`) writes its systems.

use super::{Derivatives, Linearised, offset, solve};
use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure};
use crate::method::collocation::SpectralCollocation;
use crate::method::{Coordinates, Equations, Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use crate::nonlinear::Newton;
use crate::spectral::basis::LagrangeBasis;
use crate::spectral::check_options;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector};

/// Options of spectral collocation on Hamilton's equations (`sc-h:P`).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct HamiltonianCollocation {
    /// Number of Chebyshev–Gauss–Lobatto points s + 1 (polynomial degree s), at least 2.
    pub points: usize,
    /// Cap on Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for HamiltonianCollocation {
    fn default() -> Self {
        let sc = SpectralCollocation::default();
        HamiltonianCollocation {
            points: sc.points,
            max_iterations: sc.max_iterations,
        }
    }
}

impl HamiltonianCollocation {
    /// `points` CGL points.
    pub fn new(points: usize) -> Self {
        HamiltonianCollocation {
            points,
            ..Self::default()
        }
    }
}

/// The buffers of one run of [`HamiltonianCollocation`].
#[derive(Debug, Clone)]
pub struct HamiltonianCollocationWorkspace<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    derivatives: Derivatives<N>,
    newton: Newton,
    /// Λ_νj, ν = 1, …, s (rows), j = 0, …, s (columns), on [−1, 1].
    weights: DMatrix<f64>,
    /// The CGL nodes on [0, 1].
    nodes: Vec<f64>,
    /// (Δ_1, …, Δ_s), each (Δq, Δp).
    unknowns: DVector<f64>,
    /// The step of the last converged solve, whose unknowns (still in `unknowns`) start
    /// the next one.
    last_h: Option<f64>,
}

impl<N: Dimension> Method<N> for HamiltonianCollocation
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Workspace = HamiltonianCollocationWorkspace<N>;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "sc-h",
            order: Method::<N>::info(&SpectralCollocation::new(self.points)).order,
            symmetric: false,
            symplectic: false,
            coordinates: Coordinates::Momentum,
            equations: Equations::Hamilton,
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<HamiltonianCollocationWorkspace<N>, Error> {
        check_options(self.points, None, self.max_iterations)?;
        crate::error::require_positive("h", h)?;
        let n = dimension_of::<N>(model.dimension())
            .map_err(|reason| Error::invalid("model", reason))?;
        let basis = LagrangeBasis::chebyshev_gauss_lobatto(self.points)?;
        let s = self.points - 1;
        let weights = basis.differentiation_matrix().rows(1, s).into_owned();
        let size = 2 * s * n.value();
        Ok(HamiltonianCollocationWorkspace {
            derivatives: Derivatives::new(model, n),
            newton: Newton::new(size, self.max_iterations),
            weights,
            nodes: basis.nodes().iter().map(|x| 0.5 * (x + 1.0)).collect(),
            unknowns: DVector::zeros(size),
            last_h: None,
        })
    }

    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut HamiltonianCollocationWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let iterations = workspace.solve(model, t, h, state)?;
        let (w, s) = (state.q.len(), self.points - 1);
        let last = &workspace.unknowns.as_slice()[2 * (s - 1) * w..2 * s * w];
        increment.q.as_mut_slice().copy_from_slice(&last[..w]);
        increment.y.as_mut_slice().copy_from_slice(&last[w..]);
        Ok(StepReport {
            iterations,
            evaluations: workspace.derivatives.evaluations,
            factorizations: iterations,
            analyses: 0,
        })
    }

    fn restart(&self, workspace: &mut HamiltonianCollocationWorkspace<N>) {
        workspace.last_h = None;
    }

    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &HamiltonianCollocationWorkspace<N>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        Ok(workspace.derivatives.velocity_into(model, t, q, p, v))
    }

    fn points(&self) -> Option<usize> {
        Some(self.points)
    }

    fn with_points(&self, points: usize) -> Option<Self> {
        Some(HamiltonianCollocation {
            points,
            ..self.clone()
        })
    }

    /// The implicit function theorem on the collocation equations: with J their Jacobian in
    /// the offsets, ∂Δ/∂z_k = J⁻¹ ((h/2) ∂F/∂z(ν))_ν, and z_{k+1} = z_k + Δ_s.
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut HamiltonianCollocationWorkspace<N>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let n = state.q.shape_generic().0;
        let mut increment = State::zeros(n);
        let report = self.step(model, workspace, t, h, state, &mut increment)?;
        let (w, s) = (state.q.len(), self.points - 1);
        let size = 2 * s * w;
        let unknowns = workspace.unknowns.clone();
        let mut jacobian = DMatrix::zeros(size, size);
        let mut residual = DVector::zeros(size);
        workspace.assemble(model, t, h, state, &unknowns, &mut jacobian, &mut residual)?;
        // ∂R_ν/∂z_k = −(h/2) ∂F/∂z(ν): the nodes move with z_k.
        let mut sources = DMatrix::zeros(size, 2 * w);
        for nu in 0..s {
            let (q, p, time) = workspace.node(t, h, state, &unknowns, nu);
            let field = workspace.derivatives.linearised(model, time, &q, &p)?;
            add_field_jacobian(&field, 0.5 * h, &mut sources, (2 * nu * w, 0));
        }
        let sensitivity = jacobian
            .lu()
            .solve(&sources)
            .ok_or(StepFailure::SingularMatrix)?;
        let end = sensitivity.rows(2 * (s - 1) * w, 2 * w);
        let mut tangent = TangentMap {
            qq: OMatrix::identity_generic(n, n),
            qy: OMatrix::zeros_generic(n, n),
            yq: OMatrix::zeros_generic(n, n),
            yy: OMatrix::identity_generic(n, n),
        };
        for a in 0..w {
            for b in 0..w {
                tangent.qq[(a, b)] += end[(a, b)];
                tangent.qy[(a, b)] += end[(a, w + b)];
                tangent.yq[(a, b)] += end[(w + a, b)];
                tangent.yy[(a, b)] += end[(w + a, w + b)];
            }
        }
        Ok((increment, tangent, report))
    }
}

/// Add `weight` · ∂F/∂z of F = (∂H/∂p, −g) at one node to the 2N × 2N block at (`row`,
/// `column`) of `target`.
fn add_field_jacobian<N: Dimension>(
    field: &Linearised<N>,
    weight: f64,
    target: &mut DMatrix<f64>,
    (row, column): (usize, usize),
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let w = field.hp.len();
    for b in 0..w {
        for a in 0..w {
            target[(row + a, column + b)] += weight * field.qp[(b, a)];
            target[(row + a, column + w + b)] += weight * field.pp[(a, b)];
            target[(row + w + a, column + b)] -= weight * field.gq[(a, b)];
            target[(row + w + a, column + w + b)] -= weight * field.gp[(a, b)];
        }
    }
}

impl<N: Dimension> HamiltonianCollocationWorkspace<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Solve the collocation equations of the step from `state` by Newton's method.
    fn solve<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<usize, StepFailure> {
        self.derivatives.start(model, t, &state.q, &state.y)?;
        self.start(model, t, h, state)?;
        let mut unknowns = std::mem::take(&mut self.unknowns);
        let mut newton = std::mem::replace(&mut self.newton, Newton::new(0, 1));
        let result = solve(&mut newton, &mut unknowns, |z, jacobian, residual| {
            self.assemble(model, t, h, state, z, jacobian, residual)
        });
        self.newton = newton;
        self.unknowns = unknowns;
        let iterations = result?;
        self.last_h = Some(h);
        Ok(iterations)
    }

    /// Starting values: the last step's offsets rescaled to this step, or else the explicit
    /// Euler guess Δ_ν = c_ν h F(t, z_k).
    fn start<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(), StepFailure> {
        // A failed solve leaves `last_h` at `None`: its unknowns are not a solution.
        if let Some(last_h) = self.last_h.take() {
            self.unknowns *= h / last_h;
            return Ok(());
        }
        let (g, hp) = self.derivatives.field(model, t, &state.q, &state.y)?;
        let w = state.q.len();
        for (nu, &node) in self.nodes.iter().enumerate().skip(1) {
            let block = &mut self.unknowns.as_mut_slice()[2 * (nu - 1) * w..2 * nu * w];
            for i in 0..w {
                block[i] = h * node * hp[i];
                block[w + i] = -h * node * g[i];
            }
        }
        Ok(())
    }

    /// (q, p, t) at collocation node ν + 1 for the offsets `z`.
    fn node(
        &self,
        t: f64,
        h: f64,
        state: &State<N>,
        z: &DVector<f64>,
        nu: usize,
    ) -> (OVector<f64, N>, OVector<f64, N>, f64) {
        let w = state.q.len();
        let block = &z.as_slice()[2 * nu * w..2 * (nu + 1) * w];
        (
            offset(&state.q, 1.0, &block[..w]),
            offset(&state.y, 1.0, &block[w..]),
            t + h * self.nodes[nu + 1],
        )
    }

    /// The residual Σ_j Λ_νj Δ_j − (h/2) F(t_ν, z_k + Δ_ν) at `z`, and its Jacobian.
    #[allow(clippy::too_many_arguments)]
    fn assemble<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
        z: &DVector<f64>,
        jacobian: &mut DMatrix<f64>,
        residual: &mut DVector<f64>,
    ) -> Result<(), StepFailure> {
        let w = state.q.len();
        let s = self.weights.nrows();
        jacobian.fill(0.0);
        residual.fill(0.0);
        for nu in 0..s {
            let (q, p, time) = self.node(t, h, state, z, nu);
            let field = self.derivatives.linearised(model, time, &q, &p)?;
            let row = 2 * nu * w;
            for j in 0..s {
                let weight = self.weights[(nu, j + 1)];
                for i in 0..2 * w {
                    residual[row + i] += weight * z[2 * j * w + i];
                    jacobian[(row + i, 2 * j * w + i)] += weight;
                }
            }
            for i in 0..w {
                residual[row + i] -= 0.5 * h * field.hp[i];
                residual[row + w + i] += 0.5 * h * field.g[i];
            }
            add_field_jacobian(&field, -0.5 * h, jacobian, (row, row));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::verify::observed_order;
    use crate::model::hamiltonian::{Canonical, Hamiltonian, HamiltonianStructure};
    use crate::scalar::Scalar;
    use crate::test_models::{
        HenonHeiles, VariableMassH, advance, assert_tangent_matches_central_differences, distance,
        state,
    };
    use nalgebra::{SMatrix, SVector, U1, U2};

    /// [`HenonHeiles`] (M = [[2, 1], [1, 3]]) as H = ½ pᵀM⁻¹p + V, M⁻¹ = [[3, −1], [−1, 2]]/5.
    struct HenonHeilesH;
    impl Hamiltonian<U2> for HenonHeilesH {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
            let kinetic = (p[0] * p[0] * 3.0 - p[0] * p[1] * 2.0 + p[1] * p[1] * 2.0) * 0.1;
            kinetic + q.dot(q) * 0.5 + q[0] * q[0] * q[1] - q[1].powi(3) / 3.0
        }
    }

    /// A relativistic oscillator H = √(1 + p²) + q²/2.
    struct Relativistic;
    impl Hamiltonian<U1> for Relativistic {
        const TIME_DEPENDENT: bool = false;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
        }
    }

    #[test]
    fn with_a_constant_mass_it_takes_scs_steps() {
        let mass = SMatrix::<f64, 2, 2>::new(2.0, 1.0, 1.0, 3.0);
        let (q0, v0) = (SVector::from([0.3, -0.2]), SVector::from([0.1, 0.25]));
        for points in [3, 6] {
            let (lagrangian, _) = advance(
                &SpectralCollocation::new(points),
                &HenonHeiles::<false>,
                0.1,
                50,
                State { q: q0, y: v0 },
            );
            let (hamiltonian, _) = advance(
                &HamiltonianCollocation::new(points),
                &Canonical::new(HenonHeilesH),
                0.1,
                50,
                State {
                    q: q0,
                    y: mass * v0,
                },
            );
            let expected = State {
                q: lagrangian.q,
                y: mass * lagrangian.y,
            };
            let error = distance(&hamiltonian, &expected);
            // Round-off of 50 steps and of p = M q̇ (entries up to 3).
            assert!(error < 5e-13, "{points} points: {error:e}");
        }
    }

    #[test]
    fn observed_orders_are_those_of_sc() {
        let start = state([1.0], [0.5]);
        let model = Canonical::new(Relativistic);
        let end = 4.0f64;
        let reference = advance(&HamiltonianCollocation::new(12), &model, 0.01, 400, start).0;
        for points in [3, 4, 5] {
            let method = HamiltonianCollocation::new(points);
            let order = Method::<U1>::info(&method).order;
            let steps = [0.1, 0.05];
            let errors: Vec<f64> = steps
                .iter()
                .map(|&h| {
                    let count = (end / h).round() as usize;
                    distance(&advance(&method, &model, h, count, start).0, &reference)
                })
                .collect();
            let observed = observed_order(&steps, &errors, 1e-13).unwrap();
            assert!(
                (observed - order as f64).abs() < 0.3,
                "{points} points: order {order}, observed {observed:.2}, errors {errors:?}"
            );
        }
    }

    #[test]
    fn the_tangent_map_is_exact() {
        let method = HamiltonianCollocation::new(4);
        let start = state([0.5, -0.3], [0.4, 0.6]);
        assert_tangent_matches_central_differences(&method, &Canonical::new(VariableMassH), start);
    }
}
