//! Holonomic constraints written as text: `constraints = ["x^2 + y^2 - l^2"]`, each an
//! expression g(q) in the coordinates and the parameters of a [`TextModel`](super::TextModel),
//! parsed with the model's names ([`parse_constraints`]) and compiled into the same tapes as
//! L. [`TextConstraints`] puts them behind [`Constraints<N>`], so the constrained integrators
//! take their Jacobian by automatic differentiation as for constraints written in Rust, and
//! name each in messages by its expression.
//!
//! A constraint reads no velocity (it is holonomic: a velocity constraint is not g(q) = 0) and
//! not the time (the integrators hold g fixed in time); one that reads no coordinate at all
//! constrains nothing. Each is a [`TextError::Constraint`] that quotes the expression.

use nalgebra::DefaultAllocator;
use nalgebra::OVector;
use nalgebra::allocator::Allocator;

use super::error::TextError;
use super::expression::{Expression, Tape, Velocities};
use super::tree::Names;
use crate::dimension::Dimension;
use crate::model::constraint::Constraints;
use crate::scalar::Scalar;

/// The field that names constraint `index` with its text in errors: `constraints[1] = "…"`.
fn field(index: usize, text: &str) -> String {
    format!("constraints[{index}] = \"{}\"", text.trim())
}

/// Parse the constraints `texts` with the coordinates and parameters of `names` (velocities
/// and `t` are read only to name them in an error).
///
/// # Errors
/// A [`TextError`] naming the constraint and quoting it: the expression's syntax or an unknown
/// symbol, or [`TextError::Constraint`] for one that reads a velocity or the time or no
/// coordinate at all.
pub(super) fn parse_constraints(
    texts: &[String],
    names: &Names<'_>,
) -> Result<Vec<Expression>, TextError> {
    let configuration = Names {
        phase_space: false,
        ..*names
    };
    texts
        .iter()
        .enumerate()
        .map(|(index, text)| {
            let field = field(index, text);
            let refuse = |reason: String| {
                Err(TextError::Constraint {
                    constraint: text.trim().into(),
                    reason,
                })
            };
            match Expression::parse(text, &field, &configuration) {
                Ok(expression) if !expression.uses_coordinates() => refuse(
                    "it does not depend on the coordinates, so it constrains nothing (a \
                     constraint is g(q) = 0, with q among the coordinates)"
                        .into(),
                ),
                Ok(expression) => Ok(expression),
                Err(TextError::UnknownSymbol { symbol, .. })
                    if names.velocities.contains(&symbol.as_str()) =>
                {
                    refuse(format!(
                        "it reads the velocity {symbol}: a holonomic constraint g(q) = 0 depends \
                         on the coordinates and parameters only"
                    ))
                }
                Err(TextError::UnknownSymbol { symbol, .. }) if symbol == "t" => refuse(
                    "it reads the time t: constraints that move in time (g(t, q) = 0) are not \
                     supported; write g(q)"
                        .into(),
                ),
                Err(error) => Err(error),
            }
        })
        .collect()
}

/// The holonomic constraints of a text model as [`Constraints<N>`]: g(q) by the compiled tapes
/// of the expressions, each named by its text ([`Constraints::constraint_name`]).
///
/// Made by [`TextModel::constraints`](super::TextModel::constraints) for the model's current
/// parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct TextConstraints {
    texts: Vec<String>,
    tapes: Vec<Tape>,
}

impl TextConstraints {
    /// The constraints of the expressions `expressions` (written `texts`) compiled with
    /// `parameters`.
    pub(super) fn compile(
        texts: &[String],
        expressions: &[Expression],
        parameters: &[f64],
    ) -> TextConstraints {
        TextConstraints {
            texts: texts.iter().map(|text| text.trim().to_string()).collect(),
            tapes: expressions
                .iter()
                .map(|expression| expression.compile(parameters, Velocities::Zero))
                .collect(),
        }
    }

    /// The expressions, as written (without surrounding spaces).
    pub fn texts(&self) -> &[String] {
        &self.texts
    }
}

impl<N: Dimension> Constraints<N> for TextConstraints
where
    DefaultAllocator: Allocator<N>,
{
    fn count(&self) -> usize {
        self.tapes.len()
    }

    #[inline]
    fn constraints<D: Scalar>(&self, q: &OVector<D, N>, g: &mut [D]) {
        let zero = D::from(0.0);
        for (value, tape) in g.iter_mut().zip(&self.tapes) {
            *value = tape.evaluate(zero, q.as_slice(), &[]);
        }
    }

    /// The expression, as written.
    fn constraint_name(&self, index: usize) -> String {
        self.texts
            .get(index)
            .cloned()
            .unwrap_or_else(|| format!("g[{index}]"))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::spec;
    use super::super::{TextModel, TextSpec};
    use super::*;
    use crate::dimension::Dyn;
    use crate::model::constraint::ConstraintsExt;
    use nalgebra::{DVector, U3};

    fn pendulum(constraints: &[&str]) -> TextSpec {
        TextSpec {
            parameters: vec![("l".into(), 2.0)],
            constraints: constraints.iter().map(|text| (*text).into()).collect(),
            ..spec("0.5*(vx^2 + vy^2 + vz^2) - 9.81*z", &["x", "y", "z"])
        }
    }

    #[test]
    fn constraints_evaluate_with_their_jacobian_and_are_named_by_their_text() {
        let model = TextModel::new(&pendulum(&[" x^2 + y^2 + z^2 - l^2", "x - y"])).unwrap();
        let constraints = model.constraints();
        let q = DVector::from_vec(vec![1.0, 2.0, 3.0]);
        assert_eq!(Constraints::<Dyn>::count(&constraints), 2);
        assert_eq!(constraints.values(&q).as_slice(), &[14.0 - 4.0, -1.0]);
        let jacobian = ConstraintsExt::<Dyn>::jacobian(&constraints, &q);
        assert_eq!(
            jacobian.row(0).iter().copied().collect::<Vec<_>>(),
            [2.0, 4.0, 6.0]
        );
        assert_eq!(
            jacobian.row(1).iter().copied().collect::<Vec<_>>(),
            [1.0, -1.0, 0.0]
        );
        assert_eq!(
            Constraints::<U3>::constraint_name(&constraints, 0),
            "x^2 + y^2 + z^2 - l^2"
        );
        // Parameters are read at compilation: set_parameter recompiles the constraints too.
        let mut model = model;
        model.set_parameter("l", 1.0).unwrap();
        assert_eq!(model.constraints().values(&q)[0], 13.0);
    }

    #[test]
    fn velocities_time_constants_and_unknown_names_are_errors_quoting_the_constraint() {
        let refused = |text: &str| match TextModel::new(&pendulum(&["x^2 - 1", text])) {
            Err(error @ TextError::Constraint { .. }) => error.to_string(),
            other => panic!("{text}: {other:?}"),
        };
        let velocity = refused("x*vx");
        assert!(
            velocity.contains("'x*vx'") && velocity.contains("velocity vx"),
            "{velocity}"
        );
        let time = refused("x - t");
        assert!(
            time.contains("'x - t'") && time.contains("time t"),
            "{time}"
        );
        let constant = refused("l - 1");
        assert!(
            constant.contains("'l - 1'") && constant.contains("does not depend on the coordinates"),
            "{constant}"
        );
        let unknown = TextModel::new(&pendulum(&["x^2 + w^2 - 1"]))
            .unwrap_err()
            .to_string();
        assert!(
            unknown.contains("unknown symbol 'w'")
                && unknown.contains("constraints[0] = \"x^2 + w^2 - 1\""),
            "{unknown}"
        );
        let syntax = TextModel::new(&pendulum(&["x^2 +"])).unwrap_err();
        assert!(
            matches!(&syntax, TextError::Syntax { field, .. } if field.contains("x^2 +")),
            "{syntax}"
        );
        let empty = TextModel::new(&pendulum(&[" "])).unwrap_err();
        assert!(matches!(empty, TextError::Empty { .. }), "{empty}");
    }
}
