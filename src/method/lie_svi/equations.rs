//! The equations of one step (§5.3.2, §5.4): the internal-stage conditions ∂S/∂ξᵛ = 0 and
//! the trivialised discrete Euler–Lagrange equation P − dexp_{−ξᵈ}(μ_k + g_R) = 0, their
//! residual and Jacobian in ξ¹…ξᵈ assembled from the Gauss points, and the torque sum g_R.

use super::derivatives::{PointDerivatives, point_derivatives};
use super::tables::StepTables;
use crate::method::space::RigidState;
use crate::model::rigid_body::RigidBodyLagrangian;
use crate::model::so3::{Matrix3, Vector3, body_velocity, exp};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualSVec64, DualVec, gradient, jacobian};

/// g_R = Σ_μ W_μ ∂ℓ/∂η at η = 0 (zero in the reduced form).
pub(super) fn torque_sum<L: RigidBodyLagrangian>(
    model: &L,
    tables: &StepTables,
    reduced: bool,
    r: &Matrix3<f64>,
    z: &DVector<f64>,
) -> Vector3<f64> {
    let mut sum = Vector3::zeros();
    if reduced {
        return sum;
    }
    for (mu, w) in tables.weights.iter().enumerate() {
        let (a, b) = tables.point::<3>(mu, z);
        let rotation = r * exp(&a);
        let omega = body_velocity(&a, &b);
        let (_, g) = gradient(
            |eta: Vector3<DualSVec64<3>>| {
                let moved = rotation.map(DualVec::from_re) * exp(&eta);
                model.lagrangian(&moved, &omega.map(DualVec::from_re))
            },
            &Vector3::zeros(),
        );
        // d/dη L(R_k exp(η) E, Ω) = E · (d/dζ L(R_k E exp(ζ), Ω)), ζ = Eᵀη.
        sum += exp(&a) * g * *w;
    }
    sum
}

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
