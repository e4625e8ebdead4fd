//! Lagrangians written as text: `"0.5*(vx^2 + vy^2) + 1/sqrt(x^2 + y^2)"`.
//!
//! A [`TextSpec`] gives L as an expression in named coordinates, their velocities, the time
//! and named parameters, with optional non-conservative forces and symmetry generators the
//! same way. [`TextModel::new`] parses it once into postfix tapes; [`TextLagrangian`] puts a
//! model of known dimension N behind [`Lagrangian<N>`], evaluating the tapes generically over
//! [`Scalar`]: every method, derivative and diagnostic works as for a model written in Rust,
//! with derivatives by automatic differentiation, not by hand.
//!
//! ```
//! use nalgebra::{SVector, U2};
//! use svi::model::text::{TextLagrangian, TextModel, TextSpec};
//! use svi::{Integrator, Svi, Symmetries};
//!
//! let spec = TextSpec {
//!     lagrangian: "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)".into(),
//!     coordinates: vec!["x".into(), "y".into()],
//!     parameters: vec![("mu".into(), 1.0)],
//!     symmetries: vec![vec!["-y".into(), "x".into()]],
//!     ..TextSpec::default()
//! };
//! let model = TextModel::new(&spec)?;
//! // Autonomous, unforced, ½q̇ᵀMq̇ − V(q): all three may be declared.
//! let kepler = TextLagrangian::<U2, false, false, true>::new(model)?;
//! assert_eq!(kepler.generator_count(), 1);
//! let integrator = Integrator::new(kepler, Svi::new(6));
//! let (q, v) = (SVector::from([1.0, 0.0]), SVector::from([0.0, 1.0]));
//! let run = integrator.run_from_velocity(0.0, q, v, 0.1, 6.0, &mut ()).unwrap();
//! assert!((run.last.q - SVector::from([6f64.cos(), 6f64.sin()])).amax() < 1e-10);
//! # Ok::<(), svi::model::text::TextError>(())
//! ```
//!
//! # Grammar
//!
//! ```text
//! expression := sum
//! sum        := product (('+' | '-') product)*
//! product    := unary (('*' | '/') unary)*
//! unary      := ('-' | '+') unary | power
//! power      := atom ('^' unary)?                    right-associative: 2^3^2 = 2^9
//! atom       := number | name | function '(' expression (',' expression)* ')'
//!             | '(' expression ')'
//! number     := digits ['.' digits] [('e' | 'E') ['+' | '-'] digits]     1, 0.5, .5, 1.5e-3
//! name       := (letter | '_') (letter | digit | '_')*
//! ```
//!
//! `-x^2` is `-(x^2)`; `x^-1` is `1/x`. An integer literal exponent (`x^2`, `x^-3`) is an
//! integer power (`powi`, exact for negative x); any other exponent free of t, q and q̇ (a
//! parameter, `0.5`) a real power (`powf`); an exponent depending on them exp(y ln x).
//! Spaces are ignored.
//!
//! Names, in the order they are looked up:
//! - the coordinates, as given (`x`, `theta`, `q1`);
//! - the parameters, as given, read at every evaluation (so `set_parameter` takes effect);
//! - the velocities: `v` followed by the coordinate's name (`vx` for `x`, `vtheta` for
//!   `theta`); not in symmetry generators, which are functions of q only;
//! - `t`, the time (not in symmetry generators);
//! - the constants `pi` and `e`;
//! - the functions `sin cos tan asin acos atan sinh cosh tanh exp ln sqrt abs`, `log` (the
//!   natural logarithm, as `ln`) and `atan2(y, x)`.
//!
//! No name may be given twice, or be a function, a constant, `t` or `sum`; a coordinate's
//! velocity name must not be another name.
//!
//! # Chains: indexed coordinates and sums
//!
//! A coordinate declared `q[1..n]`, with `n` a parameter (a positive whole number), is a
//! family of n coordinates read as `q[index]`, with velocities `vq[index]`; L may then add
//! up local terms with `sum(i, lower, upper, body)`:
//!
//! ```text
//! atom  := ... | name '[' index ']' | 'sum' '(' name ',' index ',' index ',' expression ')'
//! index := ['+' | '-'] term (('+' | '-') term)*      term := digits | n | the sum's index
//! ```
//!
//! Inside a sum an index is `i + c` (`q[i+1]`), outside one `c` or `n + c` (`q[1]`, `q[n]`);
//! the bounds are `c` or `n + c`; a sum is a term of L (added or subtracted, never nested or
//! inside a product or a function); [`TextSpec::boundary`] says what an index outside 1..n
//! reads (zero, or the site modulo n). The FPUT chain with fixed ends is
//!
//! ```text
//! sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1]-q[i])^2 + alpha/3*(q[i+1]-q[i])^3
//!                                          + beta/4*(q[i+1]-q[i])^4)
//! ```
//!
//! Such a model is a [`TextChainModel`] (not a [`TextModel`]): its sums compile to the terms
//! of a [`crate::model::local::LocalLagrangian`], [`TextChain`], which the large-system
//! methods integrate in O(n) per step, n up to 10⁵ and beyond. [`chain`] has the rules, the
//! boundaries and the compilation; every broken rule is a [`TextError::Indexing`] naming the
//! column and the symbol.
//!
//! # What the text declares
//!
//! The structure of the expressions decides the declarations a [`TextLagrangian`] may make
//! ([`TextModel::time_dependent`], [`TextModel::forced`], [`TextModel::structure`]):
//! time dependence when `t` appears in L; a force when forces are given; and
//! [`Structure::ConstantMass`] when L is, by its structure, a sum of terms free of q̇ and of
//! terms quadratic in q̇ with constant coefficients (numbers and parameters), and has no term
//! linear in q̇. The analysis follows sums, products, quotients by expressions free of q̇,
//! negation and squares: `0.5*m*(vx^2 + vy^2) - V` qualifies, `(vx^2 + vy^2)/(2*m)` too,
//! while `sqrt(vx^2)^2` or `vx^2*x` do not. It is sound — a model it calls constant-mass is
//! one — but not complete: a model it does not recognise runs as [`Structure::General`],
//! correctly, with Newton's method instead of the Hessian-free iteration. That M is positive
//! definite is not checked here (a singular M fails the run, as for any model).
//!
//! # Why a parser of our own
//!
//! The expression must be evaluated over every scalar type the integrators choose inside
//! their generic code (`f64`, num-dual's first- and second-order and nested dual numbers)
//! from one parse. The maintained expression crates fix the number type at parse time
//! (exmex's `FlatEx<T>`, whose operators are function pointers over one `T`) or evaluate
//! `f64` only (meval, fasteval, evalexpr's dynamic `Value`): none can be evaluated generically
//! over [`Scalar`] inside `fn lagrangian<D: Scalar>`. The grammar above is small enough for
//! about 300 lines of recursive descent, with errors that name the column and the symbol.
//!
//! # Evaluation
//!
//! Each expression is compiled, for the current parameter values, into a postfix tape:
//! parameters and constant subexpressions folded into numbers, products and quotients by
//! numbers as scalings, `1/x` as a reciprocal, a variable or its square read by the
//! operation that uses it (`x^2 + y^2` is two instructions), and the top of the stack kept in
//! a local. The tape runs on a stack array of at most [`MAX_STACK`] slots (1 or 8 for most
//! expressions): no allocation per evaluation. [`TextModel::set_parameter`] recompiles.
//!
//! For a constant-mass L the kinetic part ½q̇ᵀMq̇ is read off the tree once (M from the
//! constant coefficients) and evaluated as a sum of products without a tape; only
//! U(t, q) = L(t, q, 0) runs on one. Its force ∂U/∂q is also compiled into a straight-line
//! program by reverse-mode differentiation (as a chain's terms are, `batch`), which SVI's
//! fixed point runs on all its quadrature points at once, one a lane
//! ([`Lagrangian::batch_force`]), in registers as wide as the points need. On the Kepler
//! scene of the paper (10 000 steps of SVI 7/6) a text model takes about 1.6 times as long
//! as the same model in Rust when its size is compiled in, and about 2.4 times at run-time
//! size, where the force program and SVI's stage sums over vectors of run-time length cost
//! about equally (`cargo bench --bench text -- kepler_T2000`).

mod batch;
pub mod chain;
mod expression;
mod parse;
mod structure;
mod tree;

pub use chain::{Boundary, MAX_SITES, MAX_WIDTH, TextChain, TextChainModel, site_values};
pub use expression::MAX_STACK;
pub use tree::MAX_NODES;

use std::collections::BTreeSet;
use std::sync::Mutex;

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::model::{Defaults, ExactSolution, Invariants, Lagrangian, Structure, Symmetries};
use crate::scalar::Scalar;
use batch::{MAX_REGISTERS, Program, Source};
use expression::{Expression, Split, Tape, Velocities};
use tree::{CONSTANT_NAMES, FUNCTION_NAMES, Names};

/// What goes wrong when reading a text model: every message names the field and, for the
/// expressions, the column (counted in characters from 1) and the offending symbol.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TextError {
    /// An expression that does not follow the grammar.
    #[error("syntax error at column {column} of {field}: {message}")]
    Syntax {
        /// The field: `lagrangian`, `forces[1]`, `symmetries[0][1]`.
        field: String,
        /// Column of the error, in characters from 1.
        column: usize,
        /// What is wrong there.
        message: String,
    },
    /// A name that is neither a coordinate, a velocity, `t`, a parameter nor a constant.
    #[error("unknown symbol '{symbol}' at column {column} of {field} (known: {known})")]
    UnknownSymbol {
        /// The field.
        field: String,
        /// Column of the symbol, in characters from 1.
        column: usize,
        /// The symbol.
        symbol: String,
        /// The symbols the field may use.
        known: String,
    },
    /// A name followed by `(` that is not a function.
    #[error("unknown function '{name}' at column {column} of {field} (known: {known})")]
    UnknownFunction {
        /// The field.
        field: String,
        /// Column of the name, in characters from 1.
        column: usize,
        /// The name.
        name: String,
        /// The functions of the grammar.
        known: String,
    },
    /// An expression with nothing but spaces.
    #[error("{field} is empty")]
    Empty {
        /// The field.
        field: String,
    },
    /// An expression whose evaluation needs more than [`MAX_STACK`] values at once.
    #[error("{field} nests too deeply: its evaluation needs more than {limit} values at once")]
    TooDeep {
        /// The field.
        field: String,
        /// [`MAX_STACK`].
        limit: usize,
    },
    /// An expression of more than [`MAX_NODES`] numbers, names and operations.
    #[error("{field} is too long: more than {limit} numbers, names and operations")]
    TooLong {
        /// The field.
        field: String,
        /// [`MAX_NODES`].
        limit: usize,
    },
    /// A coordinate or parameter name that is not an identifier, is given twice, or is taken
    /// by a function, a constant, `t` or a velocity.
    #[error("invalid {role} name '{name}': {reason}")]
    InvalidName {
        /// `coordinate` or `parameter`.
        role: &'static str,
        /// The name.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A parameter value that is NaN or infinite.
    #[error("parameter '{name}' = {value} is not a finite number")]
    NonFiniteParameter {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
    },
    /// A model without coordinates.
    #[error("a text model needs at least one coordinate")]
    NoCoordinates,
    /// A Lagrangian in which a coordinate's velocity does not appear: its mass matrix
    /// ∂²L/∂q̇² is singular, and the equations of motion do not determine that coordinate.
    #[error(
        "the lagrangian does not depend on {velocity}: its mass matrix ∂²L/∂q̇² is singular, so \
         the motion of {coordinate} is not determined (every coordinate's velocity must appear \
         in L, e.g. 0.5*{velocity}^2)"
    )]
    NoVelocity {
        /// The coordinate.
        coordinate: String,
        /// Its velocity's name.
        velocity: String,
    },
    /// A list of expressions (forces, a symmetry generator) whose length is not the number
    /// of coordinates.
    #[error("{field} has {found} expressions, but the model has {expected} coordinates")]
    Dimension {
        /// `forces` or `symmetries[i]`.
        field: String,
        /// The number of coordinates.
        expected: usize,
        /// The number of expressions given.
        found: usize,
    },
    /// An index, a sum or an indexed coordinate against the rules of the grammar (see
    /// [`chain`]): an index that is not `i + c` inside a sum or constant outside, bounds that
    /// are not integers or `n ± c`, a sum inside a sum or inside a product, a power or a
    /// function.
    #[error("indexing error at column {column} of {field} ('{symbol}'): {message}")]
    Indexing {
        /// The field.
        field: String,
        /// Column of the symbol, in characters from 1.
        column: usize,
        /// The symbol or index.
        symbol: String,
        /// What is wrong.
        message: String,
    },
    /// The size parameter of indexed coordinates that is not a whole number from 1 to
    /// [`MAX_SITES`].
    #[error("the size '{name}' = {value} is not a whole number from 1 to {limit}")]
    InvalidSize {
        /// The size parameter.
        name: String,
        /// Its value.
        value: f64,
        /// [`MAX_SITES`].
        limit: usize,
    },
    /// A chain whose terms read more coordinates than [`MAX_WIDTH`].
    #[error(
        "a term of the chain reads {width} coordinates ({what}), more than {limit}, the widest \
         term compiled: use fewer families or nearer neighbours"
    )]
    TooWide {
        /// The number of coordinates one term reads.
        width: usize,
        /// Where they come from.
        what: String,
        /// [`MAX_WIDTH`].
        limit: usize,
    },
    /// A field that the kind of model does not take (forces of a chain, a boundary rule
    /// without indexed coordinates).
    #[error("{field} is not supported here: {reason}")]
    Unsupported {
        /// The field.
        field: String,
        /// Why.
        reason: String,
    },
    /// A [`TextLagrangian`] whose dimension or declarations do not fit its model.
    #[error("TextLagrangian cannot hold this model: {reason}")]
    Declaration {
        /// What does not fit.
        reason: String,
    },
}

/// A text model as written: the expressions and the names they use.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TextSpec {
    /// L(t, q, q̇) as an expression.
    pub lagrangian: String,
    /// The coordinate names; their velocities are `v` + name.
    pub coordinates: Vec<String>,
    /// The parameters, name and value.
    pub parameters: Vec<(String, f64)>,
    /// The non-conservative force f_L(t, q, q̇), one expression per coordinate (empty: none).
    pub forces: Vec<String>,
    /// Symmetry generators ξ(q), each one expression per coordinate in q and the parameters;
    /// their Noether momenta are named `J1`, `J2`, ...
    pub symmetries: Vec<Vec<String>>,
    /// What indexed coordinates read outside their range (chains only, see [`chain`]).
    pub boundary: Boundary,
}

impl TextSpec {
    /// Whether the coordinates are indexed families (`q[1..n]`): the model is then a chain,
    /// read by [`TextChainModel::new`], else by [`TextModel::new`].
    pub fn is_indexed(&self) -> bool {
        self.coordinates.iter().any(|name| name.contains('['))
    }
}

/// A parsed text model of any dimension (known at run time); [`TextLagrangian`] puts it
/// behind [`Lagrangian<N>`].
#[derive(Debug, Clone, PartialEq)]
pub struct TextModel {
    coordinates: Vec<&'static str>,
    parameter_names: Vec<&'static str>,
    parameter_values: Vec<f64>,
    lagrangian: Expression,
    forces: Vec<Expression>,
    generators: Vec<Vec<Expression>>,
    momentum_names: Vec<&'static str>,
    /// The expressions compiled for the current parameter values.
    tapes: Tapes,
}

/// The tapes of a text model for its current parameter values.
#[derive(Debug, Clone, PartialEq)]
struct Tapes {
    lagrangian: Tape,
    /// For a constant-mass L: its two parts.
    constant_mass: Option<Split>,
    /// For a constant-mass L: ∂L/∂q = ∂U/∂q as a straight-line program, run with many
    /// points as lanes ([`Lagrangian::batch_force`]); `None` where the program would need
    /// more registers than there are.
    force: Option<Program>,
    forces: Vec<Tape>,
    generators: Vec<Vec<Tape>>,
}

impl Tapes {
    /// Compile the expressions with `parameters`.
    fn compile(
        lagrangian: &Expression,
        forces: &[Expression],
        generators: &[Vec<Expression>],
        parameters: &[f64],
        n: usize,
    ) -> Tapes {
        let compile = |expression: &Expression| expression.compile(parameters, Velocities::Read);
        let constant_mass = Split::of(lagrangian, parameters, n);
        Tapes {
            lagrangian: compile(lagrangian),
            force: constant_mass
                .as_ref()
                .and_then(|split| Program::force(split.potential(), n)),
            constant_mass,
            forces: forces.iter().map(compile).collect(),
            generators: generators
                .iter()
                .map(|generator| generator.iter().map(compile).collect())
                .collect(),
        }
    }
}

impl TextModel {
    /// Name of every text model in reports ([`Defaults::name`]).
    pub const NAME: &'static str = "text";

    /// Check the names and parameter values of `spec` and parse its expressions.
    ///
    /// # Errors
    /// A [`TextError`] naming the field, and for an expression the column and the symbol.
    pub fn new(spec: &TextSpec) -> Result<TextModel, TextError> {
        if spec.coordinates.is_empty() {
            return Err(TextError::NoCoordinates);
        }
        if let Some(name) = spec.coordinates.iter().find(|name| name.contains('[')) {
            return Err(TextError::InvalidName {
                role: "coordinate",
                name: name.clone(),
                reason: "an indexed coordinate makes a chain, which TextChainModel::new reads"
                    .into(),
            });
        }
        if spec.boundary != Boundary::Fixed {
            return Err(TextError::Unsupported {
                field: "boundary".into(),
                reason: "a boundary rule applies to indexed coordinates (q[1..n])".into(),
            });
        }
        let names: Vec<&str> = spec.coordinates.iter().map(String::as_str).collect();
        let Declared {
            coordinates,
            velocities,
            parameter_names,
            parameter_values,
        } = Declared::check(&names, &spec.parameters)?;
        let phase_space = Names {
            coordinates: &coordinates,
            velocities: &velocities,
            parameters: &parameter_names,
            phase_space: true,
            families: &[],
            size: None,
        };
        let configuration = Names {
            phase_space: false,
            ..phase_space
        };
        let n = coordinates.len();
        let list = |field: &str, texts: &[String], names: &Names<'_>| {
            if texts.len() != n {
                return Err(TextError::Dimension {
                    field: field.into(),
                    expected: n,
                    found: texts.len(),
                });
            }
            texts
                .iter()
                .enumerate()
                .map(|(i, text)| Expression::parse(text, &format!("{field}[{i}]"), names))
                .collect::<Result<Vec<_>, _>>()
        };
        let lagrangian = Expression::parse(&spec.lagrangian, "lagrangian", &phase_space)?;
        if let Some(i) = (0..n).find(|&i| !lagrangian.uses_velocity(i)) {
            return Err(TextError::NoVelocity {
                coordinate: spec.coordinates[i].clone(),
                velocity: velocities[i].into(),
            });
        }
        let forces = if spec.forces.is_empty() {
            Vec::new()
        } else {
            list("forces", &spec.forces, &phase_space)?
        };
        let generators = spec
            .symmetries
            .iter()
            .enumerate()
            .map(|(i, texts)| list(&format!("symmetries[{i}]"), texts, &configuration))
            .collect::<Result<Vec<_>, _>>()?;
        let momentum_names = (1..=generators.len())
            .map(|i| intern(&format!("J{i}")))
            .collect();
        let tapes = Tapes::compile(&lagrangian, &forces, &generators, &parameter_values, n);
        Ok(TextModel {
            coordinates,
            parameter_names,
            parameter_values,
            lagrangian,
            forces,
            generators,
            momentum_names,
            tapes,
        })
    }

    /// The number of coordinates N.
    pub fn dimension(&self) -> usize {
        self.coordinates.len()
    }

    /// The coordinate names.
    pub fn coordinate_names(&self) -> &[&'static str] {
        &self.coordinates
    }

    /// Whether `t` appears in L.
    pub fn time_dependent(&self) -> bool {
        self.lagrangian.properties().time
    }

    /// Whether forces are given.
    pub fn forced(&self) -> bool {
        !self.forces.is_empty()
    }

    /// [`Structure::ConstantMass`] if L is, by its structure, ½q̇ᵀMq̇ − V(t, q) with M
    /// constant (see the [module docs](self)), else [`Structure::General`].
    pub fn structure(&self) -> Structure {
        match self.tapes.constant_mass {
            Some(_) => Structure::ConstantMass,
            None => Structure::General,
        }
    }

    /// The parameters, name and current value.
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        named_values(&self.parameter_names, &self.parameter_values)
    }

    /// Set the parameter `name`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a name that is not a parameter or a value that is not
    /// finite.
    pub fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let index = parameter_index(&self.parameter_names, name, value)?;
        self.parameter_values[index] = value;
        self.tapes = Tapes::compile(
            &self.lagrangian,
            &self.forces,
            &self.generators,
            &self.parameter_values,
            self.dimension(),
        );
        Ok(())
    }
}

/// Each parameter's name with its value.
fn named_values(names: &[&'static str], values: &[f64]) -> Vec<(&'static str, f64)> {
    names.iter().copied().zip(values.iter().copied()).collect()
}

/// The index of the parameter `name` among `names`, for the new value `value`.
///
/// # Errors
/// [`Error::InvalidParameter`] for a name that is not a parameter or a value that is not
/// finite.
fn parameter_index(names: &[&'static str], name: &str, value: f64) -> Result<usize, Error> {
    let Some(index) = names.iter().position(|known| *known == name) else {
        let known = if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        };
        return Err(Error::invalid(
            name,
            format!("not a parameter of the text model (parameters: {known})"),
        ));
    };
    if !value.is_finite() {
        return Err(Error::invalid(
            name,
            format!("{value} is not a finite number"),
        ));
    }
    Ok(index)
}

/// The checked names of a model: its coordinates (or indexed families), their velocities and
/// its parameters with their values.
struct Declared {
    coordinates: Vec<&'static str>,
    velocities: Vec<&'static str>,
    parameter_names: Vec<&'static str>,
    parameter_values: Vec<f64>,
}

impl Declared {
    /// Check `coordinates` and `parameters`: identifiers, none given twice, no velocity
    /// (`v` + a coordinate) that is another name, finite values.
    fn check(coordinates: &[&str], parameters: &[(String, f64)]) -> Result<Declared, TextError> {
        let mut taken = BTreeSet::new();
        let mut declared = Declared {
            coordinates: Vec::new(),
            velocities: Vec::new(),
            parameter_names: Vec::new(),
            parameter_values: Vec::new(),
        };
        for name in coordinates {
            check_name("coordinate", name)?;
            if !taken.insert(name.to_string()) {
                return Err(TextError::InvalidName {
                    role: "coordinate",
                    name: name.to_string(),
                    reason: "given twice".into(),
                });
            }
            declared.coordinates.push(intern(name));
        }
        for name in coordinates {
            let velocity = format!("v{name}");
            if !taken.insert(velocity.clone()) {
                return Err(TextError::InvalidName {
                    role: "coordinate",
                    name: name.to_string(),
                    reason: format!("its velocity '{velocity}' is also a coordinate"),
                });
            }
            declared.velocities.push(intern(&velocity));
        }
        for (name, value) in parameters {
            check_name("parameter", name)?;
            if !taken.insert(name.clone()) {
                return Err(TextError::InvalidName {
                    role: "parameter",
                    name: name.clone(),
                    reason: "given twice, or a coordinate or velocity".into(),
                });
            }
            if !value.is_finite() {
                return Err(TextError::NonFiniteParameter {
                    name: name.clone(),
                    value: *value,
                });
            }
            declared.parameter_names.push(intern(name));
            declared.parameter_values.push(*value);
        }
        Ok(declared)
    }
}

/// Reject a name that is not an identifier, or is a function, a constant or `t`.
fn check_name(role: &'static str, name: &str) -> Result<(), TextError> {
    let invalid = |reason: &str| {
        Err(TextError::InvalidName {
            role,
            name: name.into(),
            reason: reason.into(),
        })
    };
    let mut chars = name.chars();
    let identifier = chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
        && chars.all(|c| c.is_alphanumeric() || c == '_');
    if !identifier {
        return invalid("a name is a letter or '_' followed by letters, digits and '_'");
    }
    if FUNCTION_NAMES.contains(&name) {
        return invalid("it is a function");
    }
    if CONSTANT_NAMES.contains(&name) {
        return invalid("it is a constant");
    }
    if name == "t" {
        return invalid("t is the time");
    }
    if name == "sum" {
        return invalid("sum(i, lower, upper, body) is the indexed sum");
    }
    Ok(())
}

/// Intern `name`: the one `&'static str` with its text. The traits of a model name its
/// coordinates, parameters and momenta with `&'static str`; a text model's names are leaked
/// once per distinct name and process, not once per model.
fn intern(name: &str) -> &'static str {
    static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());
    let mut names = NAMES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(known) = names.get(name) {
        return known;
    }
    let leaked: &'static str = Box::leak(name.to_owned().into_boxed_str());
    names.insert(leaked);
    leaked
}

/// A [`TextModel`] as a [`Lagrangian<N>`] (with [`Symmetries`], [`Invariants`] — none —,
/// [`ExactSolution`] — none — and [`Defaults`]), of any number of coordinates: `N` is
/// [`crate::dimension::Dyn`] (the size is the model's, chosen at run time; what the command
/// line uses) or a fixed `Const<N>` equal to the model's size.
///
/// The other parameters are the model's declarations ([`Lagrangian::TIME_DEPENDENT`],
/// [`Lagrangian::FORCED`], and `CONSTANT_MASS` for [`Structure::ConstantMass`]): constants
/// of the type, so a caller that learns the model's at run time dispatches on them. The
/// defaults (time-dependent, forced, general) fit every model; [`TextLagrangian::new`]
/// rejects declarations the model does not allow.
#[derive(Debug, Clone, PartialEq)]
pub struct TextLagrangian<
    N,
    const TIME_DEPENDENT: bool = true,
    const FORCED: bool = true,
    const CONSTANT_MASS: bool = false,
> {
    model: TextModel,
    dimension: std::marker::PhantomData<N>,
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// `model` as a Lagrangian on ℝᴺ with the type's declarations.
    ///
    /// # Errors
    /// [`TextError::Declaration`] if `N` is fixed to another size than the model's, or a
    /// declaration does
    /// not hold: `TIME_DEPENDENT = false` with `t` in L, `FORCED = false` with forces,
    /// `CONSTANT_MASS = true` for L not recognised as constant-mass.
    pub fn new(model: TextModel) -> Result<Self, TextError> {
        let declaration = |reason: String| Err(TextError::Declaration { reason });
        if let Err(reason) = dimension_of::<N>(model.dimension()) {
            return declaration(reason);
        }
        if model.time_dependent() && !TIME_DEPENDENT {
            return declaration("L depends on t, but TIME_DEPENDENT = false".into());
        }
        if model.forced() && !FORCED {
            return declaration("the model has forces, but FORCED = false".into());
        }
        if CONSTANT_MASS && model.structure() != Structure::ConstantMass {
            return declaration(
                "CONSTANT_MASS = true, but L is not recognised as ½q̇ᵀMq̇ − V(t, q)".into(),
            );
        }
        Ok(TextLagrangian {
            model,
            dimension: std::marker::PhantomData,
        })
    }

    /// The model.
    pub fn model(&self) -> &TextModel {
        &self.model
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Lagrangian<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    const TIME_DEPENDENT: bool = TIME_DEPENDENT;
    const FORCED: bool = FORCED;
    const STRUCTURE: Structure = if CONSTANT_MASS {
        Structure::ConstantMass
    } else {
        Structure::General
    };

    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &OVector<D, N>, v: &OVector<D, N>) -> D {
        let tapes = &self.model.tapes;
        if CONSTANT_MASS && let Some(split) = &tapes.constant_mass {
            // ½q̇ᵀMq̇ without a tape, plus U(t, q).
            return split.evaluate(t, q.as_slice(), v.as_slice());
        }
        tapes.lagrangian.evaluate(t, q.as_slice(), v.as_slice())
    }

    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N> {
        let forces = &self.model.tapes.forces;
        let (n, _) = q.shape_generic();
        if forces.is_empty() {
            return OVector::zeros_generic(n, U1);
        }
        OVector::from_fn_generic(n, U1, |i, _| {
            forces[i].evaluate(t, q.as_slice(), v.as_slice())
        })
    }

    /// A constant-mass L: the compiled program of ∂U/∂q on up to `BATCH_LANES` points at once.
    #[inline]
    fn batch_force(
        &self,
        times: &[f64],
        positions: &[OVector<f64, N>],
        _v: &OVector<f64, N>,
        forces: &mut [OVector<f64, N>],
    ) -> bool {
        let program = match &self.model.tapes.force {
            Some(program) if CONSTANT_MASS => program,
            _ => return false,
        };
        // Registers no wider than the points need: SVI 7/6's 6 Gauss points fill 6 lanes,
        // the default 6/12's 12 (even widths: whole vector instructions).
        let arguments = (program, times, positions, forces);
        match positions.len() {
            0..=4 => batch_force_in::<4, N>(arguments),
            5..=6 => batch_force_in::<6, N>(arguments),
            7..=8 => batch_force_in::<8, N>(arguments),
            9..=12 => batch_force_in::<12, N>(arguments),
            _ => batch_force_in::<BATCH_LANES, N>(arguments),
        }
        true
    }
}

/// The arguments of [`batch_force_in`]: the program, the times, positions and forces.
type BatchForce<'a, N> = (
    &'a Program,
    &'a [f64],
    &'a [OVector<f64, N>],
    &'a mut [OVector<f64, N>],
);

/// ∂U/∂q at the points by `program`, `W` points at once, in the smallest register file
/// that holds the program (it is zeroed at every call).
#[inline]
fn batch_force_in<const W: usize, N: Dimension>(
    (program, times, positions, forces): BatchForce<'_, N>,
) where
    DefaultAllocator: Allocator<N>,
{
    if program.register_count() <= 8 {
        batch_force_with(program, &mut [[0.0; W]; 8], times, positions, forces);
    } else {
        let registers = &mut [[0.0; W]; MAX_REGISTERS];
        batch_force_with(program, registers, times, positions, forces);
    }
}

/// ∂U/∂q at the points by `program`, `W` points at once, with `registers`.
#[inline]
fn batch_force_with<const W: usize, N: Dimension>(
    program: &Program,
    registers: &mut [[f64; W]],
    times: &[f64],
    positions: &[OVector<f64, N>],
    forces: &mut [OVector<f64, N>],
) where
    DefaultAllocator: Allocator<N>,
{
    for ((times, positions), forces) in times
        .chunks(W)
        .zip(positions.chunks(W))
        .zip(forces.chunks_mut(W))
    {
        program.forces(
            registers,
            positions.len(),
            |source, lanes| match source {
                Source::Time => lanes[..times.len()].copy_from_slice(times),
                Source::Coordinate(u) => {
                    for (x, q) in lanes.iter_mut().zip(positions) {
                        *x = q[u];
                    }
                }
                // U(t, q) reads no velocity.
                Source::Velocity(_) => lanes.fill(0.0),
            },
            |u, lane, value| forces[lane].as_mut_slice()[u] = value,
        );
    }
}

/// The most points a text model's force program runs at once ([`Lagrangian::batch_force`]):
/// as many as SVI's usual quadrature rules have.
const BATCH_LANES: usize = 16;

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Symmetries<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    fn generator_count(&self) -> usize {
        self.model.generators.len()
    }

    /// `J1`, `J2`, ... in the order of [`TextSpec::symmetries`].
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    fn momentum_name(&self, index: usize) -> &'static str {
        self.model.momentum_names[index]
    }

    /// # Panics
    /// If `index >= generator_count()`.
    fn generator(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N> {
        let generator = &self.model.tapes.generators[index];
        OVector::from_fn_generic(q.shape_generic().0, U1, |i, _| {
            generator[i].evaluate(0.0, q.as_slice(), &[])
        })
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Invariants<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    ExactSolution<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// None: a text model has no closed-form solution.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &OVector<f64, N>,
        _v0: &OVector<f64, N>,
        _t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        None
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Defaults<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// [`TextModel::NAME`].
    fn name(&self) -> &'static str {
        TextModel::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        self.model
            .coordinates
            .iter()
            .map(|name| name.to_string())
            .collect()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.model.parameters()
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        self.model.set_parameter(name, value)
    }

    /// A text model has no literature defaults: at rest at the origin at t = 0 (give the
    /// initial state).
    fn initial_state(&self) -> (f64, OVector<f64, N>, OVector<f64, N>) {
        let n = N::from_usize(self.model.dimension());
        (
            0.0,
            OVector::zeros_generic(n, U1),
            OVector::zeros_generic(n, U1),
        )
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::derived::LagrangianExt;
    use nalgebra::{DVector, SVector, U1, U2};

    fn spec(lagrangian: &str, coordinates: &[&str]) -> TextSpec {
        TextSpec {
            lagrangian: lagrangian.into(),
            coordinates: coordinates.iter().map(|name| (*name).into()).collect(),
            ..TextSpec::default()
        }
    }

    /// A planar double pendulum in Cartesian coordinates with stiff rods replaced by springs
    /// (four coordinates, no size limit): the momentum and the Euler–Lagrange acceleration of
    /// the run-time-size text model are the hand-derived ones,
    /// q̈ = M⁻¹(−∂V/∂q) with M = diag(m1, m1, m2, m2).
    #[test]
    fn a_text_model_of_four_coordinates_runs_at_run_time_size() {
        let text = spec(
            "0.5*m1*(vx1^2 + vy1^2) + 0.5*m2*(vx2^2 + vy2^2) - m1*g*y1 - m2*g*y2 \
             - 0.5*k*(sqrt(x1^2 + y1^2) - 1)^2 - 0.5*k*(sqrt((x2-x1)^2 + (y2-y1)^2) - 1)^2",
            &["x1", "y1", "x2", "y2"],
        );
        let text = TextSpec {
            parameters: [("m1", 1.0), ("m2", 2.0), ("g", 9.81), ("k", 50.0)]
                .iter()
                .map(|(name, value)| ((*name).into(), *value))
                .collect(),
            ..text
        };
        let model = TextModel::new(&text).unwrap();
        assert_eq!(model.structure(), Structure::ConstantMass);
        let model =
            TextLagrangian::<crate::dimension::Dyn, false, false, true>::new(model).unwrap();
        assert_eq!(Lagrangian::dimension(&model), 4);
        let q = DVector::from_vec(vec![0.6, -0.9, 1.3, -1.5]);
        let v = DVector::from_vec(vec![0.2, -0.1, 0.4, 0.3]);
        let p = model.momentum(0.0, &q, &v);
        assert_eq!(p.as_slice(), &[0.2, -0.1, 0.8, 0.6]);
        let (k, g) = (50.0, 9.81);
        let (r1, r2) = (
            (0.6f64.powi(2) + 0.9f64.powi(2)).sqrt(),
            (0.7f64.powi(2) + 0.6f64.powi(2)).sqrt(),
        );
        let (s1, s2) = (k * (r1 - 1.0) / r1, k * (r2 - 1.0) / r2);
        let expected = [
            (-s1 * 0.6 + s2 * 0.7) / 1.0,
            (-g * 1.0 - s1 * -0.9 + s2 * -0.6) / 1.0,
            (-s2 * 0.7) / 2.0,
            (-g * 2.0 - s2 * -0.6) / 2.0,
        ];
        let a = model.acceleration(0.0, &q, &v).unwrap();
        for (a, e) in a.iter().zip(expected) {
            assert!((a - e).abs() <= 1e-12, "{a} vs {e}");
        }
    }

    #[test]
    fn names_are_checked() {
        let invalid = |spec: &TextSpec| match TextModel::new(spec) {
            Err(TextError::InvalidName { role, name, .. }) => (role, name),
            other => panic!("{other:?}"),
        };
        assert_eq!(invalid(&spec("x", &["x", "x"])), ("coordinate", "x".into()));
        assert_eq!(invalid(&spec("x", &["sin"])), ("coordinate", "sin".into()));
        assert_eq!(invalid(&spec("x", &["pi"])), ("coordinate", "pi".into()));
        assert_eq!(invalid(&spec("x", &["t"])), ("coordinate", "t".into()));
        assert_eq!(invalid(&spec("x", &["2x"])), ("coordinate", "2x".into()));
        assert_eq!(invalid(&spec("x", &[""])), ("coordinate", "".into()));
        // The velocity of x is vx: no coordinate may be called vx too.
        assert_eq!(
            invalid(&spec("x", &["x", "vx"])),
            ("coordinate", "x".into())
        );
        assert_eq!(
            invalid(&spec("x", &["vx", "x"])),
            ("coordinate", "x".into())
        );
        let mut with_parameter = spec("x", &["x"]);
        with_parameter.parameters = vec![("vx".into(), 1.0)];
        assert_eq!(invalid(&with_parameter), ("parameter", "vx".into()));
        with_parameter.parameters = vec![("m".into(), f64::NAN)];
        assert!(matches!(
            TextModel::new(&with_parameter),
            Err(TextError::NonFiniteParameter { .. })
        ));
        assert_eq!(
            TextModel::new(&spec("x", &[])),
            Err(TextError::NoCoordinates)
        );
        let error = TextModel::new(&spec("vx^2 + vy^2 - x", &["x", "y"])).map(|_| ());
        assert_eq!(error, Ok(()));
    }

    #[test]
    fn lists_have_one_expression_per_coordinate() {
        let mut forced = spec("vx^2/2", &["x"]);
        forced.forces = vec!["-vx".into(), "0".into()];
        assert_eq!(
            TextModel::new(&forced).unwrap_err().to_string(),
            "forces has 2 expressions, but the model has 1 coordinates"
        );
        let mut symmetric = spec("vx^2/2 + vy^2/2", &["x", "y"]);
        symmetric.symmetries = vec![vec!["-y".into(), "vx".into()]];
        let error = TextModel::new(&symmetric).unwrap_err().to_string();
        assert!(error.starts_with("unknown symbol 'vx' at column 1 of symmetries[0][1]"));
        symmetric.forces = vec!["-vx".into(), "-vy + z".into()];
        let error = TextModel::new(&symmetric).unwrap_err().to_string();
        assert!(
            error.starts_with("unknown symbol 'z' at column 7 of forces[1]"),
            "{error}"
        );
    }

    #[test]
    fn declarations_follow_the_text() {
        let model = TextModel::new(&spec("vx^2/2 - x^2/2", &["x"])).unwrap();
        assert!(!model.time_dependent() && !model.forced());
        assert_eq!(model.structure(), Structure::ConstantMass);
        assert!(TextLagrangian::<U1, false, false, true>::new(model.clone()).is_ok());
        assert!(TextLagrangian::<U1>::new(model.clone()).is_ok());
        assert!(TextLagrangian::<U2>::new(model).is_err());
        let mut driven = spec("vx^2/2 - x^2/2 + x*cos(t)", &["x"]);
        driven.forces = vec!["-0.1*vx".into()];
        let model = TextModel::new(&driven).unwrap();
        assert!(model.time_dependent() && model.forced());
        assert!(TextLagrangian::<U1, false, true, true>::new(model.clone()).is_err());
        assert!(TextLagrangian::<U1, true, false, true>::new(model.clone()).is_err());
        let driven = TextLagrangian::<U1, true, true, true>::new(model).unwrap();
        let (q, v) = (SVector::from([0.5]), SVector::from([2.0]));
        assert_eq!(driven.external_force(0.0, &q, &v)[0], -0.2);
        assert_eq!(driven.value(0.0, &q, &v), 2.0 - 0.125 + 0.5);
    }

    #[test]
    fn parameters_are_read_at_every_evaluation() {
        let mut kepler = spec("(vx^2 + vy^2)/2 + mu/sqrt(x^2 + y^2)", &["x", "y"]);
        kepler.parameters = vec![("mu".into(), 1.0)];
        let mut model = TextLagrangian::<U2>::new(TextModel::new(&kepler).unwrap()).unwrap();
        let (q, v) = (SVector::from([3.0, 4.0]), SVector::from([0.0, 0.0]));
        assert_eq!(model.value(0.0, &q, &v), 0.2);
        model.set_parameter("mu", 5.0).unwrap();
        assert_eq!(model.value(0.0, &q, &v), 1.0);
        assert_eq!(model.parameters(), [("mu", 5.0)]);
        assert!(model.set_parameter("mu", f64::INFINITY).is_err());
        assert!(model.set_parameter("m", 1.0).is_err());
        assert_eq!(model.coordinate_names(), ["x", "y"]);
        assert_eq!(model.name(), "text");
    }

    /// The compiled force program with the points as lanes is the force of the dual
    /// numbers, point by point, for a time-dependent constant-mass L, at every register
    /// width (3, 6, 7 and 12 points; more points than one batch holds).
    #[test]
    fn the_batched_force_is_the_force_point_by_point() {
        let text = spec(
            "0.5*(vx^2 + 3*vy^2) - x^2*cos(t) - sin(x*y) + 1/sqrt(1 + x^2 + y^4)",
            &["x", "y"],
        );
        let model = TextModel::new(&text).unwrap();
        let model = TextLagrangian::<crate::dimension::Dyn, true, false, true>::new(model).unwrap();
        let v = DVector::from_column_slice(&[0.3, -0.4]);
        let points = |count: usize| {
            let times: Vec<f64> = (0..count).map(|k| 0.1 * k as f64).collect();
            let positions: Vec<DVector<f64>> = (0..count)
                .map(|k| {
                    DVector::from_column_slice(&[(0.7 * k as f64).sin(), 0.2 * k as f64 - 1.0])
                })
                .collect();
            (times, positions)
        };
        for count in [3, 6, 7, 12, BATCH_LANES + 5] {
            let (times, positions) = points(count);
            let mut forces = vec![DVector::zeros(2); count];
            assert!(model.batch_force(&times, &positions, &v, &mut forces));
            for ((&t, q), force) in times.iter().zip(&positions).zip(&forces) {
                let mut expected = DVector::zeros(2);
                model.force_into(t, q, &v, &mut expected);
                assert!(
                    (force - &expected).amax() <= 1e-14 * expected.amax().max(1.0),
                    "{count} points: {force} {expected}"
                );
            }
        }
        let (times, positions) = points(6);
        let mut forces = vec![DVector::zeros(2); 6];
        // A general L offers no batch: the integrators take the points one by one.
        let general = spec("0.5*(1 + x^2)*vx^2 + 0.5*vy^2 - x^2", &["x", "y"]);
        let general = TextModel::new(&general).unwrap();
        let general = TextLagrangian::<crate::dimension::Dyn>::new(general).unwrap();
        assert!(!general.batch_force(&times, &positions, &v, &mut forces));
    }
}
