//! Lagrangians on a power Gᴷ written as sums of terms on one or two factors:
//!
//! L(g, ξ) = Σₑ ℓₑ(g_{i(e)}, g_{j(e)}, ξ_{i(e)}, ξ_{j(e)}),
//!
//! as for chains of rigid links, whose kinetic energy couples every pair of links through
//! the masses below them, and whose potential is a sum over links. The step's derivatives of
//! L (the local Lagrangian's gradient and Hessian blocks, [`super::derivatives`]) then come
//! term by term with dual numbers of the factor's dimension: for K links of SO(3), numbers of
//! 16 entries instead of (3K + 1)², so the cost is O(terms) small evaluations and the stack
//! use does not grow with K. A model implements [`PairTerms`], writes
//! [`super::GroupLagrangian::lagrangian`] (the same L, for values and checks), sets
//! [`super::GroupLagrangian::STRUCTURED`] and forwards
//! [`super::GroupLagrangian::local_gradient`], [`super::GroupLagrangian::local_hessian`] and
//! [`super::GroupLagrangian::check_structure`] to [`local_gradient`], [`local_hessian`] and
//! [`check_factors`] here
//! (see `svi_models::SphericalChain`).

use super::LieGroup;
use super::derivatives::{LocalDerivatives, Mixed, both};
use crate::error::Error;
use crate::scalar::Scalar;
use nalgebra::{SMatrix, SVector};
use num_dual::{DualSVec64, gradient, partial_hessian};

/// A Lagrangian on a power of the group [`PairTerms::Factor`] (dimension `NG`, `EG` stored
/// numbers per factor) as a sum of terms, each reading one or two factors.
pub trait PairTerms<const NG: usize, const EG: usize> {
    /// The group of one factor.
    type Factor: LieGroup<NG, EG>;

    /// The number of terms.
    fn term_count(&self) -> usize;

    /// The factors term `e` reads, [i, j] (i = j for a term on one factor, which then sees the
    /// same factor in both slots).
    fn factors(&self, e: usize) -> [usize; 2];

    /// The term ℓₑ of the configurations and body velocities of its two factors. Generic over
    /// the scalar: the integrator differentiates it.
    fn term<D: Scalar>(&self, e: usize, g: [&SVector<D, EG>; 2], xi: [&SVector<D, NG>; 2]) -> D;
}

/// Checks that every term reads factors of the power (indices below K = N / NG), for
/// [`super::GroupLagrangian::check_structure`].
///
/// # Errors
/// [`Error::InvalidParameter`] `factors`, naming the term and the index.
pub fn check_factors<T, const NG: usize, const EG: usize, const N: usize>(
    model: &T,
) -> Result<(), Error>
where
    T: PairTerms<NG, EG> + ?Sized,
{
    let count = N / NG;
    for e in 0..model.term_count() {
        if let Some(k) = model.factors(e).into_iter().find(|&k| k >= count) {
            return Err(Error::invalid(
                "factors",
                format!("term {e} reads factor {k}, but the power has {count} factors"),
            ));
        }
    }
    Ok(())
}

/// Σₑ ℓₑ: L(g, ξ) of a [`PairTerms`] model on Gᴷ (N = K·NG, E = K·EG).
pub fn lagrangian<T, D, const NG: usize, const EG: usize, const N: usize, const E: usize>(
    model: &T,
    g: &SVector<D, E>,
    xi: &SVector<D, N>,
) -> D
where
    T: PairTerms<NG, EG> + ?Sized,
    D: Scalar,
{
    (0..model.term_count()).fold(D::from(0.0), |sum, e| {
        let [i, j] = model.factors(e);
        let (gi, gj) = (
            g.fixed_rows::<EG>(EG * i).into_owned(),
            g.fixed_rows::<EG>(EG * j).into_owned(),
        );
        let (xi_i, xi_j) = (
            xi.fixed_rows::<NG>(NG * i).into_owned(),
            xi.fixed_rows::<NG>(NG * j).into_owned(),
        );
        sum + model.term(e, [&gi, &gj], [&xi_i, &xi_j])
    })
}

/// One term at configurations ĝ exp(ζ) of its (one or two) distinct factors and velocities w;
/// a slot whose ζ is not `seeded` (a constant zero) stays at ĝ.
#[inline]
fn term_at<T, D, const NG: usize, const EG: usize>(
    model: &T,
    e: usize,
    base: &[SVector<f64, EG>; 2],
    slots: usize,
    (zeta, seeded): (&[SVector<D, NG>; 2], [bool; 2]),
    w: &[SVector<D, NG>; 2],
) -> D
where
    T: PairTerms<NG, EG> + ?Sized,
    D: Scalar,
{
    let at = |k: usize| {
        let lifted = base[k].map(D::from);
        if seeded[k] {
            T::Factor::compose(&lifted, &T::Factor::exp_second_order(&zeta[k]))
        } else {
            lifted
        }
    };
    let first = at(0);
    if slots == 1 {
        model.term(e, [&first, &first], [&w[0], &w[0]])
    } else {
        model.term(e, [&first, &at(1)], [&w[0], &w[1]])
    }
}

/// A term's data: its distinct factors, their base configurations and velocities.
struct Slots<const NG: usize, const EG: usize> {
    factors: [usize; 2],
    count: usize,
    base: [SVector<f64, EG>; 2],
    w: [SVector<f64, NG>; 2],
}

impl<const NG: usize, const EG: usize> Slots<NG, EG> {
    fn new<const N: usize, const E: usize>(
        factors: [usize; 2],
        g: &SVector<f64, E>,
        w: &SVector<f64, N>,
    ) -> Self {
        let count = if factors[0] == factors[1] { 1 } else { 2 };
        Slots {
            factors,
            count,
            base: factors.map(|k| g.fixed_rows::<EG>(EG * k).into_owned()),
            w: factors.map(|k| w.fixed_rows::<NG>(NG * k).into_owned()),
        }
    }

    /// The variables of the term, (is a velocity, slot): ζ of each distinct factor, then w
    /// of each, the ζ's only with `configuration`; the first `count` entries of the array.
    fn variables(&self, configuration: bool) -> ([(bool, usize); 4], usize) {
        let mut out = [(false, 0); 4];
        let mut count = 0;
        for velocity in [false, true] {
            if !velocity && !configuration {
                continue;
            }
            for k in 0..self.count {
                out[count] = (velocity, k);
                count += 1;
            }
        }
        (out, count)
    }

    /// The value of a variable (0 for ζ, w for w).
    fn value(&self, (velocity, k): (bool, usize)) -> SVector<f64, NG> {
        if velocity {
            self.w[k]
        } else {
            SVector::zeros()
        }
    }
}

/// λ and ν ([`super::GroupLagrangian::local_gradient`]) of a [`PairTerms`] model, term by term: one
/// first-order dual evaluation per term and variable (ζ or w of each of its factors), with
/// `NG` directions.
pub fn local_gradient<T, const NG: usize, const EG: usize, const N: usize, const E: usize>(
    model: &T,
    g: &SVector<f64, E>,
    w: &SVector<f64, N>,
    configuration: bool,
) -> (SVector<f64, N>, SVector<f64, N>)
where
    T: PairTerms<NG, EG> + ?Sized,
{
    type D<const NG: usize> = DualSVec64<NG>;
    let mut lambda = SVector::<f64, N>::zeros();
    let mut nu = SVector::<f64, N>::zeros();
    for e in 0..model.term_count() {
        let slots = Slots::<NG, EG>::new(model.factors(e), g, w);
        let constant = |variable: (bool, usize)| slots.value(variable).map(D::<NG>::from);
        let (variables, count) = slots.variables(configuration);
        for &variable in &variables[..count] {
            let (_, part) = gradient(
                |x: SVector<D<NG>, NG>| {
                    let mut zeta = [constant((false, 0)), constant((false, 1))];
                    let mut velocity = [constant((true, 0)), constant((true, 1))];
                    assign(&mut zeta, &mut velocity, variable, x);
                    let seeded = [variable == (false, 0), variable == (false, 1)];
                    let configuration = (&zeta, seeded);
                    term_at(model, e, &slots.base, slots.count, configuration, &velocity)
                },
                &slots.value(variable),
            );
            let (velocity, k) = variable;
            let target = if velocity { &mut nu } else { &mut lambda };
            let mut rows = target.fixed_rows_mut::<NG>(NG * slots.factors[k]);
            rows += part;
        }
    }
    (lambda, nu)
}

/// λ, ν and the Hessian blocks ([`super::GroupLagrangian::local_hessian`]) of a [`PairTerms`]
/// model into `out`, term by term: one hyper-dual evaluation per term and pair of its variables, with
/// `NG` + `NG` directions.
pub fn local_hessian<T, const NG: usize, const EG: usize, const N: usize, const E: usize>(
    model: &T,
    g: &SVector<f64, E>,
    w: &SVector<f64, N>,
    configuration: bool,
    out: &mut LocalDerivatives<N>,
) where
    T: PairTerms<NG, EG> + ?Sized,
{
    out.lambda.fill(0.0);
    out.nu.fill(0.0);
    out.zz.fill(0.0);
    out.zw.fill(0.0);
    out.ww.fill(0.0);
    for e in 0..model.term_count() {
        let slots = Slots::<NG, EG>::new(model.factors(e), g, w);
        let lift = |variable: (bool, usize)| slots.value(variable).map(Mixed::<NG>::from_re);
        let (variables, count) = slots.variables(configuration);
        let variables = &variables[..count];
        for (position, &u) in variables.iter().enumerate() {
            for &v in &variables[position..] {
                let (xu, xv) = (slots.value(u), slots.value(v));
                let (_, gradient_u, _, block) = partial_hessian(
                    |(x, y): (SVector<Mixed<NG>, NG>, SVector<Mixed<NG>, NG>)| {
                        let mut zeta = [lift((false, 0)), lift((false, 1))];
                        let mut velocity = [lift((true, 0)), lift((true, 1))];
                        if u == v {
                            assign(&mut zeta, &mut velocity, u, both(&x, &y, &xu));
                        } else {
                            assign(&mut zeta, &mut velocity, u, x);
                            assign(&mut zeta, &mut velocity, v, y);
                        }
                        let seeded = [0, 1].map(|k| u == (false, k) || v == (false, k));
                        let configuration = (&zeta, seeded);
                        term_at(model, e, &slots.base, slots.count, configuration, &velocity)
                    },
                    (&xu, &xv),
                );
                scatter(out, &slots, u, v, gradient_u, block);
            }
        }
    }
}

/// Sets a variable (velocity?, slot) of a term's evaluation.
#[inline]
fn assign<D, const NG: usize>(
    zeta: &mut [SVector<D, NG>; 2],
    velocity: &mut [SVector<D, NG>; 2],
    (is_velocity, k): (bool, usize),
    value: SVector<D, NG>,
) {
    if is_velocity {
        velocity[k] = value;
    } else {
        zeta[k] = value;
    }
}

/// Adds one term's block (rows u, columns v) and, from a diagonal block, u's gradient.
fn scatter<const NG: usize, const EG: usize, const N: usize>(
    out: &mut LocalDerivatives<N>,
    slots: &Slots<NG, EG>,
    u: (bool, usize),
    v: (bool, usize),
    gradient_u: SVector<f64, NG>,
    block: SMatrix<f64, NG, NG>,
) {
    let (row, column) = (NG * slots.factors[u.1], NG * slots.factors[v.1]);
    if u == v {
        let target = if u.0 { &mut out.nu } else { &mut out.lambda };
        let mut rows = target.fixed_rows_mut::<NG>(row);
        rows += gradient_u;
    }
    // ζ variables come before w ones ([`Slots::variables`]), so a mixed pair is (ζ, w).
    let matrix = match (u.0, v.0) {
        (false, false) => &mut out.zz,
        (true, true) => &mut out.ww,
        _ => &mut out.zw,
    };
    let mut target = matrix.fixed_view_mut::<NG, NG>(row, column);
    target += block;
    // The symmetric blocks ζζ and ww get the transpose of an off-diagonal pair too.
    if u != v && u.0 == v.0 {
        let mut target = matrix.fixed_view_mut::<NG, NG>(column, row);
        target += block.transpose();
    }
}
