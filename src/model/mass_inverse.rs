//! The inverse of a constant mass matrix M = ∂²L/∂q̇², computed once per run and applied as
//! q̇ = M⁻¹p by the explicit methods (Störmer–Verlet and its compositions), SVI's fixed
//! point and spectral collocation.
//!
//! Which form it takes follows from the model, not from the method:
//! - a model of fixed (or small run-time) size inverts its dense M (`Dense`);
//! - a sum of local terms ([`crate::Lagrangian::terms`]: chains, lattices, discretised
//!   fields, of any n) assembles M from the terms' blocks in O(n) and inverts a diagonal M
//!   entry by entry (`Diagonal`: particles with their own masses), or factors a coupled M
//!   once by faer's sparse LU on the pattern of the terms' blocks (`Coupled`: a consistent
//!   finite-element mass matrix, bodies sharing coordinates).
//!
//! No form holds an n × n matrix for a sum of terms, so a chain of 10⁵ particles takes
//! O(n) memory and O(n) work per application.

use crate::dimension::Dimension;
use crate::error::Error;
use crate::linalg::invert_small;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::TermSum;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OMatrix, OVector, U1};
use std::cell::RefCell;

/// M⁻¹ of a constant mass matrix, ready to apply.
#[derive(Debug, Clone)]
pub enum MassInverse<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The dense inverse (models that are not sums of terms).
    Dense(OMatrix<f64, N, N>),
    /// The reciprocal diagonal entries (a sum of terms with a diagonal M).
    Diagonal(OVector<f64, N>),
    /// A coupled M of a sum of terms, in compressed-column form, with its sparse LU factors.
    Coupled(Box<Coupled>),
}

/// A coupled sparse mass matrix and its factors (made on first use after a clone: faer's
/// factors are not cloned).
#[derive(Debug)]
pub struct Coupled {
    pattern: Pattern,
    values: Vec<f64>,
    lu: RefCell<Option<SparseLu>>,
}

impl Clone for Coupled {
    fn clone(&self) -> Self {
        Coupled {
            pattern: self.pattern.clone(),
            values: self.values.clone(),
            lu: RefCell::new(None),
        }
    }
}

impl Coupled {
    /// Analyse and factor M; [`Error::InvalidParameter`] `structure` when it is singular.
    fn factor(pattern: &Pattern, values: &[f64]) -> Result<SparseLu, Error> {
        let mut lu = SparseLu::default();
        lu.analyse(pattern)?;
        lu.factor(pattern, values)
            .map_err(|_| singular("singular"))?;
        // faer does not stop at a zero pivot: a singular M shows in a solve.
        let mut probe = DVector::from_element(pattern.size(), 1.0);
        lu.solve_in_place(&mut probe)
            .map_err(|_| singular("singular"))?;
        Ok(lu)
    }

    /// `x` ← M⁻¹ `x`.
    fn solve_in_place(&self, x: &mut [f64]) {
        let mut lu = self.lu.borrow_mut();
        if lu.is_none() {
            // Factored once already when this M was built: it cannot fail now.
            *lu = Self::factor(&self.pattern, &self.values).ok();
        }
        if let Some(lu) = lu.as_mut() {
            let mut column = DVector::from_column_slice(x);
            // A non-finite result can only come from a non-finite x, and shows in the
            // caller's finiteness checks.
            let _ = lu.solve_in_place(&mut column);
            x.copy_from_slice(column.as_slice());
        } else {
            x.fill(f64::NAN);
        }
    }
}

/// The error of a mass matrix that cannot be inverted.
fn singular(what: &str) -> Error {
    Error::invalid(
        "structure",
        format!("the mass matrix ∂²L/∂q̇² is {what}: the Legendre map is not invertible"),
    )
}

impl<N: Dimension> MassInverse<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The inverse of a dense mass matrix M (a model that is not a sum of terms; the model's
    /// M⁻¹ is [`crate::LagrangianExt::mass_inverse`]). At run-time size a diagonal M is
    /// inverted entry by entry (particles in Cartesian coordinates: no n² products of a
    /// matrix of run-time size at every application); else, and always at a fixed size (whose
    /// small matrix product is unrolled), the dense inverse.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular.
    pub fn of_dense(mass: &OMatrix<f64, N, N>) -> Result<Self, Error> {
        let (n, _) = mass.shape_generic();
        let mut off_diagonal = (0..n.value())
            .flat_map(|i| (0..n.value()).filter(move |&j| j != i).map(move |j| (i, j)));
        if N::try_to_usize().is_none() && off_diagonal.all(|(i, j)| mass[(i, j)] == 0.0) {
            let inverse = OVector::from_fn_generic(n, U1, |i, _| 1.0 / mass[(i, i)]);
            return if inverse.iter().all(|x| x.is_finite()) {
                Ok(MassInverse::Diagonal(inverse))
            } else {
                Err(singular("singular"))
            };
        }
        invert_small(mass)
            .filter(|inverse| inverse.iter().all(|x| x.is_finite()))
            .map(MassInverse::Dense)
            .ok_or_else(|| singular("singular"))
    }

    /// M⁻¹ at (t, q, q̇) from the blocks of a sum of terms (never an n × n matrix): the
    /// diagonal summed in place, and only the entries off it kept (none for particles with
    /// their own masses).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `structure` when M is singular or not positive on its
    /// diagonal.
    pub fn of_terms(
        terms: &dyn TermSum<N>,
        t: f64,
        q: &OVector<f64, N>,
        v: &OVector<f64, N>,
    ) -> Result<Self, Error> {
        let (n, _) = q.shape_generic();
        let mut mass = Vec::new();
        terms.mass_triplets(t, q, v, &mut mass);
        let mut diagonal = OVector::<f64, N>::zeros_generic(n, U1);
        let mut coupled = Vec::new();
        for (i, j, value) in mass {
            if i == j {
                diagonal[i] += value;
            } else {
                coupled.push((i, j, value));
            }
        }
        if let Some(i) = diagonal.iter().position(|m| !(*m > 0.0 && m.is_finite())) {
            return Err(singular(&format!(
                "not positive on its diagonal: entry {:e} at coordinate {i}",
                diagonal[i]
            )));
        }
        if coupled.is_empty() {
            return Ok(MassInverse::Diagonal(diagonal.map(|m| 1.0 / m)));
        }
        let size = diagonal.len();
        let places: Vec<(usize, usize)> = (0..size)
            .map(|i| (i, i))
            .chain(coupled.iter().map(|&(i, j, _)| (i, j)))
            .collect();
        let pattern = Pattern::new(size, &places)?;
        let mut values = vec![0.0; pattern.len()];
        let entries = diagonal
            .iter()
            .enumerate()
            .map(|(i, &m)| (i, i, m))
            .chain(coupled.iter().copied());
        for (i, j, value) in entries {
            if let Some(slot) = pattern.slot(i, j) {
                values[slot] += value;
            }
        }
        let lu = Coupled::factor(&pattern, &values)?;
        Ok(MassInverse::Coupled(Box::new(Coupled {
            pattern,
            values,
            lu: RefCell::new(Some(lu)),
        })))
    }

    /// `out` = M⁻¹ `p`.
    #[inline(always)]
    pub fn apply_into(&self, p: &OVector<f64, N>, out: &mut OVector<f64, N>) {
        match self {
            MassInverse::Dense(inverse) => inverse.mul_to(p, out),
            MassInverse::Diagonal(inverse) => multiply_entries(inverse, 1.0, p, out),
            MassInverse::Coupled(coupled) => {
                out.copy_from(p);
                coupled.solve_in_place(out.as_mut_slice());
            }
        }
    }

    /// `out` = M `v`, from the M this inverse was made of, when it holds M: a diagonal M
    /// (entry by entry, vᵢ / (M⁻¹)ᵢᵢ, to a rounding of mᵢvᵢ) or a coupled sparse one (its
    /// entries); `false` for a dense inverse, which does not keep M.
    #[inline]
    pub(crate) fn mass_times_into(&self, v: &OVector<f64, N>, out: &mut OVector<f64, N>) -> bool {
        match self {
            MassInverse::Dense(_) => false,
            MassInverse::Diagonal(inverse) => {
                for ((o, v), m) in out
                    .as_mut_slice()
                    .iter_mut()
                    .zip(v.as_slice())
                    .zip(inverse.as_slice())
                {
                    *o = v / m;
                }
                true
            }
            MassInverse::Coupled(coupled) => {
                coupled
                    .pattern
                    .mul_into(&coupled.values, v.as_slice(), out.as_mut_slice());
                true
            }
        }
    }

    /// M⁻¹ `p`.
    #[inline]
    pub fn apply(&self, p: &OVector<f64, N>) -> OVector<f64, N> {
        let (n, _) = p.shape_generic();
        let mut out = OVector::zeros_generic(n, U1);
        self.apply_into(p, &mut out);
        out
    }

    /// `factor` · M⁻¹ as an operator whose dense form is scaled once (a step's h² M⁻¹ of
    /// SVI's fixed point, applied at every quadrature point and iteration).
    pub fn scaled(&self, factor: f64) -> Scaled<'_, N> {
        match self {
            MassInverse::Dense(inverse) => Scaled::Dense(inverse * factor),
            MassInverse::Diagonal(inverse) => Scaled::Diagonal(inverse, factor),
            other => Scaled::Lazy(other, factor),
        }
    }

    /// M⁻¹ as a dense matrix (n × n: for the forced kick's small Newton system).
    pub fn to_dense(&self) -> OMatrix<f64, N, N> {
        match self {
            MassInverse::Dense(inverse) => inverse.clone(),
            MassInverse::Diagonal(inverse) => OMatrix::from_diagonal(inverse),
            MassInverse::Coupled(_) => {
                let (n, _) = self.shape();
                let mut dense = OMatrix::zeros_generic(n, n);
                let mut column = OVector::zeros_generic(n, U1);
                for j in 0..n.value() {
                    let unit = OVector::from_fn_generic(n, U1, |i, _| f64::from(i == j));
                    self.apply_into(&unit, &mut column);
                    dense.set_column(j, &column);
                }
                dense
            }
        }
    }

    /// The shape (n, n) of M⁻¹.
    fn shape(&self) -> (N, N) {
        match self {
            MassInverse::Dense(inverse) => inverse.shape_generic(),
            MassInverse::Diagonal(inverse) => {
                (inverse.shape_generic().0, inverse.shape_generic().0)
            }
            MassInverse::Coupled(coupled) => {
                let n = N::from_usize(coupled.pattern.size());
                (n, n)
            }
        }
    }

    /// The dense inverse, when M⁻¹ is held densely.
    pub fn dense(&self) -> Option<&OMatrix<f64, N, N>> {
        match self {
            MassInverse::Dense(inverse) => Some(inverse),
            _ => None,
        }
    }
}

/// A scaled M⁻¹ ([`MassInverse::scaled`]).
#[derive(Debug)]
pub enum Scaled<'a, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The dense inverse times the factor.
    Dense(OMatrix<f64, N, N>),
    /// The diagonal inverse and the factor (no copy: a step's scaling allocates nothing).
    Diagonal(&'a OVector<f64, N>, f64),
    /// The inverse and the factor, applied together.
    Lazy(&'a MassInverse<N>, f64),
}

impl<N: Dimension> Scaled<'_, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// `out` = factor · M⁻¹ `p`.
    #[inline]
    pub fn apply_into(&self, p: &OVector<f64, N>, out: &mut OVector<f64, N>) {
        match self {
            Scaled::Dense(inverse) => inverse.mul_to(p, out),
            Scaled::Diagonal(inverse, factor) => multiply_entries(inverse, *factor, p, out),
            Scaled::Lazy(inverse, factor) => {
                inverse.apply_into(p, out);
                *out *= *factor;
            }
        }
    }

    /// `out` = factor · M⁻¹ `matrix`: one product for a dense inverse, row scaling for a
    /// diagonal one, column by column for a coupled one.
    pub fn apply_columns_into(&self, matrix: &OMatrix<f64, N, N>, out: &mut OMatrix<f64, N, N>) {
        match self {
            Scaled::Dense(inverse) => inverse.mul_to(matrix, out),
            Scaled::Diagonal(inverse, factor) => {
                for (mut target, column) in out.column_iter_mut().zip(matrix.column_iter()) {
                    for ((o, m), d) in target.iter_mut().zip(column.iter()).zip(inverse.iter()) {
                        *o = m * (d * factor);
                    }
                }
            }
            Scaled::Lazy(..) => {
                let (n, _) = matrix.shape_generic();
                let (mut column, mut image) =
                    (OVector::zeros_generic(n, U1), OVector::zeros_generic(n, U1));
                for j in 0..n.value() {
                    column.copy_from(&matrix.column(j));
                    self.apply_into(&column, &mut image);
                    out.set_column(j, &image);
                }
            }
        }
    }

    /// `outs[μ]` = factor · M⁻¹ `ps[μ]` for every μ: one call for all of SVI's quadrature
    /// points (at run-time size a call per point cost a tenth of Kepler written as text).
    #[inline]
    pub fn apply_all(&self, ps: &[OVector<f64, N>], outs: &mut [OVector<f64, N>]) {
        for (p, out) in ps.iter().zip(outs) {
            self.apply_into(p, out);
        }
    }
}

/// `out` = (`factor` `diagonal`) ∘ `p`, entry by entry (the digits of the dense inverse
/// scaled once: mᵢ·factor is exact or rounds as factor·mᵢ does).
#[inline(always)]
fn multiply_entries<N: Dimension>(
    diagonal: &OVector<f64, N>,
    factor: f64,
    p: &OVector<f64, N>,
    out: &mut OVector<f64, N>,
) where
    DefaultAllocator: Allocator<N>,
{
    for ((o, p), m) in out
        .as_mut_slice()
        .iter_mut()
        .zip(p.as_slice())
        .zip(diagonal.as_slice())
    {
        *o = p * (m * factor);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::local::LocalLagrangian;
    use crate::scalar::Scalar;
    use nalgebra::{Const, DMatrix, Dyn, SMatrix, SVector};

    /// Particles of masses 1, 2, 3, … joined by springs, with an optional coupling c q̇ᵢq̇ᵢ₊₁
    /// of neighbouring velocities (a tridiagonal M).
    struct Chain {
        n: usize,
        coupling: f64,
    }

    impl LocalLagrangian for Chain {
        type Width = Const<2>;
        fn dimension(&self) -> usize {
            self.n
        }
        fn term_count(&self) -> usize {
            self.n - 1
        }
        fn indices(&self, e: usize) -> [usize; 2] {
            [e, e + 1]
        }
        fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            // Particle e's kinetic energy in its own term (the last one's in the last term).
            let mass = |i: usize| (i + 1) as f64;
            let mut kinetic = v[0] * v[0] * (0.5 * mass(e)) + v[0] * v[1] * self.coupling;
            if e == self.n - 2 {
                kinetic += v[1] * v[1] * (0.5 * mass(e + 1));
            }
            kinetic - (q[1] - q[0]).powi(2) * 0.5
        }
    }

    /// M⁻¹p of a sum of terms, diagonal and coupled, equals the dense inverse's, and Mp
    /// from what it holds the product with M.
    #[test]
    fn term_sums_invert_like_the_dense_matrix() {
        for coupling in [0.0, 0.3] {
            let model = Chain { n: 7, coupling };
            let q = DVector::from_fn(7, |i, _| 0.1 * i as f64);
            let zero = DVector::zeros(7);
            let p = DVector::from_fn(7, |i, _| 1.0 - 0.2 * i as f64);
            let inverse = MassInverse::<Dyn>::of_terms(&model, 0.0, &q, &zero).unwrap();
            assert_eq!(
                matches!(inverse, MassInverse::Diagonal(_)),
                coupling == 0.0,
                "{inverse:?}"
            );
            // M by hand: masses 1, …, 7 on the diagonal, the coupling beside it.
            let mass = DMatrix::from_fn(7, 7, |i, j| match i.abs_diff(j) {
                0 => (i + 1) as f64,
                1 => coupling,
                _ => 0.0,
            });
            let dense = invert_small(&mass).unwrap();
            let expected = &dense * &p * 2.0;
            let mut out = DVector::zeros(7);
            inverse.scaled(2.0).apply_into(&p, &mut out);
            assert!((&out - &expected).amax() < 1e-14, "{out} vs {expected}");
            // A matrix, column by column.
            let columns = DMatrix::from_fn(7, 7, |i, j| (i as f64 - 0.5 * j as f64).sin());
            let mut image = DMatrix::zeros(7, 7);
            inverse.scaled(2.0).apply_columns_into(&columns, &mut image);
            let by_dense = &dense * &columns * 2.0;
            assert!((&image - &by_dense).amax() < 1e-14, "{image} vs {by_dense}");
            // M itself, from what the inverse holds (the observers' p = M q̇).
            let mut momentum = DVector::zeros(7);
            assert!(inverse.mass_times_into(&p, &mut momentum));
            let by_hand = &mass * &p;
            assert!(
                (&momentum - &by_hand).amax() < 1e-14,
                "{momentum} vs {by_hand}"
            );
            // A clone factors again on first use and gives the same numbers.
            let copy = inverse.clone();
            let mut second = DVector::zeros(7);
            copy.scaled(2.0).apply_into(&p, &mut second);
            assert!((&second - &expected).amax() < 1e-14);
        }
    }

    /// A diagonal dense M of run-time size is inverted entry by entry, to the digits of the
    /// dense inverse (here exact: powers of two); a coupled one, or one of fixed size,
    /// densely; a zero mass is singular.
    #[test]
    fn dense_mass_matrices_invert_entry_by_entry_when_diagonal() {
        let p = DVector::from_vec(vec![1.0, -3.0, 0.5]);
        let diagonal = DMatrix::from_diagonal(&DVector::from_vec(vec![2.0, 0.25, 8.0]));
        let inverse = MassInverse::of_dense(&diagonal).unwrap();
        assert!(matches!(inverse, MassInverse::Diagonal(_)), "{inverse:?}");
        let mut out = DVector::zeros(3);
        inverse.scaled(3.0).apply_into(&p, &mut out);
        assert_eq!(out.as_slice(), [1.5, -36.0, 0.1875]);
        let columns = DMatrix::from_fn(3, 3, |i, j| p[i] * (j + 1) as f64);
        let mut image = DMatrix::zeros(3, 3);
        inverse.scaled(3.0).apply_columns_into(&columns, &mut image);
        assert_eq!(
            image,
            DMatrix::from_fn(3, 3, |i, j| out[i] * (j + 1) as f64)
        );
        assert_eq!(inverse.to_dense(), invert_small(&diagonal).unwrap());
        let fixed = SMatrix::<f64, 3, 3>::from_column_slice(diagonal.as_slice());
        let inverse = MassInverse::of_dense(&fixed).unwrap();
        assert_eq!(inverse.dense(), invert_small(&fixed).as_ref());
        // A dense inverse does not keep M.
        let mut unused = SVector::<f64, 3>::zeros();
        assert!(!inverse.mass_times_into(&SVector::from([1.0, 2.0, 3.0]), &mut unused));
        let mut coupled = diagonal.clone();
        coupled[(0, 2)] = 1.0;
        coupled[(2, 0)] = 1.0;
        let inverse = MassInverse::of_dense(&coupled).unwrap();
        assert_eq!(inverse.dense(), invert_small(&coupled).as_ref());
        let mut massless = diagonal;
        massless[(1, 1)] = 0.0;
        let error = MassInverse::of_dense(&massless).unwrap_err();
        assert!(error.to_string().contains("singular"), "{error}");
    }

    /// A mass matrix with a zero on its diagonal is a typed error naming the coordinate.
    #[test]
    fn a_singular_mass_matrix_is_an_error() {
        struct Massless;
        impl LocalLagrangian for Massless {
            type Width = Const<1>;
            fn dimension(&self) -> usize {
                3
            }
            fn term_count(&self) -> usize {
                3
            }
            fn indices(&self, e: usize) -> [usize; 1] {
                [e]
            }
            fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
                v[0] * v[0] * (0.5 * (e as f64 - 1.0).abs()) - q[0] * q[0]
            }
        }
        let zero = DVector::zeros(3);
        let error = MassInverse::<Dyn>::of_terms(&Massless, 0.0, &zero, &zero).unwrap_err();
        assert!(error.to_string().contains("coordinate 1"), "{error}");
    }
}
