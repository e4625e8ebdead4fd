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
//!
//! [`LocalLagrangian`]: crate::model::local::LocalLagrangian
//! [`LocalLagrangian::force_into`]: crate::model::local::LocalLagrangian::force_into
//! [`LocalLagrangian::value`]: crate::model::local::LocalLagrangian::value

mod compiled;
mod initial;
mod lagrangian;
mod sums;

pub use initial::site_values;
pub use lagrangian::TextChain;

use super::TextSpec;
use super::error::TextError;
use super::expression::Expression;
use super::names::{Declared, named_values, parameter_index};
use super::parse::parse;
use super::tree::{Base, Index, Names, Node, Symbol};
use crate::error::Error;
use crate::model::Structure;
use compiled::Compiled;
use sums::terms;

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
/// [`LocalLagrangian`](crate::model::local::LocalLagrangian). See the [module docs](self).
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

impl TextChainModel {
    /// Check the names, the size and the indexing rules of `spec` and compile its terms.
    ///
    /// # Errors
    /// A [`TextError`] naming the field, and for an expression the column and the symbol.
    pub fn new(spec: &TextSpec) -> Result<TextChainModel, TextError> {
        if !spec.hamiltonian.is_empty() {
            return Err(TextError::Unsupported {
                field: "hamiltonian".into(),
                reason: "a chain of indexed coordinates is written as a lagrangian".into(),
            });
        }
        for (given, field) in [
            (!spec.forces.is_empty(), "forces"),
            (!spec.symmetries.is_empty(), "symmetries"),
            (!spec.constraints.is_empty(), "constraints"),
        ] {
            if given {
                return Err(TextError::Unsupported {
                    field: field.into(),
                    reason: "a chain of indexed coordinates takes neither forces, symmetry \
                             generators nor constraints yet"
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

    /// The number of terms of the [`LocalLagrangian`](crate::model::local::LocalLagrangian).
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
