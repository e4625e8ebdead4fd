//! Tiny models and helpers shared by the unit tests of the numerical modules (the zoo crate
//! cannot be used inside `src/`: cargo would see two copies of `svi`).

use crate::dimension::Dimension;
use crate::method::{Method, State};
use crate::model::hamiltonian::Hamiltonian;
use crate::model::{Lagrangian, Structure};
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DVector, DefaultAllocator, Dyn, SVector, U1, U2};

/// [`Structure::ConstantMass`] or [`Structure::General`]: the same model declared either way
/// runs the fixed-point or the Newton path of the spectral methods.
const fn structure(constant_mass: bool) -> Structure {
    if constant_mass {
        Structure::ConstantMass
    } else {
        Structure::General
    }
}

/// Harmonic oscillator L = q̇²/2 − q²/2.
pub(crate) struct Oscillator<const CONSTANT_MASS: bool>;
impl<const CONSTANT_MASS: bool> Lagrangian<U1> for Oscillator<CONSTANT_MASS> {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = structure(CONSTANT_MASS);
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0]) * 0.5
    }
}

/// Hénon–Heiles potential with the constant, non-diagonal mass M = [[2, 1], [1, 3]]:
/// L = ½ q̇ᵀMq̇ − ½|q|² − q₀²q₁ + q₁³/3.
pub(crate) struct HenonHeiles<const CONSTANT_MASS: bool>;
impl<const CONSTANT_MASS: bool> Lagrangian<U2> for HenonHeiles<CONSTANT_MASS> {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = structure(CONSTANT_MASS);
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let kinetic = (v[0] * v[0] * 2.0 + v[0] * v[1] * 2.0 + v[1] * v[1] * 3.0) * 0.5;
        let potential = q.dot(q) * 0.5 + q[0] * q[0] * q[1] - q[1].powi(3) / 3.0;
        kinetic - potential
    }
}

/// Position-dependent mass: L = ½ (1 + q₁²) q̇₀² + ½ q̇₁² − V(q), V = ½ |q|² + ¼ q₀⁴.
pub(crate) struct VariableMass;
impl Lagrangian<U2> for VariableMass {
    const TIME_DEPENDENT: bool = false;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let kinetic = (q[1] * q[1] + 1.0) * v[0] * v[0] * 0.5 + v[1] * v[1] * 0.5;
        kinetic - q.dot(q) * 0.5 - q[0].powi(4) * 0.25
    }
}

/// [`VariableMass`] written as a Hamiltonian (a general H, not separable):
/// H = p₀²/(2(1 + q₁²)) + p₁²/2 + ½ |q|² + ¼ q₀⁴.
pub(crate) struct VariableMassH;
impl Hamiltonian<U2> for VariableMassH {
    const TIME_DEPENDENT: bool = false;
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
        p[0] * p[0] / ((q[1] * q[1] + 1.0) * 2.0)
            + p[1] * p[1] * 0.5
            + q.dot(q) * 0.5
            + q[0].powi(4) * 0.25
    }
}

/// Damped oscillator L = q̇²/2 − q²/2 with friction f_L = −c q̇.
pub(crate) struct Damped<const CONSTANT_MASS: bool> {
    /// The friction coefficient c.
    pub(crate) c: f64,
}
impl<const CONSTANT_MASS: bool> Lagrangian<U1> for Damped<CONSTANT_MASS> {
    const TIME_DEPENDENT: bool = false;
    const FORCED: bool = true;
    const STRUCTURE: Structure = structure(CONSTANT_MASS);
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
        (v[0] * v[0] - q[0] * q[0]) * 0.5
    }
    fn external_force<D: Scalar>(
        &self,
        _t: D,
        _q: &SVector<D, 1>,
        v: &SVector<D, 1>,
    ) -> SVector<D, 1> {
        v.map(|x| x * (-self.c))
    }
}

/// The state (q, y).
pub(crate) fn state<const N: usize>(q: [f64; N], y: [f64; N]) -> State<Const<N>> {
    State {
        q: SVector::from(q),
        y: SVector::from(y),
    }
}

/// ‖a − b‖∞ over q and y.
pub(crate) fn distance<N: Dimension>(a: &State<N>, b: &State<N>) -> f64
where
    DefaultAllocator: Allocator<N>,
{
    (&a.q - &b.q).amax().max((&a.y - &b.y).amax())
}

/// `steps` steps of size `h` from `start` at t = 0, by the method alone (no stepping loop):
/// the end state and the workspace.
pub(crate) fn advance<M: Method<N>, L: Lagrangian<N>, N: Dimension>(
    method: &M,
    model: &L,
    h: f64,
    steps: usize,
    start: State<N>,
) -> (State<N>, M::Workspace)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let mut workspace = method.workspace(model, h).unwrap();
    let mut increment = State::zeros(start.dimension());
    let mut current = start;
    for k in 0..steps {
        method
            .step(
                model,
                &mut workspace,
                k as f64 * h,
                h,
                &current,
                &mut increment,
            )
            .unwrap();
        current.q += &increment.q;
        current.y += &increment.y;
    }
    (current, workspace)
}

/// Check a method's tangent map against central differences of its step map with δ = 1e-6
/// (each evaluation from a fresh workspace, converged to round-off): truncation
/// δ² |Φ'''| ≈ 1e-12 and round-off ε/δ ≈ 1e-10, so they must agree to 1e-8.
pub(crate) fn assert_tangent_matches_central_differences<
    M: Method<N>,
    L: Lagrangian<N>,
    N: Dimension,
>(
    method: &M,
    model: &L,
    start: State<N>,
) where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (h, delta) = (0.3, 1e-6);
    let n = start.q.len();
    let end = |x: State<N>| {
        let (after, _) = advance(method, model, h, 1, x);
        DVector::from_iterator(2 * n, after.q.iter().chain(after.y.iter()).copied())
    };
    let mut workspace = method.workspace(model, h).unwrap();
    let (_, tangent, _) = method
        .tangent_map(model, &mut workspace, 0.0, h, &start)
        .unwrap();
    let phi = tangent.matrix();
    for j in 0..2 * n {
        let (mut plus, mut minus) = (start.clone(), start.clone());
        if j < n {
            plus.q[j] += delta;
            minus.q[j] -= delta;
        } else {
            plus.y[j - n] += delta;
            minus.y[j - n] -= delta;
        }
        let column = (end(plus) - end(minus)) / (2.0 * delta);
        let error = (phi.column(j) - &column).amax();
        assert!(error <= 1e-8, "column {j}: {} vs {column}", phi.column(j));
    }
}

/// n! as a float.
pub(crate) fn factorial(n: usize) -> f64 {
    (1..=n).map(|k| k as f64).product()
}

/// A fixed-size model `L` seen as a run-time-size one (`Lagrangian<Dyn>`): the same
/// Lagrangian, with vectors copied between the two layouts, so tests compare the two paths.
pub(crate) struct AsDyn<L, N>(L, std::marker::PhantomData<N>);

impl<L, N> AsDyn<L, N> {
    /// `model`, of fixed dimension `N`, as a run-time-size model.
    pub(crate) fn new(model: L) -> Self {
        AsDyn(model, std::marker::PhantomData)
    }
}

impl<L: Lagrangian<Const<K>>, const K: usize> Lagrangian<Dyn> for AsDyn<L, Const<K>> {
    const TIME_DEPENDENT: bool = L::TIME_DEPENDENT;
    const STRUCTURE: Structure = L::STRUCTURE;
    const FORCED: bool = L::FORCED;

    fn dimension(&self) -> usize {
        K
    }

    fn lagrangian<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        let fixed = |x: &DVector<D>| SVector::<D, K>::from_fn(|i, _| x[i]);
        self.0.lagrangian(t, &fixed(q), &fixed(v))
    }

    fn external_force<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> DVector<D> {
        let fixed = |x: &DVector<D>| SVector::<D, K>::from_fn(|i, _| x[i]);
        let force = self.0.external_force(t, &fixed(q), &fixed(v));
        DVector::from_column_slice(force.as_slice())
    }
}
