//! Events located on the step polynomials (`svi::stepping::event`): Kepler's pericentre
//! passages against the exact times, the oscillator's zero crossings at the method's order,
//! terminal events, directions and typed errors.
//!
//! References: the exact Kepler orbit through Kepler's equation (`svi_models::Kepler`), whose
//! pericentre passages from a start at pericentre are t = 2πk (a = 1); q = sin t of the
//! oscillator, zero at t = kπ.

use std::f64::consts::{PI, TAU};

use nalgebra::{U1, U2};
use svi::solve::{SolveOptions, Span};
use svi::stepping::event::{Direction, Event, EventFunction};
use svi::{Defaults, Error, ExactSolution, Initial, Integrator, Scalar, StormerVerlet, Svi};
use svi_models::{HarmonicOscillator, Kepler};

/// r·ṙ = q·q̇, rising through zero at pericentre, written once for any scalar.
struct RadialVelocity;

impl EventFunction for RadialVelocity {
    fn value<D: Scalar>(&self, _t: D, q: &[D], v: &[D]) -> D {
        q[0] * v[0] + q[1] * v[1]
    }
}

fn kepler(e: f64) -> (Kepler, Initial<U2>) {
    let model = Kepler::new(e).unwrap();
    let (_, q, v) = model.initial_state();
    (model, Initial::Velocity { q, v })
}

/// Kepler e = 0.5 to T = 2000 with SVI 9/8 at `steps` fixed steps: the final position
/// error, the pericentre passages' time errors against 2πk, and the largest distance in
/// time of an event point from its own crossing, |g|/|ġ|.
fn pericentres(steps: usize) -> (f64, Vec<f64>, f64) {
    let (model, initial) = kepler(0.5);
    let t_end = 2000.0;
    let h = t_end / steps as f64;
    let integrator = Integrator::new(model, Svi::new(9).with_quadrature(8));
    let events = [Event::from_function("pericentre", RadialVelocity).direction(Direction::Up)];
    let solution = integrator
        .try_solve_events(
            &Span::new(0.0, t_end),
            initial,
            &SolveOptions::fixed_step(h),
            &events,
            &mut (),
        )
        .unwrap();
    let Initial::Velocity { q: q0, v: v0 } = initial else {
        unreachable!()
    };
    let (exact, _) = model.exact_solution(0.0, &q0, &v0, t_end).unwrap();
    let error = (solution.last.q - exact).amax();
    let errors = solution
        .events
        .iter()
        .enumerate()
        .map(|(k, event)| event.point.t - TAU * (k + 1) as f64)
        .collect();
    let residual = solution
        .events
        .iter()
        .map(|event| {
            let (q, v) = (&event.point.q, &event.point.v);
            let rate = v.norm_squared() - 1.0 / q.norm();
            (q.dot(v) / rate).abs()
        })
        .fold(0.0, f64::max);
    (error, errors, residual)
}

/// SVI 9/8 at 7500 steps ends 1e-9 from the exact orbit at T = 2000. Each located
/// pericentre lies on the run's own trajectory to round-off (g = q·q̇ at the event point,
/// over its rate ġ = |q̇|² − 1/r, is below 1e-12 in time, four units of round-off at t = 2000), so its time errs by the run's
/// phase error at that time, which grows linearly: every passage within its share k/318 of
/// the last one's error (plus 1e-12), the last within the final error's time equivalent.
/// The step polynomial alone (without the refinement by exact steps) errs by 1e-7 there:
/// its velocity is a derivative of degree 8.
#[test]
fn kepler_pericentre_passages_carry_only_the_runs_phase_error() {
    let (error, times, residual) = pericentres(7500);
    let early = times[..10].iter().fold(0.0f64, |m, e| m.max(e.abs()));
    let last = times[317].abs();
    println!(
        "SVI 9/8, 7500 steps: final error {error:.2e}; pericentre time errors: first ten \
         within {early:.1e}, last {last:.1e}; off the run's own crossing {residual:.1e}"
    );
    assert!(error < 1.5e-9, "{error:e}");
    assert_eq!(times.len(), 318);
    assert!(residual < 1e-12, "{residual:e}");
    assert!(last < 2.0 * error, "{last:e} against {error:e}");
    for (k, delta) in times.iter().enumerate() {
        let share = (k + 1) as f64 / 318.0;
        assert!(
            delta.abs() <= 1.2 * share * last + 1e-12,
            "passage {k}: {delta:e}"
        );
    }
}

/// The oscillator q = sin t from q = 0, q̇ = 1 with `method` at step `h` to T = 20: the worst
/// error of its zero crossings (t = kπ) over the run.
fn crossing_error<M: svi::Method<U1> + Clone>(method: M, h: f64) -> f64 {
    let model = HarmonicOscillator::default();
    let (_, q, v) = model.initial_state();
    let events = [Event::new("zero", |_, q, _| q[0])];
    let solution = Integrator::new(model, method)
        .try_solve_events(
            &Span::new(0.0, 20.0),
            Initial::Velocity { q, v },
            &SolveOptions::fixed_step(h),
            &events,
            &mut (),
        )
        .unwrap();
    assert_eq!(solution.events.len(), 6, "h = {h}");
    solution
        .events
        .iter()
        .enumerate()
        .map(|(k, event)| (event.point.t - PI * (k + 1) as f64).abs())
        .fold(0.0, f64::max)
}

/// Zero crossings of the oscillator converge at the method's order at its step points,
/// 2s − 2 for SVI with s points (the Galerkin superconvergence) and 2 for Störmer–Verlet:
/// the refinement by exact steps carries it inside the steps.
#[test]
fn oscillator_crossings_converge_at_the_methods_order() {
    let observed = |errors: [f64; 3]| {
        [
            (errors[0] / errors[1]).log2(),
            (errors[1] / errors[2]).log2(),
        ]
    };
    let steps = [0.4, 0.2, 0.1];
    println!("| method | error h = 0.4 | 0.2 | 0.1 | orders |");
    for s in 2..=5 {
        let errors = steps.map(|h| crossing_error(Svi::new(s).with_quadrature(s), h));
        let orders = observed(errors);
        println!(
            "| svi:{s}/{s} | {:.1e} | {:.1e} | {:.1e} | {:.2}, {:.2} |",
            errors[0], errors[1], errors[2], orders[0], orders[1]
        );
        let expected = (2 * s - 2) as f64;
        // The last ratio of s = 5 reaches round-off (7e-15).
        assert!(
            (orders[0] - expected).abs() < 0.1,
            "svi:{s}/{s}: {orders:?}"
        );
        assert!(
            errors[2] < 1e-13 || (orders[1] - expected).abs() < 0.1,
            "svi:{s}/{s}: {orders:?}"
        );
    }
    let errors = steps.map(|h| crossing_error(StormerVerlet::default(), h));
    let orders = observed(errors);
    println!(
        "| verlet | {:.1e} | {:.1e} | {:.1e} | {:.2}, {:.2} |",
        errors[0], errors[1], errors[2], orders[0], orders[1]
    );
    assert!(
        orders.iter().all(|order| (order - 2.0).abs() < 0.1),
        "{orders:?}"
    );
}

/// A terminal event ends the solve at its time: the last point is the event's, output times
/// after it are not served, and the steps stop with the step that holds it.
#[test]
fn a_terminal_event_ends_the_solve_at_its_time() {
    let (model, initial) = kepler(0.5);
    let h = 0.05;
    let events = [
        Event::from_function("pericentre", RadialVelocity)
            .direction(Direction::Up)
            .terminal(true),
        Event::from_function("apocentre", RadialVelocity).direction(Direction::Down),
    ];
    let span = Span::with_outputs(0.0, 100.0, vec![0.0, 3.0, 6.0, 7.0, 100.0]);
    let solution = Integrator::new(model, Svi::new(8).with_quadrature(7))
        .try_solve_events(
            &span,
            initial,
            &SolveOptions::fixed_step(h),
            &events,
            &mut (),
        )
        .unwrap();
    // Apocentre at π (not terminal), then the first pericentre at 2π ends the run.
    assert_eq!(solution.events.len(), 2);
    assert_eq!(solution.events[0].event, 1);
    assert!((solution.events[0].point.t - PI).abs() < 1e-10);
    assert_eq!(solution.terminal, Some(1));
    assert!((solution.last.t - TAU).abs() < 1e-10, "{}", solution.last.t);
    assert_eq!(solution.last, solution.events[1].point);
    assert!(!solution.stopped);
    let served: Vec<f64> = solution.points.iter().map(|point| point.t).collect();
    assert_eq!(served, [0.0, 3.0, 6.0]);
    assert_eq!(solution.statistics.steps, (TAU / h).ceil() as usize);
}

/// The step-adaptive and the energy-fitted solves locate the same passages (to their
/// tolerance), and a rejected trial step leaves no event behind.
#[test]
fn adaptive_solves_locate_the_same_events() {
    let (model, initial) = kepler(0.9);
    let events = [Event::from_function("pericentre", RadialVelocity).direction(Direction::Up)];
    let integrator = Integrator::new(model, Svi::new(8).with_quadrature(7));
    // To 20.5 periods: a passage at the span's very end is found or not by round-off.
    let solution = integrator
        .try_solve_events(
            &Span::new(0.0, 20.5 * TAU),
            initial,
            &SolveOptions::step_adaptive(1e-10),
            &events,
            &mut (),
        )
        .unwrap();
    assert!(
        solution.adaptivity.rejected > 0,
        "{:?}",
        solution.adaptivity
    );
    assert_eq!(solution.events.len(), 20);
    for (k, event) in solution.events.iter().enumerate() {
        assert!(
            (event.point.t - TAU * (k + 1) as f64).abs() < 1e-8,
            "{k}: {}",
            event.point.t
        );
    }
}

/// Two crossings inside one step are seen by the interior samples, and missed without.
#[test]
fn interior_samples_see_two_crossings_inside_one_step() {
    let model = HarmonicOscillator::default();
    let (_, q, v) = model.initial_state();
    // sin t = 0.9 at t = 1.120 and 2.022, both inside the first step [0, 2.5].
    let events = [Event::new("high", |_, q, _| q[0] - 0.9)];
    let run = |samples: usize| {
        let mut options = SolveOptions::fixed_step(2.5);
        options.event_samples = samples;
        Integrator::new(model, Svi::new(12).with_quadrature(12))
            .try_solve_events(
                &Span::new(0.0, 2.5),
                Initial::Velocity { q, v },
                &options,
                &events,
                &mut (),
            )
            .unwrap()
    };
    assert!(run(0).events.is_empty());
    let found = run(4).events;
    assert_eq!(found.len(), 2);
    let first = 0.9f64.asin();
    assert!(
        (found[0].point.t - first).abs() < 1e-9,
        "{}",
        found[0].point.t
    );
    assert!(
        (found[1].point.t - (PI - first)).abs() < 1e-9,
        "{}",
        found[1].point.t
    );
}

#[test]
fn bad_events_are_typed_errors_naming_them() {
    let (model, initial) = kepler(0.5);
    let integrator = Integrator::new(model, Svi::new(5).with_quadrature(4));
    let span = Span::new(0.0, 10.0);
    let options = SolveOptions::fixed_step(0.1);
    // Non-finite from the start, and from some time on.
    for event in [
        Event::new("broken", |_, _, _| f64::NAN),
        Event::new(
            "broken",
            |t, _, _| if t > 5.0 { f64::INFINITY } else { 1.0 },
        ),
    ] {
        let failure = integrator
            .try_solve_events(&span, initial, &options, &[event], &mut ())
            .unwrap_err();
        assert!(
            matches!(failure.error, Error::NonFinite { .. }),
            "{}",
            failure.error
        );
        assert!(
            failure.error.to_string().contains("event 'broken'"),
            "{}",
            failure.error
        );
    }
    // A solve that fails keeps the events located before: the apocentres (y falling
    // through 0) at π and 3π, on every driver.
    for adapt in [
        SolveOptions::fixed_step(0.1),
        SolveOptions::step_adaptive(1e-10),
    ] {
        let events = [
            Event::new("apocentre", |_, q, _| q[1]).direction(Direction::Down),
            Event::new("late", |t, _, _| if t > 11.0 { f64::NAN } else { 1.0 }),
        ];
        let failure = integrator
            .try_solve_events(&Span::new(0.0, 20.0), initial, &adapt, &events, &mut ())
            .unwrap_err();
        assert!(
            failure.error.to_string().contains("event 'late'"),
            "{}",
            failure.error
        );
        let times: Vec<f64> = failure.events.iter().map(|e| e.point.t).collect();
        assert_eq!(times.len(), 2, "{times:?}");
        for (k, t) in times.iter().enumerate() {
            assert!((t - PI * (2 * k + 1) as f64).abs() < 1e-7, "{times:?}");
        }
        assert!(failure.events.iter().all(|e| e.event == 0));
    }
    let mut options = options;
    options.event_samples = 1_000_000;
    let events = [Event::new("fine", |_, q, _| q[0])];
    let failure = integrator
        .try_solve_events(&span, initial, &options, &events, &mut ())
        .unwrap_err();
    assert!(
        failure.error.to_string().contains("event_samples"),
        "{}",
        failure.error
    );
}
