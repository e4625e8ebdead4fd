//! Parameter validation shared by the zoo models.

use svi::Error;

/// Check that `value` is finite and strictly positive.
pub(crate) fn positive(name: &str, value: f64) -> Result<f64, Error> {
    finite(name, value)?;
    if value <= 0.0 {
        return Err(Error::invalid(name, format!("{value:?} must be positive")));
    }
    Ok(value)
}

/// Check that `value` is finite and not negative.
pub(crate) fn non_negative(name: &str, value: f64) -> Result<f64, Error> {
    finite(name, value)?;
    if value < 0.0 {
        return Err(Error::invalid(
            name,
            format!("{value:?} must not be negative"),
        ));
    }
    Ok(value)
}

/// Check that `value` is finite.
pub(crate) fn finite(name: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, format!("{value:?} is not finite")))
    }
}

/// The error for a parameter name that `model` does not have.
pub(crate) fn unknown(model: &str, name: &str, known: &[&str]) -> Error {
    Error::invalid(
        name,
        format!(
            "model '{model}' has no such parameter (known: {})",
            known.join(", ")
        ),
    )
}

/// Panic for a symmetry or invariant index of a model that has none.
#[track_caller]
pub(crate) fn no_such_index(what: &str, model: &str, index: usize) -> ! {
    panic!("{model} has no {what} with index {index}")
}
