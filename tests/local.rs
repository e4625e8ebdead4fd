//! Runtime-dimension models (sums of local terms) through the one stepping loop: the FPUT
//! chain against the same chain written as a fixed-size Lagrangian, energy behaviour, and
//! bad input.

use nalgebra::{DVector, SVector, U8};
use svi::model::local::{LocalDefaults, LocalLagrangian, LocalLagrangianExt, Terms};
use svi::observer::EnergyError;
use svi::{Composition, Initial, Integrator, Lagrangian, Scalar, Scheme, StormerVerlet, Structure};
use svi_models::Fput;

/// The FPUT chain of 8 particles written directly as one fixed-size Lagrangian (an
/// independent implementation of the same L).
struct FixedFput {
    alpha: f64,
    beta: f64,
}

impl Lagrangian<U8> for FixedFput {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 8>, v: &SVector<D, 8>) -> D {
        let mut kinetic = D::from(0.0);
        for i in 0..8 {
            kinetic += v[i] * v[i] * 0.5;
        }
        let mut potential = D::from(0.0);
        for j in 0..=8 {
            let left = if j == 0 { D::from(0.0) } else { q[j - 1] };
            let right = if j == 8 { D::from(0.0) } else { q[j] };
            let r = right - left;
            potential +=
                r * r * 0.5 + r * r * r * (self.alpha / 3.0) + r * r * r * r * (self.beta / 4.0);
        }
        kinetic - potential
    }
}

fn fput(n: usize) -> Fput {
    let mut model = Fput::default();
    model.set_parameter("n", n as f64).unwrap();
    model.set_parameter("beta", 0.5).unwrap();
    model
}

#[test]
fn local_terms_assemble_the_fixed_size_lagrangians_derivatives() {
    use svi::LagrangianExt;
    let model = fput(8);
    let fixed = FixedFput {
        alpha: model.alpha,
        beta: model.beta,
    };
    let q = DVector::from_fn(8, |i, _| 0.3 * (i as f64 + 1.0).sin());
    let v = DVector::from_fn(8, |i, _| 0.2 * (i as f64 * 0.7).cos());
    let (qs, vs) = (
        SVector::<f64, 8>::from_column_slice(q.as_slice()),
        SVector::<f64, 8>::from_column_slice(v.as_slice()),
    );
    let mut force = DVector::zeros(8);
    model.force_into(0.0, &q, &v, &mut force);
    let mut momentum = DVector::zeros(8);
    model.momentum_into(0.0, &q, &v, &mut momentum);
    let reference = fixed.first_derivatives(0.0, &qs, &vs);
    for i in 0..8 {
        assert!((force[i] - reference.q[i]).abs() < 1e-15, "∂L/∂q[{i}]");
        assert!((momentum[i] - reference.v[i]).abs() < 1e-15, "p[{i}]");
    }
    assert!((LocalLagrangian::value(&model, 0.0, &q, &v) - reference.value).abs() < 1e-15);
    assert!(
        (LocalLagrangianExt::energy(&model, 0.0, &q, &v) - fixed.energy(0.0, &qs, &vs)).abs()
            < 1e-15
    );
    // The mass matrix is the identity, one diagonal entry per particle.
    let mut mass = model.mass_triplets(0.0, &q, &v);
    mass.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(mass, (0..8).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
}

#[test]
fn verlet_on_local_terms_follows_the_fixed_size_verlet_to_round_off() {
    let model = fput(8);
    let fixed = FixedFput {
        alpha: model.alpha,
        beta: model.beta,
    };
    let (t0, q0, v0) = model.initial_state();
    let (h, t_end) = (0.05, 50.0);
    let local = Integrator::new(Terms(model), StormerVerlet::default())
        .run(
            t0,
            Initial::Velocity {
                q: q0.clone(),
                v: v0.clone(),
            },
            h,
            t_end,
            &mut (),
        )
        .unwrap();
    let qs = SVector::<f64, 8>::from_column_slice(q0.as_slice());
    let vs = SVector::<f64, 8>::from_column_slice(v0.as_slice());
    let reference = Integrator::new(fixed, StormerVerlet::default())
        .run_from_velocity(t0, qs, vs, h, t_end, &mut ())
        .unwrap();
    assert_eq!(local.statistics.steps, 1000);
    for i in 0..8 {
        assert!(
            (local.last.q[i] - reference.last.q[i]).abs() < 1e-13,
            "q[{i}]"
        );
        assert!(
            (local.last.p[i] - reference.last.p[i]).abs() < 1e-13,
            "p[{i}]"
        );
    }
    assert_eq!(
        local.statistics.evaluations,
        reference.statistics.evaluations
    );
}

#[test]
fn compositions_on_local_terms_follow_the_fixed_size_compositions_to_round_off() {
    // Kahan–Li 8 (17 stages) and Yoshida's triple jump on the FPUT chain: the same stages as
    // the fixed-size method on the same L written independently, and order 8 and 4 against a
    // fine run of Kahan–Li 8.
    let model = fput(8);
    let (t0, q0, v0) = model.initial_state();
    let t_end = 20.0;
    let local_run = |scheme: Scheme, h: f64| {
        Integrator::new(Terms(model.clone()), Composition::new(scheme))
            .run(
                t0,
                Initial::Velocity {
                    q: q0.clone(),
                    v: v0.clone(),
                },
                h,
                t_end,
                &mut (),
            )
            .unwrap()
    };
    let qs = SVector::<f64, 8>::from_column_slice(q0.as_slice());
    let vs = SVector::<f64, 8>::from_column_slice(v0.as_slice());
    for scheme in [Scheme::Yoshida4, Scheme::KahanLi8] {
        let local = local_run(scheme, 0.1);
        let fixed = FixedFput {
            alpha: model.alpha,
            beta: model.beta,
        };
        let reference = Integrator::new(fixed, Composition::new(scheme))
            .run_from_velocity(t0, qs, vs, 0.1, t_end, &mut ())
            .unwrap();
        let difference = (0..8)
            .map(|i| (local.last.q[i] - reference.last.q[i]).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-12, "{scheme:?}: {difference:e}");
        // One assembly of ∂L/∂q per stage, as on fixed-size ℝᴺ.
        assert_eq!(
            local.statistics.evaluations,
            reference.statistics.evaluations
        );
    }
    let exact = local_run(Scheme::KahanLi8, 0.025).last.q;
    for (scheme, coarse) in [(Scheme::Yoshida4, 0.1), (Scheme::KahanLi8, 0.4)] {
        let error = |h: f64| (local_run(scheme, h).last.q - &exact).amax();
        let order = (error(coarse) / error(coarse / 2.0)).log2();
        let expected = scheme.order() as f64;
        assert!((order - expected).abs() < 0.5, "{scheme:?}: order {order}");
    }
}

#[test]
fn verlet_energy_error_is_second_order_and_bounded() {
    // Halving h divides the maximal energy error by 4 (order 2), over many periods of the
    // fastest mode (no drift: the bound holds over the whole run).
    let model = fput(64);
    let (t0, q0, v0) = model.initial_state();
    let energy_error = |h: f64| {
        let mut energy = EnergyError::default();
        Integrator::new(Terms(model.clone()), StormerVerlet::default())
            .run(
                t0,
                Initial::Velocity {
                    q: q0.clone(),
                    v: v0.clone(),
                },
                h,
                400.0,
                &mut energy,
            )
            .unwrap();
        energy.max
    };
    let (coarse, fine) = (energy_error(0.2), energy_error(0.1));
    let order = (coarse / fine).log2();
    assert!((order - 2.0).abs() < 0.1, "observed order {order}");
    assert!(fine < 1e-4 * LocalLagrangianExt::energy(&model, t0, &q0, &v0));
}

#[test]
fn observers_see_runtime_sized_points() {
    let model = fput(5);
    let (t0, q0, v0) = model.initial_state();
    let mut trajectory = svi::observer::Points::default();
    let run = Integrator::new(Terms(model), StormerVerlet::default())
        .run(
            t0,
            Initial::Velocity {
                q: q0.clone(),
                v: v0,
            },
            0.1,
            1.0,
            &mut trajectory,
        )
        .unwrap();
    assert_eq!(trajectory.points.len(), 11);
    let first: &svi::PhasePoint<svi::Dyn> = &trajectory.points[0];
    assert_eq!(first.q, q0);
    assert_eq!(trajectory.points[10].q, run.last.q);
    assert_eq!(run.last.v, run.last.p); // unit masses
}

#[test]
fn bad_sizes_and_states_are_errors_naming_them() {
    let mut model = Fput::default();
    for bad in [0.0, -3.0, 2.5, f64::NAN, 1e300] {
        let error = model.set_parameter("n", bad).unwrap_err();
        assert!(error.to_string().contains('n'), "{error}");
    }
    let (t0, q0, _) = model.initial_state();
    let short = DVector::zeros(model.dimension() - 1);
    let error = Integrator::new(Terms(model.clone()), StormerVerlet::default())
        .run(
            t0,
            Initial::Velocity {
                q: q0.clone(),
                v: short,
            },
            0.1,
            1.0,
            &mut (),
        )
        .unwrap_err();
    assert!(error.to_string().contains("initial velocity"), "{error}");
    let mut nan = q0.clone();
    nan[3] = f64::NAN;
    let v = DVector::zeros(q0.len());
    let error = Integrator::new(Terms(model), StormerVerlet::default())
        .run(t0, Initial::Velocity { q: nan, v }, 0.1, 1.0, &mut ())
        .unwrap_err();
    assert!(error.to_string().contains("initial position"), "{error}");
    // A term that reads past the last coordinate: an error naming it, before any evaluation.
    struct PastTheEnd;
    impl LocalLagrangian for PastTheEnd {
        type Width = nalgebra::Const<2>;
        fn dimension(&self) -> usize {
            3
        }
        fn term_count(&self) -> usize {
            3
        }
        fn indices(&self, term: usize) -> [usize; 2] {
            [term, term + 1]
        }
        fn term<D: Scalar>(&self, _: usize, _: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v[0] * v[0] - (q[1] - q[0]).powi(2)) * 0.5
        }
    }
    let zeros = DVector::zeros(3);
    for method in [
        svi::method::any::AnyMethod::StormerVerlet(StormerVerlet::default()),
        svi::method::any::AnyMethod::Svi(svi::Svi::new(4)),
    ] {
        let error = Integrator::new(Terms(PastTheEnd), method)
            .run_from_velocity(0.0, zeros.clone(), zeros.clone(), 0.1, 1.0, &mut ())
            .unwrap_err();
        assert!(
            error.to_string().contains("term 2 reads coordinate 3"),
            "{error}"
        );
    }
}

#[test]
fn svi_on_local_terms_follows_the_fixed_size_svi_to_round_off() {
    use svi::Svi;
    let model = fput(8);
    let fixed = FixedFput {
        alpha: model.alpha,
        beta: model.beta,
    };
    let (t0, q0, v0) = model.initial_state();
    let (h, t_end) = (0.5, 100.0);
    for method in [Svi::new(7).with_quadrature(6), Svi::new(4)] {
        let local = Integrator::new(Terms(model.clone()), method.clone())
            .run(
                t0,
                Initial::Velocity {
                    q: q0.clone(),
                    v: v0.clone(),
                },
                h,
                t_end,
                &mut (),
            )
            .unwrap();
        let qs = SVector::<f64, 8>::from_column_slice(q0.as_slice());
        let vs = SVector::<f64, 8>::from_column_slice(v0.as_slice());
        let reference = Integrator::new(FixedFput { ..fixed }, method)
            .run_from_velocity(t0, qs, vs, h, t_end, &mut ())
            .unwrap();
        for i in 0..8 {
            assert!(
                (local.last.q[i] - reference.last.q[i]).abs() < 1e-12,
                "q[{i}]"
            );
            assert!(
                (local.last.p[i] - reference.last.p[i]).abs() < 1e-12,
                "p[{i}]"
            );
        }
    }
}

#[test]
fn svi_on_local_terms_reaches_its_order_and_conserves_energy() {
    use svi::Svi;
    // SVI 4/3 is of order 6: halving h divides the error at T = 20 by 2⁶ (against a reference
    // of SVI 7/6, order 12, at h/4).
    let model = fput(16);
    let (t0, q0, v0) = model.initial_state();
    let run = |method: Svi, h: f64| {
        let mut energy = EnergyError::default();
        let run = Integrator::new(Terms(model.clone()), method)
            .run(
                t0,
                Initial::Velocity {
                    q: q0.clone(),
                    v: v0.clone(),
                },
                h,
                20.0,
                &mut energy,
            )
            .unwrap();
        (run.last.q, energy.max)
    };
    let (reference, _) = run(Svi::new(7).with_quadrature(6), 0.1);
    let (coarse, _) = run(Svi::new(4).with_quadrature(3), 0.8);
    let (fine, energy) = run(Svi::new(4).with_quadrature(3), 0.4);
    let order = ((&coarse - &reference).amax() / (&fine - &reference).amax()).log2();
    assert!((order - 6.0).abs() < 0.3, "observed order {order}");
    assert!(energy < 1e-8, "energy error {energy:e}");
}

#[test]
fn toda_lax_traces_match_a_dense_lax_matrix_and_stay_conserved() {
    use nalgebra::DMatrix;
    use svi::Svi;
    use svi::model::local::LocalInvariants;
    use svi::observer::InvariantError;
    use svi_models::Toda;
    // The traces from shifted diagonals against powers of the dense Lax matrix, for a ring
    // long enough that no power wraps around and for rings where they do.
    for n in [2, 3, 4, 9] {
        let mut model = Toda::default();
        model.set_parameter("n", n as f64).unwrap();
        let q = DVector::from_fn(n, |i, _| 0.3 * (1.7 * i as f64).sin());
        let p = DVector::from_fn(n, |i, _| 0.5 * (0.9 * i as f64).cos());
        let mut lax = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            let j = (i + 1) % n;
            let a = 0.5 * ((q[i] - q[j]) * 0.5).exp();
            lax[(i, i)] += -0.5 * p[i];
            lax[(i, j)] += a;
            lax[(j, i)] += a;
        }
        let traces = model.lax_traces(&q, &p, 4);
        let mut power = DMatrix::<f64>::identity(n, n);
        for (k, trace) in traces.iter().enumerate() {
            power = &power * &lax;
            assert!(
                (trace - power.trace()).abs() < 1e-13 * (1.0 + trace.abs()),
                "n = {n}, k = {}",
                k + 1
            );
        }
    }
    // tr 𝕃² is half the energy; SVI 6/5 keeps every trace to 1e-10 relative over 20 000 steps.
    let model = Toda::default();
    let (t0, q0, v0) = model.initial_state();
    let energy = LocalLagrangianExt::energy(&model, t0, &q0, &v0);
    assert!((model.invariant(1, t0, &q0, &v0) - 0.5 * energy).abs() < 1e-14 * energy);
    let mut invariants = InvariantError::default();
    Integrator::new(Terms(model.clone()), Svi::new(6).with_quadrature(5))
        .run(
            t0,
            Initial::Velocity {
                q: q0.clone(),
                v: v0.clone(),
            },
            0.1,
            2000.0,
            &mut invariants,
        )
        .unwrap();
    let scale = invariants
        .initial
        .iter()
        .fold(1.0f64, |m, x| m.max(x.abs()));
    assert!(
        invariants.max < 1e-10 * scale,
        "Lax trace error {:e}",
        invariants.max
    );
}

mod newton {
    use super::*;
    use svi::linalg::sparse::LinearSolverKind;
    use svi::{Solver, Svi};
    use svi_models::RelativisticChain;

    fn chain(n: usize) -> RelativisticChain {
        let mut model = RelativisticChain::default();
        model.set_parameter("n", n as f64).unwrap();
        model
    }

    #[test]
    fn sparse_and_dense_newton_take_the_same_step() {
        // One step of SVI 6/5 on the relativistic chain of 50 particles (300 unknowns), the
        // Newton systems solved by faer's sparse LU and by svi's dense LU.
        let model = chain(50);
        let (t0, q0, v0) = model.initial_state();
        let step = |kind| {
            let integrator = Integrator::new(
                Terms(model.clone()),
                Svi::new(6).with_quadrature(5).with_linear_solver(kind),
            );
            let start = integrator
                .initial_state(
                    t0,
                    &Initial::Velocity {
                        q: q0.clone(),
                        v: v0.clone(),
                    },
                )
                .unwrap();
            integrator.step(t0, &start, 0.2).unwrap().0
        };
        let (sparse, dense) = (
            step(LinearSolverKind::Sparse),
            step(LinearSolverKind::Dense),
        );
        let q = (&sparse.q - &dense.q).amax();
        let p = (&sparse.y - &dense.y).amax();
        assert!(q < 1e-12 && p < 1e-12, "q: {q:e}, p: {p:e}");
        assert!(sparse.q.amax() > 0.1, "the step moved");
    }

    #[test]
    fn the_inverse_legendre_map_matches_the_closed_form() {
        let model = chain(20);
        let (t0, q0, v0) = model.initial_state();
        let run = Integrator::new(Terms(model.clone()), Svi::new(4))
            .run(
                t0,
                Initial::Velocity {
                    q: q0,
                    v: v0.clone(),
                },
                0.1,
                1.0,
                &mut (),
            )
            .unwrap();
        for (v, p) in run.last.v.iter().zip(run.last.p.iter()) {
            assert!(
                (v - model.velocity(*p)).abs() < 1e-14,
                "{v} against {}",
                model.velocity(*p)
            );
        }
        assert!(run.last.v.amax() > 0.5, "relativistic speeds");
    }

    #[test]
    fn newton_reaches_the_order_and_conserves_energy_on_a_relativistic_chain() {
        // SVI 4/3 (order 6) with velocity-dependent mass: observed order at T = 5 against a
        // reference of SVI 7/6 (order 12); bounded energy error.
        let model = chain(12);
        let (t0, q0, v0) = model.initial_state();
        let run = |method: Svi, h: f64| {
            let mut energy = EnergyError::default();
            let run = Integrator::new(Terms(model.clone()), method)
                .run(
                    t0,
                    Initial::Velocity {
                        q: q0.clone(),
                        v: v0.clone(),
                    },
                    h,
                    5.0,
                    &mut energy,
                )
                .unwrap();
            (run.last.q, energy.max, run.statistics)
        };
        let (reference, _, _) = run(Svi::new(7).with_quadrature(6), 0.05);
        let (coarse, _, _) = run(Svi::new(4).with_quadrature(3), 0.5);
        let (fine, energy, statistics) = run(Svi::new(4).with_quadrature(3), 0.25);
        let order = ((&coarse - &reference).amax() / (&fine - &reference).amax()).log2();
        assert!((order - 6.0).abs() < 0.5, "observed order {order}");
        assert!(energy < 1e-7, "energy error {energy:e}");
        assert_eq!(statistics.steps, 20);
        // One symbolic analysis of the stage Jacobian's pattern for the whole run; the
        // simplified Newton iteration factorises less often than it steps.
        assert_eq!(statistics.analyses, 1);
        assert!(
            statistics.factorizations < statistics.steps,
            "{statistics:?}"
        );
    }

    #[test]
    fn sparse_newton_and_the_fixed_point_agree_on_a_constant_mass_chain() {
        let model = fput(16);
        let (t0, q0, v0) = model.initial_state();
        let run = |method: Svi| {
            Integrator::new(Terms(model.clone()), method)
                .run(
                    t0,
                    Initial::Velocity {
                        q: q0.clone(),
                        v: v0.clone(),
                    },
                    0.5,
                    50.0,
                    &mut (),
                )
                .unwrap()
                .last
        };
        let fixed = run(Svi::new(6).with_quadrature(5));
        let newton = run(Svi::new(6).with_quadrature(5).with_solver(Solver::Newton));
        assert!((&fixed.q - &newton.q).amax() < 1e-12);
        assert!((&fixed.p - &newton.p).amax() < 1e-12);
    }
}

#[test]
fn the_sine_gordon_chain_carries_its_kink_at_the_continuum_speed() {
    use svi::Svi;
    use svi_models::SineGordonChain;
    // A kink started at x₀ = −10 (checked) with V = 0.5 sits, at t = 20, at x₀ + V t = 0 (the
    // discretisation error of a = 0.1 moves it by far less than a spacing); energy bounded.
    let model = SineGordonChain::default();
    let (t0, q0, v0) = model.initial_state();
    assert!((model.kink_position(&q0) + 10.0).abs() < 1e-3);
    let mut energy = EnergyError::default();
    let run = Integrator::new(Terms(model.clone()), Svi::new(4).with_quadrature(3))
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            0.05,
            20.0,
            &mut energy,
        )
        .unwrap();
    let centre = model.kink_position(&run.last.q);
    assert!(centre.abs() < 0.05, "kink at {centre}");
    assert!(energy.max < 1e-8, "energy error {:e}", energy.max);
}

#[test]
fn fput_energy_leaves_mode_one_and_returns_near_the_recurrence_time() {
    use svi::Svi;
    use svi::observer::{Every, Points};
    // Fermi's run (n = 32, α = 0.25, all energy in mode 1): at t ≈ 5000 mode 1 holds under
    // 20 % of its initial energy, near t ≈ 10⁴ it is back above 90 % (measured: 98 % at
    // t ≈ 10130).
    let model = Fput::default();
    let (t0, q0, v0) = model.initial_state();
    let mut points = Every::new(50, Points::default());
    Integrator::new(Terms(model.clone()), Svi::new(4).with_quadrature(3))
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            0.2,
            11000.0,
            &mut points,
        )
        .unwrap();
    let first = &points.inner.points[0];
    let initial = model.mode_energies(&first.q, &first.v, 1)[0];
    let fraction = |window: std::ops::Range<f64>| {
        points
            .inner
            .points
            .iter()
            .filter(|p| window.contains(&p.t))
            .map(|p| model.mode_energies(&p.q, &p.v, 1)[0] / initial)
            .fold(0.0f64, f64::max)
    };
    let away = fraction(4500.0..5500.0);
    let back = fraction(9000.0..11000.0);
    assert!(away < 0.2, "mode 1 keeps {away} at t ≈ 5000");
    assert!(back > 0.9, "mode 1 recovers only {back}");
}

/// The Toda lattice's Lax traces (integrable: all four are conserved exactly by the flow)
/// over 10⁵ steps of SVI 6/5 (h = 0.1, T = 10⁴): every trace's error stays within 1e-10 of
/// its scale, and its drift fitted over windows of 1000 steps (slope × horizon) stays below the
/// oscillation amplitude or, where the error is round-off, below 1e-12 relative.
#[test]
fn toda_lax_traces_do_not_drift_over_a_hundred_thousand_steps() {
    use std::ops::ControlFlow;
    use svi::Svi;
    use svi::drift::EnergyWindows;
    use svi::model::local::LocalInvariants;
    use svi::observer::Observer;
    use svi::{Dyn, PhasePoint};
    use svi_models::Toda;

    /// Each trace's error, in windows.
    struct TraceWindows {
        initial: Vec<f64>,
        windows: Vec<EnergyWindows>,
    }
    impl Observer<Terms<Toda>, PhasePoint<Dyn>> for TraceWindows {
        fn observe(
            &mut self,
            model: &Terms<Toda>,
            _: usize,
            point: &PhasePoint<Dyn>,
        ) -> ControlFlow<()> {
            let traces = model.0.lax_traces(&point.q, &point.v, 4);
            if self.initial.is_empty() {
                self.initial = traces.clone();
            }
            for ((windows, trace), initial) in
                self.windows.iter_mut().zip(&traces).zip(&self.initial)
            {
                windows.push_error(point.t, trace - initial);
            }
            ControlFlow::Continue(())
        }
    }

    let model = Toda::default();
    assert_eq!(model.invariant_count(), 4);
    let (t0, q0, v0) = model.initial_state();
    let mut observer = TraceWindows {
        initial: Vec::new(),
        windows: (0..4).map(|_| EnergyWindows::new(1000)).collect(),
    };
    let (h, steps) = (0.1, 100_000);
    let run = Integrator::new(Terms(model.clone()), Svi::new(6).with_quadrature(5))
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            h,
            t0 + h * steps as f64,
            &mut observer,
        )
        .unwrap();
    assert_eq!(run.statistics.steps, steps);
    for (k, (windows, initial)) in observer.windows.iter().zip(&observer.initial).enumerate() {
        let scale = initial.abs().max(1.0);
        let fit = windows.fit().unwrap();
        assert!(fit.windows >= 100, "{} windows", fit.windows);
        eprintln!(
            "tr L^{}: max error {:.1e}, drift {:.1e}, amplitude {:.1e} (relative to {scale:.3})",
            k + 1,
            fit.max_error / scale,
            fit.drift / scale,
            fit.amplitude / scale
        );
        assert!(fit.max_error < 1e-10 * scale, "tr L^{}: {fit:?}", k + 1);
        assert!(
            fit.drift.abs() < fit.amplitude.max(1e-12 * scale),
            "tr L^{} drifts: {fit:?}",
            k + 1
        );
    }
}

/// A linear chain of n particles between fixed walls with the consistent mass matrix of
/// linear finite elements: spring e (0..=n) between particles e − 1 and e has kinetic energy
/// (v_l² + v_l v_r + v_r²)/6 and potential (q_r − q_l)²/2, so M = tridiag(1/6, 2/3, 1/6) is
/// coupled.
struct ConsistentChain {
    n: usize,
}

impl LocalLagrangian for ConsistentChain {
    type Width = nalgebra::Const<2>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn dimension(&self) -> usize {
        self.n
    }
    fn term_count(&self) -> usize {
        self.n + 1
    }
    fn indices(&self, e: usize) -> [usize; 2] {
        [e.saturating_sub(1), e.min(self.n - 1)]
    }
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
        let zero = D::from(0.0);
        let (ql, vl) = if e == 0 { (zero, zero) } else { (q[0], v[0]) };
        let (qr, vr) = if e == self.n {
            (zero, zero)
        } else {
            (q[1], v[1])
        };
        (vl * vl + vl * vr + vr * vr) / 6.0 - (qr - ql) * (qr - ql) * 0.5
    }
}

/// A coupled constant mass matrix runs at any n (faer's sparse LU, factored once): on the
/// consistent-mass chain of 5000 particles, started in its mode k = 2500 at rest, both
/// methods follow the exact standing wave qᵢ(t) = sin(iθ) cos(ωt), θ = πk/(n + 1),
/// ω² = (2 − 2 cos θ)/(2/3 + cos θ/3) (an eigenvector of both tridiagonal matrices): SVI 6/5
/// to 1e-10 at h = 0.1 and Störmer–Verlet to its O(h²) phase error at h = 0.01.
#[test]
fn a_coupled_mass_matrix_follows_the_exact_standing_wave() {
    use svi::Svi;
    let n = 5000;
    let theta = std::f64::consts::PI * 2500.0 / (n + 1) as f64;
    let omega = ((2.0 - 2.0 * theta.cos()) / (2.0 / 3.0 + theta.cos() / 3.0)).sqrt();
    let wave =
        |t: f64| DVector::from_fn(n, |i, _| ((i + 1) as f64 * theta).sin() * (omega * t).cos());
    let t_end = 5.0;
    let initial = Initial::Velocity {
        q: wave(0.0),
        v: DVector::zeros(n),
    };
    let model = || ConsistentChain { n };
    let svi = Integrator::new(Terms(model()), Svi::new(6).with_quadrature(5))
        .run(0.0, initial.clone(), 0.1, t_end, &mut ())
        .unwrap();
    let error = (&svi.last.q - wave(t_end)).amax();
    assert!(error < 1e-10, "svi: {error:e}");
    let verlet = Integrator::new(Terms(model()), StormerVerlet::default())
        .run(0.0, initial, 0.01, t_end, &mut ())
        .unwrap();
    let error = (&verlet.last.q - wave(t_end)).amax();
    // Phase error of Verlet: ω³h²t/24 ≈ 1.1e-4 for ω ≈ 1.73.
    let phase = omega.powi(3) * 1e-4 * t_end / 24.0;
    assert!(
        error < 2.0 * phase && error > 0.1 * phase,
        "verlet: {error:e} against {phase:e}"
    );
}

/// The stiff–soft FPU chain of HLW §I.5.1 (m = 3) with stiff frequency ω, resolved by SVI 4/3
/// at hω = 0.1 to T = 200: (max |I(t) − I(0)| of the total oscillatory energy, min I₁, max I₃,
/// max energy error).
fn stiff_soft_run(omega: f64) -> (f64, f64, f64, f64) {
    use svi::observer::{Every, Points};
    use svi_models::FputStiff;
    let mut model = FputStiff::default();
    model.set_parameter("omega", omega).unwrap();
    let (t0, q0, v0) = model.initial_state();
    let energy = LocalLagrangianExt::energy(&model, t0, &q0, &v0);
    let mut points = Every::new(20, Points::default());
    Integrator::new(Terms(model.clone()), svi::Svi::new(4).with_quadrature(3))
        .run(
            t0,
            Initial::Velocity { q: q0, v: v0 },
            0.1 / omega,
            200.0,
            &mut points,
        )
        .unwrap();
    let points = &points.inner.points;
    let largest = |f: &dyn Fn(&svi::PhasePoint<nalgebra::Dyn>) -> f64| {
        points.iter().map(f).fold(f64::NEG_INFINITY, f64::max)
    };
    let springs = |p: &svi::PhasePoint<nalgebra::Dyn>| model.oscillatory_energies(&p.q, &p.v);
    (
        largest(&|p| (springs(p).iter().sum::<f64>() - 1.0).abs()),
        -largest(&|p| -springs(p)[0]),
        largest(&|p| springs(p)[2]),
        largest(&|p| (LocalLagrangianExt::energy(&model, p.t, &p.q, &p.v) - energy).abs()),
    )
}

#[test]
fn the_stiff_soft_chain_has_hlws_energy_and_keeps_its_adiabatic_invariant() {
    use svi_models::FputStiff;
    // HLW §I.5.1 (m = 3, ω = 50): the initial energy from the Hamiltonian (I.5.1) in the
    // coordinates x₀ = 1, x₁ = 1/ω, ẋ₀ = ẋ₁ = 1 of the first stiff spring: kinetic 1, stiff
    // ω²x₁²/2 = 1/2, soft springs q₁⁴ + q₂⁴ (the walls' neighbours); I(0) = 1.
    let model = FputStiff::default();
    let omega = model.omega;
    let (t0, q0, v0) = model.initial_state();
    let (q1, q2) = (
        (1.0 - 1.0 / omega) / 2f64.sqrt(),
        (1.0 + 1.0 / omega) / 2f64.sqrt(),
    );
    let exact = 1.0 + 0.5 + q1.powi(4) + q2.powi(4);
    let energy = LocalLagrangianExt::energy(&model, t0, &q0, &v0);
    assert!(
        (energy - exact).abs() < 1e-14 * exact,
        "{energy} vs {exact}"
    );
    let initial: f64 = model.oscillatory_energies(&q0, &v0).iter().sum();
    assert!((initial - 1.0).abs() < 1e-14);
    // The total oscillatory energy I is an adiabatic invariant: I(t) − I(0) = O(1/ω), so
    // doubling ω halves its largest deviation; meanwhile the first spring hands its energy
    // on to the third on the time scale ω (HLW Fig. I.5.2), and the energy is conserved.
    // Measured: deviation 6.5e-2 at ω = 50; I₁ falls to 0.003, I₃ reaches 1.03.
    let (deviation, first, third, energy_error) = stiff_soft_run(50.0);
    let (finer, ..) = stiff_soft_run(100.0);
    let ratio = deviation / finer;
    assert!(deviation * omega < 5.0, "I deviates by {deviation:e}");
    assert!(
        (1.6..2.5).contains(&ratio),
        "deviation ratio {ratio} for ω × 2"
    );
    assert!(first < 0.1, "I₁ keeps at least {first}");
    assert!(third > 0.5, "I₃ reaches only {third}");
    assert!(
        energy_error < 1e-11 * energy,
        "energy error {energy_error:e}"
    );
}

/// A chain started at rest, where the stage offsets start from zero and their size is no
/// scale: the sine-Gordon chain (its fixed ends at 0 and 2π pull the last particle) from
/// q = q̇ = 0, which sparse Newton reported as non-convergence at step 0 with a last increment
/// of 6e-18 (its stopping rule measured increments against the starting offsets, all zero).
/// Newton and the fixed point run it, agree to round-off, and the FPUT chain at rest in its
/// ground state stays there exactly.
#[test]
fn chains_started_at_rest_run_with_every_solver() {
    use svi::Svi;
    use svi::method::variational::svi::Solver;
    use svi_models::SineGordonChain;
    let mut chain = SineGordonChain::default();
    chain.set_parameter("n", 8.0).unwrap();
    let rest = || Initial::Velocity {
        q: DVector::zeros(8),
        v: DVector::zeros(8),
    };
    let run = |method: Svi| {
        Integrator::new(Terms(chain.clone()), method)
            .run(0.0, rest(), 0.05, 2.0, &mut ())
            .unwrap()
            .last
    };
    let newton = run(Svi::new(4).with_solver(Solver::Newton));
    let fixed_point = run(Svi::new(4));
    assert!(newton.q.amax() > 1e-3, "the ends pull: {}", newton.q);
    assert!((newton.q - fixed_point.q).amax() < 1e-12);
    let ground = Integrator::new(Terms(fput(8)), Svi::new(4).with_solver(Solver::Newton))
        .run(0.0, rest(), 0.1, 10.0, &mut ())
        .unwrap();
    assert_eq!(ground.statistics.steps, 100);
    assert_eq!(ground.last.q.amax(), 0.0);
}

/// The explicit methods in velocity coordinates hand their observers p = M q̇ from the
/// constant mass matrix their run keeps (no derivative of L per observed point), and it is
/// the Lagrangian's ∂L/∂q̇: for a coupled M (the consistent-mass chain, sparse M) and a
/// diagonal one (the outer Solar System, masses from 1 to 1.7e-8).
#[test]
fn velocity_methods_observe_the_lagrangians_momentum_at_any_size() {
    use svi::method::reference::{ExplicitEuler, RungeKutta4};
    use svi::{Defaults, LagrangianExt, Method};
    fn check<L: Lagrangian<svi::Dyn>, M: Method<svi::Dyn>>(
        model: L,
        method: M,
        (q, v): (DVector<f64>, DVector<f64>),
        h: f64,
    ) {
        let mut observed = svi::observer::Points::default();
        let integrator = Integrator::new(model, method);
        integrator
            .run(0.0, Initial::Velocity { q, v }, h, 5.0 * h, &mut observed)
            .unwrap();
        assert_eq!(observed.points.len(), 6);
        for point in &observed.points {
            let p = integrator.model().momentum(point.t, &point.q, &point.v);
            let gap = (&point.p - &p).amax();
            assert!(gap <= 1e-15 * p.amax(), "t = {}: {gap:e}", point.t);
        }
    }
    let n = 40;
    let wave = DVector::from_fn(n, |i, _| (0.3 * i as f64).sin());
    let chain = (wave.clone(), wave.map(|x| 0.5 - x));
    check(
        Terms(ConsistentChain { n }),
        ExplicitEuler,
        chain.clone(),
        0.01,
    );
    check(Terms(ConsistentChain { n }), RungeKutta4, chain, 0.01);
    let sun = svi_models::NBody::outer_solar_system();
    let (_, q, v) = sun.initial_state();
    check(sun.clone(), ExplicitEuler, (q.clone(), v.clone()), 10.0);
    check(sun, RungeKutta4, (q, v), 10.0);
}
