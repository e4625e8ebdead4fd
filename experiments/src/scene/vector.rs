//! The initial state of a scene on ℝᴺ: `[initial]`'s t0, q and one of v, p, against the
//! model's dimension and defaults (fixed N, or the n of a runtime-dimension model, whose
//! vectors may also be given by an expression per site).

use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector, U1};
use svi::Initial;
use svi::{Dimension, Dyn};

use crate::scene::error::SceneError;
use crate::scene::schema::{Components, InitialSection};

/// Evaluates per-site expressions of a chain's initial vector: given the field (`q`, `v` or
/// `p`) and the expressions, one per family, the vector.
pub type SiteValues<'a> = &'a dyn Fn(&'static str, &[String]) -> Result<DVector<f64>, SceneError>;

/// The option naming the field `field` (`q`, `v` or `p`) of `[initial]`.
fn option(field: &str) -> &'static str {
    match field {
        "q" => "initial.q",
        "v" => "initial.v",
        _ => "initial.p",
    }
}

/// The initial state of `section` for a model of dimension `N` named `model` (whose number of
/// coordinates is the length of `default_q`): the given q (else `default_q`) with the given v
/// or p (else `default_v`). An error names a vector whose length is not that number, or both
/// v and p.
pub fn initial<N: Dimension>(
    section: &InitialSection,
    model: &str,
    default_q: OVector<f64, N>,
    default_v: OVector<f64, N>,
) -> Result<Initial<N>, SceneError>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let n = default_q.shape_generic().0;
    let vector = |field: &'static str, components: &Option<Components>| {
        components
            .as_ref()
            .map(|components| {
                let Components::Values(values) = components else {
                    return Err(SceneError::NotApplicable {
                        option: option(field),
                        reason: format!(
                            "an expression per site sets the initial state of a chain; model \
                             '{model}' takes its {} components as numbers",
                            n.value()
                        ),
                    });
                };
                if values.len() == n.value() {
                    Ok(OVector::<f64, N>::from_iterator_generic(
                        n,
                        U1,
                        values.iter().copied(),
                    ))
                } else {
                    Err(SceneError::Dimension {
                        model: model.into(),
                        field,
                        expected: n.value(),
                        found: values.len(),
                    })
                }
            })
            .transpose()
    };
    let q = vector("q", &section.q)?.unwrap_or(default_q);
    Ok(match (vector("v", &section.v)?, vector("p", &section.p)?) {
        (Some(_), Some(_)) => return Err(SceneError::VelocityAndMomentum),
        (Some(v), None) => Initial::Velocity { q, v },
        (None, Some(p)) => Initial::Momentum { q, p },
        (None, None) => Initial::Velocity { q, v: default_v },
    })
}

/// [`initial`] for a runtime-dimension model named `model`, whose n is the length of its
/// default state: the given q (else `default_q`) with the given v or p (else `default_v`),
/// each as its n numbers or by expressions that `sites` evaluates at every site (given the
/// field and the expressions, one per family). An error names a vector whose length is not
/// n, or both v and p.
pub fn local_initial(
    section: &InitialSection,
    model: &str,
    default_q: DVector<f64>,
    default_v: DVector<f64>,
    sites: SiteValues<'_>,
) -> Result<svi::Initial<Dyn>, SceneError> {
    let n = default_q.len();
    let vector = |field: &'static str, components: &Option<Components>| {
        components
            .as_ref()
            .map(|components| {
                let values = match components {
                    Components::Values(values) => values,
                    expressions => {
                        let expressions = expressions.expressions().unwrap_or_default();
                        return sites(field, &expressions);
                    }
                };
                if values.len() == n {
                    Ok(DVector::from_column_slice(values))
                } else {
                    Err(SceneError::Dimension {
                        model: model.into(),
                        field,
                        expected: n,
                        found: values.len(),
                    })
                }
            })
            .transpose()
    };
    let q = vector("q", &section.q)?.unwrap_or(default_q);
    Ok(match (vector("v", &section.v)?, vector("p", &section.p)?) {
        (Some(_), Some(_)) => return Err(SceneError::VelocityAndMomentum),
        (Some(v), None) => svi::Initial::Velocity { q, v },
        (None, Some(p)) => svi::Initial::Momentum { q, p },
        (None, None) => svi::Initial::Velocity { q, v: default_v },
    })
}
