//! Holonomic constraints g(q) = 0, written once.
//!
//! A constrained system is a Lagrangian L(t, q, q̇) on ℝⁿ and m functions g(q) that hold
//! along every motion: a pendulum in Cartesian coordinates (|x|² − l² = 0), the bonds of a
//! molecule, the closure of a linkage. Like the Lagrangian, the constraints are one function
//! generic over [`Scalar`] ([`Constraints::constraints`]); the integrators take the Jacobian
//! G = ∂g/∂q (m × n) from it by automatic differentiation ([`ConstraintsExt`]), so nobody
//! writes a derivative of g by hand.
//!
//! The motion lies on the manifold Q = {q : g(q) = 0} and its velocities in the tangent space
//! G(q) q̇ = 0 (the "hidden" constraint, the time derivative of g(q(t)) = 0); for L with a
//! constant mass matrix M, p = M q̇ lies in the cotangent space G(q) M⁻¹ p = 0. The
//! constrained Euler–Lagrange equations are d/dt ∂L/∂q̇ − ∂L/∂q = −G(q)ᵀ λ with multipliers λ
//! (the constraint forces −Gᵀλ; Marsden & West 2001, §3.5; Hairer, Lubich & Wanner 2006,
//! §VII.1). G must have full rank m on the manifold: a redundant or contradictory constraint
//! makes G M⁻¹ Gᵀ singular, and [`check_rank`] names it.
//!
//! [`project`] makes initial data consistent: q₀ onto g = 0 (Newton steps along M⁻¹Gᵀ, the
//! M-orthogonal projection to first order) and p₀ onto the cotangent space (the M⁻¹-orthogonal
//! projection), reporting how far each moved.
//!
//! Many constraints that each read a few coordinates (the bonds of a long chain) are written
//! as [`local::LocalConstraints`] and run as [`local::SparseConstraints`]: G is then stored
//! sparsely and every step, the rank check and the projection cost O(n) ([`sparse`]).

pub mod local;
pub mod sparse;

use crate::dimension::Dimension;
use crate::error::Error;
use crate::model::mass_inverse::MassInverse;
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector};
use num_dual::{Dual64, HyperDual64};

/// m holonomic constraints g(q) = 0 on ℝⁿ, written once, generic over the scalar.
///
/// # Example
/// ```
/// use nalgebra::{OVector, U3};
/// use svi::Scalar;
/// use svi::model::constraint::Constraints;
///
/// /// A point on the sphere of radius l: |q|² − l² = 0.
/// struct Sphere {
///     l: f64,
/// }
///
/// impl Constraints<U3> for Sphere {
///     fn count(&self) -> usize {
///         1
///     }
///     fn constraints<D: Scalar>(&self, q: &OVector<D, U3>, g: &mut [D]) {
///         g[0] = q.dot(q) - D::from(self.l * self.l);
///     }
/// }
/// ```
pub trait Constraints<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The number m of constraints (m < n).
    fn count(&self) -> usize;

    /// g(q) into `g` (length [`Constraints::count`]).
    ///
    /// Mark it `#[inline]`: the integrators evaluate it with dual numbers in their inner loops.
    fn constraints<D: Scalar>(&self, q: &OVector<D, N>, g: &mut [D]);

    /// The name of constraint `index` in messages: `g[index]` unless the model says better
    /// (a text model's expression).
    fn constraint_name(&self, index: usize) -> String {
        format!("g[{index}]")
    }

    /// The constraints as rows of a sparse Jacobian, when each reads a few coordinates
    /// ([`local::SparseConstraints`]): the integrators then store G sparsely and take O(n)
    /// per step (with a diagonal mass matrix). `None` (the default): G is a dense m × n
    /// matrix, right for a few constraints on a small system.
    fn local(&self) -> Option<&dyn local::ConstraintRows> {
        None
    }
}

/// Buffers of [`ConstraintsExt`]'s derivatives (the dual numbers of one Jacobian), sized once.
#[derive(Debug, Clone)]
pub struct ConstraintScratch<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    q: OVector<Dual64, N>,
    g: Vec<Dual64>,
    hyper_q: OVector<HyperDual64, N>,
    hyper_g: Vec<HyperDual64>,
}

impl<N: Dimension> ConstraintScratch<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// Buffers for `count` constraints on the coordinates of `q`.
    pub fn new(q: &OVector<f64, N>, count: usize) -> Self {
        ConstraintScratch {
            q: q.map(Dual64::from_re),
            g: vec![Dual64::from_re(0.0); count],
            hyper_q: q.map(HyperDual64::from_re),
            hyper_g: vec![HyperDual64::from_re(0.0); count],
        }
    }
}

/// The derivatives of [`Constraints`], by automatic differentiation.
pub trait ConstraintsExt<N: Dimension>: Constraints<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// g(q) into `g`.
    fn values_into(&self, q: &OVector<f64, N>, g: &mut DVector<f64>) {
        self.constraints(q, g.as_mut_slice());
    }

    /// G = ∂g/∂q (m × n) into `jacobian`, one sweep of the dual number [`Dual64`] per
    /// coordinate (the scratch buffers are reused: nothing is allocated).
    fn jacobian_into(
        &self,
        q: &OVector<f64, N>,
        scratch: &mut ConstraintScratch<N>,
        jacobian: &mut DMatrix<f64>,
    ) {
        for (dual, &x) in scratch.q.iter_mut().zip(q.iter()) {
            *dual = Dual64::from_re(x);
        }
        for j in 0..q.len() {
            scratch.q[j].eps = 1.0;
            self.constraints(&scratch.q, &mut scratch.g);
            scratch.q[j].eps = 0.0;
            for (i, g) in scratch.g.iter().enumerate() {
                jacobian[(i, j)] = g.eps;
            }
        }
    }

    /// The Hessian of the weighted sum Σₐ wₐ gₐ(q) (n × n) into `hessian`: the derivative of
    /// the constraint force Gᵀw with respect to q, which the implicit constrained methods'
    /// Newton matrices need. One sweep of the hyper-dual number [`HyperDual64`] per pair of
    /// coordinates (n(n + 1)/2 sweeps: meant for the small systems of the dense path).
    fn weighted_hessian_into(
        &self,
        q: &OVector<f64, N>,
        weights: &[f64],
        scratch: &mut ConstraintScratch<N>,
        hessian: &mut DMatrix<f64>,
    ) {
        for (dual, &x) in scratch.hyper_q.iter_mut().zip(q.iter()) {
            *dual = HyperDual64::from_re(x);
        }
        for i in 0..q.len() {
            for j in 0..=i {
                scratch.hyper_q[i].eps1 = 1.0;
                scratch.hyper_q[j].eps2 = 1.0;
                self.constraints(&scratch.hyper_q, &mut scratch.hyper_g);
                scratch.hyper_q[i].eps1 = 0.0;
                scratch.hyper_q[j].eps2 = 0.0;
                let value: f64 = scratch
                    .hyper_g
                    .iter()
                    .zip(weights)
                    .map(|(g, w)| g.eps1eps2 * w)
                    .sum();
                hessian[(i, j)] = value;
                hessian[(j, i)] = value;
            }
        }
    }

    /// g(q) as a new vector.
    fn values(&self, q: &OVector<f64, N>) -> DVector<f64> {
        let mut g = DVector::zeros(self.count());
        self.values_into(q, &mut g);
        g
    }

    /// G(q) as a new matrix.
    fn jacobian(&self, q: &OVector<f64, N>) -> DMatrix<f64> {
        let mut jacobian = DMatrix::zeros(self.count(), q.len());
        self.jacobian_into(
            q,
            &mut ConstraintScratch::new(q, self.count()),
            &mut jacobian,
        );
        jacobian
    }
}

impl<N: Dimension, C: Constraints<N> + ?Sized> ConstraintsExt<N> for C where
    DefaultAllocator: Allocator<N>
{
}

/// Relative size below which a row of G counts as a combination of the rows before it.
const RANK_TOLERANCE: f64 = 1e-10;

/// Check that the m × n Jacobian `jacobian` of `constraints` has full rank m: a row that is
/// zero (a constraint that does not depend on q) or a combination of the rows before it (a
/// redundant or contradictory constraint) is an [`Error::InvalidParameter`] naming it.
/// Gram–Schmidt on the rows, twice for stability.
pub fn check_rank<N: Dimension, C: Constraints<N> + ?Sized>(
    constraints: &C,
    jacobian: &DMatrix<f64>,
) -> Result<(), Error>
where
    DefaultAllocator: Allocator<N>,
{
    let (m, n) = jacobian.shape();
    if m >= n {
        return Err(Error::invalid(
            "constraints",
            format!("{m} constraints on {n} coordinates leave no motion: there must be fewer"),
        ));
    }
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(m);
    for i in 0..m {
        let row = jacobian.row(i).transpose();
        let size = row.norm();
        if !size.is_finite() {
            return Err(Error::invalid(
                "constraints",
                format!(
                    "the gradient of {} is not finite at the initial state",
                    constraints.constraint_name(i)
                ),
            ));
        }
        if size == 0.0 {
            return Err(Error::invalid(
                "constraints",
                format!(
                    "{} does not depend on q at the initial state (its gradient is zero)",
                    constraints.constraint_name(i)
                ),
            ));
        }
        let mut rest = row.clone();
        for _ in 0..2 {
            for direction in &basis {
                let along = direction.dot(&rest);
                rest.axpy(-along, direction, 1.0);
            }
        }
        let left = rest.norm();
        if left <= RANK_TOLERANCE * size {
            return Err(Error::invalid(
                "constraints",
                format!(
                    "{} is redundant or contradicts the constraints before it: its gradient is \
                     a combination of theirs at the initial state",
                    constraints.constraint_name(i)
                ),
            ));
        }
        basis.push(rest / left);
    }
    Ok(())
}

/// Consistent initial data: q on g = 0 and p in the cotangent space, and how far each moved.
#[derive(Debug, Clone, PartialEq)]
pub struct Projected<N: Dimension>
where
    DefaultAllocator: Allocator<N>,
{
    /// The projected configuration.
    pub q: OVector<f64, N>,
    /// The projected momentum.
    pub p: OVector<f64, N>,
    /// |q − q₀|.
    pub moved_q: f64,
    /// |p − p₀|.
    pub moved_p: f64,
}

/// Most Newton steps of the projection onto g = 0.
pub(crate) const PROJECTION_STEPS: usize = 50;

/// Project (q₀, p₀) onto the constraint manifold and its cotangent space, for a constant mass
/// matrix with inverse `mass_inverse`: q ← q − M⁻¹Gᵀ(G M⁻¹ Gᵀ)⁻¹ g(q) until g(q) = 0 to
/// round-off, then p ← p − Gᵀ(G M⁻¹ Gᵀ)⁻¹ G M⁻¹ p. The rank of G is checked first
/// ([`check_rank`]).
///
/// # Errors
/// [`Error::InvalidParameter`] for constraints of deficient rank, or when the projection of
/// q₀ does not converge (q₀ too far from the manifold, or no point of it near).
///
/// Local constraints ([`Constraints::local`]) with a diagonal M⁻¹ are projected in O(n) by
/// sparse LU, their rank checked in O(n) ([`sparse`]).
pub fn project<N: Dimension, C: Constraints<N> + ?Sized>(
    constraints: &C,
    mass_inverse: &MassInverse<N>,
    q0: &OVector<f64, N>,
    p0: &OVector<f64, N>,
) -> Result<Projected<N>, Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if let Some(rows) = constraints.local()
        && let Some(weights) = sparse::diagonal(mass_inverse)
    {
        return sparse::project(rows, &weights, q0, p0);
    }
    let m = constraints.count();
    let mut scratch = ConstraintScratch::new(q0, m);
    let mut jacobian = DMatrix::zeros(m, q0.len());
    constraints.jacobian_into(q0, &mut scratch, &mut jacobian);
    check_rank(constraints, &jacobian)?;
    let mut q = q0.clone();
    let mut g = constraints.values(&q);
    let scale = q0.amax().max(1.0);
    let mut converged = false;
    for _ in 0..PROJECTION_STEPS {
        constraints.jacobian_into(&q, &mut scratch, &mut jacobian);
        let (directions, schur) = schur_complement(mass_inverse, &jacobian)?;
        let multipliers = schur.solve(&g);
        let shift = &directions * &multipliers;
        for (x, d) in q.iter_mut().zip(shift.iter()) {
            *x -= d;
        }
        constraints.values_into(&q, &mut g);
        if !g.iter().all(|x| x.is_finite()) {
            break;
        }
        if shift.amax() <= 4.0 * f64::EPSILON * scale {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(not_projected(g.amax()));
    }
    constraints.jacobian_into(&q, &mut scratch, &mut jacobian);
    let (directions, schur) = schur_complement(mass_inverse, &jacobian)?;
    // p ← p − Gᵀ S⁻¹ G M⁻¹ p, with M⁻¹Gᵀ = directions: G M⁻¹ p = directionsᵀ p.
    let rate = directions.tr_mul(&DVector::from_column_slice(p0.as_slice()));
    let multipliers = schur.solve(&rate);
    let shift = jacobian.tr_mul(&multipliers);
    let mut p = p0.clone();
    for (x, d) in p.iter_mut().zip(shift.iter()) {
        *x -= d;
    }
    Ok(Projected {
        moved_q: (&q - q0).norm(),
        moved_p: (&p - p0).norm(),
        q,
        p,
    })
}

/// M⁻¹Gᵀ (n × m) and the Cholesky factors of S = G M⁻¹ Gᵀ (m × m, symmetric positive
/// definite for G of full rank).
pub fn schur_complement<N: Dimension>(
    mass_inverse: &MassInverse<N>,
    jacobian: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, nalgebra::Cholesky<f64, nalgebra::Dyn>), Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (m, n) = jacobian.shape();
    let mut directions = DMatrix::zeros(n, m);
    let mut row = OVector::<f64, N>::zeros_generic(N::from_usize(n), nalgebra::U1);
    let mut column = row.clone();
    for i in 0..m {
        for (x, &g) in row.iter_mut().zip(jacobian.row(i).iter()) {
            *x = g;
        }
        mass_inverse.apply_into(&row, &mut column);
        directions.column_mut(i).copy_from_slice(column.as_slice());
    }
    let schur = jacobian * &directions;
    let factors = nalgebra::Cholesky::<f64, nalgebra::Dyn>::new(schur).ok_or_else(|| {
        Error::invalid(
            "constraints",
            "G M⁻¹ Gᵀ is singular: the constraints' gradients are dependent here",
        )
    })?;
    Ok((directions, factors))
}

/// The error of initial data that Newton's method did not bring onto the constraints, with
/// |g| after [`PROJECTION_STEPS`] steps.
fn not_projected(residual: f64) -> Error {
    Error::invalid(
        "initial.q",
        format!(
            "cannot be projected onto the constraints: after {PROJECTION_STEPS} Newton steps \
             |g| = {residual:.1e}"
        ),
    )
}
