//! Discrete Lagrangians L_d(q_k, q_{k+1}, h) ≈ ∫ L dt and their discrete forces.
//!
//! A variational integrator is defined by one function of two configurations: the discrete
//! Lagrangian L_d(q_k, q_{k+1}), an approximation of the action over one step (Porcù–Penati,
//! slides "Discrete mechanics" and "Variational integrators"; Li, Wu, Leok 2018, §2). The
//! implicit discrete Euler–Lagrange equations (Li, Wu, Leok 2018, eq. 5)
//!
//! p_k = −D1 L_d(q_k, q_{k+1}) − f_d⁻,   p_{k+1} = D2 L_d(q_k, q_{k+1}) + f_d⁺
//!
//! define the step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}); they are solved once, for every L_d, by
//! [`crate::VariationalIntegrator`]. The discrete forces f_d^± (Marsden & West 2001, §3.2:
//! the discrete Lagrange–d'Alembert principle δΣ L_d + Σ (f_d⁻·δq_k + f_d⁺·δq_{k+1}) = 0)
//! approximate ∫ f_L·δq dt with the same quadrature as the action, so an unforced model
//! (the default, [`crate::Lagrangian::FORCED`] `= false`) gives f_d^± = 0.
//!
//! The classic discrete Lagrangians of the slides all evaluate L on the straight segment
//! q(τ) = (1 − τ) q_k + τ q_{k+1}, τ ∈ [0, 1], with the constant velocity v = (q_{k+1} − q_k)/h
//! and a quadrature rule Σ_i b_i g(τ_i) on [0, 1]:
//!
//! L_d = h Σ_i b_i L(t_k + τ_i h, q(τ_i), v),
//! f_d⁻ = h Σ_i b_i (1 − τ_i) f_L(t_k + τ_i h, q(τ_i), v),
//! f_d⁺ = h Σ_i b_i τ_i f_L(t_k + τ_i h, q(τ_i), v)
//!
//! (the virtual displacement of the segment is δq(τ) = (1 − τ) δq_k + τ δq_{k+1}). This is the
//! generalized Galerkin construction of Leok's thesis, ch. 5 (a function space — here linear
//! polynomials — plus a quadrature rule), of which the spectral variational integrator
//! ([`crate::Svi`]) is the high-degree member. [`segment_action`] and [`segment_forces`]
//! implement it for any rule; each method below is a rule:
//!
//! | type | L_d | rule (τ_i, b_i) | order | symmetric |
//! | --- | --- | --- | --- | --- |
//! | [`SymplecticEuler`] | h L(q_k, v) | (0, 1) | 1 | no |
//! | [`AdjointSymplecticEuler`] | h L(q_{k+1}, v) | (1, 1) | 1 | no |
//! | [`Midpoint`] | h L((q_k + q_{k+1})/2, v) | (½, 1) | 2 | yes |
//! | [`Trapezoid`] | ½h L(q_k, v) + ½h L(q_{k+1}, v) | (0, ½), (1, ½) | 2 | yes |
//!
//! All are symplectic without forces (a discrete Lagrangian is a type-I generating function).

use crate::dimension::Dimension;
use crate::model::Lagrangian;
use crate::scalar::Scalar;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

/// Static facts about a discrete Lagrangian and the integrator it generates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiscreteLagrangianInfo {
    /// Short name (as used by the CLI), e.g. `"midpoint"`.
    pub name: &'static str,
    /// Order of the discrete Lagrangian, which is the order of its discrete Hamiltonian map
    /// (variational error analysis, Marsden & West 2001, Thm. 2.3.1).
    pub order: usize,
    /// Whether L_d(q_k, q_{k+1}, h) = −L_d(q_{k+1}, q_k, −h): then the step is symmetric.
    pub symmetric: bool,
    /// Points at which one evaluation of L_d evaluates L (for the work statistics).
    pub points: usize,
}

/// The discrete forces (f_d⁻, f_d⁺) of one step: the virtual work ∫ f_L·δq dt over the step
/// is approximated by f_d⁻·δq_k + f_d⁺·δq_{k+1}.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscreteForces<D: Scalar, N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// f_d⁻, conjugate to δq_k.
    pub minus: OVector<D, N>,
    /// f_d⁺, conjugate to δq_{k+1}.
    pub plus: OVector<D, N>,
}

impl<D: Scalar, N: Dimension> Copy for DiscreteForces<D, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
    OVector<D, N>: Copy,
{
}

/// Where the two kicks of an explicit step fall: the weights (a, b), a + b = 1, of
/// L_d = h [a L(t_k, q_k, v) + b L(t_k + h, q_{k+1}, v)], whose discrete Euler–Lagrange
/// equations a constant-mass Lagrangian solves explicitly as a kick of weight a, a drift and a
/// kick of weight b ([`crate::method::variational::kick_drift_kick`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kicks {
    /// a = 1, b = 0: symplectic Euler (kick, then drift).
    Start,
    /// a = b = ½: Störmer–Verlet (kick, drift, kick).
    Split,
    /// a = 0, b = 1: the adjoint symplectic Euler (drift, then kick).
    End,
}

impl Kicks {
    /// The weights (a, b).
    pub fn weights(self) -> (f64, f64) {
        match self {
            Kicks::Start => (1.0, 0.0),
            Kicks::Split => (0.5, 0.5),
            Kicks::End => (0.0, 1.0),
        }
    }
}

/// A discrete Lagrangian L_d(q_k, q_{k+1}, h) ≈ ∫_{t_k}^{t_k+h} L dt and its discrete forces.
///
/// Both functions are generic over the scalar so that [`crate::VariationalIntegrator`] can
/// differentiate them with dual numbers (D1 L_d, D2 L_d, the Newton matrix D12 L_d and the
/// Hessians of the tangent map). `t` and `h` are scalars of the same type, so derivatives in
/// h (for example the discrete energy −∂L_d/∂h) are available too.
pub trait DiscreteLagrangian {
    /// Name, order, symmetry and cost.
    fn info(&self) -> DiscreteLagrangianInfo;

    /// The quadrature rule on the straight segment, for a discrete Lagrangian of the segment
    /// construction ([`segment_action`]): the methods then solve its discrete Euler–Lagrange
    /// equations as the stage equations of a degree-1 Galerkin integrator (sparse Newton for
    /// a sum of local terms). `None` (the default) for any other discrete Lagrangian.
    fn segment(&self) -> Option<&'static [SegmentNode]> {
        None
    }

    /// The kicks of the explicit step a [`crate::VariationalIntegrator`] of this discrete
    /// Lagrangian takes on a constant-mass Lagrangian ([`crate::Structure::ConstantMass`]);
    /// `None` (the default) for a discrete Lagrangian it always solves by Newton's method.
    fn kicks(&self) -> Option<Kicks> {
        None
    }

    /// L_d(q0, q1, h) for the step from `t` to `t + h`.
    fn discrete_lagrangian<L: Lagrangian<N>, D: Scalar, N: Dimension>(
        &self,
        model: &L,
        t: D,
        h: D,
        q0: &OVector<D, N>,
        q1: &OVector<D, N>,
    ) -> D
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>;

    /// The discrete forces (f_d⁻, f_d⁺) of the model's external force
    /// ([`Lagrangian::external_force`]) over the step, by the same quadrature as the action.
    /// Only called for [`Lagrangian::FORCED`] models.
    fn discrete_forces<L: Lagrangian<N>, D: Scalar, N: Dimension>(
        &self,
        model: &L,
        t: D,
        h: D,
        q0: &OVector<D, N>,
        q1: &OVector<D, N>,
    ) -> DiscreteForces<D, N>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>;
}

/// A quadrature node on the segment from q_k to q_{k+1}: position τ ∈ [0, 1] and weight b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentNode {
    /// Position τ on the segment (0: q_k at t_k, 1: q_{k+1} at t_k + h).
    pub position: f64,
    /// Quadrature weight b on [0, 1] (the weights of a rule sum to 1).
    pub weight: f64,
}

/// The point (1 − τ) q0 + τ q1, exact at the end points and at the midpoint: `q0` or `q1`
/// itself at an end point (no copy), else the interpolated point, kept in `storage`.
#[inline(always)]
fn segment_point<'a, D: Scalar, N: Dimension>(
    position: f64,
    q0: &'a OVector<D, N>,
    q1: &'a OVector<D, N>,
    storage: &'a mut Option<OVector<D, N>>,
) -> &'a OVector<D, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    if position == 0.0 {
        q0
    } else if position == 1.0 {
        q1
    } else {
        storage.insert(q0.zip_map(q1, |a, b| a * (1.0 - position) + b * position))
    }
}

/// The velocity (q1 − q0)/h of the segment.
#[inline(always)]
fn segment_velocity<D: Scalar, N: Dimension>(
    h: D,
    q0: &OVector<D, N>,
    q1: &OVector<D, N>,
) -> OVector<D, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let rate = h.recip();
    q1.zip_map(q0, |b, a| (b - a) * rate)
}

/// The action h Σ_i b_i L(t + τ_i h, (1 − τ_i) q0 + τ_i q1, (q1 − q0)/h) of the straight
/// segment from q0 to q1 under the quadrature rule `nodes`.
#[inline(always)]
pub fn segment_action<L: Lagrangian<N>, D: Scalar, N: Dimension>(
    model: &L,
    nodes: &[SegmentNode],
    t: D,
    h: D,
    q0: &OVector<D, N>,
    q1: &OVector<D, N>,
) -> D
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let v = segment_velocity(h, q0, q1);
    let mut action = D::from(0.0);
    for node in nodes {
        let mut storage = None;
        let q = segment_point(node.position, q0, q1, &mut storage);
        let time = t + h * node.position;
        action += model.lagrangian(time, q, &v) * node.weight;
    }
    action * h
}

/// The discrete forces of the straight segment under the quadrature rule `nodes`:
/// f_d⁻ = h Σ_i b_i (1 − τ_i) f_L(t_i, q(τ_i), v), f_d⁺ = h Σ_i b_i τ_i f_L(t_i, q(τ_i), v).
#[inline(always)]
pub fn segment_forces<L: Lagrangian<N>, D: Scalar, N: Dimension>(
    model: &L,
    nodes: &[SegmentNode],
    t: D,
    h: D,
    q0: &OVector<D, N>,
    q1: &OVector<D, N>,
) -> DiscreteForces<D, N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let v = segment_velocity(h, q0, q1);
    let (n, _) = q0.shape_generic();
    let mut minus = OVector::<D, N>::zeros_generic(n, U1);
    let mut plus = OVector::<D, N>::zeros_generic(n, U1);
    for node in nodes {
        let mut storage = None;
        let q = segment_point(node.position, q0, q1, &mut storage);
        let time = t + h * node.position;
        let force = model.external_force(time, q, &v);
        let (left, right) = (
            node.weight * (1.0 - node.position),
            node.weight * node.position,
        );
        if left != 0.0 {
            for (target, f) in minus.as_mut_slice().iter_mut().zip(force.as_slice()) {
                *target += *f * h * left;
            }
        }
        if right != 0.0 {
            for (target, f) in plus.as_mut_slice().iter_mut().zip(force.as_slice()) {
                *target += *f * h * right;
            }
        }
    }
    DiscreteForces { minus, plus }
}

/// Implements [`DiscreteLagrangian`] for a unit struct by a segment quadrature rule.
macro_rules! segment_rule {
    ($type:ty, $name:literal, $order:literal, $symmetric:literal, $kicks:expr, $nodes:expr) => {
        impl $type {
            /// The quadrature rule on the segment [q_k, q_{k+1}].
            pub const NODES: &'static [SegmentNode] = $nodes;
        }

        impl DiscreteLagrangian for $type {
            fn info(&self) -> DiscreteLagrangianInfo {
                DiscreteLagrangianInfo {
                    name: $name,
                    order: $order,
                    symmetric: $symmetric,
                    points: Self::NODES.len(),
                }
            }

            fn segment(&self) -> Option<&'static [SegmentNode]> {
                Some(Self::NODES)
            }

            fn kicks(&self) -> Option<Kicks> {
                $kicks
            }

            #[inline(always)]
            fn discrete_lagrangian<L: Lagrangian<N>, D: Scalar, N: Dimension>(
                &self,
                model: &L,
                t: D,
                h: D,
                q0: &OVector<D, N>,
                q1: &OVector<D, N>,
            ) -> D
            where
                DefaultAllocator: Allocator<N> + Allocator<N, N>,
            {
                segment_action(model, Self::NODES, t, h, q0, q1)
            }

            #[inline(always)]
            fn discrete_forces<L: Lagrangian<N>, D: Scalar, N: Dimension>(
                &self,
                model: &L,
                t: D,
                h: D,
                q0: &OVector<D, N>,
                q1: &OVector<D, N>,
            ) -> DiscreteForces<D, N>
            where
                DefaultAllocator: Allocator<N> + Allocator<N, N>,
            {
                segment_forces(model, Self::NODES, t, h, q0, q1)
            }
        }
    };
}

/// Symplectic Euler: the rectangle rule at the start of the step.
///
/// # Discrete equations
/// L_d = h L(t_k, q_k, v), v = (q_{k+1} − q_k)/h; f_d⁻ = h f_L(t_k, q_k, v), f_d⁺ = 0:
///
/// p_k = ∂L/∂q̇(q_k, v) − h ∂L/∂q(q_k, v) − h f_L(t_k, q_k, v),   p_{k+1} = ∂L/∂q̇(q_k, v).
///
/// For L = ½ q̇ᵀMq̇ − V(q) this is p_{k+1} = p_k − h ∇V(q_k), q_{k+1} = q_k + h M⁻¹p_{k+1}
/// (Hairer, Lubich, Wanner, *Geometric Numerical Integration*, eq. VI.3.1), which
/// [`crate::VariationalIntegrator`] runs explicitly ([`Kicks::Start`]).
///
/// # Properties
/// Order 1; not symmetric (its adjoint is [`AdjointSymplecticEuler`]); symplectic.
///
/// # References
/// Porcù & Penati (OctConf 2013), "Variational integrators" 1); Marsden & West (2001), §2.7;
/// Hairer, Lubich, Wanner (2006), §VI.6.2.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SymplecticEuler;

segment_rule!(
    SymplecticEuler,
    "symplectic-euler",
    1,
    false,
    Some(Kicks::Start),
    &[SegmentNode {
        position: 0.0,
        weight: 1.0
    }]
);

/// The adjoint symplectic Euler method: the rectangle rule at the end of the step.
///
/// # Discrete equations
/// L_d = h L(t_k + h, q_{k+1}, v), v = (q_{k+1} − q_k)/h; f_d⁻ = 0,
/// f_d⁺ = h f_L(t_k + h, q_{k+1}, v):
///
/// p_k = ∂L/∂q̇(q_{k+1}, v),   p_{k+1} = ∂L/∂q̇(q_{k+1}, v) + h ∂L/∂q(q_{k+1}, v) + h f_L.
///
/// For L = ½ q̇ᵀMq̇ − V(q) this is q_{k+1} = q_k + h M⁻¹p_k, p_{k+1} = p_k − h ∇V(q_{k+1})
/// (Hairer, Lubich, Wanner, eq. VI.3.2), which [`crate::VariationalIntegrator`] runs
/// explicitly ([`Kicks::End`]).
///
/// # Properties
/// Order 1; not symmetric (the adjoint of [`SymplecticEuler`]); symplectic.
///
/// # References
/// Marsden & West (2001), §2.7; Hairer, Lubich, Wanner (2006), §VI.3 and §VI.6.2.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AdjointSymplecticEuler;

segment_rule!(
    AdjointSymplecticEuler,
    "symplectic-euler-adjoint",
    1,
    false,
    Some(Kicks::End),
    &[SegmentNode {
        position: 1.0,
        weight: 1.0
    }]
);

/// The midpoint rule.
///
/// # Discrete equations
/// L_d = h L(t_k + h/2, q_{k+½}, v), q_{k+½} = (q_k + q_{k+1})/2, v = (q_{k+1} − q_k)/h;
/// f_d⁻ = f_d⁺ = (h/2) f_L(t_k + h/2, q_{k+½}, v):
///
/// p_k = ∂L/∂q̇ − (h/2)(∂L/∂q + f_L),   p_{k+1} = ∂L/∂q̇ + (h/2)(∂L/∂q + f_L),
///
/// all at (t_k + h/2, q_{k+½}, v). For L = ½ q̇ᵀMq̇ − V(q) this is the implicit midpoint rule.
///
/// # Properties
/// Order 2; symmetric; symplectic.
///
/// # References
/// Porcù & Penati (OctConf 2013), "Variational integrators" 2); Marsden & West (2001),
/// §2.7 (the α = ½ member of the L_d^α family).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Midpoint;

segment_rule!(
    Midpoint,
    "midpoint",
    2,
    true,
    None,
    &[SegmentNode {
        position: 0.5,
        weight: 1.0
    }]
);

/// The trapezoidal rule.
///
/// # Discrete equations
/// L_d = ½h L(t_k, q_k, v) + ½h L(t_k + h, q_{k+1}, v), v = (q_{k+1} − q_k)/h;
/// f_d⁻ = (h/2) f_L(t_k, q_k, v), f_d⁺ = (h/2) f_L(t_k + h, q_{k+1}, v):
///
/// p_k = ½[∂L/∂q̇(q_k, v) + ∂L/∂q̇(q_{k+1}, v)] − (h/2)(∂L/∂q(q_k, v) + f_L(t_k, q_k, v)),
/// p_{k+1} = ½[∂L/∂q̇(q_k, v) + ∂L/∂q̇(q_{k+1}, v)] + (h/2)(∂L/∂q(q_{k+1}, v) + f_L(t_k + h, q_{k+1}, v)).
///
/// This is the slides' "Störmer–Verlet" discrete Lagrangian, implicit in q_{k+1} for a general
/// L. It holds one velocity v over the step, so for a mass matrix that depends on q it is not
/// the Lobatto IIIA–IIIB pair (the generalized Störmer–Verlet method of HLW eq. VI.3.4, whose
/// two end velocities share one momentum: [`crate::method::hamiltonian::Partitioned`]), an
/// O(h³) difference per step (tested there); for L = ½ q̇ᵀMq̇ − V(t, q) with constant M both
/// are the explicit kick–drift–kick
/// Störmer–Verlet method, which [`crate::StormerVerlet`] runs without any Newton iteration.
/// [`crate::VariationalIntegrator`]`<Trapezoid>` always takes the implicit path.
///
/// # Properties
/// Order 2; symmetric; symplectic.
///
/// # References
/// Porcù & Penati (OctConf 2013), "Variational integrators" 3) and the Störmer–Verlet error
/// table; Marsden & West (2001), §2.7 (L_d^sym); Hairer, Lubich, Wanner (2006), §VI.6.2,
/// eq. (6.9).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Trapezoid;

segment_rule!(
    Trapezoid,
    "trapezoid",
    2,
    true,
    None,
    &[
        SegmentNode {
            position: 0.0,
            weight: 0.5
        },
        SegmentNode {
            position: 1.0,
            weight: 0.5
        }
    ]
);

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{SVector, U1};

    /// L = q̇²/2 − q²/2 with friction f = −c q̇ + a t.
    struct Damped;
    impl Lagrangian<U1> for Damped {
        const FORCED: bool = true;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            (v[0] * v[0] - q[0] * q[0]) * 0.5
        }
        fn external_force<D: Scalar>(
            &self,
            t: D,
            _q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            SVector::from([v[0] * (-0.3) + t * 0.1])
        }
    }

    #[test]
    fn the_rules_reproduce_the_slides_formulas() {
        let (t, h) = (0.2, 0.1);
        let (q0, q1) = (SVector::from([0.7]), SVector::from([0.8]));
        let v: f64 = (0.8 - 0.7) / h;
        let l = |q: f64| 0.5 * (v * v - q * q);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-14;
        let euler = SymplecticEuler.discrete_lagrangian(&Damped, t, h, &q0, &q1);
        assert!(close(euler, h * l(0.7)));
        let adjoint = AdjointSymplecticEuler.discrete_lagrangian(&Damped, t, h, &q0, &q1);
        assert!(close(adjoint, h * l(0.8)));
        let midpoint = Midpoint.discrete_lagrangian(&Damped, t, h, &q0, &q1);
        assert!(close(midpoint, h * l(0.75)));
        let trapezoid = Trapezoid.discrete_lagrangian(&Damped, t, h, &q0, &q1);
        assert!(close(trapezoid, 0.5 * h * (l(0.7) + l(0.8))));

        let f = |time: f64| -0.3 * v + 0.1 * time;
        let forces = Trapezoid.discrete_forces(&Damped, t, h, &q0, &q1);
        assert!(close(forces.minus[0], 0.5 * h * f(t)));
        assert!(close(forces.plus[0], 0.5 * h * f(t + h)));
        let forces = Midpoint.discrete_forces(&Damped, t, h, &q0, &q1);
        assert!(close(forces.minus[0], 0.5 * h * f(t + 0.5 * h)));
        assert!(close(forces.plus[0], forces.minus[0]));
        let forces = SymplecticEuler.discrete_forces(&Damped, t, h, &q0, &q1);
        assert!(close(forces.minus[0], h * f(t)) && forces.plus[0] == 0.0);
        let forces = AdjointSymplecticEuler.discrete_forces(&Damped, t, h, &q0, &q1);
        assert!(close(forces.plus[0], h * f(t + h)) && forces.minus[0] == 0.0);
    }

    #[test]
    fn rules_integrate_constants_and_declare_their_cost() {
        for (info, nodes) in [
            (SymplecticEuler.info(), SymplecticEuler::NODES),
            (AdjointSymplecticEuler.info(), AdjointSymplecticEuler::NODES),
            (Midpoint.info(), Midpoint::NODES),
            (Trapezoid.info(), Trapezoid::NODES),
        ] {
            let total: f64 = nodes.iter().map(|n| n.weight).sum();
            assert_eq!(total, 1.0, "{}", info.name);
            assert_eq!(info.points, nodes.len());
            // A symmetric rule has symmetric nodes and weights.
            let mirrored = nodes.iter().all(|n| {
                nodes
                    .iter()
                    .any(|m| m.position == 1.0 - n.position && m.weight == n.weight)
            });
            assert_eq!(mirrored, info.symmetric, "{}", info.name);
        }
    }
}
