//! `svi::solve`: output times, dense output, step and degree adaptivity, typed errors.
//!
//! Reference: the exact Kepler solution through Kepler's equation (`svi_models::Kepler`).

use nalgebra::{SVector, U2};
use svi::solve::{Adapt, SolveOptions, Span, solve};
use svi::{
    Defaults, Error, ExactSolution, Initial, Integrator, LagrangianExt, Method, Midpoint,
    SpectralCollocation, Svi, VariationalIntegrator,
};
use svi_models::Kepler;

fn kepler(e: f64) -> (Kepler, Initial<U2>) {
    let model = Kepler::new(e).unwrap();
    let (_, q, v) = model.initial_state();
    (model, Initial::Velocity { q, v })
}

/// Position error of a solution point against the exact Kepler orbit.
fn kepler_error(model: &Kepler, initial: &Initial<U2>, t: f64, q: &SVector<f64, 2>) -> f64 {
    let Initial::Velocity { q: q0, v: v0 } = initial else {
        unreachable!("the tests start from velocities")
    };
    let (exact, _) = model.exact_solution(0.0, q0, v0, t).unwrap();
    (q - exact).amax()
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift).
fn uniform(count: usize, mut seed: u64) -> Vec<f64> {
    (0..count)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

fn sorted_times(count: usize, t_end: f64) -> Vec<f64> {
    let mut times: Vec<f64> = uniform(count, 0x9e37_79b9_7f4a_7c15)
        .into_iter()
        .map(|u| u * t_end)
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
}

#[test]
fn fixed_step_output_at_grid_times_is_the_stepping_loops_result() {
    let (model, initial) = kepler(0.5);
    let h = 0.1;
    let times: Vec<f64> = (0..=50).map(|k| k as f64 * h).collect();
    let span = Span::with_outputs(0.0, 5.0, times.clone());
    let solution = solve(
        model,
        Svi::new(6).with_quadrature(5),
        &span,
        initial,
        &SolveOptions::fixed_step(h),
    )
    .unwrap();
    let run = Integrator::new(model, Svi::new(6).with_quadrature(5))
        .run(0.0, initial, h, 5.0, &mut ())
        .unwrap();
    assert_eq!(solution.points.len(), times.len());
    let last = solution.points.last().unwrap();
    assert_eq!(last.q, run.last.q);
    assert_eq!(last.p, run.last.p);
    assert_eq!(solution.statistics, run.statistics);
}

/// Dense output at 1000 random times inside the steps, against the exact solution: its error
/// is within a small multiple of the error at the step points.
fn dense_output_check<M: Method<U2> + Clone>(method: M, h: f64, t_end: f64, factor: f64) {
    let (model, initial) = kepler(0.5);
    let times = sorted_times(1000, t_end);
    let steps = (t_end / h).round() as usize;
    let grid: Vec<f64> = (0..=steps).map(|k| k as f64 * h).collect();
    let options = SolveOptions::fixed_step(h);
    let dense = solve(
        model,
        method.clone(),
        &Span::with_outputs(0.0, t_end, times.clone()),
        initial,
        &options,
    )
    .unwrap();
    let steps = solve(
        model,
        method,
        &Span::with_outputs(0.0, t_end, grid),
        initial,
        &options,
    )
    .unwrap();
    let step_error = steps
        .points
        .iter()
        .map(|p| kepler_error(&model, &initial, p.t, &p.q))
        .fold(0.0, f64::max);
    let mut dense_error: f64 = 0.0;
    let mut momentum_error: f64 = 0.0;
    for (point, &t) in dense.points.iter().zip(&times) {
        assert_eq!(point.t, t);
        dense_error = dense_error.max(kepler_error(&model, &initial, t, &point.q));
        // p at interior times is the Legendre map of the polynomial's (q, q̇).
        momentum_error =
            momentum_error.max((point.p - model.momentum(t, &point.q, &point.v)).amax());
    }
    eprintln!("h = {h}: step error {step_error:e}, dense error {dense_error:e}");
    assert_eq!(dense.points.len(), times.len());
    assert!(momentum_error < 1e-14);
    assert!(
        dense_error <= factor * step_error,
        "dense error {dense_error:e} vs step error {step_error:e}"
    );
}

#[test]
fn svi_dense_output_is_as_accurate_as_the_steps() {
    // The polynomial is accurate to O(h^(s+1)) inside the step and O(h^(2s)) at its ends, so the
    // comparison is made where the run's accumulated error matters: the Kepler scene's horizon.
    dense_output_check(Svi::new(7).with_quadrature(6), 0.2, 2000.0, 3.0);
}

#[test]
fn sc_dense_output_is_as_accurate_as_the_steps() {
    dense_output_check(SpectralCollocation::new(9), 0.1, 200.0, 3.0);
}

#[test]
fn classic_methods_interpolate_their_end_points() {
    dense_output_check(VariationalIntegrator::new(Midpoint), 0.005, 20.0, 3.0);
}

/// Fewest force evaluations of a fixed-step run of `method` reaching final error ≤ `target`
/// (a sweep over the number of steps).
fn best_fixed_step<M: Method<U2> + Clone>(
    model: &Kepler,
    initial: Initial<U2>,
    method: M,
    t_end: f64,
    target: f64,
) -> (usize, f64) {
    let mut steps = 16usize;
    loop {
        let h = t_end / steps as f64;
        // Steps too large for the nonlinear solve count as not reaching the target.
        if let Ok(solution) = solve(
            *model,
            method.clone(),
            &Span::new(0.0, t_end),
            initial,
            &SolveOptions::fixed_step(h),
        ) {
            let last = solution.points.last().unwrap();
            let error = kepler_error(model, &initial, t_end, &last.q);
            if error <= target {
                return (solution.statistics.evaluations, error);
            }
        }
        steps = steps * 9 / 8 + 1;
        assert!(steps < 1_000_000, "fixed steps never reached {target:e}");
    }
}

#[test]
fn step_adaptivity_beats_the_best_fixed_step_on_a_close_approach() {
    let (model, initial) = kepler(0.9);
    let t_end = 4.0 * std::f64::consts::TAU;
    let method = Svi::new(6).with_quadrature(5);
    for tol in [1e-6, 1e-9] {
        let adaptive = solve(
            model,
            method.clone(),
            &Span::new(0.0, t_end),
            initial,
            &SolveOptions::step_adaptive(tol),
        )
        .unwrap();
        let last = adaptive.points.last().unwrap();
        let error = kepler_error(&model, &initial, t_end, &last.q);
        let (fixed, fixed_error) = best_fixed_step(&model, initial, method.clone(), t_end, error);
        let a = &adaptive.adaptivity;
        eprintln!(
            "tol {tol:e}: adaptive error {error:e} with {} evaluations ({} accepted, {} rejected, \
             h in [{:e}, {:e}]); fixed step {fixed_error:e} with {fixed}",
            adaptive.statistics.evaluations, a.accepted, a.rejected, a.min_step, a.max_step
        );
        assert!(error <= 10.0 * tol);
        assert!(adaptive.statistics.evaluations < fixed);
        assert!(a.max_step > 10.0 * a.min_step);
    }
}

#[test]
fn degree_adaptivity_meets_its_tolerance_and_varies_the_degree() {
    let (model, initial) = kepler(0.5);
    let t_end = 10.0 * std::f64::consts::TAU;
    for (tol, h) in [(1e-6, 0.5), (1e-9, 0.5), (1e-12, 0.5)] {
        let solution = solve(
            model,
            Svi::new(5).with_quadrature(4),
            &Span::new(0.0, t_end),
            initial,
            &SolveOptions::degree_adaptive(h, tol, 3, 24),
        )
        .unwrap();
        let last = solution.points.last().unwrap();
        let error = kepler_error(&model, &initial, t_end, &last.q);
        eprintln!(
            "tol {tol:e}: error {error:e}, points {:?}, rejected {}, evaluations {}",
            solution.adaptivity.points,
            solution.adaptivity.rejected,
            solution.statistics.evaluations
        );
        assert!(error <= 10.0 * tol, "tol {tol:e}: error {error:e}");
        assert!(solution.adaptivity.points.len() >= 2);
        assert_eq!(solution.adaptivity.unmet, 0);
    }
}

#[test]
fn bad_tolerances_and_output_times_are_typed_errors() {
    let (model, initial) = kepler(0.5);
    let run = |span: Span, options: SolveOptions| {
        solve(model, Svi::new(4), &span, initial, &options).unwrap_err()
    };
    let name = |error: Error| match error {
        Error::InvalidParameter { name, .. } => name,
        other => panic!("expected an invalid parameter, got {other}"),
    };
    for tol in [0.0, -1e-6, f64::NAN, f64::INFINITY, 1e-20] {
        assert_eq!(
            name(run(Span::new(0.0, 1.0), SolveOptions::step_adaptive(tol))),
            "tol"
        );
    }
    let fixed = SolveOptions::fixed_step(0.1);
    assert_eq!(
        name(run(Span::times(&[0.0, 2.0, 1.0]), fixed.clone())),
        "output_times"
    );
    assert_eq!(
        name(run(Span::times(&[0.0, 1.0, 1.0]), fixed.clone())),
        "output_times"
    );
    assert_eq!(name(run(Span::times(&[]), fixed.clone())), "t0");
    assert_eq!(
        name(run(
            Span::with_outputs(0.0, 1.0, vec![0.5, 1.5]),
            fixed.clone()
        )),
        "output_times"
    );
    assert_eq!(
        name(run(Span::with_outputs(0.0, 1.0, vec![-0.5]), fixed.clone())),
        "output_times"
    );
    assert_eq!(
        name(run(
            Span::with_outputs(0.0, 1.0, vec![f64::NAN]),
            fixed.clone()
        )),
        "output_times[0]"
    );
    assert_eq!(name(run(Span::new(1.0, 1.0), fixed.clone())), "t_end");
    assert_eq!(
        name(run(Span::new(0.0, 1.0), SolveOptions::fixed_step(-0.1))),
        "h"
    );
    let mut no_tol = SolveOptions::degree_adaptive(0.1, 1e-8, 3, 10);
    no_tol.tol = None;
    assert_eq!(name(run(Span::new(0.0, 1.0), no_tol)), "tol");
    assert_eq!(
        name(run(
            Span::new(0.0, 1.0),
            SolveOptions::degree_adaptive(0.1, 1e-8, 1, 10)
        )),
        "points"
    );
    assert_eq!(
        name(run(
            Span::new(0.0, 1.0),
            SolveOptions::degree_adaptive(0.1, 1e-8, 8, 4)
        )),
        "points"
    );
    // Classic methods have no degree to adapt.
    let classic = solve(
        model,
        VariationalIntegrator::new(Midpoint),
        &Span::new(0.0, 1.0),
        initial,
        &SolveOptions::degree_adaptive(0.1, 1e-8, 3, 10),
    )
    .unwrap_err();
    assert_eq!(name(classic), "adapt");
    assert_eq!(
        "sometimes".parse::<Adapt>().map_err(name),
        Err("adapt".to_string())
    );
}

#[test]
fn a_tolerance_below_the_minimum_step_ends_in_a_typed_error() {
    let (model, initial) = kepler(0.99);
    let mut options = SolveOptions::step_adaptive(1e-12);
    options.min_step = Some(1e-2);
    let error = solve(
        model,
        Svi::new(3).with_quadrature(2),
        &Span::new(0.0, 10.0),
        initial,
        &options,
    )
    .unwrap_err();
    match error {
        Error::StepSizeTooSmall { h, min_step, .. } => {
            assert!(h < min_step);
            assert_eq!(min_step, 1e-2);
        }
        other => panic!("expected StepSizeTooSmall, got {other}"),
    }
}

/// Stops the run at the first observed point at or after `at`.
struct StopAt {
    at: f64,
    seen: Vec<(usize, f64)>,
}

impl<L> svi::observer::Observer<L, svi::PhasePoint<U2>> for StopAt {
    fn observe(
        &mut self,
        _: &L,
        step: usize,
        point: &svi::PhasePoint<U2>,
    ) -> std::ops::ControlFlow<()> {
        self.seen.push((step, point.t));
        if point.t >= self.at {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    }
}

#[test]
fn every_solve_mode_reports_its_accepted_steps_to_observers() {
    // The solve modes run on the stepping loop of `Integrator::try_run`: observers see the
    // initial point and every accepted step, numbered 0, 1, 2, …, at increasing times, and
    // the last one is the solution's end point.
    let (model, initial) = kepler(0.5);
    let integrator = Integrator::new(model, Svi::new(6).with_quadrature(5));
    let span = Span::new(0.0, 10.0);
    for options in [
        SolveOptions::fixed_step(0.1),
        SolveOptions::step_adaptive(1e-8),
        SolveOptions::degree_adaptive(0.25, 1e-9, 3, 12),
    ] {
        let mut trajectory = svi::observer::Trajectory::new();
        let solution = integrator
            .try_solve(&span, initial, &options, &mut trajectory)
            .unwrap();
        let points = &trajectory.points;
        assert_eq!(
            points.len(),
            solution.adaptivity.accepted + 1,
            "{:?}",
            options.adapt
        );
        assert!(points.windows(2).all(|pair| pair[0].t < pair[1].t));
        assert_eq!(points[0].t, 0.0);
        let end = points.last().unwrap();
        assert_eq!(end.t, 10.0);
        assert_eq!(end.q, solution.last.q);
        assert!((end.v - solution.last.v).amax() < 1e-14);
        assert!(kepler_error(&model, &initial, end.t, &end.q) < 1e-6);
        assert!(!solution.stopped);
    }
}

#[test]
fn an_observer_stops_a_solve_where_it_asks() {
    let (model, initial) = kepler(0.5);
    let integrator = Integrator::new(model, Svi::new(6).with_quadrature(5));
    for options in [
        SolveOptions::fixed_step(0.1),
        SolveOptions::step_adaptive(1e-8),
        SolveOptions::degree_adaptive(0.25, 1e-9, 3, 12),
    ] {
        let mut stop = StopAt {
            at: 3.0,
            seen: Vec::new(),
        };
        let solution = integrator
            .try_solve(&Span::new(0.0, 10.0), initial, &options, &mut stop)
            .unwrap();
        assert!(solution.stopped);
        let &(step, t) = stop.seen.last().unwrap();
        let (_, before) = stop.seen[stop.seen.len() - 2];
        assert!(
            before < 3.0 && t >= 3.0,
            "{:?}: stopped at {t}",
            options.adapt
        );
        assert_eq!(solution.last.t, t);
        assert_eq!(step + 1, stop.seen.len());
        // The output times up to the stop are served: here the start only.
        assert_eq!(solution.points.len(), 1);
    }
}

#[test]
fn recovery_and_divergence_limit_apply_to_fixed_step_solves() {
    // e = 0.95 with h = 0.11: a step fails at step 26 (as in `Integrator::try_run`);
    // halving failed steps gets the solve through, on the same grid.
    let (model, initial) = kepler(0.95);
    let integrator = Integrator::new(model, Svi::new(6));
    let span = Span::new(0.0, 200.0);
    let plain = SolveOptions::fixed_step(0.11);
    let failure = integrator
        .try_solve(&span, initial, &plain, &mut ())
        .unwrap_err();
    assert!(matches!(failure.error, Error::NonConvergence { .. }));
    let mut options = SolveOptions::fixed_step(0.2);
    options.run =
        svi::RunOptions::default().with_recovery(svi::Recovery::HalveStep { max_halvings: 4 });
    let solution = integrator.solve(&span, initial, &options).unwrap();
    let run = integrator
        .try_run(0.0, initial, 0.2, 200.0, &options.run, &mut ())
        .unwrap();
    assert_eq!(solution.last.q, run.last.q);
    assert_eq!(solution.statistics, run.statistics);
    assert!(run.statistics.retries > 0);
    // A divergence limit below the orbit's size stops the solve at the first step beyond it.
    options.run = svi::RunOptions::default().with_divergence_limit(0.5);
    let failure = integrator
        .try_solve(&span, initial, &options, &mut ())
        .unwrap_err();
    let Error::Diverged { norm, limit, .. } = failure.error else {
        panic!("{failure}")
    };
    assert!(norm > 0.5 && limit == 0.5);
    assert!(failure.partial.unwrap().last.q.amax() <= 0.5);
    // Recovery is for fixed steps: the adaptive modes retry failed steps themselves.
    let mut adaptive = SolveOptions::step_adaptive(1e-8);
    adaptive.run =
        svi::RunOptions::default().with_recovery(svi::Recovery::HalveStep { max_halvings: 4 });
    let Err(Error::InvalidParameter { name, .. }) = integrator.solve(&span, initial, &adaptive)
    else {
        panic!("recovery with step adaptivity must be rejected")
    };
    assert_eq!(name, "recovery");
}

#[test]
fn steps_below_the_resolution_of_the_times_are_typed_errors() {
    // At t ≈ 1e16 neighbouring doubles are 2 apart: no step mode may run on such a grid.
    let (model, initial) = kepler(0.5);
    let integrator = Integrator::new(model, Svi::new(6));
    // A span of 2 there is shorter than any resolvable step (1000 spacings).
    let short = Span::new(1e16, 1e16 + 2.0);
    for options in [
        SolveOptions::fixed_step(0.4),
        SolveOptions::degree_adaptive(0.4, 1e-8, 3, 8),
        SolveOptions::step_adaptive(1e-8),
    ] {
        assert_eq!(
            name_of(integrator.solve(&short, initial, &options)),
            "t_end"
        );
    }
    let run = integrator.run(1e16, initial, 0.4, 1e16 + 2.0, &mut ());
    assert_eq!(name_of(run), "t_end");
    // A long enough span, but a step below the resolution.
    let long = Span::new(1e16, 1e16 + 1e5);
    assert_eq!(
        name_of(integrator.solve(&long, initial, &SolveOptions::fixed_step(0.4))),
        "h"
    );
    let mut options = SolveOptions::step_adaptive(1e-8);
    options.min_step = Some(0.4);
    assert_eq!(
        name_of(integrator.solve(&long, initial, &options)),
        "min_step"
    );
    // A minimum step above the maximum is an error, not a panic.
    let mut options = SolveOptions::step_adaptive(1e-8);
    options.min_step = Some(1.0);
    options.max_step = Some(0.1);
    assert_eq!(
        name_of(integrator.solve(&Span::new(0.0, 10.0), initial, &options)),
        "min_step"
    );
}

fn name_of<T: std::fmt::Debug>(result: Result<T, Error>) -> String {
    match result {
        Err(Error::InvalidParameter { name, .. }) => name,
        other => panic!("expected a typed error, got {other:?}"),
    }
}

#[test]
fn a_non_finite_output_point_is_an_error_not_a_silent_nan() {
    // Found by the hostile suite: a subnormal step (h = 6.6e-309) integrates, but its step
    // polynomial, read off inside the step, has an infinite slope. The output point is
    // non-finite, and the run says so instead of returning NaN with success.
    let (model, initial) = kepler(0.5);
    let h = 6.6123807894145e-309;
    let result = solve(
        model,
        Svi::new(6),
        &Span::with_outputs(0.0, 2000.0 * h, vec![4.67111811255018e-309]),
        initial,
        &SolveOptions::fixed_step(h),
    );
    match result {
        Err(Error::NonFinite { what, step, .. }) => {
            assert!(what.contains("output point"), "{what}");
            // The first step (index 0, from t = 0) holds the output time.
            assert_eq!(step, 0);
        }
        other => panic!("expected a non-finite output point, got {other:?}"),
    }
}

/// The run of `options` on Kepler e = 0.99 over a span of 100 with a budget of `budget`
/// steps: it ends in `TooManySteps` at the budget, with the run so far kept.
fn out_of_budget(method: impl Method<U2> + Clone, mut options: SolveOptions, budget: usize) {
    let (model, initial) = kepler(0.99);
    options.max_steps = budget;
    let failure = Integrator::new(model, method)
        .try_solve(&Span::new(0.0, 100.0), initial, &options, &mut ())
        .unwrap_err();
    let Error::TooManySteps { step, t, max_steps } = failure.error else {
        panic!(
            "{}: expected TooManySteps, got {}",
            options.adapt, failure.error
        )
    };
    assert_eq!((step, max_steps), (budget, budget), "{}", options.adapt);
    let partial = failure.partial.expect("the run so far");
    assert_eq!(partial.statistics.steps, budget, "{}", options.adapt);
    assert_eq!(partial.last.t, t);
    assert!(
        t > 0.0 && t < 100.0,
        "{}: stopped at t = {t}",
        options.adapt
    );
}

#[test]
fn an_adaptive_solve_out_of_steps_ends_in_a_typed_error_with_the_run_so_far() {
    out_of_budget(Svi::new(4), SolveOptions::step_adaptive(1e-10), 50);
    out_of_budget(
        Svi::new(4),
        SolveOptions::degree_adaptive(0.01, 1e-10, 3, 8),
        40,
    );
    out_of_budget(Svi::new(4), SolveOptions::energy_fitted(0.01), 30);
    // A fixed grid that needs more steps is rejected before it starts.
    let (model, initial) = kepler(0.5);
    let mut options = SolveOptions::fixed_step(0.1);
    options.max_steps = 99;
    let error = solve(model, Svi::new(3), &Span::new(0.0, 10.0), initial, &options).unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "max_steps"),
        "{error}"
    );
    options.max_steps = 100;
    assert!(solve(model, Svi::new(3), &Span::new(0.0, 10.0), initial, &options).is_ok());
    options.max_steps = 0;
    assert!(solve(model, Svi::new(3), &Span::new(0.0, 10.0), initial, &options).is_err());
}

#[test]
fn a_reparametrized_solve_out_of_steps_ends_in_a_typed_error() {
    use svi::model::reparametrized::{Potential, Sundman};
    use svi::stepping::reparam::solve_reparametrized;
    let (model, initial) = kepler(0.9);
    let mut options = SolveOptions::fixed_step(0.01);
    options.max_steps = 25;
    let span = Span::new(0.0, 100.0);
    for error in [
        solve_reparametrized(
            model,
            Svi::new(4),
            Sundman { alpha: 1.5 },
            &span,
            initial,
            &options,
        ),
        solve_reparametrized(
            model,
            svi::StormerVerlet::default(),
            Potential,
            &span,
            initial,
            &options,
        ),
    ]
    .map(Result::unwrap_err)
    {
        assert!(
            matches!(error, Error::TooManySteps { step: 25, max_steps: 25, t } if t > 0.0),
            "{error}"
        );
    }
}

/// Solve Kepler e = 0.5 to `t_end` twice with `method` and `options`: once keeping the dense
/// output, once serving `times` during the solve; the kept polynomials evaluated afterwards
/// give the output points' q, q̇ and p to `tol` relative to 1 + |x|, and the two solves the
/// same steps.
fn kept_matches_served<M: Method<U2> + Clone>(method: M, mut options: SolveOptions, tol: f64) {
    let (model, initial) = kepler(0.5);
    let t_end = 20.0;
    let times = sorted_times(1000, t_end);
    let served = solve(
        model,
        method.clone(),
        &Span::with_outputs(0.0, t_end, times.clone()),
        initial,
        &options,
    )
    .unwrap();
    options.dense = true;
    let kept = solve(model, method, &Span::new(0.0, t_end), initial, &options).unwrap();
    assert_eq!(kept.statistics.steps, served.statistics.steps);
    assert!(served.dense.is_none());
    let dense = kept.dense.expect("asked for");
    assert_eq!(dense.span(), Some((0.0, t_end)));
    let mut worst: f64 = 0.0;
    for (point, &t) in served.points.iter().zip(&times) {
        let at = dense.at(t).unwrap();
        // p is kept at the samples: a polynomial again, as Kepler's mass is constant. The
        // difference is relative to the size of the number (1 + |x|): rounding in the
        // barycentric sums.
        for (kept, served) in [(&at.q, &point.q), (&at.v, &point.v), (&at.p, &point.p)] {
            for (a, b) in kept.iter().zip(served.iter()) {
                worst = worst.max((a - b).abs() / (1.0 + b.abs()));
            }
        }
    }
    eprintln!("kept against served dense output: {worst:e}");
    assert!(worst < tol, "{worst:e}");
    // At the end, the last step's polynomial meets the solve's last point.
    let end = dense.at(t_end).unwrap();
    assert!((end.q[0] - kept.last.q[0]).abs() < 1e-12);
}

/// `sol(t)`: the polynomials kept over a whole solve are the method's own dense output
/// (SVI and SC: the step polynomial; midpoint: the cubic Hermite interpolant of its end
/// points), in every mode — fixed steps, step doubling (whose half steps are kept, the
/// rejected trials forgotten) and degree adaptivity (as many samples as the most points).
#[test]
fn kept_dense_output_is_the_methods_dense_output_at_any_time() {
    kept_matches_served(
        Svi::new(7).with_quadrature(6),
        SolveOptions::fixed_step(0.1),
        1e-14,
    );
    kept_matches_served(
        SpectralCollocation::new(9),
        SolveOptions::fixed_step(0.1),
        1e-14,
    );
    // The Hermite interpolant's q̇ divides differences of q by h: its own rounding, 1e-16/h,
    // is what the kept samples reproduce.
    kept_matches_served(
        VariationalIntegrator::new(Midpoint),
        SolveOptions::fixed_step(0.01),
        1e-13,
    );
    kept_matches_served(Svi::new(6), SolveOptions::step_adaptive(1e-9), 1e-14);
    kept_matches_served(
        Svi::new(6),
        SolveOptions::degree_adaptive(0.2, 1e-9, 3, 12),
        1e-14,
    );
}

/// Dense output between steps is as accurate as the method: SVI 7/6 on the oscillator
/// q = cos t, evaluated at 1000 times, against the exact solution, with the error falling
/// at the order of the step polynomial inside steps (s = 7 points: O(h^7) at least).
#[test]
fn kept_dense_output_converges_to_the_exact_solution_between_steps() {
    let errors: Vec<f64> = [0.4, 0.2]
        .iter()
        .map(|&h| {
            let mut options = SolveOptions::fixed_step(h);
            options.dense = true;
            let initial = Initial::Velocity {
                q: nalgebra::SVector::from([1.0]),
                v: nalgebra::SVector::from([0.0]),
            };
            let solution = solve(
                svi_models::HarmonicOscillator::new(1.0).unwrap(),
                Svi::new(7).with_quadrature(6),
                &Span::new(0.0, 8.0),
                initial,
                &options,
            )
            .unwrap();
            let dense = solution.dense.unwrap();
            sorted_times(1000, 8.0)
                .iter()
                .map(|&t| {
                    let at = dense.at(t).unwrap();
                    (at.q[0] - t.cos()).abs().max((at.v[0] + t.sin()).abs())
                })
                .fold(0.0, f64::max)
        })
        .collect();
    eprintln!("oscillator dense errors at h = 0.4, 0.2: {errors:?}");
    let order = (errors[0] / errors[1]).log2();
    assert!(errors[1] < 1e-8, "{errors:?}");
    assert!(order > 6.0, "observed order {order}");
}

/// Dense output is refused where no polynomials are kept: the reparametrised solve, a time
/// outside the span.
#[test]
fn dense_output_where_it_cannot_be_kept_is_a_typed_error() {
    use svi::model::reparametrized::Sundman;
    use svi::stepping::reparam::solve_reparametrized;
    let (model, initial) = kepler(0.5);
    let mut options = SolveOptions::fixed_step(0.1);
    options.dense = true;
    let span = Span::new(0.0, 1.0);
    let error = solve_reparametrized(
        model,
        Svi::new(4),
        Sundman { alpha: 1.5 },
        &span,
        initial,
        &options,
    )
    .unwrap_err();
    assert!(
        matches!(&error, Error::InvalidParameter { name, .. } if name == "dense"),
        "{error}"
    );
    let dense = solve(model, Svi::new(4), &span, initial, &options)
        .unwrap()
        .dense
        .unwrap();
    for t in [-0.1, 1.1, f64::INFINITY] {
        assert!(
            matches!(dense.at(t), Err(Error::InvalidParameter { .. })),
            "{t}"
        );
    }
}
