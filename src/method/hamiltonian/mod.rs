//! Methods on Hamilton's equations, for any model: written as H (no Legendre transform at run
//! time) or as L (H's derivatives through the Legendre map, [`crate::model::canonical`]).
//!
//! With g(t, q, p) = ∂H/∂q − f_H(t, q, p), the equations are q̇ = ∂H/∂p, ṗ = −g (the forced
//! Hamiltonian form of [`crate::model::hamiltonian`]). Every method takes H's derivatives
//! through [`crate::model::canonical`] only, so it runs a model written as L on the same
//! equations (the inverse Legendre map started at the last velocity), and states are (q, p)
//! ([`crate::Coordinates::Momentum`]). Each is written once over the dimension N.
//!
//! | method | name | equations | order | symmetric | explicit |
//! | --- | --- | --- | --- | --- | --- |
//! | [`HamiltonianCollocation`] | `sc-h[:P]` | SC's CGL collocation of z' = (∂H/∂p, −g) ([`collocation`]) | P − 1 | no | never |
//! | [`HamiltonianGalerkin`] | `svi-h[:P[/M]]` | the Galerkin discrete right Hamiltonian on SVI's curve and Gauss rule ([`galerkin`]) | 2·min(P − 1, M) | yes | never (SVI's fixed point for H = ½pᵀM⁻¹p + V) |
//! | [`Partitioned::symplectic_euler`] | `symplectic-euler-h` | p_{k+1} = p_k − h g(t_k, q_k, p_{k+1}), q_{k+1} = q_k + h ∂H/∂p(t_k, q_k, p_{k+1}) | 1 | no | separable H, unforced |
//! | [`Partitioned::adjoint_symplectic_euler`] | `symplectic-euler-adjoint-h` | q_{k+1} = q_k + h ∂H/∂p(t_{k+1}, q_{k+1}, p_k), p_{k+1} = p_k − h g(t_{k+1}, q_{k+1}, p_k) | 1 | no | separable H |
//! | [`ImplicitMidpoint`] | `midpoint-h` | z_{k+1} = z_k + h (∂H/∂p, −g)(t_k + h/2, (z_k + z_{k+1})/2), z = (q, p) | 2 | yes | never |
//! | [`Partitioned::stormer_verlet`] | `verlet-h` | the kick–drift–kick below with a = b = ½ | 2 | yes | separable H, unforced |
//! | [`Composition::hamiltonian`] | `yoshida4-h`, `kahan-li6-h`, `kahan-li8-h` | symmetric compositions of `verlet-h` ([`Scheme`]) | 4, 6, 8 | yes | as `verlet-h` |
//!
//! The three partitioned methods are one step with the weights (a, b) of [`Kicks`] (a = 1:
//! symplectic Euler, b = 1: its adjoint, a = b = ½: Störmer–Verlet), t' = t_k + h:
//!
//! P = p_k − a h g(t_k, q_k, P),
//! q_{k+1} = q_k + a h ∂H/∂p(t_k, q_k, P) + b h ∂H/∂p(t', q_{k+1}, P),
//! p_{k+1} = P − b h g(t', q_{k+1}, P)
//!
//! (Hairer, Lubich, Wanner, *Geometric numerical integration*, 2nd ed. 2006, eqs. VI.3.1,
//! VI.3.2 and VI.3.4; Störmer–Verlet is the adjoint symplectic Euler method of step h/2 after
//! the symplectic Euler method of step h/2, §II.3, and the Lobatto IIIA–IIIB pair, §II.2).
//! The first line is implicit in P and the second in q_{k+1}, each solved by Newton's method on
//! N unknowns with H's Hessian blocks (I + a h (∂²H/∂q∂p − ∂f_H/∂p), I − b h (∂²H/∂q∂p)ᵀ).
//! For a separable H = T(p) + V(t, q) ([`crate::model::canonical::structure`]) ∂H/∂q does not
//! depend on p and ∂H/∂p = T′(p) not on (t, q): the step is the explicit kick, drift
//! q_{k+1} = q_k + h T′(P), kick, with any kinetic energy T (a relativistic √(1 + |p|²)
//! included, whose drift is not linear in p), and no Newton iteration and no Hessian without
//! a force. The implicit midpoint rule is implicit in both (Newton's method on 2N unknowns).
//!
//! # Symplecticity
//! Symplectic Euler is the map of the type II generating function (the discrete right
//! Hamiltonian of Leok & Zhang 2011, §2–3) H_d⁺(q_k, p_{k+1}) = p_{k+1}ᵀq_k + h H(t_k, q_k,
//! p_{k+1}), by p_k = ∂H_d⁺/∂q_k, q_{k+1} = ∂H_d⁺/∂p_{k+1}; its adjoint is the map of the
//! discrete left Hamiltonian H_d⁻(p_k, q_{k+1}) = −p_kᵀq_{k+1} + h H(t_{k+1}, q_{k+1}, p_k)
//! (type III); Störmer–Verlet and the compositions are compositions of them; the implicit
//! midpoint rule is symplectic (HLW Theorems VI.3.3–VI.3.5). The tests check JᵀΩJ = Ω on a
//! non-separable H.
//!
//! # Forces
//! f_H enters where ∂H/∂q does, with the same weights: at the kick points (t_k, q_k, P) with a h
//! and (t', q_{k+1}, P) with b h, at the midpoint with h. Through the Legendre map these are
//! the discrete forces f_d^± of the discrete Lagrange–d'Alembert principle of the
//! corresponding segment rules (Marsden & West, *Discrete mechanics and variational
//! integrators*, Acta Numerica 2001, §3.2): symplectic Euler's f_d⁻ = h f_L(t_k, q_k, v), the
//! adjoint's f_d⁺ = h f_L(t', q_{k+1}, v), the midpoint's f_d^± = (h/2) f_L at the midpoint, and
//! Störmer–Verlet's composition of the two half steps — for a constant mass exactly the
//! discrete forces of the trapezoidal L_d that [`crate::StormerVerlet`] uses. A force that
//! depends on p makes the first kick of a separable H implicit in P through f_H alone. With a
//! force no method is symplectic; the orders are unchanged.
//!
//! # Coincidences (tested to round-off)
//! Through the Legendre map v = ∂H/∂p: `symplectic-euler-h` is the variational
//! `symplectic-euler` (L_d = h L(t_k, q_k, v)), `symplectic-euler-adjoint-h` the variational
//! `symplectic-euler-adjoint`, and `midpoint-h` the variational `midpoint`, for every regular
//! L; `verlet-h` is the variational `symplectic-euler-adjoint` of step h/2 after the variational
//! `symplectic-euler` of step h/2, and for a constant mass also the variational `verlet`
//! (trapezoid). For a mass matrix that depends on q the trapezoid's L_d, which holds one
//! velocity on the whole step, gives another map: an O(h³) difference per step.
//!
//! # References
//! Hairer, Lubich, Wanner, *Geometric numerical integration* (2006), §II.2–II.4, §VI.3 and
//! §VI.6; Leok & Zhang, *Discrete Hamiltonian variational integrators*, IMA J. Numer. Anal. 31
//! (2011) 1497–1532; Marsden & West, Acta Numerica (2001), §3.2.
//!
//! [`Composition::hamiltonian`]: crate::method::variational::composition::Composition::hamiltonian
//! [`Scheme`]: crate::method::variational::composition::Scheme
//! [`Kicks`]: crate::method::variational::discrete_lagrangian::Kicks

pub mod collocation;
pub mod galerkin;
pub mod midpoint;
pub mod partitioned;

pub use collocation::HamiltonianCollocation;
pub use galerkin::HamiltonianGalerkin;
pub use midpoint::ImplicitMidpoint;
pub use partitioned::Partitioned;

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::model::canonical;
use crate::model::derived::cached_mass_inverse;
use crate::model::hamiltonian::CanonicalSecond;
use crate::model::mass_inverse::MassInverse;
use crate::model::{ConstantMass, Lagrangian};
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Two vectors of ℝᴺ: (∂H/∂q, ∂H/∂p), or (g, ∂H/∂p).
type Pair<N> = (OVector<f64, N>, OVector<f64, N>);

/// A derivative of H that could not be taken — the inverse Legendre map of a model written as
/// L did not converge, or its mass matrix is singular — as the failure of the step.
fn failure(error: Error) -> StepFailure {
    match error {
        Error::LegendreMap {
            iterations,
            residual,
            ..
        } if residual.is_finite() => StepFailure::NonConvergence {
            iterations,
            residual,
        },
        Error::LegendreMap { .. } => StepFailure::SingularMatrix,
        _ => StepFailure::NonFinite,
    }
}

/// H's derivatives and f_H at the points of a step, through [`canonical`], counted; the last
/// velocity ∂H/∂p starts the next inverse Legendre map of a model written as L.
#[derive(Debug, Clone)]
struct Derivatives<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Whether the model has a force f_H.
    forced: bool,
    /// ∂H/∂p at the last point: the guess of the next inverse Legendre map.
    velocity: OVector<f64, N>,
    /// Points at which H was differentiated in this step.
    evaluations: usize,
    /// M⁻¹ of a constant-mass model written as L, from the first step: the observers'
    /// q̇ = M⁻¹p.
    mass_inverse: Option<MassInverse<N>>,
}

impl<N: Dimension> Derivatives<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// For `model`, of dimension `n`.
    fn new<L: Lagrangian<N>>(model: &L, n: N) -> Self {
        Derivatives {
            forced: canonical::forced(model),
            velocity: OVector::zeros_generic(n, U1),
            evaluations: 0,
            mass_inverse: None,
        }
    }

    /// Start a step from `(t, q, p)`: the evaluation count reset, M⁻¹ of a constant-mass
    /// model written as L made once.
    fn start<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<(), StepFailure> {
        self.evaluations = 0;
        if ConstantMass::<L, N>::DECLARED && model.hamiltonian_form().is_none() {
            cached_mass_inverse(&mut self.mass_inverse, model, t, q, p)?;
        }
        Ok(())
    }

    /// (∂H/∂q, ∂H/∂p) at (t, q, p).
    fn gradient<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Pair<N>, StepFailure> {
        let (hq, hp) = canonical::gradient(model, t, q, p, &self.velocity).map_err(failure)?;
        self.velocity.copy_from(&hp);
        self.evaluations += 1;
        Ok((hq, hp))
    }

    /// ∂H/∂q alone at (t, q, p) (the kick of an unforced separable H).
    fn position_gradient<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<OVector<f64, N>, StepFailure> {
        let hq = canonical::position_gradient(model, t, q, p, &self.velocity).map_err(failure)?;
        self.evaluations += 1;
        Ok(hq)
    }

    /// ∂H/∂p alone at (t, q, p) (the drift of a separable H).
    fn velocity<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<OVector<f64, N>, StepFailure> {
        let hp = canonical::velocity(model, t, q, p, &self.velocity).map_err(failure)?;
        self.velocity.copy_from(&hp);
        self.evaluations += 1;
        Ok(hp)
    }

    /// g = ∂H/∂q − f_H and ∂H/∂p at (t, q, p).
    fn field<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Pair<N>, StepFailure> {
        let (mut g, hp) = self.gradient(model, t, q, p)?;
        if self.forced {
            g -= canonical::force(model, t, q, p, &hp).map_err(failure)?;
        }
        Ok((g, hp))
    }

    /// H's gradient and Hessian blocks at (t, q, p).
    fn second<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<CanonicalSecond<N>, StepFailure> {
        let second = canonical::second(model, t, q, p, &self.velocity).map_err(failure)?;
        self.velocity.copy_from(&second.hp);
        self.evaluations += 1;
        Ok(second)
    }

    /// The field (g, ∂H/∂p) at (t, q, p) and its derivatives.
    fn linearised<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
    ) -> Result<Linearised<N>, StepFailure> {
        let CanonicalSecond {
            hq, hp, qq, qp, pp, ..
        } = self.second(model, t, q, p)?;
        let mut field = Linearised {
            g: hq,
            hp,
            gq: qq,
            gp: qp.clone(),
            qp,
            pp,
        };
        if self.forced {
            let (f, fq, fp) =
                canonical::force_jacobian(model, t, q, p, &field.hp).map_err(failure)?;
            field.g -= f;
            field.gq -= fq;
            field.gp -= fp;
        }
        Ok(field)
    }

    /// q̇ = ∂H/∂p into `v` without a solve: H's gradient for a model written as H, M⁻¹p for a
    /// constant-mass one written as L; `false` for any other model.
    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> bool {
        if let Some(form) = model.hamiltonian_form() {
            v.copy_from(&form.velocity(t, q, p));
            return true;
        }
        match &self.mass_inverse {
            Some(inverse) => {
                inverse.apply_into(p, v);
                true
            }
            None => false,
        }
    }
}

/// The field of Hamilton's equations at a point, q̇ = ∂H/∂p, ṗ = −g with g = ∂H/∂q − f_H,
/// and its derivatives (entry (i, j) = ∂/∂xⱼ of component i, as [`CanonicalSecond`]).
#[derive(Debug, Clone)]
struct Linearised<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// g = ∂H/∂q − f_H.
    g: OVector<f64, N>,
    /// ∂H/∂p.
    hp: OVector<f64, N>,
    /// ∂g/∂q = ∂²H/∂q² − ∂f_H/∂q.
    gq: OMatrix<f64, N, N>,
    /// ∂g/∂p = ∂²H/∂q∂p − ∂f_H/∂p.
    gp: OMatrix<f64, N, N>,
    /// ∂²H/∂q∂p: ∂(∂H/∂p)/∂q is its transpose.
    qp: OMatrix<f64, N, N>,
    /// ∂²H/∂p² = ∂(∂H/∂p)/∂p.
    pp: OMatrix<f64, N, N>,
}

/// Newton's method on `unknown` whose residual may fail: `assemble(z, jacobian, residual)`
/// writes F(z) and F'(z) or returns the failure that stops the solve. Returns the iterations.
fn solve<F>(
    newton: &mut Newton,
    unknown: &mut DVector<f64>,
    mut assemble: F,
) -> Result<usize, StepFailure>
where
    F: FnMut(&DVector<f64>, &mut DMatrix<f64>, &mut DVector<f64>) -> Result<(), StepFailure>,
{
    let mut stopped = None;
    let result = newton.solve(unknown, |z, jacobian, residual| {
        if let Err(failure) = assemble(z, jacobian, residual) {
            stopped.get_or_insert(failure);
            residual.fill(f64::NAN);
        }
    });
    match stopped {
        Some(failure) => Err(failure),
        None => result,
    }
}

/// `a + weight · z` for a vector `z` of Newton's unknowns (the offset of a point from `a`).
fn offset<N: Dimension>(a: &OVector<f64, N>, weight: f64, z: &[f64]) -> OVector<f64, N>
where
    DefaultAllocator: Allocator<N>,
{
    OVector::from_fn_generic(a.shape_generic().0, U1, |i, _| a[i] + weight * z[i])
}

/// The N × N identity plus `weight` times `block`, into the column-major slice `target`.
fn identity_plus<N: Dimension>(weight: f64, block: &OMatrix<f64, N, N>, target: &mut [f64])
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = block.nrows();
    for (k, (target, entry)) in target.iter_mut().zip(block.as_slice()).enumerate() {
        *target = weight * entry + if k % (n + 1) == 0 { 1.0 } else { 0.0 };
    }
}

/// Tests of the methods on Hamilton's equations: orders against an independent reference,
/// the coincidences with the variational integrators, the explicit separable path,
/// symplecticity, forces and bad input.
#[cfg(test)]
mod tests {
    use super::{ImplicitMidpoint, Partitioned};
    use crate::analysis::verify::observed_order;
    use crate::error::Error;
    use crate::method::variational::composition::{Composition, Scheme};
    use crate::method::variational::discrete_lagrangian::{
        AdjointSymplecticEuler, Midpoint, SymplecticEuler, Trapezoid,
    };
    use crate::method::{Initial, Method, State};
    use crate::model::hamiltonian::{Canonical, Hamiltonian, HamiltonianStructure};
    use crate::model::{Lagrangian, Structure};
    use crate::scalar::Scalar;
    use crate::stepping::run::Integrator;
    use crate::test_models::{
        Damped, VariableMass, advance, assert_tangent_matches_central_differences, distance, state,
    };
    use crate::{StormerVerlet, VariationalIntegrator};
    use nalgebra::{DMatrix, SVector, U1, U2};

    /// A relativistic oscillator H = √(1 + p²) + q²/2, declared separable (`SEPARABLE`) or not.
    struct Relativistic<const SEPARABLE: bool>;

    impl<const SEPARABLE: bool> Hamiltonian<U1> for Relativistic<SEPARABLE> {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: HamiltonianStructure = if SEPARABLE {
            HamiltonianStructure::Separable
        } else {
            HamiltonianStructure::General
        };
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
        }
    }

    /// [`VariableMass`] written as H: p₀²/(2(1 + q₁²)) + p₁²/2 + (q₀² + q₁²)/2 + q₀⁴/4 (not
    /// separable).
    struct VariableMassH;

    impl Hamiltonian<U2> for VariableMassH {
        const TIME_DEPENDENT: bool = false;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, p: &SVector<D, 2>) -> D {
            p[0] * p[0] / ((q[1] * q[1] + 1.0) * 2.0)
                + p[1] * p[1] * 0.5
                + (q[0] * q[0] + q[1] * q[1]) * 0.5
                + q[0].powi(4) * 0.25
        }
    }

    /// The pendulum H = p²/2 − cos q, and as L = q̇²/2 + cos q.
    struct PendulumH;

    impl Hamiltonian<U1> for PendulumH {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            p[0] * p[0] * 0.5 - q[0].cos()
        }
    }

    struct Pendulum;

    impl Lagrangian<U1> for Pendulum {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: Structure = Structure::ConstantMass;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            v[0] * v[0] * 0.5 + q[0].cos()
        }
    }

    /// The damped oscillator H = (p² + q²)/2 with f_H = −c p: [`Damped`] written as H.
    struct DampedH {
        c: f64,
    }

    impl Hamiltonian<U1> for DampedH {
        const TIME_DEPENDENT: bool = false;
        const STRUCTURE: HamiltonianStructure = HamiltonianStructure::QuadraticKinetic;
        const FORCED: bool = true;
        fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
            (p[0] * p[0] + q[0] * q[0]) * 0.5
        }
        fn external_force<D: Scalar>(
            &self,
            _t: D,
            _q: &SVector<D, 1>,
            p: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            p.map(|x| x * (-self.c))
        }
    }

    /// The seven methods, by registry name.
    fn methods() -> Vec<(&'static str, usize, Method7)> {
        vec![
            (
                "symplectic-euler-h",
                1,
                Method7::Partitioned(Partitioned::symplectic_euler()),
            ),
            (
                "symplectic-euler-adjoint-h",
                1,
                Method7::Partitioned(Partitioned::adjoint_symplectic_euler()),
            ),
            (
                "midpoint-h",
                2,
                Method7::Midpoint(ImplicitMidpoint::default()),
            ),
            (
                "verlet-h",
                2,
                Method7::Partitioned(Partitioned::stormer_verlet()),
            ),
            (
                "yoshida4-h",
                4,
                Method7::Composition(Composition::hamiltonian(Scheme::Yoshida4)),
            ),
            (
                "kahan-li6-h",
                6,
                Method7::Composition(Composition::hamiltonian(Scheme::KahanLi6)),
            ),
            (
                "kahan-li8-h",
                8,
                Method7::Composition(Composition::hamiltonian(Scheme::KahanLi8)),
            ),
        ]
    }

    /// One of the methods as a value (the tests' own small `AnyMethod`).
    enum Method7 {
        Partitioned(Partitioned),
        Midpoint(ImplicitMidpoint),
        Composition(Composition<Partitioned>),
    }

    impl Method7 {
        /// `steps` steps of size `h` from `start` (at t = 0): the end state.
        fn advance<L: Lagrangian<nalgebra::Const<K>>, const K: usize>(
            &self,
            model: &L,
            h: f64,
            steps: usize,
            start: State<nalgebra::Const<K>>,
        ) -> State<nalgebra::Const<K>> {
            match self {
                Method7::Partitioned(m) => advance(m, model, h, steps, start).0,
                Method7::Midpoint(m) => advance(m, model, h, steps, start).0,
                Method7::Composition(m) => advance(m, model, h, steps, start).0,
            }
        }

        /// The tangent map of one step of size `h` from `start`.
        fn tangent<L: Lagrangian<nalgebra::Const<K>>, const K: usize>(
            &self,
            model: &L,
            h: f64,
            start: &State<nalgebra::Const<K>>,
        ) -> DMatrix<f64> {
            fn one<
                M: Method<nalgebra::Const<K>>,
                L: Lagrangian<nalgebra::Const<K>>,
                const K: usize,
            >(
                method: &M,
                model: &L,
                h: f64,
                start: &State<nalgebra::Const<K>>,
            ) -> DMatrix<f64> {
                let mut workspace = method.workspace(model, h).unwrap();
                let (_, tangent, _) = method
                    .tangent_map(model, &mut workspace, 0.0, h, start)
                    .unwrap();
                tangent.matrix()
            }
            match self {
                Method7::Partitioned(m) => one(m, model, h, start),
                Method7::Midpoint(m) => one(m, model, h, start),
                Method7::Composition(m) => one(m, model, h, start),
            }
        }
    }

    /// Hamilton's equations integrated by the classical Runge–Kutta method of order 4 with the
    /// field `field` written by hand: an independent reference (h = 1e-4: error ~ 1e-16).
    fn reference<const K: usize>(
        field: impl Fn(&SVector<f64, K>, &SVector<f64, K>) -> (SVector<f64, K>, SVector<f64, K>),
        start: State<nalgebra::Const<K>>,
        t_end: f64,
    ) -> State<nalgebra::Const<K>> {
        let steps = (t_end / 1e-4).round() as usize;
        let h = t_end / steps as f64;
        let (mut q, mut p) = (start.q, start.y);
        for _ in 0..steps {
            let (a1, b1) = field(&q, &p);
            let (a2, b2) = field(&(q + a1 * (h / 2.0)), &(p + b1 * (h / 2.0)));
            let (a3, b3) = field(&(q + a2 * (h / 2.0)), &(p + b2 * (h / 2.0)));
            let (a4, b4) = field(&(q + a3 * h), &(p + b3 * h));
            q += (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (h / 6.0);
            p += (b1 + b2 * 2.0 + b3 * 2.0 + b4) * (h / 6.0);
        }
        State { q, y: p }
    }

    /// `numbers` in scientific notation.
    fn scientific(numbers: &[f64]) -> String {
        let numbers: Vec<String> = numbers.iter().map(|x| format!("{x:.3e}")).collect();
        numbers.join(" ")
    }

    /// The observed order of each method at T = 1 over steps 1/4 … 1/64 (compositions: from 1/2),
    /// against the reference.
    fn assert_orders<H: Hamiltonian<nalgebra::Const<K>>, const K: usize>(
        model: H,
        start: State<nalgebra::Const<K>>,
        exact: State<nalgebra::Const<K>>,
    ) -> Vec<(&'static str, f64)> {
        let model = Canonical::new(model);
        let mut observed = Vec::new();
        for (name, order, method) in methods() {
            let counts: &[usize] = match order {
                8 => &[4, 6, 8, 10],
                6 => &[4, 6, 8, 12],
                4 => &[8, 16, 32, 64],
                _ => &[16, 32, 64, 128],
            };
            let steps: Vec<f64> = counts.iter().map(|&n| 1.0 / n as f64).collect();
            let errors: Vec<f64> = counts
                .iter()
                .map(|&n| distance(&method.advance(&model, 1.0 / n as f64, n, start), &exact))
                .collect();
            let slope = observed_order(&steps, &errors, 1e-12).unwrap();
            assert!(
                (slope - order as f64).abs() < 0.3,
                "{name}: observed order {slope:.2}, errors {}",
                scientific(&errors)
            );
            eprintln!("{name}: errors {}, order {slope:.2}", scientific(&errors));
            observed.push((name, slope));
        }
        observed
    }

    #[test]
    fn orders_on_a_relativistic_oscillator_and_a_variable_mass() {
        let start = state([1.2], [0.3]);
        let exact = reference(|q, p| (p.map(|p| p / (1.0 + p * p).sqrt()), -q), start, 1.0);
        let separable = assert_orders(Relativistic::<true>, start, exact);
        let general = assert_orders(Relativistic::<false>, start, exact);
        let start = state([0.5, -0.3], [0.4, 0.6]);
        let exact = reference(
            |q, p| {
                let m = 1.0 + q[1] * q[1];
                (
                    SVector::from([p[0] / m, p[1]]),
                    SVector::from([-q[0] - q[0].powi(3), -q[1] + p[0] * p[0] * q[1] / (m * m)]),
                )
            },
            start,
            1.0,
        );
        let variable = assert_orders(VariableMassH, start, exact);
        eprintln!(
            "observed orders: separable {separable:.2?}\ngeneral {general:.2?}\nvariable mass {variable:.2?}"
        );
    }

    /// ‖a − b‖ of `steps` steps of two runs, printed and returned.
    fn gap<const K: usize>(
        what: &str,
        a: &State<nalgebra::Const<K>>,
        b: &State<nalgebra::Const<K>>,
    ) -> f64 {
        let gap = distance(a, b);
        eprintln!("{what}: {gap:.1e}");
        gap
    }

    #[test]
    fn the_hamiltonian_maps_are_the_variational_ones_through_the_legendre_map() {
        let (h, steps) = (0.1, 100);
        // Variable mass: symplectic Euler, its adjoint and the midpoint rule for every L.
        let start = state([0.5, -0.3], [0.4, 0.6]);
        let written = Canonical::new(VariableMassH);
        let pairs: [(&str, State<U2>, State<U2>); 3] = [
            (
                "symplectic-euler",
                advance(&Partitioned::symplectic_euler(), &written, h, steps, start).0,
                advance(
                    &VariationalIntegrator::new(SymplecticEuler),
                    &VariableMass,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
            (
                "symplectic-euler-adjoint",
                advance(
                    &Partitioned::adjoint_symplectic_euler(),
                    &written,
                    h,
                    steps,
                    start,
                )
                .0,
                advance(
                    &VariationalIntegrator::new(AdjointSymplecticEuler),
                    &VariableMass,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
            (
                "midpoint",
                advance(&ImplicitMidpoint::default(), &written, h, steps, start).0,
                advance(
                    &VariationalIntegrator::new(Midpoint),
                    &VariableMass,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
        ];
        for (name, a, b) in &pairs {
            assert!(gap(&format!("{name}-h on H vs {name} on L"), a, b) < 1e-13);
        }
        // Störmer–Verlet: the adjoint variational symplectic Euler of step h/2 after the
        // variational symplectic Euler of step h/2; not the trapezoid for a variable mass.
        let verlet = advance(&Partitioned::stormer_verlet(), &written, h, steps, start).0;
        let mut composed = start;
        for k in 0..steps {
            let mut increment = State::zeros(nalgebra::Const::<2>);
            for (i, rule) in [true, false].into_iter().enumerate() {
                let t = (k as f64 + 0.5 * i as f64) * h;
                if rule {
                    let method = VariationalIntegrator::new(SymplecticEuler);
                    let mut workspace = method.workspace(&VariableMass, h / 2.0).unwrap();
                    method
                        .step(
                            &VariableMass,
                            &mut workspace,
                            t,
                            h / 2.0,
                            &composed,
                            &mut increment,
                        )
                        .unwrap();
                } else {
                    let method = VariationalIntegrator::new(AdjointSymplecticEuler);
                    let mut workspace = method.workspace(&VariableMass, h / 2.0).unwrap();
                    method
                        .step(
                            &VariableMass,
                            &mut workspace,
                            t,
                            h / 2.0,
                            &composed,
                            &mut increment,
                        )
                        .unwrap();
                }
                composed.q += &increment.q;
                composed.y += &increment.y;
            }
        }
        assert!(
            gap(
                "verlet-h on H vs adjoint(h/2) ∘ euler(h/2) on L",
                &verlet,
                &composed
            ) < 1e-13
        );
        let trapezoid = advance(
            &VariationalIntegrator::new(Trapezoid),
            &VariableMass,
            h,
            steps,
            start,
        )
        .0;
        assert!(
            gap(
                "verlet-h vs trapezoid, variable mass (O(h²) apart)",
                &verlet,
                &trapezoid
            ) > 1e-6
        );
        // The pendulum, a constant mass: verlet-h is Störmer–Verlet and the trapezoid.
        let start = state([1.0], [0.5]);
        let verlet = advance(
            &Partitioned::stormer_verlet(),
            &Canonical::new(PendulumH),
            h,
            steps,
            start,
        )
        .0;
        let lagrangian = advance(&StormerVerlet::default(), &Pendulum, h, steps, start).0;
        let trapezoid = advance(
            &VariationalIntegrator::new(Trapezoid),
            &Pendulum,
            h,
            steps,
            start,
        )
        .0;
        assert!(
            gap(
                "verlet-h on H vs verlet on L, pendulum",
                &verlet,
                &lagrangian
            ) < 1e-13
        );
        assert!(
            gap(
                "verlet-h on H vs trapezoid on L, pendulum",
                &verlet,
                &trapezoid
            ) < 1e-13
        );
    }

    #[test]
    fn a_model_written_as_l_runs_the_same_steps_as_written_as_h() {
        let (h, steps) = (0.1, 50);
        let start = state([0.5, -0.3], [0.4, 0.6]);
        for (name, _, method) in methods() {
            let from_h = method.advance(&Canonical::new(VariableMassH), h, steps, start);
            let from_l = method.advance(&VariableMass, h, steps, start);
            assert!(gap(&format!("{name}: L vs H, variable mass"), &from_h, &from_l) < 1e-12);
        }
        let start = state([1.0], [0.5]);
        for (name, _, method) in methods() {
            let from_h = method.advance(&Canonical::new(PendulumH), h, steps, start);
            let from_l = method.advance(&Pendulum, h, steps, start);
            assert!(gap(&format!("{name}: L vs H, pendulum"), &from_h, &from_l) < 1e-13);
        }
    }

    #[test]
    fn a_separable_h_is_explicit_and_takes_the_implicit_paths_steps() {
        let (h, start) = (0.1, state([1.2], [0.3]));
        for method in [
            Partitioned::symplectic_euler(),
            Partitioned::adjoint_symplectic_euler(),
            Partitioned::stormer_verlet(),
        ] {
            let model = Canonical::new(Relativistic::<true>);
            let mut workspace = Method::<U1>::workspace(&method, &model, h).unwrap();
            let (mut current, mut increment) = (start, start);
            for k in 0..100 {
                let report = method
                    .step(
                        &model,
                        &mut workspace,
                        k as f64 * h,
                        h,
                        &current,
                        &mut increment,
                    )
                    .unwrap();
                assert_eq!(report.iterations, 0);
                current.q += increment.q;
                current.y += increment.y;
            }
            let (general, _) = advance(
                &method,
                &Canonical::new(Relativistic::<false>),
                h,
                100,
                start,
            );
            let name = Method::<U1>::info(&method).name;
            assert!(gap(&format!("{name}: explicit vs Newton"), &current, &general) < 1e-13);
        }
        // Bounded energy over 10⁵ steps of verlet-h.
        let model = Canonical::new(Relativistic::<true>);
        let energy = |s: &State<U1>| (1.0 + s.y[0] * s.y[0]).sqrt() + 0.5 * s.q[0] * s.q[0];
        let method = Partitioned::stormer_verlet();
        let mut workspace = Method::<U1>::workspace(&method, &model, h).unwrap();
        let (mut current, mut increment) = (start, start);
        let (e0, mut early, mut late) = (energy(&start), 0.0_f64, 0.0_f64);
        for k in 0..100_000 {
            method
                .step(
                    &model,
                    &mut workspace,
                    k as f64 * h,
                    h,
                    &current,
                    &mut increment,
                )
                .unwrap();
            current.q += increment.q;
            current.y += increment.y;
            let error = (energy(&current) - e0).abs();
            if k < 10_000 {
                early = early.max(error);
            } else if k >= 90_000 {
                late = late.max(error);
            }
        }
        eprintln!(
            "relativistic verlet-h, h = 0.1: max |ΔE| {early:.2e} over the first 1e4 steps, \
             {late:.2e} over the last 1e4 of 1e5"
        );
        // Bounded, no drift: the error of the last steps is the error of the first ones.
        assert!(early < 5e-3 && late < 1.1 * early, "{early:e} {late:e}");
    }

    #[test]
    fn every_step_is_symplectic_on_a_non_separable_h() {
        let start = state([0.5, -0.3], [0.4, 0.6]);
        let model = Canonical::new(VariableMassH);
        let omega = DMatrix::from_fn(4, 4, |i, j| match (i, j) {
            (0, 2) | (1, 3) => 1.0,
            (2, 0) | (3, 1) => -1.0,
            _ => 0.0,
        });
        for (name, _, method) in methods() {
            let phi = method.tangent(&model, 0.3, &start);
            let defect = (phi.transpose() * &omega * &phi - &omega).amax();
            eprintln!("{name}: |ΦᵀΩΦ − Ω| = {defect:.1e}");
            assert!(defect < 1e-12, "{name}: {defect:e}");
        }
        assert_tangent_matches_central_differences(&Partitioned::symplectic_euler(), &model, start);
        assert_tangent_matches_central_differences(
            &Partitioned::adjoint_symplectic_euler(),
            &model,
            start,
        );
        assert_tangent_matches_central_differences(&Partitioned::stormer_verlet(), &model, start);
        assert_tangent_matches_central_differences(&ImplicitMidpoint::default(), &model, start);
        // Forced (and a model written as L): the tangent map is still the step's Jacobian.
        let start = state([0.8], [-0.4]);
        let model = Canonical::new(DampedH { c: 0.3 });
        assert_tangent_matches_central_differences(&Partitioned::stormer_verlet(), &model, start);
        assert_tangent_matches_central_differences(&ImplicitMidpoint::default(), &model, start);
        assert_tangent_matches_central_differences(
            &Partitioned::symplectic_euler(),
            &Damped::<false> { c: 0.3 },
            start,
        );
    }

    #[test]
    fn a_damped_oscillator_in_h_form_is_the_lagrange_dalembert_run() {
        let (c, h, steps) = (0.3, 0.05, 200);
        let start = state([1.0], [0.0]);
        let model = Canonical::new(DampedH { c });
        let lagrangian = Damped::<true> { c };
        let pairs: [(&str, State<U1>, State<U1>); 4] = [
            (
                "symplectic-euler",
                advance(&Partitioned::symplectic_euler(), &model, h, steps, start).0,
                advance(
                    &VariationalIntegrator::new(SymplecticEuler),
                    &lagrangian,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
            (
                "symplectic-euler-adjoint",
                advance(
                    &Partitioned::adjoint_symplectic_euler(),
                    &model,
                    h,
                    steps,
                    start,
                )
                .0,
                advance(
                    &VariationalIntegrator::new(AdjointSymplecticEuler),
                    &lagrangian,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
            (
                "midpoint",
                advance(&ImplicitMidpoint::default(), &model, h, steps, start).0,
                advance(
                    &VariationalIntegrator::new(Midpoint),
                    &lagrangian,
                    h,
                    steps,
                    start,
                )
                .0,
            ),
            (
                "verlet",
                advance(&Partitioned::stormer_verlet(), &model, h, steps, start).0,
                advance(&StormerVerlet::default(), &lagrangian, h, steps, start).0,
            ),
        ];
        for (name, a, b) in &pairs {
            assert!(gap(&format!("{name}-h vs {name}, damped"), a, b) < 1e-13);
        }
        // The energy E = (p² + q²)/2 at T = 10 against the exact solution
        // q = e^{−ct/2} (cos ωt + c/(2ω) sin ωt), ω² = 1 − c²/4: the error falls with the order.
        let t_end = 10.0;
        let omega = (1.0 - c * c / 4.0).sqrt();
        let decay = (-c * t_end / 2.0).exp();
        let (cos, sin) = ((omega * t_end).cos(), (omega * t_end).sin());
        let q = decay * (cos + c / (2.0 * omega) * sin);
        let p = -decay * sin / omega;
        let exact = 0.5 * (q * q + p * p);
        for (name, order, method) in methods() {
            let counts: &[usize] = match order {
                8 => &[10, 15, 20, 30],
                6 => &[20, 30, 40, 60],
                4 => &[50, 100, 200, 400],
                _ => &[200, 400, 800, 1600],
            };
            let errors: Vec<f64> = counts
                .iter()
                .map(|&n| {
                    let end = method.advance(&model, t_end / n as f64, n, start);
                    (0.5 * (end.q[0].powi(2) + end.y[0].powi(2)) - exact).abs()
                })
                .collect();
            let steps: Vec<f64> = counts.iter().map(|&n| t_end / n as f64).collect();
            let slope = observed_order(&steps, &errors, 1e-13).unwrap();
            eprintln!(
                "{name}: energy errors at T = 10 {}, order {slope:.2}",
                scientific(&errors)
            );
            assert!(slope > order as f64 - 0.3, "{name}: {slope} {errors:?}");
        }
    }

    #[test]
    fn a_singular_h_is_a_typed_error() {
        /// H linear in p: ∂²H/∂p² = 0.
        struct Linear;
        impl Hamiltonian<U1> for Linear {
            fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
                p[0] * q[0] + q[0] * q[0]
            }
        }
        let initial = Initial::Momentum {
            q: SVector::from([0.5]),
            p: SVector::from([0.3]),
        };
        for (name, _, method) in methods() {
            let error = match method {
                Method7::Partitioned(m) => Integrator::new(Canonical::new(Linear), m)
                    .run(0.0, initial, 0.1, 1.0, &mut ())
                    .map(|_| ()),
                Method7::Midpoint(m) => Integrator::new(Canonical::new(Linear), m)
                    .run(0.0, initial, 0.1, 1.0, &mut ())
                    .map(|_| ()),
                Method7::Composition(m) => Integrator::new(Canonical::new(Linear), m)
                    .run(0.0, initial, 0.1, 1.0, &mut ())
                    .map(|_| ()),
            }
            .unwrap_err();
            assert!(
                matches!(&error, Error::InvalidParameter { name, reason } if name == "model" && reason.contains("∂²H/∂p² is singular")),
                "{name}: {error}"
            );
        }
    }
}
