//! The mollified impulse method (MOLLY), the trigonometric peer of `svi bench` on the spring
//! pendulum ([`SpringPendulum`]): long steps over the fast spring, written from its published
//! formula for this model's splitting.
//!
//! # Splitting
//!
//! With p_a = m ȧ and p_θ = m (l + a)² θ̇ the Hamiltonian of the spring pendulum is
//! H = p_a²/(2m) + p_θ²/(2m (l + a)²) − m g (l + a) cos θ + k a²/2. Split about the static
//! extension a* = m g/k ([`SpringPendulum::static_extension`]), using
//! k a²/2 = k (a − a*)²/2 + m g a − k a*²/2:
//!
//! - H_fast(a, p_a) = p_a²/(2m) + k (a − a*)²/2, a harmonic oscillator of frequency
//!   ω = √(k/m) about a*, whose flow over t is the exact rotation
//!   a − a* ← cos(ωt)(a − a*) + sin(ωt) p_a/(mω), p_a ← −mω sin(ωt)(a − a*) + cos(ωt) p_a;
//! - H_slow(a, θ, p_θ) = T(a, p_θ) + V(a, θ) with T = p_θ²/(2m (l + a)²) and
//!   V = −m g (l + a) cos θ + m g a (the constant dropped).
//!
//! # The method
//!
//! The impulse method (Verlet-I / r-RESPA with the exact fast flow: Grubmüller et al. 1991,
//! Tuckerman et al. 1992; Hairer, Lubich & Wanner, §XIII.1.3) is
//! Φ_h = φ^slow_{h/2} ∘ φ^fast_h ∘ φ^slow_{h/2}. Mollifying it (García-Archilla, Sanz-Serna &
//! Skeel 1999; HLW §XIII.1.4) replaces H_slow(a, θ, p_θ) by H_slow(A(a), θ, p_θ) with
//!
//! A(a) = a* + φ(hω)(a − a*),  φ(ξ) = sinc ξ = sin ξ/ξ,
//!
//! φ(hω)(a − a*) being the average of the fast flow's displacement a − a* over [−h, h]; every
//! slow force on a gains the chain factor A′ = φ(hω). The mollified slow flow is not known in
//! closed form (with a frozen it is a pendulum), so each of its half steps is the symmetric
//! (Strang) composition φ^T_{h/4} ∘ φ^V_{h/2} ∘ φ^T_{h/4} of two exact flows, with
//! L = l + A(a):
//!
//! - φ^T_t: a, p_θ fixed; θ += p_θ t/(m L²), p_a += φ(hω) p_θ² t/(m L³);
//! - φ^V_t: a, θ fixed; p_a += φ(hω) m g (cos θ − 1) t, p_θ −= m g L sin θ t.
//!
//! In the two-step form of HLW §XIII.2.2 (for a fast part about a fixed centre) this is the
//! trigonometric method with the filters φ = sinc and ψ = sinc·φ.
//!
//! # Properties
//!
//! Order 2; symmetric (the composition is palindromic, and φ(hω) is even in h, so the step
//! with −h is the inverse); symplectic (a composition of exact flows of the Hamiltonians
//! H_fast, T∘A and V∘A). The energy of the spring pendulum is not conserved, but its error
//! stays bounded with no drift at steps of many spring periods: max |E − E₀| = 0.076 (of
//! |E₀| = 8.6) over T = 1000 at h = 0.31, five spring periods per step, the same in the first
//! and last tenth of the run. Per step the slow force is evaluated twice (one gravity kick
//! per half step; the kinetic sub-flows are rational).
//!
//! # The centre of the fast oscillation
//!
//! The spring oscillates about its loaded extension (≈ a* cos θ plus the centrifugal
//! stretch), not about 0. Split about 0 (H_fast = p_a²/(2m) + k a²/2, A(a) = φ(hω) a) the
//! mollifier shrinks the static stretch with the oscillation: for hω ≫ 1 the slow forces see
//! a spring of length ≈ l instead of l + a*, a relative error of 10⁻³ in the pendulum's
//! length. Measured on the default scene (θ₀ = 0.5, T = 10; θ error against a resolved run)
//! with a prototype of both splittings: 2.1·10⁻³ about 0 against 5.8·10⁻⁴ about a* at
//! h = 0.01, 4.0·10⁻³ against 1.2·10⁻³ at h = 0.0156, 8.6·10⁻³ against 4.4·10⁻³ at
//! h = 0.0625. Hence the split about a*, which keeps the static stretch exact (at rest
//! hanging down the slow force on a vanishes for any φ). What stays is the method's limit on
//! this problem: the slowly varying part of the stretch (a* (cos θ − 1) and the centrifugal
//! term, about 2·10⁻⁴ here) is still scaled by φ(hω) — the mollifier cannot tell it from
//! the fast oscillation — and at small hω the mollified method is about 3× less accurate than
//! the plain impulse method (5.8·10⁻⁴ against 2.0·10⁻⁴ at h = 0.01), which is in turn
//! unstable near the resonances hω ∈ πℤ (energy error 2.5 at h = 0.0625, against 6·10⁻³
//! mollified). At large steps the error is that of a second-order method on the slow
//! pendulum (4·10⁻² at h = 0.25). Equilibrium mollifiers (Izaguirre, Reich & Skeel 1999),
//! which average about a constrained equilibrium, would go further; they are not
//! implemented.
//!
//! # References
//!
//! - B. García-Archilla, J. M. Sanz-Serna, R. D. Skeel, *Long-time-step methods for
//!   oscillatory differential equations*, SIAM J. Sci. Comput. 20 (1999) 930–963.
//! - E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer
//!   (2006), §XIII.1.3 (impulse method), §XIII.1.4 (mollified impulse method), §XIII.2.2.
//! - H. Grubmüller, H. Heller, A. Windemuth, K. Schulten, Mol. Simul. 6 (1991) 121–142;
//!   M. Tuckerman, B. J. Berne, G. J. Martyna, J. Chem. Phys. 97 (1992) 1990–2001.
//! - J. A. Izaguirre, S. Reich, R. D. Skeel, *Longer time steps for molecular dynamics*,
//!   J. Chem. Phys. 110 (1999) 9853–9864.

use crate::scene::SceneError;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, SVector};
use svi::Dimension;
use svi::{Defaults, LagrangianExt};
use svi_models::SpringPendulum;

/// The method's name in `--methods`.
pub(crate) const NAME: &str = "molly";

/// Evaluations of the slow force per step (one gravity kick per half step).
pub(crate) const EVALUATIONS_PER_STEP: usize = 2;

/// sinc ξ = sin ξ/ξ, by its Taylor series 1 − ξ²/6 + ξ⁴/120 − ξ⁶/5040 for |ξ| < 10⁻²
/// (truncation below 10⁻²¹) and sin ξ/ξ beyond.
pub(crate) fn sinc(xi: f64) -> f64 {
    if xi.abs() < 1e-2 {
        let x2 = xi * xi;
        1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0))
    } else {
        xi.sin() / xi
    }
}

/// A phase-space point (a, θ, p_a, p_θ) of the spring pendulum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct State {
    /// Spring extension a.
    pub(crate) a: f64,
    /// Angle θ from the downward vertical.
    pub(crate) theta: f64,
    /// p_a = m ȧ.
    pub(crate) p_a: f64,
    /// p_θ = m (l + a)² θ̇.
    pub(crate) p_theta: f64,
}

impl State {
    /// The point with positions `q` = (a, θ) and velocities `v` = (ȧ, θ̇).
    pub(crate) fn from_velocity(
        model: &SpringPendulum,
        q: &SVector<f64, 2>,
        v: &SVector<f64, 2>,
    ) -> State {
        let length = model.l + q[0];
        State {
            a: q[0],
            theta: q[1],
            p_a: model.m * v[0],
            p_theta: model.m * length * length * v[1],
        }
    }

    /// The positions (a, θ).
    pub(crate) fn position(&self) -> SVector<f64, 2> {
        SVector::from([self.a, self.theta])
    }

    /// The velocities (ȧ, θ̇).
    pub(crate) fn velocity(&self, model: &SpringPendulum) -> SVector<f64, 2> {
        let length = model.l + self.a;
        SVector::from([
            self.p_a / model.m,
            self.p_theta / (model.m * length * length),
        ])
    }

    /// The energy of the spring pendulum at this point, from its Lagrangian
    /// ([`LagrangianExt::energy`], independent of the splitting).
    pub(crate) fn energy(&self, model: &SpringPendulum) -> f64 {
        model.energy(0.0, &self.position(), &self.velocity(model))
    }

    /// Whether every component is finite.
    fn is_finite(&self) -> bool {
        [self.a, self.theta, self.p_a, self.p_theta]
            .iter()
            .all(|x| x.is_finite())
    }
}

/// One step Φ_h of the mollified impulse method on a spring pendulum (see the module docs),
/// with the step's constants computed once.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Molly {
    model: SpringPendulum,
    /// The step h (negative steps run backwards).
    h: f64,
    /// The centre of the fast oscillation, a* = m g/k.
    centre: f64,
    /// The spring frequency ω = √(k/m).
    omega: f64,
    /// The mollifier's factor φ(hω) = sinc(hω).
    filter: f64,
    /// (cos hω, sin hω), the fast flow's rotation over h.
    rotation: (f64, f64),
}

impl Molly {
    /// The method on `model` with step `h`.
    pub(crate) fn new(model: SpringPendulum, h: f64) -> Molly {
        let omega = model.spring_frequency();
        let (sin, cos) = (h * omega).sin_cos();
        Molly {
            model,
            h,
            centre: model.static_extension(),
            omega,
            filter: sinc(h * omega),
            rotation: (cos, sin),
        }
    }

    /// The pendulum length at the mollified extension, l + A(a).
    fn mollified_length(&self, a: f64) -> f64 {
        self.model.l + self.centre + self.filter * (a - self.centre)
    }

    /// The exact flow of T∘A over `t`.
    fn kinetic_flow(&self, state: &mut State, t: f64) {
        let SpringPendulum { m, .. } = self.model;
        let length = self.mollified_length(state.a);
        let rate = state.p_theta / (m * length * length);
        state.theta += rate * t;
        state.p_a += self.filter * state.p_theta * rate / length * t;
    }

    /// The exact flow of V∘A over `t`.
    fn potential_flow(&self, state: &mut State, t: f64) {
        let SpringPendulum { m, g, .. } = self.model;
        let length = self.mollified_length(state.a);
        let (sin, cos) = state.theta.sin_cos();
        state.p_a += self.filter * m * g * (cos - 1.0) * t;
        state.p_theta -= m * g * length * sin * t;
    }

    /// Half a step of the mollified slow flow, φ^T_{h/4} ∘ φ^V_{h/2} ∘ φ^T_{h/4}.
    fn slow_half_step(&self, state: &mut State) {
        let quarter = 0.25 * self.h;
        self.kinetic_flow(state, quarter);
        self.potential_flow(state, 2.0 * quarter);
        self.kinetic_flow(state, quarter);
    }

    /// The exact fast flow over h: a rotation of (a − a*, p_a/(mω)).
    fn fast_flow(&self, state: &mut State) {
        let (cos, sin) = self.rotation;
        let scale = self.model.m * self.omega;
        let (x, y) = (state.a - self.centre, state.p_a / scale);
        state.a = self.centre + cos * x + sin * y;
        state.p_a = scale * (cos * y - sin * x);
    }

    /// One step Φ_h = φ^slow_{h/2} ∘ φ^fast_h ∘ φ^slow_{h/2}, in place.
    pub(crate) fn step(&self, state: &mut State) {
        self.slow_half_step(state);
        self.fast_flow(state);
        self.slow_half_step(state);
    }
}

/// Whether `molly` applies to the model named `model`: only to [`SpringPendulum::NAME`];
/// for any other model the error every use of `molly` on it gives.
pub(crate) fn check_model(model: &str) -> Result<(), SceneError> {
    if model == SpringPendulum::NAME {
        return Ok(());
    }
    Err(SceneError::MethodNotApplicable {
        method: NAME.into(),
        reason: format!(
            "the mollified impulse method is written for the splitting of the model '{}' (a \
             harmonic spring and a slow pendulum), not for '{model}'",
            SpringPendulum::NAME
        ),
    })
}

/// The spring pendulum of a zoo model named [`SpringPendulum::NAME`], with its parameters;
/// for any other model the error of [`check_model`].
pub(crate) fn spring_pendulum<M: Defaults<N>, N: Dimension>(
    model: &M,
) -> Result<SpringPendulum, SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    check_model(model.name())?;
    if N::try_to_usize() != Some(2) {
        let dimension = N::try_to_usize()
            .map_or_else(|| "run-time dimension".into(), |n| format!("dimension {n}"));
        return Err(SceneError::MethodNotApplicable {
            method: NAME.into(),
            reason: format!("a model of {dimension} named '{}'", model.name()),
        });
    }
    let mut pendulum = SpringPendulum::default();
    for (name, value) in model.parameters() {
        pendulum.set_parameter(name, value)?;
    }
    Ok(pendulum)
}

/// `steps` steps of [`Molly`] from `start` = (t0, point) to `t_end` (h = (t_end − t0)/steps),
/// calling `observe` after every step; the last point, or an error at the first step that
/// leaves a non-finite state or a mollified pendulum length l + A(a) ≤ 0 (the coordinates'
/// singularity).
pub(crate) fn run(
    model: SpringPendulum,
    (t0, start): (f64, State),
    t_end: f64,
    steps: usize,
    mut observe: impl FnMut(&State),
) -> Result<State, svi::Error> {
    let h = (t_end - t0) / steps as f64;
    let method = Molly::new(model, h);
    let mut state = start;
    for step in 0..steps {
        method.step(&mut state);
        if !state.is_finite() || method.mollified_length(state.a) <= 0.0 {
            return Err(svi::Error::NonFinite {
                what: "state (or a spring pendulum of length ≤ 0)".into(),
                step,
                t: t0 + step as f64 * h,
            });
        }
        observe(&state);
    }
    Ok(state)
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::Integrator;

    /// The default spring pendulum (m = 1, g = 9.81, k = 10⁴, l = 1) released at rest at
    /// (a, θ) = (0, 0.5), as the scene `stiff-spring-pendulum`.
    fn released() -> (SpringPendulum, State) {
        let model = SpringPendulum::default();
        let start = State::from_velocity(&model, &SVector::from([0.0, 0.5]), &SVector::zeros());
        (model, start)
    }

    #[test]
    fn sinc_is_smooth_across_its_series_branch() {
        assert_eq!(sinc(0.0), 1.0);
        for xi in [1e-8f64, 1e-4, 0.009_999, 0.01, 0.3, 31.0] {
            let direct = xi.sin() / xi;
            assert!((sinc(xi) - direct).abs() < 1e-15, "{xi}");
            assert_eq!(sinc(-xi), sinc(xi));
        }
        assert!(sinc(std::f64::consts::PI).abs() < 1e-16);
    }

    #[test]
    fn converges_at_order_two_to_a_resolved_run() {
        // T = 1 at h = 1e-3 … 1.25e-4 (hω = 0.1 … 0.0125) against SVI of order 12
        // (svi:7/6) at h = 1e-3: the position error falls as h², 9.6e-8 at h = 1e-3 and
        // 1.5e-9 at 1.25e-4 (as a prototype of the same formulas against RK4 at h = 2.5e-5),
        // bounded here at about twice that.
        let (model, start) = released();
        let t_end = 1.0;
        let reference = Integrator::new(model, svi::Svi::new(7).with_quadrature(6))
            .run_from_velocity(
                0.0,
                start.position(),
                start.velocity(&model),
                1e-3,
                t_end,
                &mut (),
            )
            .unwrap()
            .state
            .q;
        let steps = [1000usize, 2000, 4000, 8000];
        let errors: Vec<f64> = steps
            .iter()
            .map(|&n| {
                let end = run(model, (0.0, start), t_end, n, |_| ()).unwrap();
                (end.position() - reference).norm()
            })
            .collect();
        let sizes: Vec<f64> = steps.iter().map(|&n| t_end / n as f64).collect();
        let order = svi::verify::observed_order(&sizes, &errors, 1e-12).unwrap();
        assert!((1.8..2.2).contains(&order), "{order} {errors:?}");
        assert!(errors[0] < 2e-7 && errors[3] < 3e-9, "{errors:?}");
    }

    #[test]
    fn a_step_with_the_negated_step_undoes_it() {
        // Ten steps forward and ten with −h, at a resolving and at a long step.
        let (model, start) = released();
        for h in [0.01, 0.31] {
            let (forward, backward) = (Molly::new(model, h), Molly::new(model, -h));
            let mut state = start;
            for _ in 0..10 {
                forward.step(&mut state);
            }
            assert!((state.theta - start.theta).abs() > 1e-3, "{state:?}");
            for _ in 0..10 {
                backward.step(&mut state);
            }
            for (x, x0, scale) in [
                (state.a, start.a, model.static_extension()),
                (state.theta, start.theta, 1.0),
                (state.p_a, start.p_a, 1.0),
                (state.p_theta, start.p_theta, 1.0),
            ] {
                assert!((x - x0).abs() < 1e-12 * scale.max(1.0), "{h}: {state:?}");
            }
        }
    }

    #[test]
    fn the_energy_error_stays_bounded_at_five_spring_periods_per_step() {
        // h = 0.31 (hω = 31, about five spring periods per step) over T = 1000 (3226 steps):
        // the largest |E − E₀| and its mean are the same in the first and the last tenth.
        let (model, start) = released();
        let energy0 = start.energy(&model);
        let steps = 3226;
        let mut errors = Vec::with_capacity(steps);
        run(model, (0.0, start), 1000.0, steps, |state| {
            errors.push(state.energy(&model) - energy0)
        })
        .unwrap();
        let tenth = steps / 10;
        let (first, last) = (&errors[..tenth], &errors[steps - tenth..]);
        let largest = |e: &[f64]| e.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
        assert!(largest(&errors) < 0.08, "{}", largest(&errors));
        assert!((largest(first) - largest(last)).abs() < 2e-3);
        assert!((mean(first) - mean(last)).abs() < 1e-3);
        assert!(mean(first) > 0.03, "{}", mean(first));
    }
}
