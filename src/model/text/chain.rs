//! Chains written as text: indexed coordinates and sums that compile to local terms.
//!
//! ```text
//! coordinates = ["q[1..n]"]          n a parameter: a positive whole number (--param n=…)
//! lagrangian  = "sum(i, 1, n, 0.5*vq[i]^2)
//!              - sum(i, 0, n, 0.5*(q[i+1]-q[i])^2 + alpha/3*(q[i+1]-q[i])^3 + beta/4*(q[i+1]-q[i])^4)"
//! boundary    = "fixed"              or "periodic"
//! ```
//!
//! is the Fermi–Pasta–Ulam–Tsingou chain with fixed ends, n particles, in one line. A
//! coordinate declared `q[1..n]` is a family of n coordinates q₁ … qₙ with velocities `vq[i]`;
//! several families (`["x[1..n]", "y[1..n]"]`) share the size n and are stored site by site
//! (x₁, y₁, x₂, y₂, …). The grammar of [the module](super) gains two forms:
//!
//! ```text
//! atom  := ... | family '[' index ']' | 'sum' '(' name ',' index ',' index ',' expression ')'
//! index := ['+' | '-'] term (('+' | '-') term)*      term := digits | n | the sum's index
//! ```
//!
//! with these rules, each broken rule a [`TextError::Indexing`] naming the column and the
//! symbol:
//! - inside `sum(i, lower, upper, body)` an index is `i + c` for an integer c (`q[i]`,
//!   `q[i+1]`, `vq[i-2]`): a term reads its neighbours, nothing far away;
//! - outside a sum an index is `c` or `n + c` (`q[1]`, `q[n]`, `vq[n-1]`); the index `i`
//!   itself is read only inside brackets;
//! - the bounds are `c` or `n + c`, the range `lower ≤ i ≤ upper` (empty if upper < lower),
//!   reaching at most a term's width beyond the sites 1..n;
//! - a sum is a term of L, added or subtracted (`sum(...) - sum(...) + rest`), never inside a
//!   product, a power, a function or another sum;
//! - forces and symmetry generators are not taken with indexed coordinates
//!   ([`TextError::Unsupported`]).
//!
//! # Boundaries
//!
//! An index outside 1..n reads, under [`Boundary::Fixed`], zero (the coordinate and its
//! velocity: walls at q₀ = q_{n+1} = 0), and under [`Boundary::Periodic`] the site it equals
//! modulo n (q_{n+1} = q₁, q₀ = qₙ; a sum over 1..n then counts each bond once, and one over
//! 0..n one bond twice).
//!
//! # Compilation to local terms
//!
//! Let [a, b] be the offsets the sums' bodies read (`q[i]` and `q[i+1]`: [0, 1]). The terms
//! of the [`LocalLagrangian`] are the sites s of the sums' ranges, each reading the window
//! s + a … s + b of every family — K = families × (b − a + 1) coordinates, the width — and
//! holding Σ ± body(s) over the sums whose range holds s; the terms of L outside the sums
//! (`- 0.5*k*q[1]^2`) are one more term, reading the sites they name. For FPUT that is
//! K = 2 and n + 1 terms, spring s with particle s's kinetic energy, as in the zoo's `fput`.
//!
//! Which sums hold a site, and which slots of its window fall outside 1..n, change only at
//! a few sites near the ends of the ranges and of the chain: the sites fall into segments,
//! each one kind of term, and each kind is compiled once into a `Tape` over the K slots
//! (with the constant-mass split of [`super`]). Under fixed boundaries a slot outside the
//! chain is the number 0 in its kind's tape, folded away at compile time; its index
//! repeats the nearest site's, which the term does not read (so its derivatives there are
//! zero). No index is ever invalid, and no term tests a mask when it runs. A periodic
//! window wraps its indices instead (with n below the window's span a coordinate fills
//! several slots, and the derivatives scattered there add up, as the chain rule asks).
//!
//! The force ∂L/∂q — the one derivative Störmer–Verlet and SVI's fixed point take at every
//! stage — and the value of L — the energy diagnostic's, at every step — do not run term by
//! term ([`LocalLagrangian::force_into`] and [`LocalLagrangian::value`] are overridden): each
//! kind's tape is compiled once into straight-line programs, the force's by reverse-mode
//! differentiation, that run on batches of 32 sites at once (the private module `batch`
//! explains them); within a segment each slot's index grows by the number of families from
//! one site to the next, so a batch reads and writes evenly spaced entries. The other
//! derivatives (momenta, the mass matrix, the Hessian blocks of sparse Newton) are taken
//! term by term, by the dual numbers of every [`LocalLagrangian`].
//!
//! K is a compile-time constant of [`LocalLagrangian`]; [`TextChain<K, …>`] exists for
//! K = 1 … [`MAX_WIDTH`], and `svi_models::visit_text_chain` picks the one a model needs.
//!
//! # What the text declares
//!
//! As for [`super::TextModel`]: time dependence when `t` appears, and
//! [`Structure::ConstantMass`] when every sum's body and the rest is, by its structure, a
//! sum of terms free of q̇ and of terms quadratic in q̇ with constant coefficients, with no
//! term linear in q̇ — then Störmer–Verlet runs explicitly and SVI by its Hessian-free fixed
//! point. Every coordinate's velocity must appear in some term (else [`TextError::NoVelocity`]
//! names the site).
//!
//! # Initial states
//!
//! [`site_values`] evaluates an expression in the site index `i` and the parameters at every
//! site (`A*sin(pi*i/(n+1))`): the command line's `[initial] q = "…"`.

use std::collections::BTreeMap;

use nalgebra::{Const, DVector, SVector};

use super::batch::{LANES, Lanes, MAX_REGISTERS, Program, Registers};
use super::expression::{Expression, Split, Tape, Velocities};
use super::parse::parse;
use super::tree::{Base, Index, Names, Node, Site, Symbol};
use super::{Declared, TextError, TextModel, TextSpec, intern, named_values, parameter_index};
use crate::error::Error;
use crate::model::Structure;
use crate::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian, TermWidth};
use crate::scalar::Scalar;

/// The widest term a chain compiles to: K ≤ 4 coordinates (families × sites of a window).
pub const MAX_WIDTH: usize = 4;

/// The largest size n of a chain (vectors of 10⁷ numbers are 80 MB each).
pub const MAX_SITES: usize = 10_000_000;

/// What an index outside 1..n of a chain reads.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Boundary {
    /// Zero: the coordinate and its velocity (walls at q₀ = q_{n+1} = 0).
    #[default]
    Fixed,
    /// The site equal to it modulo n (q_{n+1} = q₁).
    Periodic,
}

/// One sum of L: its sign, range and body (a node of the model's parse tree).
#[derive(Debug, Clone, PartialEq)]
struct SumTerm {
    negative: bool,
    lower: Index,
    upper: Index,
    body: usize,
    /// Column of `sum` in the lagrangian.
    column: usize,
    /// The (family, offset) of every velocity the body reads.
    velocities: Vec<(usize, i64)>,
}

/// A chain written as text, parsed, of any width; [`TextChain`] puts it behind
/// [`LocalLagrangian`]. See the [module docs](self).
#[derive(Debug, Clone, PartialEq)]
pub struct TextChainModel {
    families: Vec<&'static str>,
    /// The size parameter, by its index among the parameters.
    size: usize,
    parameter_names: Vec<&'static str>,
    parameter_values: Vec<f64>,
    boundary: Boundary,
    /// The parse tree of L, sums standing as zeros.
    tree: Vec<Node>,
    sums: Vec<SumTerm>,
    /// The terms of L outside the sums.
    rest: Rest,
    /// The sites the rest reads, (family, index), in the order of its slots.
    rest_sites: Vec<(usize, Index)>,
    /// The offsets [a, b] the sums read.
    window: (i64, i64),
    width: usize,
    time_dependent: bool,
    constant_mass: bool,
    /// The terms for the current parameters.
    compiled: Compiled,
}

/// The terms of a chain for its current parameters (n among them).
#[derive(Debug, Clone, PartialEq)]
struct Compiled {
    /// n.
    sites: usize,
    /// The site of term 0.
    first: i64,
    /// The number of site terms (the rest's term, if any, comes after them).
    site_terms: usize,
    /// Consecutive runs of site terms of one kind, by their end (exclusive).
    segments: Vec<Segment>,
    kinds: Vec<Kind>,
    /// The rest's term and its indices.
    rest: Option<(Kind, Vec<usize>)>,
}

/// A run of site terms of one kind: terms up to `end` (exclusive) from the previous run's.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Segment {
    end: usize,
    kind: usize,
}

/// One kind of term, compiled over its K slots.
#[derive(Debug, Clone, PartialEq)]
struct Kind {
    tape: Tape,
    /// For a constant-mass kind: its two parts.
    split: Option<Split>,
    /// Its value and its force ∂ℓ/∂q as programs on batches of sites (`None`: too many
    /// registers).
    value: Option<Program>,
    force: Option<Program>,
}

impl TextChainModel {
    /// Check the names, the size and the indexing rules of `spec` and compile its terms.
    ///
    /// # Errors
    /// A [`TextError`] naming the field, and for an expression the column and the symbol.
    pub fn new(spec: &TextSpec) -> Result<TextChainModel, TextError> {
        for (given, field) in [
            (!spec.forces.is_empty(), "forces"),
            (!spec.symmetries.is_empty(), "symmetries"),
        ] {
            if given {
                return Err(TextError::Unsupported {
                    field: field.into(),
                    reason: "a chain of indexed coordinates takes neither forces nor symmetry \
                             generators yet"
                        .into(),
                });
            }
        }
        if spec.coordinates.is_empty() {
            return Err(TextError::NoCoordinates);
        }
        let mut families = Vec::new();
        let mut size_name = None;
        for declaration in &spec.coordinates {
            let (family, size) = family_declaration(declaration)?;
            if size_name.is_some_and(|known| known != size) {
                return Err(TextError::InvalidName {
                    role: "coordinate",
                    name: declaration.clone(),
                    reason: format!(
                        "the families of a chain share one size: {} before",
                        size_name.unwrap_or_default()
                    ),
                });
            }
            size_name = Some(size);
            families.push(family);
        }
        let size_name = size_name.unwrap_or_default();
        let declared = Declared::check(&families, &spec.parameters)?;
        let Some(size) = declared
            .parameter_names
            .iter()
            .position(|name| *name == size_name)
        else {
            return Err(TextError::InvalidName {
                role: "coordinate",
                name: spec.coordinates[0].clone(),
                reason: format!("its size '{size_name}' is not a parameter"),
            });
        };
        check_size(size_name, declared.parameter_values[size])?;
        let mut family_names = declared.coordinates.clone();
        family_names.extend(&declared.velocities);
        let names = Names {
            coordinates: &[],
            velocities: &[],
            parameters: &declared.parameter_names,
            phase_space: true,
            families: &family_names,
            size: Some(declared.parameter_names[size]),
        };
        let tree = parse(&spec.lagrangian, "lagrangian", &names)?;
        let (sums, rest) = terms(&tree.nodes, tree.root, &tree.sums)?;
        let family_count = families.len();
        // The offsets of the sums and the sites of the rest.
        let mut window: Option<(i64, i64)> = None;
        let mut rest_sites: Vec<(usize, Index)> = Vec::new();
        for node in &tree.nodes {
            if let Node::Symbol(Symbol::Site(site)) = node {
                if site.index.base == Base::Sum {
                    let k = site.index.offset;
                    window = Some(window.map_or((k, k), |(a, b)| (a.min(k), b.max(k))));
                } else if !rest_sites.contains(&(site.family, site.index)) {
                    rest_sites.push((site.family, site.index));
                }
            }
        }
        let window = window.unwrap_or((0, 0));
        let span = usize::try_from(window.1 - window.0 + 1).unwrap_or(usize::MAX);
        let site_width = family_count.saturating_mul(span);
        let width = site_width.max(rest_sites.len()).max(1);
        if width > MAX_WIDTH {
            let what = if site_width >= rest_sites.len() {
                format!(
                    "{family_count} famil{} × {span} sites, offsets {} to {} of a sum's index",
                    if family_count == 1 { "y" } else { "ies" },
                    window.0,
                    window.1
                )
            } else {
                format!("{} coordinates named outside the sums", rest_sites.len())
            };
            return Err(TextError::TooWide {
                width,
                what,
                limit: MAX_WIDTH,
            });
        }
        let mut model = TextChainModel {
            families: declared.coordinates,
            size,
            parameter_names: declared.parameter_names,
            parameter_values: declared.parameter_values,
            boundary: spec.boundary,
            tree: tree.nodes,
            sums,
            rest,
            rest_sites,
            window,
            width,
            time_dependent: false,
            constant_mass: true,
            compiled: Compiled::empty(),
        };
        // What the text declares, from each sum's body with every slot read and the rest
        // with every site named; the combination of all sums bounds every kind's depth.
        let parameter_count = model.parameter_names.len();
        let mut parts: Vec<Expression> = Vec::new();
        for sum in 0..model.sums.len() {
            let mut active = vec![false; model.sums.len()];
            active[sum] = true;
            parts.push(model.site_expression(&active, &|_| false, parameter_count)?);
        }
        if !model.rest.is_empty() {
            parts.push(model.rest_expression(&|_| None, parameter_count)?);
        }
        model.site_expression(&vec![true; model.sums.len()], &|_| false, parameter_count)?;
        for part in &parts {
            let properties = part.properties();
            model.time_dependent |= properties.time;
            model.constant_mass &= properties
                .velocity
                .is_some_and(|form| form.fits_constant_mass());
        }
        model.compiled = model.compile(&model.parameter_values)?;
        Ok(model)
    }

    /// The number of coordinates: families × n.
    pub fn dimension(&self) -> usize {
        self.families.len() * self.compiled.sites
    }

    /// The size n (sites per family).
    pub fn sites(&self) -> usize {
        self.compiled.sites
    }

    /// The family names, in the order of their coordinates at each site.
    pub fn families(&self) -> &[&'static str] {
        &self.families
    }

    /// K, the number of coordinates one term reads.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The boundary rule.
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Whether `t` appears in L.
    pub fn time_dependent(&self) -> bool {
        self.time_dependent
    }

    /// [`Structure::ConstantMass`] if every sum's body and the rest is, by its structure,
    /// free of terms linear in q̇ with constant coefficients of the quadratic ones (see the
    /// [module docs](self)), else [`Structure::General`].
    pub fn structure(&self) -> Structure {
        if self.constant_mass {
            Structure::ConstantMass
        } else {
            Structure::General
        }
    }

    /// The number of terms of the [`LocalLagrangian`].
    pub fn term_count(&self) -> usize {
        self.compiled.site_terms + usize::from(self.compiled.rest.is_some())
    }

    /// The parameters, name and current value (the size among them).
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        named_values(&self.parameter_names, &self.parameter_values)
    }

    /// Set the parameter `name` (the size resizes the chain) and recompile the terms.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a name that is not a parameter, a value that is not
    /// finite, a size that is not a whole number from 1 to [`MAX_SITES`], or a size for which
    /// the terms do not determine every coordinate's motion; the model is then unchanged.
    pub fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let index = parameter_index(&self.parameter_names, name, value)?;
        if index == self.size {
            check_size(name, value).map_err(|error| Error::invalid(name, error.to_string()))?;
        }
        let mut values = self.parameter_values.clone();
        values[index] = value;
        self.compiled = self
            .compile(&values)
            .map_err(|error| Error::invalid(name, error.to_string()))?;
        self.parameter_values = values;
        Ok(())
    }

    /// The terms for the parameter values `values`.
    fn compile(&self, values: &[f64]) -> Result<Compiled, TextError> {
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

    /// The site `site` reads for a chain of `n` sites: itself inside 1..n, else nothing
    /// (fixed) or the site equal to it modulo n (periodic).
    fn wrap(&self, site: i64, n: usize) -> Option<i64> {
        match self.boundary {
            _ if (1..=n as i64).contains(&site) => Some(site),
            Boundary::Fixed => None,
            Boundary::Periodic => Some((site - 1).rem_euclid(n as i64) + 1),
        }
    }

    /// The coordinate index of `family` at `site` (in 1..n).
    fn coordinate(&self, site: i64, family: usize) -> usize {
        // site ≥ 1.
        (site as usize - 1) * self.families.len() + family
    }

    /// Σ ± body of the sums marked `active`, over the slots of a site's window, a slot at
    /// offset k being zero where `outside(k)`.
    fn site_expression(
        &self,
        active: &[bool],
        outside: &dyn Fn(i64) -> bool,
        parameter_count: usize,
    ) -> Result<Expression, TextError> {
        let families = self.families.len() as i64;
        let a = self.window.0;
        let terms: Vec<(bool, usize)> = self
            .sums
            .iter()
            .zip(active)
            .filter(|(_, active)| **active)
            .map(|(sum, _)| (sum.negative, sum.body))
            .collect();
        let slot = |site: Site| {
            let k = site.index.offset;
            if outside(k) {
                return Node::Number(0.0);
            }
            // k ≥ a and the family is below the count: a slot below the width.
            let slot = ((k - a) * families) as usize + site.family;
            Node::Symbol(if site.velocity {
                Symbol::Velocity(slot)
            } else {
                Symbol::Coordinate(slot)
            })
        };
        let (nodes, root) = join(&self.tree, &terms, &slot);
        Expression::from_tree(nodes, root, "lagrangian", parameter_count)
    }

    /// The rest of L over its slots, a site's slot being zero where `site_of` gives none.
    fn rest_expression(
        &self,
        site_of: &dyn Fn(Index) -> Option<i64>,
        parameter_count: usize,
    ) -> Result<Expression, TextError> {
        let slot = |site: Site| {
            if site_of(site.index).is_none() {
                return Node::Number(0.0);
            }
            let slot = self
                .rest_sites
                .iter()
                .position(|known| *known == (site.family, site.index))
                .unwrap_or(0);
            Node::Symbol(if site.velocity {
                Symbol::Velocity(slot)
            } else {
                Symbol::Coordinate(slot)
            })
        };
        let (nodes, root) = join(&self.tree, &self.rest, &slot);
        Expression::from_tree(nodes, root, "lagrangian", parameter_count)
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
    fn empty() -> Compiled {
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
    fn kind(&self, term: usize) -> &Kind {
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

/// `name[1..size]`: the family's name and its size parameter's.
fn family_declaration(declaration: &str) -> Result<(&str, &str), TextError> {
    let invalid = || TextError::InvalidName {
        role: "coordinate",
        name: declaration.into(),
        reason: "a coordinate is a name, or an indexed family name[1..n] with n a parameter".into(),
    };
    let (name, range) = declaration.split_once('[').ok_or_else(invalid)?;
    let range = range.strip_suffix(']').ok_or_else(invalid)?;
    let (lower, size) = range.split_once("..").ok_or_else(invalid)?;
    if lower.trim() != "1" {
        return Err(TextError::InvalidName {
            role: "coordinate",
            name: declaration.into(),
            reason: "a family's indices run from 1: name[1..n]".into(),
        });
    }
    Ok((name.trim(), size.trim()))
}

/// Check that the size `name` = `value` is a whole number from 1 to [`MAX_SITES`].
fn check_size(name: &str, value: f64) -> Result<(), TextError> {
    if value.fract() != 0.0 || !(1.0..=MAX_SITES as f64).contains(&value) {
        return Err(TextError::InvalidSize {
            name: name.into(),
            value,
            limit: MAX_SITES,
        });
    }
    Ok(())
}

/// The value of `index` (not relative to a sum) for the size `n`.
fn resolve(index: Index, n: usize) -> i64 {
    index.resolve(n).unwrap_or(index.offset)
}

/// The nearest site of 1..n to `site`.
fn clamp(site: i64, n: usize) -> i64 {
    site.clamp(1, n as i64)
}

/// The terms of L outside its sums: (negative, node) for each.
type Rest = Vec<(bool, usize)>;

/// L's terms: the sums, each with its sign, and the terms outside them, (negative, node),
/// from the additive structure at `root`; an error for a sum elsewhere.
fn terms(
    nodes: &[Node],
    root: usize,
    calls: &[super::parse::SumCall],
) -> Result<(Vec<SumTerm>, Rest), TextError> {
    let mut sums: Vec<Option<SumTerm>> = vec![None; calls.len()];
    let mut rest = Vec::new();
    let mut stack = vec![(false, root)];
    while let Some((negative, node)) = stack.pop() {
        match nodes[node] {
            Node::Binary(super::tree::Binary::Add, x, y) => {
                stack.extend([(negative, y), (negative, x)]);
            }
            Node::Binary(super::tree::Binary::Subtract, x, y) => {
                stack.extend([(!negative, y), (negative, x)]);
            }
            Node::Negate(x) => stack.push((!negative, x)),
            _ => match calls.iter().position(|call| call.placeholder == node) {
                Some(i) => {
                    let call = calls[i];
                    sums[i] = Some(SumTerm {
                        negative,
                        lower: call.lower,
                        upper: call.upper,
                        body: call.body,
                        column: call.column,
                        velocities: velocities(nodes, call.body),
                    });
                }
                None => rest.push((negative, node)),
            },
        }
    }
    calls
        .iter()
        .zip(sums)
        .map(|(call, sum)| {
            sum.ok_or_else(|| TextError::Indexing {
                field: "lagrangian".into(),
                column: call.column,
                symbol: "sum".into(),
                message: "a sum is a term of L, added or subtracted (sum(...) - sum(...)), not \
                          inside a product, a power or a function"
                    .into(),
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|sums| (sums, rest))
}

/// Which nodes the subtree at `root` holds (each node after its children in the arena).
fn subtree(nodes: &[Node], root: usize) -> Vec<bool> {
    let mut reached = vec![false; root + 1];
    reached[root] = true;
    for node in (0..=root).rev() {
        if !reached[node] {
            continue;
        }
        match nodes[node] {
            Node::Negate(x) | Node::PowerInteger(x, _) | Node::Call(_, x) => reached[x] = true,
            Node::Binary(_, x, y) => {
                reached[x] = true;
                reached[y] = true;
            }
            Node::Number(_) | Node::Symbol(_) => {}
        }
    }
    reached
}

/// The (family, offset) of the velocities the sum body at `body` reads, each once.
fn velocities(nodes: &[Node], body: usize) -> Vec<(usize, i64)> {
    let mut found = Vec::new();
    for (node, reached) in nodes.iter().zip(subtree(nodes, body)) {
        if let (Node::Symbol(Symbol::Site(site)), true) = (node, reached)
            && site.velocity
            && !found.contains(&(site.family, site.index.offset))
        {
            found.push((site.family, site.index.offset));
        }
    }
    found
}

/// A new arena holding Σ ± subtree over `terms` (negative, root) of `nodes`, each site
/// replaced by `slot(site)`, and its root (the number 0 for no term).
fn join(
    nodes: &[Node],
    terms: &[(bool, usize)],
    slot: &dyn Fn(Site) -> Node,
) -> (Vec<Node>, usize) {
    let mut out: Vec<Node> = Vec::new();
    let mut total: Option<usize> = None;
    for &(negative, root) in terms {
        let reached = subtree(nodes, root);
        let mut map: BTreeMap<usize, usize> = BTreeMap::new();
        for (node, _) in reached.iter().enumerate().filter(|(_, reached)| **reached) {
            let copied = match nodes[node] {
                Node::Symbol(Symbol::Site(site)) => slot(site),
                Node::Negate(x) => Node::Negate(map[&x]),
                Node::PowerInteger(x, power) => Node::PowerInteger(map[&x], power),
                Node::Call(function, x) => Node::Call(function, map[&x]),
                Node::Binary(binary, x, y) => Node::Binary(binary, map[&x], map[&y]),
                other => other,
            };
            out.push(copied);
            map.insert(node, out.len() - 1);
        }
        let term = out.len() - 1;
        total = Some(match (total, negative) {
            (None, false) => term,
            (None, true) => {
                out.push(Node::Negate(term));
                out.len() - 1
            }
            (Some(sum), negative) => {
                let binary = if negative {
                    super::tree::Binary::Subtract
                } else {
                    super::tree::Binary::Add
                };
                out.push(Node::Binary(binary, sum, term));
                out.len() - 1
            }
        });
    }
    match total {
        Some(root) => (out, root),
        None => (vec![Node::Number(0.0)], 0),
    }
}

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

/// A [`TextChainModel`] as a [`LocalLagrangian`] with terms K = `WIDTH` coordinates wide (the
/// model's [`TextChainModel::width`]), with [`LocalDefaults`] and [`LocalInvariants`] (none).
///
/// The other parameters are the model's declarations, as for [`super::TextLagrangian`]:
/// [`LocalLagrangian::TIME_DEPENDENT`] and `CONSTANT_MASS` for [`Structure::ConstantMass`];
/// the defaults (time-dependent, general) fit every model, and [`TextChain::new`] rejects
/// declarations the model does not allow.
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
        let declaration = |reason: String| Err(TextError::Declaration { reason });
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
    /// [the module docs](self)); a kind without one, and the rest's term, term by term.
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
    /// [the module docs](self)); a kind without one, and the rest's term, term by term.
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
    /// state, e.g. by [`site_values`]).
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
