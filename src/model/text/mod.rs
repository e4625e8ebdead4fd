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
//! - in a Hamiltonian H(t, q, p) ([`TextSpec::hamiltonian`], held by [`TextHamiltonian`]), the
//!   momenta in their place: `p` followed by the coordinate's name (`px` for `x`); a velocity
//!   name there is [`TextError::VelocityInHamiltonian`];
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
//!
//! [`Lagrangian<N>`]: crate::model::Lagrangian
//! [`Lagrangian::batch_force`]: crate::model::Lagrangian::batch_force
//! [`Scalar`]: crate::scalar::Scalar

mod batch;
pub mod chain;
mod constraints;
mod error;
mod expression;
mod function;
mod hamiltonian;
mod lagrangian;
mod names;
mod parse;
mod structure;
mod tree;

pub use chain::{Boundary, MAX_SITES, MAX_WIDTH, TextChain, TextChainModel, site_values};
pub use constraints::TextConstraints;
pub use error::TextError;
pub use expression::MAX_STACK;
pub use function::TextFunction;
pub use hamiltonian::TextHamiltonian;
pub use lagrangian::TextLagrangian;
pub use tree::MAX_NODES;

use crate::dimension::Dimension;
use crate::error::Error;
use crate::model::Structure;
use crate::model::hamiltonian::HamiltonianStructure;
use batch::Program;
use constraints::parse_constraints;
use expression::{Expression, Split, Tape, Velocities};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};
use names::{Declared, Slot, intern, named_values, parameter_index};
use tree::Names;

/// A text model as written: the expressions and the names they use.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TextSpec {
    /// L(t, q, q̇) as an expression (empty for a model written as a Hamiltonian).
    pub lagrangian: String,
    /// H(t, q, p) as an expression, instead of [`TextSpec::lagrangian`] (empty for a model
    /// written as a Lagrangian): the model is then a [`TextHamiltonian`], whose momenta are
    /// `p` + the coordinate's name.
    pub hamiltonian: String,
    /// The coordinate names; their velocities are `v` + name (momenta `p` + name).
    pub coordinates: Vec<String>,
    /// The parameters, name and value.
    pub parameters: Vec<(String, f64)>,
    /// The non-conservative force, one expression per coordinate (empty: none): f_L(t, q, q̇)
    /// of a Lagrangian, f_H(t, q, p) of a Hamiltonian.
    pub forces: Vec<String>,
    /// Symmetry generators ξ(q), each one expression per coordinate in q and the parameters;
    /// their Noether momenta are named `J1`, `J2`, ...
    pub symmetries: Vec<Vec<String>>,
    /// What indexed coordinates read outside their range (chains only, see [`chain`]).
    pub boundary: Boundary,
    /// Holonomic constraints g(q) = 0, one expression each in the coordinates and the
    /// parameters ([`TextModel::constraints`]; not for chains).
    pub constraints: Vec<String>,
}

impl TextSpec {
    /// Whether the coordinates are indexed families (`q[1..n]`): the model is then a chain,
    /// read by [`TextChainModel::new`], else by [`TextModel::new`].
    pub fn is_indexed(&self) -> bool {
        self.coordinates.iter().any(|name| name.contains('['))
    }
}

/// A parsed text model of any dimension (known at run time); [`TextLagrangian`] puts a
/// model written as L behind [`Lagrangian<N>`](crate::model::Lagrangian), [`TextHamiltonian`]
/// one written as H behind [`Hamiltonian<N>`](crate::model::hamiltonian::Hamiltonian).
#[derive(Debug, Clone, PartialEq)]
pub struct TextModel {
    coordinates: Vec<&'static str>,
    parameter_names: Vec<&'static str>,
    parameter_values: Vec<f64>,
    /// What the second slot of the phase space holds: q̇ for L, p for H.
    slot: Slot,
    /// L(t, q, q̇) or H(t, q, p): the expressions read p where L's read q̇.
    lagrangian: Expression,
    forces: Vec<Expression>,
    generators: Vec<Vec<Expression>>,
    momentum_names: Vec<&'static str>,
    /// The holonomic constraints, as written and parsed.
    constraint_texts: Vec<String>,
    constraints: Vec<Expression>,
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
    /// points as lanes ([`Lagrangian::batch_force`](crate::model::Lagrangian::batch_force));
    /// `None` where the program would need more registers than there are.
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
    /// Name of every text model in reports ([`Defaults::name`](crate::model::Defaults::name)).
    pub const NAME: &'static str = "text";

    /// A placeholder step of a text model, 0.01 (the caller gives the step).
    pub const DEFAULT_STEP: f64 = 0.01;

    /// A placeholder horizon of a text model, 10 (the caller gives the horizon).
    pub const DEFAULT_HORIZON: f64 = 10.0;

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
        let (text, field, slot) = match (spec.lagrangian.is_empty(), spec.hamiltonian.is_empty()) {
            (_, true) => (&spec.lagrangian, "lagrangian", Slot::Velocity),
            (true, false) => (&spec.hamiltonian, "hamiltonian", Slot::Momentum),
            (false, false) => return Err(TextError::LagrangianAndHamiltonian),
        };
        if slot == Slot::Momentum && !spec.constraints.is_empty() {
            return Err(TextError::Unsupported {
                field: "constraints".into(),
                reason: "holonomic constraints are run with a lagrangian written as text, not a \
                         hamiltonian"
                    .into(),
            });
        }
        let names: Vec<&str> = spec.coordinates.iter().map(String::as_str).collect();
        let Declared {
            coordinates,
            velocities,
            parameter_names,
            parameter_values,
        } = Declared::check_phase_space(&names, &spec.parameters, slot)?;
        // A velocity in H (or f_H) is a slip for a momentum: say so.
        let velocity_in_hamiltonian = |error: TextError| match error {
            TextError::UnknownSymbol {
                field,
                column,
                symbol,
                ..
            } if slot == Slot::Momentum
                && let Some(momentum) = symbol
                    .strip_prefix('v')
                    .filter(|name| coordinates.contains(name))
                    .map(|name| format!("p{name}")) =>
            {
                TextError::VelocityInHamiltonian {
                    field,
                    column,
                    symbol,
                    momentum,
                }
            }
            error => error,
        };
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
                .map(|(i, text)| {
                    Expression::parse(text, &format!("{field}[{i}]"), names)
                        .map_err(velocity_in_hamiltonian)
                })
                .collect::<Result<Vec<_>, _>>()
        };
        let lagrangian =
            Expression::parse(text, field, &phase_space).map_err(velocity_in_hamiltonian)?;
        // A Hamiltonian free of a momentum is checked where it matters, at the initial state
        // of a run (∂²H/∂p² singular: `HamiltonianForm::check`).
        if slot == Slot::Velocity
            && let Some(i) = (0..n).find(|&i| !lagrangian.uses_velocity(i))
        {
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
        let constraints = parse_constraints(&spec.constraints, &configuration)?;
        let tapes = Tapes::compile(&lagrangian, &forces, &generators, &parameter_values, n);
        Ok(TextModel {
            coordinates,
            parameter_names,
            parameter_values,
            slot,
            lagrangian,
            forces,
            generators,
            momentum_names,
            constraint_texts: spec.constraints.clone(),
            constraints,
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

    /// Whether the model is written as a Hamiltonian H(t, q, p) ([`TextSpec::hamiltonian`]):
    /// then [`TextHamiltonian`] holds it, else [`TextLagrangian`].
    pub fn is_hamiltonian(&self) -> bool {
        self.slot == Slot::Momentum
    }

    /// Whether `t` appears in L (or H).
    pub fn time_dependent(&self) -> bool {
        self.lagrangian.properties().time
    }

    /// Whether forces are given.
    pub fn forced(&self) -> bool {
        !self.forces.is_empty()
    }

    /// [`Structure::ConstantMass`] if L is, by its structure, ½q̇ᵀMq̇ − V(t, q) with M
    /// constant (see the [module docs](self)), else [`Structure::General`] (also for a model
    /// written as H: see [`TextModel::hamiltonian_structure`]).
    pub fn structure(&self) -> Structure {
        match self.tapes.constant_mass {
            Some(_) if !self.is_hamiltonian() => Structure::ConstantMass,
            _ => Structure::General,
        }
    }

    /// [`HamiltonianStructure::QuadraticKinetic`] if H is, by its structure, ½pᵀAp + V(t, q)
    /// with A constant (read off the text as a constant mass is off L's);
    /// [`HamiltonianStructure::Separable`] if it is T(p) + V(t, q) with any T (a sum of parts
    /// each free of the momenta or free of t and q, `sqrt(1 + px^2) + x^2/2`); else
    /// [`HamiltonianStructure::General`] (also for a model written as L). That A is
    /// invertible is checked at the initial state of a run.
    pub fn hamiltonian_structure(&self) -> HamiltonianStructure {
        if !self.is_hamiltonian() {
            return HamiltonianStructure::General;
        }
        if self.tapes.constant_mass.is_some() {
            HamiltonianStructure::QuadraticKinetic
        } else if self.lagrangian.properties().separable {
            HamiltonianStructure::Separable
        } else {
            HamiltonianStructure::General
        }
    }

    /// The parameters, name and current value.
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        named_values(&self.parameter_names, &self.parameter_values)
    }

    /// The symmetry generator `index` (of [`TextSpec::symmetries`]) at `q` into `out`, without
    /// allocating: what a run's observer of the Noether momenta evaluates at every step.
    ///
    /// # Panics
    /// If `index` is not below the number of generators, or `q` and `out` are shorter than
    /// the coordinates.
    pub fn generator_into(&self, index: usize, q: &[f64], out: &mut [f64]) {
        for (value, tape) in out.iter_mut().zip(&self.tapes.generators[index]) {
            *value = tape.evaluate(0.0, q, &[]);
        }
    }

    /// The symmetry generator `index` at `q`, as the `Symmetries` of [`TextLagrangian`] and
    /// [`TextHamiltonian`] give it.
    ///
    /// # Panics
    /// If `index` is not below the number of generators.
    pub fn generator<N: Dimension>(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N>
    where
        DefaultAllocator: Allocator<N>,
    {
        let mut out = OVector::zeros_generic(q.shape_generic().0, U1);
        self.generator_into(index, q.as_slice(), out.as_mut_slice());
        out
    }

    /// A text model has no literature defaults: at rest at the origin at t = 0, the second
    /// vector q̇ or p (the caller gives the initial state).
    pub fn rest_state<N: Dimension>(&self) -> (f64, OVector<f64, N>, OVector<f64, N>)
    where
        DefaultAllocator: Allocator<N>,
    {
        let n = N::from_usize(self.dimension());
        (
            0.0,
            OVector::zeros_generic(n, U1),
            OVector::zeros_generic(n, U1),
        )
    }

    /// The number of holonomic constraints ([`TextSpec::constraints`]).
    pub fn constraint_count(&self) -> usize {
        self.constraints.len()
    }

    /// The holonomic constraints g(q) = 0 as [`Constraints`](crate::model::constraint::Constraints),
    /// compiled for the current parameter values (none if the model has none).
    pub fn constraints(&self) -> TextConstraints {
        TextConstraints::compile(
            &self.constraint_texts,
            &self.constraints,
            &self.parameter_values,
        )
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::derived::LagrangianExt;
    use crate::model::{Defaults, Lagrangian};
    use nalgebra::{DVector, SVector, U1, U2};

    pub(super) fn spec(lagrangian: &str, coordinates: &[&str]) -> TextSpec {
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
}
