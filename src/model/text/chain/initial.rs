//! Initial states of a chain: an expression in the site index `i` and the parameters
//! evaluated at every site (`A*sin(pi*i/(n+1))`), the command line's `[initial] q = "…"`.

use nalgebra::DVector;

use crate::model::text::error::TextError;
use crate::model::text::expression::{Expression, Velocities};
use crate::model::text::names::intern;
use crate::model::text::tree::Names;

/// The values of `expressions` (one per family, in `i`, the site index from 1, and the
/// `parameters`) at every site 1..`sites`, stored site by site as a chain's coordinates
/// are: the field `field` (named in errors; `field[f]` for family f of several).
///
/// # Errors
/// A [`TextError`] naming the field, the column and the symbol of an expression that does
/// not parse, or [`TextError::Dimension`] for a number of expressions that is not the
/// number of families (`families`).
pub fn site_values(
    expressions: &[String],
    families: usize,
    field: &str,
    parameters: &[(&'static str, f64)],
    sites: usize,
) -> Result<DVector<f64>, TextError> {
    if expressions.len() != families {
        return Err(TextError::Dimension {
            field: field.into(),
            expected: families,
            found: expressions.len(),
        });
    }
    let parameter_names: Vec<&'static str> = parameters.iter().map(|(name, _)| *name).collect();
    let values: Vec<f64> = parameters.iter().map(|(_, value)| *value).collect();
    let names = Names {
        coordinates: &[intern("i")],
        velocities: &[],
        parameters: &parameter_names,
        phase_space: false,
        families: &[],
        size: None,
    };
    let tapes = expressions
        .iter()
        .enumerate()
        .map(|(f, text)| {
            let field = if families == 1 {
                field.to_string()
            } else {
                format!("{field}[{f}]")
            };
            Expression::parse(text, &field, &names).map(|e| e.compile(&values, Velocities::Read))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(DVector::from_fn(sites * families, |index, _| {
        let site = (index / families + 1) as f64;
        tapes[index % families].evaluate(0.0, &[site], &[])
    }))
}
