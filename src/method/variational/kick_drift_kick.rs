//! The explicit step of a constant-mass Lagrangian under a discrete Lagrangian whose
//! quadrature nodes are the end points of the step: kick, drift, kick.
//!
//! # Discrete equations
//! Let L_d = h [a L(t_k, q_k, v) + b L(t_k + h, q_{k+1}, v)], v = (q_{k+1} − q_k)/h, a + b = 1,
//! with the discrete forces f_d⁻ = a h f_L(t_k, q_k, v), f_d⁺ = b h f_L(t_k + h, q_{k+1}, v)
//! ([`Kicks`]: symplectic Euler a = 1, Störmer–Verlet a = b = ½, the adjoint symplectic Euler
//! b = 1). For L = ½ q̇ᵀMq̇ − V(t, q) with constant M ([`crate::Structure::ConstantMass`]),
//! ∂L/∂q̇ = Mv and ∂L/∂q = F(t, q) = −∂V/∂q do not depend on v, and the discrete
//! Euler–Lagrange equations p_k = −D1 L_d − f_d⁻, p_{k+1} = D2 L_d + f_d⁺ read
//!
//! M v = p_k + a h (F(t_k, q_k) + f_L(t_k, q_k, v)),
//! q_{k+1} = q_k + h v,
//! p_{k+1} = M v + b h (F(t_k + h, q_{k+1}) + f_L(t_k + h, q_{k+1}, v)):
//!
//! a kick of weight a, a drift, a kick of weight b. Without a force no Newton iteration and no
//! Hessian; one gradient ∂L/∂q per step: Störmer–Verlet keeps the force at q_{k+1} and reuses
//! it as the force at q_k of the next step (recognised by position, to within the rounding of
//! the stepping loop's compensated summation), and each symplectic Euler method has a kick on
//! one side only. The momentum increment is h (a F_k + b F_{k+1}), free of cancellation. With
//! a force f_L (which may depend on q̇, like friction) the first kick is implicit in v only:
//! P = r + a h f_L(t_k, q_k, M⁻¹P), r = p_k + a h F_k, solved for P = Mv by Newton's method
//! on N unknowns with the Jacobian I − a h ∂f_L/∂q̇ M⁻¹ (no Hessian of L; one iteration when
//! f_L does not depend on q̇). The steps equal those of the implicit
//! [`crate::VariationalIntegrator`] of the same discrete Lagrangian to round-off (tested).
//!
//! # References
//! Hairer, Lubich, Wanner, *Geometric numerical integration* (2006), eqs. VI.3.1, VI.3.2 and
//! VI.3.6; Marsden & West, *Discrete mechanics and variational integrators*, Acta Numerica
//! (2001), §2.7 and §3.2.

use crate::dimension::Dimension;
use crate::error::StepFailure;
use crate::linalg::lane_extent;
use crate::method::variational::discrete_lagrangian::Kicks;
use crate::method::{State, StepReport};
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::model::derived::cached_mass_inverse;
use crate::model::mass_inverse::MassInverse;
use crate::nonlinear::Newton;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OMatrix, OVector, U1};

/// Buffers of the explicit path, sized once per run.
#[derive(Debug, Clone)]
pub(crate) struct Explicit<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The weights of the two kicks.
    kicks: Kicks,
    /// M⁻¹, from the first step.
    mass_inverse: Option<MassInverse<N>>,
    /// ∂L/∂q at the start of the step; after a step with an end kick, at its end (the next
    /// step's start when it starts there, see `reusable`).
    start_force: OVector<f64, N>,
    end_force: OVector<f64, N>,
    /// Where `start_force` was evaluated after the last step: (t, tolerance on q) and the
    /// position in `reusable_at`; `None` when it is not reusable.
    reusable: Option<(f64, f64)>,
    reusable_at: OVector<f64, N>,
    /// The momentum after the first kick, P = Mv, and v = M⁻¹P.
    kick: OVector<f64, N>,
    velocity: OVector<f64, N>,
    /// The end position q_{k+1}.
    end: OVector<f64, N>,
    /// Newton on P (forced models only; n × n, made on first use).
    newton: Option<Newton>,
    max_iterations: usize,
    /// Newton's unknown P (forced models only).
    unknown: DVector<f64>,
}

impl<N: Dimension> Explicit<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// Buffers for a configuration space of dimension `n`; `forced` sizes Newton's unknown.
    pub(crate) fn new(kicks: Kicks, n: N, forced: bool, max_iterations: usize) -> Self {
        let zero = || OVector::<f64, N>::zeros_generic(n, U1);
        Explicit {
            kicks,
            mass_inverse: None,
            start_force: zero(),
            end_force: zero(),
            reusable: None,
            reusable_at: zero(),
            kick: zero(),
            velocity: zero(),
            end: zero(),
            newton: None,
            max_iterations,
            unknown: DVector::zeros(if forced { n.value() } else { 0 }),
        }
    }

    /// M⁻¹ once a step has computed it (a constant mass matrix, checked by the integrator's
    /// first run).
    pub(crate) fn mass_inverse(&self) -> Option<&MassInverse<N>> {
        self.mass_inverse.as_ref()
    }

    /// One explicit step, in the buffers (nothing allocated per step without a force).
    pub(crate) fn step<L: Lagrangian<N>>(
        &mut self,
        model: &L,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let n = state.dimension();
        let Explicit {
            kicks,
            mass_inverse,
            start_force,
            end_force,
            reusable,
            reusable_at,
            kick,
            velocity,
            end,
            newton,
            max_iterations,
            unknown,
        } = self;
        let mass_inverse = cached_mass_inverse(mass_inverse, model, t, &state.q, &state.y)?;
        let (first, second) = kicks.weights();
        let (first, second) = (first * h, second * h);
        let mut evaluations = 0;
        let mut iterations = 0;
        if first == 0.0 {
            kick.copy_from(&state.y);
            mass_inverse.apply_into(kick, velocity);
        } else {
            // The force at q_k is the last step's end force when the step starts where that
            // one ended (to within the rounding of the stepping loop's compensated summation);
            // the position is checked inside the kick.
            let check = reusable.take().and_then(|(time, tolerance)| {
                (!L::TIME_DEPENDENT
                    || (time - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(time.abs()))
                .then_some(tolerance)
            });
            let reused = check.is_some()
                && kick_at(
                    mass_inverse,
                    first,
                    state,
                    start_force,
                    check.map(|tolerance| (&*reusable_at, tolerance)),
                    kick,
                    velocity,
                );
            if !reused {
                evaluations += 1;
                mass_inverse.apply_into(&state.y, velocity);
                model.force_into(t, &state.q, velocity, start_force);
                // Unchecked, the kick always succeeds.
                kick_at(
                    mass_inverse,
                    first,
                    state,
                    start_force,
                    None,
                    kick,
                    velocity,
                );
            }
            if L::FORCED {
                // P = r + a h f_L(t_k, q_k, M⁻¹P), implicit in P.
                let rest = kick.clone();
                let predicted =
                    &rest + model.external_force(t, &state.q, &mass_inverse.apply(&rest)) * first;
                unknown.copy_from_slice(predicted.as_slice());
                let dense = mass_inverse.to_dense();
                iterations = newton
                    .get_or_insert_with(|| Newton::new(n.value(), *max_iterations))
                    .solve(unknown, |z, matrix, residual| {
                        let momentum =
                            OVector::<f64, N>::from_column_slice_generic(n, U1, z.as_slice());
                        let force =
                            model.external_force_jacobian(t, &state.q, &(&dense * &momentum));
                        let value = &momentum - &rest - force.value * first;
                        residual.copy_from_slice(value.as_slice());
                        let jacobian = OMatrix::<f64, N, N>::identity_generic(n, n)
                            - &force.v * &dense * first;
                        // Both column-major and N × N.
                        matrix.as_mut_slice().copy_from_slice(jacobian.as_slice());
                    })?;
                kick.copy_from_slice(unknown.as_slice());
                *start_force += model.external_force(t, &state.q, &mass_inverse.apply(kick));
                mass_inverse.apply_into(kick, velocity);
            }
        }
        // Drift: q_{k+1} = q_k + h v.
        for (((d, e), q), v) in increment
            .q
            .as_mut_slice()
            .iter_mut()
            .zip(end.as_mut_slice())
            .zip(state.q.as_slice())
            .zip(velocity.as_slice())
        {
            *d = h * v;
            *e = q + *d;
        }
        let end_t = t + h;
        if second == 0.0 {
            // p_{k+1} − p_k = a h (F_k + f_L), a = 1.
            for (d, a) in increment
                .y
                .as_mut_slice()
                .iter_mut()
                .zip(start_force.as_slice())
            {
                *d = first * a;
            }
        } else {
            // The second kick, at the end; `end_force` keeps ∂L/∂q alone: it is the next
            // step's start force.
            evaluations += 1;
            model.force_into(end_t, end, velocity, end_force);
            let y = increment.y.as_mut_slice().iter_mut();
            if first == 0.0 {
                for (d, b) in y.zip(end_force.as_slice()) {
                    *d = second * b;
                }
            } else {
                // a = b: (h/2)(F_k + F_{k+1}).
                for ((d, a), b) in y.zip(start_force.as_slice()).zip(end_force.as_slice()) {
                    *d = first * (a + b);
                }
            }
            if L::FORCED {
                increment
                    .y
                    .axpy(second, &model.external_force(end_t, end, velocity), 1.0);
            }
            // The largest |q| at either end sets the tolerance; a NaN position never matches
            // (its difference is NaN).
            let (extent, _) = lane_extent([state.q.as_slice(), end.as_slice()], |[q, e]| {
                (q.abs().max(e.abs()), true)
            });
            *reusable = Some((end_t, 4.0 * f64::EPSILON * extent));
            std::mem::swap(reusable_at, end);
            std::mem::swap(start_force, end_force);
        }
        Ok(StepReport {
            iterations,
            evaluations,
            // Newton's method factorises at every iteration.
            factorizations: iterations,
            analyses: 0,
        })
    }
}

/// The kick P = p_k + w F_k into `kick` and the velocity M⁻¹P into `velocity`, in one pass
/// for a diagonal M. With `check = Some((at, tolerance))`, `force` is the force at `at`, and
/// the pass also checks that q_k is `at` to within `tolerance` entry by entry; it returns
/// `false` if not (the kick is then not the one of q_k).
#[inline]
fn kick_at<N: Dimension>(
    mass_inverse: &MassInverse<N>,
    weight: f64,
    state: &State<N>,
    force: &OVector<f64, N>,
    check: Option<(&OVector<f64, N>, f64)>,
    kick: &mut OVector<f64, N>,
    velocity: &mut OVector<f64, N>,
) -> bool
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let kicks = kick
        .as_mut_slice()
        .iter_mut()
        .zip(state.y.as_slice())
        .zip(force.as_slice());
    let same = match (mass_inverse, check) {
        (MassInverse::Diagonal(inverse), None) => {
            for (((k, p), f), (v, m)) in
                kicks.zip(velocity.as_mut_slice().iter_mut().zip(inverse.as_slice()))
            {
                *k = p + weight * f;
                *v = *k * m;
            }
            return true;
        }
        (MassInverse::Diagonal(inverse), Some((at, tolerance))) => {
            let mut same = true;
            for ((((k, p), f), (v, m)), (q, a)) in kicks
                .zip(velocity.as_mut_slice().iter_mut().zip(inverse.as_slice()))
                .zip(state.q.as_slice().iter().zip(at.as_slice()))
            {
                *k = p + weight * f;
                *v = *k * m;
                same &= (q - a).abs() <= tolerance;
            }
            return same;
        }
        (_, None) => {
            for ((k, p), f) in kicks {
                *k = p + weight * f;
            }
            true
        }
        (_, Some((at, tolerance))) => {
            let mut same = true;
            for (((k, p), f), (q, a)) in kicks.zip(state.q.as_slice().iter().zip(at.as_slice())) {
                *k = p + weight * f;
                same &= (q - a).abs() <= tolerance;
            }
            same
        }
    };
    if same {
        mass_inverse.apply_into(kick, velocity);
    }
    same
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::Method;
    use crate::method::variational::discrete_lagrangian::{
        AdjointSymplecticEuler, DiscreteLagrangian, SymplecticEuler, Trapezoid,
    };
    use crate::model::Structure;
    use crate::scalar::Scalar;
    use crate::test_models::{AsDyn, Damped, HenonHeiles, distance, state};
    use crate::{StormerVerlet, VariationalIntegrator};
    use nalgebra::{SVector, U2};

    /// A driven, damped oscillator with a constant mass: L = ½q̇² − ½q² + q sin t,
    /// f_L = −0.3 q̇ − 0.1 q³ (time-dependent, forced, the force nonlinear in q).
    struct Driven;
    impl Lagrangian<U1> for Driven {
        const FORCED: bool = true;
        const STRUCTURE: Structure = Structure::ConstantMass;
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
            (v[0] * v[0] - q[0] * q[0]) * 0.5 + q[0] * t.sin()
        }
        fn external_force<D: Scalar>(
            &self,
            _t: D,
            q: &SVector<D, 1>,
            v: &SVector<D, 1>,
        ) -> SVector<D, 1> {
            SVector::from([v[0] * (-0.3) - q[0].powi(3) * 0.1])
        }
    }

    /// `steps` steps of the explicit path of `rule` and of Newton's method on the same
    /// discrete Euler–Lagrange equations end within 1e-13 of each other; the explicit steps
    /// take no Newton iteration without a force and `evaluations` gradients each after the
    /// first step.
    fn assert_explicit_equals_implicit<Ld, L, N>(
        rule: Ld,
        model: &L,
        start: State<N>,
        evaluations: usize,
    ) where
        Ld: DiscreteLagrangian + Clone,
        L: Lagrangian<N>,
        N: Dimension,
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let h = 0.05;
        let method = VariationalIntegrator::new(rule.clone());
        let kicks = rule.kicks().or(Some(Kicks::Split));
        let mut explicit = method.workspace_with(model, h, kicks).unwrap();
        let mut implicit = method.workspace_with(model, h, None).unwrap();
        let (mut a, mut b) = (start.clone(), start);
        let mut increment = a.clone();
        for k in 0..200 {
            let t = k as f64 * h;
            let report = method
                .step(model, &mut explicit, t, h, &a, &mut increment)
                .unwrap();
            if !L::FORCED {
                assert_eq!(report.iterations, 0);
            }
            if k > 0 {
                assert_eq!(report.evaluations, evaluations, "step {k}");
            }
            a.q += &increment.q;
            a.y += &increment.y;
            method
                .step(model, &mut implicit, t, h, &b, &mut increment)
                .unwrap();
            b.q += &increment.q;
            b.y += &increment.y;
        }
        let gap = distance(&a, &b);
        assert!(gap < 1e-13, "{}: {gap:e}", rule.info().name);
        // The observers' velocity comes from M⁻¹ of the explicit path, without a solve.
        let mut v = a.q.clone();
        assert!(
            method
                .velocity_into(model, &explicit, 0.0, &a.q, &a.y, &mut v)
                .unwrap()
        );
    }

    #[test]
    fn the_explicit_steps_are_the_implicit_ones() {
        let start = state([0.3, -0.2], [0.1, 0.25]);
        let model = HenonHeiles::<true>;
        assert_explicit_equals_implicit(SymplecticEuler, &model, start, 1);
        assert_explicit_equals_implicit(AdjointSymplecticEuler, &model, start, 1);
        // Störmer–Verlet's kicks on the trapezoid: the end force is the next start force.
        assert_explicit_equals_implicit(Trapezoid, &model, start, 1);
        let dynamic = AsDyn::new(HenonHeiles::<true>);
        let start_dyn = State {
            q: nalgebra::DVector::from_column_slice(start.q.as_slice()),
            y: nalgebra::DVector::from_column_slice(start.y.as_slice()),
        };
        assert_explicit_equals_implicit(SymplecticEuler, &dynamic, start_dyn.clone(), 1);
        assert_explicit_equals_implicit(AdjointSymplecticEuler, &dynamic, start_dyn, 1);
        // Forced: the kick at the start is a Newton solve on N unknowns. Time-dependent: each
        // force at its own time (the trapezoid's end force is still the next start force).
        let start = state([0.8], [-0.4]);
        let damped = Damped::<true> { c: 0.3 };
        assert_explicit_equals_implicit(SymplecticEuler, &damped, start, 1);
        assert_explicit_equals_implicit(AdjointSymplecticEuler, &damped, start, 1);
        assert_explicit_equals_implicit(SymplecticEuler, &Driven, start, 1);
        assert_explicit_equals_implicit(AdjointSymplecticEuler, &Driven, start, 1);
        assert_explicit_equals_implicit(Trapezoid, &Driven, start, 1);
    }

    /// The registry's methods take the explicit path: Störmer–Verlet and symplectic Euler on
    /// a constant mass solve nothing.
    #[test]
    fn symplectic_euler_is_explicit_for_a_constant_mass() {
        let model = HenonHeiles::<true>;
        let start = state([0.3, -0.2], [0.1, 0.25]);
        let mut increment = start;
        let euler = VariationalIntegrator::new(SymplecticEuler);
        let mut workspace = Method::<U2>::workspace(&euler, &model, 0.1).unwrap();
        let report = euler
            .step(&model, &mut workspace, 0.0, 0.1, &start, &mut increment)
            .unwrap();
        assert_eq!((report.iterations, report.evaluations), (0, 1));
        // p₁ = p₀ + h F(q₀), q₁ = q₀ + h M⁻¹p₁ (HLW eq. VI.3.1).
        let force = SVector::from([-0.3 - 2.0 * 0.3 * -0.2, 0.2 - 0.09 + 0.04]);
        let p1 = start.y + force * 0.1;
        let mass = nalgebra::Matrix2::new(2.0, 1.0, 1.0, 3.0);
        let q1 = start.q + mass.try_inverse().unwrap() * p1 * 0.1;
        assert!((start.y + increment.y - p1).amax() < 1e-15);
        assert!((start.q + increment.q - q1).amax() < 1e-15);
        let verlet = StormerVerlet::default();
        let mut workspace = Method::<U2>::workspace(&verlet, &model, 0.1).unwrap();
        let report = verlet
            .step(&model, &mut workspace, 0.0, 0.1, &start, &mut increment)
            .unwrap();
        assert_eq!((report.iterations, report.evaluations), (0, 2));
    }
}
