//! The adjoint and the tangent of a constant-mass SVI step by its Nyström form, without the
//! tangent map.
//!
//! For L = ½ q̇ᵀMq̇ − V(t, q) and no external force, the step solves (see
//! [`ConstantMass`](super::constant_mass::ConstantMass), with G = M⁻¹, the force
//! F = ∂L/∂q and the weights W_ν = (h/2) w_ν)
//!
//! Q_μ = q + c'_μ hGp + Σ_ν K_μν hG W_ν F(Q_ν),
//! p' = p + Σ_ν W_ν F(Q_ν),  q' = q + hGp + Σ_ν d_ν hG W_ν F(Q_ν).
//!
//! Linearised, with the force Jacobians J_ν = ∂F/∂q(Q_ν) = ∂²L/∂q² (symmetric), the stage
//! equations read T δQ = 1 ⊗ δq + c' ⊗ hG δp with T_μν = δ_μν I − K_μν hG W_ν J_ν. For a
//! covector λ = (λ_q, λ_p) of (q', p') put g = hG λ_q and r_ν = W_ν J_ν (λ_p + d_ν g); then
//! the covector of (q, p), Φᵀλ, is
//!
//! λ_q + Σ_μ z_μ,  λ_p + g + hG Σ_μ c'_μ z_μ,  where Tᵀz = r:
//! z_ν = r_ν + W_ν J_ν hG Σ_μ K_μν z_μ.
//!
//! The last equation is solved by fixed-point iteration from z = r, in the sums
//! s_ν = Σ_μ K_μν z_μ: s ← Kᵀr + Kᵀ(Cᵀs) with C_ν = hG W_ν J_ν, the step's own stage sums
//! with Kᵀ for K, then z_ν = r_ν + C_νᵀ s_ν. Its iteration matrix is the transpose of the
//! step's (of the same spectral radius), so it contracts where the step's did; it stops at
//! the error its contraction predicts below round-off. A step
//! costs the forward step, N-direction Hessians at the m quadrature points and a few
//! iterations of O(m²N + mN²) each, with nothing factorised (the tangent map assembles the
//! (s + 1)N block Hessian, factorises its sN interior block and solves 2N columns).
//!
//! The same matrices give the forward sensitivities' ΦX: for each column (δq, δp) of X the
//! linearised stage equations TδQ = 1 ⊗ δq + c' ⊗ hG δp are solved by the step's own
//! iteration, linearised, then δq' = δq + hG δp + Σ_ν d_ν C_ν δQ_ν and
//! δp' = δp + Σ_ν P_ν δQ_ν. Its round-off is that of the step, where the factorised block
//! Hessian's grows as 1/h: over 10⁵ Kepler steps (h = 0.02) the product of tangent maps drifted
//! to 7·10⁻⁶ of the gradient, the stage form to 10⁻¹⁰ (`cargo bench --bench adjoint`).

use super::constant_mass::NystromTables;
use super::workspace::{StageVectors, SviWorkspace};
use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::linalg::combination::{Rows, Start};
use crate::method::adjoint::{FOREIGN_ADJOINT, StepAdjoint};
use crate::method::{State, StepReport};
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::model::mass_inverse::Scaled;
use crate::nonlinear::FixedPoint;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector};

/// The step, keeping the force Jacobians at its quadrature points in `adjoint`; `None` where
/// the Nyström form does not hold (a forced model, no fixed-point tables), and the caller
/// keeps the tangent map.
#[allow(clippy::too_many_arguments)]
pub(super) fn adjoint_step<L: Lagrangian<N>, N: Dimension>(
    step: impl FnOnce(&mut SviWorkspace<N>, &mut State<N>) -> Result<StepReport, StepFailure>,
    model: &L,
    workspace: &mut SviWorkspace<N>,
    t: f64,
    h: f64,
    state: &State<N>,
    increment: &mut State<N>,
    adjoint: &mut StepAdjoint<N>,
) -> Option<Result<StepReport, StepFailure>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if L::FORCED || workspace.constant_mass.is_none() {
        return None;
    }
    let report = match step(workspace, increment) {
        Ok(report) => report,
        Err(failure) => return Some(Err(failure)),
    };
    // A fixed-point step leaves its converged positions at the quadrature points, and M⁻¹;
    // after Newton's path (which leaves no positions, and may not have made M⁻¹) the points
    // come from the node offsets.
    let fixed_point = workspace
        .constant_mass
        .as_ref()
        .is_some_and(|data| data.pending);
    if !fixed_point {
        workspace.settle();
        if let Some(offsets) = workspace.start.last_offsets() {
            workspace.offsets.copy_from_slice(offsets);
        }
    }
    let SviWorkspace {
        tables,
        offsets,
        constant_mass,
        ..
    } = workspace;
    let Some(data) = constant_mass.as_mut() else {
        unreachable!("checked before the step");
    };
    if data.mass_inverse.is_none() {
        match model.mass_inverse(t, &state.q, &state.y) {
            Ok(inverse) => data.mass_inverse = Some(inverse),
            Err(_) => return Some(Err(StepFailure::SingularMatrix)),
        }
    }
    if !matches!(adjoint, StepAdjoint::Stages { .. }) {
        *adjoint = StepAdjoint::empty();
    }
    let StepAdjoint::Stages { h: size, matrices } = adjoint else {
        unreachable!("made a Stages above");
    };
    *size = h;
    let Some(inverse) = data.mass_inverse.as_ref() else {
        unreachable!("made above");
    };
    let kick_inverse = inverse.scaled(h);
    let n = state.q.shape_generic().0;
    let m = tables.weights.len();
    // The slots of the previous step are written over (P_μ at 2μ, C_μ at 2μ + 1).
    if matrices.len() != 2 * m || matrices[0].shape_generic().0 != n {
        matrices.clear();
        matrices.resize(2 * m, OMatrix::zeros_generic(n, n));
    }
    for (mu, weight) in tables.weights.iter().enumerate() {
        // P_μ = W_μ J_μ and C_μ = hG P_μ. (∂²L/∂q² of L = ½q̇ᵀMq̇ − V does not depend on
        // the velocity: the fixed point's forces take p for it too.)
        let time = tables.time(t, mu);
        let mut weighted = if fixed_point {
            model.force_jacobian(time, &data.positions[mu], &state.y)
        } else {
            let (q, v) = tables.point(mu, &state.q, offsets);
            model.force_jacobian(time, &q, &v)
        };
        weighted *= *weight;
        if !weighted.iter().all(|x| x.is_finite()) {
            return Some(Err(StepFailure::NonFinite));
        }
        let [kept, kicked] = &mut matrices[2 * mu..2 * mu + 2] else {
            unreachable!("2m slots");
        };
        kick_inverse.apply_columns_into(&weighted, kicked);
        *kept = weighted;
    }
    Some(Ok(report))
}

/// What applying kept stage matrices needs, from the workspace.
struct Stages<'a, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// P_μ at 2μ, C_μ at 2μ + 1.
    matrices: &'a [OMatrix<f64, N, N>],
    nystrom: &'a NystromTables,
    /// hM⁻¹ of the step.
    kick_inverse: Scaled<'a, N>,
    /// N.
    width: usize,
    buffers: &'a mut StageVectors<N>,
}

/// The parts of `workspace` that apply the stage matrices `adjoint` keeps to vectors of
/// `rows` entries, with the buffers made at their first use; [`FOREIGN_ADJOINT`] where
/// `adjoint` is not this workspace's (a tangent map, another size, no M⁻¹).
fn stages<'a, N: Dimension>(
    workspace: &'a mut SviWorkspace<N>,
    adjoint: &'a StepAdjoint<N>,
    rows: usize,
) -> Result<Stages<'a, N>, StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let StepAdjoint::Stages { h, matrices } = adjoint else {
        return Err(FOREIGN_ADJOINT);
    };
    let SviWorkspace {
        constant_mass,
        adjoint: buffers,
        ..
    } = workspace;
    let (Some(data), Some(first)) = (constant_mass.as_ref(), matrices.first()) else {
        return Err(FOREIGN_ADJOINT);
    };
    let Some(mass_inverse) = data.mass_inverse.as_ref() else {
        return Err(FOREIGN_ADJOINT);
    };
    let m = data.nystrom.end_fractions.len();
    let n = first.shape_generic().0;
    if matrices.len() != 2 * m || rows != 2 * n.value() {
        return Err(FOREIGN_ADJOINT);
    }
    Ok(Stages {
        matrices,
        nystrom: &data.nystrom,
        kick_inverse: mass_inverse.scaled(*h),
        width: n.value(),
        buffers: buffers.get_or_insert_with(|| StageVectors::new(n, m)),
    })
}

/// λ ← Φᵀλ from the stage matrices `adjoint` keeps (see the [module](self) documentation).
pub(super) fn adjoint_apply<N: Dimension>(
    workspace: &mut SviWorkspace<N>,
    max_iterations: usize,
    adjoint: &StepAdjoint<N>,
    lambda: &mut DVector<f64>,
) -> Result<(), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let Stages {
        matrices,
        nystrom,
        kick_inverse,
        width,
        buffers,
    } = stages(workspace, adjoint, lambda.len())?;
    let StageVectors {
        fixed: right,
        iterate: sums,
        constant,
        images,
        upper: lambda_q,
        lower: lambda_p,
        kicked: g,
        work,
    } = buffers;
    let (top, bottom) = lambda.as_slice().split_at(width);
    lambda_q.as_mut_slice().copy_from_slice(top);
    lambda_p.as_mut_slice().copy_from_slice(bottom);
    kick_inverse.apply_into(lambda_q, g);
    // r_ν = P_νᵀ λ_p + d_ν C_νᵀ λ_q (Pᵀ g = (hG P)ᵀ λ_q).
    for (nu, r) in right.iter_mut().enumerate() {
        let (weighted, kicked) = (&matrices[2 * nu], &matrices[2 * nu + 1]);
        weighted.tr_mul_to(lambda_p, r);
        kicked.tr_mul_to(lambda_q, work);
        r.axpy(nystrom.end_fractions[nu], work, 1.0);
    }
    // The iteration runs on the sums s_ν = Σ_μ K_μν z_μ, in which it is the step's own
    // (s ← Kᵀr + Kᵀ(Cᵀs), the stage sums of the fixed point with Kᵀ for K): from z = r,
    // s⁰ = Kᵀr, and z_ν = r_ν + C_νᵀ s_ν at the end.
    N::combine_rows(constant, transposed_rows(nystrom, Start::Zero, right));
    let scale = largest_entry(constant);
    for (sum, first) in sums.iter_mut().zip(&*constant) {
        sum.copy_from(first);
    }
    let mut control = FixedPoint::predicting(max_iterations);
    loop {
        for (nu, (image, sum)) in images.iter_mut().zip(&*sums).enumerate() {
            matrices[2 * nu + 1].tr_mul_to(sum, image);
        }
        let change = N::combine_rows(
            sums,
            transposed_rows(nystrom, Start::Rows(constant), images),
        );
        if control.converged(change.largest, scale)? {
            break;
        }
    }
    // z_ν, then λ_q + Σ_μ z_μ and λ_p + g + hG Σ_μ c'_μ z_μ.
    work.fill(0.0);
    for (nu, ((z, sum), c)) in images
        .iter_mut()
        .zip(&*sums)
        .zip(&nystrom.stage_velocity)
        .enumerate()
    {
        matrices[2 * nu + 1].tr_mul_to(sum, z);
        *z += &right[nu];
        *lambda_q += &*z;
        work.axpy(*c, z, 1.0);
    }
    *lambda_p += &*g;
    kick_inverse.apply_into(work, g);
    *lambda_p += &*g;
    lambda.as_mut_slice()[..width].copy_from_slice(lambda_q.as_slice());
    lambda.as_mut_slice()[width..].copy_from_slice(lambda_p.as_slice());
    Ok(())
}

/// The rows `start`_ν + Σ_μ K_μν `inputs`[μ] (Kᵀ's rows) of the adjoint's iteration.
fn transposed_rows<'a, N: Dimension>(
    nystrom: &'a NystromTables,
    start: Start<'a, N>,
    inputs: &'a [OVector<f64, N>],
) -> Rows<'a, N>
where
    DefaultAllocator: Allocator<N>,
{
    Rows {
        start,
        lead: None,
        matrix: &nystrom.transposed_kick_matrix,
        inputs,
    }
}

/// The rows δq + c'_μ `g` + Σ_ν K_μν `images`[ν] of the forward iteration.
fn stage_rows<'a, N: Dimension>(
    nystrom: &'a NystromTables,
    dq: &'a OVector<f64, N>,
    g: &'a OVector<f64, N>,
    images: &'a [OVector<f64, N>],
) -> Rows<'a, N>
where
    DefaultAllocator: Allocator<N>,
{
    Rows {
        start: Start::Common(dq),
        lead: Some((&nystrom.stage_velocity, g)),
        matrix: &nystrom.kick_matrix,
        inputs: images,
    }
}

/// The largest entry of any of `vectors`, in size.
fn largest_entry<N: Dimension>(vectors: &[OVector<f64, N>]) -> f64
where
    DefaultAllocator: Allocator<N>,
{
    vectors.iter().map(|x| x.amax()).fold(0.0, f64::max)
}

/// X ← ΦX from the stage matrices `adjoint` keeps: for each column (δq, δp) of `columns`,
///
/// δQ_μ = δq + c'_μ hG δp + Σ_ν K_μν C_ν δQ_ν
///
/// by the step's own fixed-point iteration, linearised (from δQ_μ = δq + c'_μ hG δp), then
/// δq' = δq + hG δp + Σ_ν d_ν C_ν δQ_ν and δp' = δp + Σ_ν P_ν δQ_ν (see the
/// [module](self) documentation).
pub(super) fn tangent_apply<N: Dimension>(
    workspace: &mut SviWorkspace<N>,
    max_iterations: usize,
    adjoint: &StepAdjoint<N>,
    columns: &mut DMatrix<f64>,
) -> Result<(), StepFailure>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let Stages {
        matrices,
        nystrom,
        kick_inverse,
        width,
        buffers,
    } = stages(workspace, adjoint, columns.nrows())?;
    let StageVectors {
        iterate: stages,
        images,
        upper: dq,
        lower: dp,
        kicked: g,
        work,
        ..
    } = buffers;
    for column in columns.as_mut_slice().chunks_exact_mut(2 * width) {
        let (top, bottom) = column.split_at_mut(width);
        dq.as_mut_slice().copy_from_slice(top);
        dp.as_mut_slice().copy_from_slice(bottom);
        kick_inverse.apply_into(dp, g);
        // δQ_μ ← δq + c'_μ hG δp + Σ_ν K_μν C_ν δQ_ν, the step's stage sums, from C δQ = 0.
        for image in images.iter_mut() {
            image.fill(0.0);
        }
        N::combine_rows(stages, stage_rows(nystrom, dq, g, images));
        let scale = largest_entry(stages);
        let mut control = FixedPoint::predicting(max_iterations);
        loop {
            for (nu, (image, stage)) in images.iter_mut().zip(&*stages).enumerate() {
                matrices[2 * nu + 1].mul_to(stage, image);
            }
            let change = N::combine_rows(stages, stage_rows(nystrom, dq, g, images));
            if control.converged(change.largest, scale)? {
                break;
            }
        }
        // δp' = δp + Σ_ν P_ν δQ_ν and δq' = δq + hG δp + Σ_ν d_ν C_ν δQ_ν.
        for (nu, stage) in stages.iter().enumerate() {
            matrices[2 * nu].mul_to(stage, work);
            *dp += &*work;
            matrices[2 * nu + 1].mul_to(stage, work);
            dq.axpy(nystrom.end_fractions[nu], work, 1.0);
        }
        *dq += &*g;
        top.copy_from_slice(dq.as_slice());
        bottom.copy_from_slice(dp.as_slice());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{Solver, Svi, SviWorkspace};
    use crate::method::adjoint::{apply_tangent_map, compose_tangent_map};
    use crate::method::{Method, State, StepAdjoint};
    use crate::model::{Lagrangian, Structure};
    use crate::scalar::Scalar;
    use crate::test_models::{AsDyn, Damped, HenonHeiles};
    use nalgebra::{DMatrix, DVector, Dyn, SVector, U2};

    /// A constant-mass model with a time-dependent anharmonic potential:
    /// L = ½|q̇|² − ½(1 + ½ sin t)|q|² − q₀³q₁/4.
    struct Pumped;
    impl Lagrangian<U2> for Pumped {
        const STRUCTURE: Structure = Structure::ConstantMass;
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            let stiffness = t.sin() * 0.5 + 1.0;
            v.dot(v) * 0.5 - q.dot(q) * stiffness * 0.5 - q[0].powi(3) * q[1] * 0.25
        }
    }

    /// One step of `method` from `start`: what it keeps for its adjoint, the workspace that
    /// applies it and the increment.
    fn kept<L: Lagrangian<N>, N: crate::dimension::Dimension>(
        method: &Svi,
        model: &L,
        start: &State<N>,
        t: f64,
        h: f64,
    ) -> (StepAdjoint<N>, SviWorkspace<N>, State<N>)
    where
        nalgebra::DefaultAllocator:
            nalgebra::allocator::Allocator<N> + nalgebra::allocator::Allocator<N, N>,
    {
        let mut workspace = method.workspace(model, h).unwrap();
        let mut increment = State::zeros(start.dimension());
        let mut kept = StepAdjoint::empty();
        method
            .adjoint_step(
                model,
                &mut workspace,
                t,
                h,
                start,
                &mut increment,
                &mut kept,
            )
            .unwrap();
        (kept, workspace, increment)
    }

    /// Φᵀλ by the kept stage matrices against the transpose of the tangent map (an
    /// independent computation: the block Hessian of the discrete action, factorised), for
    /// a few covectors, and ΦX for a few tangent vectors, relative to their size.
    fn stages_against_map<L: Lagrangian<N>, N: crate::dimension::Dimension>(
        method: &Svi,
        model: &L,
        start: &State<N>,
        t: f64,
        h: f64,
    ) -> f64
    where
        nalgebra::DefaultAllocator:
            nalgebra::allocator::Allocator<N> + nalgebra::allocator::Allocator<N, N>,
    {
        let n = start.dimension().value();
        let (kept, mut workspace, increment) = kept(method, model, start, t, h);
        assert!(matches!(kept, StepAdjoint::Stages { .. }), "{method:?}");
        let mut other = method.workspace(model, h).unwrap();
        let (step, map, _) = method.tangent_map(model, &mut other, t, h, start).unwrap();
        assert_eq!(step, increment, "the same step");
        let map = StepAdjoint::Map(map);
        let mut worst: f64 = 0.0;
        for k in 0..3 {
            let lambda = DVector::from_fn(2 * n, |i, _| ((i + 1) as f64 * (0.9 + k as f64)).sin());
            let (mut by_stages, mut by_map) = (lambda.clone(), lambda.clone());
            let mut scratch = DVector::zeros(2 * n);
            method
                .adjoint_apply(&mut workspace, &kept, &mut by_stages, &mut scratch)
                .unwrap();
            apply_tangent_map(&map, &mut by_map, &mut scratch).unwrap();
            worst = worst.max((&by_stages - &by_map).amax() / by_map.amax());
        }
        // And forwards, X ← ΦX, for three tangent vectors at once.
        let columns = DMatrix::from_fn(2 * n, 3, |i, j| ((i + 2) as f64 * (0.7 + j as f64)).cos());
        let (mut by_stages, mut by_map) = (columns.clone(), columns);
        let mut scratch = DMatrix::zeros(2 * n, 3);
        method
            .tangent_apply(&mut workspace, &kept, &mut by_stages, &mut scratch)
            .unwrap();
        compose_tangent_map(&map, &mut by_map, &mut scratch).unwrap();
        worst.max((&by_stages - &by_map).amax() / by_map.amax())
    }

    #[test]
    fn the_nystrom_adjoint_is_the_transposed_tangent_map() {
        let start = State {
            q: SVector::from([0.5, -0.3]),
            y: SVector::from([0.4, 0.6]),
        };
        // As many quadrature points as the degree (Gauss–Legendre), more, the default, and
        // a step by Newton's method (which leaves no positions at the quadrature points: they
        // come from its node offsets). The tangent map's own round-off grows as 1/h (its block
        // Hessian's condition): the two differ by 5.8e-13 at h = 0.05 and by 6e-14 at h = 0.4.
        for method in [
            Svi::new(7).with_quadrature(6),
            Svi::new(4).with_quadrature(6),
            Svi::new(5),
            Svi::new(5).with_solver(Solver::Newton),
        ] {
            for h in [0.05, 0.4] {
                let tolerance = 5e-14 / h;
                let error = stages_against_map(&method, &HenonHeiles::<true>, &start, 0.0, h);
                assert!(error <= tolerance, "{method:?} h = {h}: {error:e}");
                let error = stages_against_map(&method, &Pumped, &start, 1.3, h);
                assert!(
                    error <= tolerance,
                    "{method:?} h = {h}, time-dependent: {error:e}"
                );
            }
        }
        // At run-time size.
        let dynamic = State::<Dyn> {
            q: DVector::from_column_slice(start.q.as_slice()),
            y: DVector::from_column_slice(start.y.as_slice()),
        };
        let model = AsDyn::new(HenonHeiles::<true>);
        let error = stages_against_map(&Svi::default(), &model, &dynamic, 0.0, 0.3);
        assert!(error <= 5e-14 / 0.3, "run-time size: {error:e}");
    }

    #[test]
    fn forced_and_general_models_keep_the_tangent_map() {
        let method = Svi::new(5);
        let start = State {
            q: SVector::from([1.0]),
            y: SVector::from([-0.5]),
        };
        let (forced, ..) = kept(&method, &Damped::<true> { c: 0.7 }, &start, 0.0, 0.1);
        assert!(matches!(forced, StepAdjoint::Map(_)));
        let start = State {
            q: SVector::from([0.5, -0.3]),
            y: SVector::from([0.4, 0.6]),
        };
        let (general, ..) = kept(&method, &HenonHeiles::<false>, &start, 0.0, 0.1);
        assert!(matches!(general, StepAdjoint::Map(_)));
        let (constant, ..) = kept(&method, &HenonHeiles::<true>, &start, 0.0, 0.1);
        assert!(matches!(constant, StepAdjoint::Stages { .. }));
    }
}
