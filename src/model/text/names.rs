//! The names of a text model: the declared coordinates, velocities and parameters checked
//! once (identifiers, none given twice, none taken by a function, a constant or `t`),
//! parameters looked up by name, and every name interned as the `&'static str` the traits of a
//! model use.

use std::collections::BTreeSet;
use std::sync::Mutex;

use super::error::TextError;
use super::tree::{CONSTANT_NAMES, FUNCTION_NAMES};
use crate::error::Error;

/// Each parameter's name with its value.
pub(super) fn named_values(names: &[&'static str], values: &[f64]) -> Vec<(&'static str, f64)> {
    names.iter().copied().zip(values.iter().copied()).collect()
}

/// The index of the parameter `name` among `names`, for the new value `value`.
///
/// # Errors
/// [`Error::InvalidParameter`] for a name that is not a parameter or a value that is not
/// finite.
pub(super) fn parameter_index(
    names: &[&'static str],
    name: &str,
    value: f64,
) -> Result<usize, Error> {
    let Some(index) = names.iter().position(|known| *known == name) else {
        let known = if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        };
        return Err(Error::invalid(
            name,
            format!("not a parameter of the text model (parameters: {known})"),
        ));
    };
    if !value.is_finite() {
        return Err(Error::invalid(
            name,
            format!("{value} is not a finite number"),
        ));
    }
    Ok(index)
}

/// The checked names of a model: its coordinates (or indexed families), their velocities and
/// its parameters with their values.
pub(super) struct Declared {
    pub(super) coordinates: Vec<&'static str>,
    pub(super) velocities: Vec<&'static str>,
    pub(super) parameter_names: Vec<&'static str>,
    pub(super) parameter_values: Vec<f64>,
}

impl Declared {
    /// Check `coordinates` and `parameters`: identifiers, none given twice, no velocity
    /// (`v` + a coordinate) that is another name, finite values.
    pub(super) fn check(
        coordinates: &[&str],
        parameters: &[(String, f64)],
    ) -> Result<Declared, TextError> {
        Declared::check_phase_space(coordinates, parameters, Slot::Velocity)
    }

    /// [`Declared::check`] with the second slot of the phase space named by `slot`: the
    /// velocities (`v` + a coordinate) of a Lagrangian or the momenta (`p` + a coordinate) of
    /// a Hamiltonian, kept in [`Declared::velocities`] either way.
    pub(super) fn check_phase_space(
        coordinates: &[&str],
        parameters: &[(String, f64)],
        slot: Slot,
    ) -> Result<Declared, TextError> {
        let mut taken = BTreeSet::new();
        let mut declared = Declared {
            coordinates: Vec::new(),
            velocities: Vec::new(),
            parameter_names: Vec::new(),
            parameter_values: Vec::new(),
        };
        for name in coordinates {
            check_name("coordinate", name)?;
            if !taken.insert(name.to_string()) {
                return Err(TextError::InvalidName {
                    role: "coordinate",
                    name: name.to_string(),
                    reason: "given twice".into(),
                });
            }
            declared.coordinates.push(intern(name));
        }
        for name in coordinates {
            let velocity = format!("{}{name}", slot.prefix());
            if !taken.insert(velocity.clone()) {
                return Err(TextError::InvalidName {
                    role: "coordinate",
                    name: name.to_string(),
                    reason: format!("its {} '{velocity}' is also a coordinate", slot.noun()),
                });
            }
            declared.velocities.push(intern(&velocity));
        }
        for (name, value) in parameters {
            check_name("parameter", name)?;
            if !taken.insert(name.clone()) {
                return Err(TextError::InvalidName {
                    role: "parameter",
                    name: name.clone(),
                    reason: "given twice, or a coordinate or velocity".into(),
                });
            }
            if !value.is_finite() {
                return Err(TextError::NonFiniteParameter {
                    name: name.clone(),
                    value: *value,
                });
            }
            declared.parameter_names.push(intern(name));
            declared.parameter_values.push(*value);
        }
        Ok(declared)
    }
}

/// What the second slot of a text model's phase space holds, and how its names are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Slot {
    /// The velocities q̇ of a Lagrangian: `v` + the coordinate's name.
    Velocity,
    /// The momenta p of a Hamiltonian: `p` + the coordinate's name.
    Momentum,
}

impl Slot {
    /// The prefix of the names: `v` or `p`.
    pub(super) fn prefix(self) -> &'static str {
        match self {
            Slot::Velocity => "v",
            Slot::Momentum => "p",
        }
    }

    /// What the slot holds, in messages: `velocity` or `momentum`.
    pub(super) fn noun(self) -> &'static str {
        match self {
            Slot::Velocity => "velocity",
            Slot::Momentum => "momentum",
        }
    }
}

/// Reject a name that is not an identifier, or is a function, a constant or `t`.
fn check_name(role: &'static str, name: &str) -> Result<(), TextError> {
    let invalid = |reason: &str| {
        Err(TextError::InvalidName {
            role,
            name: name.into(),
            reason: reason.into(),
        })
    };
    let mut chars = name.chars();
    let identifier = chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
        && chars.all(|c| c.is_alphanumeric() || c == '_');
    if !identifier {
        return invalid("a name is a letter or '_' followed by letters, digits and '_'");
    }
    if FUNCTION_NAMES.contains(&name) {
        return invalid("it is a function");
    }
    if CONSTANT_NAMES.contains(&name) {
        return invalid("it is a constant");
    }
    if name == "t" {
        return invalid("t is the time");
    }
    if name == "sum" {
        return invalid("sum(i, lower, upper, body) is the indexed sum");
    }
    Ok(())
}

/// Intern `name`: the one `&'static str` with its text. The traits of a model name its
/// coordinates, parameters and momenta with `&'static str`; a text model's names are leaked
/// once per distinct name and process, not once per model.
pub(super) fn intern(name: &str) -> &'static str {
    static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());
    let mut names = NAMES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(known) = names.get(name) {
        return known;
    }
    let leaked: &'static str = Box::leak(name.to_owned().into_boxed_str());
    names.insert(leaked);
    leaked
}
