//! The events and the Poincaré section of a scene run ([`crate::scene::events`]): built into
//! the library's [`Event`]s for the model's names once per run, and the located points sorted
//! into the summary's events and the section's points afterwards.

use svi::model::text::TextFunction;
use svi::stepping::event::{Direction, Event, EventPoint};

use crate::report::events::{EventRecord, EventsSummary, SectionSummary};
use crate::run::space::RunSpace;
use crate::scene::Scene;
use crate::scene::error::SceneError;
use crate::scene::events::{SectionSpec, Side, resolve};

/// A section resolved against the model's coordinates.
struct Section {
    spec: SectionSpec,
    /// The condition as (index, velocity, side, threshold).
    condition: Option<(usize, bool, Side, f64)>,
    /// The coordinate drawn against its velocity.
    drawn: usize,
}

/// The events of a scene run, ready for the library, with the section (its event last).
pub(super) struct SceneEvents {
    /// The library's events: the scene's, then the section's.
    pub(super) events: Vec<Event<'static>>,
    names: Vec<String>,
    section: Option<Section>,
    coordinates: Vec<String>,
}

impl SceneEvents {
    /// The events of `scene` on `model`; `None` without events or section.
    ///
    /// # Errors
    /// [`SceneError::Text`] for an event function that does not parse over the model's
    /// names; [`SceneError::InvalidOption`] for a section on a name the model lacks;
    /// [`SceneError::NotApplicable`] on a space without named coordinates.
    pub(super) fn of<L, S: RunSpace<L>>(
        scene: &Scene,
        model: &L,
    ) -> Result<Option<SceneEvents>, SceneError> {
        let section = scene.output.section.as_ref();
        if !scene.has_events() && section.is_none() {
            return Ok(None);
        }
        let Some(coordinates) = S::coordinates(model) else {
            return Err(SceneError::NotApplicable {
                option: "--event, --section (events, output.section)",
                // Chains reach this (rigid bodies are refused by the scene's check).
                reason: "an event or section is written in the model's coordinate names, and \
                         this model has none (a chain of any size: its coordinates are not \
                         named)"
                    .into(),
            });
        };
        let parameters: Vec<(String, f64)> = S::parameters(model)
            .into_iter()
            .map(|(name, value)| (name.to_string(), value))
            .collect();
        let mut events = Vec::new();
        let mut names = Vec::new();
        for (index, spec) in scene.events.iter().enumerate() {
            let name = spec.name_at(index);
            let field = format!("events[{index}].g (event '{name}')");
            let g = TextFunction::parse(&spec.g, &field, &coordinates, &parameters)?;
            events.push(
                Event::from_function(name.clone(), g)
                    .direction(spec.direction.unwrap_or_default())
                    .terminal(spec.terminal),
            );
            names.push(name);
        }
        for native in &scene.native_events {
            let g = std::sync::Arc::clone(&native.function);
            events.push(
                Event::new(native.name.clone(), move |t, q, v| g(t, q, v))
                    .direction(native.direction)
                    .terminal(native.terminal),
            );
            names.push(native.name.clone());
        }
        let section = match section {
            None => None,
            Some(spec) => {
                let (i, velocity) = resolve(&spec.coordinate, &coordinates, spec)?;
                if velocity {
                    return Err(SceneError::InvalidOption {
                        option: "--section (output.section)",
                        reason: format!(
                            "the surface of '{spec}' is a velocity: write COORDINATE=VALUE"
                        ),
                    });
                }
                let condition = match &spec.condition {
                    None => None,
                    Some((name, side, threshold)) => {
                        let (j, on_velocity) = resolve(name, &coordinates, spec)?;
                        Some((j, on_velocity, *side, *threshold))
                    }
                };
                // Crossing q_i = value with q̇_i > 0 is crossing upwards.
                let direction = match condition {
                    Some((j, true, Side::Above, threshold)) if j == i && threshold == 0.0 => {
                        Direction::Up
                    }
                    Some((j, true, Side::Below, threshold)) if j == i && threshold == 0.0 => {
                        Direction::Down
                    }
                    _ => Direction::Both,
                };
                let value = spec.value;
                events.push(
                    Event::new(format!("section {spec}"), move |_, q, _| q[i] - value)
                        .direction(direction),
                );
                let drawn = (0..coordinates.len()).find(|&k| k != i).unwrap_or(i);
                Some(Section {
                    spec: spec.clone(),
                    condition,
                    drawn,
                })
            }
        };
        Ok(Some(SceneEvents {
            events,
            names,
            section,
            coordinates,
        }))
    }

    /// Sort the `located` points into the summary's events and the section's points (those
    /// meeting its condition), with the `terminal` event by index in `located`.
    pub(super) fn sort<'p, L, S: RunSpace<L>>(
        &self,
        located: &'p [EventPoint<S::Point>],
        terminal: Option<usize>,
    ) -> (EventsSummary, Vec<&'p S::Point>) {
        let mut records = Vec::new();
        let mut points = Vec::new();
        for event in located {
            match self.names.get(event.event) {
                Some(name) => {
                    let (q, v, p) = S::point_vectors(&event.point).unwrap_or_default();
                    records.push(EventRecord {
                        name: name.clone(),
                        t: S::time(&event.point),
                        q: q.to_vec(),
                        v: v.to_vec(),
                        p: p.to_vec(),
                    });
                }
                None if self.meets_condition::<L, S>(&event.point) => points.push(&event.point),
                None => {}
            }
        }
        let summary = EventsSummary {
            events: records,
            terminal_event: terminal
                .and_then(|k| located.get(k))
                .and_then(|event| self.names.get(event.event).cloned()),
            section: self.section.as_ref().map(|section| {
                let name = &self.coordinates[section.drawn];
                SectionSummary {
                    surface: section.spec.to_string(),
                    points: points.len(),
                    axes: [format!("q_{name}"), format!("v_{name}")],
                }
            }),
        };
        (summary, points)
    }

    /// Whether a crossing of the section meets its condition.
    fn meets_condition<L, S: RunSpace<L>>(&self, point: &S::Point) -> bool {
        let Some(Section {
            condition: Some((j, velocity, side, threshold)),
            ..
        }) = &self.section
        else {
            return true;
        };
        let Some((q, v, _)) = S::point_vectors(point) else {
            return false;
        };
        let value = if *velocity { v[*j] } else { q[*j] };
        match side {
            Side::Above => value > *threshold,
            Side::Below => value < *threshold,
        }
    }
}
