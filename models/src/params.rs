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

/// The largest number of particles of a chain or lattice model (vectors of 10⁷ numbers are
/// 80 MB each).
pub(crate) const MAX_SIZE: usize = 10_000_000;

/// Check that `value` is a whole number of particles from `min` to [`MAX_SIZE`].
pub(crate) fn size(name: &str, value: f64, min: usize) -> Result<usize, Error> {
    finite(name, value)?;
    if value.fract() != 0.0 || value < min as f64 || value > MAX_SIZE as f64 {
        return Err(Error::invalid(
            name,
            format!("{value:?} must be a whole number from {min} to {MAX_SIZE}"),
        ));
    }
    Ok(value as usize)
}
