//! What a solve hands back besides its end point: the points at the output times, the
//! steps' polynomials kept for dense output, and the located events, served after every
//! accepted step from the step just taken ([`Integrator::emit`]) and taken back after a
//! rejected trial step ([`Outputs::rollback`]).

use crate::error::Error;
use crate::method::space::{Space, StepState};
use crate::method::step::Step;
use crate::stepping::dense::DenseOutput;
use crate::stepping::event::{Event, EventPoint, EventTracker};
use crate::stepping::run::Integrator;

/// Output times not yet served, the points produced so far, the steps' polynomials kept
/// for dense output, and the events located so far.
pub(super) struct Outputs<'a, S: Space> {
    times: &'a [f64],
    pub(super) points: Vec<S::Point>,
    /// Last velocity, the Newton start of the next inverse Legendre map.
    pub(super) guess: S::Velocity,
    pub(super) dense: Option<DenseOutput>,
    pub(super) events: Option<EventTracker<'a, 'a>>,
    pub(super) located: Vec<EventPoint<S::Point>>,
    /// Index in `located` of the terminal event that ended the solve.
    pub(super) terminal: Option<usize>,
}

/// How far [`Outputs`] had got: output points, dense steps and located events, to go back
/// to after a rejected trial step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Mark {
    points: usize,
    steps: usize,
    events: usize,
}

impl<'a, S: Space> Outputs<'a, S> {
    /// Nothing served yet of `times`, from the velocity `guess`.
    pub(super) fn new(times: &'a [f64], guess: S::Velocity) -> Self {
        Outputs {
            times,
            points: Vec::with_capacity(times.len()),
            guess,
            dense: None,
            events: None,
            located: Vec::new(),
            terminal: None,
        }
    }

    pub(super) fn next(&self) -> Option<f64> {
        self.times.get(self.points.len()).copied()
    }

    /// Whether the start of each step is needed: an output time is left, steps are kept, or
    /// events are located.
    pub(super) fn wants_steps(&self) -> bool {
        self.next().is_some() || self.dense.is_some() || self.events.is_some()
    }

    /// The time of the terminal event that ended the solve, if one did.
    pub(super) fn terminal_time(&self) -> Option<f64> {
        self.terminal.map(|k| S::time(&self.located[k].point))
    }

    /// Where the outputs stand now (the events' values at the last accepted step are
    /// remembered with it).
    pub(super) fn mark(&mut self) -> Mark {
        if let Some(events) = &mut self.events {
            events.save();
        }
        Mark {
            points: self.points.len(),
            steps: self.dense.as_ref().map_or(0, DenseOutput::steps),
            events: self.located.len(),
        }
    }

    /// Forget what was produced after `mark`.
    pub(super) fn rollback(&mut self, mark: Mark) {
        self.points.truncate(mark.points);
        if let Some(dense) = &mut self.dense {
            dense.truncate(mark.steps);
        }
        if let Some(events) = &mut self.events {
            events.restore();
        }
        self.located.truncate(mark.events);
        self.terminal = self.terminal.filter(|&k| k < mark.events);
    }

    /// Forget the output points and events after `time` and the steps that start at or
    /// after it.
    pub(super) fn rollback_after(&mut self, time: f64) {
        let served = self.points.partition_point(|point| S::time(point) <= time);
        self.points.truncate(served);
        if let Some(dense) = &mut self.dense {
            dense.truncate_from(time);
        }
        let located = self
            .located
            .partition_point(|event| S::time(&event.point) <= time);
        self.located.truncate(located);
        self.terminal = self.terminal.filter(|&k| k < located);
    }
}

impl<L, M: Step<L, S> + Clone, S: Space> Integrator<L, M, S> {
    /// Serve every output time in (t, t + h] from the step of `method` just taken from
    /// `start` at `t` to `end` at `end_time`: at `end_time` itself the completed end point,
    /// inside the step the method's dense output or, without one, the space's interpolant of
    /// the completed end points. `steps_taken` counts the steps so far, this one included. A
    /// non-finite output point (a step too short for its polynomial's scaling, say) is
    /// [`Error::NonFinite`] in this step (index `steps_taken − 1`, starting at `t`), never a
    /// silent NaN.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(super) fn emit(
        &self,
        method: &M,
        workspace: &M::Workspace,
        outputs: &mut Outputs<'_, S>,
        steps_taken: usize,
        t: f64,
        h: f64,
        start: &S::State,
        end: &S::State,
        end_time: f64,
    ) -> Result<(), Error> {
        // Most steps serve nothing, and the serving is kept out of line: inlined here, the
        // model evaluations of its points were hoisted above these checks into every step
        // (15 ns of a 62 ns Störmer–Verlet step on Kepler).
        let due = outputs.next().is_some_and(|time| time <= end_time);
        if !due && outputs.events.is_none() && outputs.dense.is_none() {
            return Ok(());
        }
        self.serve(
            method,
            workspace,
            outputs,
            steps_taken,
            t,
            h,
            start,
            end,
            end_time,
        )
    }

    /// [`Integrator::emit`] of a step that has an output time, events or dense output.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn serve(
        &self,
        method: &M,
        workspace: &M::Workspace,
        outputs: &mut Outputs<'_, S>,
        steps_taken: usize,
        t: f64,
        h: f64,
        start: &S::State,
        end: &S::State,
        end_time: f64,
    ) -> Result<(), Error> {
        let model = self.model();
        // The point at `time` inside the step: the method's dense output or, without one, the
        // space's interpolant of the end points (completed once); `None` if it has neither.
        let mut ends: Option<(S::Point, S::Point)> = None;
        let mut inside = |time: f64, guess: &S::Velocity| -> Result<Option<S::Point>, Error> {
            if let Some(point) = method.dense_point(model, workspace, t, h, start, time) {
                return Ok(Some(point));
            }
            let (a, b) = match ends {
                Some(ref known) => known,
                None => ends.insert((
                    self.phase_point(t, start, guess)?,
                    self.phase_point(end_time, end, guess)?,
                )),
            };
            Ok(method.interpolate(model, a, b, time))
        };
        let step = steps_taken.saturating_sub(1);
        if outputs.terminal.is_none()
            && let Some(tracker) = outputs.events.as_mut()
        {
            let guess = &outputs.guess;
            let mut point_at =
                |time: f64, f: &mut dyn FnMut(&[f64], &[f64])| -> Result<(), Error> {
                    let point = inside(time, guess)?.ok_or_else(|| no_events(method))?;
                    let (q, v, _) = S::point_vectors(&point).ok_or_else(|| no_events(method))?;
                    f(q, v);
                    Ok(())
                };
            tracker.locate(t, end_time, step, &mut point_at)?;
            let mut refinement = None;
            for &(estimate, index) in tracker.found() {
                let event = tracker.event(index);
                // g's slope along the polynomial, for Newton's method on the exact steps.
                let delta = 1e-6 * h;
                let (before, after) = ((estimate - delta).max(t), (estimate + delta).min(end_time));
                let mut g = |time: f64| -> Result<f64, Error> {
                    let point = inside(time, guess)?.ok_or_else(|| no_events(method))?;
                    let (q, v, _) = S::point_vectors(&point).ok_or_else(|| no_events(method))?;
                    event.value(time, q, v, step)
                };
                let slope = (g(after)? - g(before)?) / (after - before);
                let refined = self.refine(
                    method,
                    (event, step),
                    (t, end_time, start, guess),
                    (estimate, slope),
                    &mut refinement,
                )?;
                let point = match refined {
                    Some(point) => point,
                    None => inside(estimate, guess)?.ok_or_else(|| no_events(method))?,
                };
                if event.is_terminal() {
                    outputs.terminal = Some(outputs.located.len());
                }
                outputs.located.push(EventPoint {
                    event: index,
                    point,
                });
            }
        }
        let limit = outputs.terminal_time().unwrap_or(end_time);
        while let Some(time) = outputs.next() {
            if time > limit {
                break;
            }
            let point = if time == end_time {
                self.phase_point(end_time, end, &outputs.guess)?
            } else {
                inside(time, &outputs.guess)?.ok_or_else(|| {
                    Error::invalid(
                        "output_times",
                        format!(
                            "{time:?} lies inside a step, and {} has neither dense output nor an \
                             interpolant on its space: ask for output at the ends of the span",
                            method.info().name
                        ),
                    )
                })?
            };
            if !method.point_is_finite(&point) {
                return Err(Error::NonFinite {
                    what: format!("output point at t = {time:?}"),
                    step: steps_taken.saturating_sub(1),
                    t,
                });
            }
            outputs.guess = S::velocity(&point);
            outputs.points.push(point);
        }
        let Some(dense) = outputs.dense.as_mut() else {
            return Ok(());
        };
        for j in 0..dense.samples() {
            let time = dense.sample_time(j, t, end_time);
            let point = inside(time, &outputs.guess)?.ok_or_else(|| {
                Error::invalid("dense", "the method has no step polynomial on this space")
            })?;
            let (Some((q, v, p)), true) =
                (S::point_vectors(&point), method.point_is_finite(&point))
            else {
                return Err(Error::NonFinite {
                    what: format!("dense output point at t = {time:?}"),
                    step: steps_taken.saturating_sub(1),
                    t,
                });
            };
            dense.push_sample(q, v, p);
        }
        dense.end_step(t, end_time);
        Ok(())
    }
}

/// Most Newton iterations refining an event time by steps of the method.
const REFINEMENTS: usize = 8;

impl<L, M: Step<L, S> + Clone, S: Space> Integrator<L, M, S> {
    /// The point of `event` (in step `step`) refined from the step polynomial's crossing
    /// `estimate` by Newton's method on g(τ) = g(Φ_{τ−t}(start)), each value from one step
    /// of `method` of size τ − t from the step's `start` at `t` (cold: its own
    /// `refinement` workspace, built at the first event of the solve), with g's `slope`
    /// along the polynomial: the event then carries the method's accuracy at its step
    /// points (O(h^(2s−2)) for SVI with s points) instead of the polynomial's inside the
    /// step. `None` (keep the polynomial's crossing) when a refining step fails or Newton
    /// leaves the step (t, end] or does not settle.
    #[allow(clippy::type_complexity)]
    fn refine(
        &self,
        method: &M,
        (event, step): (&Event<'_>, usize),
        (t, end, start, guess): (f64, f64, &S::State, &S::Velocity),
        (estimate, slope): (f64, f64),
        refinement: &mut Option<(M::Workspace, S::State)>,
    ) -> Result<Option<S::Point>, Error> {
        if !(slope.is_finite() && slope != 0.0) {
            return Ok(None);
        }
        let model = self.model();
        let (workspace, increment) = match refinement {
            Some(known) => known,
            None => refinement.insert((method.workspace(model, end - t)?, start.zeros_like())),
        };
        let mut time = estimate;
        for iteration in 0..REFINEMENTS {
            method.restart(workspace);
            if method
                .step(model, workspace, t, time - t, start, increment)
                .is_err()
            {
                return Ok(None);
            }
            let point = self.phase_point(time, &start.plus(increment), guess)?;
            let Some((q, v, _)) = S::point_vectors(&point) else {
                return Ok(None);
            };
            let value = event.value(time, q, v, step)?;
            let next = time - value / slope;
            if !(next > t && next <= end) {
                return Ok(None);
            }
            let change = (next - time).abs();
            let resolution = f64::EPSILON * time.abs().max(end - t);
            if change <= 2.0 * resolution || value == 0.0 {
                return Ok(Some(point));
            }
            if iteration + 1 == REFINEMENTS {
                // Round-off in g keeps Newton from settling: near enough is kept.
                return Ok((change <= 64.0 * resolution).then_some(point));
            }
            time = next;
        }
        Ok(None)
    }
}

/// The error of events asked of a method with neither a step polynomial nor an interpolant
/// on its space.
fn no_events<L, M: Step<L, S>, S: Space>(method: &M) -> Error {
    Error::invalid(
        "events",
        format!(
            "{} has neither a step polynomial nor an interpolant on its space: events are \
             located on ℝᴺ",
            method.info().name
        ),
    )
}
