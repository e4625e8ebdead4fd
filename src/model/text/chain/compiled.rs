//! The terms of a chain for its current parameters (see [the module docs](super)): the sites
//! of the sums' ranges fall into segments, each of one kind of term, compiled once into a
//! tape over its K slots and into the programs of its value and force; and the check that
//! every coordinate's velocity appears in some term.

use super::{Boundary, MAX_WIDTH, TextChainModel, clamp, resolve};
use crate::model::text::batch::Program;
use crate::model::text::error::TextError;
use crate::model::text::expression::{Expression, Split, Tape, Velocities};
use crate::model::text::tree::{Index, Node, Symbol};

/// The terms of a chain for its current parameters (n among them).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Compiled {
    /// n.
    pub(super) sites: usize,
    /// The site of term 0.
    pub(super) first: i64,
    /// The number of site terms (the rest's term, if any, comes after them).
    pub(super) site_terms: usize,
    /// Consecutive runs of site terms of one kind, by their end (exclusive).
    pub(super) segments: Vec<Segment>,
    pub(super) kinds: Vec<Kind>,
    /// The rest's term and its indices.
    pub(super) rest: Option<(Kind, Vec<usize>)>,
}

/// A run of site terms of one kind: terms up to `end` (exclusive) from the previous run's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Segment {
    pub(super) end: usize,
    pub(super) kind: usize,
}

/// One kind of term, compiled over its K slots.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Kind {
    pub(super) tape: Tape,
    /// For a constant-mass kind: its two parts.
    pub(super) split: Option<Split>,
    /// Its value and its force ∂ℓ/∂q as programs on batches of sites (`None`: too many
    /// registers).
    pub(super) value: Option<Program>,
    pub(super) force: Option<Program>,
}

impl TextChainModel {
    /// The terms for the parameter values `values`.
    pub(super) fn compile(&self, values: &[f64]) -> Result<Compiled, TextError> {
        // check_size has made the size a whole number from 1 to MAX_SITES.
        let n = values[self.size] as usize;
        let (a, b) = self.window;
        let ranges: Vec<Option<(i64, i64)>> = self
            .sums
            .iter()
            .map(|sum| {
                let (lower, upper) = (resolve(sum.lower, n), resolve(sum.upper, n));
                (lower <= upper).then_some((lower, upper))
            })
            .collect();
        for (sum, range) in self.sums.iter().zip(&ranges) {
            if let Some((lower, upper)) = *range
                && (lower + b < 1 || upper + a > n as i64)
            {
                return Err(TextError::Indexing {
                    field: "lagrangian".into(),
                    column: sum.column,
                    symbol: "sum".into(),
                    message: format!(
                        "for n = {n} the sum runs from {lower} to {upper}: its {} terms read no \
                         site of 1..{n}",
                        if lower + b < 1 { "first" } else { "last" }
                    ),
                });
            }
        }
        self.check_velocities(n, &ranges)?;
        let (first, last) = ranges
            .iter()
            .flatten()
            .fold(None, |extent: Option<(i64, i64)>, &(lower, upper)| {
                Some(extent.map_or((lower, upper), |(l, u)| (l.min(lower), u.max(upper))))
            })
            .unwrap_or((1, 0));
        // Where the kind of a site term may change: the ends of the ranges, and under fixed
        // boundaries where a slot of the window leaves the chain.
        let mut breaks: Vec<i64> = vec![first, last + 1];
        for &(lower, upper) in ranges.iter().flatten() {
            breaks.extend([lower, upper + 1]);
        }
        // (Fixed or periodic: where a slot wraps around too, so that within a segment each
        // slot's index is linear in the site, as the force's batches read it. The sites lie
        // within a window's span of 1..n, and the span is below MAX_WIDTH.)
        let wraps = MAX_WIDTH as i64 + 1;
        for k in a..=b {
            for m in -wraps..=wraps {
                breaks.push(1 + m * n as i64 - k);
            }
        }
        breaks.retain(|&site| first <= site && site <= last + 1);
        breaks.sort_unstable();
        breaks.dedup();
        let parameter_count = self.parameter_names.len();
        let mut keys: Vec<(Vec<bool>, Vec<bool>)> = Vec::new();
        let mut kinds = Vec::new();
        let mut segments = Vec::new();
        for pair in breaks.windows(2) {
            let site = pair[0];
            let active: Vec<bool> = ranges
                .iter()
                .map(|range| range.is_some_and(|(lower, upper)| lower <= site && site <= upper))
                .collect();
            let outside =
                |k: i64| self.boundary == Boundary::Fixed && !(1..=n as i64).contains(&(site + k));
            let masked: Vec<bool> = (a..=b).map(outside).collect();
            let key = (active, masked);
            let kind = match keys.iter().position(|known| *known == key) {
                Some(kind) => kind,
                None => {
                    let expression = self.site_expression(&key.0, &outside, parameter_count)?;
                    kinds.push(Kind::of(&expression, values, self.width));
                    keys.push(key);
                    kinds.len() - 1
                }
            };
            segments.push(Segment {
                end: usize::try_from(pair[1] - first).unwrap_or(usize::MAX),
                kind,
            });
        }
        let rest = if self.rest.is_empty() {
            None
        } else {
            let site_of = |index: Index| self.wrap(resolve(index, n), n);
            let expression = self.rest_expression(&site_of, parameter_count)?;
            let mut indices: Vec<usize> = self
                .rest_sites
                .iter()
                .map(|&(family, index)| {
                    let site = site_of(index).unwrap_or_else(|| clamp(resolve(index, n), n));
                    self.coordinate(site, family)
                })
                .collect();
            indices.resize(self.width, indices.first().copied().unwrap_or(0));
            Some((Kind::of(&expression, values, self.width), indices))
        };
        Ok(Compiled {
            sites: n,
            first,
            site_terms: usize::try_from(last - first + 1).unwrap_or(0),
            segments,
            kinds,
            rest,
        })
    }

    /// Whether, for `n` sites and the sums' ranges, every coordinate's velocity appears in
    /// some term; else [`TextError::NoVelocity`] for the first site without.
    fn check_velocities(&self, n: usize, ranges: &[Option<(i64, i64)>]) -> Result<(), TextError> {
        for (family, name) in self.families.iter().enumerate() {
            let mut intervals: Vec<(i64, i64)> = Vec::new();
            for (sum, range) in self.sums.iter().zip(ranges) {
                let Some((lower, upper)) = *range else {
                    continue;
                };
                for &(f, k) in &sum.velocities {
                    if f == family {
                        intervals.push((lower + k, upper + k));
                    }
                }
            }
            for node in &self.tree {
                if let Node::Symbol(Symbol::Site(site)) = node
                    && site.velocity
                    && site.family == family
                    && let Some(site) = site.index.resolve(n)
                {
                    intervals.push((site, site));
                }
            }
            let n = n as i64;
            let mut covered: Vec<(i64, i64)> = Vec::new();
            for (lower, upper) in intervals {
                match self.boundary {
                    Boundary::Fixed => covered.push((lower.max(1), upper.min(n))),
                    Boundary::Periodic if upper - lower + 1 >= n => covered.push((1, n)),
                    Boundary::Periodic => {
                        let start = (lower - 1).rem_euclid(n) + 1;
                        let end = start + (upper - lower);
                        covered.push((start, end.min(n)));
                        if end > n {
                            covered.push((1, end - n));
                        }
                    }
                }
            }
            covered.sort_unstable();
            let mut next = 1;
            for (lower, upper) in covered {
                if lower > next {
                    break;
                }
                next = next.max(upper + 1);
            }
            if next <= n {
                return Err(TextError::NoVelocity {
                    coordinate: format!("{name}[{next}]"),
                    velocity: format!("v{name}[{next}]"),
                });
            }
        }
        Ok(())
    }
}

impl Compiled {
    /// No terms (before the first compilation).
    pub(super) fn empty() -> Compiled {
        Compiled {
            sites: 0,
            first: 1,
            site_terms: 0,
            segments: Vec::new(),
            kinds: Vec::new(),
            rest: None,
        }
    }

    /// The kind of term `term`.
    #[inline]
    pub(super) fn kind(&self, term: usize) -> &Kind {
        if term < self.site_terms {
            let segment = self.segments.partition_point(|segment| segment.end <= term);
            &self.kinds[self.segments[segment].kind]
        } else {
            match &self.rest {
                Some((kind, _)) => kind,
                None => panic!("term {term} of a chain of {} terms", self.site_terms),
            }
        }
    }
}

impl Kind {
    /// The tape, the constant-mass split and the programs of `expression` over `width`
    /// slots.
    fn of(expression: &Expression, values: &[f64], width: usize) -> Kind {
        let tape = expression.compile(values, Velocities::Read);
        let split = Split::of(expression, values, width);
        // ∂ℓ/∂q of a constant-mass term is its potential's.
        let force = Program::force(split.as_ref().map_or(&tape, Split::potential), width);
        Kind {
            value: Program::value(&tape),
            tape,
            split,
            force,
        }
    }
}
