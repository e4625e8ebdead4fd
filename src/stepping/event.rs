//! Events: the times at which a function g(t, q, q̇) of the solution crosses zero, located on
//! each step's own polynomial.
//!
//! A spectral method's step is a polynomial q(t) of degree s − 1 through its nodes (the dense
//! output of [`crate::method::Step::dense_point`]), as accurate inside the step as the
//! interpolation of the exact solution at s points, O(hˢ); methods without one give the cubic
//! Hermite interpolant of the step's end points, O(h⁴). After every accepted step g is sampled
//! at the step's end and at [`SolveOptions::event_samples`](crate::solve::SolveOptions)
//! equally spaced interior times (so two crossings inside one step are seen when a sample
//! lies between them), and each sign change in the event's [`Direction`] is bracketed and
//! refined by Brent's method (argmin's [`BrentRoot`]) on the same polynomial to a few units of
//! round-off in t: the event time is then as accurate as the step polynomial, and a change
//! of the root finder's tolerance changes nothing measurable.
//!
//! The value of g at the end of one step is carried to the start of the next, so a crossing
//! at a step boundary is found once. The initial point is never an event (a run that starts
//! on a surface of section does not report its start). A terminal event ends the solve at
//! its time: the solution's last point is the event's point, later output times inside that
//! step are not served, and [`Solution::terminal`](crate::solve::Solution) names the event.
//!
//! An event function is written once, generic over the scalar ([`EventFunction`], like a
//! Lagrangian), or as a closure on `f64`s ([`Event::new`]); a non-finite value is
//! [`Error::NonFinite`] naming the event, never a missed crossing.

use std::cell::RefCell;
use std::fmt;
use std::str::FromStr;

use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::brent::BrentRoot;

use crate::error::Error;
use crate::model::text::TextFunction;
use crate::scalar::Scalar;

/// Which zero crossings of g are events.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Direction {
    /// g rises through zero: from g < 0 to g ≥ 0.
    Up,
    /// g falls through zero: from g > 0 to g ≤ 0.
    Down,
    /// Either.
    #[default]
    Both,
}

impl Direction {
    /// Whether g going from `a` to `b` crosses zero in this direction.
    pub fn crosses(self, a: f64, b: f64) -> bool {
        let up = a < 0.0 && b >= 0.0;
        let down = a > 0.0 && b <= 0.0;
        match self {
            Direction::Up => up,
            Direction::Down => down,
            Direction::Both => up || down,
        }
    }

    /// The names `up`, `down`, `both`.
    pub const NAMES: [&'static str; 3] = ["up", "down", "both"];
}

impl FromStr for Direction {
    type Err = Error;

    fn from_str(text: &str) -> Result<Self, Error> {
        match text {
            "up" => Ok(Direction::Up),
            "down" => Ok(Direction::Down),
            "both" => Ok(Direction::Both),
            _ => Err(Error::invalid(
                "direction",
                format!(
                    "unknown event direction '{text}' (known: {})",
                    Direction::NAMES.join(", ")
                ),
            )),
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let index = *self as usize;
        f.write_str(Direction::NAMES[index])
    }
}

/// An event function g(t, q, q̇), written once generic over the scalar (dual numbers give its
/// derivatives where a caller needs them).
pub trait EventFunction {
    /// The value of g at time `t`, configuration `q` and velocity `v`.
    fn value<D: Scalar>(&self, t: D, q: &[D], v: &[D]) -> D;
}

/// A function written as text is an event function.
impl EventFunction for TextFunction {
    fn value<D: Scalar>(&self, t: D, q: &[D], v: &[D]) -> D {
        self.evaluate(t, q, v)
    }
}

/// The function of an event on `f64`s.
type EventFn<'a> = dyn Fn(f64, &[f64], &[f64]) -> f64 + Send + Sync + 'a;

/// An event: its name, its function g(t, q, q̇), the direction of the crossings that count
/// and whether the first one ends the solve.
pub struct Event<'a> {
    name: String,
    direction: Direction,
    terminal: bool,
    function: Box<EventFn<'a>>,
}

impl fmt::Debug for Event<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Event")
            .field("name", &self.name)
            .field("direction", &self.direction)
            .field("terminal", &self.terminal)
            .finish_non_exhaustive()
    }
}

impl<'a> Event<'a> {
    /// The event `name` of the closure `g(t, q, v)`: crossings in both directions, not
    /// terminal.
    pub fn new(
        name: impl Into<String>,
        g: impl Fn(f64, &[f64], &[f64]) -> f64 + Send + Sync + 'a,
    ) -> Self {
        Event {
            name: name.into(),
            direction: Direction::Both,
            terminal: false,
            function: Box::new(g),
        }
    }

    /// The event `name` of an [`EventFunction`], evaluated on `f64`s.
    pub fn from_function(
        name: impl Into<String>,
        g: impl EventFunction + Send + Sync + 'a,
    ) -> Self {
        Event::new(name, move |t, q, v| g.value(t, q, v))
    }

    /// The same event counting only crossings in `direction`.
    #[must_use]
    pub fn direction(mut self, direction: Direction) -> Self {
        self.direction = direction;
        self
    }

    /// The same event, ending the solve at its first crossing when `terminal`.
    #[must_use]
    pub fn terminal(mut self, terminal: bool) -> Self {
        self.terminal = terminal;
        self
    }

    /// The event's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The crossings that count.
    pub fn crossing(&self) -> Direction {
        self.direction
    }

    /// Whether the first crossing ends the solve.
    pub fn is_terminal(&self) -> bool {
        self.terminal
    }

    /// g(t, q, v), or [`Error::NonFinite`] naming the event if it is not finite.
    pub fn value(&self, t: f64, q: &[f64], v: &[f64], step: usize) -> Result<f64, Error> {
        let value = (self.function)(t, q, v);
        if value.is_finite() {
            Ok(value)
        } else {
            Err(Error::NonFinite {
                what: format!("event '{}' (value {value} at t = {t:?})", self.name),
                step,
                t,
            })
        }
    }
}

/// A located event: which event (its index in the list given to the solve) and the point
/// of the solution at its time.
#[derive(Debug, Clone, PartialEq)]
pub struct EventPoint<P> {
    /// Index of the event in the list of the solve.
    pub event: usize,
    /// The solution's point at the event time.
    pub point: P,
}

/// The solution inside a step: hands q and q̇ at a time of the step to a callback.
pub(super) type PointAt<'p> =
    dyn FnMut(f64, &mut dyn FnMut(&[f64], &[f64])) -> Result<(), Error> + 'p;

/// Interior samples of g per step by default: four, so that crossings at least a fifth of
/// a step apart are told apart.
pub const DEFAULT_EVENT_SAMPLES: usize = 4;

/// The events of one solve and where they stand: g at the end of the last accepted step
/// (and as it was at the last mark, to go back to after a rejected trial step).
pub(super) struct EventTracker<'e, 'a> {
    events: &'e [Event<'a>],
    samples: usize,
    last: Vec<f64>,
    saved: Vec<f64>,
    /// g of every event at the sample times of the current step, sample-major.
    values: Vec<f64>,
    /// (time, event) of the crossings found in the current step.
    found: Vec<(f64, usize)>,
}

impl<'e, 'a> EventTracker<'e, 'a> {
    /// The tracker of `events` with `samples` interior samples per step, from g at the
    /// initial point (t0, q0, v0).
    pub(super) fn new(
        events: &'e [Event<'a>],
        samples: usize,
        (t0, q0, v0): (f64, &[f64], &[f64]),
    ) -> Result<Self, Error> {
        let last = events
            .iter()
            .map(|event| event.value(t0, q0, v0, 0))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(EventTracker {
            events,
            samples,
            saved: last.clone(),
            last,
            values: vec![0.0; events.len() * (samples + 2)],
            found: Vec::with_capacity(events.len()),
        })
    }

    /// Remember g at the end of the last accepted step.
    pub(super) fn save(&mut self) {
        self.saved.copy_from_slice(&self.last);
    }

    /// Go back to g as it was at [`EventTracker::save`].
    pub(super) fn restore(&mut self) {
        self.last.copy_from_slice(&self.saved);
    }

    /// Find the crossings inside the step (t, end] of the solution `point_at` (the step's
    /// polynomial: q and q̇ at a time of the step), in time order and cut after the first
    /// terminal one ([`EventTracker::found`]); `step` is the step's index for errors.
    pub(super) fn locate(
        &mut self,
        t: f64,
        end: f64,
        step: usize,
        point_at: &mut PointAt<'_>,
    ) -> Result<(), Error> {
        let count = self.events.len();
        let intervals = self.samples + 1;
        let sample_time = |j: usize| {
            if j == intervals {
                end
            } else {
                t + (end - t) * (j as f64 / intervals as f64)
            }
        };
        self.values[..count].copy_from_slice(&self.last);
        for j in 1..=intervals {
            let time = sample_time(j);
            let (events, values) = (self.events, &mut self.values[j * count..(j + 1) * count]);
            let mut error = None;
            point_at(time, &mut |q, v| {
                for (value, event) in values.iter_mut().zip(events) {
                    match event.value(time, q, v, step) {
                        Ok(g) => *value = g,
                        Err(e) => error = Some(e),
                    }
                }
            })?;
            if let Some(error) = error {
                return Err(error);
            }
        }
        self.found.clear();
        for (i, event) in self.events.iter().enumerate() {
            for j in 0..intervals {
                let (a, b) = (self.values[j * count + i], self.values[(j + 1) * count + i]);
                if event.direction.crosses(a, b) {
                    let time = root(event, step, (sample_time(j), sample_time(j + 1)), point_at)?;
                    self.found.push((time, i));
                }
            }
        }
        self.last
            .copy_from_slice(&self.values[intervals * count..(intervals + 1) * count]);
        self.found.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(first) = self
            .found
            .iter()
            .position(|&(_, i)| self.events[i].terminal)
        {
            self.found.truncate(first + 1);
        }
        Ok(())
    }

    /// The crossings (time, event) found by the last [`EventTracker::locate`].
    pub(super) fn found(&self) -> &[(f64, usize)] {
        &self.found
    }

    /// Event `index`.
    pub(super) fn event(&self, index: usize) -> &'e Event<'a> {
        &self.events[index]
    }
}

/// g of `event` along the step polynomial, for Brent's method.
struct Along<'p, 'e, 'a> {
    event: &'e Event<'a>,
    step: usize,
    point_at: RefCell<&'p mut PointAt<'p>>,
}

impl Along<'_, '_, '_> {
    fn at(&self, time: f64) -> Result<f64, Error> {
        let mut value = Ok(f64::NAN);
        (self.point_at.borrow_mut())(time, &mut |q, v| {
            value = self.event.value(time, q, v, self.step);
        })?;
        value
    }
}

impl CostFunction for Along<'_, '_, '_> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, time: &f64) -> Result<f64, argmin::core::Error> {
        self.at(*time).map_err(argmin::core::Error::from)
    }
}

/// The zero of `event`'s g in [lower, upper] along `point_at`, whose samples at the ends
/// changed sign: Brent's method where g evaluated on this step's polynomial brackets a zero;
/// `lower` where it does not (a crossing at the step's start, seen by the previous step's
/// polynomial on the other side of zero, within that polynomial's error).
fn root(
    event: &Event<'_>,
    step: usize,
    (lower, upper): (f64, f64),
    point_at: &mut PointAt<'_>,
) -> Result<f64, Error> {
    let along = Along {
        event,
        step,
        point_at: RefCell::new(point_at),
    };
    let (a, b) = (along.at(lower)?, along.at(upper)?);
    if a == 0.0 {
        return Ok(lower);
    }
    if b == 0.0 {
        return Ok(upper);
    }
    if a.signum() == b.signum() {
        return Ok(lower);
    }
    let tolerance = 2.0 * f64::EPSILON * lower.abs().max(upper.abs()).max(1.0);
    let solver = BrentRoot::new(lower, upper, tolerance);
    let result = Executor::new(along, solver)
        .configure(|state| state.param(0.5 * (lower + upper)).max_iters(200))
        .run()
        .map_err(|error| match error.downcast::<Error>() {
            Ok(error) => error,
            Err(other) => {
                Error::invalid("event", format!("locating event '{}': {other}", event.name))
            }
        })?;
    let state = result.state();
    match (state.get_termination_status(), state.get_param()) {
        (TerminationStatus::Terminated(TerminationReason::SolverConverged), Some(&time)) => {
            Ok(time)
        }
        (status, _) => Err(Error::invalid(
            "event",
            format!(
                "Brent's method did not locate event '{}' in [{lower:?}, {upper:?}]: {status:?}",
                event.name
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_count_the_crossings_they_name() {
        assert!(Direction::Up.crosses(-1.0, 0.0) && !Direction::Up.crosses(1.0, -1.0));
        assert!(Direction::Down.crosses(1.0, 0.0) && !Direction::Down.crosses(-1.0, 1.0));
        assert!(Direction::Both.crosses(-1.0, 1.0) && Direction::Both.crosses(1.0, -1.0));
        assert!(!Direction::Both.crosses(0.0, 1.0) && !Direction::Both.crosses(1.0, 2.0));
        for name in Direction::NAMES {
            assert_eq!(name.parse::<Direction>().unwrap().to_string(), name);
        }
        assert!("sideways".parse::<Direction>().is_err());
    }

    #[test]
    fn a_located_root_of_a_known_curve_is_exact_to_round_off() {
        // q(t) = cos t on [1, 2]: the zero at π/2.
        let event = Event::new("zero", |_, q, _| q[0]);
        let mut point_at = |time: f64, f: &mut dyn FnMut(&[f64], &[f64])| -> Result<(), Error> {
            f(&[time.cos()], &[-time.sin()]);
            Ok(())
        };
        let time = root(&event, 0, (1.0, 2.0), &mut point_at).unwrap();
        assert!((time - std::f64::consts::FRAC_PI_2).abs() < 1e-15, "{time}");
    }

    #[test]
    fn a_non_finite_event_value_names_the_event() {
        let event = Event::new("bad", |_, _, _| f64::NAN);
        let error = event.value(0.5, &[0.0], &[0.0], 3).unwrap_err();
        assert!(matches!(error, Error::NonFinite { step: 3, .. }));
        assert!(error.to_string().contains("event 'bad'"), "{error}");
    }
}
