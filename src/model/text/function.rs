//! A function g(t, q, q̇) written as text over a model's names — an event of a run, or the
//! surface of a Poincaré section: `"x*vx + y*vy"`. The same grammar and tapes as a text
//! Lagrangian ([`super`]), with the model's coordinates, their velocities (`v` + the name),
//! `t` and the model's parameters (their current values folded in).

use super::error::TextError;
use super::expression::{Expression, Tape, Velocities};
use super::names::intern;
use super::tree::Names;
use crate::scalar::Scalar;

/// A function g(t, q, q̇) written as text, parsed and compiled once.
#[derive(Debug, Clone, PartialEq)]
pub struct TextFunction {
    text: String,
    tape: Tape,
}

impl TextFunction {
    /// Parse `text` (named `field` in errors) over the `coordinates` of a model, their
    /// velocities, `t` and the `parameters` (name, value).
    ///
    /// # Errors
    /// A [`TextError`] naming `field`: the expression's syntax, or a symbol that is none of
    /// those names.
    pub fn parse(
        text: &str,
        field: &str,
        coordinates: &[String],
        parameters: &[(String, f64)],
    ) -> Result<TextFunction, TextError> {
        let coordinate_names: Vec<&'static str> = coordinates.iter().map(|c| intern(c)).collect();
        let velocity_names: Vec<&'static str> = coordinates
            .iter()
            .map(|c| intern(&format!("v{c}")))
            .collect();
        let parameter_names: Vec<&'static str> =
            parameters.iter().map(|(name, _)| intern(name)).collect();
        let names = Names {
            coordinates: &coordinate_names,
            velocities: &velocity_names,
            parameters: &parameter_names,
            phase_space: true,
            families: &[],
            size: None,
        };
        let expression = Expression::parse(text, field, &names)?;
        let values: Vec<f64> = parameters.iter().map(|(_, value)| *value).collect();
        Ok(TextFunction {
            text: text.trim().to_string(),
            tape: expression.compile(&values, Velocities::Read),
        })
    }

    /// The expression, as written (without surrounding spaces).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// g(t, q, q̇), generic over the scalar.
    #[inline]
    pub fn evaluate<D: Scalar>(&self, t: D, q: &[D], v: &[D]) -> D {
        self.tape.evaluate(t, q, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_coordinates_velocities_time_and_parameters() {
        let names = ["x".to_string(), "y".to_string()];
        let g = TextFunction::parse("x*vx + y*vy - c*t", "event", &names, &[("c".into(), 2.0)])
            .unwrap();
        assert_eq!(g.evaluate(0.5, &[1.0, 2.0], &[3.0, 4.0]), 3.0 + 8.0 - 1.0);
        assert_eq!(g.text(), "x*vx + y*vy - c*t");
        let error = TextFunction::parse("z + 1", "event", &names, &[]).unwrap_err();
        assert!(error.to_string().contains('z'), "{error}");
        assert!(TextFunction::parse("x +", "event", &names, &[]).is_err());
    }
}
