//! [`TextError`], what goes wrong when reading a text model: every message names the field
//! and, for the expressions, the column and the offending symbol.

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
    /// An expression whose evaluation needs more than [`MAX_STACK`](super::MAX_STACK) values at
    /// once.
    #[error("{field} nests too deeply: its evaluation needs more than {limit} values at once")]
    TooDeep {
        /// The field.
        field: String,
        /// [`MAX_STACK`](super::MAX_STACK).
        limit: usize,
    },
    /// An expression of more than [`MAX_NODES`](super::MAX_NODES) numbers, names and
    /// operations.
    #[error("{field} is too long: more than {limit} numbers, names and operations")]
    TooLong {
        /// The field.
        field: String,
        /// [`MAX_NODES`](super::MAX_NODES).
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
    /// [`chain`](super::chain)): an index that is not `i + c` inside a sum or constant
    /// outside, bounds that are not integers or `n ± c`, a sum inside a sum or inside a
    /// product, a power or a function.
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
    /// [`MAX_SITES`](super::MAX_SITES).
    #[error("the size '{name}' = {value} is not a whole number from 1 to {limit}")]
    InvalidSize {
        /// The size parameter.
        name: String,
        /// Its value.
        value: f64,
        /// [`MAX_SITES`](super::MAX_SITES).
        limit: usize,
    },
    /// A chain whose terms read more coordinates than [`MAX_WIDTH`](super::MAX_WIDTH).
    #[error(
        "a term of the chain reads {width} coordinates ({what}), more than {limit}, the widest \
         term compiled: use fewer families or nearer neighbours"
    )]
    TooWide {
        /// The number of coordinates one term reads.
        width: usize,
        /// Where they come from.
        what: String,
        /// [`MAX_WIDTH`](super::MAX_WIDTH).
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
    /// A holonomic constraint that is not g(q): it reads a velocity or the time, or no
    /// coordinate at all.
    #[error("constraint '{constraint}' is not a holonomic constraint g(q) = 0: {reason}")]
    Constraint {
        /// The constraint, as written.
        constraint: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A text model that gives both a Lagrangian and a Hamiltonian.
    #[error("the model gives both a lagrangian and a hamiltonian: give one of them")]
    LagrangianAndHamiltonian,
    /// A velocity name (`vx`) in a Hamiltonian or its force, which are functions of the
    /// momenta (`px`).
    #[error(
        "'{symbol}' at column {column} of {field} is a velocity, but a Hamiltonian is a \
         function of the momenta: write {momentum}"
    )]
    VelocityInHamiltonian {
        /// The field: `hamiltonian`, `forces[1]`.
        field: String,
        /// Column of the symbol, in characters from 1.
        column: usize,
        /// The velocity name.
        symbol: String,
        /// The momentum name meant.
        momentum: String,
    },
    /// A [`TextLagrangian`](super::TextLagrangian) or
    /// [`TextHamiltonian`](super::TextHamiltonian) whose dimension or declarations do not fit
    /// its model.
    #[error("{holder} cannot hold this model: {reason}")]
    Declaration {
        /// The type: `TextLagrangian`, `TextHamiltonian` or `TextChain`.
        holder: &'static str,
        /// What does not fit.
        reason: String,
    },
}
