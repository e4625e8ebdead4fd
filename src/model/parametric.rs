//! Models whose parameters can be differentiated, and the Lagrangian that carries them as
//! coordinates.
//!
//! # Parameters as dual numbers
//! A [`Parametric`] model writes its Lagrangian once more with its parameters θ as scalars of
//! the same type as q and q̇, L(t, q, q̇; θ) ([`Parametric::lagrangian_with`]), and so its force
//! and, where the parameters fix it, its initial state. Every derivative with respect to θ
//! then comes from the same automatic differentiation as those with respect to (q, q̇). The
//! model's own [`Lagrangian::lagrangian`] should call it with its values, so that L is
//! written once.
//!
//! # Parameters as coordinates
//! [`WithParameters`] is the Lagrangian on ℝⁿ⁺ᴾ of the coordinates z = (q, θ),
//!
//! L̂(t, z, ż) = L(t, q, q̇; θ) + ½|θ̇|²,
//!
//! with the Lagrange–d'Alembert force f̂ = (f_L(t, q, q̇; θ), −∂L/∂θ). Its Euler–Lagrange
//! equations are those of L for q and θ̈ = ∂L/∂θ − ∂L/∂θ = 0 for θ, so a run from θ̇ = 0
//! keeps θ constant and moves q as the model does. Every method of svi discretises the
//! force with the quadrature of its action (Marsden & West 2001, §3.2), so the discrete θ
//! equation is θ's own discrete Euler–Lagrange equation of ½|θ̇|², and the method's step on
//! L̂ is its step on L with θ carried along. The exact tangent map of that step
//! ([`crate::method::Method::tangent_map`]) then holds the step's derivatives with respect
//! to θ: the columns of θ (crate::analysis::sensitivity).
//!
//! L̂ is declared [`Structure::General`] and forced whatever L declares (its mass matrix
//! may depend on θ: a pendulum's m l²), so the methods take their general paths on it: the
//! same discrete map as on L, up to the convergence of their solves.

use crate::dimension::{Dimension, Dyn};
use crate::model::{Lagrangian, Structure};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector, U1};
use num_dual::Dual;
use std::marker::PhantomData;

/// A Lagrangian whose parameters θ can be carried as dual numbers (see the
/// [module](self) documentation).
pub trait Parametric<N: Dimension>: Lagrangian<N>
where
    DefaultAllocator: Allocator<N>,
{
    /// The names of the parameters, in the order of [`Parametric::parameter_values`].
    fn parameter_names(&self) -> Vec<String>;

    /// The parameters' values θ.
    fn parameter_values(&self) -> Vec<f64>;

    /// L(t, q, q̇; θ), generic over the scalar like [`Lagrangian::lagrangian`], which it
    /// equals at θ = [`Parametric::parameter_values`].
    fn lagrangian_with<D: Scalar>(
        &self,
        theta: &[D],
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> D;

    /// f_L(t, q, q̇; θ), read only when [`Lagrangian::FORCED`] is `true` (it then equals
    /// [`Lagrangian::external_force`] at the parameters' values). The default is zero.
    fn external_force_with<D: Scalar>(
        &self,
        theta: &[D],
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N> {
        let _ = (theta, t, v);
        OVector::zeros_generic(q.shape_generic().0, U1)
    }

    /// The model's own initial state (q₀, q̇₀) as a function of θ, where its parameters
    /// choose it (Kepler's eccentricity chooses the orbit); `None` (the default) where they
    /// do not.
    fn initial_state_with<D: Scalar>(&self, theta: &[D]) -> Option<(OVector<D, N>, OVector<D, N>)> {
        let _ = theta;
        None
    }

    /// Whether parameter number `index` enters L or the force (the default, `true`, is
    /// always correct). A parameter that only chooses the initial state (Kepler's e and
    /// phase) answers `false`: derivatives with respect to such parameters alone then run on
    /// the model itself, in its own dimension and with its own [`Lagrangian::STRUCTURE`],
    /// instead of on [`WithParameters`]. The declaration is checked at the initial state of
    /// every differentiated run (∂L/∂θ and ∂f/∂θ must vanish there).
    fn enters_lagrangian(&self, index: usize) -> bool {
        let _ = index;
        true
    }
}

/// The index of each of `names` among the parameters of `model`.
///
/// # Errors
/// [`crate::Error::InvalidParameter`] `parameters` naming the first name the model does not
/// have (and the names it has), or a name given twice.
pub fn parameter_indices<L: Parametric<N>, N: Dimension>(
    model: &L,
    names: &[&str],
) -> Result<Vec<usize>, crate::Error>
where
    DefaultAllocator: Allocator<N>,
{
    let known = model.parameter_names();
    let mut indices = Vec::with_capacity(names.len());
    for name in names {
        let index = known.iter().position(|k| k == name).ok_or_else(|| {
            crate::Error::invalid(
                "parameters",
                format!(
                    "the model has no parameter '{name}' (its parameters: {})",
                    if known.is_empty() {
                        "none".to_owned()
                    } else {
                        known.join(", ")
                    }
                ),
            )
        })?;
        if indices.contains(&index) {
            return Err(crate::Error::invalid(
                "parameters",
                format!("'{name}' is named twice"),
            ));
        }
        indices.push(index);
    }
    Ok(indices)
}

/// The Lagrangian L̂(t, (q, θ), (q̇, θ̇)) = L(t, q, q̇; θ) + ½|θ̇|² on ℝⁿ⁺ᴾ with the force
/// (f_L, −∂L/∂θ), for the parameters `chosen` of a [`Parametric`] model (the others keep
/// their values); see the [module](self) documentation.
#[derive(Debug, Clone)]
pub struct WithParameters<'a, L, N> {
    model: &'a L,
    /// n.
    n: usize,
    /// θ at the model's values (the parameters not chosen keep them).
    values: Vec<f64>,
    /// The indices into θ of the parameters that are coordinates, in coordinate order.
    chosen: Vec<usize>,
    dimension: PhantomData<fn() -> N>,
}

impl<'a, L: Parametric<N>, N: Dimension> WithParameters<'a, L, N>
where
    DefaultAllocator: Allocator<N>,
{
    /// L̂ for `model` of `n` coordinates with the parameters at `chosen` (indices into
    /// [`Parametric::parameter_values`], see [`parameter_indices`]) as the last coordinates.
    pub fn new(model: &'a L, n: usize, chosen: Vec<usize>) -> Self {
        WithParameters {
            model,
            n,
            values: model.parameter_values(),
            chosen,
            dimension: PhantomData,
        }
    }

    /// n, the model's coordinates.
    pub fn coordinates(&self) -> usize {
        self.n
    }

    /// P, the parameters that are coordinates.
    pub fn parameter_count(&self) -> usize {
        self.chosen.len()
    }

    /// The chosen parameters' values, the last P entries of z.
    pub fn chosen_values(&self) -> Vec<f64> {
        self.chosen.iter().map(|&i| self.values[i]).collect()
    }

    /// (q, q̇, θ) of the model from (z, ż): the first n entries and the full θ with the
    /// chosen parameters taken from z.
    fn split<D: Scalar>(&self, z: &DVector<D>, zdot: &DVector<D>) -> Split<D, N>
    where
        DefaultAllocator: Allocator<N>,
    {
        let dim = N::from_usize(self.n);
        let q = OVector::<D, N>::from_iterator_generic(dim, U1, z.iter().take(self.n).copied());
        let v = OVector::<D, N>::from_iterator_generic(dim, U1, zdot.iter().take(self.n).copied());
        let mut theta = Theta::new(self.values.iter().map(|&x| D::from(x)));
        for (k, &i) in self.chosen.iter().enumerate() {
            theta[i] = z[self.n + k];
        }
        (q, v, theta)
    }
}

/// (q, q̇, θ) of [`WithParameters::split`].
type Split<D, N> = (OVector<D, N>, OVector<D, N>, Theta<D>);

/// The most parameters [`Theta`] holds on the stack.
const INLINE: usize = 8;

/// Parameters θ, held on the stack up to [`INLINE`] of them (L̂ is evaluated many times per
/// step: no heap vector each time).
enum Theta<D> {
    /// The first `len` entries.
    Inline([D; INLINE], usize),
    /// More than [`INLINE`].
    Heap(Vec<D>),
}

impl<D: Scalar> Theta<D> {
    /// θ from its entries.
    fn new(values: impl ExactSizeIterator<Item = D>) -> Self {
        let len = values.len();
        if len <= INLINE {
            let mut inline = [D::zero(); INLINE];
            for (slot, value) in inline.iter_mut().zip(values) {
                *slot = value;
            }
            Theta::Inline(inline, len)
        } else {
            Theta::Heap(values.collect())
        }
    }
}

impl<D> std::ops::Deref for Theta<D> {
    type Target = [D];
    fn deref(&self) -> &[D] {
        match self {
            Theta::Inline(values, len) => &values[..*len],
            Theta::Heap(values) => values,
        }
    }
}

impl<D> std::ops::DerefMut for Theta<D> {
    fn deref_mut(&mut self) -> &mut [D] {
        match self {
            Theta::Inline(values, len) => &mut values[..*len],
            Theta::Heap(values) => values,
        }
    }
}

impl<L: Parametric<N>, N: Dimension> Lagrangian<Dyn> for WithParameters<'_, L, N>
where
    DefaultAllocator: Allocator<N>,
{
    const TIME_DEPENDENT: bool = L::TIME_DEPENDENT;
    const STRUCTURE: Structure = Structure::General;
    const FORCED: bool = true;

    fn dimension(&self) -> usize {
        self.n + self.chosen.len()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, z: &DVector<D>, zdot: &DVector<D>) -> D {
        let (q, v, theta) = self.split(z, zdot);
        let kinetic = zdot
            .iter()
            .skip(self.n)
            .fold(D::zero(), |sum, &rate| sum + rate * rate);
        self.model.lagrangian_with(&theta, t, &q, &v) + kinetic * 0.5
    }

    /// (f_L(t, q, q̇; θ), −∂L/∂θ): the second part by one dual sweep per parameter.
    fn external_force<D: Scalar>(&self, t: D, z: &DVector<D>, zdot: &DVector<D>) -> DVector<D> {
        let (q, v, theta) = self.split(z, zdot);
        let mut force = DVector::zeros(self.n + self.chosen.len());
        if L::FORCED {
            let f = self.model.external_force_with(&theta, t, &q, &v);
            force.rows_mut(0, self.n).copy_from(&f.rows(0, self.n));
        }
        let (lift_q, lift_v) = (q.map(Dual::from_re), v.map(Dual::from_re));
        let mut lifted = Theta::new(theta.iter().map(|&x| Dual::from_re(x)));
        for (k, &i) in self.chosen.iter().enumerate() {
            lifted[i] = Dual::new(theta[i], D::one());
            let value = self
                .model
                .lagrangian_with(&lifted, Dual::from_re(t), &lift_q, &lift_v);
            force[self.n + k] = -value.eps;
            lifted[i] = Dual::from_re(theta[i]);
        }
        force
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LagrangianExt;
    use nalgebra::{SVector, U1};

    /// L = ½ m q̇² − ½ k q² with friction −c q̇; θ = (m, k, c).
    struct Oscillator {
        m: f64,
        k: f64,
        c: f64,
    }

    impl Lagrangian<U1> for Oscillator {
        const TIME_DEPENDENT: bool = false;
        const FORCED: bool = true;
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            self.lagrangian_with(&[self.m, self.k, self.c].map(D::from), t, q, v)
        }
        fn external_force<D: Scalar>(
            &self,
            t: D,
            q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            self.external_force_with(&[self.m, self.k, self.c].map(D::from), t, q, v)
        }
    }

    impl Parametric<U1> for Oscillator {
        fn parameter_names(&self) -> Vec<String> {
            ["m", "k", "c"].map(String::from).to_vec()
        }
        fn parameter_values(&self) -> Vec<f64> {
            vec![self.m, self.k, self.c]
        }
        fn lagrangian_with<D: Scalar>(
            &self,
            theta: &[D],
            _t: D,
            q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> D {
            (theta[0] * v[0] * v[0] - theta[1] * q[0] * q[0]) * 0.5
        }
        fn external_force_with<D: Scalar>(
            &self,
            theta: &[D],
            _t: D,
            _q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            SVector::from([-theta[2] * v[0]])
        }
    }

    #[test]
    fn the_parameter_force_cancels_the_parameter_gradient() {
        let model = Oscillator {
            m: 2.0,
            k: 3.0,
            c: 0.5,
        };
        // θ = (k, m) as coordinates, in that order; c keeps its value.
        let hat = WithParameters::new(&model, 1, vec![1, 0]);
        let z = DVector::from_vec(vec![0.7, 3.0, 2.0]);
        let zdot = DVector::from_vec(vec![-0.4, 0.0, 0.0]);
        let gradient = LagrangianExt::<Dyn>::first_derivatives(&hat, 0.0, &z, &zdot);
        let force = Lagrangian::<Dyn>::external_force(&hat, 0.0, &z, &zdot);
        // ∂L/∂k = −q²/2, ∂L/∂m = q̇²/2; the force is their negative.
        assert!((gradient.q[1] - (-0.5 * 0.49)).abs() < 1e-15);
        assert!((gradient.q[2] - 0.5 * 0.16).abs() < 1e-15);
        assert_eq!(force[1], -gradient.q[1]);
        assert_eq!(force[2], -gradient.q[2]);
        // The model's own coordinate: ∂L/∂q = −k q, and the friction −c q̇.
        assert!((gradient.q[0] + 3.0 * 0.7).abs() < 1e-15);
        assert!((force[0] - 0.5 * 0.4).abs() < 1e-15);
        assert_eq!(
            hat.lagrangian(0.0, &z, &zdot),
            model.lagrangian(0.0, &SVector::from([0.7]), &SVector::from([-0.4]))
        );
    }

    #[test]
    fn an_unknown_or_repeated_parameter_is_named() {
        let model = Oscillator {
            m: 1.0,
            k: 1.0,
            c: 0.0,
        };
        assert_eq!(parameter_indices(&model, &["c", "m"]).unwrap(), vec![2, 0]);
        let error = parameter_indices(&model, &["m", "length"])
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("'length'") && error.contains("m, k, c"),
            "{error}"
        );
        let error = parameter_indices(&model, &["k", "k"])
            .unwrap_err()
            .to_string();
        assert!(error.contains("'k' is named twice"), "{error}");
    }
}
