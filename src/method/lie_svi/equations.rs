//! The equations of one step (§5.3.2, §5.4): the internal-stage conditions ∂S/∂ξᵛ = 0 and
//! the trivialised discrete Euler–Lagrange equation P − dexp_{−ξᵈ}(μ_k + g_R) = 0, their
//! residual and Jacobian in ξ¹…ξᵈ assembled from the Gauss points, with every block of ℓ's
//! Hessian (η included): what the exact tangent map of a step needs. The step itself is the
//! one on any group ([`super::group`] with [`crate::model::group::rotations::Rotations`]).

use super::derivatives::{PointDerivatives, point_derivatives};
use super::tables::StepTables;
use crate::method::space::RigidState;
use crate::model::rigid_body::RigidBodyLagrangian;
use crate::model::so3::{Matrix3, Vector3, body_velocity};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualSVec64, DualVec, jacobian};

/// Residual of the internal-stage conditions and of the discrete Euler–Lagrange equation in
/// trivialised form, and its Jacobian in ξ¹…ξᵈ.
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble<L: RigidBodyLagrangian>(
    model: &L,
    tables: &StepTables,
    reduced: bool,
    points: &mut [PointDerivatives],
    torque_rates: &mut [Matrix3<f64>],
    state: &RigidState,
    z: &DVector<f64>,
    jacobian_out: &mut DMatrix<f64>,
    residual: &mut DVector<f64>,
) {
    let d = tables.degree;
    for (mu, point) in points.iter_mut().enumerate() {
        let (a, b) = tables.point::<3>(mu, z);
        *point = point_derivatives(model, reduced, &state.r, &a, &b);
    }
    residual.fill(0.0);
    jacobian_out.fill(0.0);
    let mut torque = Vector3::zeros();
    for rate in torque_rates.iter_mut() {
        *rate = Matrix3::zeros();
    }
    for (mu, p) in points.iter().enumerate() {
        let w = tables.weights[mu];
        let g = &p.gradient;
        let hh = &p.hessian;
        let la = g.fixed_rows::<3>(3);
        let lb = g.fixed_rows::<3>(6);
        torque += g.fixed_rows::<3>(0) * w;
        let haa = hh.fixed_view::<3, 3>(3, 3);
        let hab = hh.fixed_view::<3, 3>(3, 6);
        let hba = hh.fixed_view::<3, 3>(6, 3);
        let hbb = hh.fixed_view::<3, 3>(6, 6);
        let hea = hh.fixed_view::<3, 3>(0, 3);
        let heb = hh.fixed_view::<3, 3>(0, 6);
        for nu in 1..=d {
            let (l, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
            let mut row = residual.fixed_rows_mut::<3>(3 * (nu - 1));
            row += (la * l + lb * c) * w;
        }
        for j in 1..=d {
            let (lj, cj) = (tables.values[(mu, j)], tables.derivatives[(mu, j)]);
            let from_a: Matrix3<f64> = (haa * lj + hab * cj) * w;
            let from_b: Matrix3<f64> = (hba * lj + hbb * cj) * w;
            for nu in 1..=d {
                let (l, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
                let mut target = jacobian_out.fixed_view_mut::<3, 3>(3 * (nu - 1), 3 * (j - 1));
                target += from_a * l + from_b * c;
            }
            if !reduced {
                torque_rates[j - 1] += (hea * lj + heb * cj) * w;
            }
        }
    }
    // Last block: P − dexp_{−ξᵈ}(μ_k + g_R).
    let end = z.fixed_rows::<3>(3 * (d - 1)).into_owned();
    let load = state.momentum + torque;
    let (pulled, pulled_rate) = jacobian(
        |x: Vector3<DualSVec64<3>>| body_velocity(&x, &load.map(DualVec::from_re)),
        &end,
    );
    let mut row = residual.fixed_rows_mut::<3>(3 * (d - 1));
    row -= pulled;
    let map = crate::model::so3::dexp(&(-end));
    for (j, rate) in torque_rates.iter().enumerate() {
        let mut target = jacobian_out.fixed_view_mut::<3, 3>(3 * (d - 1), 3 * j);
        if !reduced {
            target -= map * rate;
        }
        if j + 1 == d {
            target -= pulled_rate;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::lie_svi::{Form, LieSvi};
    use crate::method::space::SO3;
    use crate::method::step::Step;
    use crate::model::rigid_body::RigidBodyExt;
    use crate::model::so3::exp;
    use crate::scalar::Scalar;

    /// A heavy top with an asymmetric inertia (a free body, G-invariant, with `FREE`).
    struct Top<const FREE: bool> {
        gravity: f64,
    }
    impl<const FREE: bool> RigidBodyLagrangian for Top<FREE> {
        const G_INVARIANT: bool = FREE;
        fn lagrangian<D: Scalar>(&self, r: &Matrix3<D>, w: &Vector3<D>) -> D {
            let kinetic = (w[0] * w[0] + w[1] * w[1] * 1.7 + w[2] * w[2] * 2.3) * 0.5;
            kinetic - (r[(2, 0)] * 0.3 + r[(2, 2)]) * self.gravity
        }
    }

    /// The step (solved on the group `Rotations`, with dexp_xᵀ) satisfies these SO(3)
    /// equations (closed-form derivatives, dexp_{−x}): residual zero to round-off at its
    /// converged nodes, and its increments are R(F − I) and (F − I)ᵀμ + Fᵀg_R.
    #[test]
    fn the_step_on_the_group_solves_the_so3_equations() {
        check::<false>(2, 9.81, Form::Full);
        check::<false>(4, 9.81, Form::Full);
        check::<true>(3, 0.0, Form::Reduced);
    }

    fn check<const FREE: bool>(points: usize, gravity: f64, form: Form) {
        let model = Top::<FREE> { gravity };
        let method = LieSvi::new(points).with_form(form);
        let h = 0.02;
        let mut workspace = Step::<Top<FREE>, SO3>::workspace(&method, &model, h).unwrap();
        let r = exp(&Vector3::new(0.4, -0.2, 0.1));
        let mut state = RigidState {
            r,
            momentum: model.momentum(&r, &Vector3::new(1.0, 0.5, 3.0)),
        };
        let d = points - 1;
        let mut worst: f64 = 0.0;
        for _ in 0..20 {
            let mut increment = RigidState::zeros();
            Step::<Top<FREE>, SO3>::step(
                &method,
                &model,
                &mut workspace,
                0.0,
                h,
                &state,
                &mut increment,
            )
            .unwrap();
            let mut points_buffer = vec![PointDerivatives::zeros(); workspace.group.tables.len()];
            let mut rates = vec![Matrix3::zeros(); d];
            let mut jacobian = DMatrix::zeros(3 * d, 3 * d);
            let mut residual = DVector::zeros(3 * d);
            let z = workspace.group.unknowns.clone();
            assemble(
                &model,
                &workspace.group.tables,
                form == Form::Reduced,
                &mut points_buffer,
                &mut rates,
                &state,
                &z,
                &mut jacobian,
                &mut residual,
            );
            let scale = state.momentum.amax();
            worst = worst.max(residual.amax() / scale);
            let torque = points_buffer
                .iter()
                .zip(&workspace.group.tables.weights)
                .fold(Vector3::zeros(), |sum, (p, w)| {
                    sum + p.gradient.fixed_rows::<3>(0) * *w
                });
            let step = exp(&z.fixed_rows::<3>(3 * (d - 1)).into_owned());
            let expected_r = state.r * (step - Matrix3::identity());
            let expected_momentum = (step - Matrix3::identity()).transpose() * state.momentum
                + step.transpose() * torque;
            assert!((increment.r - expected_r).amax() < 1e-14);
            assert!((increment.momentum - expected_momentum).amax() < 1e-13 * scale);
            state.r += increment.r;
            state.momentum += increment.momentum;
        }
        assert!(
            worst < 1e-13,
            "{points} points, {form:?}: residual {worst:e}"
        );
    }
}
