//! Forced mechanics (Lagrange–d'Alembert): every integrator with an external force.
//!
//! References: the closed-form solution of the damped and of the driven harmonic oscillator
//! (`svi_models::DampedOscillator`, `svi_models::DrivenOscillator`), and for the damped
//! pendulum, which has none, a high-order SVI run (16th order at h = 0.05, error below
//! 1e-13) as reference for the low-order methods. The unforced integrators are the
//! reference for the zero-force runs (bit for bit), and central differences of the step the
//! reference for the tangent maps.

use nalgebra::{Const, SVector, U1};
use svi::observer::Trajectory;
use svi::verify::observed_order;
use svi::{
    AdjointSymplecticEuler, Defaults, ExactSolution, Integrator, Lagrangian, Method, Midpoint,
    Scalar, SpectralCollocation, State, StormerVerlet, Structure, Svi, SymplecticEuler, Trapezoid,
    VariationalIntegrator,
};
use svi_models::{
    DampedOscillator, DampedPendulum, DoublePendulum, DrivenOscillator, HarmonicOscillator, Kepler,
    Pendulum,
};

/// The same Lagrangian and force declared without structure: the methods take their Newton
/// paths (and Störmer–Verlet its implicit one).
#[derive(Debug, Clone, Copy)]
struct General<M>(M);

impl<M: Lagrangian<Const<N>>, const N: usize> Lagrangian<Const<N>> for General<M> {
    const TIME_DEPENDENT: bool = M::TIME_DEPENDENT;
    const FORCED: bool = M::FORCED;
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, N>, v: &SVector<D, N>) -> D {
        self.0.lagrangian(t, q, v)
    }
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &SVector<D, N>,
        v: &SVector<D, N>,
    ) -> SVector<D, N> {
        self.0.external_force(t, q, v)
    }
}

/// The same Lagrangian and structure, declared forced with the default (zero) force.
#[derive(Debug, Clone, Copy)]
struct ZeroForce<M>(M);

impl<M: Lagrangian<Const<N>>, const N: usize> Lagrangian<Const<N>> for ZeroForce<M> {
    const TIME_DEPENDENT: bool = M::TIME_DEPENDENT;
    const STRUCTURE: Structure = M::STRUCTURE;
    const FORCED: bool = true;
    fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, N>, v: &SVector<D, N>) -> D {
        self.0.lagrangian(t, q, v)
    }
}

/// Runs `body` for every method of `svi`, with its name: the given SVI and SC
/// configurations, then the five classic variational integrators.
macro_rules! for_each_method {
    ($svi:expr, $sc:expr, |$name:ident, $method:ident| $body:block) => {{
        {
            let $name = "svi";
            let $method = $svi;
            $body
        }
        {
            let $name = "sc";
            let $method = $sc;
            $body
        }
        {
            let $name = "symplectic-euler";
            let $method = VariationalIntegrator::new(SymplecticEuler);
            $body
        }
        {
            let $name = "symplectic-euler-adjoint";
            let $method = VariationalIntegrator::new(AdjointSymplecticEuler);
            $body
        }
        {
            let $name = "midpoint";
            let $method = VariationalIntegrator::new(Midpoint);
            $body
        }
        {
            let $name = "trapezoid";
            let $method = VariationalIntegrator::new(Trapezoid);
            $body
        }
        {
            let $name = "verlet";
            let $method = StormerVerlet::default();
            $body
        }
    }};
}

/// The trajectory of a run from (q0, q̇0) at t = 0.
fn trajectory<L: Lagrangian<Const<N>>, M: Method<Const<N>>, const N: usize>(
    model: L,
    method: M,
    q0: SVector<f64, N>,
    v0: SVector<f64, N>,
    h: f64,
    t_end: f64,
) -> (Vec<svi::PhasePoint<Const<N>>>, svi::Run<Const<N>>) {
    let mut points = Trajectory::new();
    let run = Integrator::new(model, method)
        .run_from_velocity(0.0, q0, v0, h, t_end, &mut points)
        .unwrap();
    (points.points, run)
}

/// The final states of the same run of `model` and of `forced` (equal up to a zero force).
fn same_runs<
    A: Lagrangian<Const<N>>,
    B: Lagrangian<Const<N>>,
    M: Method<Const<N>> + Clone,
    const N: usize,
>(
    model: A,
    forced: B,
    method: &M,
    q0: SVector<f64, N>,
    v0: SVector<f64, N>,
    h: f64,
) -> (svi::Run<Const<N>>, svi::Run<Const<N>>) {
    let plain = Integrator::new(model, method.clone())
        .run_from_velocity(0.0, q0, v0, h, 5.0, &mut ())
        .unwrap();
    let forced = Integrator::new(forced, method.clone())
        .run_from_velocity(0.0, q0, v0, h, 5.0, &mut ())
        .unwrap();
    (plain, forced)
}

#[test]
fn a_zero_force_reproduces_the_unforced_integrators_bit_for_bit() {
    let pendulum = (SVector::from([1.0]), SVector::from([0.2]));
    let kepler = (
        SVector::from([0.5, 0.0]),
        SVector::from([0.0, 1.7320508075688772]),
    );
    let double = (SVector::from([1.0, 0.5]), SVector::from([0.0, 0.0]));
    for_each_method!(Svi::new(5), SpectralCollocation::new(5), |name, method| {
        // Constant mass (fixed-point and explicit paths) and general (Newton paths).
        let (a, b) = same_runs(
            Pendulum::default(),
            ZeroForce(Pendulum::default()),
            &method,
            pendulum.0,
            pendulum.1,
            0.1,
        );
        assert_eq!(a.state, b.state, "{name} pendulum");
        let (a, b) = same_runs(
            General(Pendulum::default()),
            ZeroForce(General(Pendulum::default())),
            &method,
            pendulum.0,
            pendulum.1,
            0.1,
        );
        assert_eq!(a.state, b.state, "{name} pendulum (Newton)");
        let (a, b) = same_runs(
            Kepler::default(),
            ZeroForce(Kepler::default()),
            &method,
            kepler.0,
            kepler.1,
            0.05,
        );
        assert_eq!(a.state, b.state, "{name} kepler");
        let (a, b) = same_runs(
            DoublePendulum::default(),
            ZeroForce(DoublePendulum::default()),
            &method,
            double.0,
            double.1,
            0.01,
        );
        assert_eq!(a.state, b.state, "{name} double pendulum");
        // The damped oscillator with ζ = 0 is the harmonic oscillator, with a force −0·q̇.
        let (a, b) = same_runs(
            HarmonicOscillator::new(1.5).unwrap(),
            DampedOscillator::new(1.5, 0.0).unwrap(),
            &method,
            pendulum.0,
            pendulum.1,
            0.1,
        );
        assert_eq!(a.state, b.state, "{name} damped oscillator with ζ = 0");
        assert_eq!(a.last, b.last, "{name}");
    });
}

/// Largest position error and largest energy error, against the exact solution, over a run
/// of the damped (or driven) oscillator.
fn oscillator_errors<L, M>(
    model: L,
    exact: &impl ExactSolution<U1>,
    method: M,
    h: f64,
) -> (f64, f64)
where
    L: Lagrangian<U1>,
    M: Method<U1>,
{
    let (q0, v0) = (SVector::from([1.0]), SVector::from([0.0]));
    let (points, _) = trajectory(model, method, q0, v0, h, 10.0);
    let sigma = 1.0;
    let energy = |q: f64, v: f64| 0.5 * (v * v + sigma * sigma * q * q);
    let mut position: f64 = 0.0;
    let mut energy_error: f64 = 0.0;
    for point in &points {
        let (q, v) = exact.exact_solution(0.0, &q0, &v0, point.t).unwrap();
        position = position.max((point.q[0] - q[0]).abs());
        let decay = energy(point.q[0], point.v[0]) - energy(q[0], v[0]);
        energy_error = energy_error.max(decay.abs());
    }
    (position, energy_error)
}

/// Observed orders of the position and energy errors over a step ladder.
fn orders<L: Lagrangian<U1> + Copy, M: Method<U1> + Clone>(
    model: L,
    exact: &impl ExactSolution<U1>,
    method: &M,
    steps: &[f64],
) -> (f64, f64, Vec<f64>) {
    let (positions, energies): (Vec<f64>, Vec<f64>) = steps
        .iter()
        .map(|&h| oscillator_errors(model, exact, method.clone(), h))
        .unzip();
    let position = observed_order(steps, &positions, 1e-12).unwrap();
    let energy = observed_order(steps, &energies, 1e-12).unwrap();
    (position, energy, positions)
}

#[test]
fn damped_oscillator_converges_to_the_exact_solution_at_each_methods_order() {
    // Under-, critically and over-damped; SVI with 3 CGL / 3 Gauss points and SC with 5 CGL
    // points are both of order 4; the classic methods of order 1 and 2.
    for zeta in [0.1, 1.0, 2.5] {
        let model = DampedOscillator::new(1.0, zeta).unwrap();
        for_each_method!(
            Svi::new(3).with_quadrature(3),
            SpectralCollocation::new(5),
            |name, method| {
                let declared = Method::<U1>::info(&method).order as f64;
                let steps: &[f64] = if declared > 2.0 {
                    &[0.2, 0.1, 0.05, 0.025]
                } else {
                    &[0.1, 0.05, 0.025, 0.0125]
                };
                // Fixed-point / explicit paths and Newton / implicit paths.
                for (path, (position, energy, errors)) in [
                    ("structured", orders(model, &model, &method, steps)),
                    ("general", orders(General(model), &model, &method, steps)),
                ] {
                    eprintln!(
                        "ζ = {zeta} {name} ({path}): order {position:.3}, energy order \
                         {energy:.3} (declared {declared}); errors {errors:?}"
                    );
                    assert!(
                        (position - declared).abs() < 0.25,
                        "ζ = {zeta}, {name} ({path}): position order {position}"
                    );
                    // The energy decay follows the exact decay to within the method's error.
                    assert!(
                        energy > declared - 0.25,
                        "ζ = {zeta}, {name} ({path}): energy order {energy}"
                    );
                }
            }
        );
    }
}

#[test]
fn a_time_dependent_drive_converges_at_each_methods_order() {
    let model = DrivenOscillator::default();
    for_each_method!(
        Svi::new(3).with_quadrature(3),
        SpectralCollocation::new(5),
        |name, method| {
            let declared = Method::<U1>::info(&method).order as f64;
            let steps: &[f64] = if declared > 2.0 {
                &[0.2, 0.1, 0.05, 0.025]
            } else {
                &[0.1, 0.05, 0.025, 0.0125]
            };
            for (path, (position, _, errors)) in [
                ("structured", orders(model, &model, &method, steps)),
                ("general", orders(General(model), &model, &method, steps)),
            ] {
                eprintln!("driven {name} ({path}): order {position:.3}; errors {errors:?}");
                assert!(
                    (position - declared).abs() < 0.25,
                    "{name} ({path}): position order {position}"
                );
            }
        }
    );
}

#[test]
fn damped_pendulum_converges_to_a_high_order_reference() {
    let model = DampedPendulum::default();
    let (_, q0, v0) = model.initial_state();
    let t_end = 10.0;
    let (_, reference) = trajectory(model, Svi::new(9), q0, v0, 0.05, t_end);
    let (_, check) = trajectory(model, Svi::new(10), q0, v0, 0.05, t_end);
    assert!((reference.last.q - check.last.q).amax() < 1e-13);
    for_each_method!(
        Svi::new(3).with_quadrature(3),
        SpectralCollocation::new(5),
        |name, method| {
            let declared = Method::<U1>::info(&method).order as f64;
            let steps: &[f64] = if declared > 2.0 {
                &[0.2, 0.1, 0.05, 0.025]
            } else {
                &[0.1, 0.05, 0.025, 0.0125]
            };
            let errors: Vec<f64> = steps
                .iter()
                .map(|&h| {
                    let (_, run) = trajectory(model, method.clone(), q0, v0, h, t_end);
                    (run.last.q - reference.last.q).amax()
                })
                .collect();
            let order = observed_order(steps, &errors, 1e-12).unwrap();
            eprintln!("damped pendulum {name}: order {order:.3}; errors {errors:?}");
            assert!((order - declared).abs() < 0.25, "{name}: {order}");
        }
    );
}

/// The tangent map of a forced step against central differences; returns (symplecticity
/// error, largest relative difference).
fn forced_tangent<L: Lagrangian<U1> + Copy, M: Method<U1> + Clone>(
    model: L,
    method: &M,
    state: State<U1>,
    h: f64,
) -> (f64, f64) {
    let integrator = Integrator::new(model, method.clone());
    let (_, tangent) = integrator.tangent_map(0.3, &state, h).unwrap();
    let phi = tangent.matrix();
    let eps = 1e-6;
    let mut worst: f64 = 0.0;
    for j in 0..2 {
        let (mut plus, mut minus) = (state, state);
        if j == 0 {
            plus.q[0] += eps;
            minus.q[0] -= eps;
        } else {
            plus.y[0] += eps;
            minus.y[0] -= eps;
        }
        let (a, _) = integrator.tangent_map(0.3, &plus, h).unwrap();
        let (b, _) = integrator.tangent_map(0.3, &minus, h).unwrap();
        let column = [
            (a.q[0] - b.q[0]) / (2.0 * eps),
            (a.y[0] - b.y[0]) / (2.0 * eps),
        ];
        for (i, difference) in column.iter().enumerate() {
            worst = worst.max((difference - phi[(i, j)]).abs() / (1.0 + phi[(i, j)].abs()));
        }
    }
    (tangent.symplecticity_error(), worst)
}

#[test]
fn forced_tangent_maps_match_central_differences_and_are_not_symplectic() {
    let state = State {
        q: SVector::from([1.2]),
        y: SVector::from([0.3]),
    };
    let pendulum = DampedPendulum {
        c: 0.5,
        ..DampedPendulum::default()
    };
    let driven = DrivenOscillator::default();
    for_each_method!(Svi::new(4), SpectralCollocation::new(4), |name, method| {
        for (model, (symplectic, difference)) in [
            (
                "damped pendulum",
                forced_tangent(pendulum, &method, state, 0.2),
            ),
            (
                "damped pendulum (Newton)",
                forced_tangent(General(pendulum), &method, state, 0.2),
            ),
            (
                "driven oscillator",
                forced_tangent(driven, &method, state, 0.2),
            ),
        ] {
            eprintln!(
                "{name} {model}: symplecticity {symplectic:.1e}, difference {difference:.1e}"
            );
            assert!(difference < 1e-6, "{name} {model}: {difference:e}");
            // Friction contracts phase-space area: det Φ ≈ e^{−c h / (m l²)}, so ΦᵀJΦ ≠ J.
            if model != "driven oscillator" {
                assert!(symplectic > 1e-3, "{name} {model}: {symplectic:e}");
            }
        }
    });
}

#[test]
fn forced_fixed_point_and_newton_paths_agree() {
    let model = DampedPendulum {
        c: 0.3,
        ..DampedPendulum::default()
    };
    let (_, q0, v0) = model.initial_state();
    for (name, structured, general) in [
        (
            "svi",
            trajectory(model, Svi::new(6), q0, v0, 0.2, 20.0).1,
            trajectory(General(model), Svi::new(6), q0, v0, 0.2, 20.0).1,
        ),
        (
            "sc",
            trajectory(model, SpectralCollocation::new(6), q0, v0, 0.2, 20.0).1,
            trajectory(
                General(model),
                SpectralCollocation::new(6),
                q0,
                v0,
                0.2,
                20.0,
            )
            .1,
        ),
        (
            "verlet",
            trajectory(model, StormerVerlet::default(), q0, v0, 0.05, 20.0).1,
            trajectory(General(model), StormerVerlet::default(), q0, v0, 0.05, 20.0).1,
        ),
    ] {
        let difference = (structured.last.q - general.last.q)
            .amax()
            .max((structured.last.p - general.last.p).amax());
        assert!(difference < 1e-12, "{name}: {difference:e}");
    }
}

#[test]
fn strong_friction_falls_back_from_the_fixed_point_to_newton() {
    // c = 2ζσ = 20 at h = 0.5: the fixed point of the constant-mass paths contracts only by
    // O(h c) and fails; the step is then solved by Newton's method, as for a general model.
    let model = DampedOscillator::new(1.0, 10.0).unwrap();
    let (q0, v0) = (SVector::from([1.0]), SVector::from([0.0]));
    for (name, structured, general) in [
        (
            "svi",
            trajectory(model, Svi::new(5), q0, v0, 0.5, 10.0).1,
            trajectory(General(model), Svi::new(5), q0, v0, 0.5, 10.0).1,
        ),
        (
            "sc",
            trajectory(model, SpectralCollocation::new(5), q0, v0, 0.5, 10.0).1,
            trajectory(
                General(model),
                SpectralCollocation::new(5),
                q0,
                v0,
                0.5,
                10.0,
            )
            .1,
        ),
    ] {
        let difference = (structured.last.q - general.last.q).amax();
        assert!(difference < 1e-12, "{name}: {difference:e}");
        let (exact, _) = model.exact_solution(0.0, &q0, &v0, 10.0).unwrap();
        assert!((structured.last.q - exact).amax() < 1e-4, "{name}");
        // The failed fixed-point attempt is counted, then Newton's iterations.
        assert!(structured.statistics.iterations > general.statistics.iterations);
    }
}

#[test]
fn forced_stormer_verlet_stays_hessian_free() {
    // Friction depends on q̇: the first kick is a small Newton solve for the half-step
    // momentum, but the force ∂L/∂q is still evaluated once per step.
    let model = DampedPendulum::default();
    let (t0, q0, v0) = model.initial_state();
    let run = Integrator::new(model, StormerVerlet::default())
        .run_from_velocity(t0, q0, v0, 0.1, 100.0, &mut ())
        .unwrap();
    assert_eq!(run.statistics.evaluations, run.statistics.steps + 1);
    assert!(run.statistics.iterations <= 3 * run.statistics.steps);
    // The energy has decayed from −cos 1 towards the minimum −1.
    let energy = model.energy_at(&run.last);
    assert!(energy < -0.99 && energy > -1.0, "{energy}");
}

/// The damped pendulum's energy at a phase point.
trait EnergyAt {
    fn energy_at(&self, point: &svi::PhasePoint<U1>) -> f64;
}

impl EnergyAt for DampedPendulum {
    fn energy_at(&self, point: &svi::PhasePoint<U1>) -> f64 {
        let (m, l, g) = (self.m, self.l, self.g);
        0.5 * m * l * l * point.v[0] * point.v[0] - m * g * l * point.q[0].cos()
    }
}
