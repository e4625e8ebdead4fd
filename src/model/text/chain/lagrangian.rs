//! [`TextChain`]: a [`TextChainModel`] behind [`LocalLagrangian`] with terms of a width fixed
//! at compile time, its value and force run on batches of sites by the programs of each kind
//! of term (see [the module docs](super)).

use nalgebra::{Const, DVector, SVector};

use super::compiled::Kind;
use super::{TextChainModel, clamp};
use crate::error::Error;
use crate::model::Structure;
use crate::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian, TermWidth};
use crate::model::text::TextModel;
use crate::model::text::batch::{LANES, Lanes, MAX_REGISTERS, Program, Registers};
use crate::model::text::error::TextError;
use crate::scalar::Scalar;

/// A [`TextChainModel`] as a [`LocalLagrangian`] with terms K = `WIDTH` coordinates wide (the
/// model's [`TextChainModel::width`]), with [`LocalDefaults`] and [`LocalInvariants`] (none).
///
/// The other parameters are the model's declarations, as for
/// [`TextLagrangian`](crate::model::text::TextLagrangian): [`LocalLagrangian::TIME_DEPENDENT`]
/// and `CONSTANT_MASS` for [`Structure::ConstantMass`]; the defaults (time-dependent, general)
/// fit every model, and [`TextChain::new`] rejects declarations the model does not allow.
#[derive(Debug, Clone, PartialEq)]
pub struct TextChain<
    const WIDTH: usize,
    const TIME_DEPENDENT: bool = true,
    const CONSTANT_MASS: bool = false,
> {
    model: TextChainModel,
}

impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool>
    TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
{
    /// `model` as a [`LocalLagrangian`] with the type's width and declarations.
    ///
    /// # Errors
    /// [`TextError::Declaration`] if `WIDTH` is not the model's width, or a declaration does
    /// not hold: `TIME_DEPENDENT = false` with `t` in L, `CONSTANT_MASS = true` for a model
    /// not recognised as constant-mass.
    pub fn new(model: TextChainModel) -> Result<Self, TextError> {
        let declaration = |reason: String| {
            Err(TextError::Declaration {
                holder: "TextChain",
                reason,
            })
        };
        if model.width() != WIDTH {
            return declaration(format!(
                "the chain's terms read {} coordinates, but WIDTH = {WIDTH}",
                model.width()
            ));
        }
        if model.time_dependent() && !TIME_DEPENDENT {
            return declaration("L depends on t, but TIME_DEPENDENT = false".into());
        }
        if CONSTANT_MASS && model.structure() != Structure::ConstantMass {
            return declaration(
                "CONSTANT_MASS = true, but the terms are not recognised as ½q̇ᵀMq̇ − V(t, q)".into(),
            );
        }
        Ok(TextChain { model })
    }

    /// The model.
    pub fn model(&self) -> &TextChainModel {
        &self.model
    }
}

impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> LocalLagrangian
    for TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
{
    type Width = Const<WIDTH>;
    const TIME_DEPENDENT: bool = TIME_DEPENDENT;
    const STRUCTURE: Structure = if CONSTANT_MASS {
        Structure::ConstantMass
    } else {
        Structure::General
    };

    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    fn term_count(&self) -> usize {
        self.model.term_count()
    }

    /// A site term reads its window site by site, family by family; a slot outside a fixed
    /// chain repeats the nearest site's index (and its term does not read it).
    #[inline]
    fn indices(&self, term: usize) -> [usize; WIDTH] {
        let model = &self.model;
        let compiled = &model.compiled;
        if term >= compiled.site_terms {
            return match &compiled.rest {
                Some((_, indices)) => std::array::from_fn(|slot| indices[slot]),
                None => [0; WIDTH],
            };
        }
        let families = model.families.len();
        let n = compiled.sites;
        let site = compiled.first + term as i64 + model.window.0;
        std::array::from_fn(|slot| {
            // Slots beyond the window (a rest wider than it) repeat the first.
            let slot = if slot < families * (model.window.1 - model.window.0 + 1) as usize {
                slot
            } else {
                0
            };
            let at = site + (slot / families) as i64;
            let at = model.wrap(at, n).unwrap_or_else(|| clamp(at, n));
            model.coordinate(at, slot % families)
        })
    }

    #[inline]
    fn term<D: Scalar>(
        &self,
        term: usize,
        t: D,
        q: &SVector<D, WIDTH>,
        v: &SVector<D, WIDTH>,
    ) -> D {
        let kind = self.model.compiled.kind(term);
        if CONSTANT_MASS && let Some(split) = &kind.split {
            return split.evaluate(t, q.as_slice(), v.as_slice());
        }
        kind.tape.evaluate(t, q.as_slice(), v.as_slice())
    }

    /// Each segment of sites of one kind in batches of `LANES` by its program (see
    /// [the module docs](super)); a kind without one, and the rest's term, term by term.
    fn value(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        let mut sum = 0.0;
        self.batches(
            &mut sum,
            |kind| kind.value.as_ref(),
            |sum, program, registers, lanes| {
                *sum += program.sum(registers, lanes, t, q.as_slice(), v.as_slice());
            },
            |sum, term| *sum += Const::<WIDTH>::value(self, term, t, q, v),
        );
        sum
    }

    /// Each segment of sites of one kind in batches of `LANES` by its program (see
    /// [the module docs](super)); a kind without one, and the rest's term, term by term.
    fn force_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        out.as_mut_slice().fill(0.0);
        self.batches(
            out,
            |kind| kind.force.as_ref(),
            |out, program, registers, lanes| {
                let (q, v) = (q.as_slice(), v.as_slice());
                program.add_force(registers, lanes, t, q, v, out.as_mut_slice());
            },
            |out, term| Const::<WIDTH>::scatter_gradient(self, term, t, q, v, false, out),
        );
    }
}

impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool>
    TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
{
    /// Walk the terms with `state`: each segment of sites whose kind has a `program` in
    /// batches of [`LANES`] (`batch`), the other terms and the rest's one by one (`term`).
    #[inline]
    fn batches<'a, S>(
        &'a self,
        state: &mut S,
        program: impl Fn(&'a Kind) -> Option<&'a Program>,
        mut batch: impl FnMut(&mut S, &'a Program, &mut Registers, Lanes<'_>),
        mut term: impl FnMut(&mut S, usize),
    ) {
        let compiled = &self.model.compiled;
        let stride = self.model.families.len();
        let mut registers: Registers = [[0.0; LANES]; MAX_REGISTERS];
        let mut start = 0;
        for segment in &compiled.segments {
            match program(&compiled.kinds[segment.kind]) {
                Some(program) => {
                    for first in (start..segment.end).step_by(LANES) {
                        // Within a segment each slot's index grows by `stride` a site.
                        let bases = self.indices(first);
                        let lanes = Lanes {
                            count: LANES.min(segment.end - first),
                            bases: &bases,
                            stride,
                        };
                        batch(state, program, &mut registers, lanes);
                    }
                }
                None => (start..segment.end).for_each(|e| term(state, e)),
            }
            start = segment.end;
        }
        (compiled.site_terms..self.term_count()).for_each(|e| term(state, e));
    }
}

impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> LocalInvariants
    for TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
{
}

impl<const WIDTH: usize, const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> LocalDefaults
    for TextChain<WIDTH, TIME_DEPENDENT, CONSTANT_MASS>
{
    /// [`TextModel::NAME`].
    fn name(&self) -> &'static str {
        TextModel::NAME
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.model.parameters()
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        self.model.set_parameter(name, value)
    }

    /// A text chain has no literature defaults: at rest at zero at t = 0 (give the initial
    /// state, e.g. by [`site_values`](super::site_values)).
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let n = self.model.dimension();
        (0.0, DVector::zeros(n), DVector::zeros(n))
    }

    /// A placeholder, 0.01 (give the step).
    fn default_step(&self) -> f64 {
        0.01
    }

    /// A placeholder, 10 (give the horizon).
    fn default_horizon(&self) -> f64 {
        10.0
    }
}
