//! The equations of one Lie-SVI step on any group G (the generalisation of
//! [`super::equations`]): the Lagrangian at a quadrature point
//! ℓ(η, a, b) = L(g_k exp(η) exp(a), dexp_{−a} b), its gradient and Hessian blocks in
//! (η, a, b) by num-dual, and the residual and Jacobian of
//!
//! 0 = ∂S/∂ξᵛ (ν = 1, …, d − 1),  0 = P − dexp_{ξᵈ}ᵀ (μ_k + g_R).
//!
//! On SO(3), dexp_xᵀ = dexp_{−x} and this is the SO(3) equation; on a general group the
//! transpose stays (parent module docs for the derivation).
//!
//! # Derivatives by the chain rule
//! ℓ's Hessian in 3N variables is assembled from N × N blocks (stable Rust cannot size a
//! 3N-variable dual number from the group's N). Differentiating the whole of ℓ block by block
//! would push the group's exp and dexp through every hyper-dual evaluation; instead, with
//! ĝ = g_k exp(a), perturbations (η, α, β) of (0, a, b) and A = Ad_{exp(−a)}, B = dexp_{−a},
//! W(a, b) = dexp_{−a} b (the body velocity):
//!
//! - g_k exp(η) exp(a + α) = ĝ exp(ζ) with ζ = Aη + Bα + ½ S(α, α) + ½[Aη, Bα] + O(3),
//!   because exp(−a) exp(η) exp(a) = exp(Aη) exactly, log(exp(−a) exp(a + α)) = Bα +
//!   ½ S(α, α) + … with S(α, α) = ∂_a(W(a, α))·α (differentiate dexp_{−γ}γ' = W(a + sα, α)
//!   at s = 0, where the bracket [γ', γ'] vanishes), and the Baker–Campbell–Hausdorff series
//!   log(e^X e^Y) = X + Y + ½[X, Y] + …;
//! - the velocity is w = W(a + α, b + β).
//!
//! So ℓ = L̂(ζ, w) with the local Lagrangian L̂(ζ, w) = L(ĝ exp(ζ), w), and the second-order
//! chain rule needs only: λ = ∂L̂/∂ζ, ν = ∂L̂/∂w and the blocks ζζ, ζw, ww of L̂ at (0, W)
//! (three hyper-dual evaluations of the user's L, at ĝ times a curve that agrees with exp to
//! second order); the Jacobians ∂W/∂a and B; and the Hessians of the scalars
//! ⟨ν, W(a + α, b + β)⟩ and ½⟨λ, W(a + α, α)⟩ (two hyper-dual evaluations of W, which has
//! no Lagrangian in it). The bracket term gives ∂²ℓ/∂η∂α its ½ Aᵀ C B with
//! C_ij = ⟨λ, [e_i, e_j]⟩. The reduced form has λ = 0 and L̂ evaluated at e. The tests check
//! every block against brute-force hyper-dual differentiation of ℓ.
//!
//! L̂'s derivatives come from the model ([`GroupLagrangian::local_hessian`], dense by default,
//! term by term for chains) and W's from the group ([`LieGroup::velocity_derivatives`], factor
//! by factor for powers); [`crate::model::group::derivatives`] says how to supply them. The
//! N × N products of the chain rule are formed in place in heap buffers ([`GroupScratch`]),
//! so groups of dimension up to 96 fit a thread's stack.

use super::tables::StepTables;
use crate::method::group_space::GroupState;
use crate::model::group::{GroupLagrangian, LieGroup, LocalDerivatives, VelocityDerivatives};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use num_dual::{DualSVec64, jacobian};

/// Gradient and Hessian blocks of ℓ(η, a, b) at one quadrature point (η = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GroupDerivatives<const N: usize> {
    /// ∂ℓ/∂η (the integrand of g_R; zero in the reduced form).
    pub(super) eta: SVector<f64, N>,
    /// ∂ℓ/∂a.
    pub(super) a: SVector<f64, N>,
    /// ∂ℓ/∂b.
    pub(super) b: SVector<f64, N>,
    /// ∂²ℓ/∂a∂a.
    pub(super) aa: SMatrix<f64, N, N>,
    /// The derivative in b of the a-row ∂ℓ/∂a (+ Bᵀf with a force).
    pub(super) ab: SMatrix<f64, N, N>,
    /// The derivative in a of the b-row ∂ℓ/∂b (abᵀ without a force).
    pub(super) ba: SMatrix<f64, N, N>,
    /// ∂²ℓ/∂b∂b.
    pub(super) bb: SMatrix<f64, N, N>,
    /// ∂²ℓ/∂η∂a (rows η).
    pub(super) eta_a: SMatrix<f64, N, N>,
    /// ∂²ℓ/∂η∂b (rows η).
    pub(super) eta_b: SMatrix<f64, N, N>,
}

impl<const N: usize> GroupDerivatives<N> {
    pub(super) fn zeros() -> Self {
        GroupDerivatives {
            eta: SVector::zeros(),
            a: SVector::zeros(),
            b: SVector::zeros(),
            aa: SMatrix::zeros(),
            ab: SMatrix::zeros(),
            ba: SMatrix::zeros(),
            bb: SMatrix::zeros(),
            eta_a: SMatrix::zeros(),
            eta_b: SMatrix::zeros(),
        }
    }
}

/// Buffers of [`group_derivatives`] on the heap (a group of dimension N has N × N blocks:
/// 73 kB each at N = 96, too many for a thread's stack).
#[derive(Debug, Clone)]
pub(super) struct GroupScratch<const N: usize> {
    local: Box<LocalDerivatives<N>>,
    pub(super) maps: Box<VelocityDerivatives<N>>,
    pull: Box<SMatrix<f64, N, N>>,
    left: Box<SMatrix<f64, N, N>>,
    right: Box<SMatrix<f64, N, N>>,
    adjoint: Box<SMatrix<f64, N, N>>,
    bracket: Box<SMatrix<f64, N, N>>,
}

impl<const N: usize> GroupScratch<N> {
    pub(super) fn new() -> Self {
        let matrix = || Box::new(SMatrix::zeros());
        GroupScratch {
            local: Box::new(LocalDerivatives::zeros()),
            maps: Box::new(VelocityDerivatives::zeros()),
            pull: matrix(),
            left: matrix(),
            right: matrix(),
            adjoint: matrix(),
            bracket: matrix(),
        }
    }
}

/// `target += sourceᵀ` for N × N blocks, in place.
#[inline]
fn add_transpose<const N: usize>(target: &mut SMatrix<f64, N, N>, source: &SMatrix<f64, N, N>) {
    for j in 0..N {
        for i in 0..N {
            target[(i, j)] += source[(j, i)];
        }
    }
}

/// The point of L̂ at a Gauss point: ĝ = g_k exp(a) (e in the reduced form) and the body
/// velocity W(a, b).
#[inline]
fn gauss_point<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    reduced: bool,
    base: &SVector<f64, E>,
    a: &SVector<f64, N>,
    b: &SVector<f64, N>,
) -> (SVector<f64, E>, SVector<f64, N>) {
    let moved = if reduced {
        L::Group::identity()
    } else {
        L::Group::compose(base, &L::Group::exp(a))
    };
    (moved, L::Group::body_velocity(a, b))
}

/// The gradient and Hessian blocks of ℓ at (0, a, b) (the η blocks only in the full form)
/// into `out`, by the chain rule (module docs) through the model's local derivatives
/// ([`GroupLagrangian::local_hessian`] at ĝ = g_k exp(a), or at e in the reduced form) and
/// the group's derivatives of W ([`LieGroup::velocity_derivatives`]); every N × N product in
/// place.
pub(super) fn group_derivatives<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    reduced: bool,
    base: &SVector<f64, E>,
    (a, b): (&SVector<f64, N>, &SVector<f64, N>),
    out: &mut GroupDerivatives<N>,
    scratch: &mut GroupScratch<N>,
) {
    let (moved, w0) = gauss_point::<L, N, E>(reduced, base, a, b);
    let GroupScratch {
        local,
        maps,
        pull,
        left,
        right,
        adjoint,
        bracket,
    } = scratch;
    **pull = L::Group::dexp(&(-a));
    model.local_hessian(&moved, &w0, !reduced, local);
    L::Group::velocity_derivatives(a, b, &local.lambda, &local.nu, true, maps);
    let rate = &maps.rate;
    out.a = pull.tr_mul(&local.lambda) + maps.pulled;
    out.b = pull.tr_mul(&local.nu);
    // aa = Bᵀ ζζ B + S + Sᵀ + Rᵀ ww R + curvature, S = Bᵀ ζw R (B = pull, R = rate).
    left.gemm(1.0, &local.zz, pull, 0.0);
    out.aa.gemm_tr(1.0, pull, left, 0.0);
    left.gemm(1.0, &local.zw, rate, 0.0);
    right.gemm_tr(1.0, pull, left, 0.0);
    out.aa += &**right;
    add_transpose(&mut out.aa, right);
    left.gemm(1.0, &local.ww, rate, 0.0);
    out.aa.gemm_tr(1.0, rate, left, 1.0);
    out.aa += &maps.curvature;
    // ab = Bᵀ ζw B + Rᵀ ww B + twist, bb = Bᵀ ww B; `right` keeps ζw B for the η block.
    right.gemm(1.0, &local.zw, pull, 0.0);
    out.ab.gemm_tr(1.0, pull, right, 0.0);
    left.gemm(1.0, &local.ww, pull, 0.0);
    out.ab.gemm_tr(1.0, rate, left, 1.0);
    out.ab += &maps.twist;
    out.bb.gemm_tr(1.0, pull, left, 0.0);
    out.ab.transpose_to(&mut out.ba);
    if reduced {
        out.eta.fill(0.0);
        out.eta_a.fill(0.0);
        out.eta_b.fill(0.0);
        return;
    }
    // ζ = Aη + Bα + ½[Aη, Bα] + … with A = Ad_{exp(−a)}: the bracket's bilinear form
    // C_ij = ⟨λ, [e_i, e_j]⟩ = (ad_{e_i}ᵀλ)_j.
    **adjoint = L::Group::adjoint(&L::Group::exp(&(-a)));
    for i in 0..N {
        let unit = SVector::<f64, N>::from_fn(|k, _| if k == i { 1.0 } else { 0.0 });
        let row = L::Group::ad(&unit).tr_mul(&local.lambda);
        bracket.set_row(i, &row.transpose());
    }
    out.eta = adjoint.tr_mul(&local.lambda);
    left.gemm(1.0, &local.zz, pull, 0.0);
    left.gemm(1.0, &local.zw, rate, 1.0);
    left.gemm(0.5, bracket, pull, 1.0);
    out.eta_a.gemm_tr(1.0, adjoint, left, 0.0);
    out.eta_b.gemm_tr(1.0, adjoint, right, 0.0);
}

/// Adds the force's terms at one Gauss point (time `t`): the body variation of
/// g_k exp(η) exp(a + α) is ζ = Aη + Bα + … (A = Ad_{exp(−a)} = I − ad_a B, B = dexp_{−a}),
/// so the virtual work ⟨f, ζ⟩ adds Bᵀf to the a-row and Aᵀf to the η-row, and their
/// derivatives in a and b (by num-dual) to the Jacobian. The b-row has no force.
pub(super) fn add_force<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    reduced: bool,
    t: f64,
    base: &SVector<f64, E>,
    a: &SVector<f64, N>,
    b: &SVector<f64, N>,
    out: &mut GroupDerivatives<N>,
) {
    type D<const N: usize> = DualSVec64<N>;
    let lifted = base.map(D::<N>::from_re);
    let time = D::<N>::from_re(t);
    // (Bᵀf, Aᵀf) at (a', b'); `row` picks one.
    let rows = |a: &SVector<D<N>, N>, b: &SVector<D<N>, N>, row: bool| {
        let g = L::Group::compose(&lifted, &L::Group::exp(a));
        let force = model.external_force(time, &g, &L::Group::body_velocity(a, b));
        let pull = L::Group::dexp(&(-a));
        if row {
            pull.transpose() * force
        } else {
            let adjoint = SMatrix::identity() - L::Group::ad(a) * pull;
            adjoint.transpose() * force
        }
    };
    let (a_lift, b_lift) = (a.map(D::<N>::from_re), b.map(D::<N>::from_re));
    let (pulled, pulled_a) = jacobian(|x| rows(&x, &b_lift, true), a);
    let (_, pulled_b) = jacobian(|y| rows(&a_lift, &y, true), b);
    out.a += pulled;
    out.aa += pulled_a;
    out.ab += pulled_b;
    if !reduced {
        let (moved, moved_a) = jacobian(|x| rows(&x, &b_lift, false), a);
        let (_, moved_b) = jacobian(|y| rows(&a_lift, &y, false), b);
        out.eta += moved;
        out.eta_a += moved_a;
        out.eta_b += moved_b;
    }
}

/// The gradient of ℓ at (0, a, b) alone, which is all a residual needs (module docs):
/// ∂ℓ/∂η = Aᵀλ, ∂ℓ/∂a = Bᵀλ + (∂W/∂a)ᵀν and ∂ℓ/∂b = Bᵀν with λ = ∂L̂/∂ζ and ν = ∂L̂/∂w
/// ([`GroupLagrangian::local_gradient`], [`LieGroup::velocity_derivatives`] without second
/// derivatives, into `maps`); with a force f at time `t`, Aᵀf and Bᵀf join the η- and a-rows
/// (A = I − ad_a B). ∂ℓ/∂η is zero in the reduced form. Returns (∂ℓ/∂η, ∂ℓ/∂a, ∂ℓ/∂b).
pub(super) fn group_gradients<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    reduced: bool,
    (t, base): (f64, &SVector<f64, E>),
    (a, b): (&SVector<f64, N>, &SVector<f64, N>),
    maps: &mut VelocityDerivatives<N>,
) -> [SVector<f64, N>; 3] {
    let (moved, w0) = gauss_point::<L, N, E>(reduced, base, a, b);
    let pull = L::Group::dexp(&(-a));
    let (mut lambda, nu) = model.local_gradient(&moved, &w0, !reduced);
    L::Group::velocity_derivatives(a, b, &lambda, &nu, false, maps);
    let mut row_a = maps.pulled;
    let row_b = pull.tr_mul(&nu);
    if reduced && !L::FORCED {
        return [SVector::zeros(), row_a, row_b];
    }
    if L::FORCED {
        lambda += model.external_force(t, &moved, &w0);
    }
    row_a += pull.tr_mul(&lambda);
    let mut row_eta = SVector::zeros();
    if !reduced {
        // Aᵀλ = λ − Bᵀ ad_aᵀ λ.
        row_eta = lambda - pull.tr_mul(&L::Group::ad(a).tr_mul(&lambda));
    }
    [row_eta, row_a, row_b]
}

/// g_R = Σ_μ W_μ ∂ℓ/∂η from the derivatives of the last assembly.
fn configuration_sum<const N: usize>(
    tables: &StepTables,
    points: &[GroupDerivatives<N>],
) -> SVector<f64, N> {
    points
        .iter()
        .zip(&tables.weights)
        .fold(SVector::zeros(), |sum, (p, w)| sum + p.eta * *w)
}

/// g_R = Σ_μ W_μ ∂ℓ/∂η at the nodes `z` ([`group_gradients`] at each Gauss point; zero in
/// the reduced form).
pub(super) fn configuration_sum_at<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    (tables, reduced): (&StepTables, bool),
    (t, base): (f64, &SVector<f64, E>),
    z: &DVector<f64>,
    maps: &mut VelocityDerivatives<N>,
) -> SVector<f64, N> {
    let mut sum = SVector::zeros();
    if reduced {
        return sum;
    }
    for (mu, w) in tables.weights.iter().enumerate() {
        let (a, b) = tables.point::<N>(mu, z);
        let [eta, ..] = group_gradients(model, reduced, (tables.time(t, mu), base), (&a, &b), maps);
        sum += eta * *w;
    }
    sum
}

/// Residual in ξ¹…ξᵈ of the internal-stage conditions and of P − dexp_{ξᵈ}ᵀ(μ_k + g_R),
/// and, when `jacobian_out` is given, its Jacobian (with ∂g_R/∂ξʲ in `rates`); without it
/// only the gradients of ℓ are evaluated ([`group_gradients`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble_group<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
    model: &L,
    tables: &StepTables,
    reduced: bool,
    points: &mut [GroupDerivatives<N>],
    rates: &mut [SMatrix<f64, N, N>],
    scratch: &mut GroupScratch<N>,
    t: f64,
    state: &GroupState<N, E>,
    z: &DVector<f64>,
    jacobian_out: Option<&mut DMatrix<f64>>,
    residual: &mut DVector<f64>,
) {
    let d = tables.degree;
    let exact = jacobian_out.is_some();
    for (mu, point) in points.iter_mut().enumerate() {
        let (a, b) = tables.point::<N>(mu, z);
        if exact {
            group_derivatives(model, reduced, &state.g, (&a, &b), point, scratch);
            if L::FORCED {
                add_force(model, reduced, tables.time(t, mu), &state.g, &a, &b, point);
            }
        } else {
            let time = tables.time(t, mu);
            let [eta, row_a, row_b] = group_gradients(
                model,
                reduced,
                (time, &state.g),
                (&a, &b),
                &mut scratch.maps,
            );
            (point.eta, point.a, point.b) = (eta, row_a, row_b);
        }
    }
    residual.fill(0.0);
    for (mu, p) in points.iter().enumerate() {
        let w = tables.weights[mu];
        for nu in 1..=d {
            let (l, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
            let mut row = residual.fixed_rows_mut::<N>(N * (nu - 1));
            row += (p.a * l + p.b * c) * w;
        }
    }
    // Last block: P − dexp_ξᵀ (μ_k + g_R), ξ = ξᵈ.
    let end = z.fixed_rows::<N>(N * (d - 1)).into_owned();
    let load = state.momentum + configuration_sum(tables, points);
    let map = L::Group::dexp(&end);
    let mut row = residual.fixed_rows_mut::<N>(N * (d - 1));
    row -= map.tr_mul(&load);
    let Some(jacobian_out) = jacobian_out else {
        return;
    };
    jacobian_out.fill(0.0);
    for rate in rates.iter_mut() {
        *rate = SMatrix::zeros();
    }
    for (mu, p) in points.iter().enumerate() {
        let w = tables.weights[mu];
        for j in 1..=d {
            let (lj, cj) = (tables.values[(mu, j)], tables.derivatives[(mu, j)]);
            for nu in 1..=d {
                let (l, c) = (tables.values[(mu, nu)], tables.derivatives[(mu, nu)]);
                let mut target = jacobian_out.fixed_view_mut::<N, N>(N * (nu - 1), N * (j - 1));
                // (l_ν (aa l_j + ab c_j) + c_ν (ba l_j + bb c_j)) W_μ, without N × N temporaries.
                let blocks = [
                    (&p.aa, l * lj),
                    (&p.ab, l * cj),
                    (&p.ba, c * lj),
                    (&p.bb, c * cj),
                ];
                for (block, factor) in blocks {
                    target.zip_apply(block, |x, y| *x += factor * w * y);
                }
            }
            if !reduced {
                let rate = &mut rates[j - 1];
                rate.zip_apply(&p.eta_a, |x, y| *x += lj * w * y);
                rate.zip_apply(&p.eta_b, |x, y| *x += cj * w * y);
            }
        }
    }
    let pulled_rate = L::Group::dexp_transpose_jacobian(&end, &load);
    for (j, rate) in rates.iter().enumerate() {
        let mut target = jacobian_out.fixed_view_mut::<N, N>(N * (d - 1), N * j);
        if !reduced {
            target.gemm_tr(-1.0, &map, rate, 1.0);
        }
        if j + 1 == d {
            target -= pulled_rate;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::group::derivatives::{Mixed, both};
    use crate::model::group::product::RotationsAndTranslations;
    use crate::model::group::rigid_motions::RigidMotions;
    use crate::model::group::rotations::Rotations;
    use crate::scalar::Scalar;
    use num_dual::partial_hessian;

    /// ℓ(η, a, b) in hyper-dual numbers; in the reduced form the base point is the identity and
    /// η is not used.
    #[inline]
    fn lagrangian_at<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
        model: &L,
        base: &SVector<f64, E>,
        reduced: bool,
        eta: &SVector<Mixed<N>, N>,
        a: &SVector<Mixed<N>, N>,
        b: &SVector<Mixed<N>, N>,
    ) -> Mixed<N> {
        let xi = L::Group::body_velocity(a, b);
        let g = if reduced {
            L::Group::exp(a)
        } else {
            let moved = L::Group::compose(&L::Group::exp(eta), &L::Group::exp(a));
            L::Group::compose(&base.map(Mixed::from_re), &moved)
        };
        model.lagrangian(&g, &xi)
    }

    /// [`group_derivatives`] by brute force: each block one hyper-dual evaluation of ℓ through
    /// both exponentials (the reference of the tests).
    fn group_derivatives_reference<L: GroupLagrangian<N, E>, const N: usize, const E: usize>(
        model: &L,
        reduced: bool,
        base: &SVector<f64, E>,
        a: &SVector<f64, N>,
        b: &SVector<f64, N>,
    ) -> GroupDerivatives<N> {
        let zero = SVector::<f64, N>::zeros();
        let lift = |v: &SVector<f64, N>| v.map(Mixed::from_re);
        let f = |eta: &_, a: &_, b: &_| lagrangian_at(model, base, reduced, eta, a, b);
        let (_, ga, gb, ab) = partial_hessian(|(x, y)| f(&lift(&zero), &x, &y), (a, b));
        let (_, _, _, aa) =
            partial_hessian(|(x, y)| f(&lift(&zero), &both(&x, &y, a), &lift(b)), (a, a));
        let (_, _, _, bb) =
            partial_hessian(|(x, y)| f(&lift(&zero), &lift(a), &both(&x, &y, b)), (b, b));
        let mut out = GroupDerivatives {
            a: ga,
            b: gb,
            aa,
            ab,
            bb,
            ..GroupDerivatives::zeros()
        };
        if !reduced {
            let (_, ge, _, eta_a) = partial_hessian(|(x, y)| f(&x, &y, &lift(b)), (&zero, a));
            let (_, _, _, eta_b) = partial_hessian(|(x, y)| f(&x, &lift(a), &y), (&zero, b));
            out.eta = ge;
            out.eta_a = eta_a;
            out.eta_b = eta_b;
        }
        out
    }

    /// A Lagrangian that couples the configuration and the velocity nonlinearly.
    struct Coupled;
    impl<G: LieGroup<N, E>, const N: usize, const E: usize> GroupLagrangian<N, E> for (Coupled, G) {
        type Group = G;
        fn lagrangian<D: Scalar>(&self, g: &SVector<D, E>, xi: &SVector<D, N>) -> D {
            let mut sum = D::from(0.0);
            for i in 0..N {
                sum += xi[i] * xi[i] * (1.0 + 0.3 * i as f64) * 0.5;
            }
            for k in 0..E {
                sum += (g[k] * (0.2 + 0.1 * k as f64)).sin() * (xi[k % N] * 0.7 + 1.0);
            }
            sum + (g[0] * xi[N - 1]).powi(2) * 0.3
        }
    }

    fn agree<G: LieGroup<N, E>, const N: usize, const E: usize>(reduced: bool) {
        let model = (Coupled, G::default());
        let base = G::exp(&SVector::<f64, N>::from_fn(|i, _| 0.3 - 0.17 * i as f64));
        for scale in [0.0, 1e-4, 0.5] {
            let a = SVector::<f64, N>::from_fn(|i, _| scale * (0.4 - 0.23 * i as f64));
            let b = SVector::<f64, N>::from_fn(|i, _| 1.0 - 0.31 * i as f64);
            let mut fast = GroupDerivatives::zeros();
            let mut scratch = GroupScratch::new();
            group_derivatives(&model, reduced, &base, (&a, &b), &mut fast, &mut scratch);
            let reference = group_derivatives_reference(&model, reduced, &base, &a, &b);
            let pairs = [
                (fast.eta, reference.eta),
                (fast.a, reference.a),
                (fast.b, reference.b),
            ];
            for (x, y) in pairs {
                assert!((x - y).amax() < 1e-12, "{}: gradient {x} vs {y}", G::NAME);
            }
            let blocks = [
                (fast.aa, reference.aa, "aa"),
                (fast.ab, reference.ab, "ab"),
                (fast.bb, reference.bb, "bb"),
                (fast.eta_a, reference.eta_a, "ηa"),
                (fast.eta_b, reference.eta_b, "ηb"),
            ];
            for (x, y, name) in blocks {
                assert!(
                    (x - y).amax() < 1e-12,
                    "{} {name} at scale {scale}: {x} vs {y}",
                    G::NAME
                );
            }
        }
    }

    #[test]
    fn chain_rule_derivatives_match_the_brute_force_ones() {
        agree::<Rotations, 3, 9>(false);
        agree::<RigidMotions, 6, 12>(false);
        agree::<RotationsAndTranslations, 6, 12>(false);
    }
}
