//! Events and Poincaré sections of a scene: what `[[events]]` and `output.section` in a scene
//! file, `--event` and `--section` on the command line, ask a run to locate
//! ([`svi::stepping::event`]).
//!
//! An event is a function g(t, q, q̇) written as text over the model's coordinate names,
//! their velocities (`v` + the name), `t` and the model's parameters, with the direction of
//! its crossings and whether the first ends the run. On the command line:
//! `--event "pericentre: x*vx + y*vy @up @terminal"` (the name and the qualifiers optional).
//!
//! An event may also be a function of the caller's program ([`NativeEvent`]: a Python
//! callable of the package), carried by the scene beside its text events but never part of a
//! scene file.
//!
//! A section `"y=0,vy>0"` is the crossings of the surface "coordinate = value", kept where
//! the condition holds; a condition on the same coordinate's velocity counts only the
//! crossings in that direction. Coordinates may be named as the model names them (`x`, `vx`)
//! or by position (`q1`, `v1`, counted from 1).

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use serde::Deserialize;
use svi::stepping::event::Direction;

/// An event or section that does not parse, or names what the model lacks: bad input
/// ([`crate::scene::SceneError::InvalidOption`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid {option}: {reason}")]
pub struct SpecError {
    /// The option, with its scene field: `--section (output.section)`.
    pub option: &'static str,
    /// What is wrong, and what would do.
    pub reason: String,
}

/// g(t, q, q̇) on `f64`s, given as code.
pub type NativeFunction = dyn Fn(f64, &[f64], &[f64]) -> f64 + Send + Sync;

/// An event whose function is code of the caller (the Python package's callables), not text.
#[derive(Clone)]
pub struct NativeEvent {
    /// Its name in the results.
    pub name: String,
    /// Which crossings count.
    pub direction: Direction,
    /// Whether the first crossing ends the run, with status ok.
    pub terminal: bool,
    /// g(t, q, q̇); a non-finite value fails the run naming the event.
    pub function: Arc<NativeFunction>,
}

impl fmt::Debug for NativeEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("NativeEvent")
            .field("name", &self.name)
            .field("direction", &self.direction)
            .field("terminal", &self.terminal)
            .finish_non_exhaustive()
    }
}

impl PartialEq for NativeEvent {
    /// The same name, direction and terminal flag, and the same function object.
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
            && self.direction == other.direction
            && self.terminal == other.terminal
            && Arc::ptr_eq(&self.function, &other.function)
    }
}

/// One event of a scene.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventSpec {
    /// Its name in the results (default `event1`, `event2`, … by position).
    pub name: Option<String>,
    /// The function g(t, q, q̇) whose zeros are the events, as text.
    pub g: String,
    /// Which crossings count: `up` (g rises through 0), `down` or `both` (default).
    #[serde(default, deserialize_with = "direction")]
    pub direction: Option<Direction>,
    /// Whether the first crossing ends the run, with status ok (default false).
    #[serde(default)]
    pub terminal: bool,
}

fn direction<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Direction>, D::Error> {
    let text = String::deserialize(d)?;
    text.parse().map(Some).map_err(serde::de::Error::custom)
}

impl EventSpec {
    /// The name of the event at `index` (counted from 0) of its list.
    pub fn name_at(&self, index: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("event{}", index + 1))
    }
}

impl FromStr for EventSpec {
    type Err = SpecError;

    /// `[NAME:] G [@up|@down|@both] [@terminal]`.
    fn from_str(text: &str) -> Result<Self, SpecError> {
        let invalid = |reason: String| SpecError {
            option: "--event (events)",
            reason,
        };
        let mut parts = text.split('@');
        let body = parts.next().unwrap_or_default();
        let (name, g) = match body.split_once(':') {
            Some((name, g)) => (Some(name.trim().to_string()), g.trim()),
            None => (None, body.trim()),
        };
        if g.is_empty() {
            return Err(invalid(format!(
                "'{text}' gives no function: write [NAME:] G [@up|@down|@both] [@terminal]"
            )));
        }
        if name.as_deref() == Some("") {
            return Err(invalid(format!("'{text}' has an empty name before ':'")));
        }
        let mut spec = EventSpec {
            name,
            g: g.to_string(),
            direction: None,
            terminal: false,
        };
        for qualifier in parts.map(str::trim) {
            match qualifier {
                "terminal" => spec.terminal = true,
                other => {
                    spec.direction = Some(other.parse().map_err(|_| {
                        invalid(format!(
                            "unknown qualifier '@{other}' in '{text}' (known: @up, @down, \
                             @both, @terminal)"
                        ))
                    })?);
                }
            }
        }
        Ok(spec)
    }
}

/// Which side of a section's condition is kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// variable > value.
    Above,
    /// variable < value.
    Below,
}

/// A Poincaré section: the crossings of `coordinate = value` where `condition` holds.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionSpec {
    /// The coordinate of the surface, as written (`y` or `q2`).
    pub coordinate: String,
    /// The surface's value.
    pub value: f64,
    /// The condition on a coordinate or velocity (as written), its side and its threshold.
    pub condition: Option<(String, Side, f64)>,
    /// The text the section was read from.
    text: String,
}

impl fmt::Display for SectionSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl FromStr for SectionSpec {
    type Err = SpecError;

    /// `COORDINATE=VALUE[,VARIABLE>VALUE|VARIABLE<VALUE]`.
    fn from_str(text: &str) -> Result<Self, SpecError> {
        let invalid = |reason: String| SpecError {
            option: "--section (output.section)",
            reason,
        };
        let number = |word: &str| -> Result<f64, SpecError> {
            match word.trim().parse::<f64>() {
                Ok(value) if value.is_finite() => Ok(value),
                _ => Err(invalid(format!(
                    "'{}' in '{text}' is not a finite number",
                    word.trim()
                ))),
            }
        };
        let (surface, condition) = match text.split_once(',') {
            Some((surface, condition)) => (surface, Some(condition)),
            None => (text, None),
        };
        let Some((coordinate, value)) = surface.split_once('=') else {
            return Err(invalid(format!(
                "'{text}' has no surface: write COORDINATE=VALUE[,VARIABLE>VALUE], e.g. \
                 \"y=0,vy>0\""
            )));
        };
        let coordinate = coordinate.trim();
        if coordinate.is_empty() {
            return Err(invalid(format!("'{text}' names no coordinate before '='")));
        }
        let condition = match condition {
            None => None,
            Some(condition) => {
                let (variable, side, threshold) = if let Some((v, t)) = condition.split_once('>') {
                    (v, Side::Above, t)
                } else if let Some((v, t)) = condition.split_once('<') {
                    (v, Side::Below, t)
                } else {
                    return Err(invalid(format!(
                        "the condition '{}' of '{text}' is neither VARIABLE>VALUE nor \
                         VARIABLE<VALUE",
                        condition.trim()
                    )));
                };
                if variable.trim().is_empty() {
                    return Err(invalid(format!(
                        "'{text}' names no variable in its condition"
                    )));
                }
                Some((variable.trim().to_string(), side, number(threshold)?))
            }
        };
        Ok(SectionSpec {
            coordinate: coordinate.to_string(),
            value: number(value)?,
            condition,
            text: text.trim().to_string(),
        })
    }
}

impl<'de> Deserialize<'de> for SectionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// Where a name of a section points among the model's `coordinates`: (index, velocity).
///
/// # Errors
/// [`SpecError`] naming the section and the model's names when it is none of
/// them (`x`, `vx`, `q1`, `v1`).
pub fn resolve(
    name: &str,
    coordinates: &[String],
    section: &SectionSpec,
) -> Result<(usize, bool), SpecError> {
    if let Some(i) = coordinates.iter().position(|c| c == name) {
        return Ok((i, false));
    }
    if let Some(i) = coordinates.iter().position(|c| format!("v{c}") == name) {
        return Ok((i, true));
    }
    let positional = |prefix: char, velocity: bool| {
        let rest = name.strip_prefix(prefix)?;
        let index: usize = rest.parse().ok()?;
        (1..=coordinates.len())
            .contains(&index)
            .then_some((index - 1, velocity))
    };
    positional('q', false)
        .or_else(|| positional('v', true))
        .ok_or_else(|| SpecError {
            option: "--section (output.section)",
            reason: format!(
                "'{name}' in '{section}' is not a coordinate or velocity of the model (its \
                 coordinates: {}; velocities v + name; or q1…q{n}, v1…v{n})",
                coordinates.join(", "),
                n = coordinates.len()
            ),
        })
}

impl crate::scene::Scene {
    /// Whether the scene asks for events (text or native; a section is not counted).
    pub fn has_events(&self) -> bool {
        !self.events.is_empty() || !self.native_events.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn event_flags_read_name_function_and_qualifiers() {
        let spec: EventSpec = "pericentre: x*vx + y*vy @up @terminal".parse().unwrap();
        assert_eq!(spec.name.as_deref(), Some("pericentre"));
        assert_eq!(spec.g, "x*vx + y*vy");
        assert_eq!(spec.direction, Some(Direction::Up));
        assert!(spec.terminal);
        let plain: EventSpec = "atan2(y, x)".parse().unwrap();
        assert_eq!((plain.name, plain.g.as_str()), (None, "atan2(y, x)"));
        assert_eq!(plain.direction, None);
        for bad in ["", "name:", ": x", "x @sideways"] {
            assert!(bad.parse::<EventSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn sections_read_surface_and_condition_and_resolve_names() {
        let section: SectionSpec = "q2=0,v2>0".parse().unwrap();
        assert_eq!(section.coordinate, "q2");
        assert_eq!(section.condition, Some(("v2".into(), Side::Above, 0.0)));
        let names = ["x".to_string(), "y".to_string()];
        assert_eq!(resolve("q2", &names, &section).unwrap(), (1, false));
        assert_eq!(resolve("v2", &names, &section).unwrap(), (1, true));
        assert_eq!(resolve("vx", &names, &section).unwrap(), (0, true));
        let error = resolve("q3", &names, &section).unwrap_err();
        assert!(error.to_string().contains("'q3'"), "{error}");
        let below: SectionSpec = " x = 0.5 , vy < -1 ".parse().unwrap();
        assert_eq!(below.value, 0.5);
        assert_eq!(below.condition, Some(("vy".into(), Side::Below, -1.0)));
        for bad in ["x", "=0", "x=nan", "x=0,vx", "x=0,>0", "x=0,vx>inf"] {
            assert!(bad.parse::<SectionSpec>().is_err(), "{bad}");
        }
    }
}
